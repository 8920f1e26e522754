/* Bare-metal platform of the firmware example: Cortex-M7 (ARMv7E-M with FPv5-D16) on QEMU's
 * mps2-an500 board. Vector table, reset handler (FPU on, .data copied from its load image,
 * .bss zeroed, the stack painted), fault handlers, and console output and exit through ARM
 * semihosting ("Semihosting for AArch32 and AArch64", ARM IHI 0056: SYS_WRITE0 0x04 and
 * SYS_EXIT 0x18, trapped by `bkpt 0xab` in Thumb state; QEMU needs -semihosting).
 * No C library start-up code, no heap, no syscalls: the library only needs memcpy-style
 * functions and sqrt from newlib, and abort() is defined here. */
#include <stdint.h>

#include "platform.h"

/* From the linker script (mps2_an500.ld). */
extern uint32_t __data_start[], __data_end[], __data_load[];
extern uint32_t __bss_start[], __bss_end[];
extern uint32_t __stack_limit[], __stack_top[];
extern void (*__preinit_array_start[])(void), (*__preinit_array_end[])(void);
extern void (*__init_array_start[])(void), (*__init_array_end[])(void);

static unsigned char g_arena[SPLINTCORE_FIRMWARE_ARENA_BYTES]
    __attribute__((section(".arena"), aligned(16)));

enum { kStackPaint = 0x5A7C0DE5u };

unsigned char* fw_arena(void) { return g_arena; }
size_t fw_arena_bytes(void) { return sizeof g_arena; }
const char* fw_platform_name(void) {
  return "Cortex-M7 bare metal (mps2-an500, FPv5-D16, semihosting)";
}

static int semihost(int operation, const void* argument) {
  register int r0 __asm__("r0") = operation;
  register const void* r1 __asm__("r1") = argument;
  __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

void fw_write(const char* text) { (void)semihost(0x04 /* SYS_WRITE0 */, text); }

void fw_exit(int code) {
  /* ADP_Stopped_ApplicationExit: QEMU exits with status 0; RunTimeErrorUnknown: status 1. */
  for (;;) (void)semihost(0x18 /* SYS_EXIT */, (const void*)(code == 0 ? 0x20026u : 0x20023u));
}

/* The library's only libc call that does not return (its default assert path). */
void abort(void) {
  fw_write("abort\n");
  fw_exit(3);
}

/* newlib's assert hook. libstdc++'s std::to_chars and std::from_chars (which the library uses
 * for shortest round-trip numbers) keep internal assertions that call it; newlib's own version
 * prints with fiprintf, which drags in stdio, malloc and the syscalls. This one does not. */
void __assert_func(const char* file, int line, const char* function, const char* expression) {
  (void)line;
  (void)function;
  fw_write("assertion failed in the C/C++ runtime: ");
  fw_write(expression);
  fw_write(" (");
  fw_write(file);
  fw_write(")\n");
  fw_exit(3);
}

size_t fw_stack_high_water(void) {
  const uint32_t* p = __stack_limit;
  while (p < __stack_top && *p == kStackPaint) ++p;
  return (size_t)((const unsigned char*)__stack_top - (const unsigned char*)p);
}

static void fault(const char* what) {
  fw_write(what);
  fw_exit(4);
}
static void fw_nmi_handler(void) { fault("NMI\n"); }
static void fw_hard_fault_handler(void) { fault("hard fault\n"); }
static void fw_mem_manage_handler(void) { fault("memory management fault\n"); }
static void fw_bus_fault_handler(void) { fault("bus fault\n"); }
static void fw_usage_fault_handler(void) { fault("usage fault\n"); }
static void fw_default_handler(void) { fault("unexpected exception\n"); }

__attribute__((noreturn)) void fw_reset_handler(void);

/* Cortex-M vector table: initial stack pointer, then the handlers (ARMv7-M ARM B1.5.3). */
__attribute__((section(".vectors"), used)) static const void* const g_vectors[16] = {
    __stack_top,
    (const void*)fw_reset_handler,
    (const void*)fw_nmi_handler,
    (const void*)fw_hard_fault_handler,
    (const void*)fw_mem_manage_handler,
    (const void*)fw_bus_fault_handler,
    (const void*)fw_usage_fault_handler,
    0,
    0,
    0,
    0,
    (const void*)fw_default_handler, /* SVCall */
    (const void*)fw_default_handler, /* DebugMonitor */
    0,
    (const void*)fw_default_handler, /* PendSV */
    (const void*)fw_default_handler, /* SysTick */
};

/* Paints the stack below the caller's frame (this function's locals stay in registers). */
__attribute__((noinline)) static void paint_stack(void) {
  uint32_t* p = __stack_limit;
  uint32_t* const end = (uint32_t*)__builtin_frame_address(0) - 64;
  while (p < end) *p++ = kStackPaint;
}

void fw_reset_handler(void) {
  /* Full access to CP10 and CP11 (the FPU) before any floating-point instruction. */
  volatile uint32_t* const cpacr = (volatile uint32_t*)0xE000ED88u;
  *cpacr |= 0xFu << 20;
  __asm__ volatile("dsb\n\tisb" ::: "memory");
  /* Unaligned accesses trap only when CCR.UNALIGN_TRP is set: leave it clear (the default). */
  for (uint32_t *d = __data_start, *s = __data_load; d < __data_end;) *d++ = *s++;
  for (uint32_t* d = __bss_start; d < __bss_end;) *d++ = 0;
  paint_stack();
  for (void (**f)(void) = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (void (**f)(void) = __init_array_start; f < __init_array_end; ++f) (*f)();
  fw_exit(firmware_main());
}
