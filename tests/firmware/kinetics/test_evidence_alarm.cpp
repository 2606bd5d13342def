// EvidenceAlarm (firmware/kinetics/evidence_alarm.hpp) on cases with closed-form answers: a
// constant score above the raise level raises the alarm on exactly the raise_steps-th period, one
// below the clear level clears it on exactly the clear_steps-th; a score that dips back resets the
// count; through the kinetic estimator the published self-lock alarm is the evidence alarm while
// the model is not trusted and the model's own stays in model_self_lock_alarm; settings or trees
// that do not fit are refused; with the bench's EM tracker the score counts only once the tip has
// fallen the gate (6 mm) behind the hand (slack_excess.hpp). Runs as GoogleTest on x86-64 / aarch64 and with portable_check's
// runner on Cortex-M4.
#include <cstdint>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/evidence_alarm.hpp"
#include "kinetics/kinetics.hpp"
#include "messages/em_tracker_samples.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::kinetics::EvidenceAlarm;
using scopekin::kinetics::SlackTrees;
namespace kin = scopekin::kinetics;

constexpr std::int32_t kOne = 65536;

// One tree of depth 1 whose leaves are 0: the score is the base.
constexpr std::uint8_t kFeature[] = {kin::kSlackDepth};
constexpr std::int32_t kThreshold[] = {0};
constexpr std::int32_t kLeaf[] = {0, 0};

SlackTrees constant_score(std::int32_t score_raw) {
    SlackTrees trees{};
    trees.tree_count = 1;
    trees.depth = 1;
    trees.feature = kFeature;
    trees.threshold_raw = kThreshold;
    trees.leaf_raw = kLeaf;
    trees.base_raw = score_raw;
    trees.average_tau_s_raw[0] = kOne;  // the default slack trees' 1, 5, 20, 60 s
    trees.average_tau_s_raw[1] = 5 * kOne;
    trees.average_tau_s_raw[2] = 20 * kOne;
    trees.average_tau_s_raw[3] = 60 * kOne;
    return trees;
}

EvidenceAlarm::Config settings() {
    // Rise above 0.5 for 3 periods, clear below 0.4 for 4.
    return EvidenceAlarm::Config{kOne / 2, kOne * 2 / 5, 3U, 4U};
}

const Q16_16 kFeatures[kin::kSlackFeatureCount]{};

kin::State g_state;  // static: kinetics::State is a few KiB
kin::Outputs g_out;

}  // namespace

SCOPEKIN_TEST(EvidenceAlarm, RisesAndClearsAfterItsCountsExactly) {
    const SlackTrees high = constant_score(kOne * 4 / 5);
    const SlackTrees low = constant_score(kOne * 3 / 10);
    EvidenceAlarm::State state{};
    SCOPEKIN_EXPECT_TRUE(!EvidenceAlarm::step(settings(), high, kFeatures, state).alarm);
    SCOPEKIN_EXPECT_TRUE(!EvidenceAlarm::step(settings(), high, kFeatures, state).alarm);
    const EvidenceAlarm::Outputs third = EvidenceAlarm::step(settings(), high, kFeatures, state);
    SCOPEKIN_EXPECT_TRUE(third.alarm);
    SCOPEKIN_EXPECT_EQ(third.score.raw(), kOne * 4 / 5);
    for (int k = 0; k < 3; ++k)
        SCOPEKIN_EXPECT_TRUE(EvidenceAlarm::step(settings(), low, kFeatures, state).alarm);
    SCOPEKIN_EXPECT_TRUE(!EvidenceAlarm::step(settings(), low, kFeatures, state).alarm);
}

SCOPEKIN_TEST(EvidenceAlarm, AScoreThatDipsBackStartsTheCountAgain) {
    // 0.45 is between the levels: it neither raises nor clears, and breaks a run.
    const SlackTrees high = constant_score(kOne * 4 / 5);
    const SlackTrees between = constant_score(kOne * 45 / 100);
    EvidenceAlarm::State state{};
    for (int round = 0; round < 5; ++round) {
        SCOPEKIN_EXPECT_TRUE(!EvidenceAlarm::step(settings(), high, kFeatures, state).alarm);
        SCOPEKIN_EXPECT_TRUE(!EvidenceAlarm::step(settings(), high, kFeatures, state).alarm);
        SCOPEKIN_EXPECT_TRUE(!EvidenceAlarm::step(settings(), between, kFeatures, state).alarm);
    }
    for (int k = 0; k < 20; ++k)
        (void)EvidenceAlarm::step(settings(), high, kFeatures, state);
    for (int k = 0; k < 20; ++k)
        SCOPEKIN_EXPECT_TRUE(EvidenceAlarm::step(settings(), between, kFeatures, state).alarm);
}

