// Instructions and stack per kinetics::step on the Cortex-M4, checked against their budgets.
// Bare metal only: runs on QEMU `-M mps2-an386 -icount shift=0` through cmake/qemu-mps2-an386.sh,
// with the portable_check runner (bare_metal_main.cpp).  tests/budget/tools/budget.py (m4-step)
// runs it, collects the "@budget {...}" lines and writes the budget part.
//
// Instructions: QEMU's Cortex-M has no cycle counter (DWT CYCCNT reads 0), but with -icount
// shift=0 virtual time advances exactly 2^0 = 1 ns per executed instruction, and SysTick, clocked
// from the processor clock (CSR.CLKSOURCE = 1: the board's 25 MHz SYSCLK in QEMU's mps2.c),
// decrements once per 40 ns.  So one SysTick tick = 40 instructions.  The SysTick test below
// checks that ratio with loops of known length written in assembly (and the wrap counting with a
// short reload); the step measurement uses it.  Every measurement window restarts the counter
// (a write to SYST_CVR), which also aligns its phase, so the counts are deterministic.  The
// resolution is one tick: a window of N instructions (step plus its call and return, a handful)
// reads t ticks with 40 t - 40 < N < 40 t + 40; t * 40 is reported and the budget is checked on
// the upper bound 40 (t + 1).
// 24-bit wrap: SYST_RVR = 0xFFFFFF (16,777,216 ticks = 671 M instructions per period); each
// underflow (1 -> 0) raises the SysTick exception, whose handler counts wraps, and a window read
// with interrupts masked also counts a wrap whose exception is still pending.  A step never
// comes near one period, so no exception lands inside a measured step (it would add its
// instructions and its stack frame); the SysTick test exercises the wrap path.
//
// Stack: the whole free stack (from the linker's __stack_limit up to the stack pointer at the
// call) holds a pattern before every call; after the call the lowest word that no longer holds it
// gives the call's stack depth (stack pointer at the call minus that address), and the words the
// call wrote are painted again.  Exact for the scenarios run; init is measured the same way.
// This runner gets a 64 KiB stack (tests/budget/CMakeLists.txt) so that even a call far over
// the 8 KiB budget is measured, not overflowed (QEMU ignores writes below RAM).
//
// The firmware library is built with the cortex-m4 preset's flags (MinSizeRel: -Os, -mcpu=cortex-m4
// -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -ffunction-sections -fdata-sections): the numbers
// are those of the firmware as the preset ships it.
#include <cstddef>
#include <cstdint>

#include "kinetics_harness.hpp"
#include "portable_check.hpp"
#include "scenario_registry.hpp"

#ifndef SCOPEKIN_BUDGET_INSTRUCTIONS_PER_STEP
#error "SCOPEKIN_BUDGET_INSTRUCTIONS_PER_STEP must be defined (tests/budget/CMakeLists.txt)"
#endif
#ifndef SCOPEKIN_BUDGET_STACK_BYTES
#error "SCOPEKIN_BUDGET_STACK_BYTES must be defined (tests/budget/CMakeLists.txt)"
#endif

extern "C" {
// Linker script symbols (firmware/platform/cortex_m4/mps2_an386.ld): the stack region.
extern std::uint32_t __stack_limit[];
extern std::uint32_t __stack_top[];
void SysTick_Handler(void);
}

