#!/usr/bin/env bash
# Compares the per-frame runtime cost of several assets of one character on the same frames, one after
# the other in one run (e.g. the paper fit, the cover fit at 96 and at 128 spheres): refit, M1, M2 and the
# narrow phase, in µs per frame and ns per sphere, as runtime_bench measures them (one core, best median
# of --runs). The frames are the character's deformed vertex buffers (`spherechain play ... --dump-frames
# DIR`), so every asset sees the same motion.
#
#   bench/compare_assets.sh FRAMES_DIR A.sphc B.sphc ... [-- runtime_bench flags, default: --runs 3]
set -euo pipefail
usage() { sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
[[ $# -ge 2 ]] || usage
here=$(cd "$(dirname "$0")/.." && pwd)
bench=${RUNTIME_BENCH:-$here/build/dev/bench/runtime_bench}
[[ -x $bench ]] || { echo "error: $bench not found (build the bench target, or set RUNTIME_BENCH)" >&2; exit 1; }
frames=$1; shift
[[ -d $frames ]] || { echo "error: frames folder '$frames' not found" >&2; exit 1; }
assets=()
while [[ $# -gt 0 && $1 != -- ]]; do
  [[ -f $1 ]] || { echo "error: asset '$1' not found" >&2; exit 1; }
  assets+=("$1"); shift
done
[[ ${#assets[@]} -ge 1 ]] || usage
[[ ${1:-} == -- ]] && shift
flags=("$@"); [[ ${#flags[@]} -gt 0 ]] || flags=(--runs 3)

printf '%-28s %7s %6s %9s %9s %9s %11s %9s %9s %11s %11s\n' asset spheres pairs "refit us" "M1 us" "M2 us" \
  "refit+M1" "ns/sph M1" "ns/sph M2" "narrow med" "narrow max"
for a in "${assets[@]}"; do
  out=$("$bench" "$a" "$frames" --cgal-frames 0 "${flags[@]}" 2>&1) || { echo "$out" >&2; exit 1; }
  if grep -q MISMATCH <<<"$out"; then echo "$out" >&2; echo "error: $a: runtime_bench reported a mismatch" >&2; exit 1; fi
  awk -v name="$(basename "$a")" '
    /^asset:/ { s = $2 }
    /^pairs per frame/ { for (i = 1; i <= NF; ++i) if ($i == "M2") p = $(i + 1) }
    /^sc refit  / { refit = $3 } /^sc M1 detect/ { m1 = $4 } /^sc M2 detect/ { m2 = $4 } /^sc refit\+M1/ { rm1 = $3 }
    /^time us/ { med = $3; mx = $5 }
    END { printf "%-28s %7d %6.1f %9.2f %9.2f %9.2f %11.2f %9.1f %9.1f %11.1f %11.1f\n", name, s, p, refit, m1, m2, rm1,
                 1000 * rm1 / s, 1000 * (refit + m2) / s, med, mx }' <<<"$out"
done
echo "(us per frame, one core; ns/sph = (refit + detect) / spheres; narrow: NarrowPhaseJob per frame, median / max)"
