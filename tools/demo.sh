#!/usr/bin/env bash
# The main job on a bundled fixture: build splintcore, then read, check and rewrite a fixture
# STL through the streaming writer, and check the written file for the Eden260 printer.
set -eu
cd "$(dirname "$0")/.."
. tools/deps.sh
ensure_packages g++ cmake make
cmake -S . -B build/demo -DCMAKE_BUILD_TYPE=Release -DSPLINTCORE_BUILD_TESTS=OFF >/dev/null
cmake --build build/demo -j "$(nproc)" >/dev/null
mkdir -p out
build/demo/tools/splintcore convert fixtures/stl/torus_binary.stl -o out/torus.stl
build/demo/tools/splintcore check out/torus.stl --printer eden260
echo "demo: wrote out/torus.stl (sha256 $(sha256sum out/torus.stl | cut -c1-64))"
