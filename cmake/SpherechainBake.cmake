# spherechain_bake(): bake a character into a .sphc asset as a build step of a game's own CMake project.
#
#   find_package(spherechain CONFIG REQUIRED)      # or add_subdirectory(spherechain)
#   spherechain_bake(OUTPUT ${CMAKE_CURRENT_BINARY_DIR}/hero.sphc INPUT art/hero.gltf
#                    [CONFIG art/bake.json] [REPORT hero.json] [OPTIONS --regions paper ...] [COMMENT text])
#   add_custom_target(assets ALL DEPENDS ${CMAKE_CURRENT_BINARY_DIR}/hero.sphc)
#
# One add_custom_command whose OUTPUT is the asset (and the report), run by the `spherechain` executable of the
# package (the imported target spherechain::cli) with `bake --depfile`. The depfile names every file the bake
# read — the character file, its glTF buffers and images, a MakeHuman rig and weights, the configuration, a
# region map — so the build rebakes exactly when one of them changes, and when the spherechain executable
# does. A relative INPUT or CONFIG is taken from the current source folder, a relative OUTPUT or REPORT from the
# current binary folder. OPTIONS go to `spherechain bake` as they are (docs/cli.md; a relative path among them
# is taken from the binary folder, where the bake runs). The asset is written atomically; a failed bake fails
# the build and writes nothing (an asset of an earlier bake stays, older than what changed, so the next
# build bakes again). Needs CMake 3.20 (DEPFILE with every
# generator Ninja and Makefiles use, and policy CMP0116, which this sets for the call's directory).
if(COMMAND spherechain_bake)
  return()
endif()

function(spherechain_bake)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "OUTPUT;INPUT;CONFIG;REPORT;COMMENT" "OPTIONS")
  if(CMAKE_VERSION VERSION_LESS 3.20)
    message(FATAL_ERROR "spherechain_bake: needs CMake 3.20 or newer (add_custom_command DEPFILE), this is ${CMAKE_VERSION}")
  endif()
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "spherechain_bake: unknown arguments: ${arg_UNPARSED_ARGUMENTS} "
                        "(OUTPUT, INPUT, CONFIG, REPORT, OPTIONS, COMMENT)")
  endif()
  if(NOT arg_OUTPUT OR NOT arg_INPUT)
    message(FATAL_ERROR "spherechain_bake: OUTPUT and INPUT are required")
  endif()
  if(NOT TARGET spherechain::cli)
    message(FATAL_ERROR "spherechain_bake: the spherechain executable is not in this package (spherechain::cli): "
                        "it was built without SPHERECHAIN_BUILD_BAKER")
  endif()
  get_filename_component(output "${arg_OUTPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  get_filename_component(input "${arg_INPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  set(outputs "${output}")
  set(args "${input}" -o "${output}" --depfile "${output}.d")
  set(depends "${input}" "$<TARGET_FILE:spherechain::cli>")
  if(arg_CONFIG)
    get_filename_component(config "${arg_CONFIG}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    list(APPEND args --config "${config}")
    list(APPEND depends "${config}")
  endif()
  if(arg_REPORT)
    get_filename_component(report "${arg_REPORT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
    list(APPEND args --report "${report}")
    list(APPEND outputs "${report}")
  endif()
  if(NOT arg_COMMENT)
    get_filename_component(name "${input}" NAME)
    get_filename_component(out_name "${output}" NAME)
    set(arg_COMMENT "Baking ${name} into ${out_name}")
  endif()
  # Ninja reads the depfile through CMake's rewrite of it (CMP0116), which unescapes `$` and `#` but does not
  # escape them again for Ninja: a path holding either is split, and the asset rebakes on every build.
  if(CMAKE_GENERATOR MATCHES "Ninja")
    foreach(path IN LISTS depends outputs)
      if(path MATCHES "[$#]" AND NOT path MATCHES "^\\$<")
        message(WARNING "spherechain_bake: '${path}' holds a '$' or '#': with the Ninja generator CMake's depfile "
                        "rewrite cannot name it, and ${arg_OUTPUT} will bake on every build (Unix Makefiles has no "
                        "such limit)")
      endif()
    endforeach()
  endif()
  # The output and report folders: Ninja makes them, Make does not (and the bake refuses a missing folder).
  set(folders "")
  foreach(path IN LISTS outputs)
    get_filename_component(folder "${path}" DIRECTORY)
    list(APPEND folders "${folder}")
  endforeach()
  list(REMOVE_DUPLICATES folders)
  # Depfile paths are absolute; CMP0116 NEW makes Ninja read them as CMake writes its own (3.20+).
  cmake_policy(PUSH)
  cmake_policy(SET CMP0116 NEW)
  add_custom_command(OUTPUT ${outputs}
                     COMMAND ${CMAKE_COMMAND} -E make_directory ${folders}
                     COMMAND spherechain::cli -q bake ${args} ${arg_OPTIONS}
                     DEPENDS ${depends}
                     DEPFILE "${output}.d"
                     COMMENT "${arg_COMMENT}"
                     VERBATIM)
  cmake_policy(POP)
endfunction()
