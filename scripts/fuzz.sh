#!/usr/bin/env bash
# One libFuzzer campaign: scripts/fuzz.sh TARGET SECONDS [extra libFuzzer flags...]
#   TARGET: load_asset, import_gltf, import_obj, import_makehuman, import_assimp or bake_config (with or
#   without the fuzz_ prefix). Builds the target (preset `fuzz`: clang, ASan + UBSan), then fuzzes for SECONDS
#   on one core at low priority, from the seeds in fuzz/corpus/TARGET/ plus what earlier campaigns found in
#   build/fuzz/work/TARGET/ (new inputs go there; crashes, timeouts, leaks and out-of-memory inputs to
#   build/fuzz/artifacts/TARGET/). A work folder that is missing or empty starts from the last saved campaign,
#   fuzz/campaign/TARGET.tar.xz, when there is one. The limits (fuzz/README.md): 10 s per input, 2,048 MB RSS
#   and per malloc, leaks checked (third-party leaks suppressed as in the asan suite:
#   scripts/sanitizer/lsan.supp). The log's lines are prefixed by the seconds since the start.
#   Prints the campaign's line for fuzz/README.md: executions, exec/s, edges, time, crashes, and the edges its
#   last hour added (when it ran an hour or more).
# Saving a campaign: scripts/fuzz.sh save TARGET
#   merges build/fuzz/work/TARGET/ (libFuzzer -merge=1: the smallest set of its inputs with the same coverage)
#   into fuzz/campaign/TARGET.tar.xz, so that the next campaign on any machine resumes from it. On a CPU that
#   does not run the runtime's AVX-512 kernels, the archive is kept whole and the merge's inputs added to it.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz.sh TARGET SECONDS [libFuzzer flags...] | scripts/fuzz.sh save TARGET" >&2
  exit 2
fi
save=0
if [ "$1" = save ]; then
  [ $# -eq 2 ] || { echo "usage: scripts/fuzz.sh save TARGET" >&2; exit 2; }
  save=1
  name="${2#fuzz_}"
  seconds=0
else
  name="${1#fuzz_}"
  seconds="$2"
  case "$seconds" in ''|*[!0-9]*) echo "scripts/fuzz.sh: SECONDS must be a whole number, not '$seconds'" >&2; exit 2 ;; esac
fi
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
saved="fuzz/campaign/$name.tar.xz"
log="build/fuzz/logs/$name-$(date +%Y%m%d-%H%M%S).log"
mkdir -p "$work" "$artifacts" "$(dirname "$log")"
before=$(find "$artifacts" -type f | wc -l)

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$(pwd)/scripts/sanitizer/lsan.supp:print_suppressions=0}"

if [ "$save" -eq 1 ]; then
  if [ -z "$(ls -A "$work")" ]; then
    echo "scripts/fuzz.sh save: $work is empty: no campaign to save" >&2
    exit 1
  fi
  merged=$(mktemp -d)
  trap 'rm -rf "$merged"' EXIT
  # -merge=1 keeps, of the work folder and the seeds, the fewest inputs that reach every edge they reach.
  nice -n 19 "build/fuzz/fuzz/fuzz_$name" -merge=1 -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
    -artifact_prefix="$artifacts/" "$merged" "$work" "fuzz/corpus/$name" >"$log" 2>&1 || { echo "scripts/fuzz.sh save: merge failed (log: $log)" >&2; exit 1; }
  # The seeds are in the repository already: only what the campaign added is saved.
  for f in fuzz/corpus/"$name"/*; do
    [ -f "$f" ] || continue
    rm -f "$merged/$(sha1sum "$f" | cut -c1-40)"
  done
  # A merge counts the edges of the code this CPU runs. Without the four AVX-512 extensions the runtime's
  # dispatch asks for (runtime/src/kernels.cpp), or with SPHERECHAIN_ISA capping it below them, the AVX-512
  # kernels never run, and the merge drops the inputs that reach only them. The saved campaign is then kept
  # whole and the merge's inputs are added to it (the names are the inputs' SHA-1, so none is held twice).
  all_isa=1
  for flag in avx512f avx512vl avx512dq avx512bw; do
    grep -qw "$flag" /proc/cpuinfo 2>/dev/null || all_isa=0
  done
  case "${SPHERECHAIN_ISA:-avx512}" in avx512) ;; *) all_isa=0 ;; esac
  united=""
  if [ "$all_isa" -eq 0 ] && [ -f "$saved" ]; then
    kept=$(ls "$merged" | wc -l)
    if ! tar -C "$merged" -xJf "$saved"; then
      echo "scripts/fuzz.sh save: could not read $saved" >&2
      exit 1
    fi
    united=", the union of the archive before and this merge's $kept: the AVX-512 kernels do not run here"
  fi
  mkdir -p fuzz/campaign
  # Reproducible: names sorted, no owners or times (the same corpus gives the same bytes).
  (cd "$merged" && find . -type f -printf '%P\n' | LC_ALL=C sort) >"$merged.list"
  if ! tar -C "$merged" --owner=0 --group=0 --numeric-owner --mtime=@0 --mode=u=rw,go=r -cJf "$saved.tmp" \
       -T "$merged.list"; then
    rm -f "$saved.tmp" "$merged.list"
    echo "scripts/fuzz.sh save: could not write $saved" >&2
    exit 1
  fi
  rm -f "$merged.list"
  mv "$saved.tmp" "$saved"
  echo "fuzz_$name: $(ls "$merged" | wc -l) inputs saved to $saved ($(du -k "$saved" | cut -f1) KB$united); log: $log"
  exit 0
fi
if [ -z "$(ls -A "$work")" ] && [ -f "$saved" ]; then
  tar -C "$work" -xJf "$saved"
  echo "fuzz_$name: resuming from $saved ($(ls "$work" | wc -l) inputs)"
fi
flags=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 -detect_leaks=1
       -print_final_stats=1 -artifact_prefix="$artifacts/")
[ -n "$dict" ] && flags+=(-dict="$dict")

set +e
start=$SECONDS
# Each line of the log prefixed by the seconds since the start (the edges of the last hour are read from them).
nice -n 19 "build/fuzz/fuzz/fuzz_$name" "${flags[@]}" "$@" "$work" "fuzz/corpus/$name" 2>&1 |
  while IFS= read -r line || [ -n "$line" ]; do printf '%d %s\n' "$((SECONDS - start))" "$line"; done >"$log"
rc=${PIPESTATUS[0]}
elapsed=$((SECONDS - start))
set -e

execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
edges=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || echo 0)
last_new=$(grep -E '#[0-9]+\s+(NEW|REDUCE)' "$log" | tail -1 | grep -oE '#[0-9]+' | head -1 || echo "#0")
found=$(( $(find "$artifacts" -type f | wc -l) - before ))
echo "fuzz_$name: ${execs} executions, ${rate} exec/s, ${edges} edges, ${elapsed} s, ${found} new artifact(s) (exit $rc)"
echo "  last new coverage or smaller input at execution ${last_new}; log: $log"
if [ "$elapsed" -ge 3600 ]; then
  hour_ago=$(awk -v t=$((elapsed - 3600)) '$1 <= t && match($0, /cov: [0-9]+/) { e = substr($0, RSTART + 5, RLENGTH - 5) } END { print e + 0 }' "$log")
  echo "  edges in the last hour: ${hour_ago} -> ${edges} (+$((edges - hour_ago)))"
fi
[ "$found" -eq 0 ] || ls -1 "$artifacts"
exit $rc
