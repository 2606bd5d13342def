// SelfLockMonitor and the stick test (firmware/monitors/self_lock_monitor.hpp), alone and fed
// by AdvanceEfficiency, on hand-made step sequences with step counts computed by hand from the
// defaults (5 ms steps; T_on = 20, T_off = 100 steps; short advancing window 10 steps / 0.4 mm;
// efficiency window 50 steps / 2 mm; confirm 0.5, clear 0.7).
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <array>
#include <cstdint>

#include "fixed_point/q_format.hpp"
#include "monitors/advance_efficiency.hpp"
#include "monitors/self_lock_monitor.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::monitors::AdvanceEfficiency;
using scopekin::monitors::classify_stick;
using scopekin::monitors::count_sticking;
using scopekin::monitors::DistalContact;
using scopekin::monitors::SelfLockMonitor;
using scopekin::monitors::StickCriterion;
using scopekin::monitors::StickState;

constexpr Q16_16 raw(std::int32_t r) {
    return Q16_16::from_raw(r);
}
constexpr Q16_16 kOne = Q16_16::from_int(1);
constexpr std::int32_t kEighthRaw = 8192;  // 0.125 mm per step = 25 mm/s

/// Monitor inputs of a plain advance / self-lock / hold, given directly.
SelfLockMonitor::Inputs inputs(std::uint8_t sticking, bool advancing, Q16_16 efficiency,
                               bool defined) {
    SelfLockMonitor::Inputs in{};
    in.distal_sticking = sticking;
    in.handle_advancing = advancing;
    in.efficiency = efficiency;
    in.efficiency_defined = defined;
    return in;
}

/// One step of the chain AdvanceEfficiency -> SelfLockMonitor.
SelfLockMonitor::Outputs chain_step(AdvanceEfficiency<>& efficiency, SelfLockMonitor& monitor,
                                    std::int32_t tip_raw, std::int32_t handle_raw,
                                    std::uint8_t sticking) {
    const auto e = efficiency.step({raw(tip_raw), raw(handle_raw)});
    return monitor.step(inputs(sticking, e.handle_advancing, e.efficiency, e.defined));
}

}  // namespace

// ---- stick test --------------------------------------------------------------------------

SCOPEKIN_TEST(StickTest, ComparesWithoutAtanAtTheMarginExactly) {
    // f_n = 2 N, mu = 0.25: cone |f_T| < mu f_n = 0.5 N; with the 0.95 margin 0.475 N.
    // mu_eff = mul_sat(0.95 = 62259 raw, 0.25 = 16384 raw) = 15564.75 -> 15565 raw.
    // Stick iff f_T_raw * 65536 < 15565 * 131072  <=>  f_T_raw < 31130.
    const Q16_16 fn = Q16_16::from_int(2);
    const Q16_16 mu = Q16_16::from_ratio(1, 4);
    SCOPEKIN_EXPECT_EQ(classify_stick(fn, raw(31129), mu) == StickState::sticking, true);
    SCOPEKIN_EXPECT_EQ(classify_stick(fn, raw(31130), mu) == StickState::slipping, true);
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16{}, mu) == StickState::sticking);
    // On the cone (a slipping contact, possibly a few LSB inside after rounding): slipping.
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16::from_ratio(1, 2), mu) == StickState::slipping);
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, raw(32765), mu) == StickState::slipping);
    // Frictionless contact never sticks.
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16{}, Q16_16{}) == StickState::slipping);
    // Below 0.05 N (3277 raw): no contact.
    SCOPEKIN_EXPECT_TRUE(classify_stick(raw(3276), Q16_16{}, mu) == StickState::no_contact);
    SCOPEKIN_EXPECT_TRUE(classify_stick(raw(3277), Q16_16{}, mu) == StickState::sticking);
    SCOPEKIN_EXPECT_TRUE(classify_stick(Q16_16{}, Q16_16{}, mu) == StickState::no_contact);
    // The thesis's high-friction bend (mu = 1.2): 10 N normal, 11 N tangential -> stick.
    SCOPEKIN_EXPECT_TRUE(classify_stick(Q16_16::from_int(10), Q16_16::from_int(11),
                                        Q16_16::from_ratio(6, 5)) == StickState::sticking);
}

