# "No silent wrong bake" (issue 11): a body failing a plausibility check (tests/data/implausible: four
# limbs detached from the torso by the region map) is refused — exit 1, the code named, nothing written
# (asset, report, png) —; with --force the asset and report are written, the report and `inspect` carry
# the findings and `validate` exits non-zero naming the code. Fast (0.1 s a bake): 424 triangles, coarse
# voxels (fast.json), no shared data.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
set(_args bake ${DATA}/boxes.obj --region-map ${DATA}/limbs_detached.json --config ${DATA}/fast.json
          -o ${WORK}/a.sphc --report ${WORK}/a.json)

execute_process(COMMAND ${CLI} ${_args} --png ${WORK}/a.png RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "bake of an implausible body: expected exit 1, got ${rc}:\n${out}${err}")
endif()
if(NOT "${out}${err}" MATCHES "PLAUS-LIMB-DETACHED: left_arm shares no vertex with the torso")
  message(FATAL_ERROR "bake of an implausible body: PLAUS-LIMB-DETACHED (left_arm) not named:\n${out}${err}")
endif()
if(NOT "${out}${err}" MATCHES "--force")
  message(FATAL_ERROR "bake of an implausible body: the refusal does not mention --force:\n${out}${err}")
endif()
file(GLOB _left ${WORK}/*)
if(_left)
  message(FATAL_ERROR "bake of an implausible body left files behind: ${_left}")
endif()
message(STATUS "refused: exit ${rc}: ${err}")

execute_process(COMMAND ${CLI} ${_args} --force RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK}/a.sphc OR NOT EXISTS ${WORK}/a.json)
  message(FATAL_ERROR "bake --force: expected exit 0 and an asset and a report, got ${rc}:\n${out}${err}")
endif()
if(NOT out MATCHES "FAILED, written anyway" OR NOT out MATCHES "PLAUS-LIMB-DETACHED")
  message(FATAL_ERROR "bake --force: the summary does not list the failed checks:\n${out}${err}")
endif()
file(READ ${WORK}/a.json _report)
string(JSON _passed GET "${_report}" plausibility passed)
string(JSON _forced GET "${_report}" plausibility forced)
string(JSON _n LENGTH "${_report}" plausibility errors)
string(JSON _code GET "${_report}" plausibility errors 0 code)
string(JSON _sev GET "${_report}" plausibility errors 0 severity)
if(_passed OR NOT _forced OR NOT _n EQUAL 4 OR NOT _code STREQUAL "PLAUS-LIMB-DETACHED" OR NOT _sev STREQUAL "error")
  message(FATAL_ERROR "bake --force report: plausibility = passed ${_passed}, forced ${_forced}, ${_n} errors, "
                      "first ${_code} (${_sev}); expected 4 PLAUS-LIMB-DETACHED errors")
endif()

execute_process(COMMAND ${CLI} inspect ${WORK}/a.sphc RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "FORCED" OR NOT out MATCHES "PLAUS-LIMB-DETACHED")
  message(FATAL_ERROR "inspect of a forced asset: the findings are not shown (${rc}):\n${out}${err}")
endif()

foreach(_mesh "" ${DATA}/boxes.obj)
  set(_with)
  if(_mesh)
    set(_with --mesh ${_mesh})
  endif()
  execute_process(COMMAND ${CLI} validate ${WORK}/a.sphc ${_with} --json ${WORK}/v.json
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0)
    message(FATAL_ERROR "validate ${_with} of a forced asset: expected a non-zero exit, got 0:\n${out}${err}")
  endif()
  if(NOT out MATCHES "error +PLAUS-LIMB-DETACHED")
    message(FATAL_ERROR "validate ${_with} of a forced asset: PLAUS-LIMB-DETACHED not reported as an error:\n${out}${err}")
  endif()
  message(STATUS "validate ${_with}: exit ${rc}:\n${out}")
endforeach()
