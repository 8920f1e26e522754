#!/usr/bin/env bash
# `splintcore check` of the phantom maxilla (the paper's largest jaw, 543,530 triangles, a
# 27 MB binary STL), whole process, against admesh on the same file, interleaved in one run
# (issue 29's first row); the medians of REPEAT runs each, wall clock and CPU time. Beside
# them, what the machine asks just to touch the check's arena once (dd with a buffer that
# size), and the same read and check in one process with its arena already touched
# (splintcore-bench, the same phantom).
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
bench=$(dirname "$tool")/splintcore-bench
[ -x "$bench" ] && [ "$triangles" = 543530 ] || bench=
python3 - "$tool" "$file" "$repeat" "$bench" <<'PY'
import json, os, re, resource, shutil, statistics, subprocess, sys, time
tool, path, repeat, bench = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
runs = {"splintcore check": [tool, "check", path]}
if shutil.which("admesh"):
    runs["admesh"] = ["admesh", path]
# What the whole process cannot go below here: its arena's first touch. `dd` with a buffer of
# the check's peak arena (one read of /dev/zero into it) does nothing but touch that memory
# once, in a fresh process; on the project's VM that costs more than the check's own work.
peak = json.loads(subprocess.run([tool, "check", path, "--json"], capture_output=True,
                                 text=True).stdout)["peak_arena_bytes"]
runs["dd, a buffer of the check's peak arena"] = ["dd", "if=/dev/zero", "of=/dev/null",
                                                  "bs=%d" % peak, "count=1"]
# Wall clock, and the CPU time (user + sys) of each child: on a loaded machine the wall clock
# is mostly waiting, the CPU time much less so.
times = {name: [] for name in runs}
cpu = {name: [] for name in runs}
def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime
for _ in range(repeat):
    for name, argv in runs.items():
        c0 = child_cpu()
        start = time.perf_counter()
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times[name].append(time.perf_counter() - start)
        cpu[name].append(child_cpu() - c0)
size = os.path.getsize(path)
print("load average %.2f %.2f %.2f" % os.getloadavg())
print("peak arena of the check: %d bytes" % peak)
print("| program | median wall (s) | min wall (s) | MB/s (median wall) | median CPU (s) |")
print("|---|---|---|---|---|")
for name, t in times.items():
    m = statistics.median(t)
    print("| %s | %.4f | %.4f | %.0f | %.4f |" % (name, m, min(t), size / m / 1e6,
                                             statistics.median(cpu[name])))
if "admesh" in times:
    print("splintcore check is %.1fx admesh (median wall), %.1fx (median CPU)" %
          (statistics.median(times["admesh"]) / statistics.median(times["splintcore check"]),
           statistics.median(cpu["admesh"]) / statistics.median(cpu["splintcore check"])))
# The same read (from memory) and check in one process, its arena warm: the library's own
# work, without the process start and the first touch of its memory (splintcore-bench).
if bench:
    print("the same read and check in one process, its arena warm (splintcore-bench, median s):")
    line = [l for l in subprocess.run([bench, "--filter", "stl_read_check_phantom_543k",
                                       "--repeat", str(repeat)], capture_output=True,
                                      text=True).stdout.splitlines() if l.startswith("bench=")][0]
    print(line)
    if "admesh" in times:
        inside = float(re.search(r"median_s=([0-9.]+)", line).group(1))
        print("in one process: %.1fx admesh's whole process (median wall)" %
              (statistics.median(times["admesh"]) / inside))
PY
