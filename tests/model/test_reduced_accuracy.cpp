// The firmware's reduced model against the full-order reference model (tip and station force
// RMS) and the self-lock alarm against the reference's own self-lock onset, on the three
// reference scenarios of model/scenarios/reference_*.json, and on one held-out procedure
// (heldout_fast_advance.json) that is not a training run.
//
// The double tables are the build's (generated/reduced_model_double.json, written by the same
// generator run as the firmware's tables), so no test repeats the training runs.
// Each scenario is run once in the full-order world (solver step 5 ms = the firmware period);
// at every step the world's insertion depth and handle force drive
//   * the firmware itself (kinetics::step, Q16.16, the generated default tables), and
//   * the same reduced model in double (reduced_step<double> on the double tables that
//     build_reduced_model makes from the same training runs, the same solver settings).
// Compared at every step:
//   tip       the tip's position along the colon centerline [mm];
//   force     per active station, the Euclidean norm of the difference of the station force
//             vectors (n, t, s) [N] — the full-order side is the resultant of its wall forces
//             over the station's stretch (model::station_forces).
// Both full-order sides, and the reference loop onset the alarm is judged against, come from the
// ground truth's shared definitions (model/truth/: TruthReader, loop_onset_s), the code that
// writes truth.csv.
// The figures go to reduced_accuracy_<scenario>.json in the build directory (firmware/README.md,
// "Firmware accuracy").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "model/reduction/reduced_model.hpp"
#include "model/reduction/reduced_model_json.hpp"
#include "model/reduction/reduced_table_writer.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"
#include "model/truth/truth_definitions.hpp"
#include "model/truth/truth_readout.hpp"