SCOPEKIN_TEST(EvidenceAlarm, ThePublishedAlarmIsTheEvidenceWhileTheModelIsNotTrusted) {
    // 11 N of push above the training's: the model is not trusted, so a constant score of 0.8
    // raises the published alarm whatever the model's monitor says.
    static const SlackTrees high = constant_score(kOne * 4 / 5);
    kin::Config config = kin::default_config();
    config.loop_alarm_trees = &high;
    config.loop_alarm = settings();
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    kin::Inputs in{};
    in.handle_force_N = Q16_16::from_int(11);
    in.fresh_mask = kin::kAllInputSignals;
    for (int d = 20; d <= 150; ++d) {
        in.insertion_mm = Q16_16::from_int(d);
        kin::step(in, g_state, g_out);
    }
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
    SCOPEKIN_EXPECT_TRUE(g_out.self_lock_alarm);
    SCOPEKIN_EXPECT_EQ(g_out.loop_score.raw(), kOne * 4 / 5);
    // Without its trees the model's monitor is published.
    config.loop_alarm_trees = nullptr;
    kin::init(config, g_state);
    for (int d = 20; d <= 150; ++d) {
        in.insertion_mm = Q16_16::from_int(d);
        kin::step(in, g_state, g_out);
    }
    SCOPEKIN_EXPECT_TRUE(g_out.self_lock_alarm == g_out.model_self_lock_alarm);
    SCOPEKIN_EXPECT_EQ(g_out.loop_score.raw(), 0);
}

SCOPEKIN_TEST(EvidenceAlarm, WithTheTrackerTheScoreCountsOnlyOnceTheTipFallsBehind) {
    // A constant score of 0.8 and 11 N of push (the model not trusted). The hand advances 1 mm
    // per tracker pose (every 6 periods). While the tip keeps pace the gate is closed and the
    // alarm stays down; once the tip stops, the gate opens at 6 mm taken up (the 6th pose after
    // the stop) and the alarm rises 3 periods later (settings(): 3 periods above 0.5).
    static const SlackTrees high = constant_score(kOne * 4 / 5);
    kin::Config config = kin::default_config();
    config.loop_alarm_trees = &high;
    config.loop_alarm = settings();
    config.loop_alarm_with_tracker = settings();
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    kin::Inputs in{};
    in.handle_force_N = Q16_16::from_int(11);
    in.fresh_mask = kin::kAllInputSignals;
    in.tracker.valid_mask = scopekin::messages::kEmSourceTip;
    in.tracker.pose[0].orientation = {Q16_16::from_int(1), Q16_16{}, Q16_16{}, Q16_16{}};
    const auto run_poses = [&](int from, int to, bool tip_moves) {
        for (int k = from; k <= to; ++k) {
            in.insertion_mm = Q16_16::from_int(100 + k);
            if (tip_moves) in.tracker.pose[0].position_mm[0] = Q16_16::from_int(k);
            for (int period = 0; period < 6; ++period) {
                in.tracker.fresh_mask =
                    period == 0 ? std::uint8_t{scopekin::messages::kEmSourceTip} : std::uint8_t{0};
                kin::step(in, g_state, g_out);
            }
        }
    };
    run_poses(0, 120, true);
    SCOPEKIN_EXPECT_TRUE(g_out.tip_from_tracker);
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
    SCOPEKIN_EXPECT_EQ(g_out.loop_score.raw(), kOne * 4 / 5);
    SCOPEKIN_EXPECT_TRUE(!g_out.self_lock_alarm);  // 0.8, but the tip keeps pace
    run_poses(121, 125, false);                    // 5 mm taken up: the gate still closed
    SCOPEKIN_EXPECT_TRUE(!g_out.self_lock_alarm);
    run_poses(126, 126, false);  // 6 mm: open from this pose's first period, up on its third
    SCOPEKIN_EXPECT_TRUE(g_out.self_lock_alarm);
}

SCOPEKIN_TEST(EvidenceAlarm, SettingsAndTreesThatDoNotFitAreRefused) {
    static const SlackTrees high = constant_score(kOne * 4 / 5);
    SCOPEKIN_EXPECT_TRUE(kin::default_loop_alarm().valid());
    SCOPEKIN_EXPECT_TRUE(kin::default_loop_alarm_trees().valid());
    EvidenceAlarm::Config inverted = settings();
    inverted.clear_score_raw = inverted.raise_score_raw + 1;
    SCOPEKIN_EXPECT_TRUE(!inverted.valid());
    EvidenceAlarm::Config never = settings();
    never.raise_steps = 0;
    SCOPEKIN_EXPECT_TRUE(!never.valid());
    kin::Config config = kin::default_config();
    config.loop_alarm = inverted;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::loop_alarm);
    config = kin::default_config();
    config.slack_trees = nullptr;
    config.contact_force_trees = nullptr;
    config.loop_alarm_trees = &high;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::loop_alarm);
}
