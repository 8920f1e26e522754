#!/usr/bin/env bash
# The splintcore program: exit codes, --help, --json, --memory-cap, atomic output.
# usage: cli_test.sh PATH/TO/splintcore FIXTURES_DIR
set -u
tool=$1
fixtures=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

# shellcheck source=cli_checks.sh
source "$(dirname "$0")/cli_checks.sh"

# json_ok FILE: the file holds exactly one JSON object. Without python3 the file's one line is
# checked to be {...} at once; with it, a copy is kept and every copy is parsed by one python3
# at the end (json_ok_all), each counted as its own check: one interpreter start, not 25.
json_count=0
mkdir -p "$work/json-checks"
json_ok() {
  if command -v python3 >/dev/null 2>&1; then
    json_count=$((json_count + 1))
    cp "$1" "$work/json-checks/$json_count.json" && echo "$1" >>"$work/json-checks/names"
  else
    grep -q '^{.*}$' "$1"
  fi
}
json_ok_all() {  # the deferred checks (each counted as passed by `check`): a failure names the
  # file, the check's number and the error, and moves that check from passed to failed
  [ "$json_count" -gt 0 ] || return 0
  local bad
  bad=$(python3 - "$work/json-checks" "$json_count" <<'PY'
import json, sys
for i in range(1, int(sys.argv[2]) + 1):
    try:
        with open(f"{sys.argv[1]}/{i}.json") as f:
            d = json.load(f)
        if not isinstance(d, dict):
            print(f"json check {i}: not an object")
    except Exception as e:  # noqa: BLE001 (any failure to parse is the finding)
        print(f"json check {i}: {e}")
PY
  )
  local n_bad
  n_bad=$(printf '%s' "$bad" | grep -c "^json check")
  failed=$((failed + n_bad))
  passed=$((passed - n_bad))
  [ -z "$bad" ] || { printf '%s\n' "$bad" | sed 's/^/FAIL: /'; echo "files, by check number:"; cat -n "$work/json-checks/names"; }
}

sha256() {  # the SHA-256 of a file, hex
  if command -v sha256sum >/dev/null 2>&1; then
    sha256sum "$1" | cut -d' ' -f1
  else
    shasum -a 256 "$1" | cut -d' ' -f1
  fi
}

has_sha256() {  # has_sha256 FILE HASH: the file exists and HASH (not empty) is its SHA-256
  [ -n "$2" ] && [ -f "$1" ] && [ "$(sha256 "$1")" = "$2" ]
}

expect_exit 0 "help" -- "$tool" --help
expect_exit 2 "no command" -- "$tool"
expect_exit 2 "unknown command" -- "$tool" frobnicate
expect_exit 0 "check --help" -- "$tool" check --help
check "check --help mentions --memory-cap" -- grep -q -- "--memory-cap" "$work/out"
expect_exit 2 "check without input" -- "$tool" check
expect_exit 2 "bad memory cap" -- "$tool" check "$fixtures/stl/torus_binary.stl" --memory-cap 12Q
expect_exit 2 "bad threads" -- "$tool" check "$fixtures/stl/torus_binary.stl" --threads 0
expect_exit 2 "unknown printer" -- "$tool" check "$fixtures/stl/torus_binary.stl" --printer nope
expect_exit 2 "unknown option" -- "$tool" convert "$fixtures/stl/torus_binary.stl" --frob
expect_exit 2 "convert without -o" -- "$tool" convert "$fixtures/stl/torus_binary.stl"
# One option parser (issue 27): a command takes its own options and those of every command;
# another command's option is unknown, a missing value is named, and a usage error shows the
# command's options as --help does.
expect_exit 2 "another command's option" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/x.stl" --query 1,2,3
check "it is named unknown" -- grep -q "^splintcore: unknown option '--query'$" "$work/err"
check "the usage error lists the command's options" -- grep -q "^  --ascii  *write ASCII STL" "$work/err"
check "nothing written after a usage error" -- test ! -e "$work/x.stl"
expect_exit 2 "a missing value" -- "$tool" check "$fixtures/stl/torus_binary.stl" --printer
check "the missing value is named" -- grep -q "^splintcore: --printer needs a name$" "$work/err"
expect_exit 0 "--output is -o" -- "$tool" convert "$fixtures/stl/torus_binary.stl" --output "$work/x.stl"
check "--output wrote the file" -- test -s "$work/x.stl"
expect_exit 0 "check -h" -- "$tool" check -h
check "check --help lists its options" -- grep -q "^  --no-place  " "$work/out"

expect_exit 0 "check printable torus" -- "$tool" check "$fixtures/stl/torus_binary.stl"
check "human summary says printable" -- grep -q "printable: yes" "$work/out"
expect_exit 0 "check --json" -- "$tool" check "$fixtures/stl/torus_binary.stl" --json --threads 2
check "check --json is one JSON object" -- json_ok "$work/out"
check "check --json has the genus" -- grep -q '"genus":1' "$work/out"
check "check --json has peak arena" -- grep -q '"peak_arena_bytes":' "$work/out"
expect_exit 0 "check binary file with solid header" -- "$tool" check "$fixtures/stl/box_solid_header.stl"
expect_exit 0 "check ascii tetra" -- "$tool" check "$fixtures/stl/tetra_ascii.stl"
expect_exit 1 "check open box" -- "$tool" check "$fixtures/stl/open_box_ascii.stl"
check "open box message names the boundary" -- grep -q "not closed" "$work/err"
check "an open mesh says so, with its loops" -- grep -q "^closed: no ([0-9]* boundary edges in 1 loop)" "$work/out"
check "an open mesh has no outward side" -- grep -q "^outward: n/a (open)" "$work/out"
check "an open mesh has no volume" -- grep -q "volume: n/a (open)" "$work/out"
check "an open mesh has no genus" -- grep -q "genus n/a (open)" "$work/out"
expect_exit 1 "check inside-out box" -- "$tool" check "$fixtures/stl/inside_out_box.stl" --json
check "inside-out json status" -- grep -q '"status":"invalid_mesh"' "$work/out"
expect_exit 1 "check too large box" -- "$tool" check "$fixtures/stl/too_large_box.stl"
check "too large message" -- grep -q "does not fit" "$work/err"
expect_exit 1 "check missing file" -- "$tool" check "$work/nope.stl"

# Truncated input: rejected with the byte offset; nothing written.
head -c 1000 "$fixtures/stl/torus_binary.stl" > "$work/cut.stl"
expect_exit 1 "convert truncated" -- "$tool" convert "$work/cut.stl" -o "$work/never.stl" --json
check "truncated json names the byte" -- grep -q '"byte_offset":' "$work/out"
check "no output after failure" -- test ! -e "$work/never.stl"

# Convert, determinism across runs and thread counts, ASCII round trip.
expect_exit 0 "convert" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/a.stl"
expect_exit 0 "convert again, 2 threads" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/b.stl" --threads 2
check "same bytes" -- cmp -s "$work/a.stl" "$work/b.stl"
expect_exit 0 "convert to ascii" -- "$tool" convert "$work/a.stl" -o "$work/a_ascii.stl" --ascii
expect_exit 0 "convert ascii back" -- "$tool" convert "$work/a_ascii.stl" -o "$work/c.stl"
check "ascii round trip is exact" -- cmp -s "$work/a.stl" "$work/c.stl"

# Memory cap too small: clean error naming the need; an existing output is left untouched.
cp "$work/a.stl" "$work/keep.stl"
expect_exit 1 "convert under a 4K cap" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/keep.stl" --memory-cap 4K
check "cap message" -- grep -q "arena exhausted: need" "$work/err"
check "existing output untouched" -- cmp -s "$work/a.stl" "$work/keep.stl"
check "no temporary files left" -- test -z "$(ls "$work" | grep '\.tmp-')"
expect_exit 1 "unwritable output folder" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/no/such/dir/x.stl"
# A full disk, as the file size limit makes one (ulimit -f: 1024-byte blocks): the program
# is not killed (SIGXFSZ), the write fails with the system's cause, the existing output stays
# as it was and no temporary file is left. (A coverage build's profile goes to /dev/null
# there, which no file size limit cuts short, not into the job's merged profiles.)
expect_exit 1 "convert past ulimit -f 64" -- bash -c 'ulimit -f 64 && LLVM_PROFILE_FILE=/dev/null exec "$@"' limited "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/keep.stl"
check "the write's cause named" -- grep -q "keep.stl: byte [0-9]*: write failed: File too large" "$work/err"
check "existing output untouched by the failed write" -- cmp -s "$work/a.stl" "$work/keep.stl"
check "no temporary files left by the failed write" -- test -z "$(find "$work" -maxdepth 1 -name '*.tmp-*')"
# A pipe as the output (a FIFO here; /dev/stdout is one too): written in place, not renamed
# over (which would leave a regular file where the pipe was). The reader gives up after 60 s.
mkfifo "$work/pipe.stl"
timeout 60 cat "$work/pipe.stl" >"$work/piped.stl" &
reader=$!
expect_exit 0 "convert into a pipe" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o "$work/pipe.stl"
wait "$reader"
check "the pipe carried the same bytes" -- cmp -s "$work/a.stl" "$work/piped.stl"
check "the pipe is still a pipe" -- test -p "$work/pipe.stl"
# "-o -" is refused (it would have made a file named "-"), as is an empty name.
expect_exit 2 "convert -o -" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o -
check "-o - refused with why" -- grep -q 'needs a file name (not "-": the summary goes to the standard output)' "$work/err"
check "no file named -" -- test ! -e ./-
expect_exit 2 "convert -o ''" -- "$tool" convert "$fixtures/stl/torus_binary.stl" -o ""
# "-" as an input is the standard input (a pipe here, then a redirected file): the same mesh
# and bytes; given twice it is refused, naming why. A procfs file (size 0 to stat, bytes when
# read) is read as a stream: its text is no mesh, and the error is not "0 bytes".
expect_exit 0 "convert from a pipe" -- bash -c 'cat "$1" | exec "$2" convert - -o "$3"' piped "$fixtures/stl/torus_binary.stl" "$tool" "$work/from_pipe.stl"
check "the pipe's mesh has the same bytes" -- cmp -s "$work/a.stl" "$work/from_pipe.stl"
expect_exit 0 "check from standard input" -- bash -c 'exec "$2" check - --json <"$1"' redirected "$fixtures/stl/torus_binary.stl" "$tool"
check "the standard input's mesh checked" -- grep -q '"closed":true' "$work/out"
expect_exit 1 "boolean with - twice" -- bash -c 'exec "$2" boolean --difference - - -o "$3" <"$1"' twice "$fixtures/stl/torus_binary.stl" "$tool" "$work/never.stl"
check "- twice named" -- grep -q 'standard input ("-") given for more than one input' "$work/err"
check "nothing written for - twice" -- test ! -e "$work/never.stl"
expect_exit 1 "check - with the standard input closed" -- bash -c 'exec "$@" <&-' closed_in "$tool" check -
check "the closed standard input named" -- grep -q "(standard input): cannot read: Bad file descriptor" "$work/err"
if [ -r /proc/self/status ]; then
  expect_exit 1 "check a procfs file" -- "$tool" check /proc/self/status
  check "a procfs file is read, not taken as empty" -- bash -c '! grep -q "0 bytes" "$1"' grep0 "$work/err"
