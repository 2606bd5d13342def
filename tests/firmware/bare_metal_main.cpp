// Runner main for bare-metal test executables (Cortex-M4 on QEMU mps2-an386).
// Output goes to the host through semihosting; the number of failed tests becomes main()'s
// return value, which the startup code hands to QEMU as its exit status (non-zero = CTest fail).
#include "portable_check.hpp"
#include "semihosting.h"

void scopekin::portable_check::write_text(const char* text) noexcept {
    scopekin_semihost_write0(text);
}

int main() {
    const int failed = scopekin::portable_check::run_all();
    return failed > 255 ? 255 : failed;
}
