// ModelEvidence (firmware/kinetics/model_evidence.hpp) on cases with closed-form answers: the
// log-likelihood ratio of the handle force residual, one step's increment
// match_reward - mismatch_cost * r^2 (raw Q16.16: 2110 - 629 r^2 for r in whole newtons), its
// bounds, when evidence is taken, and — through the kinetic estimator with the default tables —
// that the handle force the training run needed makes the model trusted (the published tip is
// then the model's), and that a handle force 3 N above it (a patient with more friction, the
// scope otherwise the same) turns the trust after exactly the number of steps the sum predicts,
// the published tip continuing from the model's. Runs as GoogleTest on x86-64 / aarch64 and with
// portable_check's runner on Cortex-M4.
#include <cstdint>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "kinetics/model_evidence.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::kinetics::ModelEvidence;
namespace kin = scopekin::kinetics;

constexpr std::int32_t kRewardRaw = 2110;  // round(0.0322 * 65536)
constexpr std::int32_t kCostRaw = 629;     // round(0.0096 * 65536)
constexpr std::int32_t kLimitRaw = 20 * 65536;
constexpr std::int32_t kTrustRaw = 5 * 65536;

ModelEvidence::Inputs evidence(Q16_16 measured_N, Q16_16 training_N) {
    ModelEvidence::Inputs in{};
    in.handle_force_N = measured_N;
    in.training_force_N = training_N;
    in.inside_model = true;
    in.on_trained_motion = true;
    in.force_fresh = true;
    return in;
}

// Static: kinetics::State holds the contact problem (a few KiB), too large for a test stack.
kin::State g_state;
kin::Outputs g_out;

/// The handle force the default tables' advance runs needed at an integer depth, interpolated
/// as the firmware does: segment 0, 20..760 mm, a knot every 1 mm (the knot itself); from 752 mm
/// on segment 3, 752..1692 mm, a knot every 2 mm (odd depths half way, a + 0.5 (b - a) in Q16.16):
/// advancing where both hold the depth, the step takes the later run.
Q16_16 training_force_at(int depth_mm) {
    const kin::ReducedTablesQ16& tables = kin::default_reduced_tables();
    const auto& head = tables.header();
    const std::size_t force = kin::kKnotHandleForce;
    if (depth_mm < 752) return tables.knot_value(static_cast<std::size_t>(depth_mm - 20), force);
    const std::size_t knot =
        head.segments[3].first_knot + static_cast<std::size_t>(depth_mm - 752) / 2U;
    const Q16_16 a = tables.knot_value(knot, force);
    if (depth_mm % 2 == 0) return a;
    return a + Q16_16::from_ratio(1, 2) * (tables.knot_value(knot + 1U, force) - a);
}

/// One kinetics step at `depth_mm` with the handle force `force_N`.
void step_at(int depth_mm, Q16_16 force_N) {
    kin::Inputs in{};
    in.insertion_mm = Q16_16::from_int(depth_mm);
    in.handle_force_N = force_N;
    in.fresh_mask = kin::kAllInputSignals;
    kin::step(in, g_state, g_out);
}

}  // namespace

SCOPEKIN_TEST(ModelEvidence, AgreementAddsTheMatchRewardEachStep) {
    ModelEvidence::State state{};
    const Q16_16 force = Q16_16::from_int(12);
    ModelEvidence::Outputs out{};
    for (int n = 1; n <= 155; ++n)
        out = ModelEvidence::step({}, evidence(force, force), state);
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), 155 * kRewardRaw);  // 327050 <= 5 * 65536
    SCOPEKIN_EXPECT_TRUE(!out.trusted);
    out = ModelEvidence::step({}, evidence(force, force), state);
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), 156 * kRewardRaw);  // 329160 > 327680: trusted
    SCOPEKIN_EXPECT_TRUE(out.trusted);
    SCOPEKIN_EXPECT_TRUE(out.evidence);
    for (int n = 0; n < 1000; ++n)
        out = ModelEvidence::step({}, evidence(force, force), state);
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), kLimitRaw);  // bounded
}

SCOPEKIN_TEST(ModelEvidence, AResidualCountsAgainstByItsSquare) {
    // r = 1 N: 2110 - 629 = +1481; r = 2 N: 2110 - 2516 = -406 (the break-even is
    // sqrt(0.0322 / 0.0096) = 1.83 N); r = -3 N: 2110 - 5661 = -3551.
    const std::int32_t expected[] = {1481, -406, -3551};
    const int residuals[] = {1, 2, -3};
    for (int i = 0; i < 3; ++i) {
        ModelEvidence::State state{};
        const ModelEvidence::Outputs out = ModelEvidence::step(
            {}, evidence(Q16_16::from_int(10 + residuals[i]), Q16_16::from_int(10)), state);
        SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), expected[i]);
        SCOPEKIN_EXPECT_EQ(out.residual_N.raw(), Q16_16::from_int(residuals[i]).raw());
    }
    // A residual beyond the 50 N clamp costs 629 * 2500 raw: the sum goes to its lower bound.
    ModelEvidence::State state{};
    const ModelEvidence::Outputs out =
        ModelEvidence::step({}, evidence(Q16_16::from_int(95), Q16_16::from_int(-90)), state);
    SCOPEKIN_EXPECT_EQ(out.residual_N.raw(), Q16_16::from_int(50).raw());
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), -kLimitRaw);
}