fi
# The output's name picks its format: .ply is binary PLY (read back: the same mesh, checked);
# a name of another mesh format is refused before any work, as is --ascii with .ply and a PLY
# where the output is streamed as STL (sweep).
expect_exit 0 "convert to PLY" -- "$tool" convert "$work/a.stl" -o "$work/a.ply"
check "the summary says PLY" -- grep -q "output: .*a.ply (binary PLY)" "$work/out"
check "a PLY header" -- bash -c 'head -c 64 "$1" | grep -q "^format binary_little_endian 1.0"' ply "$work/a.ply"
expect_exit 0 "convert the PLY back" -- "$tool" convert "$work/a.ply" -o "$work/from_ply.stl"
check "STL -> PLY -> STL is exact" -- cmp -s "$work/a.stl" "$work/from_ply.stl"
for other in obj 3mf OFF; do
  expect_exit 1 "convert to .$other" -- "$tool" convert "$work/a.stl" -o "$work/never.$other"
  check ".$other refused, the formats named" -- grep -q "never.$other: cannot write a mesh as .$(printf %s "$other" | tr A-Z a-z): splintcore writes meshes as STL (.stl, or any other name) or binary PLY (.ply)" "$work/err"
  check "nothing written as .$other" -- test ! -e "$work/never.$other"
done
expect_exit 1 "convert to an ASCII PLY" -- "$tool" convert "$work/a.stl" -o "$work/never.ply" --ascii
check "--ascii with .ply named" -- grep -q "never.ply: PLY is written binary only" "$work/err"
expect_exit 1 "sweep to a PLY" -- "$tool" sweep "$work/a.stl" -o "$work/never.ply" --direction 0,0,1 --voxel 1
check "sweep's PLY refused" -- grep -q "never.ply: this output is streamed as STL" "$work/err"
check "no PLY left" -- test ! -e "$work/never.ply"
# What a command prints must reach its standard output: a closed one or a full disk
# (/dev/full, where there is one) fails the run, so --json is never taken cut off.
expect_exit 1 "check with its standard output closed" -- bash -c 'exec "$@" >&-' closed "$tool" check "$fixtures/stl/torus_binary.stl" --json
check "the closed output named" -- grep -q "cannot write the standard output: Bad file descriptor" "$work/err"
if [ -c /dev/full ]; then
  expect_exit 1 "check --json into a full disk" -- bash -c 'exec "$@" >/dev/full' full "$tool" check "$fixtures/stl/torus_binary.stl" --json
  check "the full disk named" -- grep -q "cannot write the standard output: No space left on device" "$work/err"
fi

# The initial splint base from a case file.
expect_exit 0 "base --help" -- "$tool" base --help
expect_exit 2 "base without -o" -- "$tool" base "$fixtures/cases/paper_scale.json"
expect_exit 0 "base paper scale" -- "$tool" base "$fixtures/cases/paper_scale.json" -o "$work/base.stl" --json
check "base json is one object" -- json_ok "$work/out"
check "base json has 2612 triangles" -- grep -q '"triangles":2612' "$work/out"
expect_exit 0 "check the written base" -- "$tool" check "$work/base.stl"
printf '{"splintcore_case": 1,\n  "base": {"upper": [], "lower": [], "frob": 1}}\n' > "$work/bad.json"
expect_exit 1 "base with an unknown key" -- "$tool" base "$work/bad.json" -o "$work/bad.stl"
check "unknown key message has line:column" -- grep -q "bad.json:2:.*unknown key \"frob\"" "$work/err"
check "no output after a bad case" -- test ! -e "$work/bad.stl"
# What an error quotes from an input reaches the terminal inert: an unknown key holding an
# escape sequence (clear the screen) is written out as \x1b, never as the byte itself.
printf '{"splintcore_case": 1,\n  "base": {"upper": [], "lower": [], "\\u001b[2Jx": 1}}\n' > "$work/esc.json"
expect_exit 1 "base with an escape sequence in a key" -- "$tool" base "$work/esc.json" -o "$work/esc.stl"
check "the key quoted with its escape written out" -- grep -qF 'unknown key "\x1b[2Jx"' "$work/err"
check "no escape byte reaches the terminal" -- test "$(tr -d -c '\033' <"$work/err" | wc -c)" -eq 0
printf '{"splintcore_case": 1, "base": {"upper": [{"position": [0,0,1]}, {"position": [0,0,1]}],\n "lower": [{"position": [0,0,0]}, {"position": [5,0,0]}]}}\n' > "$work/dup.json"
expect_exit 1 "base with a repeated pick" -- "$tool" base "$work/dup.json" -o "$work/dup.stl"
check "repeated pick named" -- grep -q "upper pick 1: same position" "$work/err"

# Distance queries.
expect_exit 2 "distance without a query" -- "$tool" distance "$fixtures/stl/box_solid_header.stl"
expect_exit 2 "distance with a bad query" -- "$tool" distance "$fixtures/stl/box_solid_header.stl" --query 1,2
expect_exit 2 "distance with a bad sign method" -- "$tool" distance "$fixtures/stl/box_solid_header.stl" --query 1,2,3 --sign maybe
expect_exit 0 "distance inside the box" -- "$tool" distance "$fixtures/stl/box_solid_header.stl" --query 16,12,8 --query 40,12,8 --json
check "distance json is one object" -- json_ok "$work/out"
check "centre is 5 mm inside" -- grep -q '"signed_distance":-5' "$work/out"
check "outside point is 9 mm out" -- grep -q '"signed_distance":9' "$work/out"
expect_exit 0 "distance by winding number" -- "$tool" distance "$fixtures/stl/torus_binary.stl" --query 20,0,0 --sign winding
check "winding method reported" -- grep -q "(winding)" "$work/out"
expect_exit 1 "distance on a missing file" -- "$tool" distance "$work/none.stl" --query 0,0,0

# Phantom jaws and the Boolean: base minus maxilla, written atomically and checked again.
expect_exit 2 "phantom without -o" -- "$tool" phantom --triangles 4000
expect_exit 2 "phantom with too few triangles" -- "$tool" phantom --triangles 10 -o "$work"
expect_exit 0 "phantom" -- "$tool" phantom --triangles 6000 -o "$work" --json
check "phantom json is one object" -- json_ok "$work/out"
check "phantom wrote the maxilla" -- test -s "$work/maxilla.stl"
check "phantom wrote the mandible" -- test -s "$work/mandible.stl"
cp "$work/maxilla.stl" "$work/maxilla.first"
expect_exit 0 "phantom again" -- "$tool" phantom --triangles 6000 -o "$work"
check "phantom bytes are the same every run" -- cmp -s "$work/maxilla.stl" "$work/maxilla.first"
check "phantom names its jaws and its case" -- test "$(grep -c -E '^(maxilla|mandible): |^case: ' "$work/out")" -eq 3
# Its files are placed together and named only then: a folder in the case's place leaves no jaw
# and prints no jaw line.
mkdir -p "$work/phantom-blocked/case.json/x"
expect_exit 1 "phantom with a folder in the case's place" -- "$tool" phantom --triangles 2000 -o "$work/phantom-blocked"
check "phantom placed no jaw" -- test ! -e "$work/phantom-blocked/maxilla.stl"
check "phantom printed no jaw line" -- test ! -s "$work/out"

# Hinge-axis autorotation (issue 32) of the phantom's mandible (in occlusion: opened, then closed
# to 2 mm), the turned mandible written atomically; the same bytes every run.
hinge=-50,-55,25,50,-55,25
expect_exit 2 "autorotate with one mesh" -- "$tool" autorotate "$work/maxilla.stl" --hinge $hinge --opening 2
expect_exit 2 "autorotate without --hinge" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --opening 2
expect_exit 2 "autorotate with a short --hinge" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --hinge 1,2,3,4,5 --opening 2
expect_exit 2 "autorotate without --opening" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --hinge $hinge
expect_exit 1 "autorotate with an opening over 10 mm" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --hinge $hinge --opening 11
check "the opening's range is named" -- grep -q "opening must be in \[0, 10\]" "$work/err"
expect_exit 1 "autorotate about a vertical axis" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --hinge 0,0,-50,0,0,50 --opening 2
check "the closing sense is named" -- grep -q "closing sense cannot be told" "$work/err"
expect_exit 0 "autorotate" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --hinge $hinge --opening 2 -o "$work/turned.stl" --json
check "autorotate json is one object" -- json_ok "$work/out"
check "autorotate reports the opening" -- grep -q '"opening_mm":2.00000000' "$work/out"
check "autorotate reports the 4x4" -- grep -q '"transform":\[[^]]*,0,0,0,1\]' "$work/out"
check "autorotate wrote the turned mandible" -- test -s "$work/turned.stl"
cp "$work/turned.stl" "$work/turned.first"
expect_exit 0 "autorotate again, text" -- "$tool" autorotate "$work/maxilla.stl" "$work/mandible.stl" --hinge $hinge --opening 2 -o "$work/turned.stl"
check "autorotate prints the angle in degrees" -- grep -q "^angle: .* rad (.* degrees)" "$work/out"
check "autorotate bytes are the same every run" -- cmp -s "$work/turned.stl" "$work/turned.first"

# Scan-CT registration (issue 30): the turned mandible placed back onto the mandible (from the
# scan as given), written atomically; the same bytes at any --threads; a wrong landmark pairing
# rejected with nothing written.
expect_exit 2 "register with one mesh" -- "$tool" register "$work/turned.stl" -o "$work/reg.json"
expect_exit 2 "register without -o" -- "$tool" register "$work/turned.stl" "$work/mandible.stl"
expect_exit 2 "register with a short landmark pair" -- "$tool" register "$work/turned.stl" "$work/mandible.stl" -o "$work/reg.json" --landmarks "1 2 3 4 5"
expect_exit 2 "register with an overlap over 1" -- "$tool" register "$work/turned.stl" "$work/mandible.stl" -o "$work/reg.json" --overlap 1.5
expect_exit 0 "register" -- "$tool" register "$work/turned.stl" "$work/mandible.stl" -o "$work/reg.json" --moved "$work/back.stl" --json
check "register json is one object" -- json_ok "$work/out"
check "register wrote its JSON" -- json_ok "$work/reg.json"
check "register reports the 4x4" -- grep -q '"transform":\[[^]]*,0,0,0,1\]' "$work/reg.json"
check "register reports a small RMS" -- python3 -c "import json, sys; sys.exit(json.load(open(sys.argv[1]))['rms_mm'] > 0.01)" "$work/reg.json"
check "register wrote the moved scan" -- test -s "$work/back.stl"
check "register reports how the scan faces the CT" -- grep -q '"facing":1,' "$work/reg.json"
expect_exit 2 "register with a zero --toward" -- "$tool" register "$work/turned.stl" "$work/mandible.stl" -o "$work/reg2.json" --toward 0,0,0
expect_exit 0 "register --toward the maxilla" -- "$tool" register "$work/turned.stl" "$work/mandible.stl" -o "$work/reg2.json" --toward 0,0,1
check "register --toward prints the facing" -- grep -q "^facing the CT: 1.0000 of the matched area" "$work/out"
cp "$work/reg.json" "$work/reg.first"
expect_exit 0 "register at 2 threads" -- "$tool" register "$work/turned.stl" "$work/mandible.stl" -o "$work/reg.json" --threads 2
check "register bytes are the same at any thread count" -- cmp -s "$work/reg.json" "$work/reg.first"
expect_exit 1 "register with a wrong landmark pairing" -- "$tool" register "$work/mandible.stl" "$work/mandible.stl" -o "$work/wrong.json" --landmarks "0 0 0 0 0 0; 10 0 0 0 10 0; 0 10 0 10 0 0"
check "the wrong pairing is named" -- grep -q "landmarks .* mm RMS apart" "$work/err"
check "nothing written for a rejected fit" -- test ! -e "$work/wrong.json"

# Two-jaw surgery (issue 32): a plan case on the phantom writes both splints, a preview of each
# and one report with the plan and both splints; the same bytes every run; a plan case cannot
# also give a jaw transform (line and column named).
cat > "$work/plan.json" <<'PLAN'
{"splintcore_case": 1, "case_id": "plan-cli",
 "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"}, {"role": "mandible", "mesh": "mandible.stl"}],
 "base": {"spacing_mm": 0.5, "auto": {}},
 "plan": {"sequence": "maxilla_first",
          "maxilla": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1],
          "mandible": [1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1],
          "hinge_axis": [[-50, -55, 25], [50, -55, 25]],
          "intermediate_opening_mm": 2, "final_opening_mm": 1.5}}
