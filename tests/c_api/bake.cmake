# Bakes the real asset of the C API's tests (fixture c_api_asset) with the CLI: INPUT -> OUTPUT, with the bake
# configuration CONFIG. Skips (visibly) when the input is absent, leaving no OUTPUT behind, so the tests that need
# it skip too.
file(REMOVE ${OUTPUT})
if(NOT EXISTS ${INPUT})
  message("SKIPPED: ${INPUT} not found (../shared/data is absent)")
  return()
endif()
get_filename_component(dir ${OUTPUT} DIRECTORY)
file(MAKE_DIRECTORY ${dir})
execute_process(COMMAND ${CLI} bake ${INPUT} --config ${CONFIG} -o ${OUTPUT}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${OUTPUT})
  message(FATAL_ERROR "bake failed (${rc}):\n${out}${err}")
endif()
message("baked ${OUTPUT}")
