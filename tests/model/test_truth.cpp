// The ground truth's definitions (model/truth/): loop episodes, advance efficiency and force
// episodes on synthetic sampled runs whose answers are known by construction (a tip that keeps
// pace, a stick-slip sawtooth, a tip that stops while the hand pushes 100 mm, a withdrawal that
// gives the excess back, a known force trace); the place along a displaced centerline against
// closed forms (a straight colon translated and stretched, a circular arc); the frontal-view
// crossing test; the world readout against World::probe_stations and model::station_forces (the
// reduction's own definition of a station's place, frame and force); and bad input refused
// with a message naming the series and the sample.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_beam.hpp"
#include "model/reduction/reduced_model.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/truth/truth_definitions.hpp"
#include "model/truth/truth_readout.hpp"
#include "model_test_support.hpp"

namespace scopekin::model::truth {
namespace {

using testing::expect_model_error;

constexpr double kPeriod_s = 0.005;  // the box's period

/// A run sampled every 5 ms: depth(t) and tip(t) given as functions.
template <class Depth, class Tip>
RunSeries sampled(double duration_s, Depth depth, Tip tip) {
    RunSeries r;
    const auto n = static_cast<std::size_t>(std::lround(duration_s / kPeriod_s));
    for (std::size_t i = 0; i <= n; ++i) {
        const double t = static_cast<double>(i) * kPeriod_s;
        r.time_s.push_back(t);
        r.insertion_mm.push_back(depth(t));
        r.tip_path_mm.push_back(tip(t));
    }
    return r;
}

TEST(LoopEpisodes, ATipThatKeepsPaceHasNone) {
    // 20 -> 320 mm at 20 mm/s; the tip goes 95 % of the way (it takes the outer curve).
    const RunSeries run = sampled(
        15.0, [](double t) { return 20.0 + 20.0 * t; }, [](double t) { return 20.0 + 19.0 * t; });
    const LoopAnalysis a = loop_episodes(run);
    EXPECT_TRUE(a.episodes.empty());
    for (double e : a.excess_mm)
        EXPECT_LE(e, 0.05 * 20.0 * kPaceWindow_s + 1e-9);  // the lag over one pace window at most
    EXPECT_FALSE(loop_onset_s(run).has_value());
}

TEST(LoopEpisodes, AStickSlipStallOfTwoTenthsOfASecondIsNoLoop) {
    // 20 mm/s; every second the tip stalls for 0.2 s, then slips back to the hand's pace within one
    // period: the sawtooth of a normal advance's stick-slip (4 mm taken up and given back).
    const auto tip = [](double t) {
        const double cycle = std::floor(t);
        const double in = t - cycle;
        const double stall_end = 0.2;
        if (in < stall_end) return 20.0 * cycle;  // stuck since the cycle began
        return 20.0 * t;                          // slipped: back at the hand's pace
    };
    const RunSeries run = sampled(
        20.0, [](double t) { return 20.0 * t; }, tip);
    const LoopAnalysis a = loop_episodes(run);
    EXPECT_TRUE(a.episodes.empty());
    double largest = 0;
    for (double e : a.excess_mm)
        largest = std::max(largest, e);
    EXPECT_NEAR(largest, 20.0 * 0.2, 20.0 * kPeriod_s + 1e-9);  // 4 mm, within one period
}

/// The tip keeps pace for 5 s, then stops while the hand advances 100 mm more (5 s at 20 mm/s).
double stop_depth(double t) {
    return 20.0 + 20.0 * std::min(t, 10.0);
}
double stop_tip(double t) {
    return 20.0 + 20.0 * std::min(t, 5.0);
}

TEST(LoopEpisodes, ATipThatStopsWhileTheHandPushesOneHundredMillimetres) {
    const RunSeries run = sampled(12.0, stop_depth, stop_tip);  // then 2 s of holding still
    const LoopAnalysis a = loop_episodes(run);
    ASSERT_EQ(a.episodes.size(), 1U);
    const LoopEpisode& e = a.episodes.front();
    EXPECT_NEAR(e.onset_s, 5.0, kPeriod_s + 1e-9) << "onset at the stop, within one period";
    EXPECT_NEAR(e.detected_s, 5.0 + kLoopOnsetExcess_mm / 20.0, kPeriod_s + 1e-9);
    EXPECT_NEAR(e.peak_excess_mm, 100.0, 1e-9);
    EXPECT_FALSE(e.end.has_value()) << "the loop is still in the colon while the hand holds";
    EXPECT_EQ(a.episode.back(), 1);
    EXPECT_EQ(a.episode[static_cast<std::size_t>(std::lround(4.9 / kPeriod_s))], 0);
    EXPECT_NEAR(*loop_onset_s(run), 5.0, kPeriod_s + 1e-9);
}

TEST(LoopEpisodes, AWithdrawalWithTheTipHookedGivesTheExcessBack) {
    // As above, then from 12 s the hand withdraws at 20 mm/s while the tip stays hooked: the
    // excess falls to kLoopEndExcess_mm after 95 mm, at 12 + 95/20 = 16.75 s.
    const RunSeries run = sampled(
        20.0,
        [](double t) { return t < 12.0 ? stop_depth(t) : 220.0 - 20.0 * std::min(t - 12.0, 6.0); },
        stop_tip);
    const LoopAnalysis a = loop_episodes(run);
    ASSERT_EQ(a.episodes.size(), 1U);
    const LoopEpisode& e = a.episodes.front();
    ASSERT_TRUE(e.end_s.has_value());
    EXPECT_NEAR(*e.end_s, 12.0 + (100.0 - kLoopEndExcess_mm) / 20.0, kPeriod_s + 1e-9);
    EXPECT_EQ(e.end_reason, "given_back");
    EXPECT_EQ(a.episode.back(), 0);
}

TEST(LoopEpisodes, ATipThatKeepsPaceAgainForASecondEndsTheEpisode) {
    // The tip stops for 5 s (100 mm), then follows the hand again from 10 s (the loop pushed
    // through): the episode ends where the tip's kept-pace run began; nothing new starts.
    const RunSeries run = sampled(
        16.0, [](double t) { return 20.0 + 20.0 * t; },
        [](double t) {
            return t < 5.0 ? 20.0 + 20.0 * t : t < 10.0 ? 120.0 : 120.0 + 20.0 * (t - 10.0);
        });
    const LoopAnalysis a = loop_episodes(run);
    ASSERT_EQ(a.episodes.size(), 1U);
    const LoopEpisode& e = a.episodes.front();
    EXPECT_EQ(e.end_reason, "tip_keeps_pace");
    ASSERT_TRUE(e.end_s.has_value());
    // Kept pace from the sample where the trailing 0.5 s shows the tip at half the hand's
    // advance: 10 + 0.5 * kPaceWindow_s.
    EXPECT_NEAR(*e.end_s, 10.0 + (1.0 - kPaceFraction) * kPaceWindow_s, kPeriod_s + 1e-9);
}

TEST(LoopEpisodes, ALoopThatStillLetsTheTipCreepIsDetectedFromWhereTheCreepBegan) {
    // From 4 s the tip advances at 30 % of the hand: the excess grows at 14 mm/s and reaches
    // 20 mm 20/14 s later; the onset is where the tip slowed.
    const RunSeries run = sampled(
        8.0, [](double t) { return 20.0 * t; },
        [](double t) { return t < 4.0 ? 20.0 * t : 80.0 + 6.0 * (t - 4.0); });
    const LoopAnalysis a = loop_episodes(run);
    ASSERT_EQ(a.episodes.size(), 1U);
    EXPECT_NEAR(a.episodes[0].onset_s, 4.0, kPeriod_s + 1e-9);
    EXPECT_NEAR(a.episodes[0].detected_s, 4.0 + 20.0 / 14.0, kPeriod_s + 1e-9);
}

TEST(AdvanceEfficiency, TipOverHandleAdvanceOverTheTrailingWindow) {
    // Tip at 60 % of the hand, then the hand holds still: 0.6, then undefined once the trailing
    // window holds less than kEfficiencyMinHandle_mm of advance.
    const RunSeries run = sampled(
        4.0, [](double t) { return 10.0 * std::min(t, 2.0); },
        [](double t) { return 6.0 * std::min(t, 2.0); });
    const std::vector<double> e = advance_efficiency(run);
    EXPECT_NEAR(e[static_cast<std::size_t>(std::lround(1.0 / kPeriod_s))], 0.6, 1e-12);
    EXPECT_NEAR(e[static_cast<std::size_t>(std::lround(0.2 / kPeriod_s))], 0.6,
                1e-12);  // young run
    EXPECT_TRUE(std::isnan(e[0]));
    EXPECT_TRUE(std::isnan(e.back()));
    // At 2.45 s the window [1.95, 2.45] holds 0.5 mm of advance (< 1 mm): undefined.
    EXPECT_TRUE(std::isnan(e[static_cast<std::size_t>(std::lround(2.45 / kPeriod_s))]));
}

TEST(ForceEpisodes, OnsetAtTheThresholdEndBelowNinetyPercentOfIt) {
    // A known trace, one sample every 0.1 s.
    const std::vector<double> f{0, 5, 9.99, 10, 12, 9.5, 9.0, 11, 8.99, 8, 14.5, 13, 12.7, 12.5, 3};
    std::vector<double> t;
    for (std::size_t i = 0; i < f.size(); ++i)
        t.push_back(0.1 * static_cast<double>(i));
    // Hysteresis alone (no merging of episodes close in time).
    const std::vector<ForceEpisode> w =
        force_episodes(t, f, kForceWarning_N, kForceClearFraction, 0.0);
    ASSERT_EQ(w.size(), 2U);
    EXPECT_EQ(w[0].onset, 3U);  // 10 N reaches the threshold
    EXPECT_EQ(*w[0].end, 8U);   // 9.5 and 9.0 stay in the band; 8.99 < 9 ends it
    EXPECT_DOUBLE_EQ(w[0].peak_N, 12.0);
    EXPECT_EQ(w[1].onset, 10U);
    EXPECT_EQ(*w[1].end, 14U);
    const std::vector<ForceEpisode> c =
        force_episodes(t, f, kForceCritical_N, kForceClearFraction, 0.0);
    ASSERT_EQ(c.size(), 1U);
    EXPECT_EQ(c[0].onset, 10U);
    EXPECT_EQ(*c[0].end, 13U);  // 12.7 >= 12.6 stays, 12.5 ends
    const std::vector<int> level = force_levels(t, f);
    // With the default merging the two warning episodes (0.2 s apart) are one.
    EXPECT_EQ(level, (std::vector<int>{0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 1, 0}));
    // A dip below the clear level shorter than kForceMergeGap_s continues the episode; a longer
    // one ends it (samples every 0.1 s: a 0.3 s dip merges, a 0.6 s one does not).
    const std::vector<double> dips{12, 8, 8, 8, 12, 8, 8, 8, 8, 8, 8, 12, 5};
    std::vector<double> td;
    for (std::size_t i = 0; i < dips.size(); ++i)
        td.push_back(0.1 * static_cast<double>(i));
    const std::vector<ForceEpisode> merged = force_episodes(td, dips, kForceWarning_N);
    ASSERT_EQ(merged.size(), 2U);
    EXPECT_EQ(merged[0].onset, 0U);
    EXPECT_EQ(*merged[0].end, 5U);
    EXPECT_EQ(merged[1].onset, 11U);
    EXPECT_EQ(*merged[1].end, 12U);
    // An episode still up at the end has no end.
    const std::vector<ForceEpisode> open = force_episodes({0, 1}, {0, 20}, 14.0);
    ASSERT_EQ(open.size(), 1U);
    EXPECT_FALSE(open[0].end.has_value());
}

TEST(LoopType, TheRegionIsTheOneThatBowedDuringTheEpisode) {
    // The sigmoid still bows 60 mm from an earlier loop, but only the transverse colon moved from
    // the onset to the peak: a transverse loop; crossing in the frontal view makes it a gamma.
    RegionBow onset{}, peak{};
    onset[1] = 60.0;  // sigmoid
    peak[1] = 60.0;
    peak[4] = 35.0;  // transverse
    LoopShape shape = classify_loop(onset, peak, false);
    EXPECT_EQ(shape.region, ColonRegion::transverse);
    EXPECT_EQ(shape.type, "transverse");
    EXPECT_EQ(classify_loop(onset, peak, true).type, "gamma");
    // Nothing grew: the region bowing most.
    shape = classify_loop(peak, peak, true);
    EXPECT_EQ(shape.region, ColonRegion::sigmoid);
    EXPECT_EQ(shape.type, "alpha");
}

TEST(LoopType, RegionAndCrossingGiveTheType) {
    EXPECT_EQ(loop_type(ColonRegion::sigmoid, false), "N");
    EXPECT_EQ(loop_type(ColonRegion::sigmoid, true), "alpha");
    EXPECT_EQ(loop_type(ColonRegion::transverse, true), "gamma");
    EXPECT_EQ(loop_type(ColonRegion::splenic_flexure, false), "transverse");
    EXPECT_EQ(loop_type(ColonRegion::descending, true), "other");
}

TEST(TruthBadInput, RefusedNamingTheSeriesAndTheSample) {
    RunSeries r = sampled(
        1.0, [](double t) { return t; }, [](double t) { return t; });
    RunSeries shorter = r;
    shorter.tip_path_mm.pop_back();
    expect_model_error([&] { loop_episodes(shorter); },
                       "tip_path_mm has 200 samples, time_s has 201");
    RunSeries nan = r;
    nan.insertion_mm[7] = std::nan("");
    expect_model_error([&] { advance_efficiency(nan); }, "insertion_mm[7] = nan is not finite");
    RunSeries back = r;
    back.time_s[3] = back.time_s[2];
    expect_model_error([&] { loop_episodes(back); },
                       "time_s[3] = 0.01 is not later than time_s[2]");
    expect_model_error(
        [&] {
            force_episodes({0, 1}, {1, 2}, 0.0);
        },
        "threshold 0 N must be positive");
    expect_model_error(
        [&] {
            force_episodes({0, 1}, {1, 2}, 10.0, 1.5);
        },
        "clear fraction 1.5 must be in (0, 1]");
    expect_model_error(
        [&] {
            force_episodes({0, 1}, {1, -2}, 10.0);
        },
        "force_N[1] = -2 is negative");
    expect_model_error(
        [&] {
            force_episodes({0, 1}, {1, 2}, 10.0, 0.9, -1.0);
        },
        "merge gap -1 s must be finite and >= 0");
    expect_model_error([&] { force_episodes({0, 1}, {1}, 10.0); }, "force_N has 1 samples");
    expect_model_error(
        [&] {
            locate_on_centerline({Eigen::Vector3d::Zero()}, {0.0}, {0.0}, Eigen::Vector3d::Zero(),
                                 0, 1);
        },
        "at least 2 points");
    EXPECT_TRUE(loop_episodes(RunSeries{}).episodes.empty());  // an empty run has none
}

// --- Places along a displaced centerline -------------------------------------------------------

std::vector<Eigen::Vector3d> straight_points(std::size_t n, double spacing_mm) {
    std::vector<Eigen::Vector3d> p;
    for (std::size_t i = 0; i < n; ++i)
        p.emplace_back(spacing_mm * static_cast<double>(i), 0.0, 0.0);
    return p;
}

TEST(CenterlinePlace, AStraightColonTranslatedAndStretched) {
    const std::vector<Eigen::Vector3d> rest = straight_points(101, 5.0);  // 500 mm
    const std::vector<double> rest_arc = displaced_arc_lengths(rest);
    EXPECT_DOUBLE_EQ(rest_arc.back(), 500.0);
    // Translated by (3, 40, -7): the place of a point moved with it is unchanged.
    std::vector<Eigen::Vector3d> moved = rest;
    const Eigen::Vector3d shift(3.0, 40.0, -7.0);
    for (Eigen::Vector3d& p : moved)
        p += shift;
    CenterlinePlace c = locate_on_centerline(moved, rest_arc, displaced_arc_lengths(moved),
                                             Eigen::Vector3d(212.5, 4.0, 0.0) + shift, 0, 500);
    ASSERT_TRUE(c.found);
    EXPECT_NEAR(c.path_mm, 212.5, 1e-9);
    EXPECT_NEAR(c.displaced_path_mm, 212.5, 1e-9);
    EXPECT_NEAR(c.distance_mm, 4.0, 1e-9);
    // Stretched by 1.5 along its axis: the colon coordinate of the point at x = 300 mm is 200 mm,
    // its arc along the displaced centerline 300 mm.
    std::vector<Eigen::Vector3d> stretched = rest;
    for (Eigen::Vector3d& p : stretched)
        p.x() *= 1.5;
    c = locate_on_centerline(stretched, rest_arc, displaced_arc_lengths(stretched),
                             Eigen::Vector3d(300.0, 0.0, 2.0), 0, 500);
    EXPECT_NEAR(c.path_mm, 200.0, 1e-9);
    EXPECT_NEAR(c.displaced_path_mm, 300.0, 1e-9);
    // The window keeps the search to the segments whose rest arc overlaps it: [0, 100] mm ends
    // with the segment from 100 to 105 mm (x = 150 to 157.5 mm), whose end is the closest point.
    c = locate_on_centerline(stretched, rest_arc, displaced_arc_lengths(stretched),
                             Eigen::Vector3d(300.0, 0.0, 2.0), 0, 100);
    EXPECT_NEAR(c.path_mm, 105.0, 1e-9);
    EXPECT_NEAR(c.displaced_path_mm, 157.5, 1e-9);
}

TEST(CenterlinePlace, ACircularArcGivesRTheta) {
    // A quarter circle of radius 200 mm in 90 chords: the arc to the point at angle theta is
    // R theta on the circle; on the polygon, k chords of 2 R sin(d/2) to vertex k.
    const double radius = 200.0;
    const std::size_t chords = 90;
    const double d = 0.5 * M_PI / static_cast<double>(chords);
    std::vector<Eigen::Vector3d> p;
    for (std::size_t i = 0; i <= chords; ++i)
        p.emplace_back(radius * std::sin(d * static_cast<double>(i)),
                       radius * (1.0 - std::cos(d * static_cast<double>(i))), 0.0);
    const std::vector<double> arc = displaced_arc_lengths(p);
    const std::size_t k = 37;
    const double chord = 2.0 * radius * std::sin(0.5 * d);
    EXPECT_NEAR(arc[k], static_cast<double>(k) * chord, 1e-9);
    // A point 10 mm inside the circle at vertex k's angle.
    const double theta = d * static_cast<double>(k);
    const Eigen::Vector3d inside((radius - 10.0) * std::sin(theta),
                                 radius - (radius - 10.0) * std::cos(theta), 0.0);
    // Its closest point lies on the chord before vertex k, 10 sin(d/2) from the vertex (the chord
    // turns d/2 inwards from the tangent there), 10 cos(d/2) from the point.
    const CenterlinePlace c = locate_on_centerline(p, arc, arc, inside, 0, 1000);
    EXPECT_NEAR(c.displaced_path_mm, static_cast<double>(k) * chord - 10.0 * std::sin(0.5 * d),
                1e-9);
    EXPECT_NEAR(c.distance_mm, 10.0 * std::cos(0.5 * d), 1e-9);
    EXPECT_NEAR(c.displaced_path_mm, radius * theta, 0.1);  // the circle's R theta
}

TEST(FrontalCrossing, AnAlphaCrossesAnNDoesNot) {
    // N: up, across, up (a zigzag in the frontal plane). Alpha: a loop that comes back across its
    // own path. Depth (z) does not matter in the frontal view.
    const std::vector<Eigen::Vector3d> n{{0, 0, 0}, {0, 100, 0}, {80, 20, 30}, {80, 150, 0}};
    EXPECT_FALSE(crosses_itself_xy(n));
    const std::vector<Eigen::Vector3d> alpha{{0, 0, 0},    {0, 100, 0},    {60, 140, 40},
                                             {90, 80, 10}, {-40, 60, -30}, {-60, 200, 0}};
    EXPECT_TRUE(crosses_itself_xy(alpha));
}

// --- The world readout against the reduction's own definitions --------------------------------

Scenario short_advance() {
    const char* text = R"({
    "description": "short advance into the default colon",
    "colon": {"bundled": "default"},
    "scope": {"model": "cf_q160l", "length_mm": 1700, "elements": 170},
    "gravity_mm_per_s2": [0, 0, -9810],
    "initial_insertion_mm": 20,
    "solver": {"time_step_s": 0.01},
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 8, "speed_mm_per_s": 30}],
    "outputs": {"sample_rate_Hz": 30}
  })";
    return read_scenario(nlohmann::json::parse(text), "short_advance");
}

