# samples/cmake_bake as a game's build uses it: install this build tree (BUILD) into WORK/prefix, configure the
# sample with Ninja against that prefix and a copy of CesiumMan split into .gltf + .bin + image (its buffer and
# image are embedded in ../shared/data; split_gltf.py), build it, then check what spherechain_bake() promises:
#   - the first build bakes (the asset, its report and depfile; the depfile names the .gltf, .bin, image, config);
#   - the sample program, linked to the runtime only, loads the asset;
#   - a second build runs nothing ("ninja: no work to do.");
#   - touching the .gltf rebakes, and so does touching the .bin, and the bake.json; each time only the bake
#     runs (the game is not relinked), and the build after it again does nothing.
# Skips visibly without ../shared/data, python3 or ninja.
if(NOT EXISTS "${GLTF}")
  message("SKIPPED: ${GLTF} not found (../shared/data is absent)")
  return()
endif()
find_program(NINJA NAMES ninja ninja-build)
find_program(PYTHON NAMES python3)
if(NOT NINJA OR NOT PYTHON)
  message("SKIPPED: the sample's build needs ninja and python3 (found: '${NINJA}', '${PYTHON}')")
  return()
endif()
file(REMOVE_RECURSE ${WORK})
include(${CMAKE_CURRENT_LIST_DIR}/../run_step.cmake)  # run()
run("install" ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix)
foreach(f bin/spherechain lib/cmake/spherechain/SpherechainBake.cmake)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run("split CesiumMan" ${PYTHON} ${SRC}/tests/package/split_gltf.py ${GLTF} ${WORK}/art)
set(art ${WORK}/art)
set(sample ${WORK}/sample)
# The sample's own folder is copied, so that its bake.json can be touched without touching the checkout.
file(COPY ${SRC}/samples/cmake_bake/ DESTINATION ${WORK}/src)
run("configure the sample" ${CMAKE_COMMAND} -S ${WORK}/src -B ${sample} -G Ninja -DCMAKE_MAKE_PROGRAM=${NINJA}
    -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release -DCHARACTER=${art}/CesiumMan.gltf)

# `build(name expect)`: builds, and checks the bake ran (expect "bake"), or that nothing ran ("nothing").
function(build name expect)
  run("build (${name})" ${CMAKE_COMMAND} --build ${sample})
  string(FIND "${out}" "Baking CesiumMan.gltf into CesiumMan.sphc" baked)
  string(FIND "${out}" "ninja: no work to do." nothing)
  if(expect STREQUAL "nothing" AND (baked GREATER -1 OR nothing EQUAL -1))
    message(FATAL_ERROR "${name}: expected no work, ninja said:\n${out}")
  elseif(expect STREQUAL "bake" AND baked EQUAL -1)
    message(FATAL_ERROR "${name}: expected the bake to run, ninja said:\n${out}")
  endif()
  if(expect STREQUAL "bake" AND NOT name STREQUAL "first build" AND out MATCHES "Linking")
    message(FATAL_ERROR "${name}: the game was relinked, only the asset should be rebuilt:\n${out}")
  endif()
  message(STATUS "${name}: ${expect} (ok)")
endfunction()

build("first build" bake)
foreach(f CesiumMan.sphc CesiumMan.json CesiumMan.sphc.d cmake_bake)
  if(NOT EXISTS ${sample}/${f})
    message(FATAL_ERROR "the first build did not write ${sample}/${f}")
  endif()
endforeach()
file(READ ${sample}/CesiumMan.sphc.d depfile)
foreach(f ${art}/CesiumMan.gltf ${art}/CesiumMan.bin ${art}/CesiumMan_image0.jpg ${WORK}/src/bake.json)
  string(FIND "${depfile}" " ${f}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the depfile does not name ${f}:\n${depfile}")
  endif()
endforeach()
run("run the sample" ${sample}/cmake_bake)
if(NOT out MATCHES "CesiumMan.sphc: 96 spheres, [0-9]+ chains, 3273 vertices, 4672 triangles; bind pose: 0 colliding")
  message(FATAL_ERROR "the sample read the asset wrongly:\n${out}")
