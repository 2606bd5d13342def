// AdvanceEfficiency (firmware/monitors/advance_efficiency.hpp): hand-made position sequences
// with answers computed by hand.  Runs as GoogleTest on x86-64 / aarch64 and with
// portable_check's runner on Cortex-M4.
//
// Units: mm per 5 ms step.  0.125 mm/step = 25 mm/s = 8192 raw per step (exact in Q16.16).
#include <cstdint>

#include "fixed_point/q_format.hpp"
#include "monitors/advance_efficiency.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::monitors::AdvanceEfficiency;
using Efficiency = AdvanceEfficiency<>;

constexpr std::int32_t kEighthRaw = 8192;  // 0.125 mm

constexpr Q16_16 raw(std::int32_t r) {
    return Q16_16::from_raw(r);
}
/// Handle (or a 1:1 tip) after `step` steps at 0.125 mm/step.
constexpr Q16_16 at_25mm_per_s(std::int32_t step) {
    return raw(kEighthRaw * step);
}

static_assert(Efficiency::valid(Efficiency::Config{}), "the defaults are a valid config");
static_assert(Efficiency::capacity == 64);

/// |a - b| in raw LSB.
std::int32_t lsb_apart(Q16_16 a, Q16_16 b) {
    const std::int32_t d = a.raw() - b.raw();
    return d < 0 ? -d : d;
}

}  // namespace

SCOPEKIN_TEST(AdvanceEfficiency, RampPairAtThreeTenthsGivesThreeTenths) {
    // Handle at 0.125 mm/step, tip at 0.3 x that (0.0375 mm/step, not exact in Q16.16: each tip
    // sample is rounded on its own, from_ratio(3 i, 80) = round(0.0375 i * 2^16)).
    // Over 50 steps: handle advance 6.25 mm exactly, tip advance 1.875 mm +- 1 LSB, so the ratio is
    // 0.3 +- 0.16 LSB before the division's own 0.5 LSB: 0.3 = 19660.8 raw -> 19661 +- 1.
    Efficiency e;
    SCOPEKIN_EXPECT_TRUE(e.init(Efficiency::Config{}));
    const Q16_16 three_tenths = Q16_16::from_ratio(3, 10);
    SCOPEKIN_EXPECT_EQ(three_tenths.raw(), 19661);
    std::int32_t defined_steps = 0;
    for (std::int32_t i = 0; i < 300; ++i) {  // 300 > 65 slots: the ring wraps four times
        const auto out = e.step({Q16_16::from_ratio(3 * i, 80), at_25mm_per_s(i)});
        if (i < 50) {
            // Fewer than 51 samples: the window is not full, undefined, initial value 1 held.
            SCOPEKIN_EXPECT_TRUE(!out.defined);
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), Q16_16::from_int(1).raw());
            SCOPEKIN_EXPECT_EQ(out.handle_advance_mm.raw(), 0);
        } else {
            SCOPEKIN_EXPECT_TRUE(out.defined);
            SCOPEKIN_EXPECT_EQ(out.handle_advance_mm.raw(), 50 * kEighthRaw);       // 6.25 mm
            SCOPEKIN_EXPECT_TRUE(lsb_apart(out.tip_advance_mm, raw(122880)) <= 1);  // 1.875 mm
            SCOPEKIN_EXPECT_TRUE(lsb_apart(out.efficiency, three_tenths) <= 1);
            SCOPEKIN_EXPECT_TRUE(!out.clamped);
            ++defined_steps;
        }
        SCOPEKIN_EXPECT_TRUE(!out.input_fault);
    }
    SCOPEKIN_EXPECT_EQ(defined_steps, 250);
}

SCOPEKIN_TEST(AdvanceEfficiency, OneToOneAdvanceIsExactlyOne) {
    Efficiency e;
    e.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 200; ++i) {
        const auto out = e.step({at_25mm_per_s(i), at_25mm_per_s(i) + Q16_16::from_int(300)});
        if (i >= 50) {
            SCOPEKIN_EXPECT_TRUE(out.defined);
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 65536);
        }
    }
}

