// kinetics::init / kinetics::step with the generated default tables, on every target: the
// tables' own checks, the refusal of a bad configuration, and the handling of bad input
// (kinetics.hpp "Bad input"). Accuracy against the full-order model is tested on the host
// (tests/model/test_reduced_accuracy.cpp).
#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
namespace kin = scopekin::kinetics;

// Static: State holds the contact problem (a few KiB), too large for a small test stack.
kin::State g_state;
kin::Outputs g_out;
std::int8_t g_signs[32768];  // a copy of the tables' slip signs to damage (static: 17 KB)

kin::Inputs sample(int insertion_mm, std::uint8_t fresh = kin::kAllInputSignals) {
    kin::Inputs in{};
    in.insertion_mm = Q16_16::from_int(insertion_mm);
    in.handle_force_N = Q16_16::from_int(2);
    in.fresh_mask = fresh;
    return in;
}

/// Advances from 20 mm to `depth_mm` at 1 mm per step (200 mm/s) and returns the last outputs.
void advance_to(int depth_mm) {
    kin::init(kin::default_config(), g_state);
    for (int d = 20; d <= depth_mm; ++d)
        kin::step(sample(d), g_state, g_out);
}

bool has(std::uint32_t flags, std::uint32_t bit) {
    return (flags & bit) != 0U;
}

}  // namespace

SCOPEKIN_TEST(ReducedTables, DefaultTablesPassShapeGridAndChecksum) {
    const kin::ReducedTablesQ16& t = kin::default_reduced_tables();
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&t, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::none);
    SCOPEKIN_EXPECT_EQ(t.head.stations, std::size_t{12});
    SCOPEKIN_EXPECT_EQ(t.head.segments[0].key_step.raw(), Q16_16::from_int(1).raw());  // 1 mm knots
    SCOPEKIN_EXPECT_EQ(t.head.segments[0].direction, 1);
}

SCOPEKIN_TEST(ReducedTables, DamagedOrMismatchedTablesAreRefused) {
    const kin::ReducedTablesQ16& good = kin::default_reduced_tables();
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(nullptr, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::missing);
    kin::ReducedTablesQ16 wrong_checksum = good;
    wrong_checksum.checksum ^= 1U;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&wrong_checksum, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::checksum_mismatch);
    kin::ReducedTablesQ16 truncated = good;
    truncated.knot_value_count -= 1U;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&truncated, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::bad_shape);
    // A table set for more stations than the firmware's capacity.
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&good, 11U) ==
                         kin::ReducedTablesFault::bad_shape);
    kin::ReducedTablesQ16 bad_step = good;
    bad_step.head.segments[0].key_step = Q16_16{};
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&bad_step, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::bad_grid);
    kin::ReducedTablesQ16 withdraw_first = good;
    withdraw_first.head.segments[0].direction = -1;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&withdraw_first, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::bad_grid);
    kin::ReducedTablesQ16 overlapping = good;
    overlapping.head.segments[1].first_knot -= 1U;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&overlapping, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::bad_shape);
    // The slip signs (one byte each, reduced_tables.hpp "Format"): missing, one short, and a
    // sign that is not -1, 0 or +1.
    kin::ReducedTablesQ16 no_signs = good;
    no_signs.slid_values = nullptr;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&no_signs, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::missing);
    kin::ReducedTablesQ16 short_signs = good;
    short_signs.slid_value_count -= 1U;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&short_signs, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::bad_shape);
    SCOPEKIN_EXPECT_TRUE(good.slid_value_count <= sizeof(g_signs));
    for (std::size_t i = 0; i < good.slid_value_count; ++i)
        g_signs[i] = good.slid_values[i];
    g_signs[good.slid_value_count / 2U] = 2;
    kin::ReducedTablesQ16 bad_sign = good;
    bad_sign.slid_values = g_signs;
    SCOPEKIN_EXPECT_TRUE(kin::check_reduced_tables(&bad_sign, kin::kStationCapacity) ==
                         kin::ReducedTablesFault::bad_shape);
}

SCOPEKIN_TEST(KineticsStep, WithoutTablesEveryStepReportsTheConfigFaultAndNoEstimate) {
    kin::init(kin::Config{}, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::tables);
    kin::step(sample(300), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags, std::uint32_t{kin::kFaultConfig});
    SCOPEKIN_EXPECT_EQ(g_out.tip_path_mm.raw(), 0);
    kin::Config zero_period = kin::default_config();
    zero_period.period_s = Q16_16{};
    kin::init(zero_period, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::period);
}

