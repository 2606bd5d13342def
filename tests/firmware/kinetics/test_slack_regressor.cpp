// SlackRegressor (firmware/kinetics/slack_regressor.hpp) on cases with closed-form answers: a
// hand-built ensemble's prediction is base + one leaf per tree by the split rule x <= t; the hand's
// travel in and out and its distance below the deepest depth are sums; a constant force's average
// is that force at every step, and a constant speed's approaches it as 1 - (1 - alpha)^n; the
// uncertainty is its linear law; invalid trees are refused; and through the kinetic estimator the
// published tip is depth - slack within the observer's bounds; the contact force trees read the
// same features and set the largest contact force (>= 0) outside the model's trust, and refuse to
// run without slack trees of the same averages. Runs as GoogleTest on x86-64 /
// aarch64 and with portable_check's runner on Cortex-M4.
#include <cmath>
#include <cstdint>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "kinetics/slack_regressor.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::kinetics::SlackRegressor;
using scopekin::kinetics::SlackTrees;
namespace kin = scopekin::kinetics;

constexpr Q16_16 kPeriod_s = Q16_16::from_ratio(1, 200);
constexpr std::int32_t kOne = 65536;

// Two trees of depth 1: tree 0 splits on the depth at 100 mm (leaves -5 / +30 mm), tree 1 on the
// handle force at 10 N (leaves 0 / +12 mm); base 10 mm.
constexpr std::uint8_t kFeature[] = {kin::kSlackDepth, kin::kSlackHandleForce};
constexpr std::int32_t kThreshold[] = {100 * kOne, 10 * kOne};
constexpr std::int32_t kLeaf[] = {-5 * kOne, 30 * kOne, 0, 12 * kOne};

SlackTrees hand_built() {
    SlackTrees trees{};
    trees.tree_count = 2;
    trees.depth = 1;
    trees.feature = kFeature;
    trees.threshold_raw = kThreshold;
    trees.leaf_raw = kLeaf;
    trees.base_raw = 10 * kOne;
    for (std::int32_t& tau : trees.average_tau_s_raw)
        tau = kOne;  // 1 s
    trees.average_tau_s_raw[3] = 20 * kOne;
    trees.sigma_floor_raw = 3 * kOne;
    trees.sigma_per_prediction_raw = kOne / 4;
    trees.sigma_per_metre_raw = 40 * kOne;
    return trees;
}

SlackRegressor::Inputs at(int depth_mm, Q16_16 force_N) {
    SlackRegressor::Inputs in{};
    in.depth_mm = Q16_16::from_int(depth_mm);
    in.handle_force_N = force_N;
    in.period_s = kPeriod_s;
    return in;
}

bool near(Q16_16 value, double expected, double tolerance) {
    const double v = static_cast<double>(value.raw()) / 65536.0;
    return v >= expected - tolerance && v <= expected + tolerance;
}

kin::State g_state;  // static: kinetics::State is a few KiB
kin::Outputs g_out;

/// Inits the estimator with `config` and advances the hand from 20 to 150 mm with 11 N of push.
void advance_to_150_mm_at_11_N(const kin::Config& config) {
    kin::init(config, g_state);
    kin::Inputs in{};
    in.handle_force_N = Q16_16::from_int(11);
    in.fresh_mask = kin::kAllInputSignals;
    for (int d = 20; d <= 150; ++d) {
        in.insertion_mm = Q16_16::from_int(d);
        kin::step(in, g_state, g_out);
    }
}

}  // namespace

SCOPEKIN_TEST(SlackRegressor, APredictionIsTheBasePlusOneLeafPerTree) {
    const SlackTrees trees = hand_built();
    SCOPEKIN_EXPECT_TRUE(trees.valid());
    Q16_16 x[kin::kSlackFeatureCount]{};
    x[kin::kSlackDepth] = Q16_16::from_int(100);  // on the threshold: left (x <= t)
    x[kin::kSlackHandleForce] = Q16_16::from_int(5);
    SCOPEKIN_EXPECT_EQ(SlackRegressor::predict(trees, x).raw(), 5 * kOne);  // 10 - 5 + 0
    x[kin::kSlackDepth] = Q16_16::from_raw(100 * kOne + 1);  // one raw unit past it: right
    x[kin::kSlackHandleForce] = Q16_16::from_int(11);
    SCOPEKIN_EXPECT_EQ(SlackRegressor::predict(trees, x).raw(), 52 * kOne);  // 10 + 30 + 12
}