SCOPEKIN_TEST(AdvanceEfficiency, WindowWrapAroundWithShortAndFullCapacityWindows) {
    // Tip at half the handle speed until step 99, then 1:1.  With window N the efficiency at
    // step i is (tip[i] - tip[i-N]) / (handle[i] - handle[i-N]); computed by hand below.
    const std::uint16_t windows[] = {7, 64};
    for (const std::uint16_t n : windows) {  // bound: 2
        Efficiency e;
        Efficiency::Config config{};
        config.window_steps = n;
        config.advancing_steps = 5;
        config.min_handle_advance_mm = Q16_16::from_ratio(1, 2);  // 7 steps give 0.875 mm
        SCOPEKIN_EXPECT_TRUE(e.init(config));
        // tip[i] = i * 4096 raw for i <= 99, then 99 * 4096 + (i - 99) * 8192.
        auto tip_raw = [](std::int32_t i) {
            return i <= 99 ? i * 4096 : 99 * 4096 + (i - 99) * kEighthRaw;
        };
        const std::int32_t window = n;
        for (std::int32_t i = 0; i < 400; ++i) {
            const auto out = e.step({raw(tip_raw(i)), at_25mm_per_s(i)});
            if (i < window) {
                SCOPEKIN_EXPECT_TRUE(!out.defined);
                continue;
            }
            SCOPEKIN_EXPECT_TRUE(out.defined);
            const std::int32_t tip_advance = tip_raw(i) - tip_raw(i - window);
            SCOPEKIN_EXPECT_EQ(out.tip_advance_mm.raw(), tip_advance);
            SCOPEKIN_EXPECT_EQ(out.handle_advance_mm.raw(), window * kEighthRaw);
            if (i <= 99) {
                SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 32768);  // 0.5
            } else if (i - window >= 99) {
                SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 65536);  // 1
            } else {
                // k = i - 99 steps at full speed, window - k at half speed:
                // e = (k + (window - k) / 2) / window = (window + k) / (2 window).
                const std::int32_t k = i - 99;
                SCOPEKIN_EXPECT_EQ(out.efficiency.raw(),
                                   Q16_16::from_ratio(window + k, 2 * window).raw());
            }
        }
    }
}

SCOPEKIN_TEST(AdvanceEfficiency, UndefinedBelowTheMinimumHandleAdvanceHoldsTheLastValue) {
    // Steps 0..99: handle 0.125 mm/step, tip 0.0625 mm/step (e = 0.5 from step 50).
    // Step 100 on: both stop (a hold).  Handle advance over the window at step i >= 100:
    // 0.125 * (149 - i) mm >= 2 mm  <=>  i <= 133.  So defined up to step 133, held from 134.
    Efficiency e;
    e.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 400; ++i) {
        const std::int32_t moving = i <= 99 ? i : 99;
        const auto out = e.step({raw(4096 * moving), at_25mm_per_s(moving)});
        if (i >= 50 && i <= 133) {
            SCOPEKIN_EXPECT_TRUE(out.defined);
        } else {
            SCOPEKIN_EXPECT_TRUE(!out.defined);
        }
        if (i >= 50) {
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 32768);  // 0.5, held after step 133
        }
        if (i == 133) {
            SCOPEKIN_EXPECT_EQ(out.handle_advance_mm.raw(), 16 * kEighthRaw);  // 2 mm
        }
        if (i == 134) {
            SCOPEKIN_EXPECT_EQ(out.handle_advance_mm.raw(), 15 * kEighthRaw);  // 1.875 mm
        }
    }
    SCOPEKIN_EXPECT_EQ(e.efficiency().raw(), 32768);
}

SCOPEKIN_TEST(AdvanceEfficiency, WithdrawalIsUndefined) {
    Efficiency e;
    e.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 200; ++i) {
        const Q16_16 depth = Q16_16::from_int(500) - at_25mm_per_s(i);  // pulling back
        const auto out = e.step({depth, depth});
        SCOPEKIN_EXPECT_TRUE(!out.defined);
        SCOPEKIN_EXPECT_TRUE(!out.handle_advancing);
        SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 65536);  // initial value held
    }
}

SCOPEKIN_TEST(AdvanceEfficiency, HandleAdvancingUsesTheShortWindow) {
    // Default short window: 10 steps, 0.4 mm.
    Efficiency e;
    e.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 40; ++i) {
        const auto out = e.step({at_25mm_per_s(i), at_25mm_per_s(i)});
        // Needs 11 samples; then 10 * 0.125 = 1.25 mm >= 0.4 mm.
        SCOPEKIN_EXPECT_EQ(out.handle_advancing, i >= 10);
        if (i >= 10) {
            SCOPEKIN_EXPECT_EQ(out.handle_recent_advance_mm.raw(), 10 * kEighthRaw);
        }
    }
    // Hand stops at step 39 (last moving sample): recent advance at step 39 + j is
    // 0.125 * (10 - j) mm >= 0.4 mm  <=>  j <= 6.
    for (std::int32_t j = 1; j < 20; ++j) {
        const auto out = e.step({at_25mm_per_s(39), at_25mm_per_s(39)});
        SCOPEKIN_EXPECT_EQ(out.handle_advancing, j <= 6);
    }
    // Creeping at 6 mm/s (0.03 mm/step): 0.3 mm in 10 steps < 0.4 mm -> not advancing.
    Efficiency slow;
    slow.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 100; ++i) {
        const Q16_16 x = Q16_16::from_ratio(3 * i, 100);
        const auto out = slow.step({x, x});
        SCOPEKIN_EXPECT_TRUE(!out.handle_advancing);
        SCOPEKIN_EXPECT_TRUE(!out.defined);  // 1.5 mm per window < 2 mm
    }
}

