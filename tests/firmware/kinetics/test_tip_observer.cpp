// TipObserver (firmware/kinetics/tip_observer.hpp) on cases with closed-form answers: a scope
// that slides freely delivers the hand's travel to the tip (eta = 1), a held tip turns it into
// slack (eta = 0), the linear gate between them, the withdrawal ratio, the exponential
// forgetting of the slack (slack(t) = slack(0) (1 - f h)^n), the physical bounds, the stale
// force cell and the uncertainty's linear model. Runs as GoogleTest on x86-64 / aarch64 and with
// portable_check's runner on Cortex-M4.
#include <cstdint>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "kinetics/tip_observer.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::kinetics::TipObserver;
namespace kin = scopekin::kinetics;

constexpr Q16_16 kPeriod_s = Q16_16::from_ratio(1, 200);

/// The defaults without forgetting: pure dead reckoning, so the answers are exact sums.
TipObserver::Config dead_reckoning() {
    TipObserver::Config config{};
    config.forget_per_s = Q16_16{};
    return config;
}

TipObserver::Inputs at(Q16_16 depth_mm, Q16_16 force_N, bool fresh = true) {
    TipObserver::Inputs in{};
    in.depth_mm = depth_mm;
    in.handle_force_N = force_N;
    in.force_fresh = fresh;
    in.period_s = kPeriod_s;
    return in;
}

/// Moves the depth from `from_mm` to `to_mm` in 1 mm steps at a constant handle force.
TipObserver::Outputs move(const TipObserver::Config& config, TipObserver::State& state, int from_mm,
                          int to_mm, Q16_16 force_N, bool fresh = true) {
    TipObserver::Outputs out{};
    const int step = to_mm >= from_mm ? 1 : -1;
    for (int d = from_mm; d != to_mm + step; d += step)
        out = TipObserver::step(config, at(Q16_16::from_int(d), force_N, fresh), state);
    return out;
}

bool near(Q16_16 value, double expected, double tolerance) {
    const double v = static_cast<double>(value.raw()) / 65536.0;
    return v >= expected - tolerance && v <= expected + tolerance;
}

// Static: kinetics::State holds the contact problem (a few KiB), too large for a test stack.
kin::State g_state;
kin::Outputs g_out;

}  // namespace

SCOPEKIN_TEST(TipObserver, AFreelySlidingScopeDeliversTheHandsTravelToTheTip) {
    TipObserver::State state{};
    const TipObserver::Outputs out =
        move(dead_reckoning(), state, 20, 520, Q16_16::from_int(5));  // 5 N < 15 N: free
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(520).raw());
    SCOPEKIN_EXPECT_EQ(out.slack_mm.raw(), 0);
    SCOPEKIN_EXPECT_EQ(out.eta.raw(), Q16_16::from_int(1).raw());
    SCOPEKIN_EXPECT_TRUE(out.force_evidence);
}

SCOPEKIN_TEST(TipObserver, AHeldTipTurnsTheAdvanceIntoSlack) {
    TipObserver::State state{};
    (void)move(dead_reckoning(), state, 20, 300, Q16_16::from_int(5));
    // Pushing at 50 N (above the 45 N blocked force): 100 mm of advance, the tip does not move.
    const TipObserver::Outputs out = move(dead_reckoning(), state, 301, 400, Q16_16::from_int(50));
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(300).raw());
    SCOPEKIN_EXPECT_EQ(out.slack_mm.raw(), Q16_16::from_int(100).raw());
    SCOPEKIN_EXPECT_EQ(out.eta.raw(), 0);
}

SCOPEKIN_TEST(TipObserver, BetweenFreeAndBlockedTheTipTakesTheGatedShare) {
    TipObserver::State state{};
    (void)move(dead_reckoning(), state, 20, 300, Q16_16::from_int(5));
    // 30 N is half way from 15 N to 45 N: eta = 1/2 exactly, 100 mm of advance moves the tip 50.
    const TipObserver::Outputs out = move(dead_reckoning(), state, 301, 400, Q16_16::from_int(30));
    SCOPEKIN_EXPECT_EQ(out.eta.raw(), Q16_16::from_ratio(1, 2).raw());
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(350).raw());
}

SCOPEKIN_TEST(TipObserver, AWithdrawalMovesTheTipByTheWithdrawalRatio) {
    TipObserver::State state{};
    (void)move(dead_reckoning(), state, 20, 500, Q16_16::from_int(5));
    // Pulling 100 mm back: eta_withdrawal = 1/2, whatever the (stale or fresh) pull.
    TipObserver::Outputs out = move(dead_reckoning(), state, 499, 400, Q16_16::from_int(-20));
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(450).raw());
    SCOPEKIN_EXPECT_TRUE(!out.force_evidence);
    out = move(dead_reckoning(), state, 399, 300, Q16_16::from_int(-20), false);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(400).raw());
}

SCOPEKIN_TEST(TipObserver, WithAStaleForceCellTheTipFollowsTheDepth) {
    TipObserver::State state{};
    (void)move(dead_reckoning(), state, 20, 300, Q16_16::from_int(5));
    // 80 N would hold the tip, but the reading is stale: no evidence, eta = 1.
    const TipObserver::Outputs out =
        move(dead_reckoning(), state, 301, 400, Q16_16::from_int(80), false);
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(400).raw());
    SCOPEKIN_EXPECT_TRUE(!out.force_evidence);
}

