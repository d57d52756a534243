# `spherechain evaluate` on the MakeHuman morph (the asset of the cli_bake_makehuman fixture): the narrow
# phase equals the exact ground truth (recall = precision = 1), the JSON has the documented keys, the
# PNG is written, --min-recall gates the exit code; bad input (a --min-recall outside [0, 1], the wrong
# mesh, an unknown clip) exits 1 with a message and writes nothing. Skips visibly when data is absent.
foreach(f ${MESH} ${ASSET})
  if(NOT EXISTS ${f})
    message("SKIPPED: ${f} not found (../shared/data is absent)")
    return()
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

execute_process(COMMAND ${CLI} -q evaluate ${ASSET} --mesh ${MESH} --json ${WORK}/eval.json --png ${WORK}/eval.png
                        --min-recall 0 --sweep-margin=0,0.004,0.02
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "evaluate failed (${rc}):\n${out}${err}")
endif()
message(STATUS "${out}")
if(NOT err MATCHES "evaluate: frame 40/40")
  message(FATAL_ERROR "no progress line on stderr:\n${err}")
endif()
if(NOT EXISTS ${WORK}/eval.png)
  message(FATAL_ERROR "--png wrote nothing")
endif()
file(READ ${WORK}/eval.json json)
foreach(key "summary;proxy;recall_m1" "summary;proxy;recall_m2" "summary;narrow;recall" "summary;narrow;precision"
            "summary;coverage;phi1_adjusted" "summary;protrusion;phi1_adjusted")
  string(JSON v GET "${json}" ${key})
  message(STATUS "${key}: ${v}")
endforeach()
string(JSON n_recall GET "${json}" summary narrow recall)
string(JSON n_precision GET "${json}" summary narrow precision)
string(JSON contacts GET "${json}" summary contacts)
if(NOT n_recall EQUAL 1 OR NOT n_precision EQUAL 1)
  message(FATAL_ERROR "narrow phase vs exact ground truth: recall ${n_recall}, precision ${n_precision} (expected 1, 1)")
endif()
if(NOT contacts GREATER 0)
  message(FATAL_ERROR "the MakeHuman morph should have contacts, got ${contacts}")
endif()
# The refit spheres measured against every deformed frame: a coverage near the bind fit's (a broken
# refit that left the spheres at bind pose or scattered them would fall far below), and the list of
# spheres sticking out of the skin.
string(JSON refit_cov GET "${json}" summary refit coverage_median)
string(JSON bind_cov GET "${json}" summary coverage phi1_adjusted)
string(JSON stick TYPE "${json}" summary refit spheres_sticking_out)
string(JSON f0_cov GET "${json}" frames 0 refit_coverage coverage)
message(STATUS "refit coverage median ${refit_cov} (bind ${bind_cov}), frame 0 ${f0_cov}")
if(refit_cov LESS 0.8 OR refit_cov GREATER 1 OR NOT stick STREQUAL "ARRAY" OR f0_cov LESS 0.8)
  message(FATAL_ERROR "refit coverage across the animation: median ${refit_cov}, frame 0 ${f0_cov}, spheres_sticking_out ${stick}")
endif()
string(JSON ff TYPE "${json}" summary proxy false_alarm_frames)
string(JSON fr LENGTH "${json}" frames)
string(JSON e TYPE "${json}" frames 0 exact_region_pairs)
string(JSON e2 TYPE "${json}" frames 0 proxy_region_pairs_m2)
string(JSON e3 TYPE "${json}" frames 0 narrow_region_pairs)
if(NOT ff STREQUAL "ARRAY" OR NOT fr EQUAL 40 OR NOT e STREQUAL "ARRAY" OR NOT e2 STREQUAL "ARRAY" OR NOT e3 STREQUAL "ARRAY")
  message(FATAL_ERROR "JSON shape: false_alarm_frames ${ff}, ${fr} frames, region pair lists ${e} ${e2} ${e3}")
endif()

# --sweep-margin: one row per margin; the row at the asset's own margin (0.4 % of the height, the bake's
# default) is the main result; a larger margin reports a superset of pairs, so recall and false alarms
# never drop and the pairs per frame grow (they would stay flat if the margin were ignored).
string(JSON n_sweep LENGTH "${json}" margin_sweep)
if(NOT n_sweep EQUAL 3)
  message(FATAL_ERROR "margin_sweep: ${n_sweep} rows, expected 3")
endif()
string(JSON main_recall GET "${json}" summary proxy recall_m2)
string(JSON main_false GET "${json}" summary proxy false_alarms_m2)
# Sphere-pair precision: the share of M2's reported pairs whose own surrounding regions come within the
# margin. Every pair that is an exact contact counts as precise, so it is at least found / reported (> 0 on the
# crossed arms), and pairs listed as imprecise in a frame are reported pairs of that frame.
string(JSON main_precision GET "${json}" summary proxy sphere_precision_m2)
string(JSON reported GET "${json}" summary proxy sphere_pairs_m2)
message(STATUS "sphere-pair precision M2 ${main_precision} of ${reported} reported pairs")
if(NOT main_precision GREATER 0.3 OR main_precision GREATER 1 OR NOT reported GREATER 0)
  message(FATAL_ERROR "sphere-pair precision ${main_precision} (${reported} pairs reported): expected in (0.3, 1]")
