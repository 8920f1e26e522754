/* What the firmware example needs from its platform: text out, an end, and the stack use.
 * Two implementations: baremetal.c (Cortex-M7 on QEMU's mps2-an500: vector table, start-up,
 * ARM semihosting) and hosted.c (the same program as a Linux process, for the x86-64 and
 * qemu-user runs that CI compares the board's output with). */
#ifndef SPLINTCORE_FIRMWARE_PLATFORM_H
#define SPLINTCORE_FIRMWARE_PLATFORM_H

#include <stddef.h>

/* The arena's size (the example's whole heap-free memory budget for the library). The board's
 * PSRAM holds 16 MiB; the link fails if this does not fit. */
#ifndef SPLINTCORE_FIRMWARE_ARENA_BYTES
#define SPLINTCORE_FIRMWARE_ARENA_BYTES (16u * 1024u * 1024u)
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The example's program; called by the platform once memory is set up. Returns 0 on success. */
int firmware_main(void);

/* Writes NUL-terminated text to the console (semihosting SYS_WRITE0, or stdout). */
void fw_write(const char* text);

/* Ends the program: 0 is success, anything else a failure (QEMU exits with 0 or 1). */
void fw_exit(int code) __attribute__((noreturn));

/* "Cortex-M7 bare metal (mps2-an500, semihosting)" or "hosted <arch>". Static text. */
const char* fw_platform_name(void);

/* Deepest main-stack use so far in bytes (0 when the platform cannot tell). */
size_t fw_stack_high_water(void);

/* The arena: a static buffer of fw_arena_bytes() bytes (on the board, the PSRAM section). */
unsigned char* fw_arena(void);
size_t fw_arena_bytes(void);

#ifdef __cplusplus
}
#endif

#endif /* SPLINTCORE_FIRMWARE_PLATFORM_H */
