#!/usr/bin/env bash
# Regenerates the paper's figures (Madera, Ayala, Moo-Mena 2015, §6) from this build, plus the proxy's
# recall per frame against exact contacts, into docs/ (PNGs) with scripts/plots/paper_figures.py:
#   docs/fig13_rays.png        — Fig. 13: distance along each ray of the torso disk to the skin and to
#                                 the sphere surface, φ1 / φ1' / φ2, the paper's fit, torso spheres 0–7;
#   docs/fig15_m1_m2_cpu.png    — Figs. 15–16 (CPU): µs per frame of M1 and M2 over the 40-frame
#                                 MakeHuman morph, paper fit and the default cover fit (no GPU measured);
#   docs/recall_per_frame.png   — exact region pairs in contact per frame, those the spheres report (M2),
#                                 and false alarms: MakeHuman morph, CesiumMan walk, BCN_Epileptic clip.
set -euo pipefail

repo=$(cd "$(dirname "$0")/../.." && pwd)

usage() {
  cat <<EOF
Usage: scripts/plots/paper_figures.sh [OPTIONS] [OUT_DIR]

Bakes, plays and evaluates the characters into OUT_DIR (default /tmp/spherechain-paper-figures), then
draws the PNGs into docs/.

Options:
  -b, --binary PATH   spherechain CLI (env SPHERECHAIN; default: build/dev/cli/spherechain in the repo)
  -d, --data DIR      shared data (default: ../shared/data relative to the repo root)
  -x, --x-model PATH  BCN_Epileptic.X (default: /usr/share/assimp/models/X/BCN_Epileptic.X; skipped if absent)
      --docs DIR      where the PNGs go (default: docs/ in the repo)
      --python PATH   Python with numpy + matplotlib (env PYTHON; default: /usr/bin/python3)
      --plot-only     skip the runs; plot what OUT_DIR holds
  -h, --help          this text
EOF
}

binary=${SPHERECHAIN:-$repo/build/dev/cli/spherechain}
data=$repo/../shared/data
xmodel=/usr/share/assimp/models/X/BCN_Epileptic.X
docs=$repo/docs
python=${PYTHON:-/usr/bin/python3}
out=/tmp/spherechain-paper-figures
plot_only=0

need_arg() { [ $# -ge 2 ] || { echo "error: $1 needs a value (see --help)" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    -b|--binary) need_arg "$@"; binary=$2; shift 2 ;;
    -d|--data) need_arg "$@"; data=$2; shift 2 ;;
    -x|--x-model) need_arg "$@"; xmodel=$2; shift 2 ;;
    --docs) need_arg "$@"; docs=$2; shift 2 ;;
    --python) need_arg "$@"; python=$2; shift 2 ;;
    --plot-only) plot_only=1; shift ;;
    -*) echo "error: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) out=$1; shift ;;
  esac
done

[ -x "$python" ] || { echo "error: Python '$python' not found (set --python or PYTHON)" >&2; exit 1; }
"$python" -c 'import matplotlib, numpy' 2>/dev/null || {
  echo "error: '$python' cannot import matplotlib/numpy (Debian: apt-get install python3-matplotlib)" >&2; exit 1; }
mkdir -p "$out" "$docs"

if [ "$plot_only" = 0 ]; then
  [ -x "$binary" ] || { echo "error: spherechain binary '$binary' not found; build it or pass --binary" >&2; exit 1; }
  mh=$data/makehuman/base.obj
  cm=$data/gltf/CesiumMan.gltf
  [ -f "$mh" ] || { echo "error: '$mh' not found; pass --data DIR (the shared data folder)" >&2; exit 1; }
  run() {  # run LOG CMD...: quiet unless it fails
    local log=$1; shift
    "$@" >"$log" 2>&1 || { echo "error: $* failed, see $log" >&2; tail -n 20 "$log" >&2; exit 1; }
  }
  echo '{"fit": "paper"}' >"$out/paper.config.json"
  echo "== MakeHuman, paper fit: bake (torso ray CSV), play (M1 and M2 timings), evaluate"
  run "$out/mh_paper.bake.log" "$binary" -q bake "$mh" -o "$out/mh_paper.sphc" --config "$out/paper.config.json" \
    --ray-csv "$out/mh_paper.rays.csv"
  run "$out/mh_paper.play.log" "$binary" -q play "$out/mh_paper.sphc" --mesh "$mh" --repeat 20 --json "$out/mh_paper.play.json"
  run "$out/mh_paper.eval.log" "$binary" -q evaluate "$out/mh_paper.sphc" --mesh "$mh" --json "$out/mh_paper.eval.json"
  # The figures are the paper's: its five regions and Table 1's chains (--regions paper), with the cover fit.
  echo "== MakeHuman, cover fit, the paper's five regions"
  run "$out/mh.bake.log" "$binary" -q bake "$mh" -o "$out/mh.sphc" --regions paper
  run "$out/mh.play.log" "$binary" -q play "$out/mh.sphc" --mesh "$mh" --repeat 20 --json "$out/mh.play.json"
  run "$out/mh.eval.log" "$binary" -q evaluate "$out/mh.sphc" --mesh "$mh" --json "$out/mh.eval.json"
  if [ -f "$cm" ]; then
    echo "== CesiumMan walk"
    run "$out/cm.bake.log" "$binary" -q bake "$cm" -o "$out/cm.sphc" --regions paper
    run "$out/cm.eval.log" "$binary" -q evaluate "$out/cm.sphc" --mesh "$cm" --json "$out/cm.eval.json"
  fi
  if [ -f "$xmodel" ]; then
    echo "== BCN_Epileptic clip"
    run "$out/bcn.bake.log" "$binary" -q bake "$xmodel" -o "$out/bcn.sphc" --regions paper
    run "$out/bcn.eval.log" "$binary" -q evaluate "$out/bcn.sphc" --mesh "$xmodel" --json "$out/bcn.eval.json"
  fi
fi

"$python" "$repo/scripts/plots/paper_figures.py" "$out" --docs "$docs"
