/* ARM semihosting calls, see semihosting.h. */
#include "semihosting.h"

#include <stdint.h>

enum {
    SYS_WRITE0 = 0x04,
    SYS_EXIT_EXTENDED = 0x20,
    ADP_STOPPED_APPLICATION_EXIT = 0x20026
};

static uintptr_t semihost_call(uintptr_t operation, uintptr_t parameter) {
    register uintptr_t r0 __asm__("r0") = operation;
    register uintptr_t r1 __asm__("r1") = parameter;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void scopekin_semihost_write0(const char* text) {
    (void)semihost_call(SYS_WRITE0, (uintptr_t)text);
}

_Noreturn void scopekin_semihost_exit(int status) {
    /* The 32-bit SYS_EXIT only carries the reason (success or not); SYS_EXIT_EXTENDED takes a
       two-word block {reason, subcode} and QEMU uses the subcode as its exit status. */
    const uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, (uint32_t)status};
    (void)semihost_call(SYS_EXIT_EXTENDED, (uintptr_t)block);
    for (;;) {
        /* Without a semihosting host there is nowhere to go. */
        __asm__ volatile("wfi");
    }
}
