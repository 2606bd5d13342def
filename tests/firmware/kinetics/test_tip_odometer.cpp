// TipOdometer (firmware/kinetics/tip_odometer.hpp) on cases with closed-form answers: a tip
// sliding along its own axis advances the estimate by exactly its travel (the axis from the
// quaternion, rotated or not); motion across the axis adds nothing; the handle's estimate pulls
// the fused tip by the Kalman gain r / (r + correlation / T); without the tracker, or with its
// tip sensor stale, the published tip is the handle's, bit for bit; through the kinetic
// estimator, a run without tracker samples gives the same outputs with and without the odometer.
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <array>
#include <cstdint>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "kinetics/tip_odometer.hpp"
#include "messages/em_tracker_samples.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::kinetics::TipOdometer;
using scopekin::kinetics::TrackerInputs;
namespace kin = scopekin::kinetics;
namespace messages = scopekin::messages;

constexpr Q16_16 kPeriod = Q16_16::from_ratio(1, 200);

/// A tracker whose tip sensor is at `position` with orientation `q` (w, x, y, z), fresh or not.
TrackerInputs tip_at(std::array<Q16_16, 3> position, std::array<Q16_16, 4> q, bool fresh) {
    TrackerInputs tracker{};
    tracker.pose[0].position_mm = position;
    tracker.pose[0].orientation = q;
    tracker.valid_mask = messages::kEmSourceTip;
    tracker.fresh_mask = fresh ? std::uint8_t{messages::kEmSourceTip} : std::uint8_t{0};
    return tracker;
}

constexpr std::array<Q16_16, 4> kIdentity{Q16_16::from_int(1), Q16_16{}, Q16_16{}, Q16_16{}};
// 90 degrees about z: the sensor's x axis points along +y. (w, z) = (cos 45, sin 45).
constexpr std::array<Q16_16, 4> kAboutZ{Q16_16::from_raw(46341), Q16_16{}, Q16_16{},
                                        Q16_16::from_raw(46341)};

TipOdometer::Inputs handle(const TrackerInputs* tracker, Q16_16 tip_mm, Q16_16 sd_mm) {
    TipOdometer::Inputs in{};
    in.tracker = tracker;
    in.handle_tip_mm = tip_mm;
    in.handle_sd_mm = sd_mm;
    in.tip_min_mm = Q16_16{};
    in.tip_max_mm = Q16_16::from_int(2000);
    in.period_s = kPeriod;
    return in;
}

/// Config whose update never comes within the test (1000 periods).
TipOdometer::Config odometry_only() {
    TipOdometer::Config config{};
    config.update_steps = 1000;
    return config;
}

}  // namespace

SCOPEKIN_TEST(TipOdometer, SlidingAlongItsAxisAdvancesByTheTravel) {
    // Along x with the identity orientation, then along y with the sensor turned to +y: 10 mm
    // per sample, 20 samples each; the handle says 100 mm throughout.
    const TipOdometer::Config config = odometry_only();
    TipOdometer::State state{};
    TrackerInputs tracker = tip_at({Q16_16::from_int(5), Q16_16{}, Q16_16{}}, kIdentity, true);
    TipOdometer::Outputs out = TipOdometer::step(
        config, handle(&tracker, Q16_16::from_int(100), Q16_16::from_int(30)), state);
    SCOPEKIN_EXPECT_TRUE(out.active);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(100).raw());  // starts at the handle's
    for (int k = 1; k <= 20; ++k) {
        tracker = tip_at({Q16_16::from_int(5 + 10 * k), Q16_16{}, Q16_16{}}, kIdentity, true);
        out = TipOdometer::step(
            config, handle(&tracker, Q16_16::from_int(100), Q16_16::from_int(30)), state);
    }
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(300).raw());
    // Turned in place (no travel), then along y.
    tracker = tip_at({Q16_16::from_int(205), Q16_16{}, Q16_16{}}, kAboutZ, true);
    out = TipOdometer::step(config, handle(&tracker, Q16_16::from_int(100), Q16_16::from_int(30)),
                            state);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(300).raw());
    for (int k = 1; k <= 20; ++k) {
        tracker =
            tip_at({Q16_16::from_int(205), Q16_16::from_int(10 * k), Q16_16{}}, kAboutZ, true);
        out = TipOdometer::step(
            config, handle(&tracker, Q16_16::from_int(100), Q16_16::from_int(30)), state);
    }
    // The turned axis is (1 - 2 sin^2 45, 2 sin 45 cos 45, 0) in Q16.16: y within 2e-5 of 1.
    const std::int32_t error = out.tip_mm.raw() - Q16_16::from_int(500).raw();
    SCOPEKIN_EXPECT_TRUE(error > -300 && error < 300);  // 200 mm * 2e-5 = 0.004 mm = 262 raw
}