PLAN
expect_exit 0 "design a plan" -- "$tool" design "$work/plan.json" -o "$work/plan-out"
check "plan wrote the intermediate splint" -- test -s "$work/plan-out/intermediate.stl"
check "plan wrote the final splint" -- test -s "$work/plan-out/final.stl"
check "plan wrote no single splint" -- test ! -e "$work/plan-out/splint.stl"
check "plan wrote a preview of each" -- test -s "$work/plan-out/intermediate.png" -a -s "$work/plan-out/final.png"
int_sha=$(sha256sum "$work/plan-out/intermediate.stl" | cut -d' ' -f1)
fin_sha=$(sha256sum "$work/plan-out/final.stl" | cut -d' ' -f1)
check "plan wrote one print job: both splints on the Eden260 tray, 5 mm apart (Python zipfile)" -- \
  python3 "$(dirname "$0")/check_3mf.py" "$work/plan-out/job.3mf" 2 255 252 5 "$int_sha" "$fin_sha" \
  --height 200 --stl "$work/plan-out/intermediate.stl" "$work/plan-out/final.stl"
check "plan report is one object" -- json_ok "$work/plan-out/report.json"
job_sha=$(sha256sum "$work/plan-out/job.3mf" | cut -d' ' -f1)
check "plan report names the print job and its SHA-256" -- grep -q "\"print_job\":{\"path\":\"[^\"]*job.3mf\",\"sha256\":\"$job_sha\"}" "$work/plan-out/report.json"
check "plan report has the plan and both splints" -- grep -q '"plan":{"sequence":"maxilla_first".*"intermediate":{.*"autorotation":{"angle_rad":.*"final":{' "$work/plan-out/report.json"
check "the splints differ" -- sh -c "! cmp -s '$work/plan-out/intermediate.stl' '$work/plan-out/final.stl'"
check "plan printed both splints" -- grep -q "^final: mandible turned .* deg" "$work/out"
expect_exit 0 "the plan's intermediate splint is printable" -- "$tool" check "$work/plan-out/intermediate.stl"
cp "$work/plan-out/intermediate.stl" "$work/intermediate.first"
cp "$work/plan-out/final.stl" "$work/final.first"
expect_exit 0 "design a plan again, 2 threads" -- "$tool" design "$work/plan.json" -o "$work/plan-out" --json --threads 2
check "plan bytes are the same every run and at 2 threads (the STLs written in two tasks)" -- sh -c "cmp -s '$work/plan-out/intermediate.stl' '$work/intermediate.first' && cmp -s '$work/plan-out/final.stl' '$work/final.first'"
sed 's/"mesh": "mandible.stl"}/"mesh": "mandible.stl", "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}/' "$work/plan.json" > "$work/plan-bad.json"
expect_exit 1 "a plan with a jaw transform" -- "$tool" design "$work/plan-bad.json" -o "$work/plan-bad"
check "the refusal names the line and column" -- grep -q "plan-bad.json:2:[0-9]*: .*both move it" "$work/err"
expect_exit 1 "outline of a plan case" -- "$tool" outline "$work/plan.json" -o "$work/plan-resolved.json"
# The plan fixture (fixtures/cases/plan.json: each splint labelled, INT P1 and FIN P1): both
# splints and the print job have the golden bytes (pinned by tests/design/design_golden_test.cpp
# from the library), and the job holds the STLs' triangles and volumes, apart on the tray.
cp "$fixtures/cases/plan.json" "$work/plan-fixture.json"
expect_exit 0 "design the plan fixture" -- "$tool" design "$work/plan-fixture.json" -o "$work/plan-fixture"
for part in intermediate final; do
  check "the plan fixture's $part splint has the golden bytes" -- has_sha256 "$work/plan-fixture/$part.stl" "$(grep " design:plan-$part-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)"
done
check "the plan fixture's job.3mf has the golden bytes" -- has_sha256 "$work/plan-fixture/job.3mf" "$(grep " design:plan-job3mf-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)"
check "the plan fixture's job: the STLs' triangles and volumes, on the tray 5 mm apart (Python)" -- \
  python3 "$(dirname "$0")/check_3mf.py" "$work/plan-fixture/job.3mf" 2 255 252 5 \
  --height 200 --stl "$work/plan-fixture/intermediate.stl" "$work/plan-fixture/final.stl"
check "the plan fixture's report names each splint's label" -- grep -q '"intermediate":{.*"label_text":"INT P1".*"final":{.*"label_text":"FIN P1"' "$work/plan-fixture/report.json"
# The same plan with each splint's own picks (the plan's "picks"): the paper-scale picks for
# the intermediate splint, the same picks moved with the jaws (the upper by the maxilla's move,
# the lower by the mandible's) for the final one.
python3 - "$fixtures/cases/plan.json" "$fixtures/cases/paper_scale.json" "$work/plan-picks.json" <<'PY'
import json, sys
plan, paper = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
def moved(picks, m):
    out = []
    for p in picks:
        x, y, z = p["position"]
        q = dict(p)
        q["position"] = [m[4 * i] * x + m[4 * i + 1] * y + m[4 * i + 2] * z + m[4 * i + 3] for i in range(3)]
        out.append(q)
    return out
plan["base"] = {"spacing_mm": 0.5, "occlusal_normal": paper["base"]["occlusal_normal"]}
up, low = paper["base"]["upper"], paper["base"]["lower"]
plan["plan"]["picks"] = {"intermediate": {"upper": up, "lower": low},
                         "final": {"upper": moved(up, plan["plan"]["maxilla"]),
                                   "lower": moved(low, plan["plan"]["mandible"])}}
json.dump(plan, open(sys.argv[3], "w"), indent=1)
plan["base"]["upper"], plan["base"]["lower"] = up, low  # two sources of picks: refused
json.dump(plan, open(sys.argv[3].replace(".json", "-both.json"), "w"), indent=1)
PY
expect_exit 0 "design a plan whose splints have their own picks" -- "$tool" design "$work/plan-picks.json" -o "$work/plan-picks"
expect_exit 0 "its final splint is printable" -- "$tool" check "$work/plan-picks/final.stl"
check "its report gives each splint's picks" -- grep -q '"plan":{.*"picks":{"intermediate":{"upper":\[.*"final":{"upper":\[' "$work/plan-picks/report.json"
expect_exit 1 "a plan with its own picks and the base's too" -- "$tool" design "$work/plan-picks-both.json" -o "$work/plan-both"
check "the base's picks are named" -- grep -q 'leave "upper" out of "base"' "$work/err"

