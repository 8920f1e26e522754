#!/usr/bin/env bash
# Every test, as CI runs it: installs what the tests need when missing (apt: GoogleTest,
# MeshLab, Xvfb, clang), then builds and tests with g++ and clang++ at -O0 and -O2 (the golden
# hashes must match in all four), with ASan+UBSan, and builds the core alone with
# -fno-exceptions -fno-rtti and no platform layer, checking it pulls in no heap or exception
# symbols.
#   bash tools/test.sh            all default jobs
#   bash tools/test.sh gcc-O2     one job (gcc-O0 gcc-O2 clang-O0 clang-O2 asan core baremetal
#                                 cross-golden coverage lint fuzz)
# The default list also runs (the fuzz job for 5 s per target):
#   bash tools/test.sh fuzz        libFuzzer targets (clang): replay every corpus in
#                                  fixtures/fuzz/, then run each target SPLINTCORE_FUZZ_SECONDS
#                                  (default 60) one after the other (tests/fuzz/README.md)
#   bash tools/test.sh lint        the floors (tools/check_layers.py), the layout
#                                  (clang-format), function lengths (tools/function_sizes.py),
#                                  clang-tidy (.clang-tidy) and cppcheck over src/ include/
#                                  tools/; any finding fails
#   bash tools/test.sh baremetal   the core for Cortex-M7 (arm-none-eabi, no platform layer),
#                                  its link checked and sized per module, and the firmware
#                                  example (tools/firmware) run under qemu-system-arm -M
#                                  mps2-an500: its SHA-256 next to the x86-64 golden
#                                  (docs/embedding.md; about 2.5 min to build from a clean
#                                  build dir, then QEMU: 99 s on a quiet machine (2026-11-30),
#                                  mostly the blockout at 0.1 mm, in the background beside the
#                                  jobs after it)
#   bash tools/test.sh cross-golden   (or aarch64-golden, armv7-golden) AArch64 and ARMv7 cross
#                                  builds, the golden-hash tests (every pinned output) and the
#                                  firmware example as a process under qemu-user, with the
#                                  table: target, tests passed, golden hashes equal, code size,
#                                  peak arena (about 4 min for both)
#   bash tools/test.sh coverage    llvm-cov line and branch coverage per file (tools/coverage.sh);
#                                  fails when a parser is under 95% branch coverage. In the
#                                  default list the asan job is built instrumented and gives
#                                  this report from its own test run (about 2-3 min from a
#                                  clean build dir on a quiet machine)
# Optional jobs, not in the default list (cross builds run under qemu-user, about 27 min):
#   bash tools/test.sh aarch64 armv7
#   bash tools/test.sh tsan        ThreadSanitizer: the executor's tests and the tool at 2
#                                  threads on the fixture cases (about 5 min)
#   They run the suite except the long randomised Boolean properties (BooleanRandom.Phantom*,
#   about 8 min under qemu, run natively by the default jobs); SPLINTCORE_CROSS_FULL=1 runs all.
set -u
cd "$(dirname "$0")/.."
. tools/deps.sh

# What each job installs when missing (apt), beside the build tools every job needs.
job_packages() {  # job
  case $1 in
    gcc-*|core) ;;
    clang-*) echo clang ;;
    asan|coverage) echo clang llvm libclang-rt-14-dev ;;
    tsan|fuzz) echo clang libclang-rt-14-dev ;;
    baremetal) echo gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib \
                    binutils-arm-none-eabi qemu-system-arm ;;
    aarch64*) echo g++-aarch64-linux-gnu qemu-user ;;
    armv7*) echo g++-arm-linux-gnueabihf qemu-user ;;
    cross-golden) echo g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user ;;
    lint) echo clang clang-tidy clang-format cppcheck universal-ctags ;;
  esac
}
# What the full test suite needs besides (the MeshLab oracle's tests, in a virtual display).
suite_packages="meshlab xvfb xauth"

# The build tools first; the rest of what the jobs need is installed in the background while
# the first job builds (on a fresh Debian 12 machine the installs took about 3.5 minutes, one
# after another between the jobs). need_packages waits for that install before it looks.
apt_bg=""
apt_bg_log=build/apt-background.log
ensure_packages g++ cmake make pkg-config python3 libgtest-dev || exit 1
need_packages() {  # pkg...
  packages_installed "$@" && return 0
  if [ -n "$apt_bg" ]; then
    wait "$apt_bg" || echo "the background install failed ($apt_bg_log): installing here"
    apt_bg=""
  fi
  ensure_packages "$@"
}

