#!/usr/bin/env bash
# Issue 29, the 64 MiB cases on the command line: the real CBCT dentition (../shared/realdata,
# not in the repository: exits 77, skipped, without it), exported by splintcore-bench as a case
# with explicit picks, designed with --memory-cap 64M (jaws, Boolean, checks and preview in the
# one arena), its two-jaw plan likewise, and the Boolean of its base and the 31 tooth files as scanned (in occlusion:
# overlapping shells, two passes) file to file in 64 MiB; each result checked a valid solid.
#   usage: realdata_cli_test.sh SPLINTCORE SPLINTCORE_BENCH REALDATA_DIR
# shellcheck source=realdata_steps.sh
source "$(dirname "$0")/realdata_steps.sh"
step "export the real case" "$bench" --realdata "$real" --export-realcase "$work/rc"
step "design the real case in 64 MiB" "$tool" design "$work/rc/case.json" -o "$work/d" --memory-cap 64M
step "the splint written is a printable solid" "$tool" check "$work/d/splint.stl"
step "the preview was drawn in the same 64 MiB" test -s "$work/d/preview.png"
# Issue 32, the two-jaw plan (the exported plan.json: advancement, hinge axis, openings) in the
# same 64 MiB: both splints, their previews and the one 3MF job.
# The plan: the automatic outline, the maxilla 3 mm and the mandible 5 mm forward (-y), the
# hinge axis through the condyles, openings 2 mm (intermediate) and 1.5 mm (final).
cat >"$work/rc/plan.json" <<'PLAN'
{"splintcore_case": 1, "case_id": "realdata-patient26", "units": "mm", "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"}, {"role": "mandible", "mesh": "mandible.stl"}], "base": {"spacing_mm": 0.5, "auto": {}}, "printer": "eden260", "output": {"report": "report.json"}, "plan": {"sequence": "maxilla_first", "maxilla": [1, 0, 0, 0, 0, 1, 0, -3, 0, 0, 1, 0, 0, 0, 0, 1], "mandible": [1, 0, 0, 0, 0, 1, 0, -5, 0, 0, 1, 0, 0, 0, 0, 1], "hinge_axis": [[4, 90, 80], [104, 90, 80]], "intermediate_opening_mm": 2, "final_opening_mm": 1.5}}
PLAN
step "the real plan (both splints, previews, 3MF) in 64 MiB" "$tool" design "$work/rc/plan.json" \
  -o "$work/p" --memory-cap 64M
for k in intermediate final; do
  step "the $k splint is a printable solid" "$tool" check "$work/p/$k.stl"
  step "the $k preview was drawn in the same 64 MiB" test -s "$work/p/$k.png"
done
step "the 3MF job was written" test -s "$work/p/job.3mf"
step "the base of the real case" "$tool" base "$work/rc/case.json" -o "$work/base.stl"
step "base minus the 31 teeth as scanned, file to file in 64 MiB" "$tool" boolean --difference \
  "$work/base.stl" "$real"/maxilla/*.stl "$real"/mandible/*.stl -o "$work/cut.stl" --memory-cap 64M --json
grep -q '"passes":2' "$work/out" || { echo "FAILED: expected two passes (overlapping shells)"; failed=1; }
step "the cut base is a valid solid" "$tool" check "$work/cut.stl" --no-place
exit $failed