SCOPEKIN_TEST(SlackRegressor, TheHandsTravelIsSummedInAndOut) {
    const SlackTrees trees = hand_built();
    SlackRegressor::State state{};
    SlackRegressor::Outputs out{};
    for (int d = 20; d <= 120; ++d)
        out = SlackRegressor::step(trees, at(d, Q16_16{}), state);
    for (int d = 119; d >= 90; --d)
        out = SlackRegressor::step(trees, at(d, Q16_16{}), state);
    SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackAdvanced].raw(), 100 * kOne);
    SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackWithdrawn].raw(), 30 * kOne);
    SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackBelowDeepest].raw(), 30 * kOne);
    SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackDepth].raw(), 90 * kOne);
}

SCOPEKIN_TEST(SlackRegressor, AveragesFollowTheirClosedForms) {
    // A constant 7 N from the first step: every force average is 7 N exactly. A constant 1 mm per
    // 5 ms step (200 mm/s): after n steps the 1 s average is 200 (1 - (1 - alpha)^n) mm/s,
    // alpha = 0.005 (Q16.16: 328 / 65536), within 0.01 mm/s (the averages carry 32 fraction bits).
    const SlackTrees trees = hand_built();
    SlackRegressor::State state{};
    SlackRegressor::Outputs out{};
    const int steps = 400;
    for (int n = 0; n <= steps; ++n)
        out = SlackRegressor::step(trees, at(20 + n, Q16_16::from_int(7)), state);
    for (std::size_t k = 0; k < kin::kSlackAverages; ++k)
        SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackForceEma1s + k].raw(), 7 * kOne);
    const double alpha = 328.0 / 65536.0;
    const double speed = 1.0 / (328.0 / 65536.0);  // the period as Q16.16 holds it
    const double expected = speed * (1.0 - std::pow(1.0 - alpha, steps));
    SCOPEKIN_EXPECT_TRUE(near(out.features[kin::kSlackSpeedEma1s], expected, 0.01));
    const double alpha20 = 16.0 / 65536.0;  // 0.005 / 20 s (the fourth average's), rounded
    SCOPEKIN_EXPECT_TRUE(near(out.features[kin::kSlackSpeedEma60s],
                              speed * (1.0 - std::pow(1.0 - alpha20, steps)), 0.01));
}

SCOPEKIN_TEST(SlackRegressor, AStaleForceHoldsTheForceAveragesWhileTheSpeedsGoOn) {
    // 7 N for 100 steps, then the cell is stale for 300 steps while the hand still advances 1 mm
    // per step: whatever value the stale input carries (here 40 N), every force average stays at
    // the 7 N the cell last said, and the 1 s speed average keeps its closed form
    // 200 (1 - (1 - alpha)^n) mm/s over all 401 steps (as in AveragesFollowTheirClosedForms).
    const SlackTrees trees = hand_built();
    SlackRegressor::State state{};
    SlackRegressor::Outputs out{};
    for (int n = 0; n <= 100; ++n)
        out = SlackRegressor::step(trees, at(20 + n, Q16_16::from_int(7)), state);
    for (int n = 101; n <= 400; ++n) {
        SlackRegressor::Inputs stale = at(20 + n, Q16_16::from_int(40));
        stale.force_fresh = false;
        out = SlackRegressor::step(trees, stale, state);
    }
    for (std::size_t k = 0; k < kin::kSlackAverages; ++k)
        SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackForceEma1s + k].raw(), 7 * kOne);
    const double alpha = 328.0 / 65536.0;
    const double speed = 1.0 / (328.0 / 65536.0);
    SCOPEKIN_EXPECT_TRUE(near(out.features[kin::kSlackSpeedEma1s],
                              speed * (1.0 - std::pow(1.0 - alpha, 400)), 0.01));
    SCOPEKIN_EXPECT_EQ(out.features[kin::kSlackAdvanced].raw(), 400 * kOne);
}