mkdir -p build
# The default list ends with static analysis and a short fuzz of every target (5 s each,
# every corpus replayed); SPLINTCORE_FUZZ_SECONDS=3600 bash tools/test.sh fuzz runs them longer.
if [ $# -eq 0 ]; then
  export SPLINTCORE_FUZZ_SECONDS=${SPLINTCORE_FUZZ_SECONDS:-5}
fi
jobs=${*:-gcc-O0 gcc-O2 clang-O0 clang-O2 asan core baremetal cross-golden lint fuzz}
total_passed=0
total_failed=0
failed_jobs=""
par=$(nproc)

# The long randomised properties (the Boolean on random phantom jaws and on the real teeth:
# about 36 s in Release, several minutes at -O0 and under ASan) and the sampled error of the
# experimental sweep decimation (about 35 s in Release: the error sampled at 15 points a
# triangle, both ways, twice) run in the gcc-O2 job only;
# the other compiler jobs and asan run every other test (the golden hashes among them).
slow_properties='^BooleanRandom\.|^SweepDecimate\.StaysWithin'
# The tests on the real dentition (../shared/realdata, 887k triangles: skipped where it is
# absent) run in the -O2 jobs only; at -O0 and under ASan they are the slowest tests (under
# ASan, -O1, a loaded machine: 215 s of test time, 103 s for OutlineRealData.FrameInvariance) and
# exercise the same code as the phantom tests next to them.
realdata_tests='RealData\.|\.Real[A-Z]'
# The experimental sweep decimation's bytes across slab sizes and threads, and its blockout
# under the independent line check, run at -O2 only (gcc-O2, and clang-O2 for the bytes): at -O0
# and under ASan they were the longest tests (132 s and 124 s at clang -O0, 66 s and 40 s under
# ASan), and the decimation's own arena test still runs under ASan.
slow_decimation='^SweepDecimate\.SameBytes|^Blockout\.DecimatedSweep'
# ASan also leaves to the other jobs four tests whose time under it is mostly the test's own
# brute force or thread sweep, with no parser in reach: the QEM decimation's two distance
# properties (an oracle over every input vertex: 23 and 10 s under ASan) and two byte tests at
# 1, 2, 3 and 8 threads (21 and 14 s; the four byte jobs and gcc-O2 run them). Their code runs
# under ASan in the smaller tests beside them.
asan_long='^DecimateQem\.MaxDistance(Holds|Carries)|^MeshPairDistance\.SplitSearchAnswers'
asan_long="$asan_long|^Outline\.SameBitsAtEveryThreadCount"

# The whole suite runs with g++ -O2 (every test) and with clang++ -O1, ASan, UBSan and coverage
# instrumentation (every test but the groups above; its profiles give the coverage report).
# g++ -O0, clang++ -O0 and clang++ -O2 run the tests that pin or compare output bytes (the
# goldens, same bytes at every thread count and run, the command line and the C API): the
# build with -Werror and the bytes are what those builds add; running the rest a third and a
# fourth time took about 6 minutes of CI each.
# Those builds compile only the test files that hold these tests (-DSPLINTCORE_BYTES_ONLY=ON,
# tests/CMakeLists.txt; about two thirds of each build's time was the tests' compile); a bytes
# job that finds the gcc-O2 job's full build checks it has every such test.
# (Until 2026-12 the clang -O0 build ran the whole suite for the coverage, and the ASan build
# again: one instrumented build and one run now serve both. A clang -O0 run of the byte tests
# and the parsers' own tests alone was too little for the gate: case_file.cpp fell to 89.8%,
# as part of it is reached only through the pipeline's tests.)
bytes_tests='Golden|SameBytes|SameBits|Determinis|Pinned|Thread|^cli\.|^capi\.|^Sha256\.'
bytes_names() {  # build-dir: the names of the byte tests a job runs there, sorted
  (cd "$1" && ctest -N -R "$bytes_tests" -E "$slow_properties|$realdata_tests") |
    sed -n 's/^ *Test *#[0-9]*: //p' | sort
}

run_ctest_job() {  # name cxx build_type extra-cmake-args...
  local name=$1 cxx=$2 type=$3
  shift 3
  local dir=build/ci-$name exclude=() bytes_only=0
  case $name in
    gcc-O2) ;;
    gcc-O0) exclude=(-R "$bytes_tests" -E "$slow_properties|$realdata_tests|$slow_decimation")
            bytes_only=1 ;;
    clang-O2) exclude=(-R "$bytes_tests" -E "$slow_properties|$realdata_tests")
              bytes_only=1 ;;
    clang-O0) exclude=(-R "$bytes_tests" -E "$slow_properties|$realdata_tests|$slow_decimation")
              bytes_only=1 ;;
    asan) exclude=(-E "$slow_properties|$realdata_tests|$slow_decimation|$asan_long") ;;
    tsan) exclude=(-R 'Thread|Parallel|Executor|ArenaMemory|AtomicFile|InTasks') ;;  # those that run threads
    *) exclude=(-E "$slow_properties|$realdata_tests") ;;
  esac
  echo "=== $name: $cxx $type $*"
  need_packages $(job_packages "$name") || return 1
  if ! cmake -S . -B "$dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE="$type" "$@" \
       >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  if ! cmake --build "$dir" -j "$par" >"$dir.build.log" 2>&1; then
    tail -n 40 "$dir.build.log"
    return 1
  fi
  local log=$dir.ctest.log
  [ "$bytes_only" = 1 ] || need_packages $suite_packages || return 1
  (cd "$dir" && ${ctest_profile:+env LLVM_PROFILE_FILE="$ctest_profile"} \
     ctest --output-on-failure -j "$par" --timeout 600 "${exclude[@]}") >"$log" 2>&1
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
  if [ "$bytes_only" = 1 ] && [ -f build/ci-gcc-O2/CTestTestfile.cmake ]; then
    local missing
    missing=$(comm -23 <(bytes_names build/ci-gcc-O2) <(bytes_names "$dir"))
    if [ -n "$missing" ]; then
      echo "$name lacks byte tests the full build has (add their files to SPLINTCORE_BYTES_ONLY" \
        "in tests/CMakeLists.txt):" $missing
      total_failed=$((total_failed + 1)); rc=1
    fi
  fi
  return $rc
}

