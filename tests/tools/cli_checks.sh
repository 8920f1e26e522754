# The checks of the program's shell tests (cli_test.sh, plan_scan_cli_test.sh), sourced by
# them: each counts into $passed / $failed and prints what failed; commands' output goes to
# $work/out and $work/err.

# python3 as the system installs it, when it is there: the checks start it about 25 times, and
# a version manager's shim in front of it (pyenv's) costs about a second of CPU a start.
if [ -x /usr/bin/python3 ]; then
  python3() { /usr/bin/python3 "$@"; }
fi

expect_exit() {  # expect_exit CODE DESCRIPTION -- command...
  local want=$1 what=$2
  shift 3
  "$@" >"$work/out" 2>"$work/err"
  local got=$?
  if [ "$got" -eq "$want" ]; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $what: exit $got, expected $want"
    sed 's/^/  stdout: /' "$work/out" | head -5
    sed 's/^/  stderr: /' "$work/err" | head -5
  fi
}

check() {  # check DESCRIPTION -- test-command...
  local what=$1
  shift 2
  if "$@"; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $what"
  fi
}