expect_exit 0 "base for the Boolean" -- "$tool" base "$fixtures/cases/paper_scale.json" -o "$work/base.stl"
expect_exit 2 "boolean without an operation" -- "$tool" boolean "$work/base.stl" "$work/maxilla.stl" -o "$work/cut.stl"
expect_exit 2 "boolean with two operations" -- "$tool" boolean --union --difference "$work/base.stl" "$work/maxilla.stl" -o "$work/cut.stl"
expect_exit 2 "boolean with one input" -- "$tool" boolean --difference "$work/base.stl" -o "$work/cut.stl"
expect_exit 2 "boolean without -o" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl"
expect_exit 2 "boolean with a bad translation" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" -o "$work/cut.stl" --translate-b 1,2
expect_exit 0 "boolean difference" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" -o "$work/cut.stl" --json
check "boolean json is one object" -- json_ok "$work/out"
check "boolean reports a valid solid" -- grep -q '"valid_solid":true' "$work/out"
check "boolean cut crowns" -- grep -q '"intersecting_pairs":[1-9]' "$work/out"
check "boolean reads B cropped to A's box (fewer triangles kept than the file's)" -- python3 -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if 0 < d['b_triangles_kept'] < d['b_triangles'] // 2 else 1)" "$work/out"
expect_exit 0 "the written difference is a printable solid" -- "$tool" check "$work/cut.stl"
cp "$work/cut.stl" "$work/cut.first"
expect_exit 0 "boolean again, two threads" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" -o "$work/cut.stl" --threads 2
check "boolean bytes are the same every run" -- cmp -s "$work/cut.stl" "$work/cut.first"
expect_exit 0 "boolean with both jaws in occlusion (overlapping shells: two passes)" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" "$work/mandible.stl" -o "$work/both.stl" --json
check "overlapping shells grouped" -- grep -q '"shell_groups":2,"passes":2' "$work/out"
expect_exit 0 "the splint cut by overlapping jaws is a printable solid" -- "$tool" check "$work/both.stl"
rm -f "$work/both.stl"
expect_exit 2 "boolean with a translation per file, miscounted" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" "$work/mandible.stl" -o "$work/both.stl" --translate-b 0,0,0 --translate-b 0,0,-2 --translate-b 0,0,0
expect_exit 0 "boolean with both jaws, the mandible opened" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" "$work/mandible.stl" -o "$work/both.stl" --translate-b 0,0,0 --translate-b 0,0,-2
expect_exit 0 "the written splint is a printable solid" -- "$tool" check "$work/both.stl"
# B made of three files, the third far away: it is read, joined and dropped as far from A;
# the splint is the same bytes as from the two files.
expect_exit 0 "boolean with a third B file far away" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" "$work/mandible.stl" "$work/maxilla.stl" -o "$work/both3.stl" --translate-b 0,0,0 --translate-b 0,0,-2 --translate-b 500,0,0
check "a far B file changes no byte" -- cmp -s "$work/both.stl" "$work/both3.stl"
expect_exit 0 "boolean intersection" -- "$tool" boolean --intersection "$work/base.stl" "$work/maxilla.stl" -o "$work/inter.stl"
expect_exit 0 "boolean union (B is read whole: everywhere matters)" -- "$tool" boolean --union "$work/base.stl" "$work/maxilla.stl" -o "$work/union.stl" --json
check "the union keeps every B triangle" -- python3 -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d['b_triangles_kept'] == d['b_triangles'] > 0 else 1)" "$work/out"
expect_exit 0 "the written intersection is a solid" -- "$tool" check "$work/inter.stl" --no-place
expect_exit 1 "boolean with an open A" -- "$tool" boolean --difference "$fixtures/stl/open_box_ascii.stl" "$work/maxilla.stl" -o "$work/open.stl"
check "open A named" -- grep -q "A must be a solid" "$work/err"
check "no output after an open A" -- test ! -e "$work/open.stl"
expect_exit 1 "boolean under a tiny memory cap" -- "$tool" boolean --difference "$work/base.stl" "$work/maxilla.stl" -o "$work/small.stl" --memory-cap 300K
check "tiny cap says arena exhausted" -- grep -qi "arena exhausted" "$work/err"
check "no output after exhaustion" -- test ! -e "$work/small.stl"
# A of two closed boxes that overlap (each a solid: their faces cross), B far away: the
# result is A, which self-intersects; the check refuses it at one thread and at two (where
# the file is written beside the check): exit 1, nothing left in the directory.
mkdir -p "$work/si"
python3 - "$work/si/a.stl" "$work/si/b.stl" <<'PY'
import sys
def box(lo, hi):
    x = (lo[0], hi[0]); y = (lo[1], hi[1]); z = (lo[2], hi[2])
    c = [(x[i & 1], y[(i >> 1) & 1], z[i >> 2]) for i in range(8)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for a, b, e, d in quads:
        tris += [(c[a], c[b], c[e]), (c[a], c[e], c[d])]
    return tris
def write(path, tris):
    with open(path, "w") as f:
        f.write("solid t\n")
        for t in tris:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for v in t:
                f.write("   vertex %g %g %g\n" % v)
            f.write("  endloop\n endfacet\n")
        f.write("endsolid t\n")
write(sys.argv[1], box((0, 0, 0), (2, 2, 2)) + box((1, 1, 1), (3, 3, 3)))
write(sys.argv[2], box((10, 10, 10), (11, 11, 11)))
PY
for t in 1 2; do
  expect_exit 1 "boolean whose result self-intersects, $t thread(s)" -- "$tool" boolean --difference "$work/si/a.stl" "$work/si/b.stl" -o "$work/si/out.stl" --threads "$t"
  check "the self-intersection named, $t thread(s)" -- grep -q "self-intersects" "$work/err"
  check "nothing left after it, $t thread(s)" -- test "$(ls "$work/si")" = "$(printf 'a.stl\nb.stl')"
done
expect_exit 1 "boolean on a missing file" -- "$tool" boolean --difference "$work/base.stl" "$work/none.stl" -o "$work/none-out.stl"

# Interference elimination (issue 6): the swept volume streamed to STL, and the splint minus it.
expect_exit 0 "sweep --help" -- "$tool" sweep --help
expect_exit 2 "sweep without --direction" -- "$tool" sweep "$work/maxilla.stl" --voxel 0.3 -o "$work/swept.stl"
expect_exit 2 "sweep with a zero direction" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,0 --voxel 0.3 -o "$work/swept.stl"
expect_exit 2 "sweep without --voxel" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,1 -o "$work/swept.stl"
expect_exit 2 "sweep with a negative voxel" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,1 --voxel -1 -o "$work/swept.stl"
expect_exit 1 "sweep with a closing below two voxels" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,1 --voxel 0.3 --close 0.4 -o "$work/swept.stl"
check "closing radius named" -- grep -q "closing radius" "$work/err"
expect_exit 0 "sweep" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,1 --voxel 0.3 --extent 1 -o "$work/swept.stl" --json
check "sweep json is one object" -- json_ok "$work/out"
check "sweep reports its grid" -- grep -q '"grid":"' "$work/out"
expect_exit 0 "the swept volume is a printable solid" -- "$tool" check "$work/swept.stl"
cp "$work/swept.stl" "$work/swept.first"
expect_exit 0 "sweep again, 2 threads, 24M cap" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,1 --voxel 0.3 --extent 1 -o "$work/swept.stl" --threads 2 --memory-cap 24M
check "sweep bytes are the same for threads and caps" -- cmp -s "$work/swept.stl" "$work/swept.first"
expect_exit 0 "sweep with a closing, ascii" -- "$tool" sweep "$work/maxilla.stl" --direction 0.1,0,1 --voxel 0.3 --close 0.6 -o "$work/swept-closed.stl" --ascii
expect_exit 0 "the closed swept volume is a printable solid" -- "$tool" check "$work/swept-closed.stl"
expect_exit 1 "sweep under a 1M cap" -- "$tool" sweep "$work/maxilla.stl" --direction 0,0,1 --voxel 0.3 -o "$work/swept-small.stl" --memory-cap 1M
check "no swept file after a failure" -- test ! -e "$work/swept-small.stl"
expect_exit 2 "blockout with one input" -- "$tool" blockout "$work/cut.stl" --direction 0,0,1 --voxel 0.3 -o "$work/blocked.stl"
expect_exit 0 "blockout" -- "$tool" blockout "$work/cut.stl" "$work/maxilla.stl" --direction 0,0,1 --voxel 0.3 -o "$work/blocked.stl" --json
check "blockout json is one object" -- json_ok "$work/out"
check "blockout removed a volume" -- grep -q '"removed_volume_mm3":' "$work/out"
expect_exit 0 "the blocked-out splint is a printable solid" -- "$tool" check "$work/blocked.stl"
expect_exit 0 "blockout --exact of the base" -- "$tool" blockout "$work/base.stl" "$work/maxilla.stl" --direction 0,0,1 --exact -o "$work/blocked-exact.stl" --json
check "blockout --exact json is one object" -- json_ok "$work/out"
check "blockout --exact: the exact method, walls, a valid solid" -- grep -qE '"method":"exact","direction":\[0,0,1\],"front_triangles":[1-9][0-9]*,"kept_front_triangles":[0-9]+,"walls":[0-9]+' "$work/out"
check "blockout --exact: valid" -- grep -q '"valid_solid":true' "$work/out"
expect_exit 0 "the exact blockout is printable" -- "$tool" check "$work/blocked-exact.stl"
expect_exit 2 "blockout --exact takes no voxels" -- "$tool" blockout "$work/cut.stl" "$work/maxilla.stl" --direction 0,0,1 --exact --voxel 0.3 -o "$work/blocked-x2.stl"
check "the usage error says why" -- grep -q "blockout --exact has no voxels" "$work/err"
check "no file after the usage error" -- test ! -e "$work/blocked-x2.stl"
expect_exit 1 "blockout of a missing jaw" -- "$tool" blockout "$work/cut.stl" "$work/none.stl" --direction 0,0,1 --voxel 0.3 -o "$work/blocked-none.stl"
check "no blocked file after a failure" -- test ! -e "$work/blocked-none.stl"

# The pipeline on the paper-scale case with the 6,000-triangle phantom jaws: the splint's bytes
# are the Boolean golden's.
mkdir -p "$work/case" "$work/design"
"$tool" phantom --triangles 6000 -o "$work/case" >/dev/null
cp "$fixtures/cases/paper_scale.json" "$work/case/case.json"
expect_exit 2 "design without -o" -- "$tool" design "$work/case/case.json"
expect_exit 0 "design" -- "$tool" design "$work/case/case.json" -o "$work/design"
cp "$work/out" "$work/out.design"
check "design wrote the splint" -- test -s "$work/design/splint.stl"
check "design wrote the report" -- json_ok "$work/design/report.json"
golden=$(grep "boolean:paper_scale-phantom6000" "$fixtures/golden.sha256" | cut -d' ' -f1)
check "design splint has the golden bytes" -- grep -q "\"splint_sha256\":\"$golden\"" "$work/design/report.json"
check "report has the case hash" -- grep -q '"case_sha256":"[0-9a-f]\{64\}"' "$work/design/report.json"
check "report has the stages" -- grep -q '"stage":"boolean"' "$work/design/report.json"
expect_exit 0 "the designed splint is printable" -- "$tool" check "$work/design/splint.stl"
# The run's files are placed together: one that cannot be placed (a folder named report.json
# in the way) leaves the earlier run's splint as it was and no temporary file.
mkdir -p "$work/design-blocked/report.json"
printf 'old' >"$work/design-blocked/splint.stl"
expect_exit 1 "design with a folder in the report's place" -- "$tool" design "$work/case/case.json" -o "$work/design-blocked"
check "the folder in the way named" -- grep -q "design-blocked/report.json: cannot move the output into place: a folder has its name" "$work/err"
check "the earlier splint left as it was" -- test "$(cat "$work/design-blocked/splint.stl")" = old
check "no other file left" -- test "$(find "$work/design-blocked" -mindepth 1 | wc -l)" -eq 2
# A jaw in other units than the case's mm (here the maxilla in inches, written by convert
# --scale): refused, its size and the factor to mm named, nothing written; convert --scale 25.4
# brings it back to mm and the case designs.
expect_exit 0 "convert a jaw to inches" -- "$tool" convert "$work/case/maxilla.stl" -o "$work/case/maxilla_in.stl" --scale 0.03937007874015748 --json
check "convert says the scale" -- grep -q '"scale":0.03937007874015748' "$work/out"
sed 's/"maxilla.stl"/"maxilla_in.stl"/' "$work/case/case.json" >"$work/case/inches.json"
expect_exit 1 "design with a jaw in inches" -- "$tool" design "$work/case/inches.json" -o "$work/design-inches"
check "the jaw's size and the factor named" -- grep -q "jaw 0 (maxilla) is [0-9.]* x [0-9.]* x [0-9.]* across: too small for a jaw in mm (at least 10 mm).*x25.4" "$work/err"
check "nothing written for a jaw in inches" -- test ! -e "$work/design-inches/splint.stl"
expect_exit 0 "convert the jaw back to mm" -- "$tool" convert "$work/case/maxilla_in.stl" -o "$work/case/maxilla_mm.stl" --scale 25.4
sed 's/"maxilla.stl"/"maxilla_mm.stl"/' "$work/case/case.json" >"$work/case/back.json"
expect_exit 0 "design with the jaw back in mm" -- "$tool" design "$work/case/back.json" -o "$work/design-back"
expect_exit 2 "convert with a scale of 0" -- "$tool" convert "$work/case/maxilla.stl" -o "$work/case/never.stl" --scale 0
check "no file for a scale of 0" -- test ! -e "$work/case/never.stl"
# The side-wall check: the case's jaws cross no wall (no summary line; the report has both
# jaws). The mandible moved 3 mm sideways still reaches the base, but its teeth cross the
# walls, the outer in one half of the arch and the inner in the other: refused by default
# (max_sideways_crossing 0.05), nothing written; designed with "max_sideways_crossing": 1, with
# a summary line saying where; refused with "max_wall_crossing": 0.1.
check "design says nothing of the side walls when no jaw crosses them" -- sh -c "! grep -q '^side walls' '$work/out.design'"
check "report: both jaws' side walls" -- grep -q '"side_walls":{"max_wall_crossing":1,"max_sideways_crossing":0.05,"jaws":\[{"jaw":0,"role":"maxilla","arch_mm":[0-9.]*,"outer_mm":0,"inner_mm":0,"either_mm":0,"share":0,"halves":\[{"outer_mm":0,"inner_mm":0},{"outer_mm":0,"inner_mm":0}\],"sideways_mm":0,"sideways_share":0,"stretches":[0-9]*,"crossed":0},{"jaw":1,"role":"mandible"' "$work/design/report.json"
python3 - "$work/case/case.json" "$work/case/sideways.json" <<'PY'
import json, sys
case = json.load(open(sys.argv[1]))
case["jaws"][1]["transform"][3] += 3.0  # x of the translation
json.dump(case, open(sys.argv[2], "w"), indent=1)
case["max_sideways_crossing"] = 1
json.dump(case, open(sys.argv[2].replace(".json", "-measured.json"), "w"), indent=1)
PY
expect_exit 1 "design with the mandible 3 mm sideways" -- "$tool" design "$work/case/sideways.json" -o "$work/design-sideways-default"
check "the sideways refusal names the jaw, both walls, the share and what to check" -- grep -q "design: jaw 1 (mandible) sits to one side of the base: it crosses the outer wall along [0-9.]* mm in one half of the arch, the inner along [0-9.]* in the other (share 0\.[2-9][0-9]*, max_sideways_crossing 0.05); check the jaw's transform and the picks" "$work/err"
check "nothing written when refused sideways" -- test ! -e "$work/design-sideways-default/splint.stl"
expect_exit 0 "design with the mandible 3 mm sideways, max_sideways_crossing 1" -- "$tool" design "$work/case/sideways-measured.json" -o "$work/design-sideways"
check "the summary says where the mandible crosses the side walls" -- grep -q '^side walls (mandible): crossed along [0-9.]* of [0-9.]* mm of the arch ([0-9]*%; outer [0-9.]*, inner [0-9.]* mm; sideways [0-9.]* mm, [2-9][0-9]%), first at (' "$work/out"
check "report: the mandible's crossing" -- grep -q '"role":"mandible","arch_mm":[0-9.]*,"outer_mm":[1-9][0-9.]*,"inner_mm":[1-9][0-9.]*,"either_mm":[0-9.]*,"share":0\.[3-9][0-9]*,"halves":\[{"outer_mm":[1-9][0-9.]*,"inner_mm":0},{"outer_mm":0,"inner_mm":[1-9][0-9.]*}\],"sideways_mm":[1-9][0-9.]*,"sideways_share":0\.[2-9][0-9]*,"stretches":[0-9]*,"crossed":[1-9][0-9]*,"first_at":\[' "$work/design-sideways/report.json"
sed 's/"printer":/"max_wall_crossing": 0.1,\n  "printer":/' "$work/case/sideways.json" >"$work/case/sideways-refused.json"
expect_exit 1 "design with the mandible sideways and max_wall_crossing 0.1" -- "$tool" design "$work/case/sideways-refused.json" -o "$work/design-sideways-refused"
check "the refusal names the jaw, the share and what to check" -- grep -q "design: jaw 1 (mandible) crosses the base's side walls along [0-9.]* of its [0-9.]* mm (share 0\.[3-9][0-9]*, max_wall_crossing 0.1), first at \[.*check the jaw's transform and the picks" "$work/err"
check "nothing written when refused" -- test ! -e "$work/design-sideways-refused/splint.stl"
# One splint's print job ("output": {"job": NAME}, issue 32): the splint alone on the Eden260
# tray as a 3MF, its triangles and volume those of the STL (Python's zipfile and XML parser),
# named in the report with its SHA-256; the STL's bytes unchanged.
sed 's/"report": "report.json"/"report": "report.json", "job": "splint.3mf"/' "$work/case/case.json" >"$work/case/job.json"
expect_exit 0 "design with a print job" -- "$tool" design "$work/case/job.json" -o "$work/design-job"
check "the job's splint has the golden bytes" -- has_sha256 "$work/design-job/splint.stl" "$golden"
check "the splint's print job: one object on the tray, the STL's triangles and volume (Python)" -- \
  python3 "$(dirname "$0")/check_3mf.py" "$work/design-job/splint.3mf" 1 255 252 5 "$golden" \
  --height 200 --stl "$work/design-job/splint.stl"
one_job_sha=$(sha256sum "$work/design-job/splint.3mf" | cut -d' ' -f1)
check "the report names the splint's print job and its SHA-256" -- grep -q "\"print_job\":{\"path\":\"[^\"]*splint.3mf\",\"sha256\":\"$one_job_sha\"}" "$work/design-job/report.json"
sed 's/"report": "report.json"/"report": "report.json", "job": "..\/x.3mf"/' "$work/case/case.json" >"$work/case/job-bad.json"
expect_exit 1 "a print job outside the output folder" -- "$tool" design "$work/case/job-bad.json" -o "$work/design-job-bad"
check "the refusal names the rule" -- grep -q '"job" must be a file name in the output folder' "$work/err"
# The same case with interference elimination ("blockout" added before "printer").
sed 's/"printer":/"blockout": {"voxel": 0.3},\n  "printer":/' "$work/case/case.json" >"$work/case/blockout.json"
mkdir -p "$work/design-blockout"
expect_exit 0 "design with blockout" -- "$tool" design "$work/case/blockout.json" -o "$work/design-blockout"
check "blockout reported per jaw" -- grep -q '"blockout":\[{"role":"maxilla"' "$work/design-blockout/report.json"
check "blockout parameters reported" -- grep -q '"blockout_voxel_mm":0.3' "$work/design-blockout/report.json"
expect_exit 0 "the blocked-out design is printable" -- "$tool" check "$work/design-blockout/splint.stl"
# Scan-CT fusion (issue 30): the turned mandible (autorotate, above) as the mandible's "scan":
# registered back onto it, reported under "fusion"; a wrong landmark pairing stops the design
# with the jaw named and nothing written.
python3 - "$work/case/case.json" "$work/turned.stl" "$work/case/fused.json" "$work/case/fused-wrong.json" <<'PY'
import json, sys
case = json.load(open(sys.argv[1]))
case["jaws"][1]["scan"] = {"path": sys.argv[2], "max_rms_mm": 0.05}
json.dump(case, open(sys.argv[3], "w"))
case["jaws"][1]["scan"]["landmarks"] = [[[0, 0, 0], [0, 0, 0]], [[10, 0, 0], [0, 10, 0]], [[0, 10, 0], [10, 0, 0]]]
json.dump(case, open(sys.argv[4], "w"))
PY
mkdir -p "$work/design-fused" "$work/design-fused-wrong"
expect_exit 0 "design with a scan" -- "$tool" design "$work/case/fused.json" -o "$work/design-fused"
check "fusion reported for the mandible" -- grep -q '"fusion":\[{"role":"mandible","scan":"[^"]*turned.stl","scan_sha256":"[0-9a-f]\{64\}"' "$work/design-fused/report.json"
check "fusion fits within 0.01 mm" -- python3 -c "import json, sys; f = json.load(open(sys.argv[1]))['fusion'][0]; sys.exit(not (f['rms_mm'] < 0.01 and f['overlap'] > 0.99))" "$work/design-fused/report.json"
check "fusion printed" -- grep -q "^fusion (mandible): scan .*turned.stl registered, RMS 0.0" "$work/out"
check "fusion reported as a stage" -- grep -q '"stage":"fusion"' "$work/design-fused/report.json"
expect_exit 0 "the fused design is printable" -- "$tool" check "$work/design-fused/splint.stl"
expect_exit 1 "design with a wrong landmark pairing" -- "$tool" design "$work/case/fused-wrong.json" -o "$work/design-fused-wrong"
check "the wrong pairing names the jaw" -- grep -q "design: fusion: jaw 1 (mandible), scan .*turned.stl: .*landmarks" "$work/err"
check "no splint after a wrong pairing" -- test ! -e "$work/design-fused-wrong/splint.stl"
check "no report after a wrong pairing" -- test ! -e "$work/design-fused-wrong/report.json"
rm "$work/case/mandible.stl"
mkdir -p "$work/design2"
expect_exit 1 "design with a missing jaw" -- "$tool" design "$work/case/case.json" -o "$work/design2"
check "missing jaw named" -- grep -q "mandible.stl" "$work/err"
check "no splint after a failure" -- test ! -e "$work/design2/splint.stl"
check "no report after a failure" -- test ! -e "$work/design2/report.json"

# CT: the skull phantom in each format, then reconstruction of both jaws (issue 7).
ctsize=(--size 120,110,80 --spacing 0.6,0.6,0.6)
expect_exit 0 "ct-phantom --help" -- "$tool" ct-phantom --help
expect_exit 2 "ct-phantom without --format" -- "$tool" ct-phantom -o "$work/ct.nrrd"
expect_exit 2 "ct-phantom with a bad format" -- "$tool" ct-phantom -o "$work/ct.nrrd" --format png
expect_exit 2 "ct-phantom with a bad size" -- "$tool" ct-phantom -o "$work/ct.nrrd" --format nrrd --size 10,10
expect_exit 1 "ct-phantom too small for the jaws" -- "$tool" ct-phantom -o "$work/ct.nrrd" --format nrrd --size 40,40,40
check "too small named" -- grep -q "the jaws need at least" "$work/err"
expect_exit 0 "ct-phantom nrrd" -- "$tool" ct-phantom -o "$work/ct.nrrd" --format nrrd "${ctsize[@]}" --json
check "ct-phantom --json" -- json_ok "$work/out"
check "ct-phantom gives seeds" -- grep -q '"seed_maxilla":\[0,18,13' "$work/out"
expect_exit 0 "ct-phantom mha" -- "$tool" ct-phantom -o "$work/ct.mha" --format mha "${ctsize[@]}" --noise 30 --no-streak --seed 5
expect_exit 0 "ct-phantom dicom" -- "$tool" ct-phantom -o "$work/ctdcm" --format dicom "${ctsize[@]}"
check "ct-phantom dicom wrote 80 slices" -- test "$(ls "$work/ctdcm" | wc -l)" -eq 80
seeds=(--seed-maxilla 0,18,13 --seed-mandible 0,18,-13)
expect_exit 0 "reconstruct --help" -- "$tool" reconstruct --help
expect_exit 2 "reconstruct without seeds" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jaws"
expect_exit 2 "reconstruct with a bad connectivity" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jaws" "${seeds[@]}" --connectivity 7
expect_exit 2 "reconstruct with a bad plane" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jaws" "${seeds[@]}" --split-plane 0,0,0
expect_exit 0 "reconstruct nrrd" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jaws" "${seeds[@]}" --json
check "reconstruct --json" -- json_ok "$work/out"
check "reconstruct separated the jaws" -- grep -q '"meets_other_region":true' "$work/out"
check "reconstruct reports the peak arena" -- grep -q '"peak_arena_bytes":[1-9]' "$work/out"
expect_exit 0 "the reconstructed maxilla is a printable solid" -- "$tool" check "$work/jaws/maxilla.stl"
expect_exit 0 "the reconstructed mandible is a printable solid" -- "$tool" check "$work/jaws/mandible.stl"
expect_exit 0 "reconstruct again, 26-connectivity" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jaws26" "${seeds[@]}" --connectivity 26 --threads 2
expect_exit 0 "reconstruct nrrd again" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jaws2" "${seeds[@]}"
check "reconstruct is deterministic" -- cmp -s "$work/jaws/maxilla.stl" "$work/jaws2/maxilla.stl"
# Both jaws are placed together, and the summary names them only once they are: a folder in
# the mandible's place leaves no maxilla and no line for it.
mkdir -p "$work/jawsblocked/mandible.stl/x"
expect_exit 1 "reconstruct with a folder in the mandible's place" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsblocked" "${seeds[@]}"
check "no maxilla placed" -- test ! -e "$work/jawsblocked/maxilla.stl"
check "no jaw line printed" -- test ! -s "$work/out"
expect_exit 2 "reconstruct with a bad --decimate" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsbad" "${seeds[@]}" --decimate 2
expect_exit 0 "reconstruct, smoothed and decimated" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsdec" "${seeds[@]}" --smooth 5 --decimate 20000 --json
check "decimation reported" -- grep -q '"decimated_from_triangles":' "$work/out"
check "at most 20000 triangles" -- python3 -c "import json,sys; r=json.load(open('$work/out')); sys.exit(0 if all(j['triangles'] <= 20000 for j in r['jaws']) else 1)"
expect_exit 0 "the decimated maxilla is a printable solid" -- "$tool" check "$work/jawsdec/maxilla.stl"
expect_exit 0 "reconstruct mha" -- "$tool" reconstruct "$work/ct.mha" -o "$work/jawsmha" "${seeds[@]}"
expect_exit 0 "reconstruct dicom folder" -- "$tool" reconstruct "$work/ctdcm" -o "$work/jawsdcm" "${seeds[@]}" --hu-min 300 --hu-max 4000
# One DICOM file given directly (issue 31): read as a series of one slice (by its extension, or
# by the "DICM" preamble without one), so the error is the seed's, not the format's.
one_dcm=$(ls "$work/ctdcm" | head -n 1)
cp "$work/ctdcm/$one_dcm" "$work/one-slice"
for f in "$work/ctdcm/$one_dcm" "$work/one-slice"; do
  expect_exit 1 "reconstruct one DICOM file ($(basename "$f"))" -- "$tool" reconstruct "$f" -o "$work/jawsone" "${seeds[@]}"
  check "one DICOM file read as a volume of one slice" -- grep -q "outside the volume" "$work/err"
done
printf 'not a CT' >"$work/not-ct.bin"
expect_exit 1 "reconstruct a file of unknown format" -- "$tool" reconstruct "$work/not-ct.bin" -o "$work/jawsone" "${seeds[@]}"
check "unknown format named" -- grep -q "cannot tell the CT format of .*a DICOM file or a folder" "$work/err"
expect_exit 0 "reconstruct with a split plane" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsplane" "${seeds[@]}" --split-plane 0,0,0,0,0,1
expect_exit 1 "reconstruct with the plane the wrong way" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsbad" "${seeds[@]}" --split-plane 0,0,0,0,0,-1
check "wrong side named" -- grep -q "split plane's side" "$work/err"
expect_exit 1 "reconstruct with a seed outside" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsbad" --seed-maxilla 0,18,13 --seed-mandible 0,18,99
check "seed outside named" -- grep -q "outside the volume" "$work/err"
expect_exit 1 "reconstruct with a seed in soft tissue" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsbad" --seed-maxilla 0,0,13 --seed-mandible 0,18,-13
check "seed not in window named" -- grep -q "not in the HU window" "$work/err"
expect_exit 1 "reconstruct under a 2M cap" -- "$tool" reconstruct "$work/ct.nrrd" -o "$work/jawsbad" "${seeds[@]}" --memory-cap 2M --json
check "cap failure is arena_exhausted" -- grep -q '"status":"arena_exhausted"' "$work/out"
check "no jaw written after failures" -- test ! -e "$work/jawsbad/maxilla.stl"
# The whole method from CT: fixtures/cases/ct_phantom.json reconstructs both jaws from the
# phantom volume (seeds instead of meshes), opens the bite, builds the base and cuts it.
mkdir -p "$work/ctcase"
cp "$fixtures/cases/ct_phantom.json" "$work/ctcase/case.json"
cp "$work/ct.nrrd" "$work/ctcase/ct.nrrd"
expect_exit 0 "design from CT" -- "$tool" design "$work/ctcase/case.json" -o "$work/ctcase/out"
check "design from CT reports the voxels' hash" -- grep -q '"ct_voxels_sha256":"[0-9a-f]\{64\}"' "$work/ctcase/out/report.json"
ctgolden=$(grep "design:ct_phantom-120x110x80" "$fixtures/golden.sha256" | cut -d' ' -f1)
check "design from CT has the golden bytes" -- grep -q "\"splint_sha256\":\"$ctgolden\"" "$work/ctcase/out/report.json"
expect_exit 0 "the splint from CT is printable" -- "$tool" check "$work/ctcase/out/splint.stl"
# The automatic outline from CT (issue 28): fixtures/cases/ct_auto.json is the CT case with
# "base": {"auto": {}} (the mandible's 2 mm move keeps the reconstructed jaws apart);
# `outline` writes the resolved case, and designing either gives the pinned bytes.
mkdir -p "$work/ctauto"
cp "$fixtures/cases/ct_auto.json" "$work/ctauto/case.json"
cp "$work/ct.nrrd" "$work/ctauto/ct.nrrd"
expect_exit 0 "outline from CT" -- "$tool" outline "$work/ctauto/case.json" -o "$work/ctauto/resolved.json" --json
check "outline from CT: one JSON object" -- json_ok "$work/out"
check "outline from CT: the jaws were apart" -- grep -q '"gap_as_given_mm":[1-9].*"bite_opened":false' "$work/out"
check "outline from CT wrote the resolved case" -- json_ok "$work/ctauto/resolved.json"
expect_exit 0 "design the auto case from CT" -- "$tool" design "$work/ctauto/case.json" -o "$work/ctauto/out"
ctautogolden=$(grep " design:ct_auto-120x110x80$" "$fixtures/golden.sha256" | cut -d' ' -f1)
check "design of the auto case from CT has the golden bytes" -- grep -q "\"splint_sha256\":\"$ctautogolden\"" "$work/ctauto/out/report.json"
check "the report has the outline" -- grep -q '"outline":{' "$work/ctauto/out/report.json"
check "design wrote the resolved case" -- json_ok "$work/ctauto/out/case.resolved.json"
check "the CT volume named absolute from another folder" -- grep -q '"volume":"/[^"]*ctauto/ct.nrrd"' "$work/ctauto/out/case.resolved.json"
check "and as the case gives it in the case's folder" -- grep -q '"volume":"ct.nrrd"' "$work/ctauto/resolved.json"
expect_exit 0 "design the resolved case design wrote" -- "$tool" design "$work/ctauto/out/case.resolved.json" -o "$work/ctauto/again-out"
check "design's resolved case from CT gives the same splint" -- has_sha256 "$work/ctauto/again-out/splint.stl" "$ctautogolden"
expect_exit 0 "the auto splint from CT is printable" -- "$tool" check "$work/ctauto/out/splint.stl"
expect_exit 0 "design outline's resolved case from CT" -- "$tool" design "$work/ctauto/resolved.json" -o "$work/ctauto/again"
check "the resolved case from CT gives the same splint" -- has_sha256 "$work/ctauto/again/splint.stl" "$ctautogolden"
rm "$work/ctcase/ct.nrrd"
expect_exit 1 "design from a missing CT" -- "$tool" design "$work/ctcase/case.json" -o "$work/ctcase/out2"
check "no splint without the CT" -- test ! -e "$work/ctcase/out2/splint.stl"
expect_exit 1 "reconstruct a missing volume" -- "$tool" reconstruct "$work/none.nrrd" -o "$work/jawsbad" "${seeds[@]}"

# PLY and OBJ input, and `compare` (issue 8): surface deviation and the coloured PLY.
cube_obj() {  # cube_obj FILE DZ: the cube [0,10]^2 x [DZ,DZ+10] as OBJ quads (outward)
  local z0=$2 z1=$(($2 + 10))
  printf '# cube\nv 0 0 %s\nv 10 0 %s\nv 10 10 %s\nv 0 10 %s\n' "$z0" "$z0" "$z0" "$z0" >"$1"
  printf 'v 0 0 %s\nv 10 0 %s\nv 10 10 %s\nv 0 10 %s\n' "$z1" "$z1" "$z1" "$z1" >>"$1"
  printf 'f 1 4 3 2\nf 5/1 6/1 7/1 8/1\nf 1//1 2//1 6//1 5//1\nf 2 3 7 6\nf -5 -1 -2 -6\nf 1 5 8 4\n' >>"$1"
}
cube_obj "$work/cube.obj" 0
cube_obj "$work/cube_up.obj" 1
printf 'ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\nelement face 6\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n10 0 0\n10 10 0\n0 10 0\n0 0 10\n10 0 10\n10 10 10\n0 10 10\n4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 3 7 6 2\n4 0 4 7 3\n' >"$work/cube.ply"
expect_exit 0 "an OBJ cube is a printable solid" -- "$tool" check "$work/cube.obj" --json
check "OBJ check names the format" -- grep -q '"genus":0' "$work/out"
expect_exit 0 "an ASCII PLY cube is a printable solid" -- "$tool" check "$work/cube.ply"
check "PLY check says ply-ascii" -- grep -q "ply-ascii, 12 triangles" "$work/out"
expect_exit 0 "convert OBJ to STL" -- "$tool" convert "$work/cube.obj" -o "$work/cube.stl"
expect_exit 0 "compare --help" -- "$tool" compare --help
check "compare --help mentions --ply" -- grep -q -- "--ply" "$work/out"
expect_exit 2 "compare with one file" -- "$tool" compare "$work/cube.obj"
expect_exit 2 "compare with a bad --range" -- "$tool" compare "$work/cube.obj" "$work/cube.ply" --range 0
expect_exit 2 "compare --ply without a name" -- "$tool" compare "$work/cube.obj" "$work/cube.ply" --ply
expect_exit 0 "compare OBJ, PLY and STL of one cube" -- "$tool" compare "$work/cube.obj" "$work/cube.ply" --json
check "compare --json is one JSON object" -- json_ok "$work/out"
check "same cube: Hausdorff 0" -- grep -q '"hausdorff_mm":0,' "$work/out"
expect_exit 0 "compare STL and PLY" -- "$tool" compare "$work/cube.stl" "$work/cube.ply" --json
check "STL and PLY: Hausdorff 0" -- grep -q '"hausdorff_mm":0,' "$work/out"
expect_exit 0 "compare with a cube moved 1 mm, --ply" -- "$tool" compare "$work/cube.obj" "$work/cube_up.obj" --ply "$work/dev.ply" --json
check "moved cube: mean 0.5, max 1, Hausdorff 1" -- grep -q '"a_to_b_mean_mm":0.5,"a_to_b_max_mm":1,.*"hausdorff_mm":1,' "$work/out"
check "compare --ply wrote a binary PLY" -- grep -qa 'format binary_little_endian 1.0' "$work/dev.ply"
expect_exit 0 "the coloured PLY reads back as a solid" -- "$tool" check "$work/dev.ply"
expect_exit 0 "compare --ply again, 2 threads" -- "$tool" compare "$work/cube.obj" "$work/cube_up.obj" --ply "$work/dev2.ply" --threads 2
check "compare --ply is deterministic" -- cmp -s "$work/dev.ply" "$work/dev2.ply"
expect_exit 0 "compare the coloured PLY with its source" -- "$tool" compare "$work/dev.ply" "$work/cube.obj" --json
check "round trip: Hausdorff 0" -- grep -q '"hausdorff_mm":0,' "$work/out"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n' >"$work/bad.obj"
expect_exit 1 "an OBJ face naming a missing vertex" -- "$tool" compare "$work/cube.obj" "$work/bad.obj" --ply "$work/bad.ply"
check "the error names line and column" -- grep -q 'bad.obj:4:7' "$work/err"
check "no PLY written after a failure" -- test ! -e "$work/bad.ply"
expect_exit 1 "compare a missing file" -- "$tool" compare "$work/cube.obj" "$work/none.ply"

# Input caps (issue 9): a case file over the cap (16M by default; a sparse 17M file here) is
# refused before it is read, naming the file and its size, and nothing is written;
# --max-input-bytes sets the cap for the case and for the jaw meshes design reads whole.
mkdir -p "$work/caps/out"
cp "$fixtures/cases/paper_scale.json" "$work/caps/big.json"
truncate -s 17M "$work/caps/big.json"
expect_exit 1 "design: a case file over the 16M cap" -- "$tool" design "$work/caps/big.json" -o "$work/caps/out"
check "the cap error names the file, its size and the cap" -- grep -q "big.json: file is 17825792 bytes, over the limit of 16777216 bytes" "$work/err"
check "nothing written after the case cap" -- test -z "$(ls -A "$work/caps/out")"
expect_exit 1 "base: a case file over the 16M cap" -- "$tool" base "$work/caps/big.json" -o "$work/caps/out/base.stl"
check "base names the file and the limit" -- grep -q "big.json: file is 17825792 bytes, over the limit of 16777216" "$work/err"
check "no base after the case cap" -- test ! -e "$work/caps/out/base.stl"
expect_exit 2 "--max-input-bytes needs a size" -- "$tool" design "$work/case/case.json" -o "$work/caps/out" --max-input-bytes lots
expect_exit 1 "design: --max-input-bytes under the case's size" -- "$tool" design "$work/case/case.json" -o "$work/caps/out" --max-input-bytes 1K
check "the case over --max-input-bytes is named" -- grep -q "case.json: file is [0-9]* bytes, over the limit of 1024 bytes" "$work/err"
expect_exit 1 "design: a jaw mesh over --max-input-bytes" -- "$tool" design "$work/case/case.json" -o "$work/caps/out" --max-input-bytes 64K --json
check "the jaw over the cap is named" -- grep -q "maxilla.stl: file is [0-9]* bytes, over the limit of 65536 bytes" "$work/err"
check "--json says limit_exceeded" -- grep -q '"status":"limit_exceeded"' "$work/out"
check "nothing written after the jaw cap" -- test -z "$(ls -A "$work/caps/out")"

# render (issue 8): PNG previews from splintcore's own rasteriser and encoder.
png_ok() {  # png_ok FILE [W H]: signature, chunk CRCs, IDAT inflates to H rows of 3W+1 bytes
  [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] || return 1
  command -v python3 >/dev/null 2>&1 || return 0
  python3 -c '
import struct, sys, zlib
d = open(sys.argv[1], "rb").read()
p, idat, w, h = 8, b"", 0, 0
while p < len(d):
    n, = struct.unpack(">I", d[p:p + 4])
    t, body = d[p + 4:p + 8], d[p + 8:p + 8 + n]
    assert zlib.crc32(t + body) & 0xffffffff == struct.unpack(">I", d[p + 8 + n:p + 12 + n])[0], t
    if t == b"IHDR":
        w, h = struct.unpack(">II", body[:8])
    if t == b"IDAT":
        idat += body
    p += 12 + n
assert t == b"IEND"
raw = zlib.decompress(idat)
assert len(raw) == h * (3 * w + 1), (len(raw), w, h)
if len(sys.argv) > 2:
    assert (w, h) == (int(sys.argv[2]), int(sys.argv[3])), (w, h)
' "$@"
}
expect_exit 0 "render --help" -- "$tool" render --help
check "render --help mentions --views" -- grep -q -- "--views" "$work/out"
expect_exit 2 "render without -o" -- "$tool" render "$work/cube.obj"
expect_exit 2 "render without a mesh" -- "$tool" render -o "$work/bad.png"
expect_exit 2 "render with --size 0x10" -- "$tool" render "$work/cube.obj" -o "$work/bad.png" --size 0x10
expect_exit 2 "render with --size 9000x10" -- "$tool" render "$work/cube.obj" -o "$work/bad.png" --size 9000x10
expect_exit 2 "render with an unknown view" -- "$tool" render "$work/cube.obj" -o "$work/bad.png" --views front,side
expect_exit 2 "render with an empty view" -- "$tool" render "$work/cube.obj" -o "$work/bad.png" --views front,
expect_exit 2 "render with a bad --shading" -- "$tool" render "$work/cube.obj" -o "$work/bad.png" --shading phong
check "no PNG after usage errors" -- test ! -e "$work/bad.png"
expect_exit 0 "render two meshes" -- "$tool" render "$work/cube.obj" "$work/cube_up.obj" -o "$work/r.png" --size 200x150 --json
check "render --json is one JSON object" -- json_ok "$work/out"
check "render --json names the PNG's hash" -- grep -q '"png_sha256":"[0-9a-f]\{64\}"' "$work/out"
check "render wrote a valid 200x150 PNG" -- png_ok "$work/r.png" 200 150
expect_exit 0 "render again with 2 threads" -- "$tool" render "$work/cube.obj" "$work/cube_up.obj" -o "$work/r2.png" --size 200x150 --threads 2
check "render is deterministic" -- cmp -s "$work/r.png" "$work/r2.png"
expect_exit 0 "render one view, Gouraud" -- "$tool" render "$work/cube.ply" -o "$work/r3.png" --views iso --shading gouraud --size 64x64
check "one view: a valid 64x64 PNG" -- png_ok "$work/r3.png" 64 64
expect_exit 1 "render a broken mesh" -- "$tool" render "$work/bad.obj" -o "$work/bad.png"
expect_exit 1 "render with a memory cap too small" -- "$tool" render "$work/cube.obj" -o "$work/bad.png" --memory-cap 1M --json
check "render --json says arena_exhausted" -- grep -q '"status":"arena_exhausted"' "$work/out"
check "no PNG after a failure" -- test ! -e "$work/bad.png"
expect_exit 0 "compare --png" -- "$tool" compare "$work/cube.obj" "$work/cube_up.obj" --png "$work/dev.png" --json
check "compare --png wrote a valid PNG" -- png_ok "$work/dev.png" 1024 1024
check "compare --json names the PNG" -- grep -q '"png":".*dev.png","png_sha256":"[0-9a-f]\{64\}","png_range_mm":1' "$work/out"
expect_exit 2 "compare --png without a name" -- "$tool" compare "$work/cube.obj" "$work/cube_up.obj" --png
check "design wrote the preview" -- png_ok "$work/design/preview.png" 1024 1024
check "the report names the preview" -- grep -q '"preview":".*preview.png","preview_sha256":"[0-9a-f]\{64\}"' "$work/design/report.json"
check "no preview after a failed design" -- test ! -e "$work/design2/preview.png"
mkdir -p "$work/case3" "$work/design3"  # (a test above removed $work/case's mandible)
"$tool" phantom --triangles 6000 -o "$work/case3" >/dev/null
cp "$fixtures/cases/paper_scale.json" "$work/case3/case.json"
expect_exit 0 "design again" -- "$tool" design "$work/case3/case.json" -o "$work/design3"
check "design prints where the preview is" -- grep -q "^preview: .*design3/preview.png" "$work/out"
check "the preview is deterministic" -- cmp -s "$work/design/preview.png" "$work/design3/preview.png"

# An auto case (issue 28): the preview shows the outline's picks and arch in red (kMarkRgb:
# green and blue 0) over the splint and the jaws; the resolved case designs to the same splint
# and its preview has no marks, so the two previews differ only by them.
red_pixels() {  # red_pixels FILE...: per file, how many pixels are pure red (R > 0, G = B = 0)
  python3 -c '
import struct, sys, zlib
for name in sys.argv[1:]:
    d = open(name, "rb").read()
    p, idat, w, h = 8, b"", 0, 0
    while p < len(d):
        n, = struct.unpack(">I", d[p:p + 4])
        t, body = d[p + 4:p + 8], d[p + 8:p + 8 + n]
        if t == b"IHDR":
            w, h = struct.unpack(">II", body[:8])
        if t == b"IDAT":
            idat += body
        p += 12 + n
    raw, stride, prev, count = zlib.decompress(idat), 3 * w, bytearray(3 * w), 0
    for y in range(h):
        f, row = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 1:
            for i in range(3, stride):
                row[i] = (row[i] + row[i - 3]) & 255
        elif f == 2:
            row = bytearray((u + v) & 255 for u, v in zip(row, prev))
        elif f in (3, 4):
            for i in range(stride):
                a = row[i - 3] if i >= 3 else 0
                b, c = prev[i], prev[i - 3] if i >= 3 else 0
                if f == 3:
                    row[i] = (row[i] + (a + b) // 2) & 255
                else:
                    q = a + b - c
                    pa, pb, pc = abs(q - a), abs(q - b), abs(q - c)
                    row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        count += sum(1 for r, g, b in zip(row[0::3], row[1::3], row[2::3]) if r > 0 and g == 0 and b == 0)
        prev = row
    print(count)' "$@"
}
cat >"$work/case3/auto.json" <<'JSON'
{"splintcore_case": 1, "case_id": "phantom-auto", "units": "mm",
 "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"},
          {"role": "mandible", "mesh": "mandible.stl",
           "transform": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -2.0, 0, 0, 0, 1]}],
 "base": {"spacing_mm": 0.42, "auto": {}}, "printer": "eden260"}