namespace {

using namespace scopekin;
using fixed_point::Q16_16;

/// The tables' own conversion (rounded to nearest; refuses values outside Q16.16).
Q16_16 q16(double x) {
    return Q16_16::from_raw(model::q16_raw(x, "reference input"));
}
double real(Q16_16 x) {
    return static_cast<double>(x.raw()) / 65536.0;
}

struct Sample {
    double t_s = 0;
    double depth_mm = 0;
    double full_tip_mm = 0;
    double fixed_tip_mm = 0;
};

struct Rms {
    double sum = 0;
    double max = 0;
    std::size_t n = 0;
    void add(double e) {
        sum += e * e;
        max = std::max(max, std::fabs(e));
        ++n;
    }
    double value() const { return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0; }
};

struct ReferenceRun {
    Rms tip_fixed_vs_full, force_fixed_vs_full, normal_fixed_vs_full;
    Rms tip_fixed_vs_double, force_fixed_vs_double;
    Rms published_tip_vs_full;    ///< the published tip (the model's while the evidence trusts it)
    std::vector<Sample> samples;  // every step
    std::vector<double> alarm_rises_s;
    double period_s = 0.005;
};

/// The reduced model in double from the same training runs: the build's own (it runs them once
/// for the firmware's tables, model/reduction/reduced_model_json.hpp), or, in a build that takes
/// the committed tables instead, run here (about a minute).
const model::ReducedModelData& double_tables() {
    static const model::ReducedModelData data = [] {
        const model::ReductionSettings spec = model::read_reduction_spec(
            std::string(SCOPEKIN_SOURCE_DIR) + "/model/reduction/training.json");
#ifdef SCOPEKIN_REDUCED_MODEL_DOUBLE
        return model::read_reduced_model_json(SCOPEKIN_REDUCED_MODEL_DOUBLE, spec);
#else
        return model::build_reduced_model(spec);
#endif
    }();
    return data;
}

const ReferenceRun& run(const std::string& name) {
    static std::map<std::string, ReferenceRun> cache;
    if (auto it = cache.find(name); it != cache.end()) return it->second;
    ReferenceRun& r = cache[name];
    const model::Scenario scenario = model::read_scenario_file(
        std::string(SCOPEKIN_SOURCE_DIR) + "/model/scenarios/" + name + ".json");
    std::unique_ptr<model::World> world = model::build_world(scenario);
    model::ProcedurePlayer player(scenario.procedure, scenario.settings.initial_insertion_mm,
                                  scenario.scope.length_mm);
    const model::truth::TruthReader truth(
        *world,
        model::truth::station_layout(*world, double_tables().settings.stations,
                                     double_tables().settings.station_spacing_mm),
        scenario.settings.gravity_mm_per_s2);

    static kinetics::State firmware;  // static: large
    kinetics::init(kinetics::default_config(), firmware);
    static kinetics::ReducedState<double, kinetics::kStationCapacity> reduced_double;
    reduced_double = {};
    contact::GaussSeidelSettings<double> gs;
    gs.mode = contact::SweepMode::fixed;
    gs.max_sweeps = firmware.config.contact_sweeps;
    gs.local_iterations = firmware.config.contact_local_iterations;
    const double h = world->time_step_s();
    r.period_s = h;
    EXPECT_NEAR(h, real(firmware.config.period_s), 1e-4)
        << "the reference must step at the firmware period";

    bool alarm = false;
    while (world->time_s() < scenario.procedure.end_s() - 1e-9) {
        const model::HandleCommand command =
            player.command(world->time_s(), h, world->insertion_depth_mm(), world->roll_rad());
        const model::WorldStepReport report = world->step(command);
        if (!report.ok) {
            ADD_FAILURE() << name << ": the reference run failed: " << report.failure;
            break;
        }
        kinetics::Inputs in;
        in.insertion_mm = q16(world->insertion_depth_mm());
        in.handle_force_N = q16(world->handle_force_N());
        in.handle_torque_Nmm = q16(world->handle_torque_Nmm());
        in.roll_rad = q16(world->roll_rad());
        in.fresh_mask = kinetics::kAllInputSignals;
        kinetics::Outputs out;
        kinetics::step(in, firmware, out);
        (void)kinetics::reduced_step(double_tables(), real(firmware.insertion_mm),
                                     real(firmware.config.period_s), reduced_double, gs);

        if (out.self_lock_alarm && !alarm) r.alarm_rises_s.push_back(world->time_s());
        alarm = out.self_lock_alarm;
        // The reduced model's own tip (the published tip is the model's only while the handle's
        // evidence trusts it, else the slack regressor's: kinetics.hpp).
        r.tip_fixed_vs_double.add(real(out.model_tip_path_mm) - reduced_double.tip_path_mm);
        for (std::size_t j = 0; j < out.active_stations; ++j) {
            const auto& fd = reduced_double.force_N[j];
            const auto& ff = firmware.model.force_N[j];
            r.force_fixed_vs_double.add(
                std::hypot(real(ff[0]) - fd[0], real(ff[1]) - fd[1], real(ff[2]) - fd[2]));
        }
        const model::truth::TruthReadout full = truth.read(*world);
        const double full_tip = full.tip_path_mm;
        r.samples.push_back(
            {world->time_s(), world->insertion_depth_mm(), full_tip, real(out.model_tip_path_mm)});
        r.tip_fixed_vs_full.add(real(out.model_tip_path_mm) - full_tip);
        r.published_tip_vs_full.add(real(out.tip_path_mm) - full_tip);
        for (std::size_t j = 0; j < out.active_stations; ++j) {
            const auto& ff = firmware.model.force_N[j];
            const Eigen::Vector3d fixed(real(ff[0]), real(ff[1]), real(ff[2]));
            r.force_fixed_vs_full.add((fixed - full.stations[j].force_N).norm());
            r.normal_fixed_vs_full.add(fixed(0) - full.stations[j].force_N(0));
        }
    }
    return r;
}

/// The reference's self-lock onset [s]: the onset of the first loop episode of the full-order
/// run (model/truth/README.md, "Loop episodes"); < 0 if none.
/// How long before the reference's loop onset a self-lock alarm may rise (see Section 3 below).
constexpr double kEarlyWarning_s = 1.0;

double reference_onset_s(const ReferenceRun& r) {
    model::truth::RunSeries series;
    for (const Sample& s : r.samples) {
        series.time_s.push_back(s.t_s);
        series.insertion_mm.push_back(s.depth_mm);
        series.tip_path_mm.push_back(s.full_tip_mm);
    }
    return model::truth::loop_onset_s(series).value_or(-1.0);
}

void record(const std::string& name, const ReferenceRun& r) {
    nlohmann::json all = nlohmann::json::object();
    const double onset = reference_onset_s(r);
    std::vector<double> early;  // raised more than 0.25 s before the onset (or with no loop)
    for (double t : r.alarm_rises_s)
        if (onset < 0 || t < onset - kEarlyWarning_s) early.push_back(t);
    all[name] = {{"tip_rms_mm_fixed_vs_full", r.tip_fixed_vs_full.value()},
                 {"tip_max_mm_fixed_vs_full", r.tip_fixed_vs_full.max},
                 {"force_rms_N_fixed_vs_full", r.force_fixed_vs_full.value()},
                 {"normal_force_rms_N_fixed_vs_full", r.normal_fixed_vs_full.value()},
                 {"tip_rms_mm_fixed_vs_double", r.tip_fixed_vs_double.value()},
                 {"tip_max_mm_fixed_vs_double", r.tip_fixed_vs_double.max},
                 {"published_tip_rms_mm_vs_full", r.published_tip_vs_full.value()},
                 {"published_tip_max_mm_vs_full", r.published_tip_vs_full.max},
                 {"force_rms_N_fixed_vs_double", r.force_fixed_vs_double.value()},
                 {"force_max_N_fixed_vs_double", r.force_fixed_vs_double.max},
                 {"reference_self_lock_onset_s",
                  onset < 0 ? nlohmann::json(nullptr) : nlohmann::json(onset)},
                 {"self_lock_alarm_rises_s", r.alarm_rises_s},
                 {"self_lock_alarm_rises_before_onset_s", early}};
    std::ofstream(std::string(SCOPEKIN_BINARY_DIR) + "/reduced_accuracy_" + name + ".json")
        << all.dump(2) << "\n";
    std::cout << "[ accuracy ] " << name << ": " << all[name].dump() << "\n";
}

class ReducedAccuracy : public ::testing::TestWithParam<const char*> {};

TEST_P(ReducedAccuracy, AgainstTheReducedModelInDoubleAndTheFullOrderModel) {
    const ReferenceRun& r = run(GetParam());
    record(GetParam(), r);
    // The firmware's Q16.16 against the same reduced model in double (bounds 0.05 mm / 0.01 N),
    // RMS over the run (and the stations) as below; the maxima are recorded (firmware/README.md).
    EXPECT_LE(r.tip_fixed_vs_double.value(), 0.05) << "tip RMS [mm]";
    EXPECT_LE(r.force_fixed_vs_double.value(), 0.01) << "station force RMS [N]";
    // Against the full-order model (bounds 3 mm / 0.2 N).
    EXPECT_LE(r.tip_fixed_vs_full.value(), 3.0) << "tip RMS [mm] vs the full-order model";
    EXPECT_LE(r.force_fixed_vs_full.value(), 0.2)
        << "station force RMS [N] vs the full-order model";
    // The published tip: on its training patient the handle force is the training's, the model
    // evidence trusts the model, and the box publishes the model's tip (model_evidence.hpp;
    // bound 1 mm RMS, the estimator issue's for training-like cases).
    EXPECT_LE(r.published_tip_vs_full.value(), 1.0) << "published tip RMS [mm] vs full-order";
}

// Generalisation: a procedure the tables were not trained on (25 mm/s instead of 20 mm/s). Not
// held to the bounds above; these bounds only keep the measured figures (firmware/README.md,
// "Firmware accuracy": tip RMS 2.6 mm, station force RMS 0.36 N) from getting worse.
TEST(ReducedAccuracyHeldOut, FasterAdvanceThanTrained) {
    const ReferenceRun& r = run("heldout_fast_advance");
    record("heldout_fast_advance", r);
    EXPECT_LE(r.tip_fixed_vs_full.value(), 3.5) << "tip RMS [mm] vs the full-order model";
    EXPECT_LE(r.force_fixed_vs_full.value(), 0.5)
        << "station force RMS [N] vs the full-order model";
    EXPECT_LE(r.published_tip_vs_full.value(), 1.0) << "published tip RMS [mm] vs full-order";
}

// Section 3: no self-lock alarm where no loop forms, and where one forms an alarm comes at most
// 0.25 s after the reference's onset and at most kEarlyWarning_s (1 s) before it. The onset is the
// first loop episode's (model/truth/README.md), dated to where the tip locked dead; with static
// friction the tip first stalls and creeps (reference_sigmoid_loop: stalls at 15.7 s, creeps
// 10 mm, locks at 16.9 s), and an alarm in that stall saw the loop coming. The window is the
// scorecard's (host_sim/evaluate/README.md, "Alarms against episodes"). Alarms raised earlier came
// at stalls that took up less than the episode threshold (false alarms by that definition,
// recorded in reduced_accuracy_<scenario>.json as self_lock_alarm_rises_before_onset_s).
TEST(SelfLockAlarm, NeverFiresOnTheStraightAdvance) {
    const ReferenceRun& r = run("reference_straight_advance");
    EXPECT_LT(reference_onset_s(r), 0.0)
        << "the reference itself locks: the scenario is not loop-free";
    EXPECT_TRUE(r.alarm_rises_s.empty());
}

class SelfLockAlarmOnLoops : public ::testing::TestWithParam<const char*> {};

TEST_P(SelfLockAlarmOnLoops, FiresWithinAQuarterSecondOfTheReferenceOnset) {
    const ReferenceRun& r = run(GetParam());
    const double onset = reference_onset_s(r);
    ASSERT_GE(onset, 0.0) << "no loop forms in the reference";
    ASSERT_FALSE(r.alarm_rises_s.empty()) << "the alarm never fired";
    const auto rise = std::find_if(r.alarm_rises_s.begin(), r.alarm_rises_s.end(),
                                   [&](double t) { return t >= onset - kEarlyWarning_s; });
    ASSERT_NE(rise, r.alarm_rises_s.end()) << "no alarm from the reference onset " << onset << " s";
    EXPECT_LE(*rise, onset + 0.25) << "reference onset " << onset << " s";
}

INSTANTIATE_TEST_SUITE_P(LoopScenarios, SelfLockAlarmOnLoops,
                         ::testing::Values("reference_sigmoid_loop", "reference_withdraw_torque"));

INSTANTIATE_TEST_SUITE_P(ReferenceScenarios, ReducedAccuracy,
                         ::testing::Values("reference_straight_advance", "reference_sigmoid_loop",
                                           "reference_withdraw_torque"));

}  // namespace
