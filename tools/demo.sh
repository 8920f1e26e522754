#!/usr/bin/env bash
# The main job on a bundled fixture: build splintcore, then design a splint from the bundled
# case fixtures/cases/blockout.json (the paper-scale wafer with interference elimination,
# rounded edges, the wall-thickness check, placed on the Eden260 tray) on synthetic phantom
# jaws, and say where the STL, the audit report and the preview are.
set -eu
cd "$(dirname "$0")/.."
. tools/deps.sh
ensure_packages g++ cmake make
cmake -S . -B build/demo -DCMAKE_BUILD_TYPE=Release -DSPLINTCORE_BUILD_TESTS=OFF >/dev/null
cmake --build build/demo -j "$(nproc)" >/dev/null
tool=build/demo/tools/splintcore
mkdir -p out/case
# The jaws: phantom maxilla and mandible (6,000 triangles each) fitted to the bundled case.
"$tool" phantom --triangles 6000 -o out/case >/dev/null
cp fixtures/cases/blockout.json out/case/case.json
rm -rf out/splint
"$tool" design out/case/case.json -o out/splint
"$tool" check out/splint/splint.stl --printer eden260 --no-place >/dev/null
echo "demo: the splint is out/splint/splint.stl, the audit report out/splint/report.json," \
     "the preview out/splint/preview.png"
