#!/usr/bin/env bash
# Installs every build and test dependency of spherechain from Debian 12 packages.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null 2>&1; then
    echo "spherechain: installing packages needs root: run this script as root, or install sudo" >&2
    exit 1
  fi
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential cmake ninja-build pkg-config doxygen \
  libassimp-dev libeigen3-dev libcgal-dev libtinygltf-dev libflatbuffers-dev flatbuffers-compiler \
  doctest-dev nlohmann-json3-dev libcli11-dev libspdlog-dev libxxhash-dev \
  libfcl-dev libbullet-dev libtbb-dev libembree-dev \
  clang libclang-rt-14-dev \
  python3-dev python3-numpy python3-pytest pybind11-dev \
  librsvg2-bin libxml2-utils assimp-testmodels chromium >/dev/null
# three.js for `spherechain view` (viewer/package.json pins it; the CLI embeds it in the HTML it writes),
# from the npm registry. Node and npm from Debian when the machine has none.
if ! command -v npm >/dev/null 2>&1; then
  $SUDO apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
# Without the registry the rest still builds and runs; only `spherechain view` fails, saying to run npm ci.
(cd "$(dirname "$0")/../viewer" && npm ci --no-audit --no-fund --loglevel=error) ||
  echo "spherechain: three.js not installed (npm ci failed): \`spherechain view\` will fail until \`npm ci\` succeeds in viewer/" >&2
echo "spherechain: dependencies installed"