cross_table=""
# The golden-file tests (pinned SHA-256 of output bytes), run first on their own.
cross_golden='^(Golden\.|BooleanGolden\.|DesignGolden\.|CtGolden\.|Phantom\.BytesAreDeterministicAndPinned|MarchingCubes\.GoldenHashIsTheSameEverywhere|Sha256\.|DeterministicMinMax\.)'

firmware_golden='^DesignGolden\.FirmwareBlockout'

cross_job() {  # name toolchain-file cross-triple
  local name=$1 toolchain=$2 triple=$3
  local dir=build/ci-$name
  echo "=== $name: $toolchain, tests under qemu-user"
  need_packages $(job_packages "$name") || return 1
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
  cross_table="$cross_table$(printf '%-14s %-22s tests passed %4d/%-4d golden hashes equal: %-3s libsplintcore.a: %s' \
    "$name" "$triple" $((n - failed)) "$n" "$golden" "$sz")"$'\n'
  [ "$rc" -eq 0 ] && [ "$grc" -eq 0 ]
}

# ---- bare metal, and the golden hashes on AArch64/ARMv7 (issue 10, docs/embedding.md) --------
# The firmware example (tools/firmware) builds the paper-scale base, the design (base minus the
# phantom jaws of `splintcore phantom --triangles 6000`) and the design with blockout on a
# 0.1 mm grid, streaming each as binary STL into SHA-256, in a static arena of 16 MiB. Besides
# the board it is built as a Linux process (hosted.c) against a libsplintcore.a already built
# for that CPU: the same golden hashes, and the cross jobs' peak arena figures.
golden_hash() { grep -E " $1\$" fixtures/golden.sha256 | cut -d' ' -f1; }
fw_field() {  # log stage field: a field of the example's "result <stage> ..." line
  grep -E "^result $2 " "$1" 2>/dev/null | grep -oE " $3=[0-9a-f]+" | cut -d= -f2
}

build_firmware_twin() {  # cc cxx libsplintcore.a jaws-dir out
  local cc=$1 cxx=$2 lib=$3 jaws=$4 out=$5
  local defs=("-DSPLINTCORE_FIRMWARE_CASE=\"$PWD/fixtures/cases/paper_scale.json\""
    -DSPLINTCORE_FIRMWARE_WITH_JAWS=1 "-DSPLINTCORE_FIRMWARE_MAXILLA=\"$jaws/maxilla.stl\""
    "-DSPLINTCORE_FIRMWARE_MANDIBLE=\"$jaws/mandible.stl\"")
  "$cc" -O2 -Wall -Wextra -Werror -c tools/firmware/hosted.c -o "$out.hosted.o" &&
    "$cxx" -std=c++17 -O2 -Wall -Wextra -Werror -fno-exceptions -fno-rtti -ffp-contract=off \
      -Iinclude "${defs[@]}" tools/firmware/main.cpp tools/firmware/assets.S "$out.hosted.o" \
      "$lib" -pthread -o "$out"
}

# Compares the example's stages in `log` with the golden hashes (base, design, and the blockout
# on a 0.1 mm grid: DesignGolden.FirmwareBlockoutTenthMillimetreIn16MiB pins it on x86-64).
# Prints one line per stage; sets fw_equal (stages equal) and fw_peak (the largest arena
# high-water mark).
fw_equal=0
fw_peak=0
fw_host=build/ci-baremetal-host  # where the x86-64 run of the example is (baremetal_job)
compare_firmware_log() {  # label log
  local label=$1 log=$2 stage h ref what peak
  fw_equal=0
  fw_peak=0
  for stage in base design blockout; do
    h=$(fw_field "$log" "$stage" sha256)
    case $stage in
      base) what="golden base:cases/paper_scale.json"; ref=$(golden_hash "base:cases/paper_scale.json") ;;
      design) what="golden boolean:paper_scale-phantom6000"; ref=$(golden_hash "boolean:paper_scale-phantom6000") ;;
      *) what="golden design:blockout-0.1mm-paper_scale-phantom6000"
         ref=$(golden_hash "design:blockout-0.1mm-paper_scale-phantom6000") ;;
    esac
    peak=$(fw_field "$log" "$stage" arena_high_water)
    [ -n "$peak" ] && [ "$peak" -gt "$fw_peak" ] && fw_peak=$peak
    printf '%-10s %-9s %-64s %8s B  peak arena %9s B  %s: %s\n' "$label" "$stage" "${h:-(none)}" \
      "$(fw_field "$log" "$stage" bytes)" "${peak:-?}" "$what" \
      "$([ -z "$ref" ] && echo "no reference" || { [ "$h" = "$ref" ] && echo "equal" || echo "DIFFERENT ($ref)"; })"
    if [ -n "$h" ] && [ "$h" = "$ref" ]; then fw_equal=$((fw_equal + 1)); fi
  done
}

