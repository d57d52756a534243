#!/usr/bin/env bash
# Bakes and evaluates the MakeHuman body at several sphere budgets (cover fit, max_spheres 40, 64, 96,
# 128, 160) plus the paper's fit as a reference point, writes one JSON per point, then draws
# docs/sphere_count.png and docs/sphere_count.csv with scripts/plot_sphere_count.py.
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)

usage() {
  cat <<EOF
Usage: scripts/plot_sphere_count.sh [OPTIONS] [OUT_DIR]

Bakes the MakeHuman body with the cover fit at max_spheres = 40, 64, 96, 128, 160 and with
{"fit": "paper"}, evaluates each asset on the 40-frame MakeHuman morph (contact margin: the asset's
default; false-alarm margin: evaluate's default), writes one JSON per point into OUT_DIR
(default: /tmp/spherechain-sphere-count) and plots coverage, protrusion and proxy recall against the
actual sphere count.

Options:
  -b, --binary PATH     spherechain CLI (env SPHERECHAIN; default: build/dev/cli/spherechain in the repo)
  -m, --mesh PATH       MakeHuman OBJ (env SPHERECHAIN_MESH; default: ../shared/data/makehuman/base.obj
                        relative to the repo root); its rig default.mhskel must sit beside it
  -p, --poses-dir DIR   key poses of the morph (default: data/poses/makehuman in the repo)
  -c, --counts "N ..."  sphere budgets (default: "40 64 96 128 160")
  -r, --repeats N       bakes per point; the bake time is the fastest (default: 3)
      --png PATH        plot to write (default: docs/sphere_count.png in the repo)
      --csv PATH        numbers to write (default: docs/sphere_count.csv in the repo)
      --python PATH     Python with numpy + matplotlib (env PYTHON; default: /usr/bin/python3)
      --plot-only       skip baking/evaluating; plot the JSONs already in OUT_DIR
  -h, --help            this text

Example:
  scripts/plot_sphere_count.sh -b /tmp/plot/spherechain /tmp/spherechain-sphere-count
EOF
}

binary=${SPHERECHAIN:-$repo/build/dev/cli/spherechain}
mesh=${SPHERECHAIN_MESH:-$repo/../shared/data/makehuman/base.obj}
poses=$repo/data/poses/makehuman
counts="40 64 96 128 160"
repeats=3
png=$repo/docs/sphere_count.png
csv=$repo/docs/sphere_count.csv
python=${PYTHON:-/usr/bin/python3}
out=/tmp/spherechain-sphere-count
plot_only=0

need_arg() { [ $# -ge 2 ] || { echo "error: $1 needs a value (see --help)" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    -b|--binary) need_arg "$@"; binary=$2; shift 2 ;;
    -m|--mesh) need_arg "$@"; mesh=$2; shift 2 ;;
    -p|--poses-dir) need_arg "$@"; poses=$2; shift 2 ;;
    -c|--counts) need_arg "$@"; counts=$2; shift 2 ;;
    -r|--repeats) need_arg "$@"; repeats=$2; shift 2 ;;
    --png) need_arg "$@"; png=$2; shift 2 ;;
    --csv) need_arg "$@"; csv=$2; shift 2 ;;
    --python) need_arg "$@"; python=$2; shift 2 ;;
    --plot-only) plot_only=1; shift ;;
    -*) echo "error: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) out=$1; shift ;;
  esac
done

case "$repeats" in ''|*[!0-9]*|0) echo "error: --repeats needs a positive integer" >&2; exit 2 ;; esac
[ -x "$python" ] || { echo "error: Python '$python' not found (set --python or PYTHON)" >&2; exit 1; }
"$python" -c 'import matplotlib, numpy' 2>/dev/null || {
  echo "error: '$python' cannot import matplotlib/numpy (Debian: apt-get install python3-matplotlib)" >&2; exit 1; }
mkdir -p "$out"

if [ "$plot_only" = 0 ]; then
  if [ ! -x "$binary" ]; then
    echo "error: spherechain binary '$binary' not found or not executable;" \
         "build it (cmake --preset dev && cmake --build --preset dev) or pass --binary" >&2
    exit 1
  fi
  if [ ! -f "$mesh" ]; then
    echo "error: MakeHuman mesh '$mesh' not found; pass --mesh PATH/base.obj" \
         "(default.mhskel beside it)" >&2
    exit 1
  fi
  if [ ! -d "$poses" ]; then
    echo "error: key-pose folder '$poses' not found; pass --poses-dir" >&2
    exit 1
  fi
  rm -f "$out"/point-*.json
  mkdir -p "$out/raw"

  # point LABEL CONFIG_JSON: bake + evaluate, then merge config, bake report and evaluation into one JSON.
  point() {
    local label=$1 config=$2 raw=$out/raw/$1
    echo "== $label: $config"
    printf '%s\n' "$config" >"$raw.config.json"
    # Bake `repeats` times (same asset each time): the bake time reported is the fastest run.
    local k
    for k in $(seq 1 "$repeats"); do
      "$binary" -q bake "$mesh" -o "$raw.sphc" --config "$raw.config.json" --report "$raw.report.$k.json" \
        >"$raw.bake.log" 2>&1 || { echo "error: bake failed, see $raw.bake.log" >&2; tail -n 20 "$raw.bake.log" >&2; exit 1; }
    done
    "$binary" -q evaluate "$raw.sphc" --mesh "$mesh" --poses-dir "$poses" --json "$raw.eval.json" \
      >"$raw.eval.log" 2>&1 || { echo "error: evaluate failed, see $raw.eval.log" >&2; tail -n 20 "$raw.eval.log" >&2; exit 1; }
    grep -E '^(proxy|bind pose phi1_adjusted)' "$raw.eval.log" | sed 's/^/   /' || true
    "$python" - "$label" "$raw" "$out/point-$label.json" "$repeats" <<'PY'
import json, sys
label, raw, dst, repeats = sys.argv[1:5]
reports = [json.load(open(f"{raw}.report.{k}.json")) for k in range(1, int(repeats) + 1)]
bake_runs = [r["timings_ms"]["total"] for r in reports]
report = min(reports, key=lambda r: r["timings_ms"]["total"])  # timings of the fastest run
config = json.load(open(raw + ".config.json"))
ev = json.load(open(raw + ".eval.json"))
point = {
    "label": label,
    "config": config,
    "bake": {k: report.get(k) for k in ("fit", "spheres", "coverage", "timings_ms", "contact_margin_rel",
                                        "excluded_pairs", "body_height", "asset_bytes")},
    "evaluate": {k: ev.get(k) for k in ("margin_rel", "refit", "body_height", "animation")},
    "bake_total_ms_runs": bake_runs,
    "bake_total_ms_min": min(bake_runs),
    "summary": ev["summary"],
}
json.dump(point, open(dst, "w"), indent=1)
PY
  }

  for n in $counts; do
    # The paper's five regions, as the published figure (docs/sphere_count.png) was measured.
    point "cover-$n" "{\"max_spheres\": $n, \"regions\": \"paper\"}"
  done
  point paper '{"fit": "paper"}'
fi

"$python" "$repo/scripts/plot_sphere_count.py" "$out" --png "$png" --csv "$csv"
