# The installed CLI finds its data: `cmake --install` into a temporary prefix, then the installed
# `spherechain play` runs the MakeHuman morph from / and must take the key poses from
# <prefix>/share/spherechain/poses/makehuman (not from the source tree). Skips (visibly) when
# ../shared/data is absent.
if(NOT EXISTS ${MESH} OR NOT EXISTS ${ASSET})
  message("SKIPPED: ${MESH} or ${ASSET} not found (../shared/data is absent)")
  return()
endif()
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc}):\n${out}${err}")
endif()
set(poses ${WORK}/prefix/share/spherechain/poses/makehuman)
file(GLOB pose_files ${poses}/*.json)
list(LENGTH pose_files n)
if(n LESS 2)
  message(FATAL_ERROR "${poses}: ${n} key pose files installed")
endif()
execute_process(COMMAND ${WORK}/prefix/bin/spherechain play ${ASSET} --mesh ${MESH} --frames 10 --repeat 1
                        --json ${WORK}/play.json
                WORKING_DIRECTORY / RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "installed play from / failed (${rc}):\n${out}${err}")
endif()
string(FIND "${out}${err}" "from ${poses}" at)
if(at LESS 0)
  message(FATAL_ERROR "installed play did not take the installed key poses (${poses}):\n${out}${err}")
endif()
file(READ ${WORK}/play.json json)
string(JSON frames LENGTH "${json}" frames)
if(NOT frames EQUAL 10)
  message(FATAL_ERROR "installed play wrote ${frames} frames, expected 10")
endif()
message("installed to ${WORK}/prefix; play from / took the key poses from ${poses}")
