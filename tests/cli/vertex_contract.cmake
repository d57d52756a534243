# `bake --vertices joined|source` (the vertex contract for assimp formats) end to end on BCN_Epileptic.X:
# the default bake is joined and plays against its mesh; a --vertices source bake validates against the
# source buffer and refuses the joined one naming the contract; glTF ignores the option with a warning;
# a bad value writes nothing. Skips visibly when inputs are absent.
foreach(f ${INPUT} ${GLTF})
  if(NOT EXISTS ${f})
    message("SKIPPED: ${f} not found")
    return()
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

function(run expect_rc)
  execute_process(COMMAND ${CLI} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(expect_rc STREQUAL "0" AND NOT rc EQUAL 0)
    message(FATAL_ERROR "spherechain ${ARGN}: expected exit 0, got ${rc}:\n${out}${err}")
  elseif(NOT expect_rc STREQUAL "0" AND rc EQUAL 0)
    message(FATAL_ERROR "spherechain ${ARGN}: expected a non-zero exit, got 0:\n${out}${err}")
  endif()
  set(out "${out}${err}" PARENT_SCOPE)
endfunction()

# Default: joined.
run(0 bake ${INPUT} -o ${WORK}/joined.sphc)
run(0 inspect ${WORK}/joined.sphc --json)
if(NOT out MATCHES "\"vertex_contract\": \"joined\"")
  message(FATAL_ERROR "inspect: vertex_contract joined expected:\n${out}")
endif()
run(0 play ${WORK}/joined.sphc --mesh ${INPUT} --frames 4)
run(0 validate ${WORK}/joined.sphc --mesh ${INPUT})
run(1 validate ${WORK}/joined.sphc --mesh ${INPUT} --vertices source)
if(NOT out MATCHES "FP-COUNTS.*the buffer has 15,378 vertices: it looks like the source contract; this asset was baked with --vertices joined")
  message(FATAL_ERROR "validate --vertices source: the contract is not named:\n${out}")
endif()
message(STATUS "joined asset, source buffer: ${out}")

# --vertices source: the importer's own buffer (one vertex per face corner).
run(0 bake ${INPUT} -o ${WORK}/source.sphc --vertices source)
run(0 inspect ${WORK}/source.sphc --json)
if(NOT out MATCHES "\"vertex_contract\": \"source\"" OR NOT out MATCHES "\"vertices\": 15378")
  message(FATAL_ERROR "inspect: vertex_contract source, 15378 vertices expected:\n${out}")
endif()
run(0 validate ${WORK}/source.sphc --mesh ${INPUT})
run(0 play ${WORK}/source.sphc --mesh ${INPUT} --frames 4)
run(1 validate ${WORK}/source.sphc --mesh ${INPUT} --vertices joined)
if(NOT out MATCHES "FP-COUNTS.*it looks like the joined contract; this asset was baked with --vertices source")
  message(FATAL_ERROR "validate --vertices joined: the contract is not named:\n${out}")
endif()
message(STATUS "source asset, joined buffer: ${out}")

# glTF: the option is a no-op with a warning; the asset records "file".
run(0 bake ${GLTF} -o ${WORK}/gltf.sphc --vertices source)
if(NOT out MATCHES "applies to assimp formats only")
  message(FATAL_ERROR "bake glTF --vertices source: no warning:\n${out}")
endif()
run(0 inspect ${WORK}/gltf.sphc --json)
if(NOT out MATCHES "\"vertex_contract\": \"file\"")
  message(FATAL_ERROR "inspect glTF: vertex_contract file expected:\n${out}")
endif()

# A bad value: exit non-zero, nothing written.
run(1 bake ${INPUT} -o ${WORK}/bad.sphc --vertices welded)
if(EXISTS ${WORK}/bad.sphc)
  message(FATAL_ERROR "bake --vertices welded wrote an asset")
endif()
