# The start of the real-data shell tests (realdata_cli_test.sh, realdata_blockout_test.sh,
# realdata_auto_blockout_test.sh, realdata_exact_blockout_test.sh), sourced by them with their
# arguments SPLINTCORE SPLINTCORE_BENCH REALDATA_DIR: skipped (exit
# 77) without ../shared/realdata, a work folder removed at exit, and `step WHAT COMMAND...`,
# which prints ok or FAILED (then the command's output) and sets $failed.
set -u
tool=$1
bench=$2
real=$3
[ -f "$real/maxilla/tooth_1.stl" ] || { echo "realdata not found: skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
step() {  # what command...
  local what=$1
  shift
  if "$@" >"$work/out" 2>"$work/err"; then
    echo "ok: $what"
  else
    echo "FAILED: $what"; cat "$work/out" "$work/err"; failed=1
  fi
}

# auto_case FILE BLOCKOUT [DEPTH]: the exported real case (spacing 0.5 mm, "auto" outline with a
# 2 mm bite opening; DEPTH: its indentation_depth_mm) with the blockout object BLOCKOUT (JSON),
# written to FILE.
auto_case() {
  python3 - "$@" <<'PY'
import json, sys
c = {"splintcore_case": 1, "case_id": "realdata-patient26", "units": "mm",
     "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"},
              {"role": "mandible", "mesh": "mandible.stl"}],
     "base": {"spacing_mm": 0.5, "auto": {"bite_opening_mm": 2}}, "printer": "eden260",
     "blockout": json.loads(sys.argv[2]),
     "output": {"splint": "splint.stl", "report": "report.json"}}
if len(sys.argv) > 3:
    c["base"]["auto"]["indentation_depth_mm"] = float(sys.argv[3])
json.dump(c, open(sys.argv[1], "w"))
PY
}

# blockout_report REPORT CAP_BYTES [auto]: the report of a design with the blockout says it ran
# on both jaws and checked the result for self-intersections, a closed solid of one shell,
# within the memory cap; with `auto`, that the outline was the automatic one.
blockout_report() {
  python3 - "$@" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
cap = int(sys.argv[2])
if len(sys.argv) > 3:
    assert "outline" in r, "the outline was not the automatic one"
c = r["checks"]
assert len(c["blockout"]) == 2, c["blockout"]
for b in c["blockout"]:
    assert b["swept_triangles"] > 0 and b["removed_volume_mm3"] >= 0, b
assert c["self_intersection_free"] and c["self_intersection_checked_by"] == "blockout", c
assert c["closed"] and c["edge_manifold"] and c["outward"] and c["shells"] == 1, c
assert r["run"]["memory_cap_bytes"] == cap, r["run"]
assert r["run"]["peak_arena_bytes"] <= cap, r["run"]
print("peak arena", r["run"]["peak_arena_bytes"], "bytes;",
      [(s["stage"], s["peak_arena_bytes"]) for s in r["run"]["stages"]])
PY
}