SCOPEKIN_TEST(KineticsStep, NoEstimateBeforeTheFirstInsertionSample) {
    kin::init(kin::default_config(), g_state);
    kin::step(sample(100, kin::kHandleForce), g_state, g_out);
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultInsertionStale));
    SCOPEKIN_EXPECT_EQ(static_cast<int>(g_out.active_stations), 0);
}

SCOPEKIN_TEST(KineticsStep, EarlyAdvanceTipFollowsTheDepthWithoutFaults) {
    // At 150 mm the scope is in the rectum and lower sigmoid: the tip lies along the centerline a
    // little behind the depth (the shaft bends in the lumen), never ahead of it.
    advance_to(150);
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags, std::uint32_t{0});
    SCOPEKIN_EXPECT_EQ(static_cast<int>(g_out.active_stations), 3);  // stations at 0, 50, 100 mm
    // (The observer's tip; the published one is the slack regressor's, tested on its own.)
    SCOPEKIN_EXPECT_TRUE(g_out.observer_tip_path_mm <= Q16_16::from_int(151));
    SCOPEKIN_EXPECT_TRUE(g_out.observer_tip_path_mm >= Q16_16::from_int(135));
    SCOPEKIN_EXPECT_TRUE(!g_out.self_lock_alarm);
    // 200 mm/s handle speed: the tip moves forward at a comparable speed.
    SCOPEKIN_EXPECT_TRUE(g_out.tip_velocity_mm_per_s > Q16_16::from_int(100));
}

SCOPEKIN_TEST(KineticsStep, StaleInsertionHoldsTheDepthAndRecovers) {
    advance_to(200);
    const Q16_16 tip = g_out.tip_path_mm;
    kin::step(sample(260, kin::kHandleForce | kin::kHandleTorque | kin::kRoll), g_state, g_out);
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultInsertionStale));
    const Q16_16 drift = g_out.tip_path_mm - tip;
    SCOPEKIN_EXPECT_TRUE(drift <= Q16_16::from_ratio(1, 10) && drift >= Q16_16::from_ratio(-1, 10));
    kin::step(sample(201), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags, std::uint32_t{0});
}

/// Tips published while the force cell is stale (StaleForce... below).
Q16_16 g_stale_tips[60];

/// From 200 mm, 60 steps advancing 1 mm each with the force cell stale, its input carrying
/// `stale_force_N`; fills g_stale_tips and checks the fault bits of each step.
bool advance_with_a_stale_force_cell(int stale_force_N) {
    advance_to(200);
    bool flags_right = true;
    for (int k = 1; k <= 60; ++k) {
        kin::Inputs in = sample(200 + k, kin::kInsertion | kin::kRoll);
        in.handle_force_N = Q16_16::from_int(stale_force_N);
        kin::step(in, g_state, g_out);
        g_stale_tips[k - 1] = g_out.tip_path_mm;
        // Stale from the first period; lost (kFaultForceBlind) from the 20th in a row.
        flags_right = flags_right && has(g_out.fault_flags, kin::kFaultForceStale) &&
                      has(g_out.fault_flags, kin::kFaultForceBlind) == (k >= 20);
    }
    return flags_right;
}

SCOPEKIN_TEST(KineticsStep, AStaleForceCellIsFlaggedLostAfter20PeriodsAndSaysNothing) {
    SCOPEKIN_EXPECT_TRUE(advance_with_a_stale_force_cell(2));
    Q16_16 first_run[60];
    for (int k = 0; k < 60; ++k)
        first_run[k] = g_stale_tips[k];
    // What a stale input carries is not a measurement: 80 N instead of 2 N changes nothing.
    SCOPEKIN_EXPECT_TRUE(advance_with_a_stale_force_cell(80));
    for (int k = 0; k < 60; ++k)
        SCOPEKIN_EXPECT_EQ(g_stale_tips[k].raw(), first_run[k].raw());
    // The tip still follows the depth: the hand advanced 60 mm.
    SCOPEKIN_EXPECT_TRUE(g_stale_tips[59] - g_stale_tips[0] > Q16_16::from_int(30));
    // The first fresh sample clears both bits.
    kin::step(sample(261), g_state, g_out);
    SCOPEKIN_EXPECT_TRUE(!has(g_out.fault_flags, kin::kFaultForceStale));
    SCOPEKIN_EXPECT_TRUE(!has(g_out.fault_flags, kin::kFaultForceBlind));
    // A threshold of 0 periods (lost before it is stale) is refused.
    kin::Config never = kin::default_config();
    never.force_blind_after_steps = 0;
    kin::init(never, g_state);
    SCOPEKIN_EXPECT_TRUE(g_state.config_fault == kin::ConfigFault::limits);
}