namespace {

using scopekin::portable_check::write_text;
using scopekin::portable_check::write_unsigned;

// --- SysTick ------------------------------------------------------------------------------------

constexpr std::uintptr_t kSystCsr = 0xE000E010U;    // control and status
constexpr std::uintptr_t kSystRvr = 0xE000E014U;    // reload value
constexpr std::uintptr_t kSystCvr = 0xE000E018U;    // current value
constexpr std::uintptr_t kSystCalib = 0xE000E01CU;  // calibration
constexpr std::uintptr_t kScbIcsr = 0xE000ED04U;    // interrupt control and state
constexpr std::uint32_t kCsrEnable = 1U << 0U;
constexpr std::uint32_t kCsrTickInt = 1U << 1U;
constexpr std::uint32_t kCsrClkSourceCpu = 1U << 2U;
constexpr std::uint32_t kIcsrPendStSet = 1U << 26U;
constexpr std::uint32_t kIcsrPendStClr = 1U << 25U;
constexpr std::uint32_t kFullReload = 0x00FFFFFFU;

// The ratio the measurement relies on, from first principles; the SysTick test checks it.
constexpr std::uint32_t kCpuClockHz = 25'000'000U;  // QEMU hw/arm/mps2.c SYSCLK_FRQ
constexpr std::uint32_t kNsPerInstruction = 1U;     // -icount shift=0: 2^0 ns per instruction
constexpr std::uint32_t kInstructionsPerTick = 1'000'000'000U / kCpuClockHz / kNsPerInstruction;
static_assert(kInstructionsPerTick == 40U);

volatile std::uint32_t& reg(std::uintptr_t address) noexcept {
    return *reinterpret_cast<volatile std::uint32_t*>(address);
}

volatile std::uint32_t g_wraps = 0;  // SysTick underflows since the window opened
std::uint32_t g_reload = kFullReload;

void systick_configure(std::uint32_t reload) noexcept {
    reg(kSystCsr) = 0U;
    reg(kSystRvr) = reload;
    reg(kSystCvr) = 0U;
    reg(kScbIcsr) = kIcsrPendStClr;
    g_reload = reload;
    g_wraps = 0U;
    reg(kSystCsr) = kCsrClkSourceCpu | kCsrTickInt | kCsrEnable;
}

/// Restarts the count (SYST_CVR write: count 0, reload on the next edge, no exception) and waits
/// for the reload edge.  Returns the count at the start of the window.
[[gnu::always_inline]] inline std::uint32_t window_open() noexcept {
    reg(kSystCvr) = 0U;
    reg(kScbIcsr) = kIcsrPendStClr;
    g_wraps = 0U;
    std::uint32_t value = 0U;
    do {
        value = reg(kSystCvr);
    } while (value == 0U);
    return value;
}

/// Ticks since position 0 of the period (count == reload) after `wraps` underflows.  The count
/// runs reload, reload-1, ..., 1, 0 (one tick each) and the underflow exception comes with the
/// step 1 -> 0, so at count 0 the wrap of the current period is already counted.
[[gnu::always_inline]] inline std::int64_t position(std::uint32_t wraps,
                                                    std::uint32_t value) noexcept {
    const std::int64_t periods = static_cast<std::int64_t>(wraps) - (value == 0U ? 1 : 0);
    return periods * (static_cast<std::int64_t>(g_reload) + 1) +
           (static_cast<std::int64_t>(g_reload) - static_cast<std::int64_t>(value));
}

/// Ticks since window_open() returned `start`.
[[gnu::always_inline]] inline std::uint64_t window_close(std::uint32_t start) noexcept {
    __asm__ volatile("cpsid i" ::: "memory");
    std::uint32_t wraps = g_wraps;
    std::uint32_t value = reg(kSystCvr);
    if ((reg(kScbIcsr) & kIcsrPendStSet) != 0U) {
        // An underflow whose exception has not run yet: count it, and read the value after it.
        value = reg(kSystCvr);
        wraps += 1U;
    }
    __asm__ volatile("cpsie i" ::: "memory");
    return static_cast<std::uint64_t>(position(wraps, value) - position(0U, start));
}

/// Exactly 2 * n instructions (n >= 1): `subs` and a taken/not-taken `bne` per iteration.
[[gnu::always_inline]] inline void spin(std::uint32_t n) noexcept {
    __asm__ volatile(
        "1:\n\t"
        "subs %0, %0, #1\n\t"
        "bne 1b\n\t"
        : "+r"(n)
        :
        : "cc");
}

[[gnu::noinline]] std::uint64_t ticks_of_spin(std::uint32_t n) noexcept {
    const std::uint32_t start = window_open();
    spin(n);
    return window_close(start);
}

[[gnu::noinline]] std::uint64_t ticks_of_empty_window() noexcept {
    const std::uint32_t start = window_open();
    return window_close(start);
}

// --- stack painting -----------------------------------------------------------------------------

constexpr std::uint32_t kPaint = 0xC5AC3A5CU;  // not a byte repeat, not a small integer

[[gnu::always_inline]] inline std::uintptr_t stack_pointer() noexcept {
    std::uintptr_t sp = 0;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

/// Paints the stack words in [from, sp).  Inlined into the measuring function, so it runs at
/// that function's stack depth (sp) and paints nothing it still uses.
[[gnu::always_inline]] inline void paint_stack(std::uintptr_t from, std::uintptr_t sp) noexcept {
    for (auto* word = reinterpret_cast<volatile std::uint32_t*>(from);
         reinterpret_cast<std::uintptr_t>(word) < sp; ++word) {
        *word = kPaint;
    }
}

/// The lowest address below `sp` written since it was painted (sp if none).
[[gnu::always_inline]] inline std::uintptr_t lowest_written(std::uintptr_t sp) noexcept {
    const volatile std::uint32_t* word = __stack_limit;
    while (reinterpret_cast<std::uintptr_t>(word) < sp && *word == kPaint) {
        ++word;
    }
    return reinterpret_cast<std::uintptr_t>(word);
}

/// Stack bytes the call just measured used below `sp`; repaints them for the next call (the
/// words below were never touched, so each call costs a scan plus its own depth, not a full
/// repaint).
[[gnu::always_inline]] inline std::uint32_t take_stack_used(std::uintptr_t sp) noexcept {
    const std::uintptr_t lowest = lowest_written(sp);
    paint_stack(lowest, sp);
    return static_cast<std::uint32_t>(sp - lowest);
}

// --- output -------------------------------------------------------------------------------------

void write_key(const char* key, std::uint64_t value, bool last = false) noexcept {
    write_text("\"");
    write_text(key);
    write_text("\": ");
    write_unsigned(value);
    if (!last) {
        write_text(", ");
    }
}

// --- the firmware under measurement -------------------------------------------------------------

scopekin::kinetics::State g_state;  // static storage, as in the firmware (10-30 KiB to come)
scopekin::kinetics::Outputs g_outputs;

struct ScenarioBudget {
    std::uint64_t steps;
    std::uint64_t ticks_max;
    std::uint64_t ticks_max_step;
    std::uint64_t ticks_sum;
    std::uint32_t stack_max;
    std::uint32_t stack_max_step;
    std::uint64_t init_ticks;
    std::uint32_t init_stack;
    std::uint32_t depth_at_call;  // __stack_top - sp at the call (this runner's own frames)
};

[[gnu::noinline]] ScenarioBudget measure(const scopekin::test_data::Scenario& scenario) noexcept {
    ScenarioBudget b{};
    const scopekin::kinetics::Config config = scopekin::kinetics::default_config();
    const std::uintptr_t sp = stack_pointer();
    b.depth_at_call =
        static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(__stack_top) - sp);

    paint_stack(reinterpret_cast<std::uintptr_t>(__stack_limit), sp);  // the whole free stack
    std::uint32_t start = window_open();
    scopekin::kinetics::init(config, g_state);
    b.init_ticks = window_close(start);
    b.init_stack = take_stack_used(sp);

    for (std::size_t i = 0; i < scenario.step_count; ++i) {  // bound: the scenario's length
        const scopekin::kinetics::Inputs inputs = scopekin::budget::to_inputs(scenario.steps[i]);
        start = window_open();
        scopekin::kinetics::step(inputs, g_state, g_outputs);
        const std::uint64_t ticks = window_close(start);
        const std::uint32_t stack = take_stack_used(sp);
        b.ticks_sum += ticks;
        if (ticks > b.ticks_max) {
            b.ticks_max = ticks;
            b.ticks_max_step = i;
        }
        if (stack > b.stack_max) {
            b.stack_max = stack;
            b.stack_max_step = static_cast<std::uint32_t>(i);
        }
    }
    b.steps = scenario.step_count;
    return b;
}

SCOPEKIN_TEST(SysTick, OneTickIsFortyInstructionsUnderIcount) {
    const std::uint32_t calib = reg(kSystCalib);
    systick_configure(kFullReload);
    const std::uint32_t csr = reg(kSystCsr);
    SCOPEKIN_EXPECT_TRUE((csr & kCsrClkSourceCpu) != 0U);  // processor clock selected

    // Coarse: two loops 2,000,000 instructions apart -> 50,000 ticks apart (+-1 for quantisation).
    constexpr std::uint32_t n_short = 250'000U;
    constexpr std::uint32_t n_long = 1'250'000U;
    const std::uint64_t ticks_short = ticks_of_spin(n_short);
    const std::uint64_t ticks_long = ticks_of_spin(n_long);
    const std::uint64_t delta_instructions = 2U * (n_long - n_short);
    const std::uint64_t delta_ticks = ticks_long - ticks_short;
    const std::uint64_t expected_ticks = delta_instructions / kInstructionsPerTick;
    SCOPEKIN_EXPECT_TRUE(delta_ticks + 1U >= expected_ticks && delta_ticks <= expected_ticks + 1U);

    // Fine: loops of 1000 .. 1099 iterations, 2 instructions apart.  The window's phase is fixed,
    // so the count must step by exactly one tick every 40 instructions = every 20 iterations.
    std::uint64_t previous = ticks_of_spin(1000U);
    std::uint32_t first_step_at = 0U;
    std::uint32_t steps_seen = 0U;
    bool fine_ok = true;
    for (std::uint32_t k = 1U; k < 100U; ++k) {
        const std::uint64_t ticks = ticks_of_spin(1000U + k);
        if (ticks == previous + 1U) {
            if (steps_seen == 0U) {
                first_step_at = k;
            } else if ((k - first_step_at) != 20U * steps_seen) {
                fine_ok = false;
            }
            ++steps_seen;
        } else if (ticks != previous) {
            fine_ok = false;
        }
        previous = ticks;
    }
    SCOPEKIN_EXPECT_TRUE(fine_ok);
    SCOPEKIN_EXPECT_TRUE(steps_seen == 4U || steps_seen == 5U);

    // Wrap counting: a reload of 9,999 (10,000 ticks = 400,000 instructions per period) makes
    // the long loop (62,500 ticks) wrap 6 times; the result must match the unwrapped
    // measurement, up to the handler's few instructions per wrap.
    constexpr std::uint32_t short_reload = 9'999U;
    systick_configure(short_reload);
    const std::uint64_t ticks_wrapped = ticks_of_spin(n_long);
    const std::uint32_t wraps = g_wraps;
    systick_configure(kFullReload);
    const std::uint64_t ticks_unwrapped = ticks_of_spin(n_long);
    SCOPEKIN_EXPECT_EQ(static_cast<std::uint64_t>(wraps), ticks_unwrapped / (short_reload + 1U));
    SCOPEKIN_EXPECT_TRUE(ticks_wrapped >= ticks_unwrapped && ticks_wrapped <= ticks_unwrapped + 2U);

    const std::uint64_t empty_ticks = ticks_of_empty_window();

    write_text("@budget {\"calibration\": {");
    write_key("instructions_per_tick_assumed", kInstructionsPerTick);
    write_key("cpu_clock_hz", kCpuClockHz);
    write_key("syst_calib", calib);
    // SYST_CALIB: bit 31 NOREF (no reference clock), bits 23:0 TENMS (ref ticks in 10 ms - 1).
    write_key("reference_clock_hz", (calib >> 31U) != 0U ? 0U : ((calib & 0xFFFFFFU) + 1U) * 100U);
    write_key("syst_csr", csr);
    write_key("loop_short_instructions", 2ULL * n_short);
    write_key("loop_short_ticks", ticks_short);
    write_key("loop_long_instructions", 2ULL * n_long);
    write_key("loop_long_ticks", ticks_long);
    write_key("delta_instructions", delta_instructions);
    write_key("delta_ticks", delta_ticks);
    write_key("fine_loop_first_tick_step_at_iteration", first_step_at);
    write_key("fine_loop_tick_steps_over_100_iterations", steps_seen);
    write_key("fine_loop_ok", fine_ok ? 1U : 0U);
    write_key("wrap_test_reload", short_reload);
    write_key("wrap_test_wraps", wraps);
    write_key("wrap_test_ticks", ticks_wrapped);
    write_key("wrap_test_ticks_unwrapped", ticks_unwrapped);
    write_key("empty_window_ticks", empty_ticks, true);
    write_text("}}\n");
}

SCOPEKIN_TEST(StepBudget, InstructionsAndStackPerStep) {
    systick_configure(kFullReload);
    std::uint64_t worst_ticks = 0;
    std::uint32_t worst_stack = 0;
    for (const scopekin::test_data::Scenario* scenario : scopekin::test_data::all_scenarios) {
        const ScenarioBudget b = measure(*scenario);
        write_text("@budget {\"scenario\": {\"name\": \"");
        write_text(scenario->name);
        write_text("\", ");
        write_key("steps", b.steps);
        write_key("ticks_max", b.ticks_max);
        write_key("ticks_max_at_step", b.ticks_max_step);
        write_key("ticks_sum", b.ticks_sum);
        write_key("instructions_per_tick", kInstructionsPerTick);
        write_key("stack_bytes", b.stack_max);
        write_key("stack_max_at_step", b.stack_max_step);
        write_key("init_ticks", b.init_ticks);
        write_key("init_stack_bytes", b.init_stack);
        write_key("runner_stack_depth_at_call_bytes", b.depth_at_call, true);
        write_text("}}\n");
        worst_ticks = b.ticks_max > worst_ticks ? b.ticks_max : worst_ticks;
        worst_stack = b.stack_max > worst_stack ? b.stack_max : worst_stack;
        SCOPEKIN_EXPECT_TRUE(b.steps > 0U);
    }
    // Bounds, conservatively: a window of t ticks held at most (t + 1) * 40 instructions.
    const std::uint64_t worst_instructions_upper = (worst_ticks + 1U) * kInstructionsPerTick;
    write_text("[ budget ] instructions per step, max over all scenarios: ");
    write_unsigned(worst_ticks * kInstructionsPerTick);
    write_text(" (upper bound ");
    write_unsigned(worst_instructions_upper);
    write_text(", budget ");
    write_unsigned(SCOPEKIN_BUDGET_INSTRUCTIONS_PER_STEP);
    write_text(")\n[ budget ] stack of step, max over all scenarios: ");
    write_unsigned(worst_stack);
    write_text(" bytes (budget ");
    write_unsigned(SCOPEKIN_BUDGET_STACK_BYTES);
    write_text(")\n");
    SCOPEKIN_EXPECT_TRUE(worst_instructions_upper <= SCOPEKIN_BUDGET_INSTRUCTIONS_PER_STEP);
    SCOPEKIN_EXPECT_TRUE(worst_stack <= SCOPEKIN_BUDGET_STACK_BYTES);
}

}  // namespace

extern "C" void SysTick_Handler(void) {
    g_wraps = g_wraps + 1U;
}
