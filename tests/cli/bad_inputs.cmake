# Every bad input: exit 1 (2 for a usage error), an error message naming the problem, and no output file left.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
file(WRITE ${WORK}/notes.txt "hello")
file(WRITE ${WORK}/empty.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\n")
file(WRITE ${WORK}/nan.obj "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
file(WRITE ${WORK}/inf.obj "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n")
file(WRITE ${WORK}/badindex.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
file(WRITE ${WORK}/truncated.gltf "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [")
file(WRITE ${WORK}/cube.obj "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n")
file(WRITE ${WORK}/not_an_asset.sphc "this is not a flatbuffer at all, but long enough to have a header")
file(WRITE ${WORK}/config_bad.json "{\"penetration_depth\": 7}")

# Each case: the exit code (1 for a bad input, 2 for a usage error), the message on stderr (what and where, as
# docs/guide.md "Bad input" gives it) and no output file left.
function(expect_exit name code pattern)
  execute_process(COMMAND ${CLI} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL ${code} OR NOT "${err}" MATCHES "${pattern}" OR EXISTS ${WORK}/out.sphc)
    message(FATAL_ERROR "${name}: expected exit ${code}, '${pattern}' and no output; got exit ${rc}:\n${out}${err}")
  endif()
  message(STATUS "${name}: exit ${rc}: ${err}")
endfunction()

file(WRITE ${WORK}/big.obj "v 0 0 0\nv 1e50 0 0\nv 0 1 0\nf 1 2 3\n")
file(WRITE ${WORK}/empty.fbx "")
file(WRITE ${WORK}/off.stl "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
file(WRITE ${WORK}/g/escape.gltf "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"uri\": \"../secret/data.bin\", \"byteLength\": 36}], \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]}], \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}], \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}")
file(MAKE_DIRECTORY ${WORK}/secret)
file(WRITE ${WORK}/secret/data.bin "0123456789abcdef0123456789abcdef0123")
file(WRITE ${WORK}/png_only.gltf "{\"asset\": {\"version\": \"2.0\"}, \"images\": [{\"uri\": \"data:image/png;base64,AAAAAAAAAAAAAAAA\"}], \"scenes\": [{\"nodes\": []}], \"scene\": 0}")

expect_exit(missing 1 "io: .*missing.obj: file not found" bake ${WORK}/missing.obj -o ${WORK}/out.sphc)
expect_exit(unsupported 1 "format: .*notes.txt: unsupported format '.txt': the baker reads glTF/GLB"
            bake ${WORK}/notes.txt -o ${WORK}/out.sphc)
expect_exit(no_triangles 1 "invalid-mesh: .*empty.obj: no triangles" bake ${WORK}/empty.obj -o ${WORK}/out.sphc)
expect_exit(nan 1 "invalid-mesh: .*nan.obj: vertex 1 has a non-finite coordinate" bake ${WORK}/nan.obj -o ${WORK}/out.sphc)
expect_exit(inf 1 "invalid-mesh: .*inf.obj: vertex 1 has a non-finite coordinate" bake ${WORK}/inf.obj -o ${WORK}/out.sphc)
expect_exit(beyond_float 1 "invalid-mesh: .*big.obj: vertex 1 has a non-finite coordinate" bake ${WORK}/big.obj -o ${WORK}/out.sphc)
expect_exit(bad_index 1 "invalid-mesh: .*badindex.obj: line 4: face references vertex 9 \\(1-based\\) but the file has 3 vertices"
            bake ${WORK}/badindex.obj -o ${WORK}/out.sphc)
expect_exit(truncated_gltf 1 "format: .*truncated.gltf: not a readable glTF file: \\[json.exception.parse_error.101\\]"
            bake ${WORK}/truncated.gltf -o ${WORK}/out.sphc)
# The buffer exists (${WORK}/secret/data.bin) but lies outside the glTF's folder: refused, never read.
expect_exit(gltf_outside_folder 1 "format: .*escape.gltf: not a readable glTF file: File not found : ../secret/data.bin \\(refused .*: a glTF may only reference files inside its own folder\\)"
            bake ${WORK}/g/escape.gltf -o ${WORK}/out.sphc)
expect_exit(garbage_png_only 1 "invalid-mesh: .*png_only.gltf: no triangles" bake ${WORK}/png_only.gltf -o ${WORK}/out.sphc)
expect_exit(empty_fbx 1 "format: .*empty.fbx: assimp cannot read it: FBX-Parser unexpected end of file"
            bake ${WORK}/empty.fbx -o ${WORK}/out.sphc)
expect_exit(off_as_stl 1 "format: .*off.stl: assimp cannot read it: Failed to determine STL storage representation"
            bake ${WORK}/off.stl -o ${WORK}/out.sphc)
if(EXISTS "${BCN}")
  execute_process(COMMAND head -c 30000 ${BCN} OUTPUT_FILE ${WORK}/cut.x)  # its first 30,000 bytes, as they are
  expect_exit(cut_x 1 "format: .*cut.x: assimp cannot read it: Line 1000: Separator character"
              bake ${WORK}/cut.x -o ${WORK}/out.sphc)
else()
  message(STATUS "cut_x: not run, ${BCN} not found (Debian's assimp-testmodels)")
endif()
expect_exit(rig_with_gltf 1 "config: .*creature.gltf: a MakeHuman rig \\(--rig, or the config's \"rig\"\\) applies to an OBJ mesh"
            bake ${CREATURE} --rig ${WORK}/no.mhskel -o ${WORK}/out.sphc)
expect_exit(not_a_body 1 "segmentation: segment \\(geometry\\): not a standing body: " bake ${WORK}/cube.obj -o ${WORK}/out.sphc)
expect_exit(bad_config 1 "config: .*config_bad.json: 'penetration_depth' = 7 is out of range \\[0, 0.9\\]"
            bake ${WORK}/cube.obj -o ${WORK}/out.sphc --config ${WORK}/config_bad.json)
# A torso disk step that is no length: refused by the parser (exit 2), before anything is read.
expect_exit(disk_step_negative 2 "--disk-step: Value -1 not in range" bake ${WORK}/cube.obj -o ${WORK}/out.sphc --disk-step -1)
expect_exit(disk_step_nan 2 "--disk-step: Value nan not in range" bake ${WORK}/cube.obj -o ${WORK}/out.sphc --disk-step nan)
# A frame count past the limit (a mistyped one ended in std::bad_alloc): a usage error before anything is read.
expect_exit(frames_too_many 2 "--frames: Value 4000000000 not in range \\[1 - 1e\\+06\\]"
            play ${CREATURE} --mesh ${CREATURE} --frames 4000000000 --json ${WORK}/out.sphc)
# An output naming a file of the default key-pose folder (data/poses/<character> upward from the current
# directory, where a bare --morph and --poses read): refused (exit 2), the pose untouched. It was overwritten.
file(WRITE ${WORK}/data/poses/creature/wave.json "{\"rotations\": {}}")
foreach(cmd "play;${CREATURE};--mesh;${CREATURE};--morph;--json" "check;${CREATURE};--poses;--json")
  execute_process(COMMAND ${CLI} ${cmd} data/poses/creature/wave.json WORKING_DIRECTORY ${WORK}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  file(READ ${WORK}/data/poses/creature/wave.json pose)
  if(NOT rc EQUAL 2 OR NOT "${err}" MATCHES "wave.json' is also an input: writing it would destroy what is read"
     OR NOT pose STREQUAL "{\"rotations\": {}}")
    message(FATAL_ERROR "${cmd} onto a default pose: expected exit 2, the clash named, the pose kept; got exit ${rc}, "
                        "pose '${pose}':\n${out}${err}")
  endif()
  message(STATUS "${cmd} onto a default pose: exit 2: ${err}")
endforeach()
# `check` given a character that does not import: its usage error (exit 2), with the kind as every command gives it.
file(WRITE ${WORK}/broken.gltf "{not json")
expect_exit(check_broken_gltf 2 "error: format: .*broken.gltf: not a readable glTF file" check ${WORK}/broken.gltf)
# The asset loader's fuzz finding: reach offsets past the end, falling back later (read past the vector before).
expect_exit(inspect_reach_offsets 1 "is not a loadable .sphc asset: kErrorOffsets: surrounding_offsets or reach_offsets malformed"
            inspect ${REACH_OFFSETS})
expect_exit(inspect_missing 1 "'.*nothing.sphc': no such file" inspect ${WORK}/nothing.sphc)
expect_exit(inspect_garbage 1 "'.*not_an_asset.sphc' is not a loadable .sphc asset: kErrorIdentifier: not a .sphc asset"
            inspect ${WORK}/not_an_asset.sphc)
expect_exit(no_output_folder 1 "io: cannot write '.*out.sphc': folder '.*/no/such/dir' does not exist"
            bake ${WORK}/cube.obj -o ${WORK}/no/such/dir/out.sphc)
expect_exit(vertices_welded 2 "--vertices: welded not in \\{joined,source\\}"
            bake ${WORK}/cube.obj -o ${WORK}/out.sphc --vertices welded)
# An output that is an input or another output: refused before anything is written (exit 2), the files intact.
expect_exit(report_is_output 2 "-o and --report both name .*: one would overwrite the other"
            bake ${WORK}/cube.obj -o ${WORK}/out.sphc --report ${WORK}/out.sphc)
expect_exit(output_is_input 2 "-o .*cube.obj' is also the input: writing it would destroy what is read"
            bake ${WORK}/cube.obj -o ${WORK}/./cube.obj)
expect_exit(report_is_config 2 "--report .*config_bad.json' is also --config" bake ${WORK}/cube.obj -o ${WORK}/out.sphc
            --config ${WORK}/config_bad.json --report ${WORK}/sub/../config_bad.json)
expect_exit(report_is_rig 2 "--report .*config_bad.json' is also --rig" bake ${WORK}/cube.obj -o ${WORK}/out.sphc
            --rig ${WORK}/config_bad.json --report ${WORK}/config_bad.json)
file(READ ${WORK}/cube.obj _cube_after)
file(READ ${WORK}/config_bad.json _config_after)
if(NOT _cube_after MATCHES "^v -1 -1 -1" OR NOT _config_after STREQUAL "{\"penetration_depth\": 7}")
  message(FATAL_ERROR "an input was overwritten by a refused command")
endif()
file(COPY ${GOLDEN} DESTINATION ${WORK})
get_filename_component(_golden_name ${GOLDEN} NAME)
file(SHA256 ${WORK}/${_golden_name} _golden_sum)
expect_exit(validate_json_is_asset 2 "--json .* is also ASSET: writing it would destroy what is read" validate ${WORK}/${_golden_name} --json ${WORK}/${_golden_name})
file(SHA256 ${WORK}/${_golden_name} _golden_after)
if(NOT _golden_sum STREQUAL _golden_after)
  message(FATAL_ERROR "validate --json ASSET overwrote the asset")
endif()
# What fuzzing the importers and the configuration found (fuzz/README.md "Findings", docs/guide.md "Bad input"):
# exit 1 exactly, the message, nothing written. 30,000 nested arrays overflowed the stack (in tinygltf, and in
# nlohmann's dump() printing a bad rig or region map entry); offsets near 2^64 wrapped round a bounds check; an
# accessor without data asked for gigabytes.
string(REPEAT "[" 30000 _open)
string(REPEAT "]" 30000 _close)
string(REPEAT "A" 48 _zeros36)  # base64 of 36 zero bytes
set(_tri "\"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}], \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream;base64,${_zeros36}\"}]")
file(WRITE ${WORK}/deep.gltf "{\"extras\": ${_open}${_close}, \"asset\": {\"version\": \"2.0\"}}")
file(WRITE ${WORK}/wrapped_offset.gltf "{\"asset\": {\"version\": \"2.0\"}, ${_tri}, \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 18446744073709551600, \"byteLength\": 36}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}]}")
file(WRITE ${WORK}/zero_accessor.gltf "{\"asset\": {\"version\": \"2.0\"}, ${_tri}, \"accessors\": [{\"componentType\": 5126, \"count\": 1000000000, \"type\": \"VEC3\"}]}")
file(WRITE ${WORK}/rig/deep.mhskel "{\"bones\": {}, \"joints\": {\"j\": [${_open}${_close}]}}")
file(WRITE ${WORK}/secret.mhw "{\"weights\": {}}")
file(WRITE ${WORK}/rig/escape.mhskel "{\"bones\": {\"root\": {\"head\": \"h\"}}, \"joints\": {\"h\": [0]}, \"weights_file\": \"../secret.mhw\"}")
string(REPEAT ", 0" 11 _eleven)
file(WRITE ${WORK}/deep_map.json "{\"triangle_regions\": [${_open}${_close}${_eleven}]}")
expect_exit(deep_gltf 1 "format: .*deep.gltf: not a readable glTF file: its JSON nests deeper than 64 levels"
             bake ${WORK}/deep.gltf -o ${WORK}/out.sphc)
expect_exit(wrapped_offset 1 "format: .*wrapped_offset.gltf: .*POSITION: bufferView runs past its buffer"
             bake ${WORK}/wrapped_offset.gltf -o ${WORK}/out.sphc)
expect_exit(zero_accessor 1 "format: .*zero_accessor.gltf: .*POSITION: 1000000000 elements without a bufferView, over the limit"
             bake ${WORK}/zero_accessor.gltf -o ${WORK}/out.sphc)
expect_exit(deep_rig 1 "format: .*deep.mhskel: joint 'j' lists vertex an array of 1, the OBJ has 8"
             bake ${WORK}/cube.obj --rig ${WORK}/rig/deep.mhskel -o ${WORK}/out.sphc)
expect_exit(rig_weights_escape 1 "format: .*escape.mhskel: weights file .*secret.mhw is outside the skeleton's folder"
             bake ${WORK}/cube.obj --rig ${WORK}/rig/escape.mhskel -o ${WORK}/out.sphc)
expect_exit(deep_region_map 1 "config: .*triangle_regions.0. = an array of 1 is not a region 0..4"
             bake ${WORK}/cube.obj --region-map ${WORK}/deep_map.json -o ${WORK}/out.sphc)
# fuzz_import_gltf: a skin of two bone trees whose trunk's top is a root (it crashed the skeleton path).
expect_exit(skin_two_trees 1 "segmentation: .*segment \\(skeleton\\): no recognisable limbs: the trunk's bones \\(node0\\) dominate no triangle"
             bake ${TWO_TREES} -o ${WORK}/out.sphc)
# fuzz_import_gltf: a GLB 8·10^9 times wider than tall; the geometric segmentation's T-pose search converted its
# slab count to int (UBSan). Now a tip more than 5 heights out is no arm: both segmentations give their reasons.
expect_exit(slab_overflow 1 "segmentation: segment \\(geometry\\): not a standing body: two arms were not found .*; segment \\(skeleton\\): no recognisable limbs: the skin uses 2 bones"
             bake ${SLAB} -o ${WORK}/out.sphc)
# Review findings the importer's tests build (tests/fuzz/findings_test.cpp), through the CLI: 2^60 elements in a
# 36-byte view (the memory was taken before the bounds check); float indices of -1 (double -> uint32_t is UB).
file(WRITE ${WORK}/huge_count.gltf "{\"asset\": {\"version\": \"2.0\"}, ${_tri}, \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 1152921504606846976, \"type\": \"VEC3\"}]}")
expect_exit(huge_count 1 "format: .*huge_count.gltf: .*POSITION.*run past their bufferView"
             bake ${WORK}/huge_count.gltf -o ${WORK}/out.sphc)
# One triangle, then its indices as floats -1, 1, 2.
file(WRITE ${WORK}/float_indices.gltf "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}], \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"buffers\": [{\"byteLength\": 48, \"uri\": \"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAvwAAgD8AAABA\"}], \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 12}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"}, {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": \"SCALAR\"}]}")
expect_exit(float_indices 1 "format: .*float_indices.gltf: .*indices: index 0 is -1, not a vertex number"
             bake ${WORK}/float_indices.gltf -o ${WORK}/out.sphc)
# fuzz_import_gltf: a GLB whose positions are far from the origin against the mesh's size; the weld's cell keys
# overflowed int64 (UBSan). Now keyed from the mesh's box: it reaches segmentation, which refuses it.
expect_exit(far_weld_keys 1 "segmentation: segment \\(geometry\\): not a standing body"
             bake ${FAR_WELD} -o ${WORK}/out.sphc)
# fuzz_load_asset: the creature with a bind pose mutated to pass through itself in 91,382 pairs. The narrow
# phase's model refuses it within its budget (it swept the bind pose for 0.4 s, 6 s in the fuzz build).
expect_exit(tangled_bind_pose 1 "format: '[^']*found_c7efeae7.sphc': runtime Model::Init: kErrorBindPoseTangled: the bind pose passes through itself"
             play ${TANGLED} --mesh ${CREATURE} --narrow-phase --frames 2 --json ${WORK}/out.sphc)
# The same asset given to `check` (exit 2: its bad input), named in the message, no report written.
execute_process(COMMAND ${CLI} check ${CREATURE} --asset ${TANGLED} --json ${WORK}/out.sphc
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT "${err}" MATCHES "'[^']*found_c7efeae7.sphc': runtime Model::Init: kErrorBindPoseTangled"
   OR EXISTS ${WORK}/out.sphc)
  message(FATAL_ERROR "check of a tangled asset: expected exit 2, the asset named and no report; got exit ${rc}:\n${out}${err}")
endif()
message(STATUS "check of a tangled asset: exit 2: ${err}")

find_program(PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT PYTHON)
  find_program(PYTHON NAMES python3)
endif()
# A 228-triangle STL the assimp fuzzer found: a body lying down, segmented as a biped whose trunk is horizontal.
# Refused in a moment by the plausibility checks (exit 1, nothing written); with --force its fit ran for 6 minutes
# on 3.1 million interior voxels until bipeds got a voxel budget (tests/fuzz/findings_test.cpp).
# An assimp corpus file as the file it stands for: the fuzzer's first byte, which picks the format, dropped.
function(write_assimp_corpus_file src dst)
  execute_process(COMMAND ${PYTHON} -c "import sys; open(sys.argv[2], 'wb').write(open(sys.argv[1], 'rb').read()[1:])"
                          ${src} ${dst} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "could not write ${dst} from ${src}")
  endif()
endfunction()
write_assimp_corpus_file(${LYING} ${WORK}/lying.stl)
# fuzz_import_assimp: a 135-byte PLY with a mangled property line; assimp's PLY reader dereferences null. It runs
# in a child process, whose death is the file's format error.
write_assimp_corpus_file(${PLY_SEGV} ${WORK}/segv.ply)
expect_exit(assimp_child_crash 1 "format: .*segv.ply: the assimp importer's process died reading it \\(signal 11"
             bake ${WORK}/segv.ply -o ${WORK}/out.sphc)
# fuzz_import_assimp: an 83-byte SMD whose skin has no weights; decoding the child's answer passed a null pointer
# to memcpy (UBSan). Now it crosses whole, and the bake refuses the mesh, which has no area.
write_assimp_corpus_file(${EMPTY_WEIGHTS} ${WORK}/empty_weights.smd)
expect_exit(smd_no_weights 1 "segmentation: segment \\(geometry\\): not a standing body: the mesh has no area; segment \\(skeleton\\): no recognisable limbs: no bone carries skin weight"
            bake ${WORK}/empty_weights.smd -o ${WORK}/out.sphc)
expect_exit(lying_body 1 "implausible: .*lying.stl: the bake looks wrong, refused .nothing written.: .*PLAUS-TRUNK-AXIS: the torso's principal axis is 88 degrees from the up axis"
             bake ${WORK}/lying.stl -o ${WORK}/out.sphc)

# Names are bytes as the mesh file had them: an asset whose bone name is not valid UTF-8 (one byte of the
# golden creature's "ForeLeg_R_01" set to 0xFF; the verifier does not check UTF-8) is still described, the
# bad byte shown as U+FFFD (the JSON library would otherwise throw and abort the process).
execute_process(COMMAND ${PYTHON} -c "import sys; d = bytearray(open(sys.argv[1], 'rb').read()); i = d.find(b'ForeLeg_R_01'); assert i > 0; d[i] = 0xFF; open(sys.argv[2], 'wb').write(d)"
                        ${GOLDEN} ${WORK}/bad_utf8.sphc RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "could not write bad_utf8.sphc from ${GOLDEN}")
endif()
foreach(json "" "--json")
  execute_process(COMMAND ${CLI} inspect ${WORK}/bad_utf8.sphc ${json} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "inspect ${json} of a name that is not UTF-8: exit ${rc}\n${out}${err}")
  endif()
endforeach()
string(FIND "${out}" "�oreLeg_R_01" at)  # U+FFFD (UTF-8 EF BF BD), then the rest of the name
if(at LESS 0)
  message(FATAL_ERROR "inspect --json: the bad byte is not shown as U+FFFD:\n${out}")
endif()
message(STATUS "inspect of a name that is not UTF-8: exit 0, shown as U+FFFD")