SCOPEKIN_TEST(StickTest, AbsurdInputsAreInvalid) {
    const Q16_16 fn = Q16_16::from_int(2);
    const Q16_16 mu = Q16_16::from_ratio(1, 4);
    SCOPEKIN_EXPECT_TRUE(classify_stick(Q16_16::from_int(-1), Q16_16{}, mu) == StickState::invalid);
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16::from_int(-1), mu) == StickState::invalid);
    SCOPEKIN_EXPECT_TRUE(classify_stick(Q16_16::max(), Q16_16{}, mu) == StickState::invalid);
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16::max(), mu) == StickState::invalid);
    SCOPEKIN_EXPECT_TRUE(classify_stick(Q16_16::from_int(1001), Q16_16{}, mu) ==
                         StickState::invalid);
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16{}, Q16_16::from_ratio(-1, 10)) ==
                         StickState::invalid);
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16{}, Q16_16::from_ratio(21, 10)) ==
                         StickState::invalid);
    StickCriterion bad{};
    bad.stick_ratio = Q16_16::from_ratio(11, 10);  // > 1
    SCOPEKIN_EXPECT_TRUE(classify_stick(fn, Q16_16{}, mu, bad) == StickState::invalid);
}

SCOPEKIN_TEST(StickTest, CountsOnlyActiveValidStickingContacts) {
    const Q16_16 mu = Q16_16::from_ratio(1, 4);
    const std::array<DistalContact, 3> contacts{{
        {Q16_16::from_int(2), Q16_16::from_ratio(1, 10), mu},  // stick (0.1 < 0.475)
        {Q16_16::from_int(2), Q16_16::from_ratio(1, 2), mu},   // slip (on the cone)
        {Q16_16::from_int(-3), Q16_16{}, mu},                  // absurd
    }};
    auto count = count_sticking(contacts, 3);
    SCOPEKIN_EXPECT_EQ(count.sticking, 1);
    SCOPEKIN_EXPECT_EQ(count.invalid, 1);
    count = count_sticking(contacts, 2);
    SCOPEKIN_EXPECT_EQ(count.sticking, 1);
    SCOPEKIN_EXPECT_EQ(count.invalid, 0);
    count = count_sticking(contacts, 0);
    SCOPEKIN_EXPECT_EQ(count.sticking, 0);
    count = count_sticking(contacts, 7);  // more than the capacity: the capacity bounds it
    SCOPEKIN_EXPECT_EQ(count.sticking, 1);
    SCOPEKIN_EXPECT_EQ(count.invalid, 1);
}

// ---- the monitor on direct inputs --------------------------------------------------------

SCOPEKIN_TEST(SelfLockMonitor, SteadyAdvanceWithSlipNeverFires) {
    SelfLockMonitor monitor;
    SCOPEKIN_EXPECT_TRUE(monitor.init(SelfLockMonitor::Config{}));
    for (int i = 0; i < 2000; ++i) {
        // Any efficiency: even a poor one does not raise without a distal stick.
        const Q16_16 e = (i / 100) % 2 == 0 ? kOne : Q16_16::from_ratio(3, 10);
        const auto out = monitor.step(inputs(0, true, e, true));
        SCOPEKIN_EXPECT_TRUE(!out.alarm);
        SCOPEKIN_EXPECT_TRUE(!out.condition);
    }
}

SCOPEKIN_TEST(SelfLockMonitor, HoldWithEveryContactStuckNeverFires) {
    SelfLockMonitor monitor;
    monitor.init(SelfLockMonitor::Config{});
    for (int i = 0; i < 2000; ++i) {
        const auto out = monitor.step(inputs(3, false, kOne, false));
        SCOPEKIN_EXPECT_TRUE(!out.alarm);
    }
}

SCOPEKIN_TEST(SelfLockMonitor, FiresOnTheTwentiethStepOfStickWhileAdvancing) {
    SelfLockMonitor monitor;
    monitor.init(SelfLockMonitor::Config{});
    for (int i = 0; i < 100; ++i) {
        SCOPEKIN_EXPECT_TRUE(!monitor.step(inputs(0, true, kOne, true)).alarm);
    }
    // Stick from step 100: alarm false on steps 100..118, true from step 119 (20th step).
    for (int i = 100; i < 200; ++i) {
        const auto out = monitor.step(inputs(1, true, kOne, true));
        SCOPEKIN_EXPECT_EQ(out.alarm, i >= 119);
        SCOPEKIN_EXPECT_EQ(static_cast<int>(out.condition_steps), i - 100 + 1 < 20 ? i - 99 : 20);
        SCOPEKIN_EXPECT_TRUE(!out.confirmed);  // efficiency still 1
    }
}