JSON
expect_exit 0 "design of an auto case" -- "$tool" design "$work/case3/auto.json" -o "$work/design_auto"
expect_exit 0 "design of its resolved case" -- "$tool" design "$work/design_auto/case.resolved.json" -o "$work/design_resolved"
check "the resolved case designs the same splint" -- cmp -s "$work/design_auto/splint.stl" "$work/design_resolved/splint.stl"
check "the auto preview differs by the marks" -- bash -c '! cmp -s "$0" "$1"' "$work/design_auto/preview.png" "$work/design_resolved/preview.png"
if command -v python3 >/dev/null 2>&1; then
  reds=$(red_pixels "$work/design_auto/preview.png" "$work/design_resolved/preview.png" | tr '\n' ' ')
  check "the auto preview has red marks" -- test "$(echo "$reds" | cut -d' ' -f1)" -gt 500
  check "the resolved preview has none" -- test "$(echo "$reds" | cut -d' ' -f2)" -eq 0
fi

# The designer's options through the command (issue 8): fixtures/cases/blockout.json
# (blockout, rounded edges, an engraved label, the thickness check, on the tray) with the
# phantom jaws; `phantom` writes the matching case.
mkdir -p "$work/opts"
expect_exit 0 "phantom for the options" -- "$tool" phantom --triangles 6000 -o "$work/opts"
check "phantom writes its case" -- grep -q "^case: .*opts/case.json" "$work/out"
expect_exit 0 "design the phantom's own case" -- "$tool" design "$work/opts/case.json" -o "$work/opts/plain"
check "the phantom's case gives the paper-scale golden" -- grep -q "\"splint_sha256\":\"$(grep " boolean:paper_scale-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)\"" "$work/opts/plain/report.json"
# The jaws' SHA-256 in the report are the files' own, hashed beside the reading when the run has
# threads (a 4.5 MB maxilla: more than the hasher's four 1 MiB slots) and in the reading without.
mkdir -p "$work/hash"
expect_exit 0 "phantom of 90000 triangles" -- "$tool" phantom --triangles 90000 -o "$work/hash"
for threads in 1 3; do
  expect_exit 0 "design at $threads threads" -- "$tool" design "$work/hash/case.json" -o "$work/hash/t$threads" --threads "$threads"
  for jaw in maxilla mandible; do
    check "report: the $jaw's SHA-256 at $threads threads" -- grep -q "\"sha256\":\"$(sha256 "$work/hash/$jaw.stl")\"" "$work/hash/t$threads/report.json"
  done