endif()
message(STATUS "the sample: ${out}")

build("second build" nothing)
foreach(touched ${art}/CesiumMan.gltf ${art}/CesiumMan.bin ${WORK}/src/bake.json)
  get_filename_component(n ${touched} NAME)
  file(TIMESTAMP ${sample}/CesiumMan.sphc before "%s")
  execute_process(COMMAND ${CMAKE_COMMAND} -E sleep 1.1)  # a later mtime than the asset's, on any file system
  file(TOUCH ${touched})
  build("after touching ${n}" bake)
  file(TIMESTAMP ${sample}/CesiumMan.sphc after "%s")
  if(NOT after GREATER before)
    message(FATAL_ERROR "after touching ${n}: CesiumMan.sphc was not rewritten (${before} -> ${after})")
  endif()
  build("the build after that" nothing)
endforeach()
message("cmake_bake: baked once, a second build did nothing, touching the .gltf, the .bin and bake.json each rebaked")

# With Unix Makefiles (which, unlike Ninja, makes no output folder), an OUTPUT and a REPORT in folders that do not
# exist yet: spherechain_bake makes them.
find_program(MAKE_PROGRAM NAMES make gmake)
if(MAKE_PROGRAM)
  file(WRITE ${WORK}/make_src/CMakeLists.txt "cmake_minimum_required(VERSION 3.20)
project(make_bake LANGUAGES NONE)
find_package(spherechain CONFIG REQUIRED COMPONENTS cli)
spherechain_bake(OUTPUT assets/hero.sphc INPUT \"${art}/CesiumMan.gltf\" CONFIG \"${SRC}/samples/cmake_bake/bake.json\"
                 REPORT reports/hero.json)
add_custom_target(assets ALL DEPENDS \"\${CMAKE_CURRENT_BINARY_DIR}/assets/hero.sphc\")
")
  run("configure (Unix Makefiles)" ${CMAKE_COMMAND} -S ${WORK}/make_src -B ${WORK}/make_build -G "Unix Makefiles"
      -DCMAKE_PREFIX_PATH=${WORK}/prefix)
  run("build (Unix Makefiles)" ${CMAKE_COMMAND} --build ${WORK}/make_build)
  foreach(f assets/hero.sphc reports/hero.json)
    if(NOT EXISTS ${WORK}/make_build/${f})
      message(FATAL_ERROR "Unix Makefiles: spherechain_bake did not write ${f} into its new folder:\n${out}")
    endif()
  endforeach()
  message("cmake_bake: with Unix Makefiles, the asset and report written into folders the build made")
else()
  message("SKIPPED: the Unix Makefiles bake (no make)")
endif()

# With Ninja, an input whose path holds '#' cannot be named through CMake's depfile rewrite: the configure warns.
file(WRITE ${WORK}/hash_src/CMakeLists.txt "cmake_minimum_required(VERSION 3.20)
project(hash_bake LANGUAGES NONE)
find_package(spherechain CONFIG REQUIRED COMPONENTS cli)
spherechain_bake(OUTPUT hero.sphc INPUT \"art#1/hero.gltf\")
")
run("configure (Ninja, a '#' in the input's path)" ${CMAKE_COMMAND} -S ${WORK}/hash_src -B ${WORK}/hash_build -G Ninja
    -DCMAKE_MAKE_PROGRAM=${NINJA} -DCMAKE_PREFIX_PATH=${WORK}/prefix)
# CMake wraps a warning's lines at a width, so where the break falls depends on the path's length: match on
# the message with its runs of white space made single spaces.
string(REGEX REPLACE "[ \t\r\n]+" " " flat "${out}")
if(NOT flat MATCHES "holds a '\\$' or '#'")
  message(FATAL_ERROR "spherechain_bake did not warn about a '#' in a path under Ninja:\n${out}")
endif()
