#!/usr/bin/env bash
# Two-jaw surgery with intraoral scans on the command line (issue 30 with issue 32): the phantom
# jaws, each given a "scan" (its crowns and a band below them cut out of the jaw's STL, moved by
# a known rigid motion; written by Python's struct, no code shared with splintcore). `design`
# writes both splints, their previews and job.3mf (checked with Python's zipfile), and
# report.json gives the fusion of both jaws in each splint's section: the registration takes
# the known motion back (0.05 mm), with its RMS and overlap; the same bytes every run. A case
# that gives one jaw twice, each with a scan (two scans of the same jaw), is refused with the
# line named and nothing written.
#   usage: plan_scan_cli_test.sh PATH/TO/splintcore
set -u
tool=$1
command -v python3 >/dev/null 2>&1 || { echo "python3 not found: skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

# shellcheck source=cli_checks.sh
source "$(dirname "$0")/cli_checks.sh"

expect_exit 0 "phantom" -- "$tool" phantom --triangles 6000 -o "$work"

# Each jaw's scan: the triangles on the crowns' side (the maxilla's below z = 7, the mandible's
# above z = -5, as tests/design/fusion_test.cpp cuts them), moved by a rotation about z through
# the jaw's box centre and a translation; the motions (scan -> jaw, row-major 4 x 4) in
# truth.json.
python3 - "$work" <<'PY'
import json, math, struct, sys
work = sys.argv[1]

def read_stl(path):
    data = open(path, "rb").read()
    n = struct.unpack_from("<I", data, 80)[0]
    tris = []
    for i in range(n):
        v = struct.unpack_from("<12f", data, 84 + 50 * i)
        tris.append((v[3:6], v[6:9], v[9:12]))
    return tris

def write_stl(path, tris):
    out = bytearray(80) + struct.pack("<I", len(tris))
    for a, b, c in tris:
        out += struct.pack("<12fH", 0, 0, 0, *a, *b, *c, 0)
    open(path, "wb").write(out)

truth = {}
for name, keep, angle_deg, move in (("maxilla", lambda z: z < 7, -4.0, (-1.0, 1.5, -0.5)),
                                    ("mandible", lambda z: z > -5, 5.0, (1.5, -2.0, 0.8))):
    tris = read_stl(f"{work}/{name}.stl")
    xs = [p[0] for t in tris for p in t]
    ys = [p[1] for t in tris for p in t]
    cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    # jaw -> scan: x' = R (x - centre) + centre + move; the registration is its inverse.
    def to_scan(p):
        x, y = p[0] - cx, p[1] - cy
        return (c * x - s * y + cx + move[0], s * x + c * y + cy + move[1], p[2] + move[2])
    cut = [tuple(to_scan(p) for p in t) for t in tris if all(keep(p[2]) for p in t)]
    assert 500 < len(cut) < len(tris), (name, len(cut), len(tris))
    write_stl(f"{work}/{name}_scan.stl", cut)
    # scan -> jaw: x = R^T (x' - centre - move) + centre
    tx, ty = -(cx + move[0]), -(cy + move[1])
    truth[name] = {"r": [[c, s, 0], [-s, c, 0], [0, 0, 1]],
                   "t": [c * tx + s * ty + cx, -s * tx + c * ty + cy, -move[2]]}
json.dump(truth, open(f"{work}/truth.json", "w"))
PY
check "the scans were cut and moved" -- test -s "$work/mandible_scan.stl" -a -s "$work/maxilla_scan.stl"

cat >"$work/plan.json" <<'PLAN'
{"splintcore_case": 1, "case_id": "plan-scans-cli",
 "jaws": [{"role": "maxilla", "mesh": "maxilla.stl", "scan": {"path": "maxilla_scan.stl"}},
          {"role": "mandible", "mesh": "mandible.stl", "scan": {"path": "mandible_scan.stl"}}],
 "base": {"spacing_mm": 0.5, "auto": {}},
 "plan": {"sequence": "maxilla_first",
          "maxilla": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1],
          "mandible": [1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1],
          "hinge_axis": [[-50, -55, 25], [50, -55, 25]],
          "intermediate_opening_mm": 2, "final_opening_mm": 1.5}}
