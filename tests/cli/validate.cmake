# `spherechain validate`: a fresh bake validates against its own mesh (exit 0, JSON written) and fails
# against another character's mesh (non-zero, FP-COUNTS named). Skips visibly when inputs are absent.
foreach(f ${INPUT} ${WRONG})
  if(NOT EXISTS ${f})
    message("SKIPPED: ${f} not found")
    return()
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${CLI} bake ${INPUT} -o ${WORK}/a.sphc RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "bake failed (${rc}):\n${out}${err}")
endif()

execute_process(COMMAND ${CLI} validate ${WORK}/a.sphc --mesh ${INPUT} --json ${WORK}/ok.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "validate against its own mesh: expected exit 0, got ${rc}:\n${out}${err}")
endif()
if(NOT EXISTS ${WORK}/ok.json)
  message(FATAL_ERROR "validate --json wrote nothing")
endif()
message(STATUS "own mesh: ${out}")

execute_process(COMMAND ${CLI} validate ${WORK}/a.sphc --mesh ${WRONG}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "validate against the wrong mesh: expected a non-zero exit, got 0:\n${out}${err}")
endif()
if(NOT "${out}${err}" MATCHES "FP-COUNTS")
  message(FATAL_ERROR "validate against the wrong mesh: FP-COUNTS not reported:\n${out}${err}")
endif()
message(STATUS "wrong mesh: exit ${rc}: ${out}")

execute_process(COMMAND ${CLI} validate ${WORK}/missing.sphc RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "validate of a missing asset: expected a non-zero exit")
endif()
