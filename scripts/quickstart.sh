#!/usr/bin/env bash
# Installs the dependencies, builds (release preset), and bakes a real character:
# MakeHuman from ../shared/data when present, else X/BCN_Epileptic.X from Debian's assimp-testmodels.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)"
mkdir -p out
input=../shared/data/makehuman/base.obj
[ -f "$input" ] || input=/usr/share/assimp/models/X/BCN_Epileptic.X
name=$(basename "${input%.*}")
build/release/cli/spherechain bake "$input" -o "out/$name.sphc" --report "out/$name.json" \
  --ray-csv "out/$name.rays.csv" --png "out/$name.png"
build/release/cli/spherechain inspect "out/$name.sphc"
build/release/cli/spherechain export-debug "out/$name.sphc" --mesh "$input" -o "out/$name.debug.gltf"
echo
echo "results in $(pwd)/out: $name.sphc (asset), $name.json (report), $name.png (front/side views),"
echo "  $name.debug.gltf (open in any glTF viewer), $name.rays.csv (per-ray torso comparison)"
