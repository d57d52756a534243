# Outputs all or nothing, on CesiumMan: a command whose last output cannot be written exits non-zero and
# leaves an earlier run's outputs as they were (byte for byte); `play --dump-frames` leaves the folder holding
# the run's frames only; values out of range (NaN, 0 frames) and --clip with --morph are usage errors (exit 2)
# found before the mesh is read; `export-debug -o X.glb` writes binary glTF. An output that cannot be written
# after every check passed is an output in /proc (its folder exists; no file can be created there, even as
# root). Skips (visibly) when ../shared/data is absent.
if(NOT EXISTS ${GLTF})
  message("SKIPPED: ${GLTF} not found (../shared/data is absent)")
  return()
endif()
if(NOT IS_DIRECTORY /proc/self)
  message("SKIPPED: no /proc (the unwritable output these cases need)")
  return()
endif()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

function(run expect_rc name)
  execute_process(COMMAND ${CLI} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL ${expect_rc})
    message(FATAL_ERROR "${name}: expected exit ${expect_rc}, got ${rc}:\n${out}${err}")
  endif()
  set(last_err "${err}" PARENT_SCOPE)
  set(last_out "${out}" PARENT_SCOPE)
endfunction()

# The failure's message names the output as the user gave it, never a hidden temporary.
function(expect_named name path)
  if(NOT last_err MATCHES "'${path}'" OR last_err MATCHES "\\.tmp[0-9]")
    message(FATAL_ERROR "${name}: the message should name '${path}', not a temporary:\n${last_err}")
  endif()
endfunction()

# An earlier run's output, unchanged by a failed run.
function(expect_kept name path)
  file(READ ${path} now)
  if(NOT now STREQUAL "earlier run")
    message(FATAL_ERROR "${name}: '${path}' was changed or removed by a failed run")
  endif()
endfunction()

run(0 bake bake ${GLTF} -o ${WORK}/cm.sphc)
set(A ${WORK}/cm.sphc)

# bake: the asset cannot be written; the report and the depfile of an earlier run stay.
file(WRITE ${WORK}/r.json "earlier run")
file(WRITE ${WORK}/cm.d "earlier run")
run(1 bake_fails bake ${GLTF} -o /proc/cm.sphc --report ${WORK}/r.json --depfile ${WORK}/cm.d)
expect_named(bake_fails /proc/cm.sphc)
expect_kept(bake_fails ${WORK}/r.json)
expect_kept(bake_fails ${WORK}/cm.d)

# export-debug: the glTF cannot be written; the picture of an earlier run stays.
file(WRITE ${WORK}/d.png "earlier run")
run(1 export_debug_fails export-debug ${A} --mesh ${GLTF} -o /proc/d.gltf --png ${WORK}/d.png)
expect_named(export_debug_fails /proc/d.gltf)
expect_kept(export_debug_fails ${WORK}/d.png)

# evaluate: the JSON cannot be written; the picture of an earlier run stays.
file(WRITE ${WORK}/e.png "earlier run")
run(1 evaluate_fails evaluate ${A} --mesh ${GLTF} --frames 3 --json /proc/e.json --png ${WORK}/e.png)
expect_named(evaluate_fails /proc/e.json)
expect_kept(evaluate_fails ${WORK}/e.png)

# check: the JUnit report cannot be written (exit 2, the verdict said); the JSON of an earlier run stays.
file(WRITE ${WORK}/c.json "earlier run")
run(2 check_fails check ${GLTF} --asset ${A} --json ${WORK}/c.json --junit /proc/c.xml)
if(NOT last_err MATCHES "the check itself: (PASS|FAIL); no report written")
  message(FATAL_ERROR "check_fails: the verdict is not said:\n${last_err}")
endif()
expect_kept(check_fails ${WORK}/c.json)

# play --dump-frames: a failed run leaves the folder as it was; a shorter run removes a longer one's frames
# (a benchmark reads every frame file there) and nothing else.
file(MAKE_DIRECTORY ${WORK}/frames ${WORK}/frames/frame_0099.f32)
file(WRITE ${WORK}/frames/notes.txt "earlier run")
file(WRITE ${WORK}/frames/frame_7.joints "earlier run")
run(1 play_fails play ${A} --mesh ${GLTF} --frames 6 --repeat 1 --dump-frames ${WORK}/frames --json /proc/p.json)
file(GLOB left LIST_DIRECTORIES true ${WORK}/frames/* ${WORK}/frames/.frame*)
if(NOT left STREQUAL "${WORK}/frames/frame_0099.f32;${WORK}/frames/frame_7.joints;${WORK}/frames/notes.txt")
  message(FATAL_ERROR "play_fails: a failed run left files in the frames folder: ${left}")
endif()
run(0 play_six play ${A} --mesh ${GLTF} --frames 6 --repeat 1 --dump-frames ${WORK}/frames)
run(0 play_three play ${A} --mesh ${GLTF} --frames 3 --repeat 1 --dump-frames ${WORK}/frames)
file(GLOB f32 LIST_DIRECTORIES false ${WORK}/frames/frame_*.f32)
file(GLOB joints LIST_DIRECTORIES false ${WORK}/frames/frame_????*.joints)
list(LENGTH f32 n_f32)
list(LENGTH joints n_joints)
if(NOT n_f32 EQUAL 3 OR NOT n_joints EQUAL 3 OR NOT last_out MATCHES "removed 6 frame files of an earlier run")
  message(FATAL_ERROR "play --frames 3 after --frames 6: ${n_f32} .f32 and ${n_joints} .joints files:\n${last_out}")
endif()
expect_kept(play_three ${WORK}/frames/notes.txt)
expect_kept(play_three ${WORK}/frames/frame_7.joints)  # not a name play writes (4 digits at least)
if(NOT IS_DIRECTORY ${WORK}/frames/frame_0099.f32)
  message(FATAL_ERROR "play_three: removed a folder named like a frame")
endif()

# Usage errors found while parsing: exit 2 before the mesh is imported (no import line logged).
foreach(case "evaluate;--frames;0" "evaluate;--crease;nan" "play;--narrow-behind;nan" "play;--narrow-behind;0"
             "play;--narrow-behind;1e-50"
             "play;--clip;x;--morph" "view;--frames;0;-o;${WORK}/v.html")
  list(POP_FRONT case command)
  run(2 "${command} ${case}" ${command} ${A} --mesh ${GLTF} ${case})
  if(last_err MATCHES "import:" OR NOT last_err MATCHES "(not in range|is not >=|excludes)")
    message(FATAL_ERROR "${command} ${case}: not refused while parsing:\n${last_err}")
  endif()
endforeach()

# export-debug without an animation: its options are refused, not ignored.
run(2 export_static_frames export-debug ${A} --mesh ${GLTF} -o ${WORK}/s.gltf --frames 5)
if(NOT last_err MATCHES "--frames needs --clip or --morph" OR EXISTS ${WORK}/s.gltf)
  message(FATAL_ERROR "export-debug --frames without an animation:\n${last_err}")
endif()

# export-debug -o X.glb: binary glTF (magic "glTF", version 2).
run(0 export_glb export-debug ${A} --mesh ${GLTF} -o ${WORK}/d.glb)
file(READ ${WORK}/d.glb head LIMIT 8 HEX)
if(NOT head STREQUAL "676c544602000000")
  message(FATAL_ERROR "export-debug -o d.glb: not binary glTF (first bytes ${head})")
endif()
