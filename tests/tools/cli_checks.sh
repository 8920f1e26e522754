# The checks of the program's shell tests (cli_test.sh, plan_scan_cli_test.sh), sourced by
# them: each counts into $passed / $failed and prints what failed; commands' output goes to
# $work/out and $work/err.

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
