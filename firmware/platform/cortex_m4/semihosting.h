/*
 * ARM semihosting for the Cortex-M4 platform (QEMU mps2-an386 with
 * -semihosting-config enable=on, or a debug probe that implements semihosting).
 *
 * Only what the firmware and its bare-metal tests need: console output and exit
 * with a status.  Each call is a `bkpt 0xAB` trap; without a semihosting host
 * attached it faults, so production firmware must not call these.
 */
#ifndef SCOPEKIN_PLATFORM_CORTEX_M4_SEMIHOSTING_H
#define SCOPEKIN_PLATFORM_CORTEX_M4_SEMIHOSTING_H

#ifdef __cplusplus
extern "C" {
#endif

/* SYS_WRITE0: write a NUL-terminated string to the host's stdout. */
void scopekin_semihost_write0(const char* text);

/*
 * SYS_EXIT_EXTENDED with reason ADP_Stopped_ApplicationExit and subcode
 * `status`: the host (QEMU) exits with `status` as its own exit status
 * (only the low 8 bits survive on POSIX hosts).
 */
#ifdef __cplusplus
[[noreturn]]
#else
_Noreturn
#endif
void scopekin_semihost_exit(int status);

#ifdef __cplusplus
}
#endif

#endif /* SCOPEKIN_PLATFORM_CORTEX_M4_SEMIHOSTING_H */
