# API reference: `cmake --build <dir> --target docs` runs Doxygen on the public headers (<room>/include),
# docs/mainpage.md and docs/namespaces.dox into <dir>/docs/api/index.html. Not part of ALL. Any Doxygen
# warning fails the target (docs/Doxyfile.in: WARN_AS_ERROR = FAIL_ON_WARNINGS); the test docs_warning_free
# (tests/CMakeLists.txt) builds it.
find_package(Doxygen QUIET)
if(NOT DOXYGEN_FOUND)
  message(STATUS "spherechain: doxygen not found — no `docs` target (Debian: doxygen)")
  return()
endif()

# Every room's public headers, whether or not the room is built in this configuration: INPUT, the include
# path (formulas.h includes formulas.inl) and the prefix stripped from the include names shown.
set(SPHERECHAIN_DOCS_INCLUDE_PATH "")
foreach(_room runtime import baker playback evaluate cuda)
  if(IS_DIRECTORY ${PROJECT_SOURCE_DIR}/${_room}/include)
    string(APPEND SPHERECHAIN_DOCS_INCLUDE_PATH " \"${PROJECT_SOURCE_DIR}/${_room}/include\"")
  endif()
endforeach()
set(SPHERECHAIN_DOCS_OUTPUT_DIR ${CMAKE_BINARY_DIR}/docs)
configure_file(${PROJECT_SOURCE_DIR}/docs/Doxyfile.in ${SPHERECHAIN_DOCS_OUTPUT_DIR}/Doxyfile @ONLY)

add_custom_target(docs
  COMMAND ${DOXYGEN_EXECUTABLE} ${SPHERECHAIN_DOCS_OUTPUT_DIR}/Doxyfile
  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
  COMMENT "Doxygen: API reference of the public headers -> ${SPHERECHAIN_DOCS_OUTPUT_DIR}/api/index.html"
  VERBATIM)
