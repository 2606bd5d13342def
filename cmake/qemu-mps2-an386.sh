#!/usr/bin/env bash
# Run a bare-metal Cortex-M4 ELF on QEMU's mps2-an386 board with semihosting.
#
#   qemu-mps2-an386.sh <program.elf> [args...]
#
# * Output: the program writes through semihosting (SYS_WRITE0/SYS_WRITE) to this terminal.
# * Exit status: the program ends with semihosting SYS_EXIT_EXTENDED, which QEMU turns into its
#   own exit status, so the value returned by main() is this script's exit status.
# * -icount shift=0: one instruction = 1 ns of virtual time, deterministic timing.
# * Timeout: SCOPEKIN_QEMU_TIMEOUT seconds (default 60); a hang gives exit status 124.
# Used as CMAKE_CROSSCOMPILING_EMULATOR by cmake/toolchains/arm-none-eabi-cortex-m4.cmake.
set -euo pipefail

if [[ $# -lt 1 ]]; then
  echo "usage: $0 <program.elf> [args...]" >&2
  exit 2
fi
elf=$1
shift
timeout_s=${SCOPEKIN_QEMU_TIMEOUT:-60}

# Semihosting console -> this script's stdout (QEMU's default for it is stderr).
qemu_args=(-M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none
           -chardev stdio,id=semihosting_console
           -semihosting-config enable=on,target=native,chardev=semihosting_console
           -icount shift=0 -kernel "$elf")
if [[ $# -gt 0 ]]; then
  # Visible to the program through semihosting SYS_GET_CMDLINE.
  qemu_args+=(-append "$*")
fi

set +e
timeout --foreground -k 5 "$timeout_s" qemu-system-arm "${qemu_args[@]}"
rc=$?
set -e
if [[ $rc -eq 124 ]]; then
  echo "qemu-mps2-an386.sh: '$elf' timed out after ${timeout_s}s" >&2
fi
exit "$rc"
