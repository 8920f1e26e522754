#!/usr/bin/env bash
# Issue 29, the exact blockout on the real CBCT dentition (../shared/realdata, not in the
# repository: exits 77, skipped, without it): the case tools/bench/issue29.sh designs (spacing
# 0.5 mm, "auto" with a 2 mm bite opening) with "blockout": {"method": "exact"}, designed in
# 64 MiB on one thread, with 1 GiB, on two threads, and with the default "blockout": {}
# ("auto", which is exact here; so is {"voxel": 0.1}), and with a base 3 mm deep: the splint is a
# closed, valid solid
# (splintcore check), the same bytes every way, the report says the exact method ran on both
# jaws and checked the result, within the cap.
#   usage: realdata_exact_blockout_test.sh SPLINTCORE SPLINTCORE_BENCH REALDATA_DIR
# shellcheck source=realdata_steps.sh
source "$(dirname "$0")/realdata_steps.sh"
step "export the real case" "$bench" --realdata "$real" --export-realcase "$work/rc"
step "the automatic case with the exact blockout" \
  auto_case "$work/rc/exact.json" '{"method": "exact"}'
step "design it in 64M" "$tool" design "$work/rc/exact.json" -o "$work/d" --memory-cap 64M
cat "$work/out"
step "design it with 1 GiB" "$tool" design "$work/rc/exact.json" -o "$work/big" --memory-cap 1G
step "design it on two threads" "$tool" design "$work/rc/exact.json" -o "$work/t2" \
  --memory-cap 64M --threads 2
step "the splint written is a printable solid" "$tool" check "$work/d/splint.stl"
cat "$work/out"
step "the same bytes with 1 GiB" cmp "$work/big/splint.stl" "$work/d/splint.stl"
step "the same bytes on two threads" cmp "$work/t2/splint.stl" "$work/d/splint.stl"
# The default ("blockout": {}, "auto") is the exact method here: the same splint.
step "the automatic case with the default blockout" auto_case "$work/rc/default.json" '{}'
step "design it in 64M" "$tool" design "$work/rc/default.json" -o "$work/default" \
  --memory-cap 64M
step "the default gives the exact method's bytes" cmp "$work/default/splint.stl" \
  "$work/d/splint.stl"
# Issue 29's row {"voxel": 0.1}: without "method" that is "auto" too (the voxel is its
# fallback's grid), so the same splint in 64 MiB.
step "the automatic case with {\"voxel\": 0.1}" auto_case "$work/rc/voxel.json" '{"voxel": 0.1}'
step "design it in 64M" "$tool" design "$work/rc/voxel.json" -o "$work/voxel" --memory-cap 64M
step "{\"voxel\": 0.1} gives the exact method's bytes" cmp "$work/voxel/splint.stl" \
  "$work/d/splint.stl"
step "the report: outlined, blockout on both jaws, checked, within the cap" \
  blockout_report "$work/d/report.json" "$((64 << 20))" auto
cat "$work/out"
step "the report: the exact method on both jaws, the jaws' own Boolean not run" python3 - \
  "$work/d/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
c = r["checks"]
assert r["parameters"]["blockout_method"] == "exact", r["parameters"]
assert c["imprint"].startswith("exact swept volume"), c["imprint"]
assert c["boolean_intersecting_pairs"] == 0, c
for b in c["blockout"]:
    assert b["method"] == "exact" and b["walls"] > 0 and b["kept_front_triangles"] > 0, b
    print(b["role"], "front", b["front_triangles"], "kept", b["kept_front_triangles"], "walls",
          b["walls"], "folds", b["fold_vertices"], "taken in", b["back_triangles_taken_in"])
PY
cat "$work/out"
# The base 3 mm deep (the default is 2): the fold rounds take in triangles whose pockets are wider
# and deeper than 0.05 mm, but none with the base in its column, so the design stays exact.
step "the automatic case with a base 3 mm deep" auto_case "$work/rc/deep.json" '{}' 3
step "design it in 64M" "$tool" design "$work/rc/deep.json" -o "$work/deep" --memory-cap 64M
step "the splint written is a printable solid" "$tool" check "$work/deep/splint.stl"
step "the report: exact on both jaws, pockets clear of the base, within the cap" \
  blockout_report "$work/deep/report.json" "$((64 << 20))" auto
step "the report: the exact method, pockets clear of the base counted" python3 - \
  "$work/deep/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
c = r["checks"]
assert c["blockout_method_used"] == "exact" and "blockout_fallback" not in c, c
clear = [b["fold_pockets_clear_of_splint"] for b in c["blockout"]]
assert sum(clear) > 0, clear
print("pockets clear of the base", clear, "taken in",
      [b["back_triangles_taken_in"] for b in c["blockout"]])
PY
cat "$work/out"
# The base 4 mm deep: the mandible's exact sweep is refused (a fold would leave an overhang), and
# "auto" makes that jaw with the height field (on its 0.1 mm grid); the whole design fits 64 MiB
# (peak 63.1 MB, 1.7 s; with voxels for that jaw, as until 2026-12-04, 66.4 MB and 5.8 s).
# Closed, manifold, outward and one piece: the two crumbs of under 1e-4 mm^3 the Boolean leaves
# beside it are taken out and reported
# (ExactBlockoutRealData.DeepBaseIn64MiB checks the bytes against a design with room to spare,
# and both jaws with the line check).
step "the automatic case with a base 4 mm deep" auto_case "$work/rc/deep4.json" '{}' 4
step "design it in 64M" "$tool" design "$work/rc/deep4.json" -o "$work/deep4" --memory-cap 64M
step "the splint written is closed, manifold and outward" "$tool" check "$work/deep4/splint.stl"
cat "$work/out"
step "the report: the maxilla exact, the mandible by the height field and why, checked, within the cap" \
  python3 - "$work/deep4/report.json" "$((64 << 20))" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
c = r["checks"]
assert c["blockout_method_used"] == "exact and heightfield", c["blockout_method_used"]
assert [b["method"] for b in c["blockout"]] == ["exact", "heightfield"], c["blockout"]
assert "mandible" in c["blockout_fallback"], c["blockout_fallback"]
assert c["self_intersection_free"] and c["self_intersection_checked_by"] == "blockout", c
assert c["closed"] and c["edge_manifold"] and c["outward"] and c["shells"] == 1, c
assert c["crumbs_removed"] == 2 and c["crumbs_volume_mm3"] < 1e-3, c
assert r["run"]["peak_arena_bytes"] <= int(sys.argv[2]), r["run"]
print("peak arena", r["run"]["peak_arena_bytes"], "bytes; crumbs removed", c["crumbs_removed"],
      "(%g mm^3); fallback:" % c["crumbs_volume_mm3"],
      c["blockout_fallback"])
PY
cat "$work/out"
exit $failed