SCOPEKIN_TEST(SelfLockMonitor, AnInterruptedConditionRestartsTheCount) {
    SelfLockMonitor monitor;
    monitor.init(SelfLockMonitor::Config{});
    for (int i = 0; i < 19; ++i) {
        SCOPEKIN_EXPECT_TRUE(!monitor.step(inputs(1, true, kOne, true)).alarm);
    }
    SCOPEKIN_EXPECT_TRUE(!monitor.step(inputs(1, false, kOne, true)).alarm);  // hand paused
    for (int i = 0; i < 19; ++i) {
        SCOPEKIN_EXPECT_TRUE(!monitor.step(inputs(1, true, kOne, true)).alarm);
    }
    SCOPEKIN_EXPECT_TRUE(monitor.step(inputs(1, true, kOne, true)).alarm);  // 20th in a row
}

SCOPEKIN_TEST(SelfLockMonitor, ClearsOnlyAfterTOffAndAHighEfficiency) {
    SelfLockMonitor monitor;
    monitor.init(SelfLockMonitor::Config{});
    const Q16_16 low = Q16_16::from_ratio(3, 10);
    const Q16_16 good = Q16_16::from_ratio(8, 10);
    for (int i = 0; i < 20; ++i)
        monitor.step(inputs(1, true, low, true));
    SCOPEKIN_EXPECT_TRUE(monitor.alarm());
    // Confirmed: alarm and defined efficiency < 0.5.
    SCOPEKIN_EXPECT_TRUE(monitor.step(inputs(1, true, low, true)).confirmed);

    // Slipping again with a good efficiency: C false; clears on the 100th such step.
    for (int i = 1; i <= 100; ++i) {
        const auto out = monitor.step(inputs(0, true, good, true));
        SCOPEKIN_EXPECT_EQ(out.alarm, i < 100);
        SCOPEKIN_EXPECT_TRUE(!out.confirmed);
    }

    // Again, but C comes back at the 99th step: the off count restarts.
    for (int i = 0; i < 20; ++i)
        monitor.step(inputs(1, true, low, true));
    SCOPEKIN_EXPECT_TRUE(monitor.alarm());
    for (int i = 0; i < 99; ++i)
        monitor.step(inputs(0, true, good, true));
    SCOPEKIN_EXPECT_TRUE(monitor.step(inputs(1, true, good, true)).alarm);
    for (int i = 1; i <= 100; ++i) {
        SCOPEKIN_EXPECT_EQ(monitor.step(inputs(0, true, good, true)).alarm, i < 100);
    }

    // T_off elapsed but the efficiency stays low (0.6 < 0.7): the alarm stays.
    for (int i = 0; i < 20; ++i)
        monitor.step(inputs(1, true, low, true));
    for (int i = 0; i < 500; ++i) {
        SCOPEKIN_EXPECT_TRUE(monitor.step(inputs(0, true, Q16_16::from_ratio(6, 10), true)).alarm);
    }
    // 0.7 exactly is enough.
    SCOPEKIN_EXPECT_TRUE(!monitor.step(inputs(0, true, Q16_16::from_ratio(7, 10), true)).alarm);
}

SCOPEKIN_TEST(SelfLockMonitor, HoldAfterAnAlarmLatchesUntilTheTipFollows) {
    SelfLockMonitor monitor;
    monitor.init(SelfLockMonitor::Config{});
    for (int i = 0; i < 20; ++i)
        monitor.step(inputs(1, true, Q16_16::from_ratio(3, 10), true));
    SCOPEKIN_EXPECT_TRUE(monitor.alarm());
    // Hold: not advancing, efficiency undefined.  Even a held value above 0.7 does not clear.
    for (int i = 0; i < 1000; ++i) {
        SCOPEKIN_EXPECT_TRUE(
            monitor.step(inputs(3, false, Q16_16::from_ratio(9, 10), false)).alarm);
    }
    // Advancing with slip and a good, defined efficiency: T_off already elapsed, clears at once.
    SCOPEKIN_EXPECT_TRUE(!monitor.step(inputs(0, true, Q16_16::from_ratio(9, 10), true)).alarm);
}