SCOPEKIN_TEST(KineticsStep, OneMetreJumpIsRateLimitedFlaggedAndRecovered) {
    advance_to(200);
    const Q16_16 tip = g_out.observer_tip_path_mm;
    kin::step(sample(1200), g_state, g_out);  // 1 m in 5 ms: an encoder glitch
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultInsertionJump));
    // The depth moved by at most 1000 mm/s * 5 ms = 5 mm, so the tip stays behind 205 mm: it may
    // catch up the few mm it lagged at 200 mm (the tables carry static friction's stick-slip: the
    // tip at 196.3 mm there), never run ahead of the scope's own depth.
    SCOPEKIN_EXPECT_TRUE(g_out.observer_tip_path_mm <= Q16_16::from_int(206));
    SCOPEKIN_EXPECT_TRUE(g_out.observer_tip_path_mm >= tip);
    SCOPEKIN_EXPECT_EQ(
        g_state.insertion_mm.raw(),
        (Q16_16::from_int(200) + Q16_16::from_int(1000) * Q16_16::from_ratio(1, 200)).raw());
    kin::step(sample(200), g_state, g_out);  // the glitch is gone: back within one limit
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags, std::uint32_t{0});
    SCOPEKIN_EXPECT_EQ(g_state.insertion_mm.raw(), Q16_16::from_int(200).raw());
}

SCOPEKIN_TEST(KineticsStep, OutOfRangeInputsAreSaturatedAndFlagged) {
    advance_to(100);
    kin::Inputs in = sample(100);
    in.handle_force_N = Q16_16::from_int(1000);
    in.handle_torque_Nmm = Q16_16::from_int(-30000);
    in.roll_rad = Q16_16::from_int(400);
    kin::step(in, g_state, g_out);
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultForceRange));
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultTorqueRange));
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultRollRange));
    SCOPEKIN_EXPECT_EQ(g_state.handle_force_N.raw(), Q16_16::from_int(100).raw());
    SCOPEKIN_EXPECT_EQ(g_state.handle_torque_Nmm.raw(), Q16_16::from_int(-2000).raw());
    // A depth below the encoder's range: saturated to -50 mm (reached at the rate limit), and
    // below the tables' first knot (20 mm), so the model clamps and says so.
    kin::init(kin::default_config(), g_state);
    kin::step(sample(-500), g_state, g_out);
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultInsertionRange));
    SCOPEKIN_EXPECT_TRUE(has(g_out.fault_flags, kin::kFaultDepthOutsideModel));
    SCOPEKIN_EXPECT_EQ(g_state.insertion_mm.raw(), Q16_16::from_int(-50).raw());
}

// The training run in use follows the hand (reduced_kinetics.hpp, "Training runs"): segment 0
// advances, 1 is the hold at 680 mm, 2 the withdrawal 680 -> 560 mm (model/reduction/training.json).
SCOPEKIN_TEST(KineticsStep, TheHandsMotionPicksTheTrainingRun) {
    const kin::ReducedModelHeader<Q16_16>& head = kin::default_reduced_tables().header();
    SCOPEKIN_EXPECT_EQ(head.segment_count, std::size_t{4});
    SCOPEKIN_EXPECT_EQ(head.segments[1].kind, static_cast<int>(kin::kSegmentHold));
    SCOPEKIN_EXPECT_EQ(head.segments[2].direction, -1);
    SCOPEKIN_EXPECT_EQ(head.segments[3].direction, 1);
    SCOPEKIN_EXPECT_EQ(head.segments[3].key_start.raw(), Q16_16::from_int(752).raw());
    SCOPEKIN_EXPECT_EQ(kin::detail::segment_end_mm(head.segments[3]).raw(),
                       Q16_16::from_int(1692).raw());
    advance_to(680);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{0});
    for (int i = 0; i < 100; ++i)
        kin::step(sample(680), g_state, g_out);  // 0.5 s held still
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{1});
    SCOPEKIN_EXPECT_EQ(g_state.model.hold_steps, std::uint32_t{100});
    // The first move after the hold sets the direction at once: withdrawing, the withdrawal run.
    kin::step(sample(679), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.direction, -1);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{2});
    for (int d = 678; d >= 600; --d)
        kin::step(sample(d), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{2});
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags, std::uint32_t{0});
    // Below the withdrawal run's depths: back to segment 0, still withdrawing.
    for (int d = 599; d >= 500; --d)
        kin::step(sample(d), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{0});
    SCOPEKIN_EXPECT_EQ(g_state.model.direction, -1);
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags, std::uint32_t{0});
}