endif()
# The asset-independent truth (contacts by bind distance): the crossed arms' hand and forearm lie far apart at
# bind, so there are such contacts; a reported sphere pair always reports its region pair, so the region pairs
# cover at least what the sphere pairs cover.
string(JSON apart GET "${json}" summary contacts_by_bind_distance triangle_pairs)
string(JSON apart_s GET "${json}" summary contacts_by_bind_distance covered_by_sphere_pairs_m2)
string(JSON apart_r GET "${json}" summary contacts_by_bind_distance covered_by_region_pairs_m2)
message(STATUS "contacts by bind distance: ${apart} triangle pairs, covered by sphere pairs ${apart_s}, region pairs ${apart_r}")
if(NOT apart GREATER 0 OR apart_s GREATER apart_r OR apart_r GREATER 1 OR NOT apart_r GREATER 0.5)
  message(FATAL_ERROR "contacts_by_bind_distance: ${apart} pairs, sphere cover ${apart_s}, region cover ${apart_r}")
endif()
string(JSON ip TYPE "${json}" frames 0 imprecise_sphere_pairs_m2)
if(NOT ip STREQUAL "ARRAY")
  message(FATAL_ERROR "frames[0].imprecise_sphere_pairs_m2: ${ip}, expected an array")
endif()
set(prev_recall -1)
set(prev_pairs -1)
set(prev_false -1)
foreach(i 0 1 2)
  string(JSON m GET "${json}" margin_sweep ${i} margin_rel)
  string(JSON r GET "${json}" margin_sweep ${i} recall_m2)
  string(JSON fa GET "${json}" margin_sweep ${i} false_alarms_m2)
  string(JSON p GET "${json}" margin_sweep ${i} sphere_pairs_per_frame_m2)
  message(STATUS "sweep margin ${m}: recall M2 ${r}, false alarms ${fa}, ${p} sphere pairs a frame")
  if(r LESS prev_recall OR fa LESS prev_false OR NOT p GREATER prev_pairs)
    message(FATAL_ERROR "margin sweep not monotonic at margin ${m}: recall ${r}, false ${fa}, pairs ${p}")
  endif()
  set(prev_recall ${r})
  set(prev_pairs ${p})
  set(prev_false ${fa})
  if(i EQUAL 1 AND (NOT r EQUAL main_recall OR NOT fa EQUAL main_false))
    message(FATAL_ERROR "sweep at the asset's margin: recall ${r}, false ${fa}; main result: ${main_recall}, ${main_false}")
  endif()
  string(JSON sp GET "${json}" margin_sweep ${i} sphere_precision_m2)
  if(i EQUAL 1 AND NOT sp EQUAL main_precision)
    message(FATAL_ERROR "sweep at the asset's margin: sphere precision ${sp}; main result: ${main_precision}")
  endif()
endforeach()

# --refit joints: the proxy a GPU-skinned game gets (centres skinned by the frame's joint matrices) against
# the same truth. Spheres left at the bind pose (a joint refit that did nothing) would miss the crossed arms
# of frames 1-3 entirely (10 frames: two a key pose, the first key at frame 1).
execute_process(COMMAND ${CLI} -q evaluate ${ASSET} --mesh ${MESH} --frames 10 --no-coverage --refit joints
                        --json ${WORK}/joints.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "evaluate --refit joints failed (${rc}):\n${out}${err}")
endif()
file(READ ${WORK}/joints.json jj)
string(JSON refit_kind GET "${jj}" refit)
string(JSON j_recall GET "${jj}" summary proxy recall_m2)
string(JSON j_contacts GET "${jj}" summary contacts)
message(STATUS "--refit joints on 10 frames: ${j_contacts} contacts, region-pair recall M2 ${j_recall}")
if(NOT refit_kind STREQUAL "joints" OR NOT j_contacts GREATER 0 OR j_recall LESS 0.5)
  message(FATAL_ERROR "--refit joints: refit '${refit_kind}', ${j_contacts} contacts, recall ${j_recall} (expected joints, > 0, >= 0.5)")
endif()

# --min-recall 1.0: exit 1 with the reason when the proxy misses anything on these 16 frames, else 0.
execute_process(COMMAND ${CLI} -q evaluate ${ASSET} --mesh ${MESH} --frames 16 --no-coverage --min-recall 1.0
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT (rc EQUAL 1 AND err MATCHES "is below --min-recall 1.000") AND NOT (rc EQUAL 0 AND out MATCHES ">= --min-recall"))
  message(FATAL_ERROR "--min-recall 1.0: unexpected exit ${rc}:\n${out}${err}")
endif()
message(STATUS "--min-recall 1.0 on 16 frames: exit ${rc}")

# Bad input: exit 1, a message, nothing written.
foreach(case "--min-recall;1.5;is outside \\[0, 1\\]" "--clip;nope;no clip named 'nope'"
             "--sweep-margin;0.01,x;'x' is not a margin")
  list(GET case 0 flag)
  list(GET case 1 value)
  list(GET case 2 expect)
  execute_process(COMMAND ${CLI} evaluate ${ASSET} --mesh ${MESH} ${flag} ${value} --json ${WORK}/bad.json
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT "${out}${err}" MATCHES "${expect}" OR EXISTS ${WORK}/bad.json)
    message(FATAL_ERROR "${flag} ${value}: expected exit 1 with '${expect}' and no output, got ${rc}:\n${out}${err}")
  endif()
endforeach()
if(EXISTS ${WRONG})
  execute_process(COMMAND ${CLI} evaluate ${ASSET} --mesh ${WRONG} --json ${WORK}/bad.json --png ${WORK}/bad.png
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT "${out}${err}" MATCHES "does not match asset" OR EXISTS ${WORK}/bad.json OR EXISTS ${WORK}/bad.png)
    message(FATAL_ERROR "wrong mesh: expected exit 1 with the fingerprint error and no output, got ${rc}:\n${out}${err}")
  endif()
endif()
