# `spherechain bake --depfile`: the depfile names exactly the files the bake read, Make and Ninja read it back
# (paths with spaces, '#' and '$'), and a failed bake writes neither the asset nor the depfile.
#   1. boxes.obj + --config fast.json + --region-map limbs_detached.json + --force: the three files, absolute;
#      the same OBJ renamed in another folder bakes to the same bytes.
#   2. The same without --force fails its plausibility checks: exit 1, no asset, no depfile (an old one stays
#      untouched, as the asset does); a depfile path that is a folder is refused before the bake; a
#      configuration's relative region map is read from the configuration's folder.
#   3. The creature in a folder named "a b#c$d": its depfile read by GNU make (`make -q`: up to date, then
#      out of date once the input is touched) and by Ninja (`ninja -t deps` lists the path; a second build does
#      nothing, a touched input rebuilds).
#   4. With ../shared/data: CesiumMan split into .gltf + .bin + image (tests/package/split_gltf.py): all three.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
include(${CMAKE_CURRENT_LIST_DIR}/../run_step.cmake)  # run()
# The prerequisites a depfile names (one per line after the first, "\ "-escaped; the empty rules after the
# blank line are not read): `deps` in `var`.
function(read_deps depfile var)
  file(READ ${depfile} text)
  string(FIND "${text}" "\n\n" end)
  if(end GREATER -1)
    string(SUBSTRING "${text}" 0 ${end} text)
  endif()
  string(REPLACE "\\\n" "\n" text "${text}")
  string(REPLACE "\n" ";" lines "${text}")
  list(POP_FRONT lines)  # "target:"
  set(deps "")
  foreach(l IN LISTS lines)
    string(STRIP "${l}" l)
    list(APPEND deps "${l}")
  endforeach()
  set(${var} "${deps}" PARENT_SCOPE)
endfunction()
function(expect_deps name depfile)
  read_deps(${depfile} got)
  if(NOT got STREQUAL "${ARGN}")
    file(READ ${depfile} text)
    message(FATAL_ERROR "${name}: the depfile names\n  ${got}\nexpected\n  ${ARGN}\n${text}")
  endif()
  message(STATUS "${name}: ${got}")
endfunction()

# ---- 1. configuration + region map --------------------------------------------------------------------
run("bake boxes" ${CLI} -q bake ${IMPLAUSIBLE}/boxes.obj -o ${WORK}/boxes.sphc --depfile ${WORK}/boxes.d
    --config ${IMPLAUSIBLE}/fast.json --region-map ${IMPLAUSIBLE}/limbs_detached.json --force)
expect_deps("config + region map" ${WORK}/boxes.d
            ${IMPLAUSIBLE}/fast.json ${IMPLAUSIBLE}/boxes.obj ${IMPLAUSIBLE}/limbs_detached.json)
file(READ ${WORK}/boxes.d text)
if(NOT text MATCHES "^${WORK}/boxes.sphc: ")
  message(FATAL_ERROR "the depfile's target is not the asset as -o named it:\n${text}")
endif()
# The same OBJ under another name in another folder: the same bytes (the asset records neither; an OBJ's part
# was named after its file).
file(MAKE_DIRECTORY ${WORK}/renamed)
file(COPY_FILE ${IMPLAUSIBLE}/boxes.obj ${WORK}/renamed/other.obj)
run("bake boxes renamed" ${CLI} -q bake ${WORK}/renamed/other.obj -o ${WORK}/renamed.sphc
    --config ${IMPLAUSIBLE}/fast.json --region-map ${IMPLAUSIBLE}/limbs_detached.json --force)
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${WORK}/boxes.sphc ${WORK}/renamed.sphc RESULT_VARIABLE differ)
if(differ)
  message(FATAL_ERROR "one OBJ baked under two names gave two assets")
endif()

# ---- 2. a failed bake writes nothing ------------------------------------------------------------------
execute_process(COMMAND ${CLI} -q bake ${IMPLAUSIBLE}/boxes.obj -o ${WORK}/refused.sphc --depfile ${WORK}/refused.d
                        --config ${IMPLAUSIBLE}/fast.json --region-map ${IMPLAUSIBLE}/limbs_detached.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR EXISTS ${WORK}/refused.sphc OR EXISTS ${WORK}/refused.d)
  message(FATAL_ERROR "a refused bake: exit ${rc} (expected 1), asset or depfile written:\n${out}${err}")
