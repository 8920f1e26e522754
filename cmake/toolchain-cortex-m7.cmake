# Bare-metal Cortex-M7 with its double-precision FPU (apt: gcc-arm-none-eabi
# libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib). The core only: no OS, no threads,
# no files, no exceptions, no RTTI:
#   cmake -S . -B /tmp/x-m7 -DCMAKE_TOOLCHAIN_FILE=$PWD/cmake/toolchain-cortex-m7.cmake \
#         -DSPLINTCORE_WITH_PLATFORM=OFF -DSPLINTCORE_BUILD_TESTS=OFF -DSPLINTCORE_BUILD_TOOLS=OFF
# A whole image (start-up, linker script, semihosting) that runs under qemu-system-arm -M
# mps2-an500: tools/firmware (docs/embedding.md; CI: bash tools/test.sh baremetal). An image
# links with -nostartfiles and its own start-up; nano.specs below selects newlib-nano.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(SPLINTCORE_CROSS_TRIPLE arm-none-eabi)

set(CMAKE_C_COMPILER ${SPLINTCORE_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${SPLINTCORE_CROSS_TRIPLE}-g++)
set(CMAKE_AR ${SPLINTCORE_CROSS_TRIPLE}-ar CACHE FILEPATH "")
set(CMAKE_RANLIB ${SPLINTCORE_CROSS_TRIPLE}-ranlib CACHE FILEPATH "")
set(CMAKE_SIZE ${SPLINTCORE_CROSS_TRIPLE}-size CACHE FILEPATH "")
# No OS to link a test program against: compiler checks build a static library instead.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(SPLINTCORE_M7_FLAGS "-mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard -mthumb")
set(CMAKE_C_FLAGS_INIT "${SPLINTCORE_M7_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT
    "${SPLINTCORE_M7_FLAGS} -ffunction-sections -fdata-sections -fno-exceptions -fno-rtti")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${SPLINTCORE_M7_FLAGS} -Wl,--gc-sections --specs=nano.specs")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