SCOPEKIN_TEST(AdvanceEfficiency, ClampsToPlusMinusTwo) {
    Efficiency e;
    e.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 60; ++i) {
        const auto out = e.step({at_25mm_per_s(3 * i), at_25mm_per_s(i)});  // tip 3x the handle
        if (i >= 50) {
            SCOPEKIN_EXPECT_TRUE(out.defined && out.clamped);
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 2 * 65536);
        }
    }
    Efficiency back;
    back.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 60; ++i) {
        const auto out = back.step({Q16_16::from_int(100) - at_25mm_per_s(3 * i),
                                    at_25mm_per_s(i)});  // paradoxical: tip goes back 3x
        if (i >= 50) {
            SCOPEKIN_EXPECT_TRUE(out.defined && out.clamped);
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), -2 * 65536);
        }
    }
}

SCOPEKIN_TEST(AdvanceEfficiency, AbsurdSamplesAreReplacedByTheLastValidOne) {
    // 1:1 advance; at step 100 the tip is saturated, at step 120 the handle is 6000 mm away.
    Efficiency e;
    e.init(Efficiency::Config{});
    for (std::int32_t i = 0; i < 200; ++i) {
        Q16_16 tip = at_25mm_per_s(i);
        Q16_16 handle = at_25mm_per_s(i);
        if (i == 100) tip = Q16_16::max();
        if (i == 120) handle = Q16_16::from_int(6000);
        const auto out = e.step({tip, handle});
        SCOPEKIN_EXPECT_EQ(out.input_fault, i == 100 || i == 120);
        // A replaced sample is inside the 51-sample window from step 100 to 170.
        SCOPEKIN_EXPECT_EQ(out.window_has_substitute, i >= 100 && i <= 170);
        // Every full window still has >= 2 mm of handle advance.
        SCOPEKIN_EXPECT_EQ(out.defined, i >= 50);
        if (i == 100) {
            // tip[100] := tip[99]: (49 * 0.125) / (50 * 0.125) = 0.98 -> 64225.28 -> 64225
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 64225);
        } else if (i == 120) {
            // handle[120] := handle[119]: 50 / 49 = 1.0204 -> 66873.47 -> 66873
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 66873);
        } else if (i == 150) {
            // tip[100] (= tip[99]) is the oldest sample: 51 / 50 = 1.02 -> 66846.72 -> 66847
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 66847);
        } else if (i == 170) {
            // handle[120] (= handle[119]) is the oldest: 50 / 51 -> 64250.98 -> 64251
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 64251);
        } else if (i >= 50) {
            SCOPEKIN_EXPECT_EQ(out.efficiency.raw(), 65536);
        }
    }
    // Before any valid sample the replacement is 0.
    Efficiency fresh;
    fresh.init(Efficiency::Config{});
    const auto out = fresh.step({Q16_16::min(), Q16_16::from_int(-5001)});
    SCOPEKIN_EXPECT_TRUE(out.input_fault);
    SCOPEKIN_EXPECT_TRUE(!out.defined);
}

SCOPEKIN_TEST(AdvanceEfficiency, InvalidConfigFallsBackToDefaults) {
    Efficiency e;
    Efficiency::Config bad{};
    bad.window_steps = 65;  // > capacity 64
    SCOPEKIN_EXPECT_TRUE(!e.init(bad));
    SCOPEKIN_EXPECT_TRUE(e.config_fault());
    SCOPEKIN_EXPECT_EQ(e.config().window_steps, 50);

    bad = Efficiency::Config{};
    bad.advancing_steps = 51;  // > window
    SCOPEKIN_EXPECT_TRUE(!e.init(bad));
    bad = Efficiency::Config{};
    bad.window_steps = 0;
    SCOPEKIN_EXPECT_TRUE(!e.init(bad));
    bad = Efficiency::Config{};
    bad.min_handle_advance_mm = Q16_16{};  // would divide by 0
    SCOPEKIN_EXPECT_TRUE(!e.init(bad));
    bad = Efficiency::Config{};
    bad.max_abs_position_mm = Q16_16::from_int(20000);
    SCOPEKIN_EXPECT_TRUE(!e.init(bad));

    SCOPEKIN_EXPECT_TRUE(e.init(Efficiency::Config{}));
    SCOPEKIN_EXPECT_TRUE(!e.config_fault());

    // A smaller capacity clamps the default windows.
    AdvanceEfficiency<16> small;
    AdvanceEfficiency<16>::Config small_bad{};  // window 50 > 16: invalid
    SCOPEKIN_EXPECT_TRUE(!small.init(small_bad));
    SCOPEKIN_EXPECT_EQ(small.config().window_steps, 16);
    SCOPEKIN_EXPECT_EQ(small.config().advancing_steps, 10);
}