SCOPEKIN_TEST(KineticsStep, BeyondTheFirstAdvanceTheReAdvanceRunCoversTheDepthBothWays) {
    // Advancing past 760 mm: the re-advance run (segment 3, 752..1692 mm), inside the model.
    advance_to(760);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{3});  // the last run holding 760 mm
    for (int d = 761; d <= 1200; ++d)
        kin::step(sample(d), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{3});
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags & kin::kFaultDepthOutsideModel, std::uint32_t{0});
    // Withdrawing there: no withdrawal run holds the depth, so the advance run, backwards.
    for (int d = 1199; d >= 1000; --d)
        kin::step(sample(d), g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.direction, -1);
    SCOPEKIN_EXPECT_EQ(g_state.model.segment, std::size_t{3});
    SCOPEKIN_EXPECT_EQ(g_out.fault_flags & kin::kFaultDepthOutsideModel, std::uint32_t{0});
    // Past its last knot the depth is clamped and flagged.
    for (int d = 1000; d <= 1700; d += 2)
        kin::step(sample(d), g_state, g_out);
    SCOPEKIN_EXPECT_TRUE((g_out.fault_flags & kin::kFaultDepthOutsideModel) != 0U);
}

SCOPEKIN_TEST(KineticsStep, DepthJitterBelowTheHysteresisDoesNotReverseTheDirection) {
    advance_to(600);
    kin::Inputs in = sample(600);
    in.insertion_mm = Q16_16::from_ratio(5996, 10);  // 0.4 mm back: within the 0.5 mm hysteresis
    kin::step(in, g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.direction, 1);
    in.insertion_mm = Q16_16::from_ratio(5994, 10);  // 0.6 mm back: reversed
    kin::step(in, g_state, g_out);
    SCOPEKIN_EXPECT_EQ(g_state.model.direction, -1);
}

SCOPEKIN_TEST(KineticsStep, PublishedNormalForcesNeverPullOnTheWall) {
    // Found by fuzz.sensor_box: a box starting at 530.5 mm with 1 N on the handle published a
    // station normal force of -1.12 N. That station is passive (its training stretch presses on
    // opposite walls, so the resultant pulls); a wall can only push (kinetics_io.hpp: >= 0).
    kin::init(kin::default_config(), g_state);
    kin::Inputs in = sample(530);
    in.insertion_mm = Q16_16::from_ratio(5305, 10);
    in.handle_force_N = Q16_16::from_int(1);
    kin::step(in, g_state, g_out);
    bool resultant_pulls = false;
    for (std::size_t j = 0; j < g_out.active_stations; ++j) {
        SCOPEKIN_EXPECT_TRUE(g_out.stations[j].normal_force_N >= Q16_16{});
        resultant_pulls = resultant_pulls || g_state.model.force_N[j][0] < Q16_16{};
    }
    SCOPEKIN_EXPECT_TRUE(resultant_pulls);  // the case above still exercises a pulling station
    // A first period at every depth of the training, 5 mm apart.
    for (int depth = 20; depth <= 1700; depth += 5) {
        kin::init(kin::default_config(), g_state);
        kin::step(sample(depth), g_state, g_out);
        for (std::size_t j = 0; j < g_out.active_stations; ++j)
            SCOPEKIN_EXPECT_TRUE(g_out.stations[j].normal_force_N >= Q16_16{});
    }
}
