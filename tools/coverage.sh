#!/usr/bin/env bash
# Line and branch coverage of the library by the unit tests (clang source-based coverage:
# -fprofile-instr-generate -fcoverage-mapping, then llvm-profdata and llvm-cov).
#   bash tools/coverage.sh [build-dir]          (default build/ci-coverage)
#   SPLINTCORE_COVERAGE_FILTER='-Realdata|Meshlab' bash tools/coverage.sh   (gtest filter)
#   bash tools/coverage.sh --report build-dir   the report alone, from the profiles a test run
#                                               of an instrumented build left there (the
#                                               asan job of tools/test.sh: it is built with
#                                               -DSPLINTCORE_COVERAGE=ON and runs ctest with
#                                               LLVM_PROFILE_FILE=build-dir/coverage-%4m.profraw)
# Prints llvm-cov's per-file report for src/ (lines, regions, branches), then the parsers'
# figures on their own (issue 9 asks for >= 95% branch coverage of every parser of outside
# bytes: JSON, the case schema, STL, PLY, OBJ, their shared text scanner, the CT readers, and
# inflate).
# The HTML report is written to <build-dir>/coverage-html. Exit status: that of the build and
# the test run; with SPLINTCORE_COVERAGE_MIN_BRANCH=95 (as tools/test.sh sets it) also 1 when a
# parser is under that branch coverage (marked "LOW" in the table).
set -u
cd "$(dirname "$0")/.."
report_only=0
if [ "${1:-}" = "--report" ]; then report_only=1; shift; fi
dir=${1:-build/ci-coverage}
par=${SPLINTCORE_JOBS:-$(nproc)}
llvm_profdata=$(command -v llvm-profdata || ls /usr/bin/llvm-profdata-* 2>/dev/null | tail -n 1)
llvm_cov=$(command -v llvm-cov || ls /usr/bin/llvm-cov-* 2>/dev/null | tail -n 1)
if [ -z "$llvm_profdata" ] || [ -z "$llvm_cov" ]; then
  echo "coverage: llvm-profdata and llvm-cov are needed (apt-get install llvm)"; exit 1
fi
rc=0
if [ "$report_only" -eq 0 ]; then
  cmake -S . -B "$dir" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug \
    -DSPLINTCORE_COVERAGE=ON >"$dir.configure.log" 2>&1 \
    || { cat "$dir.configure.log"; exit 1; }
  cmake --build "$dir" -j "$par" --target splintcore_tests >"$dir.build.log" 2>&1 \
    || { tail -n 40 "$dir.build.log"; exit 1; }
  rm -f "$dir"/coverage-*.profraw
  # The long randomised properties, the MeshLab oracle and the real dentition's tests (run
  # serially here, at -O0) add little line coverage and most of the time; the filter can be
  # widened.
  filter=${SPLINTCORE_COVERAGE_FILTER:--BooleanRandom.*:*Meshlab*:*MeshLab*:*RealData*:*.Real*}
  (cd "$dir" && LLVM_PROFILE_FILE="$PWD/coverage-%p.profraw" \
     ./tests/splintcore_tests --gtest_filter="$filter" >coverage-tests.log 2>&1)
  rc=$?
  tail -n 3 "$dir/coverage-tests.log"
elif ! ls "$dir"/coverage-*.profraw >/dev/null 2>&1; then
  echo "coverage: no profiles (coverage-*.profraw) in $dir"; exit 1
fi
"$llvm_profdata" merge -sparse "$dir"/coverage-*.profraw -o "$dir/coverage.profdata" || exit 1
objects="$dir/tests/splintcore_tests"
"$llvm_cov" report "$objects" -instr-profile="$dir/coverage.profdata" \
  -show-branch-summary "$PWD/src" 2>/dev/null | sed "s|$PWD/||" | tee "$dir/coverage-report.txt"
"$llvm_cov" show "$objects" -instr-profile="$dir/coverage.profdata" -format=html \
  -output-dir="$dir/coverage-html" -show-branches=count "$PWD/src" >/dev/null 2>&1
echo
echo "parsers (lines, branches):"
gate=0
for f in src/json/json.cpp src/design/case_file.cpp src/io/stl_read.cpp src/io/ply_read.cpp \
         src/io/obj_read.cpp src/io/mesh_text.h src/ct/ct_common.cpp src/ct/ct_nrrd.cpp \
         src/ct/ct_metaimage.cpp src/ct/ct_dicom.cpp src/ct/dicom_frames.cpp src/ct/dicom_rle.cpp \
         src/ct/jpeg_lossless.cpp src/ct/jpeg_ls.cpp src/compress/inflate.cpp \
         src/ct/jpeg2000_codestream.cpp src/ct/jpeg2000_tier1.cpp; do
  # llvm-cov report columns: Regions Missed Cover Functions Missed Executed Lines Missed Cover
  # Branches Missed Cover.
  # llvm-cov names files relative to the common prefix (src/): match either form.
  line=$(grep -E "^(src/)?${f#src/} " "$dir/coverage-report.txt")
  lines=$(echo "$line" | awk '{print $10}')
  branches=$(echo "$line" | awk '{print $13}')
  low=""
  if [ -n "${SPLINTCORE_COVERAGE_MIN_BRANCH:-}" ]; then
    b=${branches%\%}
    if [ -z "$b" ] || awk -v b="$b" -v m="$SPLINTCORE_COVERAGE_MIN_BRANCH" \
         'BEGIN { exit !(b + 0 < m + 0) }'; then
      gate=1; low="  LOW (under ${SPLINTCORE_COVERAGE_MIN_BRANCH}%)"
    fi
  fi
  printf '  %-28s lines %8s  branches %8s%s\n' "$f" "$lines" "$branches" "$low"
done
echo "HTML: $dir/coverage-html/index.html"
[ "$gate" -eq 0 ] || echo "coverage: a parser is under ${SPLINTCORE_COVERAGE_MIN_BRANCH}% branch coverage"
[ "$rc" -eq 0 ] && [ "$gate" -eq 0 ]
