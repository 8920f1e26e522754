# Cross build for AArch64 Linux with Debian's toolchain (apt: g++-aarch64-linux-gnu qemu-user).
# Tests run under qemu-user through CMAKE_CROSSCOMPILING_EMULATOR, so `ctest` works as on the
# host. GoogleTest is built from source for the target:
#   cmake -S . -B /tmp/x-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64-linux-gnu.cmake \
#         -DSPLINTCORE_GTEST_SOURCE_DIR=/usr/src/googletest
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(SPLINTCORE_CROSS_TRIPLE aarch64-linux-gnu)

set(CMAKE_C_COMPILER ${SPLINTCORE_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${SPLINTCORE_CROSS_TRIPLE}-g++)
set(CMAKE_AR ${SPLINTCORE_CROSS_TRIPLE}-ar CACHE FILEPATH "")
set(CMAKE_RANLIB ${SPLINTCORE_CROSS_TRIPLE}-ranlib CACHE FILEPATH "")
set(CMAKE_STRIP ${SPLINTCORE_CROSS_TRIPLE}-strip CACHE FILEPATH "")

set(CMAKE_FIND_ROOT_PATH /usr/${SPLINTCORE_CROSS_TRIPLE})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# AArch64 has fused multiply-add in the base ISA; -ffp-contract=off (SplintcoreFlags.cmake)
# is what keeps GCC from fusing a*b+c, so the bytes equal x86-64's.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L /usr/${SPLINTCORE_CROSS_TRIPLE})
