# Compiler flags for splintcore's own targets.
#
# Determinism first: the same input must give the same output bytes with g++ and clang++,
# at -O0 and -O2, on x86-64 and AArch64. So no floating-point contraction (an FMA rounds
# once where a multiply-then-add rounds twice), no fast-math, and IEEE semantics kept.

include_guard(GLOBAL)

option(SPLINTCORE_WERROR "Treat warnings as errors on splintcore's own code" ON)
option(SPLINTCORE_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(SPLINTCORE_CORE_NO_EXCEPTIONS "Build the core library with -fno-exceptions -fno-rtti" ON)
option(SPLINTCORE_FUZZ "Build libFuzzer targets (clang only)" OFF)
option(SPLINTCORE_TSAN "Build with ThreadSanitizer (the executor's tasks; tools/test.sh tsan)" OFF)
option(SPLINTCORE_COVERAGE "clang source-based coverage of the library (tools/coverage.sh)" OFF)

set(SPLINTCORE_WARNINGS
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion
  -Wcast-align -Wnon-virtual-dtor -Wold-style-cast -Wdouble-promotion)
if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  # Dead code: a function template, or a member of a class local to its file, that nothing
  # uses (clang only: GCC has no such warning).
  list(APPEND SPLINTCORE_WARNINGS -Wunused-template -Wunused-member-function)
endif()
if(SPLINTCORE_WERROR)
  list(APPEND SPLINTCORE_WARNINGS -Werror)
endif()

# Flags that change results: applied to everything we compile, tests and tools included,
# so a golden hash computed in a test is the one the tool writes.
set(SPLINTCORE_FP_FLAGS -ffp-contract=off -fno-fast-math)
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU")
  # GCC 12's basic-block (SLP) vectoriser drops double -> float -> double round trips on
  # neighbouring fields (Vec3{(double)(float)p.x, (double)(float)p.y, ...} keeps x and y
  # unrounded at -O2; reproduced with Debian's g++ 12.2). Rounding to float32 is what makes a
  # written STL what we checked, so it is off for everything we compile. round_to_float32()
  # (geometry.h) also rounds through a volatile, so a consumer's flags cannot bring it back.
  list(APPEND SPLINTCORE_FP_FLAGS -fno-tree-slp-vectorize)
  # x87 extended precision would break bit-identity; SSE2 is the x86-64 baseline anyway.
  if(CMAKE_SYSTEM_PROCESSOR MATCHES "i.86")
    list(APPEND SPLINTCORE_FP_FLAGS -msse2 -mfpmath=sse)
  endif()
endif()
add_compile_options(${SPLINTCORE_FP_FLAGS})

if(SPLINTCORE_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# Coverage counts the library's code only (the report is of src/): the library's files are
# compiled with the counters (CMakeLists.txt), every program links the profile runtime. Test
# files compiled without them build about 10% faster under ASan and run no counters of their own.
if(SPLINTCORE_COVERAGE)
  set(SPLINTCORE_COVERAGE_FLAGS -fprofile-instr-generate -fcoverage-mapping)
  add_link_options(-fprofile-instr-generate)
endif()

if(SPLINTCORE_TSAN)
  if(SPLINTCORE_SANITIZE OR SPLINTCORE_FUZZ)
    message(FATAL_ERROR "SPLINTCORE_TSAN cannot be combined with AddressSanitizer builds")
  endif()
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
endif()

# A sanitizer's runtime replaces malloc and operator new, and each consumer of an instrumented
# library needs it: the allocation-counting tests and the install consumer are left out.
if(SPLINTCORE_SANITIZE OR SPLINTCORE_FUZZ OR SPLINTCORE_TSAN)
  set(SPLINTCORE_SANITIZER_RUNTIME ON)
else()
  set(SPLINTCORE_SANITIZER_RUNTIME OFF)
endif()

if(SPLINTCORE_FUZZ)
  # Coverage instrumentation for everything; the fuzz targets add the libFuzzer main.
  # Undefined behaviour stops the run as ASan's findings do (without it UBSan prints and goes
  # on, and a corpus replay passes over it).
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# splintcore_apply_warnings(target): our warning set, on our own code only.
function(splintcore_apply_warnings target)
  target_compile_options(${target} PRIVATE ${SPLINTCORE_WARNINGS})
endfunction()

# splintcore_apply_core_flags(target): what the core library is built with.
function(splintcore_apply_core_flags target)
  splintcore_apply_warnings(${target})
  if(SPLINTCORE_CORE_NO_EXCEPTIONS)
    target_compile_options(${target} PRIVATE -fno-exceptions -fno-rtti)
  endif()
endfunction()