PLAN
expect_exit 0 "design a plan with scans" -- "$tool" design "$work/plan.json" -o "$work/out-plan"
check "the fusion printed for both jaws" -- sh -c "grep -q '^fusion (maxilla): scan .*maxilla_scan.stl registered' '$work/out' && grep -q '^fusion (mandible): scan .*mandible_scan.stl registered' '$work/out'"
check "the intermediate splint written" -- test -s "$work/out-plan/intermediate.stl"
check "the final splint written" -- test -s "$work/out-plan/final.stl"
check "a preview of each" -- test -s "$work/out-plan/intermediate.png" -a -s "$work/out-plan/final.png"
int_sha=$(sha256sum "$work/out-plan/intermediate.stl" | cut -d' ' -f1)
fin_sha=$(sha256sum "$work/out-plan/final.stl" | cut -d' ' -f1)
check "job.3mf: both splints on the Eden260 tray, 5 mm apart, the STLs' triangles (Python zipfile)" -- \
  python3 "$(dirname "$0")/check_3mf.py" "$work/out-plan/job.3mf" 2 255 252 5 "$int_sha" "$fin_sha" \
  --height 200 --stl "$work/out-plan/intermediate.stl" "$work/out-plan/final.stl"
expect_exit 0 "the intermediate splint is printable" -- "$tool" check "$work/out-plan/intermediate.stl"
expect_exit 0 "the final splint is printable" -- "$tool" check "$work/out-plan/final.stl"
# report.json: in each splint's section "fusion" holds both jaws, each with its scan's SHA-256,
# the registration (within 0.05 mm of the truth over the scan's box corners and 0.1 degree),
# its RMS, overlap and the transform as applied; the same registration in both sections.
check "report.json has the fusion of both jaws in both splints" -- python3 - "$work" <<'PY'
import hashlib, json, math, sys
work = sys.argv[1]
report = json.load(open(f"{work}/out-plan/report.json"))
truth = json.load(open(f"{work}/truth.json"))
corners = [(x, y, z) for x in (-40, 40) for y in (-50, 50) for z in (-10, 10)]
fits = []
for part in ("intermediate", "final"):
    fusion = report[part]["fusion"]
    assert [f["role"] for f in fusion] == ["maxilla", "mandible"], fusion
    for f in fusion:
        want = truth[f["role"]]
        scan = f"{work}/{f['role']}_scan.stl"
        assert f["scan"].endswith(f"{f['role']}_scan.stl"), f["scan"]
        assert f["scan_sha256"] == hashlib.sha256(open(scan, "rb").read()).hexdigest()
        assert f["scan_triangles"] > 500 and f["start"] == "automatic"
        assert 0 <= f["rms_mm"] < 0.05 and 0.9 < f["overlap"] <= 1, f
        assert f["imprint"] == "scan triangles" and len(f["applied_transform"]) == 16
        m = f["transform"]
        assert m[12:] == [0, 0, 0, 1], m
        worst = 0
        for p in corners:
            got = [sum(m[4 * i + k] * p[k] for k in range(3)) + m[4 * i + 3] for i in range(3)]
            exp = [sum(want["r"][i][k] * p[k] for k in range(3)) + want["t"][i] for i in range(3)]
            worst = max(worst, math.dist(got, exp))
        trace = sum(m[4 * i + k] * want["r"][i][k] for i in range(3) for k in range(3))
        degrees = math.degrees(math.acos(max(-1.0, min(1.0, (trace - 1) / 2))))
        assert worst < 0.05 and degrees < 0.1, (f["role"], worst, degrees)
        fits.append((f["role"], m, f["rms_mm"], f["overlap"]))
assert fits[:2] == fits[2:], "both splints hold the fusion made once"
PY
check "the report's stages include the plan's fusion" -- grep -q '"stage":"plan: fusion"\|"stage":"fusion"' "$work/out-plan/report.json"
cp "$work/out-plan/intermediate.stl" "$work/intermediate.first"
cp "$work/out-plan/job.3mf" "$work/job.first"
expect_exit 0 "design the plan with scans again, 2 threads" -- "$tool" design "$work/plan.json" -o "$work/out-plan" --threads 2
check "the same bytes every run and at any thread count" -- sh -c "cmp -s '$work/out-plan/intermediate.stl' '$work/intermediate.first' && cmp -s '$work/out-plan/job.3mf' '$work/job.first'"

# Two scans of the same jaw: the mandible given twice, each time with a scan.
python3 - "$work/plan.json" "$work/twice.json" <<'PY'
import json, sys
case = json.load(open(sys.argv[1]))
case["jaws"].append({"role": "mandible", "mesh": "mandible.stl", "scan": {"path": "maxilla_scan.stl"}})
json.dump(case, open(sys.argv[2], "w"), indent=1)
PY
expect_exit 1 "a plan with two scans of the mandible" -- "$tool" design "$work/twice.json" -o "$work/out-twice"
check "the refusal names the place and the cause" -- grep -q 'twice.json:[0-9]*:[0-9]*: .*two scans of the mandible' "$work/err"
check "nothing written for two scans of one jaw" -- test ! -e "$work/out-twice/intermediate.stl"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
