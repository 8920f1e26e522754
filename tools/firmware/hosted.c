/* Hosted platform of the firmware example: the same program as a Linux process (x86-64, or an
 * AArch64/ARMv7 build under qemu-user), so CI can put the board's output next to a
 * workstation's. Output to stdout; the arena is a static array of the same size. */
#include <stdio.h>
#include <stdlib.h>

#include "platform.h"

static unsigned char g_arena[SPLINTCORE_FIRMWARE_ARENA_BYTES] __attribute__((aligned(16)));

unsigned char* fw_arena(void) { return g_arena; }
size_t fw_arena_bytes(void) { return sizeof g_arena; }
void fw_write(const char* text) {
  fputs(text, stdout);
  fflush(stdout);
}
void fw_exit(int code) { exit(code == 0 ? 0 : 1); }
size_t fw_stack_high_water(void) { return 0; }

const char* fw_platform_name(void) {
#if defined(__x86_64__)
  return "hosted x86-64";
#elif defined(__aarch64__)
  return "hosted AArch64";
#elif defined(__arm__)
  return "hosted ARMv7";
#else
  return "hosted";
#endif
}

int main(void) { return firmware_main() == 0 ? 0 : 1; }
