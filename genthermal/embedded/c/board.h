/* board.h -- what the emulated Cortex-M4F board gives the target programs (startup.c):
 * host I/O through ARM semihosting, a 64-bit tick counter, and the deepest stack used. */
#ifndef BOARD_H
#define BOARD_H

#include <stdint.h>

/* Print a NUL-terminated string on the host (QEMU's semihosting output). */
void semihost_write(const char* text);
/* End the program with an exit status the host reports as QEMU's exit code. */
void semihost_exit(int status) __attribute__((noreturn));

/* Processor-clock ticks since start-up (SysTick at the 25 MHz board clock, extended to 64 bits by
 * its wrap interrupt). Under QEMU -icount the host converts ticks into executed instructions. */
uint64_t board_ticks(void);

/* Bytes of stack used so far: the deepest point below the top that start-up's paint no longer holds. */
uint32_t stack_used_bytes(void);

#endif
