#!/usr/bin/env bash
# The tool under ThreadSanitizer (tools/test.sh tsan): the fixture cases designed at 2 threads
# (the plan's two STLs written in two tasks, the autorotations, Booleans, outlines, previews,
# print jobs and blockout on the executor), a boolean, check and render at 2 threads. Any race report
# ends the run (halt_on_error, exit 66); every output's bytes must equal a plain build's at one
# thread.
#   bash tests/tools/tsan_cli_test.sh TSAN_TOOL PLAIN_TOOL FIXTURES_DIR
set -u
tsan=$1 plain=$2 fixtures=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export TSAN_OPTIONS="halt_on_error=1 exitcode=66"
fail=0
"$plain" phantom --triangles 6000 -o "$work" >/dev/null || exit 1
for c in plan auto paper_scale blockout; do
  cp "$fixtures/cases/$c.json" "$work/"
  if ! "$tsan" design "$work/$c.json" -o "$work/t-$c" --threads 2 >/dev/null 2>"$work/err"; then
    echo "FAIL design $c at 2 threads under TSan:"; head -n 40 "$work/err"; fail=1; continue
  fi
  "$plain" design "$work/$c.json" -o "$work/p-$c" --threads 1 >/dev/null 2>&1 || { echo "FAIL plain design $c"; fail=1; }
  for f in "$work/p-$c"/*.stl "$work/p-$c"/*.3mf "$work/p-$c"/*.png; do
    [ -e "$f" ] || continue
    cmp -s "$f" "$work/t-$c/$(basename "$f")" || { echo "FAIL $c: $(basename "$f") differs"; fail=1; }
  done
  echo "ok design $c (2 threads, TSan): the plain build's bytes"
done
# The boolean command at 2 threads: its output written and synced on a thread of its own
# while the result is checked, its records encoded in tasks.
"$plain" base "$work/paper_scale.json" -o "$work/base.stl" >/dev/null 2>&1 || { echo "FAIL plain base"; fail=1; }
bool=(boolean --difference "$work/base.stl" "$work/maxilla.stl" "$work/mandible.stl")
if "$tsan" "${bool[@]}" -o "$work/t-bool.stl" --threads 2 >/dev/null 2>"$work/err"; then
  "$plain" "${bool[@]}" -o "$work/p-bool.stl" --threads 1 >/dev/null 2>&1 || { echo "FAIL plain boolean"; fail=1; }
  if cmp -s "$work/p-bool.stl" "$work/t-bool.stl"; then
    echo "ok boolean (2 threads, TSan): the plain build's bytes"
  else
    echo "FAIL boolean: the output differs"; fail=1
  fi
else
  echo "FAIL boolean at 2 threads under TSan:"; head -n 40 "$work/err"; fail=1
fi
for cmd in "check $work/maxilla.stl" "render $work/maxilla.stl $work/mandible.stl -o $work/r.png"; do
  # shellcheck disable=SC2086
  if "$tsan" $cmd --threads 2 >/dev/null 2>"$work/err"; then
    echo "ok ${cmd%% *} (2 threads, TSan)"
  else
    echo "FAIL ${cmd%% *} at 2 threads under TSan:"; head -n 40 "$work/err"; fail=1
  fi
done
exit $fail
