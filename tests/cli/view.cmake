# `spherechain view` on the MakeHuman morph, opened from disk in a real browser (headless Chromium,
# software WebGL): the HTML is self-contained and <= 10 MB; on a frame with contacts (hand on the opposite
# shoulder) the page reports ready with no console output, and the screenshot has the contact colour
# where the page says the contact triangles are, a drawn body and the timeline's bars; at the start of
# the morph (frame 0, no contacts) no pixel of the contact colour. Without three.js, `view` fails saying how to install it
# and writes nothing. Skips (visibly) when ../shared/data, Chromium or three.js is absent.
cmake_policy(VERSION 3.22)
if(NOT EXISTS ${MESH} OR NOT EXISTS ${ASSET})
  message("SKIPPED: ${MESH} or ${ASSET} not found (../shared/data is absent)")
  return()
endif()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# Without three.js (an empty --three folder): exit 1, a message naming `npm ci`, no file.
execute_process(COMMAND ${CLI} view ${ASSET} --mesh ${MESH} --three ${WORK} -o ${WORK}/none.html
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT "${out}${err}" MATCHES "three.js not found.*npm ci" OR EXISTS ${WORK}/none.html)
  message(FATAL_ERROR "view without three.js: expected exit 1, a message naming `npm ci` and no file; got ${rc}:\n${out}${err}")
endif()

# An output folder that does not exist, or an output that is a folder: exit 2 before three.js or a frame.
foreach(out "${WORK}/missing/v.html" "${WORK}")
  execute_process(COMMAND ${CLI} view ${ASSET} --mesh ${MESH} --three ${WORK} -o ${out}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out_text ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT "${out_text}${err}" MATCHES "cannot write .*(does not exist|it is a folder)"
     OR EXISTS ${WORK}/missing)
    message(FATAL_ERROR "view -o ${out}: expected exit 2 naming the path; got ${rc}:\n${out_text}${err}")
  endif()
endforeach()

