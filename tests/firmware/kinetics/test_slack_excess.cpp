// SlackExcess (firmware/kinetics/slack_excess.hpp) on cases with closed-form answers, the truth's
// pace rule (model/truth/README.md, "Loop episodes") on the tracker's odometry: a tip that stops
// dead while the hand advances 1 mm per pose takes up exactly the hand's advance since the stop,
// and the gate opens at 6 mm, not before; holding still keeps the excess, the tip slipping ahead
// gives it back; a creep at the pace fraction is pace; without the tracker's odometry it is not
// valid and starts afresh; settings that do not fit are refused, also through the estimator.
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <cstdint>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "kinetics/slack_excess.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::kinetics::SlackExcess;
namespace kin = scopekin::kinetics;

constexpr std::uint32_t kStepsPerPose = 6;  // ~33 Hz poses at the box's 200 Hz

/// Pose k: the hand at insertion_mm, the odometer at travel_mm.
SlackExcess::Inputs pose(int k, int insertion_mm, int travel_mm) {
    SlackExcess::Inputs in{};
    in.active = true;
    in.fresh = true;
    in.step = static_cast<std::uint32_t>(k) * kStepsPerPose;
    in.insertion_mm = Q16_16::from_int(insertion_mm);
    in.travel_mm = Q16_16::from_int(travel_mm);
    return in;
}

/// 60 poses keeping pace (tip = hand, 1 mm per pose), then `stopped` poses with the tip still.
SlackExcess::Outputs stop_after_pace(const SlackExcess::Config& config, SlackExcess::State& state,
                                     int stopped) {
    SlackExcess::Outputs out{};
    for (int k = 0; k <= 60; ++k)
        out = SlackExcess::step(config, pose(k, k, k), state);
    SCOPEKIN_EXPECT_TRUE(out.valid);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), 0);
    for (int k = 61; k <= 60 + stopped; ++k)
        out = SlackExcess::step(config, pose(k, k, 60), state);
    return out;
}

}  // namespace

SCOPEKIN_TEST(SlackExcess, ATipThatStopsDeadTakesUpTheHandsAdvance) {
    const SlackExcess::Config config{};
    for (const int stopped : {5, 6, 30}) {
        SlackExcess::State state{};
        const SlackExcess::Outputs out = stop_after_pace(config, state, stopped);
        SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), Q16_16::from_int(stopped).raw());
        SCOPEKIN_EXPECT_TRUE(out.gate_open == (stopped >= 6));  // the gate opens at 6 mm
    }
}

SCOPEKIN_TEST(SlackExcess, HoldingKeepsTheExcessAndSlippingAheadGivesItBack) {
    const SlackExcess::Config config{};
    SlackExcess::State state{};
    SlackExcess::Outputs out = stop_after_pace(config, state, 30);  // 30 mm taken up at 90 mm
    // The hand holds at 90 mm for 2 s: no pace (the hand does not advance), the loop stays.
    for (int k = 91; k <= 150; ++k)
        out = SlackExcess::step(config, pose(k, 90, 60), state);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), Q16_16::from_int(30).raw());
    // Between poses the excess is held.
    SlackExcess::Inputs between = pose(150, 90, 60);
    between.fresh = false;
    between.step += 1;
    between.insertion_mm = Q16_16::from_int(95);
    out = SlackExcess::step(config, between, state);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), Q16_16::from_int(30).raw());
    // The tip slips 20 mm ahead in one pose, then 10 more: the scope taken up is given back.
    out = SlackExcess::step(config, pose(151, 90, 80), state);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), Q16_16::from_int(10).raw());
    out = SlackExcess::step(config, pose(152, 90, 90), state);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), 0);
    SCOPEKIN_EXPECT_TRUE(!out.gate_open);
}

SCOPEKIN_TEST(SlackExcess, ACreepAtThePaceFractionKeepsPace) {
    // The hand 2 mm per pose, the tip 1 mm (exactly the pace fraction 0.5): it keeps pace at
    // every pose once a window is full, so the excess is what was taken up within the last
    // window: 16 poses of 1 mm (96 periods <= 100), 17 poses span 102 periods.
    const SlackExcess::Config config{};
    SlackExcess::State state{};
    SlackExcess::Outputs out{};
    for (int k = 0; k <= 100; ++k)
        out = SlackExcess::step(config, pose(k, 2 * k, k), state);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), Q16_16::from_int(16).raw());
}

SCOPEKIN_TEST(SlackExcess, WithoutTheTrackersOdometryItIsNotValidAndStartsAfresh) {
    const SlackExcess::Config config{};
    SlackExcess::State state{};
    SlackExcess::Outputs out = stop_after_pace(config, state, 30);
    SCOPEKIN_EXPECT_TRUE(out.gate_open);
    SlackExcess::Inputs off = pose(91, 91, 60);
    off.active = false;
    out = SlackExcess::step(config, off, state);
    SCOPEKIN_EXPECT_TRUE(!out.valid && !out.gate_open);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), 0);
    // Back: it starts from the first pose (nothing taken up yet).
    out = SlackExcess::step(config, pose(92, 92, 60), state);
    SCOPEKIN_EXPECT_TRUE(out.valid);
    SCOPEKIN_EXPECT_EQ(out.excess_mm.raw(), 0);
    // Before any fresh pose it is not valid either.
    SlackExcess::State fresh_state{};
    off.active = true;
    off.fresh = false;
    out = SlackExcess::step(config, off, fresh_state);
    SCOPEKIN_EXPECT_TRUE(!out.valid);
}

SCOPEKIN_TEST(SlackExcess, SettingsThatDoNotFitAreRefused) {
    SlackExcess::Config config{};
    SCOPEKIN_EXPECT_TRUE(config.valid());
    config.window_steps = 0;
    SCOPEKIN_EXPECT_TRUE(!config.valid());
    config.window_steps = SlackExcess::kCapacity;  // more poses than the ring holds
    SCOPEKIN_EXPECT_TRUE(!config.valid());
    config = SlackExcess::Config{};
    config.min_hand_mm = Q16_16{};
    SCOPEKIN_EXPECT_TRUE(!config.valid());
    config = SlackExcess::Config{};
    config.pace_fraction = Q16_16::from_ratio(3, 2);
    SCOPEKIN_EXPECT_TRUE(!config.valid());
    config = SlackExcess::Config{};
    config.gate_mm = Q16_16::from_int(-1);
    SCOPEKIN_EXPECT_TRUE(!config.valid());
    // Through the estimator: refused at init, like the loop alarm's other settings.
    kin::Config kinetics_config = kin::default_config();
    kinetics_config.slack_excess.window_steps = 0;
    static kin::State kinetics_state;
    kin::init(kinetics_config, kinetics_state);
    SCOPEKIN_EXPECT_TRUE(kinetics_state.config_fault == kin::ConfigFault::loop_alarm);
    kinetics_config = kin::default_config();
    kinetics_config.loop_alarm_with_tracker.raise_steps = 0;
    kin::init(kinetics_config, kinetics_state);
    SCOPEKIN_EXPECT_TRUE(kinetics_state.config_fault == kin::ConfigFault::loop_alarm);
}