SCOPEKIN_TEST(SlackRegressor, TheUncertaintyIsItsLinearLaw) {
    // Depth 150 mm, force 11 N: slack 52 mm; sigma = 3 + 52 / 4 + 40 x 0.15 = 22 mm.
    const SlackTrees trees = hand_built();
    SlackRegressor::State state{};
    const SlackRegressor::Outputs out =
        SlackRegressor::step(trees, at(150, Q16_16::from_int(11)), state);
    SCOPEKIN_EXPECT_EQ(out.slack_mm.raw(), 52 * kOne);
    SCOPEKIN_EXPECT_TRUE(near(out.uncertainty_mm, 22.0, 0.01));
}

SCOPEKIN_TEST(SlackRegressor, InvalidTreesAreRefused) {
    SCOPEKIN_EXPECT_TRUE(kin::default_slack_trees().valid());
    SlackTrees none = hand_built();
    none.tree_count = 0;
    SCOPEKIN_EXPECT_TRUE(!none.valid());
    SlackTrees flat = hand_built();
    flat.depth = 0;
    SCOPEKIN_EXPECT_TRUE(!flat.valid());
    static constexpr std::uint8_t kBadFeature[] = {kin::kSlackFeatureCount, 0};
    SlackTrees bad = hand_built();
    bad.feature = kBadFeature;
    SCOPEKIN_EXPECT_TRUE(!bad.valid());
    SlackTrees missing = hand_built();
    missing.leaf_raw = nullptr;
    SCOPEKIN_EXPECT_TRUE(!missing.valid());
    SlackTrees instant = hand_built();
    instant.average_tau_s_raw[2] = 0;
    SCOPEKIN_EXPECT_TRUE(!instant.valid());
    static const SlackTrees refused = bad;
    kin::Config config = kin::default_config();
    config.slack_trees = &refused;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::slack_regressor);
}

SCOPEKIN_TEST(SlackRegressor, ThePublishedTipIsTheDepthLessTheSlackWithinTheBounds) {
    // The hand-built trees in the estimator: at 150 mm with 11 N of push the slack is 52 mm, so
    // the published tip is 98 mm (the model evidence does not trust the model at 11 N above
    // its training's force); without trees the observer's tip is published.
    static const SlackTrees trees = hand_built();
    kin::Config config = kin::default_config();
    config.slack_trees = &trees;
    config.contact_force_trees = nullptr;  // the default ones average over other time constants
    config.loop_alarm_trees = nullptr;     // likewise
    advance_to_150_mm_at_11_N(config);
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
    SCOPEKIN_EXPECT_EQ(g_out.tip_path_mm.raw(), 98 * kOne);
    SCOPEKIN_EXPECT_TRUE(near(g_out.tip_uncertainty_mm, 22.0, 0.01));
    config.slack_trees = nullptr;
    advance_to_150_mm_at_11_N(config);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    SCOPEKIN_EXPECT_EQ(g_out.tip_path_mm.raw(), g_out.observer_tip_path_mm.raw());
}

namespace {

// The force trees: the hand-built splits with other leaves; base `base_N`, tree 0 -1 / +3 N,
// tree 1 0 / +4 N.
constexpr std::int32_t kForceLeaf[] = {-1 * kOne, 3 * kOne, 0, 4 * kOne};

SlackTrees force_trees(int base_N) {
    SlackTrees trees = hand_built();
    trees.leaf_raw = kForceLeaf;
    trees.base_raw = base_N * kOne;
    return trees;
}

}  // namespace

SCOPEKIN_TEST(ContactForceTrees, TheLargestForceIsTheTreesOutsideTheModelsTrust) {
    // At 150 mm with 11 N of push: 2 + 3 + 4 = 9 N, SD 3 + 9 / 4 + 40 x 0.15 = 11.25 N; the
    // model's own largest force stays in model_max_contact_force_N.
    static const SlackTrees slack = hand_built();
    static const SlackTrees force = force_trees(2);
    kin::Config config = kin::default_config();
    config.slack_trees = &slack;
    config.contact_force_trees = &force;
    config.loop_alarm_trees = nullptr;  // the default ones average over other time constants
    advance_to_150_mm_at_11_N(config);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
    SCOPEKIN_EXPECT_EQ(g_out.max_contact_force_N.raw(), 9 * kOne);
    SCOPEKIN_EXPECT_TRUE(near(g_out.max_contact_force_uncertainty_N, 11.25, 0.01));
    SCOPEKIN_EXPECT_TRUE(!(g_out.model_max_contact_force_N < Q16_16{}));
    // A contact force is never negative: base -20 N gives -13 N, published as 0 N.
    static const SlackTrees pulling = force_trees(-20);
    config.contact_force_trees = &pulling;
    advance_to_150_mm_at_11_N(config);
    SCOPEKIN_EXPECT_EQ(g_out.max_contact_force_N.raw(), 0);
    // Without force trees the model's largest force is published.
    config.contact_force_trees = nullptr;
    advance_to_150_mm_at_11_N(config);
    SCOPEKIN_EXPECT_EQ(g_out.max_contact_force_N.raw(), g_out.model_max_contact_force_N.raw());
}

