#!/usr/bin/env bash
# Every test, as CI runs it: installs what the tests need when missing (apt: GoogleTest,
# MeshLab, Xvfb, clang), then builds and tests with g++ and clang++ at -O0 and -O2 (the golden
# hashes must match in all four), with ASan+UBSan, and builds the core alone with
# -fno-exceptions -fno-rtti and no platform layer, checking it pulls in no heap or exception
# symbols.
#   bash tools/test.sh            all default jobs
#   bash tools/test.sh gcc-O2     one job (gcc-O0 gcc-O2 clang-O0 clang-O2 asan core lint fuzz)
# The default list also runs (the fuzz job for 15 s per target):
#   bash tools/test.sh fuzz        libFuzzer targets (clang): replay every corpus in
#                                  fixtures/fuzz/, then run each target SPLINTCORE_FUZZ_SECONDS
#                                  (default 60) one after the other (tests/fuzz/README.md)
#   bash tools/test.sh lint        clang-tidy (.clang-tidy) and cppcheck over src/ include/
#                                  tools/; any finding fails
# Optional jobs, not in the default list (cross builds run under qemu-user, about 27 min):
#   bash tools/test.sh coverage    llvm-cov line and branch coverage per file (tools/coverage.sh)
#   bash tools/test.sh aarch64 armv7
#   They run the suite except the long randomised Boolean properties (BooleanRandom.Phantom*,
#   about 8 min under qemu, run natively by the default jobs); SPLINTCORE_CROSS_FULL=1 runs all.
set -u
cd "$(dirname "$0")/.."
. tools/deps.sh
ensure_packages g++ clang cmake make pkg-config python3 libgtest-dev meshlab xvfb xauth || exit 1

