// Minimal Cortex-M4 firmware image for the memory budget (flash, RAM, stack): the platform's
// start-up code (vector table, reset handler, semihosting), kinetics::init and kinetics::step,
// with State and Outputs in static storage as in the real firmware — and nothing else (no test
// runner, no scenario data).  Its sections give flash (everything loaded from code memory:
// vectors, text, rodata, exidx, init arrays, the .data image) and static RAM (.data + .bss).
//
// Run on QEMU it also reports its own stack: the free stack is painted at the top of main, then
// init and a few steps run on inputs read from volatile memory (so nothing is folded away), and
// the lowest overwritten word gives the whole image's stack high-water mark (reset handler, main,
// init, step), plus the stack depth at the call of step, which budget.py (m4-memory) adds to the
// worst step/init stack measured over all scenarios by step_budget_cortex_m4.cpp.
#include <cstddef>
#include <cstdint>

#include "decimal_text.hpp"
#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "semihosting.h"

extern "C" {
extern std::uint32_t __stack_limit[];
extern std::uint32_t __stack_top[];
}

namespace {

scopekin::kinetics::State g_state;
scopekin::kinetics::Outputs g_outputs;

// Stand-in for the sensor drivers: raw Q16.16 force, torque, insertion, roll and the fresh mask.
volatile std::int32_t g_raw_inputs[4][4] = {
    {65536, 1638400, 6553600, 0},
    {131072, -1638400, 13107200, 32768},
    {-65536, 0, 19660800, -32768},
    {0, 327680, 26214400, 65536},
};
volatile std::uint8_t g_fresh_masks[4] = {0x0F, 0x07, 0x0B, 0x00};
volatile std::uint32_t g_sink = 0;

constexpr std::uint32_t kPaint = 0xC5AC3A5CU;
constexpr std::uint32_t kSteps = 64U;

void write_decimal(std::uint32_t value) noexcept {
    scopekin::portable_check::DecimalBuffer buffer;
    scopekin_semihost_write0(scopekin::portable_check::decimal_text(value, buffer));
}

}  // namespace

int main() {
    std::uintptr_t sp = 0;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    for (volatile std::uint32_t* word = __stack_limit; reinterpret_cast<std::uintptr_t>(word) < sp;
         ++word) {
        *word = kPaint;
    }

    const scopekin::kinetics::Config config = scopekin::kinetics::default_config();
    scopekin::kinetics::init(config, g_state);
    for (std::uint32_t i = 0; i < kSteps; ++i) {
        const std::uint32_t k = i % 4U;
        scopekin::kinetics::Inputs inputs{};
        inputs.handle_force_N = scopekin::kinetics::Q16_16::from_raw(g_raw_inputs[k][0]);
        inputs.handle_torque_Nmm = scopekin::kinetics::Q16_16::from_raw(g_raw_inputs[k][1]);
        inputs.insertion_mm = scopekin::kinetics::Q16_16::from_raw(g_raw_inputs[k][2]);
        inputs.roll_rad = scopekin::kinetics::Q16_16::from_raw(g_raw_inputs[k][3]);
        inputs.fresh_mask = g_fresh_masks[k];
        scopekin::kinetics::step(inputs, g_state, g_outputs);
        g_sink = g_sink ^ g_outputs.step_index ^ g_outputs.fault_flags;
    }

    const volatile std::uint32_t* lowest = __stack_limit;
    while (reinterpret_cast<std::uintptr_t>(lowest) < sp && *lowest == kPaint) {
        ++lowest;
    }
    const auto top = reinterpret_cast<std::uintptr_t>(__stack_top);
    scopekin_semihost_write0("@budget {\"image\": {\"stack_high_water_bytes\": ");
    write_decimal(static_cast<std::uint32_t>(top - reinterpret_cast<std::uintptr_t>(lowest)));
    scopekin_semihost_write0(", \"stack_depth_at_call_bytes\": ");
    write_decimal(static_cast<std::uint32_t>(top - sp));
    scopekin_semihost_write0(", \"steps\": ");
    write_decimal(kSteps);
    scopekin_semihost_write0("}}\n");
    return 0;
}
