#!/usr/bin/env bash
# Prepares .carry/ (git-ignored) for the GPU machine, which has CMake, nvcc and a compiler but no
# package registry: the FlatBuffers and doctest headers from this machine's Debian packages, doctest's
# CMake package made relocatable, baked MakeHuman / CesiumMan / BCN_Epileptic assets with their recorded
# frames (positions and joint matrices) plus MakeHuman's body mesh, for the CPU == GPU tests and the bench.
# Run it here, then the whole check on the GPU machine in one command (device tool, carry [".carry"]):
#   bash scripts/gpu-check.sh [--ncu]
# which builds the `cuda` preset there, runs the CUDA suite on these assets and frames, the bench,
# compute-sanitizer and ctest's guard, and writes its logs into $OUT (see its header).
# `scripts/gpu-carry.sh --base REV` also carries cuda/ as it is at git revision REV (.carry/base/cuda), which
# gpu-check.sh then builds beside the working tree's and benches in the same run (a before/after on one GPU).
set -euo pipefail
cd "$(dirname "$0")/.."
base_rev=
if [ "${1:-}" = "--base" ]; then
  base_rev=${2:?usage: gpu-carry.sh [--base REV]}
  git rev-parse --verify -q "$base_rev^{commit}" >/dev/null || { echo "gpu-carry.sh: no such revision: $base_rev" >&2; exit 1; }
fi
cli=${SPHERECHAIN_CLI:-build/dev/cli/spherechain}
[ -x "$cli" ] || { echo "build the CLI first (bash scripts/test.sh, or set SPHERECHAIN_CLI)" >&2; exit 1; }
rm -rf .carry && mkdir -p .carry/include .carry/lib/cmake .carry/data/makehuman .carry/data/gltf
cp -r /usr/include/flatbuffers /usr/include/doctest .carry/include/
cp -r /usr/lib/cmake/doctest .carry/lib/cmake/
sed -i 's|^set(_IMPORT_PREFIX "/usr")|get_filename_component(_IMPORT_PREFIX "${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)|' \
  .carry/lib/cmake/doctest/doctestTargets.cmake
data=../shared/data
cp $data/makehuman/base.obj $data/makehuman/default.mhskel $data/makehuman/default_weights.mhw .carry/data/makehuman/
cp $data/gltf/CesiumMan.gltf .carry/data/gltf/
"$cli" -q bake $data/makehuman/base.obj -o .carry/mh.sphc >/dev/null
"$cli" -q bake $data/gltf/CesiumMan.gltf -o .carry/cesiumman.sphc >/dev/null
bcn=/usr/share/assimp/models/X/BCN_Epileptic.X  # Debian's assimp-testmodels
"$cli" -q bake $bcn -o .carry/bcn.sphc >/dev/null
mkdir -p .carry/frames/mh .carry/frames/cesiumman .carry/frames/bcn
"$cli" -q play .carry/mh.sphc --mesh $data/makehuman/base.obj --repeat 1 --dump-frames .carry/frames/mh >/dev/null
"$cli" -q play .carry/cesiumman.sphc --mesh $data/gltf/CesiumMan.gltf --repeat 1 --dump-frames .carry/frames/cesiumman >/dev/null
"$cli" -q play .carry/bcn.sphc --mesh $bcn --repeat 1 --dump-frames .carry/frames/bcn >/dev/null
if [ -n "$base_rev" ]; then
  mkdir -p .carry/base
  git archive "$base_rev" cuda | tar -x -C .carry/base
  git rev-parse --short "$base_rev" >.carry/base/REVISION
fi
echo "then, on the GPU machine: bash scripts/gpu-check.sh"
du -sh .carry