baremetal_job() {
  local dir=build/ci-baremetal host=$fw_host t0=$SECONDS
  echo "=== baremetal: Cortex-M7 core (cmake/toolchain-cortex-m7.cmake, -fno-exceptions -fno-rtti," \
    "no platform layer), the firmware example under qemu-system-arm -M mps2-an500"
  need_packages $(job_packages baremetal) || return 1
  # Host side: `splintcore phantom` writes the jaws the example embeds; the example as an
  # x86-64 process is the reference for the blockout stage. The gcc-O2 job's build is the same
  # configuration (g++, Release): it serves when it is there, else a tree of its own is built.
  if [ -x build/ci-gcc-O2/tools/splintcore ] && [ -f build/ci-gcc-O2/libsplintcore.a ]; then
    host=build/ci-gcc-O2
  else
    if ! cmake -S . -B "$host" -DCMAKE_BUILD_TYPE=Release -DSPLINTCORE_BUILD_TESTS=OFF \
         >"$host.configure.log" 2>&1; then
      mkdir -p "$host"; cat "$host.configure.log"; return 1
    fi
    cmake --build "$host" -j "$par" --target splintcore_tool >"$host.build.log" 2>&1 ||
      { tail -n 40 "$host.build.log"; return 1; }
  fi
  fw_host=$host
  mkdir -p "$host/jaws"
  "$host/tools/splintcore" phantom --triangles 6000 -o "$host/jaws" >"$host/jaws.log" 2>&1 ||
    { cat "$host/jaws.log"; return 1; }
  build_firmware_twin gcc g++ "$host/libsplintcore.a" "$PWD/$host/jaws" \
    "$host/firmware_example" >"$host.example.log" 2>&1 || { cat "$host.example.log"; return 1; }
  "$host/firmware_example" >"$host/firmware_example.log" 2>&1 ||
    { cat "$host/firmware_example.log"; return 1; }
  # The board: the core and the example, one image.
  if ! cmake -S tools/firmware -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$PWD/cmake/toolchain-cortex-m7.cmake" \
       -DCMAKE_BUILD_TYPE=Release -DSPLINTCORE_FIRMWARE_JAWS_DIR="$PWD/$host/jaws" \
       >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  cmake --build "$dir" -j "$par" >"$dir.build.log" 2>&1 || { tail -n 40 "$dir.build.log"; return 1; }
  local elf=$dir/splintcore_firmware.elf lib=$dir/splintcore/libsplintcore.a rc=0
  local build_seconds=$((SECONDS - t0))
  # Link inspection: heap, exceptions, RTTI support and printf must not be referenced by the
  # core, nor be anywhere in the image (the example's start-up has its own output and abort).
  local forbidden='^(malloc|free|calloc|realloc|_(malloc|free|calloc|realloc)_r|_sbrk(_r)?|_Zn[wa].*|_Zd[la].*|__cxa_.*|_Unwind_.*|__gxx_personality.*|__aeabi_unwind_cpp_pr[0-9]|_?[a-z]*printf(_r)?|_?v?fi?printf(_r)?|_printf_[a-z]+|puts|fputs|__sinit)$'
  local in_core in_image
  in_core=$(arm-none-eabi-nm --undefined-only "$lib" | awk 'NF > 1 {print $NF}' | grep -E "$forbidden" | sort -u)
  in_image=$(arm-none-eabi-nm "$elf" | awk '{print $NF}' | grep -E "$forbidden" | sort -u)
  if [ -n "$in_core$in_image" ]; then
    echo "forbidden symbols: core references: ${in_core:-none}; in the image: ${in_image:-none}"
    rc=1
  else
    echo "link check: no malloc/free/operator new/delete, __cxa_*, _Unwind_*, personality or printf-family symbol referenced by libsplintcore.a or present in $elf"
  fi
  echo "core undefined symbols outside splintcore: $(arm-none-eabi-nm --undefined-only "$lib" | awk 'NF > 1 {print $NF}' | grep -vE '^_ZN?K?10splintcore' | sort -u | tr '\n' ' ')"
  echo "code size per module (arm-none-eabi-size; bytes):"
  python3 tools/firmware/size_report.py arm-none-eabi-size "$dir/splintcore/CMakeFiles/splintcore.dir" \
    "$dir/splintcore_firmware.map" | tee "$dir/size.txt" | grep -v "^linked core text"
  arm-none-eabi-size "$elf" | sed 's/^/image: /'
  # The board's run: the blockout at 0.1 mm is most of it, 99 s of emulated Cortex-M7 on one
  # core here when quiet (several times that beside other builds: hence the long timeout).
  # Unless this is the last job it runs in the background beside the next jobs
  # (baremetal_finish after the list, its result reported there).
  bm_dir=$dir bm_lib=$lib bm_host=$host bm_rc=$rc bm_t0=$t0 bm_build_seconds=$build_seconds
  # Detached (not a child of this shell: the fuzz job's `wait` must not wait for it); its exit
  # status and seconds go to qemu.rc.
  rm -f "$dir/qemu.rc"
  ( (start=$SECONDS
     timeout 1500 qemu-system-arm -M mps2-an500 -nographic -monitor none -serial none \
       -semihosting-config enable=on,target=native -kernel "$elf" >"$dir/qemu.log" 2>&1
     echo "$? $((SECONDS - start))" >"$dir/qemu.rc") & )
  bm_pending=1
  if [ "${bm_defer:-0}" = 1 ]; then
    echo "baremetal: QEMU runs in the background; its result comes after the last job"
    return $rc
  fi
  baremetal_finish
}

