# `spherechain export-debug --morph`: the animated glTF of the MakeHuman morph is written with one animation
# (the file's content is checked in depth by the playback doctests); --clip on a mesh without that clip and
# --clip with --morph fail, leaving nothing behind. Skips (visibly) when ../shared/data is absent.
if(NOT EXISTS ${MESH} OR NOT EXISTS ${ASSET})
  message("SKIPPED: ${MESH} or ${ASSET} not found (../shared/data is absent)")
  return()
endif()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${CLI} export-debug ${ASSET} --mesh ${MESH} --morph --frames 10 -o ${WORK}/morph.gltf
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "export-debug --morph failed (${rc}):\n${out}${err}")
endif()
if(NOT out MATCHES "animated glTF: morph through [0-9]+ key poses.*10 frames.*128 spheres as animated nodes")
  message(FATAL_ERROR "export-debug --morph: unexpected report:\n${out}")
endif()
file(READ ${WORK}/morph.gltf json)
string(JSON n LENGTH "${json}" animations)
string(JSON channels LENGTH "${json}" animations 0 channels)
string(JSON name GET "${json}" animations 0 name)
if(NOT n EQUAL 1 OR NOT name STREQUAL "morph" OR channels LESS 256)
  message(FATAL_ERROR "export-debug --morph: ${n} animations, first '${name}' with ${channels} channels")
endif()
execute_process(COMMAND ${CLI} export-debug ${ASSET} --mesh ${MESH} --clip Walk -o ${WORK}/bad.gltf
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT "${out}${err}" MATCHES "no clip named 'Walk'" OR EXISTS ${WORK}/bad.gltf OR EXISTS ${WORK}/bad.png)
  message(FATAL_ERROR "export-debug --clip Walk on MakeHuman: expected a failure naming the clip:\n${out}${err}")
endif()
execute_process(COMMAND ${CLI} export-debug ${ASSET} --mesh ${MESH} --clip Walk --morph arms_crossed -o ${WORK}/bad.gltf
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT "${out}${err}" MATCHES "--clip excludes --morph" OR EXISTS ${WORK}/bad.gltf)
  message(FATAL_ERROR "export-debug --clip with --morph: expected a failure:\n${out}${err}")
endif()
message(STATUS "morph: ${out} (${channels} channels)")

# Nothing is written when the export is refused: an output folder that does not exist (the PNG would have been
# written first), and a mesh that is not the asset's (static export too: checked against the fingerprint).
execute_process(COMMAND ${CLI} export-debug ${ASSET} --mesh ${MESH} -o ${WORK}/no/such/x.gltf --png ${WORK}/ok.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT "${out}${err}" MATCHES "does not exist" OR EXISTS ${WORK}/ok.png)
  message(FATAL_ERROR "export-debug into a missing folder: expected a failure and no PNG:\n${out}${err}")
endif()
# -o ending in .png: the picture's default path is -o itself (it was written, then overwritten by the glTF)
execute_process(COMMAND ${CLI} export-debug ${ASSET} --mesh ${MESH} -o ${WORK}/same.png
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT "${out}${err}" MATCHES "both name" OR EXISTS ${WORK}/same.png)
  message(FATAL_ERROR "export-debug -o same.png: expected a clash (exit 2), nothing written:\n${out}${err}")
endif()
get_filename_component(shared ${MESH} DIRECTORY)
set(other ${shared}/../gltf/CesiumMan.gltf)
if(EXISTS ${other})
  execute_process(COMMAND ${CLI} export-debug ${ASSET} --mesh ${other} -o ${WORK}/other.gltf
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT "${out}${err}" MATCHES "does not match asset" OR EXISTS ${WORK}/other.gltf OR EXISTS ${WORK}/other.png)
    message(FATAL_ERROR "export-debug with another character's mesh: expected a failure, nothing written:\n${out}${err}")
  endif()
endif()
