#!/usr/bin/env bash
# Issue 29's table in one run: reading and checking against admesh, the Booleans (and the
# pair from Manifold's bug reports), the blockout and spacer of the real case at 0.1 mm in a
# 64 MiB cap, with peak arena where the program reports one, and the least cap of the real
# 4 mm design (a bisection: about a minute more). Each row is measured here, now, by the
# command named beside it.
#   bash tools/bench/issue29.sh [BUILD_DIR] [REPEAT] [REALDATA_DIR]
# Rows that need the real dentition (../shared/realdata) say so and are skipped without it.
# CGAL and Manifold are not Debian packages with a command-line Boolean: their figures are in
# ../shared/peers.md (same machine class), not rerun here.
set -eu
build=${1:-build/rel}
repeat=${2:-5}
realdata=${3:-../shared/realdata/open-full-jaw-patient26}
tool=$build/tools/splintcore
bench=$build/tools/splintcore-bench
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "== check of the 543,530-triangle phantom maxilla (27 MB binary STL), whole process"
bash "$(dirname "$0")/read_check.sh" "$tool" "$repeat"

echo
echo "== the exact Boolean in memory (splintcore-bench; peak_arena_bytes is the arena's high water)"
"$bench" --filter boolean_phantom_87k --repeat "$((repeat * 4))" | grep -E "^bench="
"$bench" --filter boolean_phantom_324k --repeat "$repeat" | grep -E "^bench="
if [ -d "$realdata" ]; then
  "$bench" --realdata "$realdata" --filter boolean_realdata --repeat "$repeat" | grep -E "^bench="
else
  echo "boolean_realdata: no real data at $realdata"
fi

