#!/usr/bin/env bash
# Batch bake timing: the same ten inputs baked one process after another (how a script bakes them today), then
# in one call with `--out-dir` at -j 1 and at -j N, ROUNDS times in alternation, and once one process after another on
# one core (taskset -c 0: what the bakes cost without the cover fit's own threads); prints each wall time and the
# assets' bytes compared with the one-at-a-time bakes (cmp). The ten: the nine characters the default
# configuration bakes (MakeHuman, CesiumMan, BCN_Epileptic, human.zae, HUMAN.blend, mrfixit.iqm, Testwuson.X, and
# tests/data/creature's creature and figure) and the SMD Wuson, which is refused (a failing input costs its
# import and segmentation, then the batch goes on).
#
# Usage: bench/bake_batch_bench.sh [CLI] [ROUNDS] [JOBS]     (defaults: build/dev/cli/spherechain 3 2)
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
CLI=${1:-$REPO/build/dev/cli/spherechain}
ROUNDS=${2:-3}
JOBS=${3:-2}
S=${SPHERECHAIN_SHARED_DATA_DIR:-$REPO/../shared/data}
M=/usr/share/assimp/models
INPUTS=("$S/makehuman/base.obj" "$S/gltf/CesiumMan.gltf" "$M/X/BCN_Epileptic.X" "$M/Collada/human.zae"
        "$M/BLEND/HUMAN.blend" "$M/IQM/mrfixit.iqm" "$M/X/Testwuson.X" "$REPO/tests/data/creature/creature.gltf"
        "$REPO/tests/data/creature/figure.gltf" "$M/SMD/WusonSMD.smd")
for f in "${INPUTS[@]}"; do [[ -f $f ]] || { echo "SKIPPED: $f not found"; exit 0; }; done
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
now() { date +%s.%N; }
echo "cores: $(nproc); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for r in $(seq 1 "$ROUNDS"); do
  rm -rf "$WORK/seq" "$WORK/j1" "$WORK/jn" && mkdir -p "$WORK/seq"
  t0=$(now)
  for f in "${INPUTS[@]}"; do
    stem=$(basename "${f%.*}")
    "$CLI" -q bake "$f" -o "$WORK/seq/$stem.sphc" 2>/dev/null || true
  done
  t1=$(now)
  "$CLI" -q bake "${INPUTS[@]}" --out-dir "$WORK/j1" -j 1 2>/dev/null || true
  t2=$(now)
  "$CLI" -q bake "${INPUTS[@]}" --out-dir "$WORK/jn" -j "$JOBS" 2>/dev/null || true
  t3=$(now)
  same=0
  for a in "$WORK"/seq/*.sphc; do
    cmp -s "$a" "$WORK/j1/$(basename "$a")" && cmp -s "$a" "$WORK/jn/$(basename "$a")" && same=$((same + 1))
  done
  awk -v r="$r" -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" -v j="$JOBS" -v same="$same" 'BEGIN {
    printf "round %d: one process each %.2f s, --out-dir -j 1 %.2f s, -j %d %.2f s (%.2fx of one process each); %d assets identical\n",
           r, b - a, c - b, j, d - c, (d - c) / (b - a), same }'
done
if command -v taskset >/dev/null; then
  rm -rf "$WORK/one" && mkdir -p "$WORK/one"
  t0=$(now)
  for f in "${INPUTS[@]}"; do
    taskset -c 0 "$CLI" -q bake "$f" -o "$WORK/one/$(basename "${f%.*}").sphc" 2>/dev/null || true
  done
  t1=$(now)
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "one process each on one core (taskset -c 0): %.2f s\n", b - a }'
fi
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
