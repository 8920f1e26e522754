# The start of the real-data shell tests (realdata_cli_test.sh, realdata_blockout_test.sh),
# sourced by them with their arguments SPLINTCORE SPLINTCORE_BENCH REALDATA_DIR: skipped (exit
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