SCOPEKIN_TEST(TipOdometer, MotionAcrossTheAxisAddsNothing) {
    // The tip carried 40 mm sideways (y) and 40 mm up (z) with its axis along x.
    const TipOdometer::Config config = odometry_only();
    TipOdometer::State state{};
    TrackerInputs tracker = tip_at({}, kIdentity, true);
    (void)TipOdometer::step(config, handle(&tracker, Q16_16::from_int(250), Q16_16::from_int(30)),
                            state);
    TipOdometer::Outputs out{};
    for (int k = 1; k <= 40; ++k) {
        tracker = tip_at({Q16_16{}, Q16_16::from_int(k), Q16_16::from_int(k)}, kIdentity, true);
        out = TipOdometer::step(
            config, handle(&tracker, Q16_16::from_int(250), Q16_16::from_int(30)), state);
    }
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(250).raw());
    // No odometry, no added variance: the SD is still the handle's 30 mm.
    SCOPEKIN_EXPECT_EQ(out.uncertainty_mm.raw(), Q16_16::from_int(30).raw());
}

SCOPEKIN_TEST(TipOdometer, ATipCarriedWithTheSigmoidDoesNotAdvance) {
    // Tip and sigmoid sensor both move 5 mm per sample along the tip's axis (x), 60 mm apart:
    // the sigmoid is carried with the tip, no advance. 150 mm apart (beyond the 100 mm reach):
    // the tip's own travel counts in full.
    const TipOdometer::Config config = odometry_only();
    for (const int apart_mm : {60, 150}) {
        TipOdometer::State state{};
        TipOdometer::Outputs out{};
        for (int k = 0; k <= 20; ++k) {
            TrackerInputs tracker =
                tip_at({Q16_16::from_int(5 * k), Q16_16{}, Q16_16{}}, kIdentity, true);
            tracker.pose[3].position_mm = {Q16_16::from_int(5 * k), Q16_16::from_int(apart_mm),
                                           Q16_16{}};
            tracker.valid_mask = messages::kEmSourceTip | messages::kEmSourceSigmoid;
            out = TipOdometer::step(
                config, handle(&tracker, Q16_16::from_int(400), Q16_16::from_int(30)), state);
        }
        SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(apart_mm < 100 ? 400 : 500).raw());
    }
}

SCOPEKIN_TEST(TipOdometer, TheHandleEstimatePullsByTheKalmanGain) {
    // A still tip: P = R = 30^2 (r = 1). The update every 100 periods (T = 0.5 s) with
    // correlation 20 s: K = 1 / (1 + 40) = 1/41; the handle 41 mm ahead moves the tip by 1 mm and
    // P becomes 900 * 40/41 (SD 29.633 mm). The Q16.16 period is 328 / 65536 s (0.1 % long), so
    // T / correlation is 39.961 and K = 0.024414: the tip moves 1.00095 mm, SD 29.6315 mm.
    TipOdometer::Config config{};
    config.update_steps = 100;
    config.correlation_s = Q16_16::from_int(20);
    TipOdometer::State state{};
    TrackerInputs tracker = tip_at({}, kIdentity, true);
    (void)TipOdometer::step(config, handle(&tracker, Q16_16::from_int(100), Q16_16::from_int(30)),
                            state);
    tracker.fresh_mask = 0;  // held: no new sample, no odometry
    TipOdometer::Outputs out{};
    for (int k = 1; k < 100; ++k) {
        out = TipOdometer::step(
            config, handle(&tracker, Q16_16::from_int(141), Q16_16::from_int(30)), state);
    }
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(100).raw());  // not yet
    out = TipOdometer::step(config, handle(&tracker, Q16_16::from_int(141), Q16_16::from_int(30)),
                            state);
    const std::int32_t tip_error = out.tip_mm.raw() - 6619198;         // 101.00095 mm
    SCOPEKIN_EXPECT_TRUE(tip_error > -40 && tip_error < 40);           // the Q16.16 gain: 6e-4 mm
    const std::int32_t sd_error = out.uncertainty_mm.raw() - 1941932;  // 29.6315 mm
    SCOPEKIN_EXPECT_TRUE(sd_error > -70 && sd_error < 70);
}