SCOPEKIN_TEST(ContactForceTrees, TheyNeedSlackTreesOfTheSameAverages) {
    SCOPEKIN_EXPECT_TRUE(kin::default_contact_force_trees().valid());
    SCOPEKIN_EXPECT_TRUE(
        kin::same_features(kin::default_slack_trees(), kin::default_contact_force_trees()));
    static const SlackTrees slack = hand_built();
    static const SlackTrees force = force_trees(2);
    kin::Config config = kin::default_config();
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    config.loop_alarm_trees = nullptr;  // the default ones average over 1, 5, 20, 60 s
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    config.slack_trees = nullptr;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::contact_force_regressor);
    config.slack_trees = &kin::default_slack_trees();
    config.contact_force_trees = &force;  // averages over 1, 1, 1, 20 s against 1, 5, 20, 60 s
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::contact_force_regressor);
    config.slack_trees = &slack;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
}

SCOPEKIN_TEST(ContactForceTrees, ThePublishedLevelReadsThePublishedForceAfter20Steps) {
    // base 8 N: 8 - 1 + 4 = 11 N up to 100 mm, 8 + 3 + 4 = 15 N beyond (11 N of push). The
    // published level reads that force and rises after 20 steps at or above a threshold: the
    // warning at the 20th step from 20 mm (39 mm), the critical level at the 20th step from
    // 101 mm (120 mm), not one step before. The model's own level reads the model's force.
    static const SlackTrees slack = hand_built();
    static const SlackTrees force = force_trees(8);
    kin::Config config = kin::default_config();
    config.slack_trees = &slack;
    config.contact_force_trees = &force;
    config.loop_alarm_trees = nullptr;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::none);
    kin::Inputs in{};
    in.handle_force_N = Q16_16::from_int(11);
    in.fresh_mask = kin::kAllInputSignals;
    const auto level_at = [&](int depth_mm) {
        in.insertion_mm = Q16_16::from_int(depth_mm);
        kin::step(in, g_state, g_out);
        return g_out.contact_force_level;
    };
    bool model_level_as_its_force = true;
    for (int d = 20; d <= 150; ++d) {
        const kin::ContactForceLevel level = level_at(d);
        if (d == 38) {
            SCOPEKIN_EXPECT_TRUE(level == kin::ContactForceLevel::normal);
        } else if (d == 39 || d == 119) {
            SCOPEKIN_EXPECT_TRUE(level == kin::ContactForceLevel::warning);
        } else if (d == 120) {
            SCOPEKIN_EXPECT_TRUE(level == kin::ContactForceLevel::critical);
        }
        // The model's monitor raises on the first step (persistence 1): below 9 N it is normal.
        if (g_out.model_max_contact_force_N < Q16_16::from_int(9) &&
            g_out.model_contact_force_level != kin::ContactForceLevel::normal)
            model_level_as_its_force = false;
    }
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
    SCOPEKIN_EXPECT_EQ(g_out.max_contact_force_N.raw(), 15 * kOne);
    SCOPEKIN_EXPECT_TRUE(g_out.contact_force_level == kin::ContactForceLevel::critical);
    SCOPEKIN_EXPECT_TRUE(model_level_as_its_force);
    // A published force of 0 N (base -20 N) keeps the level normal whatever the model says.
    static const SlackTrees pulling = force_trees(-20);
    config.contact_force_trees = &pulling;
    advance_to_150_mm_at_11_N(config);
    SCOPEKIN_EXPECT_TRUE(g_out.contact_force_level == kin::ContactForceLevel::normal);
}