SCOPEKIN_TEST(TipObserver, TheSlackIsForgottenExponentially) {
    // 100 mm of slack, then the hand holds still for 20 s (4000 periods): each period keeps
    // 1 - f h of it. f h = 0.05 /s x 5 ms rounds to 16 / 65536 in Q16.16, so the slack left is
    // 100 (1 - 16/65536)^4000 = 100 exp(-0.9766) = 37.66 mm (continuous time: 100 / e = 36.8).
    const TipObserver::Config config{};
    TipObserver::State state{};
    (void)move(dead_reckoning(), state, 20, 300, Q16_16::from_int(5));
    (void)move(dead_reckoning(), state, 301, 400, Q16_16::from_int(50));
    TipObserver::Outputs out{};
    for (int k = 0; k < 4000; ++k)
        out = TipObserver::step(config, at(Q16_16::from_int(400), Q16_16::from_int(50)), state);
    SCOPEKIN_EXPECT_TRUE(near(out.slack_mm, 37.66, 0.2));
}

SCOPEKIN_TEST(TipObserver, TheTipStaysInsideItsPhysicalBounds) {
    TipObserver::State state{};
    // Held while the hand advances 800 mm: the loop cannot exceed max_slack_mm (600 mm).
    TipObserver::Outputs out = move(dead_reckoning(), state, 20, 820, Q16_16::from_int(60));
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), Q16_16::from_int(220).raw());
    // Below the anus the tip is at 0, never negative.
    TipObserver::State outside{};
    out = move(dead_reckoning(), outside, 10, -40, Q16_16{});
    SCOPEKIN_EXPECT_EQ(out.tip_mm.raw(), 0);
}

SCOPEKIN_TEST(TipObserver, TheUncertaintyIsItsLinearModel) {
    // sigma = 21 + 64 x 1.0 m + 0.2 x |100 mm| = 105 mm at a depth of 1000 mm with 100 mm slack
    // (Q16.16 rounds the division by 1000 and 1/5: within 0.1 mm).
    TipObserver::State state{};
    (void)move(dead_reckoning(), state, 20, 900, Q16_16::from_int(5));
    const TipObserver::Outputs out = move(dead_reckoning(), state, 901, 1000, Q16_16::from_int(60));
    SCOPEKIN_EXPECT_EQ(out.slack_mm.raw(), Q16_16::from_int(100).raw());
    SCOPEKIN_EXPECT_TRUE(near(out.uncertainty_mm, 105.0, 0.1));
}

SCOPEKIN_TEST(TipObserver, InvalidConfigurationsAreRefused) {
    SCOPEKIN_EXPECT_TRUE(TipObserver::Config{}.valid());
    TipObserver::Config narrow{};
    narrow.push_blocked_N = narrow.push_free_N + Q16_16::from_ratio(1, 2);  // span < 1 N
    SCOPEKIN_EXPECT_TRUE(!narrow.valid());
    TipObserver::Config ratio{};
    ratio.eta_withdrawal = Q16_16::from_ratio(3, 2);
    SCOPEKIN_EXPECT_TRUE(!ratio.valid());
    TipObserver::Config forget{};
    forget.forget_per_s = Q16_16::from_int(-1);
    SCOPEKIN_EXPECT_TRUE(!forget.valid());
    kin::Config config = kin::default_config();
    config.tip_observer = narrow;
    kin::init(config, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::tip_observer);
}

SCOPEKIN_TEST(TipObserver, PastTheReducedModelsDepthRangeThePublishedTipStillFollows) {
    // The reduced model is trained to 1692 mm and clamps beyond; the observer does not. A free
    // advance (2 N) to 1700 mm at 200 mm/s: the observer's tip is at the depth (a free scope
    // delivers the hand's travel), the model's tip stopped at the end of its range.
    kin::init(kin::default_config(), g_state);
    kin::Inputs in{};
    in.handle_force_N = Q16_16::from_int(2);
    in.fresh_mask = kin::kAllInputSignals;
    Q16_16 model_tip_at_1695{};
    for (int d = 20; d <= 1700; ++d) {
        in.insertion_mm = Q16_16::from_int(d);
        kin::step(in, g_state, g_out);
        if (d == 1695) model_tip_at_1695 = g_out.model_tip_path_mm;
    }
    SCOPEKIN_EXPECT_TRUE((g_out.fault_flags & kin::kFaultDepthOutsideModel) != 0U);
    SCOPEKIN_EXPECT_EQ(g_out.observer_tip_path_mm.raw(), Q16_16::from_int(1700).raw());
    SCOPEKIN_EXPECT_EQ(g_out.model_tip_path_mm.raw(), model_tip_at_1695.raw());
    // The published tip is the slack regressor's (slack_regressor.hpp), within the bounds.
    SCOPEKIN_EXPECT_TRUE(g_out.tip_path_mm > Q16_16::from_int(1100));
    SCOPEKIN_EXPECT_TRUE(!(g_out.tip_path_mm > Q16_16::from_int(2100)));
    SCOPEKIN_EXPECT_TRUE(g_out.tip_uncertainty_mm > Q16_16::from_int(2));
}
