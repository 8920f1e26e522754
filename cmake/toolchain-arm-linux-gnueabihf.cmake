# Cross build for 32-bit ARMv7-A Linux, hard float (Debian armhf: -march=armv7-a -mfpu=vfpv3-d16
# by default), with Debian's toolchain (apt: g++-arm-linux-gnueabihf qemu-user). The 32-bit
# target: size_t is 32 bits, so every size, count and index must fit or fail with a clear error.
# Tests run under qemu-user through CMAKE_CROSSCOMPILING_EMULATOR:
#   cmake -S . -B /tmp/x-armv7 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-arm-linux-gnueabihf.cmake \
#         -DSPLINTCORE_GTEST_SOURCE_DIR=/usr/src/googletest
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(SPLINTCORE_CROSS_TRIPLE arm-linux-gnueabihf)

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

set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm -L /usr/${SPLINTCORE_CROSS_TRIPLE})