SCOPEKIN_TEST(SelfLockMonitor, AbsurdInputsHoldTheState) {
    SelfLockMonitor monitor;
    monitor.init(SelfLockMonitor::Config{});
    for (int i = 0; i < 10; ++i)
        monitor.step(inputs(1, true, kOne, true));
    // 4 distal stations in stick (> max_distal_stations = 3) and an efficiency of 3 (outside
    // [-2, 2]) are absurd: fault flag, counters held.
    auto out = monitor.step(inputs(4, true, kOne, true));
    SCOPEKIN_EXPECT_TRUE(out.input_fault);
    SCOPEKIN_EXPECT_EQ(static_cast<int>(out.condition_steps), 10);
    out = monitor.step(inputs(1, true, Q16_16::from_int(3), true));
    SCOPEKIN_EXPECT_TRUE(out.input_fault && !out.alarm);
    out = monitor.step(inputs(0, true, Q16_16::max(), true));
    SCOPEKIN_EXPECT_TRUE(out.input_fault);
    for (int i = 0; i < 9; ++i) {
        out = monitor.step(inputs(1, true, kOne, true));
        SCOPEKIN_EXPECT_TRUE(!out.alarm && !out.input_fault);
    }
    SCOPEKIN_EXPECT_TRUE(monitor.step(inputs(1, true, kOne, true)).alarm);  // 10 + 10 valid steps
    // With the alarm raised, absurd inputs do not clear it.
    for (int i = 0; i < 300; ++i) {
        out = monitor.step(inputs(200, false, Q16_16::min(), true));
        SCOPEKIN_EXPECT_TRUE(out.alarm && out.input_fault);
    }
}

SCOPEKIN_TEST(SelfLockMonitor, InvalidConfigFallsBackToDefaults) {
    SelfLockMonitor monitor;
    SelfLockMonitor::Config bad{};
    bad.on_steps = 0;
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    SCOPEKIN_EXPECT_TRUE(monitor.config_fault());
    SCOPEKIN_EXPECT_EQ(static_cast<int>(monitor.config().on_steps), 20);
    bad = SelfLockMonitor::Config{};
    bad.clear_efficiency = Q16_16::from_ratio(4, 10);  // below confirm 0.5
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    bad = SelfLockMonitor::Config{};
    bad.min_sticking_stations = 4;  // > max_distal_stations
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    SCOPEKIN_EXPECT_TRUE(monitor.init(SelfLockMonitor::Config{}));
    SCOPEKIN_EXPECT_TRUE(!monitor.config_fault());
}

// ---- AdvanceEfficiency -> SelfLockMonitor ------------------------------------------------

SCOPEKIN_TEST(SelfLockChain, TipStuckWhileHandleAdvancesFiresAfterTheDocumentedSteps) {
    // Handle at 25 mm/s from step 0.  The tip follows 1:1 (slipping) up to step 99 and is stuck
    // from step 100 (tip[i] = tip[99]); one distal station sticks from step 100.
    //   advancing: true from step 10 (11 samples, 1.25 mm >= 0.4 mm)
    //   C from step 100 -> alarm from step 119 (95 ms after the first stuck sample)
    //   efficiency at i in 100..149: (149 - i) / 50; < 0.5 first at i = 125 -> confirmed
    AdvanceEfficiency<> efficiency;
    SelfLockMonitor monitor;
    efficiency.init(AdvanceEfficiency<>::Config{});
    monitor.init(SelfLockMonitor::Config{});
    int first_alarm = -1;
    int first_confirmed = -1;
    for (std::int32_t i = 0; i < 400; ++i) {
        const std::int32_t tip = kEighthRaw * (i <= 99 ? i : 99);
        const auto out = chain_step(efficiency, monitor, tip, kEighthRaw * i, i >= 100 ? 1 : 0);
        if (out.alarm && first_alarm < 0) first_alarm = i;
        if (out.confirmed && first_confirmed < 0) first_confirmed = i;
        SCOPEKIN_EXPECT_EQ(out.alarm, i >= 119);
    }
    SCOPEKIN_EXPECT_EQ(first_alarm, 119);
    SCOPEKIN_EXPECT_EQ(first_confirmed, 125);
}