baremetal_finish() {  # the second half of baremetal_job: the board's output compared
  local dir=$bm_dir lib=$bm_lib host=$bm_host rc=$bm_rc qlog=$bm_dir/qemu.log waited=0
  while [ ! -s "$dir/qemu.rc" ] && [ "$waited" -lt 1600 ]; do
    sleep 2
    waited=$((waited + 2))
  done
  local qrc qemu_seconds
  read -r qrc qemu_seconds <"$dir/qemu.rc" 2>/dev/null || qrc=124
  bm_pending=0
  local build_seconds=$bm_build_seconds t0=$bm_t0
  grep -E "^(splintcore|arena|stack|error|assert)" "$qlog"
  [ $qrc -eq 0 ] || { echo "qemu-system-arm exited with $qrc"; tail -n 20 "$qlog"; rc=1; }
  compare_firmware_log cortex-m7 "$qlog"
  local m7_equal=$fw_equal m7_peak=$fw_peak
  compare_firmware_log x86-64 "$host/firmware_example.log"
  [ "$m7_equal" -eq 3 ] && [ "$fw_equal" -eq 3 ] || rc=1
  echo "baremetal: build ${build_seconds}s, qemu ${qemu_seconds:-?}s, until its result $((SECONDS - t0))s"
  total_passed=$((total_passed + m7_equal + (rc == 0 ? 1 : 0)))
  total_failed=$((total_failed + 3 - m7_equal + (rc == 0 ? 0 : 1)))
  cross_table="$cross_table$(printf '%-14s %-22s tests passed %4d/%-4d golden hashes equal: %-3s code: core text %s B linked (%s B in libsplintcore.a)  peak arena %s B' \
    baremetal "cortex-m7 mps2-an500" "$m7_equal" 3 "$([ "$m7_equal" -eq 3 ] && echo yes || echo no)" \
    "$(sed -n 's/^linked core text //p' "$dir/size.txt")" \
    "$(arm-none-eabi-size -t "$lib" | tail -n 1 | awk '{print $1}')" "$m7_peak")"$'\n'
  return $rc
}