mkdir -p build
# The default list ends with static analysis and a short fuzz of every target (15 s each,
# every corpus replayed); SPLINTCORE_FUZZ_SECONDS=3600 bash tools/test.sh fuzz runs them longer.
if [ $# -eq 0 ]; then
  export SPLINTCORE_FUZZ_SECONDS=${SPLINTCORE_FUZZ_SECONDS:-15}
fi
jobs=${*:-gcc-O0 gcc-O2 clang-O0 clang-O2 asan core lint fuzz}
total_passed=0
total_failed=0
failed_jobs=""
par=$(nproc)

run_ctest_job() {  # name cxx build_type extra-cmake-args...
  local name=$1 cxx=$2 type=$3
  shift 3
  local dir=build/ci-$name
  echo "=== $name: $cxx $type $*"
  if ! cmake -S . -B "$dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE="$type" "$@" \
       >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  if ! cmake --build "$dir" -j "$par" >"$dir.build.log" 2>&1; then
    tail -n 40 "$dir.build.log"
    return 1
  fi
  local log=$dir.ctest.log
  (cd "$dir" && ctest --output-on-failure -j "$par" --timeout 600) >"$log" 2>&1
  local rc=$?
  grep -E "tests passed|tests failed|Failed|\*\*\*" "$log" | tail -n 15
  local n failed
  n=$(grep -oE "out of [0-9]+" "$log" | tail -n 1 | grep -oE "[0-9]+")
  failed=$(grep -oE "[0-9]+ tests failed" "$log" | tail -n 1 | grep -oE "^[0-9]+")
  n=${n:-0}
  failed=${failed:-0}
  total_passed=$((total_passed + n - failed))
  total_failed=$((total_failed + failed))
  [ "$rc" -eq 0 ] || tail -n 60 "$log"
  return $rc
}

cross_table=""
# The golden-file tests (pinned SHA-256 of output bytes), run first on their own.
cross_golden='^(Golden\.|BooleanGolden\.|Phantom\.BytesAreDeterministicAndPinned|MarchingCubes\.GoldenHashIsTheSameEverywhere|Sha256\.)'

cross_job() {  # name toolchain-file cross-triple
  local name=$1 toolchain=$2 triple=$3
  local dir=build/ci-$name
  echo "=== $name: $toolchain, tests under qemu-user"
  ensure_packages "g++-$triple" qemu-user libgtest-dev || return 1
  if ! cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$toolchain" -DCMAKE_BUILD_TYPE=Release \
       -DSPLINTCORE_GTEST_SOURCE_DIR=/usr/src/googletest >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  if ! cmake --build "$dir" -j "$par" >"$dir.build.log" 2>&1; then
    tail -n 40 "$dir.build.log"
    return 1
  fi
  local glog=$dir.golden.log log=$dir.ctest.log exclude="$cross_golden"
  [ "${SPLINTCORE_CROSS_FULL:-0}" = 1 ] || exclude="$exclude|^BooleanRandom\.Phantom"
  (cd "$dir" && ctest --output-on-failure -j "$par" --timeout 900 -R "$cross_golden") >"$glog" 2>&1
  local grc=$?
  (cd "$dir" && ctest --output-on-failure -j "$par" --timeout 900 -E "$exclude") >"$log" 2>&1
  local rc=$?
  local golden=no n=0 failed=0 f
  for f in "$glog" "$log"; do
    grep -E "tests passed|tests failed|\*\*\*" "$f" | tail -n 15
    n=$((n + $(grep -oE "out of [0-9]+" "$f" | tail -n 1 | grep -oE "[0-9]+" || echo 0)))
    failed=$((failed + $(grep -oE "[0-9]+ tests failed" "$f" | tail -n 1 | grep -oE "^[0-9]+" || echo 0)))
  done
  # yes only when every pinned-hash test ran and passed (there are at least 8 of them).
  if [ "$grc" -eq 0 ] && [ "$(grep -cE "Test +#.*Passed" "$glog")" -ge 8 ]; then golden=yes; fi
  total_passed=$((total_passed + n - failed))
  total_failed=$((total_failed + failed))
  [ "$rc" -eq 0 ] || tail -n 60 "$log"
  [ "$grc" -eq 0 ] || tail -n 60 "$glog"
  local sz
  sz=$("$triple-size" -t "$dir/libsplintcore.a" | tail -n 1 | awk '{print "text " $1 " data " $2 " bss " $3}')
  cross_table="$cross_table$(printf '%-8s %-24s tests passed %4d/%-4d golden hashes equal: %-3s libsplintcore.a: %s' \
    "$name" "$triple" $((n - failed)) "$n" "$golden" "$sz")"$'\n'
  [ "$rc" -eq 0 ] && [ "$grc" -eq 0 ]
}

core_job() {
  # The core alone, as firmware builds it: no platform layer, no exceptions, no RTTI anywhere.
  local dir=build/ci-core
  echo "=== core: -fno-exceptions -fno-rtti, SPLINTCORE_WITH_PLATFORM=OFF"
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DSPLINTCORE_WITH_PLATFORM=OFF \
    -DSPLINTCORE_BUILD_TESTS=OFF -DSPLINTCORE_BUILD_TOOLS=OFF \
    -DCMAKE_CXX_FLAGS="-fno-exceptions -fno-rtti" >"$dir.configure.log" 2>&1 || return 1
  cmake --build "$dir" -j "$par" >"$dir.build.log" 2>&1 || { tail -n 40 "$dir.build.log"; return 1; }
  local undefined
  undefined=$(nm -C --undefined-only "$dir/libsplintcore.a" | grep -E \
    "operator new|operator delete|\bmalloc\b|\bcalloc\b|\brealloc\b|__cxa_throw|__cxa_allocate_exception|__gxx_personality|\bprintf\b|\bfprintf\b|\bsnprintf\b" \
    | sort -u)
  if [ -n "$undefined" ]; then
    echo "core pulls in forbidden symbols:"
    echo "$undefined"
    total_failed=$((total_failed + 1))
    return 1
  fi
  echo "core: no heap, exception or printf symbols; $(size -t "$dir/libsplintcore.a" | tail -n 1 | awk '{print "text " $1 " data " $2 " bss " $3 " bytes"}')"
  total_passed=$((total_passed + 1))
  return 0
}

fuzz_job() {
  # libFuzzer targets: build (clang, -fsanitize=fuzzer,address,undefined), replay every corpus
  # (the fuzz.*.corpus tests), then fuzz each target for SPLINTCORE_FUZZ_SECONDS, one at a time.
  # New inputs go to build/ci-fuzz/corpus/<target> (not into fixtures/); a crash leaves its
  # input in build/ci-fuzz/artifacts/<target>/ and fails the job.
  local dir=build/ci-fuzz seconds=${SPLINTCORE_FUZZ_SECONDS:-60}
  echo "=== fuzz: clang++ -fsanitize=fuzzer,address,undefined, ${seconds}s per target"
  ensure_packages clang libclang-rt-14-dev || return 1  # the libFuzzer and sanitizer runtimes
  if ! cmake -S . -B "$dir" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
       -DSPLINTCORE_FUZZ=ON >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  local targets
  # Every target the SPLINTCORE_FUZZ block declares (ours and the CT readers').
  targets=$(sed -n 's/^ *foreach(splintcore_\(ct_\)\{0,1\}fuzz_name \(.*\))/\2/p' tests/CMakeLists.txt)
  local t list=""
  for t in $targets; do list="$list splintcore_fuzz_$t"; done
  if ! cmake --build "$dir" -j "$par" --target $list >"$dir.build.log" 2>&1; then
    tail -n 40 "$dir.build.log"; return 1
  fi
  local rc=0 log=$dir.ctest.log
  (cd "$dir" && ctest --output-on-failure -R '^fuzz\.' --timeout 900) >"$log" 2>&1 || rc=1
  grep -E "tests passed|tests failed|\*\*\*" "$log" | tail -n 15
  local n failed
  n=$(grep -oE "out of [0-9]+" "$log" | tail -n 1 | grep -oE "[0-9]+")
  failed=$(grep -oE "[0-9]+ tests failed" "$log" | tail -n 1 | grep -oE "^[0-9]+")
  total_passed=$((total_passed + ${n:-0} - ${failed:-0}))
  total_failed=$((total_failed + ${failed:-0}))
  for t in $targets; do
    mkdir -p "$dir/corpus/$t" "$dir/artifacts/$t"
    "$dir/tests/splintcore_fuzz_$t" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$dir/artifacts/$t/" "$dir/corpus/$t" \
      "fixtures/fuzz/$t" >"$dir/fuzz-$t.log" 2>&1
    local frc=$?
    printf 'fuzz %-10s %10s execs %6s exec/s  %s\n' "$t" \
      "$(grep -oE '^stat::number_of_executed_units: [0-9]+' "$dir/fuzz-$t.log" | grep -oE '[0-9]+$')" \
      "$(grep -oE '^stat::average_exec_per_sec: [0-9]+' "$dir/fuzz-$t.log" | grep -oE '[0-9]+$')" \
      "$([ $frc -eq 0 ] && echo ok || echo "FAILED: see $dir/fuzz-$t.log")"
    if [ $frc -ne 0 ]; then
      rc=1; total_failed=$((total_failed + 1)); grep -E "^==|ERROR|SUMMARY" "$dir/fuzz-$t.log" | head -n 20
    else
      total_passed=$((total_passed + 1))
    fi
  done
  return $rc
}

lint_job() {
  # clang-tidy with the checked-in .clang-tidy, and cppcheck, over our own sources; a finding
  # from either fails the job. compile_commands.json comes from a configure-only build dir.
  local dir=build/ci-lint
  echo "=== lint: clang-tidy (.clang-tidy) and cppcheck over src/ include/ tools/"
  ensure_packages clang clang-tidy cppcheck || return 1
  if ! cmake -S . -B "$dir" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release \
       -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  local files rc=0
  files=$(ls src/*/*.cpp tools/common/*.cpp tools/splintcore/*.cpp tools/bench/*.cpp 2>/dev/null)
  # Headers are checked through the sources that include them (HeaderFilterRegex).
  if ! printf '%s\n' $files | xargs -P "$par" -n 4 clang-tidy -p "$dir" --quiet \
       >"$dir.clang-tidy.log" 2>&1; then
    rc=1
  fi
  if grep -qE "(warning|error):" "$dir.clang-tidy.log"; then
    rc=1; grep -E "(warning|error):" "$dir.clang-tidy.log" | sort -u | head -n 40
  fi
  echo "clang-tidy: $(grep -cE "(warning|error):" "$dir.clang-tidy.log") findings in $(echo $files | wc -w) files"
  # cppcheck: warnings, performance and portability (style is clang-tidy's and the reviewer's).
  # Suppressions are listed in tools/cppcheck-suppressions.txt with a reason each.
  if ! cppcheck --project="$dir/compile_commands.json" --enable=warning,performance,portability \
       --inline-suppr --suppressions-list=tools/cppcheck-suppressions.txt --error-exitcode=1 \
       --quiet -j "$par" -i "$dir" -i tests --template='{file}:{line}: {severity} ({id}): {message}' \
       >"$dir.cppcheck.log" 2>&1; then
    rc=1
  fi
  grep -vE "^$|^Checking|files checked" "$dir.cppcheck.log" | head -n 40
  echo "cppcheck: $(grep -cE ": (error|warning|performance|portability) " "$dir.cppcheck.log") findings"
  if [ $rc -eq 0 ]; then total_passed=$((total_passed + 1)); else total_failed=$((total_failed + 1)); fi
  return $rc
}

coverage_job() {
  echo "=== coverage: clang -fprofile-instr-generate -fcoverage-mapping, llvm-cov report"
  ensure_packages clang llvm || return 1
  if SPLINTCORE_JOBS="$par" bash tools/coverage.sh build/ci-coverage; then
    total_passed=$((total_passed + 1))
  else
    total_failed=$((total_failed + 1)); return 1
  fi
}

for job in $jobs; do
  case $job in
    gcc-O0) run_ctest_job "$job" g++ Debug ;;
    gcc-O2) run_ctest_job "$job" g++ Release ;;
    clang-O0) run_ctest_job "$job" clang++ Debug ;;
    clang-O2) run_ctest_job "$job" clang++ Release ;;
    asan) run_ctest_job "$job" g++ RelWithDebInfo -DSPLINTCORE_SANITIZE=ON ;;
    core) core_job ;;
    fuzz) fuzz_job ;;
    lint) lint_job ;;
    coverage) coverage_job ;;
    aarch64) cross_job "$job" cmake/toolchain-aarch64-linux-gnu.cmake aarch64-linux-gnu ;;
    armv7) cross_job "$job" cmake/toolchain-arm-linux-gnueabihf.cmake arm-linux-gnueabihf ;;
    *) echo "unknown job $job"; false ;;
  esac || failed_jobs="$failed_jobs $job"
done

echo
if [ -n "$cross_table" ]; then
  echo "target   triple                   (x86-64 golden hashes: fixtures/golden.sha256 and the tests)"
  printf '%s' "$cross_table"
fi
if [ -n "$failed_jobs" ]; then
  echo "failed jobs:$failed_jobs"
fi
echo "$total_passed passed, $total_failed failed"
[ -z "$failed_jobs" ]