done
cp "$fixtures/cases/blockout.json" "$work/opts/case.json"
expect_exit 0 "design with every option" -- "$tool" design "$work/opts/case.json" -o "$work/opts/out"
check "summary names the label" -- grep -q '^label: "PHANTOM-01" engraved, 10 glyphs' "$work/out"
check "summary gives the thinnest wall" -- grep -q '^thickness: .* thinner than 1 mm; thinnest' "$work/out"
check "summary says placed on the tray" -- grep -q 'placed on the tray)$' "$work/out"
check "design with every option has the golden bytes" -- grep -q "\"splint_sha256\":\"$(grep " design:blockout-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)\"" "$work/opts/out/report.json"
check "report: the label" -- grep -q '"label":{"text":"PHANTOM-01","glyphs":10' "$work/opts/out/report.json"
check "report: the thin spots" -- grep -q '"thin_spots":\[{"position":\[' "$work/opts/out/report.json"
check "report: the tray translation" -- grep -q '"placed_on_tray":true,"tray_translation_mm":\[' "$work/opts/out/report.json"
check "report: the parameters" -- grep -q '"min_thickness_mm":1,"label_text":"PHANTOM-01","label_mode":"engrave"' "$work/opts/out/report.json"
check "report: the self-intersection check is the label's recorded one" -- grep -q '"self_intersection_free":true,"self_intersection_checked_by":"label","self_intersection_candidates":[1-9]' "$work/opts/out/report.json"
check "report: the case's memory cap applied" -- grep -q '"memory_cap_bytes":536870912,"memory_cap_from":"case"' "$work/opts/out/report.json"
# Every key of this full report is in docs/report-format.md (written as `key`).
report_keys_documented() {
  local key missing=""
  for key in $(grep -oE '"[a-z_0-9]+":' "$1" | tr -d '":' | sort -u); do
    grep -q "\`$key\`" "$fixtures/../docs/report-format.md" || missing="$missing $key"
  done
  [ -z "$missing" ] || { echo "not in docs/report-format.md:$missing"; return 1; }
}
check "report: every key is documented" -- report_keys_documented "$work/opts/out/report.json"
expect_exit 0 "the splint on the tray is a printable solid as placed" -- "$tool" check "$work/opts/out/splint.stl" --no-place
# The same options with the default blockout ("blockout": {}: the exact swept boundary).
cp "$fixtures/cases/exact.json" "$work/opts/case.json"
expect_exit 0 "design with the default blockout" -- "$tool" design "$work/opts/case.json" -o "$work/opts/exact"
check "summary: the exact blockout on both jaws" -- test "$(grep -c '^blockout (.*, exact): ' "$work/out")" -eq 2
check "the default blockout has the golden bytes" -- grep -q "\"splint_sha256\":\"$(grep " design:exact-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)\"" "$work/opts/exact/report.json"
check "report: auto asked, exact used, in the case's 64M" -- grep -q '"blockout_method":"auto"' "$work/opts/exact/report.json"
check "report: exact used" -- grep -q '"blockout_method_used":"exact","blockout":\[{"role":"maxilla","method":"exact"' "$work/opts/exact/report.json"
check "report: the case's 64M applied" -- grep -q '"memory_cap_bytes":67108864,"memory_cap_from":"case"' "$work/opts/exact/report.json"
check "report (exact): every key is documented" -- report_keys_documented "$work/opts/exact/report.json"
# The same options with the height field ("method": "heightfield", 0.1 mm): its golden bytes,
# its own report keys, documented.
cp "$fixtures/cases/heightfield.json" "$work/opts/case.json"
expect_exit 0 "design with the height field" -- "$tool" design "$work/opts/case.json" -o "$work/opts/height"
check "the height field has the golden bytes" -- grep -q "\"splint_sha256\":\"$(grep " design:heightfield-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)\"" "$work/opts/height/report.json"
check "report: heightfield used" -- grep -q '"blockout_method_used":"heightfield","blockout":\[{"role":"maxilla","method":"heightfield"' "$work/opts/height/report.json"
check "report: the height field's imprint" -- grep -q '"imprint":"height field of the swept volume"' "$work/opts/height/report.json"
check "report (heightfield): every key is documented" -- report_keys_documented "$work/opts/height/report.json"
# The height-field spacer (heightfield_spacer.json: 0.2 mm on 0.1 mm, the case's 64M): its
# golden bytes, the clearance in the report, documented.
cp "$fixtures/cases/heightfield_spacer.json" "$work/opts/case.json"
expect_exit 0 "design the height-field spacer" -- "$tool" design "$work/opts/case.json" -o "$work/opts/hspacer"
check "the height-field spacer has the golden bytes" -- grep -q "\"splint_sha256\":\"$(grep " design:heightfield_spacer-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)\"" "$work/opts/hspacer/report.json"
check "report: the spacer's imprint, in the case's 64M" -- grep -q '"imprint":"height field of the swept volume.s clearance offset"' "$work/opts/hspacer/report.json"
check "report: the clearance used" -- grep -q '"clearance_used_mm":0.2' "$work/opts/hspacer/report.json"
check "report (heightfield spacer): every key is documented" -- report_keys_documented "$work/opts/hspacer/report.json"
sed 's/"text": "PHANTOM-01"/"text": "50%"/' "$fixtures/cases/blockout.json" >"$work/opts/case.json"
expect_exit 1 "a label the font cannot write" -- "$tool" design "$work/opts/case.json" -o "$work/opts/bad"
check "the error names the character" -- grep -q "label.*'%'" "$work/err"
check "no splint after the label error" -- test ! -e "$work/opts/bad/splint.stl"