SCOPEKIN_TEST(SelfLockChain, WorstCaseHandleStartingWithTheStickAtEightMmPerSecond) {
    // Everything at rest and stuck; from step 0 on the handle moves 0.04 mm/step (8 mm/s, the
    // advancing threshold) and the tip does not move.  0.04 mm = 2621.44 raw: positions
    // from_ratio(i, 25).  The recent advance over 10 steps is 26214.4 raw +- 1 rounded, i.e.
    // 26214 or 26215 raw, never below min_advancing_mm = from_ratio(2, 5) = 26214 raw: advancing
    // from step 10 (the 11th sample) on, and the alarm on the 20th step of C.
    AdvanceEfficiency<> efficiency;
    SelfLockMonitor monitor;
    efficiency.init(AdvanceEfficiency<>::Config{});
    monitor.init(SelfLockMonitor::Config{});
    int first_advancing = -1;
    int first_alarm = -1;
    for (std::int32_t i = 0; i < 100; ++i) {
        const auto e = efficiency.step({Q16_16{}, Q16_16::from_ratio(i, 25)});
        if (e.handle_advancing && first_advancing < 0) first_advancing = i;
        const auto out = monitor.step(inputs(1, e.handle_advancing, e.efficiency, e.defined));
        if (out.alarm && first_alarm < 0) first_alarm = i;
    }
    // from_ratio(10, 25) - from_ratio(0, 25) = 26214 raw = 0.4 mm (rounded): advancing at 10.
    SCOPEKIN_EXPECT_EQ(first_advancing, 10);
    SCOPEKIN_EXPECT_EQ(first_alarm, 29);  // 10 + 19: 29 steps = 145 ms after the hand starts
}

SCOPEKIN_TEST(SelfLockChain, HoldWithEveryContactStuckDoesNotFire) {
    // Advance with slip (0 sticking) to step 99, then the hand and the tip stop and every
    // distal contact sticks.  Recent advance at i >= 100: 0.125 (109 - i) mm >= 0.4 mm
    // <=> i <= 105, so C holds on steps 100..105 only (6 < 20).
    AdvanceEfficiency<> efficiency;
    SelfLockMonitor monitor;
    efficiency.init(AdvanceEfficiency<>::Config{});
    monitor.init(SelfLockMonitor::Config{});
    int max_condition_steps = 0;
    for (std::int32_t i = 0; i < 700; ++i) {
        const std::int32_t x = kEighthRaw * (i <= 99 ? i : 99);
        const auto out = chain_step(efficiency, monitor, x, x, i >= 100 ? 3 : 0);
        SCOPEKIN_EXPECT_TRUE(!out.alarm);
        SCOPEKIN_EXPECT_EQ(out.condition, i >= 100 && i <= 105);
        if (out.condition_steps > max_condition_steps) max_condition_steps = out.condition_steps;
    }
    SCOPEKIN_EXPECT_EQ(max_condition_steps, 6);
}

SCOPEKIN_TEST(SelfLockChain, TipStickingTenStepsBeforeTheHandStopsDoesNotFire) {
    // The tip sticks at step 90 while the hand still pushes until step 99, then holds:
    // C on steps 90..105 = 16 steps < 20.
    AdvanceEfficiency<> efficiency;
    SelfLockMonitor monitor;
    efficiency.init(AdvanceEfficiency<>::Config{});
    monitor.init(SelfLockMonitor::Config{});
    for (std::int32_t i = 0; i < 400; ++i) {
        const std::int32_t handle = kEighthRaw * (i <= 99 ? i : 99);
        const std::int32_t tip = kEighthRaw * (i <= 89 ? i : 89);
        const auto out = chain_step(efficiency, monitor, tip, handle, i >= 90 ? 1 : 0);
        SCOPEKIN_EXPECT_TRUE(!out.alarm);
        if (i == 105) {
            SCOPEKIN_EXPECT_EQ(static_cast<int>(out.condition_steps), 16);
        }
    }
}

SCOPEKIN_TEST(SelfLockChain, ReleasedLoopClearsWithHysteresis) {
    // Stuck from step 100 (alarm at 119) to step 200; from step 201 the tip slips and follows
    // 1:1 again (tip[i] = tip[99] + 0.125 (i - 200)).  C is false from 201; the off count
    // reaches 100 at step 300; the efficiency (i - 200) / 50 passes 0.7 at step 235 and is 1
    // from 250.  So the alarm clears at step 300.
    AdvanceEfficiency<> efficiency;
    SelfLockMonitor monitor;
    efficiency.init(AdvanceEfficiency<>::Config{});
    monitor.init(SelfLockMonitor::Config{});
    for (std::int32_t i = 0; i < 500; ++i) {
        const std::int32_t tip = kEighthRaw * (i <= 99 ? i : (i <= 200 ? 99 : 99 + i - 200));
        const auto out =
            chain_step(efficiency, monitor, tip, kEighthRaw * i, i >= 100 && i <= 200 ? 1 : 0);
        SCOPEKIN_EXPECT_EQ(out.alarm, i >= 119 && i < 300);
        // Confirmed from 125 while the efficiency (defined) is < 0.5: up to step 225
        // (25 / 50 = 0.5 at 225 is not < 0.5).
        SCOPEKIN_EXPECT_EQ(out.confirmed, i >= 125 && i < 225);
    }
}