# Golden-only cross job: the golden-hash tests (cross_golden above) and the firmware example
# as a process, under qemu-user; builds only the tests binary and the splintcore tool.
cross_golden_job() {  # name toolchain-file cross-triple qemu
  local name=$1 toolchain=$2 triple=$3 qemu=$4
  local dir=build/ci-$name t0=$SECONDS
  echo "=== $name: $toolchain, the golden-hash tests and the firmware example under $qemu"
  need_packages $(job_packages "$name") || return 1
  # SPLINTCORE_CROSS_WERROR=OFF: warnings do not stop the build (to see the hashes while a
  # 32-bit conversion warning is being fixed); the default keeps -Werror.
  if ! cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$toolchain" -DCMAKE_BUILD_TYPE=Release \
       -DSPLINTCORE_GTEST_SOURCE_DIR=/usr/src/googletest -DSPLINTCORE_GOLDEN_ONLY=ON \
       -DSPLINTCORE_WERROR="${SPLINTCORE_CROSS_WERROR:-ON}" >"$dir.configure.log" 2>&1; then
    mkdir -p "$dir"; cat "$dir.configure.log"; return 1
  fi
  if ! cmake --build "$dir" -j "$par" --target splintcore_tests splintcore_tool \
       >"$dir.build.log" 2>&1; then
    tail -n 40 "$dir.build.log"
    return 1
  fi
  local build_seconds=$((SECONDS - t0)) rc=0 glog=$dir.golden.log
  # The firmware blockout's golden test is left out: the example run below computes the same
  # design on this CPU and compares it with the same golden hash (about a minute less each).
  (cd "$dir" && ctest --output-on-failure -j "$par" --timeout 900 -R "$cross_golden" \
    -E "$firmware_golden") >"$glog" 2>&1 || rc=1
  grep -E "tests passed|tests failed|\*\*\*" "$glog" | tail -n 15
  local n failed
  n=$(grep -oE "out of [0-9]+" "$glog" | tail -n 1 | grep -oE "[0-9]+")
  failed=$(grep -oE "[0-9]+ tests failed" "$glog" | tail -n 1 | grep -oE "^[0-9]+")
  n=${n:-0}
  failed=${failed:-0}
  [ "$n" -ge 8 ] || rc=1  # every pinned-hash test ran (there are at least 8)
  [ $rc -eq 0 ] || tail -n 60 "$glog"
  mkdir -p "$dir/jaws"
  local ex=$dir/firmware_example
  if "$qemu" -L "/usr/$triple" "$dir/tools/splintcore" phantom --triangles 6000 -o "$dir/jaws" \
       >"$dir/jaws.log" 2>&1 &&
     build_firmware_twin "$triple-gcc" "$triple-g++" "$dir/libsplintcore.a" "$PWD/$dir/jaws" \
       "$ex" >"$dir.example.log" 2>&1 &&
     "$qemu" -L "/usr/$triple" "$ex" >"$ex.log" 2>&1; then
    compare_firmware_log "$name" "$ex.log"
    [ "$fw_equal" -eq 3 ] || rc=1
  else
    cat "$dir/jaws.log" "$dir.example.log" "$ex.log" 2>/dev/null | tail -n 30
    fw_equal=0; fw_peak=0; rc=1
  fi
  total_passed=$((total_passed + n - failed + fw_equal))
  total_failed=$((total_failed + failed + (rc == 0 ? 0 : 1)))
  echo "$name: build ${build_seconds}s, total $((SECONDS - t0))s"
  cross_table="$cross_table$(printf '%-14s %-22s tests passed %4d/%-4d golden hashes equal: %-3s code: libsplintcore.a text %s B  peak arena %s B' \
    "$name" "$triple" $((n - failed)) "$n" "$([ $rc -eq 0 ] && echo yes || echo no)" \
    "$("$triple-size" -t "$dir/libsplintcore.a" | tail -n 1 | awk '{print $1}')" "$fw_peak")"$'\n'
  return $rc
}

