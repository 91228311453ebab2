/* startup.c -- reset handler and vector table of a bare-metal Cortex-M4F program, and the ARM
 * semihosting calls it talks to the host through (QEMU: -semihosting-config enable=on).
 *
 * No C library start-up code and no heap: the reset handler enables the FPU, copies .data,
 * zeroes .bss, paints the free stack (to measure its deepest use), calls main() and reports
 * its return value to the host with SYS_EXIT_EXTENDED.
 */
#include <stdint.h>

#include "board.h"

extern uint32_t _data_load, _data_start, _data_end, _bss_start, _bss_end, _stack_top;
extern int main(void);

#define SYS_WRITE0 0x04
#define SYS_EXIT_EXTENDED 0x20
#define ADP_STOPPED_APPLICATION_EXIT 0x20026
#define STACK_PAINT 0xA5A5A5A5u
#define CPACR (*(volatile uint32_t*)0xE000ED88u)
#define SYST_CSR (*(volatile uint32_t*)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t*)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t*)0xE000E018u)
#define SYST_RELOAD 0xFFFFFFu

/* SysTick wraps counted by its interrupt: the program's only mutable global besides main's. */
static volatile uint32_t systick_wraps;

static int semihost_call(int operation, const void* argument)
{
    register int r0 __asm__("r0") = operation;
    register const void* r1 __asm__("r1") = argument;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void semihost_write(const char* text)
{
    semihost_call(SYS_WRITE0, text);
}

void semihost_exit(int status)
{
    uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, (uint32_t)status};
    for (;;) semihost_call(SYS_EXIT_EXTENDED, block);
}

/* Fill the free RAM between .bss and the stack in use with a pattern (stack_used_bytes). */
static void paint_stack(void)
{
    uint32_t sp;
    volatile uint32_t* word = &_bss_end;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    while ((uint32_t)word < sp - 64u) *word++ = STACK_PAINT;
}

static void systick_handler(void)
{
    ++systick_wraps;
}

uint64_t board_ticks(void)
{
    uint32_t wraps, value;
    do { /* a wrap between the two reads is taken at once as an interrupt: read again */
        wraps = systick_wraps;
        value = SYST_CVR;
    } while (wraps != systick_wraps);
    return (uint64_t)wraps * (SYST_RELOAD + 1u) + (SYST_RELOAD - value);
}

uint32_t stack_used_bytes(void)
{
    const uint32_t* word = &_bss_end;
    while (word < &_stack_top && *word == STACK_PAINT) ++word;
    return (uint32_t)((const char*)&_stack_top - (const char*)word);
}

void reset_handler(void)
{
    uint32_t* source = &_data_load;
    uint32_t* target;
    CPACR |= 0xFu << 20; /* full access to CP10 and CP11: the FPU */
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    for (target = &_data_start; target < &_data_end;) *target++ = *source++;
    for (target = &_bss_start; target < &_bss_end;) *target++ = 0;
    paint_stack();
    SYST_RVR = SYST_RELOAD;
    SYST_CVR = 0u;
    SYST_CSR = 7u; /* enabled, wrap interrupt, processor clock */
    semihost_exit(main());
}

static void fault_handler(void)
{
    semihost_write("fault: the program trapped\n");
    semihost_exit(99);
}

__attribute__((section(".isr_vector"), used)) static void (*const vector_table[16])(void) = {
    (void (*)(void))&_stack_top, reset_handler, fault_handler, fault_handler, fault_handler, fault_handler,
    fault_handler, 0, 0, 0, 0, fault_handler, fault_handler, 0, fault_handler, systick_handler,
};