TEST(TruthReader, StationsMatchTheProbeAndTheReductionsStationForces) {
    const Scenario scenario = short_advance();
    std::unique_ptr<World> world = build_world(scenario);
    ProcedurePlayer player(scenario.procedure, scenario.settings.initial_insertion_mm,
                           scenario.scope.length_mm);
    const StationLayout layout = station_layout(*world);
    const TruthReader reader(*world, layout, scenario.settings.gravity_mm_per_s2);
    const std::vector<std::size_t> increasing(layout.nodes.rbegin(), layout.nodes.rend());
    std::size_t compared = 0;
    double largest_force = 0;
    while (world->time_s() < scenario.procedure.end_s() - 1e-9) {
        const WorldStepReport report = world->step(player.command(
            world->time_s(), world->time_step_s(), world->insertion_depth_mm(), world->roll_rad()));
        ASSERT_TRUE(report.ok) << report.failure;
        if (world->time_s() < 2.0 || std::lround(world->time_s() * 100) % 50 != 0) continue;
        const TruthReadout r = reader.read(*world);
        const StationCompliance probe = world->probe_stations(increasing);
        const std::vector<Eigen::Vector3d> forces =
            station_forces(*world, probe, layout.stations, layout.spacing_mm);
        for (std::size_t s = 0; s < layout.stations; ++s) {
            const StationProbe& p = probe.stations[layout.stations - 1 - s];
            ASSERT_EQ(r.stations[s].inside, p.inside) << "station " << s;
            if (!p.inside) continue;
            EXPECT_NEAR(r.stations[s].path_mm, p.path_mm, 1e-9) << "station " << s;
            EXPECT_EQ(r.stations[s].region, p.region);
            EXPECT_LT((r.stations[s].frame - p.frame).norm(), 1e-9) << "station " << s;
            EXPECT_LT((r.stations[s].force_N - forces[s]).norm(), 1e-9) << "station " << s;
            largest_force = std::max(largest_force, forces[s].norm());
            ++compared;
        }
        EXPECT_DOUBLE_EQ(r.tip_path_mm, probe.stations.back().path_mm);
        // Arc along the displaced centerline vs the colon coordinate: the colon moves little here.
        EXPECT_NEAR(r.tip_displaced_path_mm, r.tip_path_mm, 5.0);
    }
    EXPECT_GT(compared, 20U);
    EXPECT_GT(largest_force, 0.1) << "the comparison must include loaded stations";
}