# The automatic outline (issue 28): fixtures/cases/auto.json (the paper-scale case with
# "base": {"auto": {}}) and auto_open.json (the jaws in occlusion, the bite opened 2 mm) with
# the phantom jaws. `outline` writes the resolved case (explicit picks); `design` of an auto
# case writes OUTDIR/case.resolved.json, and designing that gives the same bytes.
mkdir -p "$work/auto"
"$tool" phantom --triangles 6000 -o "$work/auto" >/dev/null
cp "$fixtures/cases/auto.json" "$fixtures/cases/auto_open.json" "$work/auto/"
expect_exit 0 "outline --help" -- "$tool" outline --help
expect_exit 2 "outline without -o" -- "$tool" outline "$work/auto/auto.json"
check "outline without -o is named" -- grep -q "^splintcore: outline needs -o RESOLVED.json$" "$work/err"
expect_exit 0 "outline" -- "$tool" outline "$work/auto/auto.json" -o "$work/auto/resolved.json"
check "outline names the file it wrote" -- grep -q "^wrote .*auto/resolved.json$" "$work/out"
check "outline wrote the resolved case" -- json_ok "$work/auto/resolved.json"
check "the resolved case has explicit picks" -- python3 -c "import json,sys; b=json.load(open('$work/auto/resolved.json'))['base']; sys.exit(0 if 'auto' not in b and len(b['upper']) == len(b['lower']) > 8 else 1)"
check "jaw paths stay relative in the case's folder" -- grep -q '"mesh":"maxilla.stl"' "$work/auto/resolved.json"
expect_exit 0 "outline --json" -- "$tool" outline "$work/auto/auto_open.json" -o "$work/auto/resolved_open.json" --json
check "outline --json is one JSON object" -- json_ok "$work/out"
outline_keys_ok() {  # every key outline --json gives, and the bite opened to 2 mm
  python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
want = ["command", "status", "case", "resolved_case", "occlusal_normal", "gap_as_given_mm",
        "bite_opened", "mandible_translation_mm", "opening_mm", "picks_per_jaw",
        "arch_length_mm", "wafer_min_mm", "wafer_max_mm"]
assert sorted(d) == sorted(want), sorted(d)
assert d["command"] == "outline" and d["status"] == "ok", d
assert d["bite_opened"] is True and d["gap_as_given_mm"] == 0, d
assert abs(d["opening_mm"] - 2.0) < 1e-6, d["opening_mm"]
assert d["mandible_translation_mm"][2] < 0 and d["picks_per_jaw"] > 8, d
assert 0 < d["wafer_min_mm"] <= d["wafer_max_mm"], d
' "$1"
}
check "outline --json has every key" -- outline_keys_ok "$work/out"
autogolden=$(grep " design:auto-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)
expect_exit 0 "design an auto case" -- "$tool" design "$work/auto/auto.json" -o "$work/auto/out"
check "the auto design has the golden bytes" -- grep -q "\"splint_sha256\":\"$autogolden\"" "$work/auto/out/report.json"
check "design wrote case.resolved.json" -- json_ok "$work/auto/out/case.resolved.json"
check "the report names the resolved case and the outline" -- grep -q '"outline":{' "$work/auto/out/report.json"
expect_exit 0 "design the written case.resolved.json" -- "$tool" design "$work/auto/out/case.resolved.json" -o "$work/auto/again"
check "the resolved case gives the same splint" -- has_sha256 "$work/auto/again/splint.stl" "$(sha256 "$work/auto/out/splint.stl")"
check "no resolved case from an explicit case" -- test ! -e "$work/auto/again/case.resolved.json"
expect_exit 0 "design outline's resolved case" -- "$tool" design "$work/auto/resolved.json" -o "$work/auto/again2"
check "outline's resolved case gives the same splint" -- has_sha256 "$work/auto/again2/splint.stl" "$autogolden"
opengolden=$(grep " design:auto_open-phantom6000$" "$fixtures/golden.sha256" | cut -d' ' -f1)
expect_exit 0 "design the auto case with the bite opened" -- "$tool" design "$work/auto/auto_open.json" -o "$work/auto/open"
check "the opened auto design has the golden bytes" -- has_sha256 "$work/auto/open/splint.stl" "$opengolden"
expect_exit 0 "design its resolved case" -- "$tool" design "$work/auto/open/case.resolved.json" -o "$work/auto/open2"
check "its resolved case gives the same splint" -- has_sha256 "$work/auto/open2/splint.stl" "$opengolden"
# Refusals: exit 1, the reason named, nothing written.
sed 's/"bite_opening_mm": 2.0//' "$work/auto/auto_open.json" >"$work/auto/closed.json"
expect_exit 1 "outline with the jaws in occlusion" -- "$tool" outline "$work/auto/closed.json" -o "$work/auto/closed.resolved.json"
check "interpenetrating jaws named, the opening suggested" -- grep -q 'closed.json: outline: the jaws interpenetrate as given .*"bite_opening_mm"' "$work/err"
check "no resolved case after a refusal" -- test ! -e "$work/auto/closed.resolved.json"
expect_exit 1 "design with the jaws in occlusion, --json" -- "$tool" design "$work/auto/closed.json" -o "$work/auto/closed" --json
check "--json says invalid_argument" -- grep -q '"status":"invalid_argument","message":"outline: the jaws interpenetrate' "$work/out"
check "nothing designed after a refusal" -- test -z "$(ls -A "$work/auto/closed" 2>/dev/null)"
python3 -c "import json; c = json.load(open('$work/auto/auto.json')); c['jaws'] = c['jaws'][:1]; json.dump(c, open('$work/auto/maxilla_only.json', 'w'))"
expect_exit 1 "outline with only a maxilla" -- "$tool" outline "$work/auto/maxilla_only.json" -o "$work/auto/maxilla_only.resolved.json"
check "the missing jaw named" -- grep -q "outline: the automatic outline needs one mandible and one maxilla; the case has 0 mandibles" "$work/err"
check "no resolved case without a mandible" -- test ! -e "$work/auto/maxilla_only.resolved.json"
cp "$fixtures/cases/paper_scale.json" "$work/auto/explicit.json"
expect_exit 1 "outline of a case with its own picks" -- "$tool" outline "$work/auto/explicit.json" -o "$work/auto/explicit.resolved.json"
check "no auto named" -- grep -q 'outline: the case gives its picks (no "auto" in "base")' "$work/err"

# Scans (issue 30): the scan-like phantom, check on an open scan, prepare, and an open B whose
# border meets the splint refused by name while the prepared scan is subtracted.
mkdir -p "$work/scan"
expect_exit 2 "phantom --scan with --triangles" -- "$tool" phantom --scan --triangles 6000 -o "$work/scan"
expect_exit 0 "phantom --scan" -- "$tool" phantom --scan --seed 2 -o "$work/scan" --json
check "phantom --scan json is one object" -- json_ok "$work/out"
check "phantom --scan says what it planted" -- grep -q '"holes":3,"max_hole_edges":8,"islands":3' "$work/out"
check "phantom --scan wrote PLY" -- test -s "$work/scan/mandible_scan.ply"
expect_exit 1 "check an open scan" -- "$tool" check "$work/scan/mandible_scan.ply" --json
check "check --json: no volume for an open scan" -- grep -q '"genus":null,"closed":false' "$work/out"
check "check --json: loops" -- grep -q '"boundary_loops":9,' "$work/out"
expect_exit 2 "prepare without -o" -- "$tool" prepare "$work/scan/maxilla_scan.stl"
expect_exit 0 "prepare" -- "$tool" prepare "$work/scan/maxilla_scan.stl" -o "$work/scan/prepared.stl"
check "prepare prints its steps" -- grep -q "5. islands removed  *3" "$work/out"
check "prepare leaves one border" -- grep -q "^closed: no ([0-9]* boundary edges in 1 loop)" "$work/out"
expect_exit 0 "prepare --json" -- "$tool" prepare "$work/scan/maxilla_scan.ply" -o "$work/scan/prepared2.stl" --json --max-hole-edges 4
check "prepare --json is one object" -- json_ok "$work/out"
check "prepare --max-hole-edges 4 fills one hole" -- grep -q '"holes_filled":1,' "$work/out"
expect_exit 0 "base for the scans" -- "$tool" base "$fixtures/cases/paper_scale.json" -o "$work/scan/base.stl"
expect_exit 1 "boolean with the raw scan" -- "$tool" boolean --difference "$work/scan/base.stl" "$work/scan/maxilla_scan.stl" -o "$work/scan/cut.stl"
check "an open B is named" -- grep -q "B is open: [0-9]* boundary edges in 9 loops; its border meets A at vertex" "$work/err"
expect_exit 0 "boolean with the prepared scan" -- "$tool" boolean --difference "$work/scan/base.stl" "$work/scan/prepared.stl" -o "$work/scan/cut.stl"
expect_exit 0 "the splint from the prepared scan is printable" -- "$tool" check "$work/scan/cut.stl"

# One command table (tools/splintcore/main.cpp): --help lists it, every command's --help
# starts with its usage line, and the README shows the same commands with no option their
# --help lacks.
if command -v python3 >/dev/null 2>&1; then
  check "the command table, --help and the README agree" -- \
    python3 "$(dirname "$0")/cli_commands.py" "$tool" "$fixtures/../README.md"
fi

json_ok_all
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
