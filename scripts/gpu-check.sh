#!/usr/bin/env bash
# The GPU machine's whole check, one command (run there, in the repository root, after
# scripts/gpu-carry.sh has prepared .carry/ here; device tool: carry [".carry"]):
#   bash scripts/gpu-check.sh [--ncu] [--blocks]
# 1. builds the `cuda` preset (runtime + spherechain::cuda + cuda_tests + cuda_bench) with the carried
#    FlatBuffers / doctest headers, and beside it the benches of the variants (step 4);
# 2. runs the CUDA suite on the carried assets and recorded frames (MakeHuman, CesiumMan, BCN_Epileptic)
#    through `ctest -L cuda` (each case, and the assertions guard, which runs the suite once more: no
#    case may pass without checking anything);
# 3. runs cuda_bench on MakeHuman for 1 … 100,000 characters, from vertices and from joints, as an
#    animated crowd (the recorded morph's frames; every strategy, with the CPU columns);
# 4. runs the variants' benches on the same crowd (the default strategy, no CPU columns): when
#    gpu-carry.sh was given --base REV, the kernels of that revision (.carry/base/cuda), and with --blocks
#    the vertex kernel under other register caps (SPHERECHAIN_CUDA_VERTEX_BLOCKS 4 and 5; the default is 6);
# 5. runs the suite's fast cases under compute-sanitizer racecheck, memcheck and synccheck;
# 6. with --ncu, profiles the kernel of the 10,000-character frame (both sources) and of one character
#    (from joints) with Nsight Compute;
# 7. benches the bind pose (no overlapping pairs).
# Every step has its own time limit, so one slow step cannot eat the machine's lease, and with
# GPU_CHECK_SECONDS=N no step runs past N seconds from the start (a step that would is cut to fit, or
# skipped when under 10 s are left); the steps run in order of what matters most, so a run cut short
# keeps the rest. The logs are written straight into the
# device tool's $OUT when it is set (they come back even when the command is cut off), else into
# /tmp/gpu-check, as six files (the device tool brings back only a few): summary.txt (each step's exit
# status and time), build.log, variants.log (their builds), tests.log (suite, sanitizers, ctest),
# bench.log, ncu.log.
# Exit status: the number of failed steps; 100 for a bad argument or GPU_CHECK_SECONDS, 98/99 when the build
# or its configuration fails.
set -uo pipefail
cd "$(dirname "$0")/.."
ncu_too=0 blocks_too=0
for arg in "$@"; do
  case $arg in
    --ncu) ncu_too=1 ;;
    --blocks) blocks_too=1 ;;
    *) echo "usage: gpu-check.sh [--ncu] [--blocks]" >&2; exit 100 ;;
  esac