/// A straight scope of `length_mm` in 10 mm elements, `inserted_mm` of it in a straight, wide
/// 600 mm tube (no gravity: it touches nothing).
World straight_world(double length_mm, double inserted_mm) {
    const ColonTube tube = straight_tube(600.0, 20.0, ColonRegion::rectum, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.gravity_mm_per_s2.setZero();
    settings.initial_insertion_mm = inserted_mm;
    ScopeSpec scope;
    scope.length_mm = length_mm;
    scope.elements = static_cast<std::size_t>(std::lround(length_mm / 10.0));
    scope.section = cf_q160l::section();
    return World(scope, tube, default_colon_properties(), settings);
}

TEST(TruthReader, AStraightScopeInAStraightTubeIsAtItsDepth) {
    const World world = straight_world(600.0, 300.0);
    const TruthReader reader(world, station_layout(world, 4, 50.0), Eigen::Vector3d::Zero());
    const TruthReadout r = reader.read(world);
    EXPECT_NEAR(r.tip_path_mm, 300.0, 1e-9);
    EXPECT_NEAR(r.tip_displaced_path_mm, 300.0, 1e-9);
    for (std::size_t s = 0; s < 4; ++s)
        EXPECT_NEAR(r.stations[s].path_mm, 300.0 - 50.0 * static_cast<double>(s), 1e-9);
    EXPECT_FALSE(r.has_wall_force);
    EXPECT_FALSE(r.scope_crosses);
    EXPECT_NEAR(r.bow_mm, 0.0, 1e-9);
}

// Where the contact detection tracks a node, its place along the colon is searched only around
// the tracked segment: a node cannot be read onto another turn of a loop that lies closer in
// space (the 400 mm window did that in looped runs: the truth tip jumped 200 mm in 10 ms).
TEST(TruthReader, ATrackedNodeIsSearchedAroundItsTrackedSegmentOnly) {
    World world = straight_world(600.0, 300.0);  // 10 mm segments; the tip at 300 mm
    const std::size_t tip = world.scope_node_count() - 1;
    EXPECT_EQ(world.tracked_colon_segment(tip), -1);
    const auto [untracked_from, untracked_to] = world.centerline_search_window_mm(tip, 400.0);
    EXPECT_NEAR(untracked_from, 300.0 - 400.0, 1e-9);
    EXPECT_NEAR(untracked_to, 300.0 + 5.0, 1e-9);

    HandleCommand hold;
    hold.insertion_mm = 300.0;
    ASSERT_TRUE(world.step(hold).ok);
    const long segment = world.tracked_colon_segment(tip);
    ASSERT_GE(segment, 29);  // the segment [290, 300] or [300, 310] mm
    ASSERT_LE(segment, 30);
    const auto [from, to] = world.centerline_search_window_mm(tip, 400.0);
    EXPECT_NEAR(from, 10.0 * static_cast<double>(segment - 4), 1e-9);  // 3 + 1 segments back
    EXPECT_NEAR(to, 10.0 * static_cast<double>(segment + 5), 1e-9);    // and ahead (its end)
    const TruthReader reader(world, station_layout(world, 4, 50.0), Eigen::Vector3d::Zero());
    EXPECT_NEAR(reader.read(world).tip_path_mm, 300.0, 1e-6);
}

TEST(TruthReader, AScopeShorterThanTheStationsSpanHasTheStationsThatFit) {
    // 300 mm of scope in 30 elements: stations 0..6 (0 to 300 mm from the tip) fit, 7..11 do not.
    // The reduction's layout refuses such a scope; truth.csv's takes the stations that fit.
    const World world = straight_world(300.0, 280.0);
    expect_model_error([&] { station_layout(world); }, "stations must fall on scope nodes");
    const StationLayout layout = nearest_station_layout(world);
    EXPECT_EQ(layout.nodes, (std::vector<std::size_t>{30, 25, 20, 15, 10, 5, 0}));
    const TruthReader reader(world, layout, Eigen::Vector3d::Zero());
    const TruthReadout r = reader.read(world);
    ASSERT_EQ(r.stations.size(), 12U);
    for (std::size_t s = 0; s < 12; ++s)
        EXPECT_EQ(r.stations[s].inside, s <= 5) << "station " << s;  // 280 mm inserted
    EXPECT_NEAR(r.tip_path_mm, 280.0, 1e-9);
    StationLayout none;
    none.stations = 0;
    expect_model_error([&] { TruthReader(world, none, Eigen::Vector3d::Zero()); },
                       "at least the tip's station");
}

}  // namespace
}  // namespace scopekin::model::truth
