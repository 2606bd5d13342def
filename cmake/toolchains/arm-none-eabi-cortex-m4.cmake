# MCU sensor box: bare-metal Cortex-M4F (ARMv7E-M, single-precision FPU, hard-float ABI),
# Debian's gcc-arm-none-eabi + newlib.  Emulated board: QEMU mps2-an386 (ARM AN386 FPGA image).
# Startup code, vector table and linker script: firmware/platform/cortex_m4/.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER   arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_AR           arm-none-eabi-ar)
set(CMAKE_RANLIB       arm-none-eabi-ranlib)
set(CMAKE_OBJCOPY      arm-none-eabi-objcopy CACHE FILEPATH "")
set(CMAKE_SIZE         arm-none-eabi-size    CACHE FILEPATH "")

# There is no OS to link a test executable for during compiler checks.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(SCOPEKIN_CORTEX_M4_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
# -ffunction-sections/-fdata-sections + --gc-sections: drop what is not referenced (flash budget).
set(CMAKE_C_FLAGS_INIT   "${SCOPEKIN_CORTEX_M4_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_CXX_FLAGS_INIT "${SCOPEKIN_CORTEX_M4_FLAGS} -ffunction-sections -fdata-sections")
set(CMAKE_ASM_FLAGS_INIT "${SCOPEKIN_CORTEX_M4_FLAGS}")
# newlib-nano for the few libc routines used (memcpy, memset, ...).  No newlib start files and no
# newlib syscalls: firmware/platform/cortex_m4 provides the reset handler, the semihosting I/O and
# an _sbrk that always fails (no heap on the MCU).
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs -nostartfiles -Wl,--gc-sections")

set(CMAKE_FIND_ROOT_PATH /usr/lib/arm-none-eabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
# BOTH: header-only packages are found on the build machine (see aarch64 toolchain).
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)

# CTest runs every test executable through this wrapper (qemu-system-arm mps2-an386, semihosting,
# exit status of main() becomes the exit status of QEMU).
set(CMAKE_CROSSCOMPILING_EMULATOR "${CMAKE_CURRENT_LIST_DIR}/../qemu-mps2-an386.sh")
