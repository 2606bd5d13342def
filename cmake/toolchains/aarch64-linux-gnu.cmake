# Linux sensor box: aarch64 (ARMv8-A) Linux, Debian cross toolchain g++-aarch64-linux-gnu.
# Tests run under qemu-user with the Debian cross sysroot as the dynamic-loader prefix.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CMAKE_C_COMPILER   aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

set(SCOPEKIN_AARCH64_SYSROOT /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH ${SCOPEKIN_AARCH64_SYSROOT})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
# BOTH: lets header-only, architecture-independent packages (CLI11 and nlohmann-json for
# scopekin-box) be found on the build machine.  Compiled packages must not be used
# this way; GoogleTest is therefore built from source when cross-compiling (cmake/scopekin_gtest.cmake).
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)

set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;${SCOPEKIN_AARCH64_SYSROOT})
