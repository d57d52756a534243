#!/usr/bin/env bash
# Configures, builds and runs the whole test suite (doctest via ctest).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset dev >/dev/null
cmake --build --preset dev -j"$(nproc)"
ctest --preset dev -j"$(nproc)"
