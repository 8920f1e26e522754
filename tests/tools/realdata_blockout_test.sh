#!/usr/bin/env bash
# Issue 29, the whole design in 64 MiB with the blockout: the real CBCT dentition
# (../shared/realdata, not in the repository: exits 77, skipped, without it), exported by
# splintcore-bench as a case (its 14 + 14 picks) with "blockout": {"voxel": 0.1}, designed with
# --memory-cap 64M (the case's own memory_cap is 1G: the flag wins); the splint written must be a
# closed, valid solid (splintcore check), and the report must say the blockout ran on both
# jaws and checked the result for self-intersections.
#   usage: realdata_blockout_test.sh SPLINTCORE SPLINTCORE_BENCH REALDATA_DIR
# shellcheck source=realdata_steps.sh
source "$(dirname "$0")/realdata_steps.sh"
step "export the real case" "$bench" --realdata "$real" --export-realcase "$work/rc"
# The exported case (its picks, the insertion direction) with the blockout at 0.1 mm.
step "the case with the blockout" python3 -c '
import json, sys
c = json.load(open(sys.argv[1]))
c["blockout"] = {"voxel": 0.1}
json.dump(c, open(sys.argv[2], "w"))' "$work/rc/case.json" "$work/rc/blockout.json"
step "design the real case with the blockout in 64 MiB" \
  "$tool" design "$work/rc/blockout.json" -o "$work/d" --memory-cap 64M
cat "$work/out"
step "the splint written is a printable solid" "$tool" check "$work/d/splint.stl"
cat "$work/out"
report=$work/d/report.json
step "the report says the blockout ran on both jaws, the result checked" python3 - "$report" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
c = r["checks"]
assert len(c["blockout"]) == 2, c["blockout"]
for b in c["blockout"]:
    assert b["swept_triangles"] > 0 and b["removed_volume_mm3"] >= 0, b
assert c["self_intersection_free"] and c["self_intersection_checked_by"] == "blockout", c
assert c["closed"] and c["edge_manifold"] and c["outward"] and c["shells"] == 1, c
assert r["run"]["memory_cap_bytes"] == 64 << 20, r["run"]
assert r["run"]["peak_arena_bytes"] <= 64 << 20, r["run"]
print("peak arena", r["run"]["peak_arena_bytes"], "bytes;",
      [(s["stage"], s["peak_arena_bytes"]) for s in r["run"]["stages"]])
PY
cat "$work/out"
exit $failed