execute_process(COMMAND ${CLI} view ${ASSET} --mesh ${MESH} -o ${WORK}/makehuman.html
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  if("${out}${err}" MATCHES "three.js not found")
    message("SKIPPED: three.js is not installed (run `npm ci` in viewer/):\n${out}${err}")
    return()
  endif()
  message(FATAL_ERROR "view failed (${rc}):\n${out}${err}")
endif()
message(STATUS "${out}")
file(SIZE ${WORK}/makehuman.html size)
math(EXPR kb "${size} / 1024")
message(STATUS "makehuman.html: ${kb} KiB")
if(size GREATER 10485760)
  message(FATAL_ERROR "makehuman.html is ${kb} KiB, over 10 MiB")
endif()
# Self-contained: no script or import from elsewhere.
file(STRINGS ${WORK}/makehuman.html remote REGEX "src=\"(https?:)?//|from ['\"]https?:|\"https?://[^\"]*\\.js\"")
if(remote)
  message(FATAL_ERROR "makehuman.html loads something from the network:\n${remote}")
endif()

find_program(CHROMIUM NAMES chromium chromium-browser google-chrome)
if(NOT CHROMIUM)
  message("SKIPPED: chromium not found (Debian: apt-get install chromium; scripts/setup.sh installs it)")
  return()
endif()
find_program(PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT PYTHON)
  find_program(PYTHON NAMES python3)
endif()

# Runs Chromium once more when it times out or fails to start: a browser stuck on a loaded machine is not a
# finding about the page (what the page reports is checked after, on the run that finished).
function(run_chrome out_var err_var rc_var)
  foreach(attempt 1 2)
    execute_process(COMMAND ${chrome} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
    if(rc EQUAL 0)
      break()
    endif()
    message(STATUS "chromium attempt ${attempt} ended with '${rc}'")
  endforeach()
  set(${out_var} "${out}" PARENT_SCOPE)
  set(${err_var} "${err}" PARENT_SCOPE)
  set(${rc_var} "${rc}" PARENT_SCOPE)
endfunction()

set(chrome ${CHROMIUM} --headless --no-sandbox --disable-gpu --use-angle=swiftshader --enable-unsafe-swiftshader
    --hide-scrollbars --no-first-run --user-data-dir=${WORK}/profile --window-size=1000,780
    --virtual-time-budget=15000)
# frame 12: hand on the opposite shoulder (R1 × R4 in contact); frame 0: the bind pose, no contact
foreach(case "12;some" "0;none")
  list(GET case 0 frame)
  list(GET case 1 expect)
  set(url "file://${WORK}/makehuman.html#frame=${frame}&size=1000x600")
  run_chrome(dom err rc --dump-dom ${url})
  string(REGEX MATCH "<body[^>]*>" body "${dom}")
  if(NOT rc EQUAL 0 OR NOT body MATCHES "data-status=\"ready\"")
    message(FATAL_ERROR "frame ${frame}: the page did not report ready (chromium exit ${rc}): '${body}'\n${err}")
  endif()
  string(REGEX MATCH "data-contacts=\"([0-9]+)\"" _ "${body}")
  set(n_contacts ${CMAKE_MATCH_1})
  string(REGEX MATCH "data-view=\"([-0-9,]+)\"" _ "${body}")
  set(view_rect ${CMAKE_MATCH_1})
  string(REGEX MATCH "data-contact-box=\"([-0-9,]*)\"" _ "${body}")
  set(contact_box ${CMAKE_MATCH_1})
  message(STATUS "frame ${frame}: ${body}")
  if(NOT body MATCHES "data-frame=\"${frame}\"")
    message(FATAL_ERROR "frame ${frame}: the page shows another frame: ${body}")
  endif()

  set(png ${WORK}/frame_${frame}.png)
  run_chrome(out log rc --enable-logging=stderr --v=0 --screenshot=${png} ${url})
  if(NOT rc EQUAL 0 OR NOT EXISTS ${png})
    message(FATAL_ERROR "frame ${frame}: no screenshot (chromium exit ${rc}):\n${out}${log}")
  endif()
  # The page logs nothing; the only console lines allowed are software GL's performance notes.
  string(REGEX MATCHALL "[^\n]*:CONSOLE[^\n]*" console "${log}")
  list(FILTER console EXCLUDE REGEX "GL Driver Message \\(OpenGL, Performance")
  if(console)
    message(FATAL_ERROR "frame ${frame}: console output:\n${console}")
  endif()

  if(expect STREQUAL "some")
    if(NOT n_contacts GREATER 0 OR contact_box STREQUAL "")
      message(FATAL_ERROR "frame ${frame}: expected contacts, the page reports ${n_contacts} (box '${contact_box}')")
    endif()
    set(check --contact-box ${contact_box} --min-contact 20)
  else()
    if(NOT n_contacts EQUAL 0)
      message(FATAL_ERROR "frame ${frame} (start of the morph): expected no contacts, the page reports ${n_contacts}")
    endif()
    set(check --no-contact)
  endif()
  execute_process(COMMAND ${PYTHON} ${CMAKE_CURRENT_LIST_DIR}/view_check.py ${png} --view ${view_rect} ${check}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "frame ${frame}: screenshot check failed (${png})")
  endif()
endforeach()

# Names from the input files are text, never markup: a key pose named like an HTML element (the page shows
# the frame's label) stays text in the page, and its onerror never runs.
file(READ ${CMAKE_CURRENT_LIST_DIR}/../../data/poses/makehuman/hand_on_shoulder.json pose)
string(REGEX REPLACE "\"name\": \"[^\"]*\"" "\"name\": \"<img src=x onerror=\\\\\"document.body.dataset.pwned=1\\\\\">\""
       pose "${pose}")
file(WRITE ${WORK}/evil_pose.json "${pose}")
execute_process(COMMAND ${CLI} view ${ASSET} --mesh ${MESH} --morph ${WORK}/evil_pose.json --frames 4
                        -o ${WORK}/evil.html RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "view with a pose named like markup failed (${rc}):\n${out}${err}")
endif()
run_chrome(dom err rc --dump-dom "file://${WORK}/evil.html#frame=2&size=600x400")
string(REGEX MATCH "<body[^>]*>" body "${dom}")
if(NOT body MATCHES "data-status=\"ready\"" OR body MATCHES "pwned" OR NOT dom MATCHES "&lt;img src=x")
  message(FATAL_ERROR "a pose's name became markup in the page (or the page did not load): '${body}'")
endif()
message(STATUS "a pose named like markup is shown as text")

# A page too large to hold is refused before any frame is skinned, nothing written.
execute_process(COMMAND ${CLI} view ${ASSET} --mesh ${MESH} --frames 100000 -o ${WORK}/huge.html
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT "${out}${err}" MATCHES "over 512 MB: ask for fewer --frames" OR EXISTS ${WORK}/huge.html)
  message(FATAL_ERROR "view --frames 100000: expected a refusal and no page, got ${rc}:\n${out}${err}")
endif()