SCOPEKIN_TEST(TipOdometer, WithoutTheTrackerTheTipIsTheHandles) {
    const TipOdometer::Config config{};
    TipOdometer::State state{};
    TipOdometer::Outputs out = TipOdometer::step(
        config, handle(nullptr, Q16_16::from_int(321), Q16_16::from_int(44)), state);
    SCOPEKIN_EXPECT_TRUE(!out.active);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(321).raw());
    SCOPEKIN_EXPECT_EQ(out.uncertainty_mm.raw(), Q16_16::from_int(44).raw());
    // Running, then the tip sensor goes stale: the handle's again, and it restarts from it.
    TrackerInputs tracker = tip_at({}, kIdentity, true);
    (void)TipOdometer::step(config, handle(&tracker, Q16_16::from_int(321), Q16_16::from_int(44)),
                            state);
    tracker = tip_at({Q16_16::from_int(50), Q16_16{}, Q16_16{}}, kIdentity, true);
    out = TipOdometer::step(config, handle(&tracker, Q16_16::from_int(321), Q16_16::from_int(44)),
                            state);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(371).raw());
    tracker.stale_mask = messages::kEmSourceTip;
    out = TipOdometer::step(config, handle(&tracker, Q16_16::from_int(330), Q16_16::from_int(44)),
                            state);
    SCOPEKIN_EXPECT_TRUE(!out.active);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(330).raw());
    tracker = tip_at({Q16_16::from_int(60), Q16_16{}, Q16_16{}}, kIdentity, true);
    out = TipOdometer::step(config, handle(&tracker, Q16_16::from_int(330), Q16_16::from_int(44)),
                            state);
    SCOPEKIN_EXPECT_TRUE(out.active);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(330).raw());
    // Disabled: the handle's whatever the tracker says.
    TipOdometer::Config disabled{};
    disabled.enabled = false;
    out = TipOdometer::step(disabled, handle(&tracker, Q16_16::from_int(7), Q16_16::from_int(8)),
                            state);
    SCOPEKIN_EXPECT_TRUE(!out.active);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(7).raw());
}

SCOPEKIN_TEST(TipOdometer, WhileTheModelIsTrustedItsTipIsPublishedAndTheOdometerGoesOnFromIt) {
    // Trusted: the tip slides 30 mm but the published tip is the model's 412.5 mm (SD 7 mm);
    // then not trusted: 10 mm more travel puts it at 422.5 mm.
    const TipOdometer::Config config = odometry_only();
    TipOdometer::State state{};
    TrackerInputs tracker = tip_at({}, kIdentity, true);
    TipOdometer::Inputs in = handle(&tracker, Q16_16::from_ratio(825, 2), Q16_16::from_int(7));
    in.handle_trusted = true;
    (void)TipOdometer::step(config, in, state);
    tracker = tip_at({Q16_16::from_int(30), Q16_16{}, Q16_16{}}, kIdentity, true);
    TipOdometer::Outputs out = TipOdometer::step(config, in, state);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_ratio(825, 2).raw());
    SCOPEKIN_EXPECT_EQ(out.uncertainty_mm.raw(), Q16_16::from_int(7).raw());
    in.handle_trusted = false;
    tracker = tip_at({Q16_16::from_int(40), Q16_16{}, Q16_16{}}, kIdentity, true);
    out = TipOdometer::step(config, in, state);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_ratio(845, 2).raw());
}

SCOPEKIN_TEST(TipOdometer, TheFusedTipStaysWithinTheBounds) {
    const TipOdometer::Config config = odometry_only();
    TipOdometer::State state{};
    TrackerInputs tracker = tip_at({}, kIdentity, true);
    TipOdometer::Inputs in = handle(&tracker, Q16_16::from_int(100), Q16_16::from_int(30));
    in.tip_max_mm = Q16_16::from_int(120);
    (void)TipOdometer::step(config, in, state);
    tracker = tip_at({Q16_16::from_int(80), Q16_16{}, Q16_16{}}, kIdentity, true);
    const TipOdometer::Outputs out = TipOdometer::step(config, in, state);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(120).raw());
}

SCOPEKIN_TEST(TipOdometer, SettingsThatDoNotFitAreRefused) {
    TipOdometer::Config config{};
    SCOPEKIN_EXPECT_TRUE(config.valid(kPeriod));
    config.update_steps = 0;
    SCOPEKIN_EXPECT_TRUE(!config.valid(kPeriod));
    config = TipOdometer::Config{};
    config.correlation_s = Q16_16{};
    SCOPEKIN_EXPECT_TRUE(!config.valid(kPeriod));
    config = TipOdometer::Config{};
    config.q_mm2_per_mm = Q16_16::from_int(-1);
    SCOPEKIN_EXPECT_TRUE(!config.valid(kPeriod));
    config = TipOdometer::Config{};
    config.max_variance_mm2 = Q16_16::from_int(30001);
    SCOPEKIN_EXPECT_TRUE(!config.valid(kPeriod));
    // Through the estimator: refused at init, every step flags the configuration.
    kin::Config kinetics_config = kin::default_config();
    kinetics_config.tip_odometer.update_steps = 0;
    static kin::State kinetics_state;
    kin::init(kinetics_config, kinetics_state);
    SCOPEKIN_EXPECT_TRUE(kinetics_state.config_fault == kin::ConfigFault::tip_odometer);
}