core_job() {
  # The core alone, as firmware builds it: no platform layer, no exceptions, no RTTI anywhere.
  local dir=build/ci-core
  echo "=== core: -fno-exceptions -fno-rtti, SPLINTCORE_WITH_PLATFORM=OFF"
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DSPLINTCORE_WITH_PLATFORM=OFF \
    -DSPLINTCORE_BUILD_TESTS=OFF -DSPLINTCORE_BUILD_TOOLS=OFF \
    -DCMAKE_CXX_FLAGS="-fno-exceptions -fno-rtti" >"$dir.configure.log" 2>&1 || return 1
  cmake --build "$dir" -j "$par" >"$dir.build.log" 2>&1 || { tail -n 40 "$dir.build.log"; return 1; }
  # Symbols the core must not reference: the heap, exceptions and printf (firmware has none),
  # and libm functions whose results are not exact or not the same on every target
  # (docs/architecture.md, "Deterministic bytes"): the transcendentals, and fmin/fmax, for which
  # min_of/max_of stand. The exact ones (sqrt, floor, ceil, round, ldexp, frexp, nextafter...)
  # are allowed.
  local lib=$dir/libsplintcore.a forbidden
  forbidden=$({
    nm -C --undefined-only "$lib" | grep -E \
      "operator new|operator delete|\bmalloc\b|\bcalloc\b|\brealloc\b|__cxa_throw|__cxa_allocate_exception|__gxx_personality|\bprintf\b|\bfprintf\b|\bsnprintf\b"
    nm --undefined-only "$lib" | awk 'NF > 1 {print $NF}' | grep -E \
      '^(a?(sin|cos|tan)h?|atan2|sincos|exp(2|m1)?|log(2|10|1p|b)?|pow|cbrt|hypot|erfc?|[lt]gamma|fmin|fmax)[fl]?$'
  } | sort -u)
  if [ -n "$forbidden" ]; then
    echo "core pulls in forbidden symbols (heap, exceptions, printf, or libm that is not exact"
    echo "or not the same on every target):"
    echo "$forbidden"
    total_failed=$((total_failed + 1))
    return 1
  fi
  echo "core: no heap, exception, printf or inexact libm symbols; $(size -t "$dir/libsplintcore.a" | tail -n 1 | awk '{print "text " $1 " data " $2 " bss " $3 " bytes"}')"
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
  # The libFuzzer and sanitizer runtimes.
  need_packages $(job_packages fuzz) || return 1
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
  (cd "$dir" && ctest --output-on-failure -j "$par" -R '^fuzz\.' --timeout 900) >"$log" 2>&1 || rc=1
  grep -E "tests passed|tests failed|\*\*\*" "$log" | tail -n 15
  local n failed
  n=$(grep -oE "out of [0-9]+" "$log" | tail -n 1 | grep -oE "[0-9]+")
  failed=$(grep -oE "[0-9]+ tests failed" "$log" | tail -n 1 | grep -oE "^[0-9]+")
  total_passed=$((total_passed + ${n:-0} - ${failed:-0}))
  total_failed=$((total_failed + ${failed:-0}))
  # The targets run $par at a time (each fuzzes on one core); the table is printed in order.
  local running=0
  rm -f "$dir"/fuzz-*.rc
  for t in $targets; do
    mkdir -p "$dir/corpus/$t" "$dir/artifacts/$t"
    if [ "$running" -ge "$par" ]; then wait -n; running=$((running - 1)); fi
    ("$dir/tests/splintcore_fuzz_$t" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 \
       -print_final_stats=1 -artifact_prefix="$dir/artifacts/$t/" "$dir/corpus/$t" \
       "fixtures/fuzz/$t" >"$dir/fuzz-$t.log" 2>&1
     echo $? >"$dir/fuzz-$t.rc") &
    running=$((running + 1))
  done
  wait
  for t in $targets; do
    local frc
    frc=$(cat "$dir/fuzz-$t.rc" 2>/dev/null || echo 1)
    printf 'fuzz %-10s %10s execs %6s exec/s  %s\n' "$t" \
      "$(grep -oE '^stat::number_of_executed_units: +[0-9]+' "$dir/fuzz-$t.log" | grep -oE '[0-9]+$')" \
      "$(grep -oE '^stat::average_exec_per_sec: +[0-9]+' "$dir/fuzz-$t.log" | grep -oE '[0-9]+$')" \
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
  echo "=== lint: the floors (tools/check_layers.py), the layout (clang-format), function lengths (tools/function_sizes.py), clang-tidy (.clang-tidy) and cppcheck over src/ include/ tools/"
  need_packages $(job_packages lint) || return 1
  local layers_rc=0 layers
  layers=$(python3 tools/check_layers.py) || layers_rc=1
  printf '%s\n' "$layers" | tail -n 12
  # The layout: every C and C++ file of ours as clang-format (.clang-format) writes it.
  local unformatted
  unformatted=$(git ls-files '*.cpp' '*.h' '*.c' | grep -E '^(src|include|tools|tests)/' |
    xargs clang-format --dry-run 2>&1 | grep -oE '^[^:]+:[0-9]+:[0-9]+: (warning|error)' |
    cut -d: -f1 | sort -u)
  if [ -n "$unformatted" ]; then
    echo "not as clang-format writes them (clang-format -i FILE):" $unformatted; layers_rc=1
  else
    echo "clang-format: every file as .clang-format lays it out"
  fi
  # Function lengths (issue 27): none in src/ or tools/ over 150 lines (but those
  # tools/function_sizes.allow lists, none now), and at most 10% of function lines in functions
  # over 100 lines (the issue's goal was 25%; the splits brought it from 33.6% to under 3%).
  layers=$(python3 tools/function_sizes.py --check --max 150 --max-share 10 --list 100000 src tools) ||
    layers_rc=1
  printf '%s\n' "$layers" | tail -n 5
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
  [ $layers_rc -eq 0 ] || rc=1
  if [ $rc -eq 0 ]; then total_passed=$((total_passed + 1)); else total_failed=$((total_failed + 1)); fi
  return $rc
}

# The asan job is built with coverage instrumentation too (the counters change no arithmetic,
# and clang's counters are placed before the optimiser, so -O1 counts as -O0 does) and its
# test run leaves the profiles for the coverage report: one build and one test run serve
# both, where they were two full builds and two full runs (the clang-O0 job's, about 3.5
# minutes more of CI). -O1 -g1 (line tables): half the compile time of -O2 -g, the same
# findings (ASan's own recommendation is -O1), stack traces still name file and line. clang++:
# UBSan on the test files costs it little, where g++ took 2x the time of ASan alone.
ctest_profile=""
asan_job() {
  local dir=build/ci-asan rc=0
  # The sanitizer and the profile runtimes.
  need_packages $(job_packages asan) || return 1
  rm -f "$dir"/coverage-*.profraw
  ctest_profile="$PWD/$dir/coverage-%4m.profraw"
  run_ctest_job asan clang++ RelWithDebInfo -DSPLINTCORE_SANITIZE=ON \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DSPLINTCORE_COVERAGE=ON || rc=1
  ctest_profile=""
  echo "--- coverage of the asan test run (tools/coverage.sh --report $dir)"
  if SPLINTCORE_COVERAGE_MIN_BRANCH="${SPLINTCORE_COVERAGE_MIN_BRANCH:-95}" \
       bash tools/coverage.sh --report "$dir"; then
    total_passed=$((total_passed + 1))
  else
    total_failed=$((total_failed + 1)); rc=1
  fi
  return $rc
}

