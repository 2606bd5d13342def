/*
 * Reset and exception entry for the Cortex-M4F platform (QEMU mps2-an386 board).
 *
 * Reset_Handler:
 *   1. enables the FPU (CP10/CP11 full access) — the code is compiled for the hard-float ABI;
 *   2. copies .data from its load address in code memory to RAM and zeroes .bss;
 *   3. runs static constructors (.preinit_array, .init_array);
 *   4. calls main() and hands its return value to the semihosting host as the exit status
 *      (SYS_EXIT_EXTENDED), so a test that returns non-zero makes QEMU — and CTest — fail.
 *
 * The initial stack pointer is word 0 of the vector table; the linker script
 * (mps2_an386.ld) emits it in front of the .isr_vector section below, so no object-to-function
 * pointer cast is needed here.
 *
 * Any unexpected exception (HardFault, BusFault, ... or an interrupt without a handler) reports
 * its exception number through semihosting and exits with status SCOPEKIN_EXIT_FAULT.
 *
 * There is no heap: _sbrk always fails, so any malloc() returns NULL.
 */
#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#include "semihosting.h"

/* Exit status of a run that ended in an unexpected exception / failed assert(). */
#define SCOPEKIN_EXIT_FAULT 250
#define SCOPEKIN_EXIT_ASSERT 251

/* Symbols from mps2_an386.ld. */
extern uint32_t __data_load_start[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
typedef void (*scopekin_init_function)(void);
extern scopekin_init_function __preinit_array_start[];
extern scopekin_init_function __preinit_array_end[];
extern scopekin_init_function __init_array_start[];
extern scopekin_init_function __init_array_end[];

int main(void);

_Noreturn void Reset_Handler(void);
void Default_Handler(void);

/* Weak aliases: a driver defines e.g. `void NMI_Handler(void)` to take over one vector. */
#define SCOPEKIN_WEAK_HANDLER(name) void name(void) __attribute__((weak, alias("Default_Handler")))
SCOPEKIN_WEAK_HANDLER(NMI_Handler);
SCOPEKIN_WEAK_HANDLER(HardFault_Handler);
SCOPEKIN_WEAK_HANDLER(MemManage_Handler);
SCOPEKIN_WEAK_HANDLER(BusFault_Handler);
SCOPEKIN_WEAK_HANDLER(UsageFault_Handler);
SCOPEKIN_WEAK_HANDLER(SVC_Handler);
SCOPEKIN_WEAK_HANDLER(DebugMon_Handler);
SCOPEKIN_WEAK_HANDLER(PendSV_Handler);
SCOPEKIN_WEAK_HANDLER(SysTick_Handler);

/* Number of external interrupt lines wired on the AN386 image (CMSDK UARTs, timers, ...). */
#define SCOPEKIN_AN386_IRQ_COUNT 32

#define SCOPEKIN_IRQ_HANDLERS_4 Default_Handler, Default_Handler, Default_Handler, Default_Handler,
#define SCOPEKIN_IRQ_HANDLERS_32                                                \
    SCOPEKIN_IRQ_HANDLERS_4 SCOPEKIN_IRQ_HANDLERS_4 SCOPEKIN_IRQ_HANDLERS_4     \
        SCOPEKIN_IRQ_HANDLERS_4 SCOPEKIN_IRQ_HANDLERS_4 SCOPEKIN_IRQ_HANDLERS_4 \
            SCOPEKIN_IRQ_HANDLERS_4 SCOPEKIN_IRQ_HANDLERS_4

/* Vector table entries 1.. (entry 0, the initial SP, comes from the linker script). */
__attribute__((section(".isr_vector"),
               used)) static void (*const vector_table[15 + SCOPEKIN_AN386_IRQ_COUNT])(void) = {
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    MemManage_Handler,
    BusFault_Handler,
    UsageFault_Handler,
    0,
    0,
    0,
    0, /* reserved */
    SVC_Handler,
    DebugMon_Handler,
    0, /* reserved */
    PendSV_Handler,
    SysTick_Handler,
    SCOPEKIN_IRQ_HANDLERS_32 /* IRQ 0..31 */
};

static void write_decimal(uint32_t value) {
    char digits[11];
    size_t n = sizeof digits;
    digits[--n] = '\0';
    do {
        digits[--n] = (char)('0' + (value % 10u));
        value /= 10u;
    } while (value != 0u && n > 0u);
    scopekin_semihost_write0(&digits[n]);
}

void Default_Handler(void) {
    uint32_t ipsr;
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    scopekin_semihost_write0("\n*** scopekin: unexpected exception ");
    write_decimal(ipsr & 0x1FFu);
    scopekin_semihost_write0(" (3 = HardFault, 16+n = IRQ n)\n");
    scopekin_semihost_exit(SCOPEKIN_EXIT_FAULT);
}

_Noreturn void Reset_Handler(void) {
    /* CPACR: CP10 and CP11 full access, before any floating-point instruction. */
    volatile uint32_t* const cpacr = (volatile uint32_t*)0xE000ED88u;
    *cpacr |= (0xFu << 20);
    __asm__ volatile("dsb\n\tisb" ::: "memory");

    for (uint32_t *src = __data_load_start, *dst = __data_start; dst < __data_end; ++src, ++dst) {
        *dst = *src;
    }
    for (uint32_t* dst = __bss_start; dst < __bss_end; ++dst) {
        *dst = 0u;
    }

    for (scopekin_init_function* f = __preinit_array_start; f < __preinit_array_end; ++f) {
        (*f)();
    }
    for (scopekin_init_function* f = __init_array_start; f < __init_array_end; ++f) {
        (*f)();
    }

    /* Static destructors are not run: the firmware never ends; tests end through semihosting. */
    scopekin_semihost_exit(main());
}

/* --- minimal newlib hooks ------------------------------------------------------------------ */

/* No heap (hard rule): every allocation attempt fails. */
void* _sbrk(ptrdiff_t increment);
void* _sbrk(ptrdiff_t increment) {
    (void)increment;
    errno = ENOMEM;
    return (void*)-1;
}

/* exit()/abort() end up here. */
_Noreturn void _exit(int status);
_Noreturn void _exit(int status) {
    scopekin_semihost_exit(status);
}

/* assert() failures: report through semihosting instead of newlib's stdio. */
_Noreturn void __assert_func(const char* file, int line, const char* function,
                             const char* expression);
_Noreturn void __assert_func(const char* file, int line, const char* function,
                             const char* expression) {
    scopekin_semihost_write0("\n*** scopekin: assertion failed: ");
    scopekin_semihost_write0(expression != NULL ? expression : "?");
    scopekin_semihost_write0("\n    in ");
    scopekin_semihost_write0(function != NULL ? function : "?");
    scopekin_semihost_write0(" at ");
    scopekin_semihost_write0(file != NULL ? file : "?");
    scopekin_semihost_write0(":");
    write_decimal((uint32_t)line);
    scopekin_semihost_write0("\n");
    scopekin_semihost_exit(SCOPEKIN_EXIT_ASSERT);
}
