#!/usr/bin/env bash
# Issue 29, the whole design in 64 MiB with the blockout: the real CBCT dentition
# (../shared/realdata, not in the repository: exits 77, skipped, without it), exported by
# splintcore-bench as a case (its 14 + 14 picks) with "blockout": {"method": "voxel", "voxel": 0.1}
# (the sampled sweep; without "method" the same object is "auto", the exact sweep), designed with
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
c["blockout"] = {"method": "voxel", "voxel": 0.1}
json.dump(c, open(sys.argv[2], "w"))' "$work/rc/case.json" "$work/rc/blockout.json"
step "design the real case with the blockout in 64 MiB" \
  "$tool" design "$work/rc/blockout.json" -o "$work/d" --memory-cap 64M
cat "$work/out"
step "the splint written is a printable solid" "$tool" check "$work/d/splint.stl"
cat "$work/out"
step "the report says the blockout ran on both jaws, the result checked" \
  blockout_report "$work/d/report.json" "$((64 << 20))"
cat "$work/out"
exit $failed