# ThreadSanitizer (optional: about 5 min from a clean build dir; a report fails the test with
# TSan's exit code 66): the tests that run the executor's tasks (names with Thread, Parallel,
# Executor; run_ctest_job) and the tool at 2 threads on the fixture cases
# (tests/tools/tsan_cli_test.sh: its bytes against the gcc-O2 job's tool when built, else this
# build's own at one thread).
tsan_job() {
  need_packages $(job_packages tsan) || return 1
  run_ctest_job tsan clang++ RelWithDebInfo -DSPLINTCORE_TSAN=ON || return 1
  local plain=build/ci-gcc-O2/tools/splintcore
  [ -x "$plain" ] || plain=build/ci-tsan/tools/splintcore
  if bash tests/tools/tsan_cli_test.sh build/ci-tsan/tools/splintcore "$plain" fixtures; then
    total_passed=$((total_passed + 1))
  else
    total_failed=$((total_failed + 1)); return 1
  fi
}

coverage_job() {
  # Fails when a parser of outside bytes (JSON, case, STL, PLY, OBJ, the CT readers) is under
  # SPLINTCORE_COVERAGE_MIN_BRANCH percent branch coverage (default 95, issue 9); prints the table.
  echo "=== coverage: clang -fprofile-instr-generate -fcoverage-mapping, llvm-cov report"
  # The profile runtime (libclang_rt.profile).
  need_packages $(job_packages coverage) || return 1
  if SPLINTCORE_JOBS="$par" SPLINTCORE_COVERAGE_MIN_BRANCH="${SPLINTCORE_COVERAGE_MIN_BRANCH:-95}" \
       bash tools/coverage.sh build/ci-coverage; then
    total_passed=$((total_passed + 1))
  else
    total_failed=$((total_failed + 1)); return 1
  fi
}

later_packages=$suite_packages
for job in $jobs; do later_packages="$later_packages $(job_packages "$job")"; done
if ! packages_installed $later_packages; then
  echo "installing in the background ($apt_bg_log): $(missing_packages $later_packages)"
  (ensure_packages $later_packages) >"$apt_bg_log" 2>&1 &
  apt_bg=$!
fi

job_times=""
for job in $jobs; do
  job_start=$SECONDS
  case $job in
    gcc-O0) run_ctest_job "$job" g++ Debug -DSPLINTCORE_BYTES_ONLY=ON ;;
    gcc-O2) run_ctest_job "$job" g++ Release ;;
    clang-O0) run_ctest_job "$job" clang++ Debug -DSPLINTCORE_BYTES_ONLY=ON ;;
    clang-O2) run_ctest_job "$job" clang++ Release -DSPLINTCORE_BYTES_ONLY=ON ;;
    asan) asan_job ;;
    core) core_job ;;
    fuzz) fuzz_job ;;
    lint) lint_job ;;
    coverage) coverage_job ;;
    tsan) tsan_job ;;
    aarch64) cross_job "$job" cmake/toolchain-aarch64-linux-gnu.cmake aarch64-linux-gnu ;;
    armv7) cross_job "$job" cmake/toolchain-arm-linux-gnueabihf.cmake arm-linux-gnueabihf ;;
    baremetal) bm_defer=0
               [ "$job" = "${jobs##* }" ] || bm_defer=1  # not the last job: QEMU beside the next
               baremetal_job ;;
    aarch64-golden) cross_golden_job "$job" cmake/toolchain-aarch64-linux-gnu.cmake aarch64-linux-gnu qemu-aarch64 ;;
    armv7-golden) cross_golden_job "$job" cmake/toolchain-arm-linux-gnueabihf.cmake arm-linux-gnueabihf qemu-arm ;;
    cross-golden)
      cross_golden_job aarch64-golden cmake/toolchain-aarch64-linux-gnu.cmake aarch64-linux-gnu qemu-aarch64
      r1=$?
      cross_golden_job armv7-golden cmake/toolchain-arm-linux-gnueabihf.cmake arm-linux-gnueabihf qemu-arm &&
        [ $r1 -eq 0 ] ;;
    *) echo "unknown job $job"; false ;;
  esac || failed_jobs="$failed_jobs $job"
  job_times="$job_times $job $((SECONDS - job_start))s"
done
if [ "${bm_pending:-0}" = 1 ]; then  # the board's run, started by the baremetal job
  job_start=$SECONDS
  echo "=== baremetal (continued): the firmware example's output from qemu-system-arm"
  baremetal_finish || failed_jobs="$failed_jobs baremetal"
  job_times="$job_times baremetal-qemu-wait $((SECONDS - job_start))s"
fi

[ -z "$apt_bg" ] || wait "$apt_bg"  # no job needed what it installs: it ends before the script
echo
if [ -n "$cross_table" ]; then
  echo "target         triple                 (x86-64 golden hashes: fixtures/golden.sha256 and the tests)"
  printf '%s' "$cross_table"
fi
echo "job times (installs included):$job_times; total ${SECONDS}s"
if [ -n "$failed_jobs" ]; then
  echo "failed jobs:$failed_jobs"
fi
echo "$total_passed passed, $total_failed failed"
[ -z "$failed_jobs" ]
