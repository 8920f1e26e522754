#!/usr/bin/env bash
# The real case file to file (issues 28 and 32): `splintcore design` of the real dentition
# (../shared/realdata, 887,688 triangles, exported by splintcore-bench --export-realcase) with
# the automatic outline (one splint, bite opened 2 mm) and with the surgical plan (intermediate
# and final splints, autorotation, job.3mf), whole process: reading the STLs, designing, writing
# the STLs, report, previews and 3MF. Medians of REPEAT runs each, wall clock and CPU time, at
# 1 and 2 threads (the bytes are the same at every thread count; the script checks it).
#   bash tools/bench/realcase.sh [BUILD_DIR] [REPEAT] [REALDATA_DIR]
set -eu
build=${1:-build/rel}
repeat=${2:-7}
realdata=${3:-../shared/realdata/open-full-jaw-patient26}
tool=$build/tools/splintcore
bench=$build/tools/splintcore-bench
if [ ! -d "$realdata" ]; then
  echo "no real data at $realdata: nothing to measure"
  exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bench" --realdata "$realdata" --export-realcase "$work/case" >/dev/null
python3 - "$tool" "$work" "$repeat" <<'PY'
import hashlib, json, os, resource, statistics, subprocess, sys, time
tool, work, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
case = os.path.join(work, "case")
# The two cases of tests/tools/realdata_cli_test.sh: the automatic outline opening the bite by
# 2 mm, and the plan (maxilla 3 mm back, mandible 5 mm back, hinge axis through the condyles).
jaws = [{"role": "maxilla", "mesh": "maxilla.stl"}, {"role": "mandible", "mesh": "mandible.stl"}]
def move_y(dy):
    return [1, 0, 0, 0, 0, 1, 0, dy, 0, 0, 1, 0, 0, 0, 0, 1]
cases = {
    "auto.json": {"splintcore_case": 1, "case_id": "realdata-patient26", "units": "mm",
                  "jaws": jaws, "base": {"spacing_mm": 0.5, "auto": {"bite_opening_mm": 2}},
                  "printer": "eden260", "memory_cap": "64M",
                  "output": {"splint": "splint.stl", "report": "report.json"}},
    "plan.json": {"splintcore_case": 1, "case_id": "realdata-patient26", "units": "mm",
                  "jaws": jaws, "base": {"spacing_mm": 0.5, "auto": {}}, "printer": "eden260",
                  "memory_cap": "64M", "output": {"report": "report.json"},
                  "plan": {"sequence": "maxilla_first", "maxilla": move_y(-3),
                           "mandible": move_y(-5), "hinge_axis": [[4, 90, 80], [104, 90, 80]],
                           "intermediate_opening_mm": 2, "final_opening_mm": 1.5}},
}
for name, body in cases.items():
    with open(os.path.join(case, name), "w") as f:
        json.dump(body, f, indent=1)
rows = []
for name, outputs in (("auto.json", ["splint.stl", "preview.png"]),
                      ("plan.json", ["intermediate.stl", "final.stl", "job.3mf",
                                     "intermediate.png", "final.png"])):
    digests = {}
    for threads in (1, 2):
        wall, cpu = [], []
        for r in range(repeat):
            out = os.path.join(work, "out-%s-%d-%d" % (name, threads, r))
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            subprocess.run([tool, "design", os.path.join(case, name), "-o", out,
                            "--threads", str(threads)], stdout=subprocess.DEVNULL, check=True)
            wall.append(time.perf_counter() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
            digest = tuple(hashlib.sha256(open(os.path.join(out, f), "rb").read()).hexdigest()
                           for f in outputs)
            digests.setdefault(digest, []).append((threads, r))
        rows.append((name, threads, statistics.median(wall), min(wall), statistics.median(cpu)))
    if len(digests) != 1:
        print("DIFFERENT BYTES for %s across runs or thread counts: %s" % (name, digests))
        sys.exit(1)
print("| case | threads | median wall (s) | min wall (s) | median CPU (s) |")
print("|---|---|---|---|---|")
for name, threads, med, low, cpu in rows:
    print("| %s | %d | %.3f | %.3f | %.3f |" % (name, threads, med, low, cpu))
print("(same output bytes in every run and at 1 and 2 threads)")
PY