SCOPEKIN_TEST(ModelEvidence, NoEvidenceKeepsTheSumAndOutsideTheModelItIsLost) {
    ModelEvidence::State state{};
    state.log_ratio = Q16_16::from_int(10);
    ModelEvidence::Inputs in = evidence(Q16_16::from_int(40), Q16_16::from_int(0));
    in.on_trained_motion = false;  // held, or moving against the run's direction
    ModelEvidence::Outputs out = ModelEvidence::step({}, in, state);
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), Q16_16::from_int(10).raw());
    SCOPEKIN_EXPECT_TRUE(!out.evidence);
    in.on_trained_motion = true;
    in.force_fresh = false;  // a stale force cell says nothing
    out = ModelEvidence::step({}, in, state);
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), Q16_16::from_int(10).raw());
    in.inside_model = false;  // the model does not cover the depth
    out = ModelEvidence::step({}, in, state);
    SCOPEKIN_EXPECT_EQ(out.log_ratio.raw(), -kLimitRaw);
    SCOPEKIN_EXPECT_TRUE(!out.trusted);
}

SCOPEKIN_TEST(ModelEvidence, InvalidConfigurationsAreRefused) {
    SCOPEKIN_EXPECT_TRUE(ModelEvidence::Config{}.valid());
    ModelEvidence::Config bad{};
    bad.mismatch_cost_per_N2 = Q16_16{};
    SCOPEKIN_EXPECT_TRUE(!bad.valid());
    bad = ModelEvidence::Config{};
    bad.trust_above = bad.limit;  // could never be trusted
    SCOPEKIN_EXPECT_TRUE(!bad.valid());
    bad = ModelEvidence::Config{};
    bad.residual_clamp_N = Q16_16::from_int(60);  // 60^2 would overflow Q16.16
    SCOPEKIN_EXPECT_TRUE(!bad.valid());
    kin::Config config = kin::default_config();
    config.model_evidence = bad;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::model_evidence);
}

SCOPEKIN_TEST(ModelEvidence, TheTrainingsHandleForceMakesTheModelsTipThePublishedOne) {
    kin::init(kin::default_config(), g_state);
    for (int d = 20; d <= 600; ++d)
        step_at(d, training_force_at(d));
    // 581 agreeing steps (the first, at 20 mm, moved from 0): 581 * 2110 raw, below the bound.
    SCOPEKIN_EXPECT_EQ(g_out.model_log_likelihood_ratio.raw(), 581 * kRewardRaw);
    SCOPEKIN_EXPECT_TRUE(g_out.tip_from_model);
    SCOPEKIN_EXPECT_EQ(g_out.tip_path_mm.raw(), g_out.model_tip_path_mm.raw());
    SCOPEKIN_EXPECT_EQ(g_out.tip_uncertainty_mm.raw(), Q16_16::from_int(7).raw());
}

SCOPEKIN_TEST(ModelEvidence, AHandleForce3NAboveTheTrainingsTurnsTheTrustAfter93Steps) {
    // 311 agreeing steps (20..330 mm) give 311 * 2110 = 656210 raw; then each step adds
    // 2110 - 629 * 9 = -3551 raw: trusted (> 5 = 327680 raw) after 92 steps (329518 raw), not
    // after 93 (325967 raw).
    kin::init(kin::default_config(), g_state);
    int d = 20;
    for (; d <= 330; ++d)
        step_at(d, training_force_at(d));
    const std::int32_t agreed = 311 * kRewardRaw;
    SCOPEKIN_EXPECT_EQ(g_out.model_log_likelihood_ratio.raw(), agreed);
    const Q16_16 three = Q16_16::from_int(3);
    for (int n = 1; n <= 92; ++n, ++d)
        step_at(d, training_force_at(d) + three);
    SCOPEKIN_EXPECT_EQ(g_out.model_log_likelihood_ratio.raw(), agreed - 92 * 3551);
    SCOPEKIN_EXPECT_TRUE(agreed - 92 * 3551 > kTrustRaw && agreed - 93 * 3551 <= kTrustRaw);
    SCOPEKIN_EXPECT_TRUE(g_out.tip_from_model);
    const Q16_16 last_model_tip = g_out.tip_path_mm;
    SCOPEKIN_EXPECT_EQ(g_out.observer_tip_path_mm.raw(), last_model_tip.raw());  // reseeded
    step_at(d, training_force_at(d) + three);
    SCOPEKIN_EXPECT_EQ(g_out.model_log_likelihood_ratio.raw(), agreed - 93 * 3551);
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
    // The observer continued from the model's tip: one 1 mm step of dead reckoning (eta <= 1)
    // and 0.025 % of forgetting away from it, not the observer's own slack. (The published tip
    // is now the slack regressor's, which reads the observer's slack.)
    const Q16_16 moved = g_out.observer_tip_path_mm - last_model_tip;
    SCOPEKIN_EXPECT_TRUE(!(moved < Q16_16{}) && !(moved > Q16_16::from_ratio(11, 10)));
}

SCOPEKIN_TEST(ModelEvidence, PastTheModelsDepthRangeTheModelIsNotTrusted) {
    kin::init(kin::default_config(), g_state);
    for (int d = 20; d <= 1692; ++d)
        step_at(d, training_force_at(d));
    SCOPEKIN_EXPECT_TRUE(g_out.tip_from_model);
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags & kin::kFaultDepthOutsideModel, 0U);
    step_at(1693, training_force_at(1692));
    SCOPEKIN_EXPECT_TRUE((g_out.fault_flags & kin::kFaultDepthOutsideModel) != 0U);
    SCOPEKIN_EXPECT_EQ(g_out.model_log_likelihood_ratio.raw(), -kLimitRaw);
    SCOPEKIN_EXPECT_TRUE(!g_out.tip_from_model);
}
