#!/usr/bin/env bash
# Installs the dependencies, builds (release preset), and bakes a real character:
# MakeHuman from ../shared/data when present, else X/BCN_Epileptic.X from Debian's assimp-testmodels; and installs
# the Python module (docs/python.md).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)"
mkdir -p out
input=../shared/data/makehuman/base.obj
[ -f "$input" ] || input=/usr/share/assimp/models/X/BCN_Epileptic.X
name=$(basename "${input%.*}")
build/release/cli/spherechain bake "$input" -o "out/$name.sphc" --report "out/$name.json" --png "out/$name.png"
build/release/cli/spherechain inspect "out/$name.sphc"
build/release/cli/spherechain export-debug "out/$name.sphc" --mesh "$input" -o "out/$name.debug.gltf"
# The Python module (built when python3-dev, python3-numpy and pybind11-dev are there: setup.sh installs them),
# installed where Debian's python3 finds it: /usr/local/lib/python3.11/dist-packages/spherechain.
if [ -d build/release/python/spherechain ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO cmake --install build/release --component python >/dev/null
  py=$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' build/release/CMakeCache.txt)  # /usr/bin/python3 unless told
  "${py:-python3}" -c "import spherechain, sys; a = spherechain.load(sys.argv[1]); print('python3: import spherechain:', a)" \
    "out/$name.sphc"
fi
echo
echo "results in $(pwd)/out: $name.sphc (asset), $name.json (report), $name.png (front/side views),"
echo "  $name.debug.gltf (open in any glTF viewer)"
