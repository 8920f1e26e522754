#!/usr/bin/env bash
# Issue 29, the blockout row with the AUTOMATIC outline: the real CBCT dentition (../shared/
# realdata, not in the repository: exits 77, skipped, without it), exported by splintcore-bench,
# as the case tools/bench/issue29.sh designs (spacing 0.5 mm, "auto" with a 2 mm bite opening)
# with "blockout": {"method": "voxel", "voxel": 0.1} (the sampled sweep; without "method" the
# same object is "auto", the exact sweep), designed with a 1 GiB cap and with the tight cap
# below: the splint written under the tight cap must be a closed, valid solid (splintcore
# check), its bytes the 1 GiB run's, and the report's peak arena within the cap.
# The cap is issue 29's goal, 64M: the design's peak is 63,374,912 B, set by the first Boolean
# (the blockout's sweep peaks at 62.5 MB since its extractor takes one sample layer a fill call).
#   usage: realdata_auto_blockout_test.sh SPLINTCORE SPLINTCORE_BENCH REALDATA_DIR
# shellcheck source=realdata_steps.sh
source "$(dirname "$0")/realdata_steps.sh"
cap=64M
step "export the real case" "$bench" --realdata "$real" --export-realcase "$work/rc"
step "the automatic case with the blockout" \
  auto_case "$work/rc/auto_blockout.json" '{"method": "voxel", "voxel": 0.1}'
step "design it with 1 GiB" "$tool" design "$work/rc/auto_blockout.json" -o "$work/big" \
  --memory-cap 1G
step "design it in $cap" "$tool" design "$work/rc/auto_blockout.json" -o "$work/d" \
  --memory-cap "$cap"
cat "$work/out"
step "the splint written is a printable solid" "$tool" check "$work/d/splint.stl"
cat "$work/out"
step "the same bytes as with 1 GiB" cmp "$work/big/splint.stl" "$work/d/splint.stl"
step "the report: outlined, blockout on both jaws, checked, within the cap" \
  blockout_report "$work/d/report.json" "$((${cap%M} << 20))" auto
cat "$work/out"
exit $failed
