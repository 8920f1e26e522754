#!/usr/bin/env bash
# `splintcore check` of the phantom maxilla (the paper's largest jaw, 543,530 triangles, a
# 27 MB binary STL), whole process, against admesh on the same file, interleaved in one run
# (issue 29's first row); the medians of REPEAT runs each, wall clock.
#   bash tools/bench/read_check.sh [TOOL] [REPEAT] [TRIANGLES]   (TOOL: build/tools/splintcore)
set -eu
tool=${1:-build/tools/splintcore}
repeat=${2:-11}
triangles=${3:-543530}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$tool" phantom --triangles "$triangles" -o "$work" >/dev/null
file=$work/maxilla.stl
command -v admesh >/dev/null || echo "admesh not installed (apt-get install admesh): its column is empty"
python3 - "$tool" "$file" "$repeat" <<'PY'
import os, shutil, statistics, subprocess, sys, time
tool, path, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
runs = {"splintcore check": [tool, "check", path]}
if shutil.which("admesh"):
    runs["admesh"] = ["admesh", path]
times = {name: [] for name in runs}
for _ in range(repeat):
    for name, argv in runs.items():
        start = time.perf_counter()
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times[name].append(time.perf_counter() - start)
size = os.path.getsize(path)
print("| program | median (s) | min (s) | MB/s (median) |")
print("|---|---|---|---|")
for name, t in times.items():
    m = statistics.median(t)
    print("| %s | %.4f | %.4f | %.0f |" % (name, m, min(t), size / m / 1e6))
if "admesh" in times:
    print("splintcore check is %.1fx admesh (medians)" %
          (statistics.median(times["admesh"]) / statistics.median(times["splintcore check"])))
PY
