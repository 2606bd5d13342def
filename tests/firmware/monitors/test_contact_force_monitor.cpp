// ContactForceMonitor (firmware/monitors/contact_force_monitor.hpp): thresholds crossed up and
// down with hysteresis, persistence, absurd inputs.  Hand-computed raw values (N * 65536).
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <cstdint>

#include "fixed_point/q_format.hpp"
#include "monitors/contact_force_monitor.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::monitors::ContactForceLevel;
using scopekin::monitors::ContactForceMonitor;

constexpr Q16_16 raw(std::int32_t r) {
    return Q16_16::from_raw(r);
}
constexpr Q16_16 newtons(std::int32_t n) {
    return Q16_16::from_int(n);
}

bool is(ContactForceMonitor::Outputs out, ContactForceLevel level) {
    return out.level == level;
}

}  // namespace

SCOPEKIN_TEST(ContactForceMonitor, DefaultThresholdsAndClearLevels) {
    ContactForceMonitor monitor;  // usable before init(): default config
    SCOPEKIN_EXPECT_TRUE(ContactForceMonitor::valid(ContactForceMonitor::Config{}));
    SCOPEKIN_EXPECT_EQ(monitor.config().warning_N.raw(), 655360);   // 10 N
    SCOPEKIN_EXPECT_EQ(monitor.config().critical_N.raw(), 917504);  // 14 N
    // 0.9 = from_ratio(9, 10) = 58982 raw; 10 N * 58982 / 65536 = 589820 raw (8.99994 N) exactly,
    // 14 N: 825748 raw (12.59979 N) exactly.
    SCOPEKIN_EXPECT_EQ(monitor.config().clear_fraction.raw(), 58982);
    SCOPEKIN_EXPECT_EQ(monitor.warning_clear_N().raw(), 589820);
    SCOPEKIN_EXPECT_EQ(monitor.critical_clear_N().raw(), 825748);
    SCOPEKIN_EXPECT_TRUE(monitor.init(ContactForceMonitor::Config{}));
    SCOPEKIN_EXPECT_TRUE(!monitor.config_fault());
    SCOPEKIN_EXPECT_TRUE(monitor.level() == ContactForceLevel::normal);
}

SCOPEKIN_TEST(ContactForceMonitor, CrossesThresholdsUpAndDownWithHysteresis) {
    ContactForceMonitor monitor;
    monitor.init(ContactForceMonitor::Config{});
    // Up.
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(5)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(655359)), ContactForceLevel::normal));  // 10 N - LSB
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(10)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(13)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(917503)), ContactForceLevel::warning));  // 14 N - LSB
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(14)), ContactForceLevel::critical));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(20)), ContactForceLevel::critical));
    // Down: critical holds down to its clear level 825748 raw, included.
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(13)), ContactForceLevel::critical));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(825748)), ContactForceLevel::critical));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(825747)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(13)), ContactForceLevel::warning));  // < 14 N
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(9)), ContactForceLevel::warning));   // >= 8.99994
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(589820)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(589819)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(9)), ContactForceLevel::normal));  // < 10 N
    // Straight from normal to critical and straight back to normal.
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(30)), ContactForceLevel::critical));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(Q16_16{}), ContactForceLevel::normal));
}

SCOPEKIN_TEST(ContactForceMonitor, PersistenceNeedsConsecutiveSteps) {
    ContactForceMonitor monitor;
    ContactForceMonitor::Config config{};
    config.persistence_steps = 3;
    SCOPEKIN_EXPECT_TRUE(monitor.init(config));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(15)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(15)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(5)), ContactForceLevel::normal));  // resets
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(15)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(15)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(15)), ContactForceLevel::critical));  // 3rd
    // Clearing takes one step below the clear level.
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(11)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(8)), ContactForceLevel::normal));
    // 11 N twice then 14 N three times: the warning's 3rd step >= 10 N is the first 14 N step,
    // the critical's 3rd step >= 14 N the last one.
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(11)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(11)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(14)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(14)), ContactForceLevel::warning));
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(14)), ContactForceLevel::critical));
}

SCOPEKIN_TEST(ContactForceMonitor, AbsurdInputsSetTheFlagAndHoldTheLevel) {
    ContactForceMonitor monitor;
    monitor.init(ContactForceMonitor::Config{});
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(11)), ContactForceLevel::warning));
    const Q16_16 absurd[] = {newtons(-1), raw(-1), Q16_16::max(), Q16_16::min(), newtons(1001)};
    for (const Q16_16 f : absurd) {  // bound: 5
        const auto out = monitor.step(f);
        SCOPEKIN_EXPECT_TRUE(out.input_fault);
        SCOPEKIN_EXPECT_TRUE(out.level ==
                             ContactForceLevel::warning);  // neither raised nor cleared
    }
    const auto ok = monitor.step(newtons(1000));  // the limit itself is valid
    SCOPEKIN_EXPECT_TRUE(!ok.input_fault && ok.level == ContactForceLevel::critical);

    // A fault step does not count towards persistence and does not reset it.
    ContactForceMonitor persistent;
    ContactForceMonitor::Config config{};
    config.persistence_steps = 2;
    persistent.init(config);
    SCOPEKIN_EXPECT_TRUE(is(persistent.step(newtons(15)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(persistent.step(newtons(-5)), ContactForceLevel::normal));
    SCOPEKIN_EXPECT_TRUE(is(persistent.step(newtons(15)), ContactForceLevel::critical));
}

SCOPEKIN_TEST(ContactForceMonitor, InvalidConfigFallsBackToDefaults) {
    ContactForceMonitor monitor;
    ContactForceMonitor::Config bad{};
    bad.warning_N = newtons(15);  // above critical
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    SCOPEKIN_EXPECT_TRUE(monitor.config_fault());
    SCOPEKIN_EXPECT_EQ(monitor.config().warning_N.raw(), 655360);
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(12)), ContactForceLevel::warning));

    bad = ContactForceMonitor::Config{};
    bad.clear_fraction = Q16_16::from_ratio(11, 10);
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    bad = ContactForceMonitor::Config{};
    bad.persistence_steps = 0;
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    bad.persistence_steps = 201;
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    bad = ContactForceMonitor::Config{};
    bad.warning_N = Q16_16{};
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));
    bad = ContactForceMonitor::Config{};
    bad.critical_N = newtons(1000);  // not below max_valid_force_N
    SCOPEKIN_EXPECT_TRUE(!monitor.init(bad));

    ContactForceMonitor::Config custom{};
    custom.warning_N = newtons(5);
    custom.critical_N = newtons(8);
    custom.clear_fraction = Q16_16::from_ratio(1, 2);
    SCOPEKIN_EXPECT_TRUE(monitor.init(custom));
    SCOPEKIN_EXPECT_TRUE(!monitor.config_fault());
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(newtons(8)), ContactForceLevel::critical));
    SCOPEKIN_EXPECT_TRUE(
        is(monitor.step(newtons(4)), ContactForceLevel::critical));  // 4 N: not < 4
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(262143)), ContactForceLevel::warning));  // >= 2.5 N
    SCOPEKIN_EXPECT_TRUE(is(monitor.step(raw(163839)), ContactForceLevel::normal));   // < 2.5 N
}
