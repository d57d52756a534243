#!/usr/bin/env bash
# The GPU machine's whole check, one command (run there, in the repository root, after
# scripts/gpu-carry.sh has prepared .carry/ here; device tool: carry [".carry"]):
#   bash scripts/gpu-check.sh [--ncu]
# 1. builds the `cuda` preset (runtime + spherechain::cuda + cuda_tests + cuda_bench) with the carried
#    FlatBuffers / doctest headers;
# 2. runs the CUDA suite on the carried assets and recorded frames (MakeHuman, CesiumMan, BCN_Epileptic),
#    then `ctest -L cuda` (the assertions guard: no case may pass without checking anything);
# 3. runs cuda_bench on MakeHuman for 1 … 100,000 characters, from vertices and from joints, at the bind
#    pose and as an animated crowd (the recorded morph's frames);
# 4. runs the suite's fast cases under compute-sanitizer memcheck, racecheck and synccheck;
# 5. with --ncu, profiles the 10,000-character frame's kernel with Nsight Compute (both sources).
# Every step has its own time limit, so one slow step cannot eat the machine's lease. The logs go to
# /tmp/gpu-check, and when the device tool's $OUT is set, packed into $OUT/gpu-check.tgz beside a copy of
# summary.txt and bench.log. Exit status: the number of failed steps.
set -uo pipefail
cd "$(dirname "$0")/.."
ncu_too=0
[ "${1:-}" = "--ncu" ] && ncu_too=1
out=/tmp/gpu-check
rm -rf "$out" && mkdir -p "$out"
pack() {
  [ -n "${OUT:-}" ] || return 0
  tar czf "$OUT/gpu-check.tgz" -C "$out" . && cp "$out/summary.txt" "$out/bench.log" "$OUT/" 2>/dev/null
}
trap pack EXIT
root=$PWD
export SPHERECHAIN_MH_ASSET=$root/.carry/mh.sphc
export SPHERECHAIN_GPU_FRAMES="$root/.carry/mh.sphc=$root/.carry/frames/mh;$root/.carry/cesiumman.sphc=$root/.carry/frames/cesiumman;$root/.carry/bcn.sphc=$root/.carry/frames/bcn"
failed=0
step() {  # step NAME SECONDS COMMAND...: runs COMMAND with a time limit, its output in $out/NAME.log
  local name=$1 limit=$2
  shift 2
  local t0=$SECONDS
  timeout "$limit" "$@" >"$out/$name.log" 2>&1
  local rc=$?
  echo "== $name: exit $rc in $((SECONDS - t0)) s" | tee -a "$out/summary.txt"
  tail -n 15 "$out/$name.log"
  [ $rc -eq 0 ] || failed=$((failed + 1))
  return $rc
}
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv >"$out/summary.txt" 2>&1
nvcc --version | tail -1 >>"$out/summary.txt"
cat "$out/summary.txt"
step configure 120 env FLATBUFFERS_INCLUDE_DIR="$root/.carry/include" cmake --preset cuda -DSPHERECHAIN_BUILD_BENCH=ON \
  -Ddoctest_DIR="$root/.carry/lib/cmake/doctest" -DSPHERECHAIN_SHARED_DATA_DIR="$root/.carry/data" || exit 99
step build 300 cmake --build build/cuda --target cuda_tests cuda_bench -j"$(nproc)" || exit 98
step tests 180 build/cuda/tests/cuda_tests --duration=true
step ctest 120 ctest --test-dir build/cuda -L cuda --output-on-failure -j4
step bench 150 build/cuda/bench/cuda_bench "$root/.carry/mh.sphc" "$root/.carry/data/makehuman/base.obj" --max-instances 100000
step bench-frames 120 build/cuda/bench/cuda_bench "$root/.carry/mh.sphc" "$root/.carry/data/makehuman/base.obj" \
  --sizes 1,1000,10000,100000 --frames "$root/.carry/frames/mh"
fast='*synthetic*,*rest pose*,*graph*,*invalid*,*too-small*,*NaN*,*joint*'
step memcheck 100 compute-sanitizer --tool memcheck --leak-check full --error-exitcode 1 build/cuda/tests/cuda_tests -tc="$fast"
step racecheck 60 compute-sanitizer --tool racecheck --error-exitcode 1 build/cuda/tests/cuda_tests -tc="$fast"
step synccheck 60 compute-sanitizer --tool synccheck --error-exitcode 1 build/cuda/tests/cuda_tests -tc="$fast"
# The kernels' register cap (SPHERECHAIN_CUDA_SPHERE_BLOCKS, default 6) against none (1).
step configure-b 60 env FLATBUFFERS_INCLUDE_DIR="$root/.carry/include" cmake -S . -B build/cuda-b --preset cuda \
  -DSPHERECHAIN_BUILD_BENCH=ON -DSPHERECHAIN_BUILD_TESTS=OFF -DCMAKE_CUDA_FLAGS=-DSPHERECHAIN_CUDA_SPHERE_BLOCKS=1 &&
  step build-b 200 cmake --build build/cuda-b --target cuda_bench -j"$(nproc)" &&
  step bench-b 120 build/cuda-b/bench/cuda_bench "$root/.carry/mh.sphc" "$root/.carry/data/makehuman/base.obj" --sizes 1,1000,10000,100000
if [ $ncu_too = 1 ]; then
  sections="--section SpeedOfLight --section MemoryWorkloadAnalysis --section Occupancy --section WarpStateStats --section SchedulerStats --section LaunchStats"
  for src in vertices joints; do
    step "ncu-$src" 120 ncu --clock-control none -k regex:BoxKernel --launch-count 1 $sections \
      build/cuda/bench/cuda_bench "$root/.carry/mh.sphc" "$root/.carry/data/makehuman/base.obj" --sizes 10000 --source $src
  done
fi
exit $failed
