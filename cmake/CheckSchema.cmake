# Regenerates the schema header with flatc and fails if it differs from the committed copy.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${FLATC} --cpp --scoped-enums -o ${OUT} ${SRC}/schemas/spherechain.fbs RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "flatc failed (${rc})")
endif()
file(READ ${OUT}/spherechain_generated.h generated)
file(READ ${SRC}/runtime/include/spherechain/runtime/schema/spherechain_generated.h committed)
if(NOT generated STREQUAL committed)
  message(FATAL_ERROR "runtime/include/spherechain/runtime/schema/spherechain_generated.h is stale: run "
                      "flatc --cpp --scoped-enums -o runtime/include/spherechain/runtime/schema schemas/spherechain.fbs")
endif()
