#!/usr/bin/env bash
# One libFuzzer campaign: scripts/fuzz.sh TARGET SECONDS [extra libFuzzer flags...]
#   TARGET: load_asset, import_gltf, import_obj, import_makehuman, import_assimp or bake_config (with or
#   without the fuzz_ prefix). Builds the target (preset `fuzz`: clang, ASan + UBSan), then fuzzes for SECONDS
#   on one core at low priority, from the seeds in fuzz/corpus/TARGET/ plus what earlier campaigns found in
#   build/fuzz/work/TARGET/ (new inputs go there; crashes, timeouts, leaks and out-of-memory inputs to
#   build/fuzz/artifacts/TARGET/). The limits (fuzz/README.md): 10 s per input, 2,048 MB RSS and per malloc,
#   leaks checked (third-party leaks suppressed as in the asan suite: scripts/sanitizer/lsan.supp).
#   Prints the campaign's line for fuzz/README.md: executions, exec/s, edges, time, crashes.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz.sh TARGET SECONDS [libFuzzer flags...]" >&2
  exit 2
fi
name="${1#fuzz_}"
seconds="$2"
shift 2
case "$name" in
  load_asset) dict="" ;;
  import_gltf) dict=fuzz/dict/gltf.dict ;;
  import_obj) dict=fuzz/dict/obj.dict ;;
  import_makehuman) dict=fuzz/dict/makehuman.dict ;;
  import_assimp) dict=fuzz/dict/assimp.dict ;;
  bake_config) dict=fuzz/dict/bake_config.dict ;;
  *) echo "scripts/fuzz.sh: unknown target '$name'" >&2; exit 2 ;;
esac

if [ ! -f build/fuzz/build.ninja ]; then cmake --preset fuzz >/dev/null; fi
nice -n 19 cmake --build build/fuzz -j2 --target "fuzz_$name" >/dev/null

work="build/fuzz/work/$name"
artifacts="build/fuzz/artifacts/$name"
log="build/fuzz/logs/$name-$(date +%Y%m%d-%H%M%S).log"
mkdir -p "$work" "$artifacts" "$(dirname "$log")"
before=$(find "$artifacts" -type f | wc -l)

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$(pwd)/scripts/sanitizer/lsan.supp:print_suppressions=0}"
flags=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 -detect_leaks=1
       -print_final_stats=1 -artifact_prefix="$artifacts/")
[ -n "$dict" ] && flags+=(-dict="$dict")

set +e
start=$SECONDS
nice -n 19 "build/fuzz/fuzz/fuzz_$name" "${flags[@]}" "$@" "$work" "fuzz/corpus/$name" >"$log" 2>&1
rc=$?
elapsed=$((SECONDS - start))
set -e

execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
edges=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
last_new=$(grep -E '#[0-9]+\s+(NEW|REDUCE)' "$log" | tail -1 | grep -o '^#[0-9]*' || echo "#0")
found=$(( $(find "$artifacts" -type f | wc -l) - before ))
echo "fuzz_$name: ${execs} executions, ${rate} exec/s, ${edges} edges, ${elapsed} s, ${found} new artifact(s) (exit $rc)"
echo "  last new coverage or smaller input at execution ${last_new}; log: $log"
[ "$found" -eq 0 ] || ls -1 "$artifacts"
exit $rc
