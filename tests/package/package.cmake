# The runtime as a package, as a game gets it: configure the source tree with the `runtime-noexcept`
# preset (runtime only, -fno-exceptions -fno-rtti) into WORK, build, install into WORK/prefix, then build
# tests/package/consumer against it with find_package(spherechain) (also without exceptions or RTTI)
# and run it on the golden v2 asset; its C program (consumer_c) links the installed C API, spherechain::c. On
# Linux, oom_c checks that the C API returns SC_ERROR_OUT_OF_MEMORY (never aborts) under a capped address space,
# though the runtime beside it is built without exceptions.
file(REMOVE_RECURSE ${WORK})
include(${CMAKE_CURRENT_LIST_DIR}/../run_step.cmake)  # run()
run("configure (preset runtime-noexcept)" ${CMAKE_COMMAND} -S ${SRC} --preset runtime-noexcept -B ${WORK}/build
    -DCMAKE_INSTALL_PREFIX=${WORK}/prefix)
run("build" ${CMAKE_COMMAND} --build ${WORK}/build -j 2)
run("install" ${CMAKE_COMMAND} --install ${WORK}/build)
run("configure the consumer" ${CMAKE_COMMAND} -S ${SRC}/tests/package/consumer -B ${WORK}/consumer
    -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS=-fno-exceptions -fno-rtti")
run("build the consumer" ${CMAKE_COMMAND} --build ${WORK}/consumer)
run("run the consumer" ${WORK}/consumer/consumer ${ASSET})
if(NOT out MATCHES "spheres 128 chains 6 ")
  message(FATAL_ERROR "the consumer read the golden asset wrongly: ${out}")
endif()
message("consumer built against ${WORK}/prefix (no exceptions, no RTTI): ${out}")
run("run the C consumer" ${WORK}/consumer/consumer_c ${ASSET})
if(NOT out MATCHES "C: spheres 128 chains 6 joints 0 m2_pairs [0-9]+")
  message(FATAL_ERROR "the C consumer read the golden asset wrongly: ${out}")
endif()
message("C consumer (spherechain::c, shared) built against ${WORK}/prefix: ${out}")
if(CMAKE_HOST_SYSTEM_NAME STREQUAL "Linux")
  run("run the C API out of memory" ${WORK}/consumer/oom_c ${CREASE_ASSET})
  message("C API out of memory (spherechain::c of a -fno-exceptions build): ${out}")
endif()
# A C game: find_package(spherechain COMPONENTS c) with the FlatBuffers headers out of CMake's sight (the C API needs
# none), builds and runs.
run("configure the C-only consumer" ${CMAKE_COMMAND} -S ${SRC}/tests/package/consumer -B ${WORK}/consumer_c_only
    -DC_ONLY=ON -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release -DCMAKE_IGNORE_PATH=/usr/include)
run("build the C-only consumer" ${CMAKE_COMMAND} --build ${WORK}/consumer_c_only)
run("run the C-only consumer" ${WORK}/consumer_c_only/consumer_c ${ASSET})
if(NOT out MATCHES "C: spheres 128 chains 6")
  message(FATAL_ERROR "the C-only consumer read the golden asset wrongly: ${out}")
endif()
