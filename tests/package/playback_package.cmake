# The playback library as a package: install this build tree (BUILD) into WORK/prefix, build
# tests/package/playback_consumer against it with find_package(spherechain) and run it on the golden v3
# asset (asset-only validation: no error), on the same asset with its glTF mesh (GLTF, when present: the
# consumer imports it through the installed import library — a glTF import in a find_package consumer used to bind
# to libdraco's older tinygltf and crash), and on a truncated copy (SPHC-LOAD, exit 1).
file(REMOVE_RECURSE ${WORK})
include(${CMAKE_CURRENT_LIST_DIR}/../run_step.cmake)  # run()
run("install" ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix)
foreach(f lib/libspherechain_playback.a lib/libspherechain_baker.a include/spherechain/playback/play.h
          include/spherechain/import/types.h)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run("configure the consumer" ${CMAKE_COMMAND} -S ${SRC}/tests/package/playback_consumer -B ${WORK}/consumer -G Ninja
    -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release)
run("build the consumer" ${CMAKE_COMMAND} --build ${WORK}/consumer)
# Playback needs the importers and the runtime, not the baker: the consumer's link line must not name it.
file(READ ${WORK}/consumer/build.ninja link_rules)
if(link_rules MATCHES "libspherechain_baker")
  message(FATAL_ERROR "the playback consumer links the baker (spherechain::playback must not depend on it)")
endif()
if(NOT link_rules MATCHES "libspherechain_import")
  message(FATAL_ERROR "the playback consumer does not link spherechain::import (the check above would prove nothing)")
endif()
run("run the consumer" ${WORK}/consumer/playback_consumer ${ASSET})
if(NOT out MATCHES "errors 0")
  message(FATAL_ERROR "the consumer reported errors on the golden asset: ${out}")
endif()
if(GLTF AND EXISTS "${GLTF}")
  run("run the consumer with the glTF mesh" ${WORK}/consumer/playback_consumer ${ASSET} ${GLTF})
  if(NOT out MATCHES "errors 0")
    message(FATAL_ERROR "the consumer reported errors on the golden asset with ${GLTF}: ${out}")
  endif()
else()
  message("SKIPPED: the glTF import through the package (no ${GLTF}: ../shared/data absent)")
endif()
file(WRITE ${WORK}/truncated.sphc "")  # an empty file: not loadable
execute_process(COMMAND ${WORK}/consumer/playback_consumer ${WORK}/truncated.sphc RESULT_VARIABLE rc OUTPUT_VARIABLE out2)
if(NOT rc EQUAL 1 OR NOT out2 MATCHES "SPHC-LOAD")
  message(FATAL_ERROR "the consumer on an empty asset: exit ${rc}, expected 1 with SPHC-LOAD:\n${out2}")
endif()
message("playback consumer built against ${WORK}/prefix: ${out}")
# A C game against the whole install: find_package(spherechain COMPONENTS c) looks for none of the offline tools'
# dependencies, so CGAL's configuration messages and warnings do not appear in the game's configure.
run("configure a C-only consumer" ${CMAKE_COMMAND} -S ${SRC}/tests/package/consumer -B ${WORK}/consumer_c_only -G Ninja
    -DC_ONLY=ON -DCMAKE_PREFIX_PATH=${WORK}/prefix)
if(out MATCHES "CGAL|assimp|Eigen")
  message(FATAL_ERROR "find_package(spherechain COMPONENTS c) looked for the offline dependencies:\n${out}")
endif()
run("build the C-only consumer" ${CMAKE_COMMAND} --build ${WORK}/consumer_c_only)