echo
echo "== the Boolean file to file: \`splintcore boolean --difference\`, whole process, one thread"
echo "   (the last row two; with a second core the arena's memory is touched ahead on a thread"
echo "   of its own at any --threads, and one core alone is the row pinned by taskset -c 0)"
echo "   (B read cropped to A's box; CGAL's whole process on the 324k phantom: 0.77-1.04 s,"
echo "   Manifold's Boolean alone on the real dentition 0.57 s: ../shared/peers.md)"
mkdir -p "$work/p324"
"$tool" phantom --triangles 162122 -o "$work/p324" >/dev/null
"$tool" base "$work/p324/case.json" -o "$work/p324/base.stl" >/dev/null
runs=("324k phantom (2 files, mandible opened 2 mm)|$work/p324/base.stl|$work/p324/maxilla.stl $work/p324/mandible.stl|--translate-b 0,0,0 --translate-b 0,0,-2")
if [ -d "$realdata" ]; then
  "$bench" --realdata "$realdata" --export-realcase "$work/rb" >/dev/null
  "$tool" base "$work/rb/case.json" -o "$work/rb/base.stl" >/dev/null
  teeth=$(ls "$realdata"/maxilla/*.stl "$realdata"/mandible/*.stl | tr '\n' ' ')
  runs+=("real dentition (31 tooth files, in occlusion)|$work/rb/base.stl|$teeth|")
  if command -v taskset >/dev/null; then
    runs+=("the same on one core (taskset -c 0)|$work/rb/base.stl|$teeth||taskset -c 0")
  fi
  runs+=("the same at --threads 2|$work/rb/base.stl|$teeth|--threads 2")
fi
for row in "${runs[@]}"; do
  IFS='|' read -r name a b extra pin <<<"$row"
  # shellcheck disable=SC2086  # the file lists and options split on purpose
  python3 - "$name" "$repeat" $pin "$tool" boolean --difference "$a" $b $extra -o "$work/bool.stl" <<'PY'
import json, statistics, subprocess, sys, time
name, repeat, argv = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
wall, last = [], None
for _ in range(repeat):
    t0 = time.perf_counter()
    r = subprocess.run(argv + ["--json"], capture_output=True, text=True, check=True)
    wall.append(time.perf_counter() - t0)
    last = json.loads(r.stdout)
# The first touch of that much memory alone, in a fresh process (dd with a buffer the size of
# the peak arena): on the project's VM a floor under the whole process (read_check.sh).
touch = []
for _ in range(repeat):
    t0 = time.perf_counter()
    subprocess.run(["dd", "if=/dev/zero", "of=/dev/null", "bs=%d" % last["peak_arena_bytes"],
                    "count=1"], capture_output=True, check=True)
    touch.append(time.perf_counter() - t0)
print("%-46s median %.3f s (min %.3f): read %.3f, Boolean %.3f, check %.3f; B %d of %d "
      "triangles kept, peak arena %d B (dd touching as much: %.3f s)" % (
      name, statistics.median(wall), min(wall), last["read_s"], last["boolean_s"],
      last["self_check_s"], last["b_triangles_kept"], last["b_triangles"],
      last["peak_arena_bytes"], statistics.median(touch)))
PY
done

echo
echo "== the pair from Manifold's bug reports (about 20k + 12k triangles): \`boolean --union\`, whole"
echo "   process, one thread; it must answer, either way, in under a second"
twin=$realdata/../manifold-bugreports
if [ -f "$twin/Generic_Twin_7081.1.t0_left.obj" ]; then
  python3 - "$tool" "$twin" "$repeat" "$work/twin.stl" <<'PY'
import statistics, subprocess, sys, time
tool, d, repeat, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
argv = [tool, "boolean", "--union", d + "/Generic_Twin_7081.1.t0_left.obj",
        d + "/Generic_Twin_7081.1.t0_right.obj", "-o", out]
wall = []
for _ in range(repeat):
    t0 = time.perf_counter()
    r = subprocess.run(argv, capture_output=True, text=True)
    wall.append(time.perf_counter() - t0)
said = "ok" if r.returncode == 0 else (r.stderr.strip().splitlines() or ["?"])[-1][:100]
print("median %.3f s (min %.3f), exit %d: %s" % (statistics.median(wall), min(wall),
                                                 r.returncode, said))
PY
else
  echo "no Manifold pair at $twin: skipped"
fi

echo
echo "== the paper-scale phantom's sweep at 0.05 mm in 64 MiB (splintcore-bench)"
"$bench" --filter sweep_phantom_005_64m --repeat 1 | grep -E "^bench=|^# sweep"

echo
echo "== the paper-scale phantom (271,768 triangles a jaw) designed with the default blockout,"
echo "   --memory-cap 64M, whole process, one thread (median of $repeat)"
mkdir -p "$work/p272"
"$tool" phantom --triangles 271768 -o "$work/p272" >/dev/null
python3 - "$tool" "$work/p272" "$repeat" <<'PY'
import json, statistics, subprocess, sys, time
tool, d, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
c = json.load(open(d + "/case.json"))
c["blockout"] = {}  # the default: "auto", the exact sweep here
c["output"] = {"splint": "splint.stl", "report": "report.json"}
json.dump(c, open(d + "/exact.json", "w"))
wall = []
for _ in range(repeat):
    t0 = time.perf_counter()
    subprocess.run([tool, "design", d + "/exact.json", "-o", d + "/out", "--memory-cap", "64M"],
                   check=True, capture_output=True)
    wall.append(time.perf_counter() - t0)
r = json.load(open(d + "/out/report.json"))
print("median %.3f s (min %.3f), peak arena %d B, %d triangles; swept %s" % (
    statistics.median(wall), min(wall), r["run"]["peak_arena_bytes"], r["output"]["triangles"],
    [b["swept_triangles"] for b in r["checks"]["blockout"]]))
PY

echo
echo "== the same phantom with the height field at 0.05 mm, --memory-cap 64M, whole process (one run)"
python3 - "$tool" "$work/p272" <<'PY'
import json, subprocess, sys, time
tool, d = sys.argv[1], sys.argv[2]
c = json.load(open(d + "/case.json"))
c["blockout"] = {"method": "heightfield", "voxel": 0.05}
c["output"] = {"splint": "splint.stl", "report": "report.json"}
json.dump(c, open(d + "/hf005.json", "w"))
t0 = time.perf_counter()
r = subprocess.run([tool, "design", d + "/hf005.json", "-o", d + "/hf", "--memory-cap", "64M"],
                   capture_output=True, text=True)
wall = time.perf_counter() - t0
if r.returncode != 0:
    print("%.3f s: %s" % (wall, (r.stderr.strip().splitlines() or ["?"])[-1][:120]))
else:
    rep = json.load(open(d + "/hf/report.json"))
    print("%.3f s, peak arena %d B, %d triangles; grids %s" % (
        wall, rep["run"]["peak_arena_bytes"], rep["output"]["triangles"],
        [b["grid_cells"] for b in rep["checks"]["blockout"]]))
PY

echo
echo "== the real case, file to file, blockout and spacer at 0.1 mm, --memory-cap 64M"
if [ ! -d "$realdata" ]; then
  echo "no real data at $realdata: skipped"
  exit 0
fi
"$bench" --realdata "$realdata" --export-realcase "$work/case" >/dev/null
python3 - "$tool" "$work/case" <<'PY'
import json, os, subprocess, sys, time
tool, case = sys.argv[1], sys.argv[2]
base = {"splintcore_case": 1, "case_id": "realdata-patient26", "units": "mm",
        "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"},
                 {"role": "mandible", "mesh": "mandible.stl"}],
        "base": {"spacing_mm": 0.5, "auto": {"bite_opening_mm": 2}}, "printer": "eden260",
        "output": {"splint": "splint.stl", "report": "report.json"}}
rows = [("plain splint", None), ("blockout default ({}: auto)", {}),
        ("blockout exact", {"method": "exact"}),
        ("blockout auto, base 3 mm deep", {"deep": 3}),
        ("blockout auto, base 4 mm deep", {"deep": 4}),
        ("blockout {voxel: 0.1} (auto)", {"voxel": 0.1}),
        ("blockout method voxel 0.1", {"method": "voxel", "voxel": 0.1}),
        ("blockout heightfield 0.1", {"method": "heightfield", "voxel": 0.1}),
        ("heightfield, base 4 mm deep", {"deep": 4, "method": "heightfield", "voxel": 0.1}),
        ("spacer {voxel: 0.1, clearance: 0.1}", {"voxel": 0.1, "clearance": 0.1}),
        ("the same spacer at --threads 2", {"voxel": 0.1, "clearance": 0.1, "threads": 2}),
        ("spacer method voxel (clearance 0.1)",
         {"method": "voxel", "voxel": 0.1, "clearance": 0.1})]
print("%-36s %9s %14s %11s  %s" % ("case", "wall (s)", "peak arena (B)", "triangles", "result"))
for name, blockout in rows:
    c = json.loads(json.dumps(base))
    threads = (blockout or {}).get("threads", 1)
    if blockout is not None:
        blockout = {k: v for k, v in blockout.items() if k != "threads"}
    if blockout is not None and "deep" in blockout:  # a base reaching the necks (4 mm: voxels)
        c["base"]["auto"]["indentation_depth_mm"] = blockout["deep"]
        blockout = {k: v for k, v in blockout.items() if k != "deep"}
    if blockout is not None:
        c["blockout"] = blockout
    path = os.path.join(case, "c.json")
    with open(path, "w") as f:
        json.dump(c, f)
    out = os.path.join(case, "out")
    t0 = time.perf_counter()
    r = subprocess.run([tool, "design", path, "-o", out, "--memory-cap", "64M",
                        "--threads", str(threads)],
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        err = (r.stderr.strip().splitlines() or ["exit %d" % r.returncode])[-1]
        print("%-36s %9.3f %14s %11s  %s" % (name, wall, "-", "-", err[:110]))
        continue
    rep = json.load(open(os.path.join(out, "report.json")))
    def find(d, key):
        if isinstance(d, dict):
            if key in d:
                return d[key]
            for v in d.values():
                x = find(v, key)
                if x is not None:
                    return x
        return None
    used = rep["checks"].get("blockout_method_used")
    how = "" if used is None else " (%s%s)" % (
        used, ", the exact sweep stopped" if "blockout_fallback" in rep["checks"] else "")
    print("%-36s %9.3f %14s %11s  ok%s" % (name, wall, find(rep, "peak_arena_bytes"),
                                          rep.get("output", {}).get("triangles"), how))
PY

# The least --memory-cap the real 4 mm design runs in, by bisection (each run about 7 s), with
# the splint's bytes checked against the run at 1G at every cap that works: the bytes must not
# depend on the cap, and every cap above one that works must work (issue 29's 64 MiB goal).
echo
echo "== the real case, base 4 mm deep, default blockout: the least --memory-cap that works"
python3 - "$tool" "$work/case" <<'PY'
import hashlib, json, os, subprocess, sys
tool, case = sys.argv[1], sys.argv[2]
c = json.load(open(os.path.join(case, "c.json")))
c["base"]["auto"]["indentation_depth_mm"] = 4
c["blockout"] = {}
path = os.path.join(case, "deep4.json")
json.dump(c, open(path, "w"))
def run(cap):
    out = os.path.join(case, "least")
    r = subprocess.run([tool, "design", path, "-o", out, "--memory-cap", str(cap)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        return None, None
    rep = json.load(open(os.path.join(out, "report.json")))
    return hashlib.sha256(open(os.path.join(out, "splint.stl"), "rb").read()).hexdigest(), rep
ample, rep = run(1 << 30)
if ample is None:
    print("fails at 1G")
    sys.exit(0)
peak = rep["run"]["peak_arena_bytes"]
lo, hi = 64 << 20, peak  # fails (or is the goal), works
first, _ = run(lo)
if first is not None:
    print("works at 64 MiB: %s" % ("the same bytes" if first == ample else "DIFFERENT BYTES"))
    sys.exit(0)
while hi - lo > (256 << 10):
    mid = (lo + hi) // 2
    h, _ = run(mid)
    if h is not None and h != ample:
        print("DIFFERENT BYTES at %d" % mid)
        sys.exit(1)
    if h is None:
        lo = mid
    else:
        hi = mid
print("peak at 1G %d B (splint %s...); least cap %d B (within 256 KiB), fails at 64 MiB" % (
    peak, ample[:8], hi))
PY