endif()
file(WRITE ${WORK}/old.d "old")
execute_process(COMMAND ${CLI} -q bake ${IMPLAUSIBLE}/boxes.obj -o ${WORK}/boxes.sphc --depfile ${WORK}/old.d
                        --config ${IMPLAUSIBLE}/fast.json --region-map ${IMPLAUSIBLE}/limbs_detached.json
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
file(READ ${WORK}/old.d old_text)
if(NOT rc EQUAL 1 OR NOT old_text STREQUAL "old")
  message(FATAL_ERROR "a refused bake touched an existing depfile (exit ${rc}): '${old_text}'")
endif()
execute_process(COMMAND ${CLI} -q bake ${IMPLAUSIBLE}/boxes.obj -o ${WORK}/x.sphc --depfile ${WORK}/no/such/x.d
                        --config ${IMPLAUSIBLE}/fast.json --region-map ${IMPLAUSIBLE}/limbs_detached.json --force
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR EXISTS ${WORK}/x.sphc OR NOT err MATCHES "io: cannot write .*folder .* does not exist")
  message(FATAL_ERROR "--depfile into a missing folder: exit ${rc}, expected 1 before any bake:\n${out}${err}")
endif()
# An output that is a folder is refused before the bake (it used to fail only at its rename, after the
# asset was written: Make then took the asset as up to date, with no depfile).
file(MAKE_DIRECTORY ${WORK}/folder.d)
execute_process(COMMAND ${CLI} -q bake ${IMPLAUSIBLE}/boxes.obj -o ${WORK}/folder.sphc --depfile ${WORK}/folder.d
                        --config ${IMPLAUSIBLE}/fast.json --region-map ${IMPLAUSIBLE}/limbs_detached.json --force
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR EXISTS ${WORK}/folder.sphc OR NOT err MATCHES "io: cannot write .*: it is a folder")
  message(FATAL_ERROR "--depfile onto a folder: exit ${rc}, expected 1 before any bake, no asset:\n${out}${err}")
endif()
message(STATUS "a failed bake: exit 1, no asset, no depfile, an old depfile untouched; an output that is a folder refused")

# A configuration's region map is relative to the configuration's folder, wherever the bake runs from.
file(MAKE_DIRECTORY ${WORK}/cfg ${WORK}/elsewhere)
file(COPY ${IMPLAUSIBLE}/limbs_detached.json DESTINATION ${WORK}/cfg)
file(WRITE ${WORK}/cfg/bake.json "{\"cover_voxel_rel\": 0.01, \"region_map\": \"limbs_detached.json\"}")
execute_process(COMMAND ${CLI} -q bake ${IMPLAUSIBLE}/boxes.obj -o ${WORK}/relative.sphc --depfile ${WORK}/relative.d
                        --config ../cfg/bake.json --force
                WORKING_DIRECTORY ${WORK}/elsewhere RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "a configuration's relative region map, run from another folder: exit ${rc}:\n${out}${err}")
endif()
file(READ ${WORK}/relative.d text)
if(NOT text MATCHES "cfg/limbs_detached.json")
  message(FATAL_ERROR "the depfile does not name the configuration's region map:\n${text}")
endif()
message(STATUS "a configuration's region map is found beside it")

# ---- 3. Make and Ninja read it back -------------------------------------------------------------------
set(odd "${WORK}/a b#c$d")
file(MAKE_DIRECTORY "${odd}")
file(COPY ${CREATURE} DESTINATION "${odd}")
get_filename_component(creature_name ${CREATURE} NAME)
set(input "${odd}/${creature_name}")
# Run there with a relative -o, as Make names its target: the depfile's rule is for "out.sphc".
execute_process(COMMAND ${CLI} -q bake "${input}" -o out.sphc --depfile out.d --config ${IMPLAUSIBLE}/fast.json
                WORKING_DIRECTORY "${odd}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS "${odd}/out.sphc")
  message(FATAL_ERROR "bake from an odd folder: exit ${rc}:\n${out}${err}")
endif()
file(READ "${odd}/out.d" text)
string(FIND "${text}" "a\\ b\\#c$$d/${creature_name}" at)
if(at EQUAL -1)
  message(FATAL_ERROR "the odd path is not escaped as Make reads it:\n${text}")
endif()
find_program(MAKE NAMES make gmake)
if(MAKE)
  # out.sphc's only rule comes from the depfile; `make -q` exits 0 when it is up to date, 1 when not, 2 when a
  # prerequisite is missing (a path read wrongly).
  file(WRITE "${odd}/Makefile" "include out.d\nout.sphc:\n\t@echo rebake\n")
  execute_process(COMMAND ${MAKE} -q out.sphc WORKING_DIRECTORY "${odd}" RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "make -q after the bake: exit ${rc}, expected 0 (up to date):\n${o}${e}")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E sleep 1.1)
  file(TOUCH "${input}")
  execute_process(COMMAND ${MAKE} -q out.sphc WORKING_DIRECTORY "${odd}" RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
  if(NOT rc EQUAL 1)
    message(FATAL_ERROR "make -q after touching the input: exit ${rc}, expected 1 (out of date):\n${o}${e}")
  endif()
  message(STATUS "GNU make: up to date after the bake, out of date after touching '${input}'")
else()
  message(STATUS "make not found: the depfile not read by Make")
endif()
find_program(NINJA NAMES ninja ninja-build)
if(NINJA)
  set(nj "${WORK}/ninja")
  file(MAKE_DIRECTORY ${nj})
  # The odd input only in the command (ninja's own "$" escaped, the shell's single quotes) and the depfile.
  string(REPLACE "$" "$$" n_input "${input}")
  file(WRITE ${nj}/build.ninja
       "rule bake\n  command = '${CLI}' -q bake '${n_input}' -o $out --depfile $out.d --config ${IMPLAUSIBLE}/fast.json\n"
       "  depfile = $out.d\n  deps = gcc\nbuild out.sphc: bake\n")
  run("ninja" ${NINJA} -C ${nj})
  run("ninja -t deps" ${NINJA} -C ${nj} -t deps out.sphc)
  string(FIND "${out}" "    ${input}\n" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "ninja did not read '${input}' from the depfile:\n${out}")
  endif()
  run("ninja again" ${NINJA} -C ${nj})
  if(NOT out MATCHES "no work to do")
    message(FATAL_ERROR "ninja's second build did work:\n${out}")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E sleep 1.1)
  file(TOUCH "${input}")
  run("ninja after touching the input" ${NINJA} -C ${nj} -v)
  if(NOT out MATCHES "bake")
    message(FATAL_ERROR "ninja did not rebake after the input was touched:\n${out}")
  endif()
  message(STATUS "Ninja: read the depfile (deps = gcc), no work on a second build, a rebake after touching '${input}'")
else()
  message(STATUS "ninja not found: the depfile not read by Ninja")
endif()

# ---- 4. CesiumMan with its .bin and image -------------------------------------------------------------
find_program(PYTHON NAMES python3)
if(EXISTS "${GLTF}" AND PYTHON)
  run("split CesiumMan" ${PYTHON} ${SRC}/tests/package/split_gltf.py ${GLTF} ${WORK}/cesium)
  run("bake CesiumMan" ${CLI} -q bake ${WORK}/cesium/CesiumMan.gltf -o ${WORK}/cesium.sphc --depfile ${WORK}/cesium.d
      --config ${IMPLAUSIBLE}/fast.json)
  expect_deps("CesiumMan split" ${WORK}/cesium.d ${IMPLAUSIBLE}/fast.json ${WORK}/cesium/CesiumMan.gltf
              ${WORK}/cesium/CesiumMan.bin ${WORK}/cesium/CesiumMan_image0.jpg)
else()
  message(STATUS "CesiumMan (../shared/data) or python3 not found: its part not run")
endif()
message("bake --depfile: exact inputs, read by Make and Ninja, nothing written on failure")
