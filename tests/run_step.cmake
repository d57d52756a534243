# run(WHAT COMMAND ARGS...) for the CMake-script tests: runs one step; a non-zero exit fails the test with
# WHAT, the exit code and everything the step printed. Sets `out` in the caller to what it printed (stdout,
# then stderr).
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}${err}")
  endif()
  set(out "${out}${err}" PARENT_SCOPE)
endfunction()
