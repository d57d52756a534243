# The installed Python package: `cmake --install BUILD --component python --prefix WORK/prefix`, then PYTHON imports
# spherechain from WORK/prefix/DIR (the package folder the build installs to, relative to the prefix) and not from
# the build tree: the module, the stub, py.typed and the default key poses (evaluate()'s morph) are there, and the
# module loads and verifies an asset of the repository.
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --component python --prefix ${WORK}/prefix
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed (${rc}):\n${out}${err}")
endif()
if(IS_ABSOLUTE "${DIR}")
  message("SPHERECHAIN_PYTHON_INSTALL_DIR is absolute (${DIR}): --prefix does not apply, nothing to check here")
  return()
endif()
set(pkg ${WORK}/prefix/${DIR}/spherechain)
foreach(f __init__.py __init__.pyi py.typed data/poses/makehuman)
  if(NOT EXISTS ${pkg}/${f})
    message(FATAL_ERROR "not installed: ${pkg}/${f}")
  endif()
endforeach()
get_filename_component(golden ${CMAKE_CURRENT_LIST_DIR}/../../tests/data/golden/v4/creature.sphc ABSOLUTE)
execute_process(
  COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${WORK}/prefix/${DIR} PYTHONNOUSERSITE=1
          ${PYTHON} -c "import spherechain, sys; print(spherechain.__file__); a = spherechain.load(sys.argv[1]); print(a.sphere_count, a.info()['schema_version'])" ${golden}
  WORKING_DIRECTORY / RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "import spherechain from ${WORK}/prefix/${DIR} failed (${rc}):\n${out}${err}")
endif()
if(NOT out MATCHES "^${pkg}/__init__.py\n[0-9]+ 4\n")
  message(FATAL_ERROR "spherechain was not imported from the installed package ${pkg}:\n${out}${err}")
endif()
message("installed to ${pkg}; imported from there:\n${out}")