done
budget=${GPU_CHECK_SECONDS:-0}
[[ $budget =~ ^[0-9]+$ ]] || { echo "gpu-check.sh: GPU_CHECK_SECONDS must be a whole number of seconds, not '$budget'" >&2; exit 100; }
budget=$((10#$budget))
out=${OUT:-/tmp/gpu-check}
[ -n "${OUT:-}" ] || { rm -rf "$out" && mkdir -p "$out"; }
root=$PWD
export SPHERECHAIN_MH_ASSET=$root/.carry/mh.sphc
export SPHERECHAIN_GPU_FRAMES="$root/.carry/mh.sphc=$root/.carry/frames/mh;$root/.carry/cesiumman.sphc=$root/.carry/frames/cesiumman;$root/.carry/bcn.sphc=$root/.carry/frames/bcn"
failed=0
step() {  # step LOG NAME SECONDS COMMAND...: runs COMMAND with a time limit, its output appended to $out/LOG.log
  local log=$out/$1.log name=$2 limit=$3
  shift 3
  local t0=$SECONDS
  if [ "$budget" -gt 0 ] && [ $((t0 + limit)) -gt "$budget" ]; then
    limit=$((budget - t0))
    if [ $limit -lt 10 ]; then
      echo "== $name: skipped, $((limit > 0 ? limit : 0)) s left of GPU_CHECK_SECONDS=$budget" | tee -a "$out/summary.txt"
      failed=$((failed + 1))
      return 1
    fi
  fi
  echo "==== $name: $*" >>"$log"
  timeout "$limit" "$@" >>"$log" 2>&1
  local rc=$?
  echo "== $name: exit $rc in $((SECONDS - t0)) s" | tee -a "$out/summary.txt"
  [ $rc -eq 0 ] || failed=$((failed + 1))
  return $rc
}
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv >>"$out/summary.txt" 2>&1
nvcc --version | tail -1 >>"$out/summary.txt"
cat "$out/summary.txt"
mh=("$root/.carry/mh.sphc" "$root/.carry/data/makehuman/base.obj")
crowd=(--sizes 1,1000,10000,100000 --frames "$root/.carry/frames/mh")
# A variant's tree: the working tree with another cuda/ or other flags; only its cuda_bench is built.
variant() {  # variant NAME CUDA_DIR [CMAKE ARGS...]
  local name=$1 cuda_dir=$2 src=/tmp/gpu-variant-$1
  shift 2
  rm -rf "$src" && mkdir -p "$src" &&
    tar --exclude=./build --exclude=./.carry --exclude=./.git -cf - . | tar -xf - -C "$src" &&
    rm -rf "$src/cuda" && cp -r "$cuda_dir" "$src/cuda" &&
    env FLATBUFFERS_INCLUDE_DIR="$root/.carry/include" cmake -S "$src" -B "$root/build/$name" --preset cuda \
      -DSPHERECHAIN_BUILD_BENCH=ON -DSPHERECHAIN_BUILD_TESTS=OFF -Ddoctest_DIR="$root/.carry/lib/cmake/doctest" \
      -DSPHERECHAIN_SHARED_DATA_DIR="$root/.carry/data" "$@" >/dev/null &&
    cmake --build "$root/build/$name" --target cuda_bench -j4
}
export -f variant
export root
step build configure 120 env FLATBUFFERS_INCLUDE_DIR="$root/.carry/include" cmake --preset cuda -DSPHERECHAIN_BUILD_BENCH=ON -DSPHERECHAIN_BUILD_TESTS=ON \
  -Ddoctest_DIR="$root/.carry/lib/cmake/doctest" -DSPHERECHAIN_SHARED_DATA_DIR="$root/.carry/data" || exit 99
# The variants build beside the main build (the machine's cores shared) and bench later, on an idle GPU.
variants=() builders=()  # the variants' builds run in the background; their exit statuses are counted at `wait`
if [ -d .carry/base/cuda ]; then
  variants+=(base)
  step variants "build base ($(cat .carry/base/REVISION))" 300 bash -c 'variant base .carry/base/cuda' &
  builders+=($!)
fi
if [ $blocks_too = 1 ]; then
  for vb in 4 5; do
    variants+=(vertex-blocks-$vb)
    step variants "build vertex-blocks-$vb" 300 bash -c "variant vertex-blocks-$vb cuda -DCMAKE_CUDA_FLAGS=-DSPHERECHAIN_CUDA_VERTEX_BLOCKS=$vb" &
    builders+=($!)
  done
fi
step build build 300 cmake --build build/cuda --target cuda_tests cuda_bench -j"$(nproc)" || exit 98
step tests ctest 180 ctest --test-dir build/cuda -L cuda --output-on-failure --timeout 150 -j8
for b in ${builders[@]+"${builders[@]}"}; do wait "$b" || failed=$((failed + 1)); done  # the variants' builds
step bench bench-crowd 150 build/cuda/bench/cuda_bench "${mh[@]}" "${crowd[@]}"
for v in ${variants[@]+"${variants[@]}"}; do
  [ -x "build/$v/bench/cuda_bench" ] &&
    step bench "bench-crowd $v" 90 "build/$v/bench/cuda_bench" "${mh[@]}" "${crowd[@]}" --strategies auto --no-cpu
done
fast='*synthetic*,*rest pose*,*graph*,*invalid*,*too-small*,*NaN*,*joint*'
step tests racecheck 60 compute-sanitizer --tool racecheck --error-exitcode 1 build/cuda/tests/cuda_tests -tc="$fast"
step tests memcheck 100 compute-sanitizer --tool memcheck --leak-check full --error-exitcode 1 build/cuda/tests/cuda_tests -tc="$fast"
step tests synccheck 60 compute-sanitizer --tool synccheck --error-exitcode 1 build/cuda/tests/cuda_tests -tc="$fast"
if [ $ncu_too = 1 ]; then
  sections="--section SpeedOfLight --section MemoryWorkloadAnalysis --section Occupancy --section WarpStateStats --section SchedulerStats --section LaunchStats"
  step ncu "ncu-one-joints" 60 ncu --clock-control none -k regex:BoxKernel --launch-count 1 $sections \
    build/cuda/bench/cuda_bench "${mh[@]}" --sizes 1 --source joints --frames "$root/.carry/frames/mh" --strategies auto --no-cpu
  for src in vertices joints; do
    step ncu "ncu-$src" 120 ncu --clock-control none -k regex:BoxKernel --launch-count 1 $sections \
      build/cuda/bench/cuda_bench "${mh[@]}" --sizes 10000 --source $src --frames "$root/.carry/frames/mh" --strategies auto --no-cpu
  done
fi
step bench bench-bind 60 build/cuda/bench/cuda_bench "${mh[@]}" --sizes 1,10000,100000 --strategies auto --no-cpu
exit $failed
