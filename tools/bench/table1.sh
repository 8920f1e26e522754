#!/usr/bin/env bash
# The paper's Table 1 end to end (Chen et al. 2016: generation of the base, the Boolean, the
# whole time), file in to file out, on phantom jaws of the paper's sizes: for each size,
# `splintcore phantom` writes both jaws and their case (fixtures/cases/paper_scale.json's
# picks), then `splintcore design CASE -o OUT --json` runs REPEAT times on one core; the
# medians of report.json's figures are printed as a table; then the same for the real
# dentition when ../shared/realdata is there. The paper's VTK tool took 7.6 s,
# 33.9 s and 55.3 s for the Boolean alone at these sizes.
#   bash tools/bench/table1.sh [TOOL] [REPEAT]     (TOOL: build/tools/splintcore)
set -eu
tool=${1:-build/tools/splintcore}
repeat=${2:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '| jaw triangles (both) | base | Boolean | design (all stages) | read | file to file | peak arena | splint triangles |\n'
printf '|---|---|---|---|---|---|---|---|\n'
# The real dentition (31 CBCT teeth, ../shared/realdata; its wafer fitted to the arch by
# tools/common/realcase.h) when present.
realdata=${SPLINTCORE_REALDATA:-../shared/realdata/open-full-jaw-patient26}
sizes="43434 162122 271768"
if [ -d "$realdata" ]; then sizes="$sizes real"; fi
for per_jaw in $sizes; do
  dir=$work/p$per_jaw
  mkdir -p "$dir"
  if [ "$per_jaw" = real ]; then
    "$(dirname "$tool")/splintcore-bench" --realdata "$realdata" --export-realcase "$dir" >/dev/null
  else
    "$tool" phantom --triangles "$per_jaw" -o "$dir" >/dev/null
  fi
  rows=""
  for i in $(seq "$repeat"); do
    rm -rf "$dir/out"
    start=$(date +%s.%N)
    "$tool" design "$dir/case.json" -o "$dir/out" --threads 1 --json >"$dir/run.json"
    end=$(date +%s.%N)
    rows="$rows$(python3 - "$dir/out/report.json" "$start" "$end" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
run = r["run"]  # this run's figures (the report's last object)
st = {s["stage"]: s["time_s"] for s in run["stages"]}
print(sum(i["triangles"] for i in r["inputs"]), st.get("base", 0), st.get("boolean", 0),
      run["design_s"], run["read_s"], float(sys.argv[3]) - float(sys.argv[2]),
      run["peak_arena_bytes"], r["output"]["triangles"])
PY
)
"
  done
  printf '%s' "$rows" | python3 -c '
import sys, statistics as s
rows = [l.split() for l in sys.stdin if l.strip()]
med = lambda k: s.median(float(r[k]) for r in rows)
print("| %d | %.2f ms | %.1f ms | %.1f ms | %.1f ms | %.3f s (process wall) | %.1f MB | %d |" % (
    int(rows[0][0]), med(1) * 1e3, med(2) * 1e3, med(3) * 1e3, med(4) * 1e3, med(5),
    med(6) / 1e6, int(rows[0][7])))'
done
