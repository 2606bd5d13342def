#include "host_sim/discrepancy/model_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "host_sim/simulator/world_readout.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::discrepancy {

std::string ModelPrediction::region_at(double t) const {
    if (step_region.empty()) return "";
    const double x = std::round((t - t0_s) / h_s);
    return step_region[static_cast<std::size_t>(
        std::clamp(x, 0.0, static_cast<double>(step_region.size() - 1)))];
}

namespace {

Eigen::Vector3d output_of(const host_sim::WorldReadout& r, OutputId id) {
    switch (id) {
        case OutputId::tip_position: return r.em[host_sim::kEmTip].position_mm;
        case OutputId::p20_position: return r.em[host_sim::kEm20cm].position_mm;
        case OutputId::sigmoid_position: return r.em[host_sim::kEmSigmoid].position_mm;
        case OutputId::tip_force: {
            // Along the tip's axis, as the single-axis tip force sensor's z, which reads compression
            // only (host_sim/sensors/SENSORS.md): never below 0.
            const Eigen::Vector3d axis =
                r.em[host_sim::kEmTip].orientation * Eigen::Vector3d::UnitX();
            return {std::max(0.0, axis.dot(r.tip_force_N)), 0.0, 0.0};
        }
        case OutputId::handle_force: return {r.handle_force_N, 0.0, 0.0};
        case OutputId::handle_torque: return {r.handle_torque_Nmm, 0.0, 0.0};
    }
    return Eigen::Vector3d::Zero();
}

}  // namespace

double world_origin_s(const MeasuredRecording& data, double h) {
    return std::floor(data.start_s / h + 1e-9) * h;
}

model::HandleCommand RecordingDrive::command_for_step(std::size_t step, double /*t_s*/, double h_s,
                                                      double /*depth_now_mm*/,
                                                      double /*roll_now_rad*/) {
    // From the step's index, not the world's clock: a restored window continues on the same grid.
    const double t = t0_s_ + static_cast<double>(step) * h_s;
    model::HandleCommand command;
    command.insertion_mm = data_.insertion_at(t);
    command.roll_rad = data_.roll_at(t);
    return command;
}

namespace {

/// The step at or before recording time t.
std::size_t step_at(double t, double t0, double h) {
    return static_cast<std::size_t>(std::max(0.0, std::floor((t - t0) / h + 1e-9)));
}

/// Steps the world from its step `from` to `to` under the recording's hand motion
/// (model::run_simulation), reading it after each step into readouts[k - from]. Returns "" or
/// why the run stopped.
std::string run_steps(model::World& world, const model::Scenario& scenario,
                      host_sim::WorldReader& reader, const MeasuredRecording& data, double t0,
                      std::size_t from, std::size_t to,
                      std::vector<host_sim::WorldReadout>& readouts,
                      const std::function<void(std::size_t)>& after_step) {
    const double h = world.time_step_s();
    RecordingDrive drive(data, t0);
    std::size_t k = from;
    model::SimulationCallbacks callbacks;
    callbacks.on_step = [&](const model::World& w, const model::WorldStepReport&) {
        ++k;
        readouts[k - from] = reader.read(w);
        if (after_step) after_step(k);
    };
    const model::SimulationSummary summary = model::run_simulation(
        world, scenario, drive, {from, to, static_cast<double>(to) * h}, callbacks);
    if (summary.complete) return "";
    // The loop's times are world times.
    return t0 == 0.0 ? summary.message
                     : summary.message + " (world time; the recording's is " + std::to_string(t0) +
                           " s later)";
}

/// The outputs at the measured samples with time in [from_s, to_s], interpolated between the
/// readouts of steps first .. first + readouts.size() - 1.
void fill_outputs(const MeasuredRecording& data,
                  const std::vector<host_sim::WorldReadout>& readouts, double t0, double h,
                  std::size_t first, double from_s, double to_s, ModelPrediction& out) {
    const std::size_t last = first + readouts.size() - 1;
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        const MeasuredSeries& m = data.outputs[o];
        for (std::size_t i = 0; i < m.time_s.size(); ++i) {
            const double t = m.time_s[i];
            if (t < from_s || t > to_s) continue;
            const double x =
                std::clamp((t - t0) / h, static_cast<double>(first), static_cast<double>(last));
            const auto k = std::min(static_cast<std::size_t>(x), last > first ? last - 1 : first);
            const double w = x - static_cast<double>(k);
            const host_sim::WorldReadout r =
                host_sim::blend(readouts[k - first], readouts[std::min(k + 1, last) - first], w);
            out.outputs[o][i] = output_of(r, m.id);
        }
    }
}

void size_outputs(const MeasuredRecording& data, ModelPrediction& out) {
    out.outputs.resize(data.outputs.size());
    for (std::size_t o = 0; o < data.outputs.size(); ++o)
        out.outputs[o].assign(data.outputs[o].time_s.size(),
                              Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
}

}  // namespace

ModelPrediction predict(const ModelSpec& model, const nlohmann::json& extra_effects,
                        const MeasuredRecording& data, const std::function<void(double)>& progress,
                        const std::vector<RunWindow>* windows,
                        std::vector<model::World::State>* window_states) {
    const model::Scenario scenario =
        scenario_for_run(model, extra_effects, data.initial_insertion_mm);
    std::unique_ptr<model::World> world = model::build_world(scenario);
    host_sim::WorldReader reader(*world);
    const double h = world->time_step_s();
    const double t0 = world_origin_s(data, h);
    const auto steps = static_cast<std::size_t>(std::ceil((data.end_s - t0) / h - 1e-9));
    // Where to save states: window w's start step (sorted by step, windows come in time order).
    std::vector<std::size_t> save_steps;
    if (windows != nullptr && window_states != nullptr) {
        window_states->assign(windows->size(), model::World::State{});
        for (const RunWindow& w : *windows)
            save_steps.push_back(step_at(w.start_s, t0, h));
        for (std::size_t w = 0; w < save_steps.size(); ++w)
            if (save_steps[w] == 0) (*window_states)[w] = world->state();
    }
    std::vector<host_sim::WorldReadout> readouts(steps + 1);
    readouts[0] = reader.read(*world);
    ModelPrediction out;
    out.failure =
        run_steps(*world, scenario, reader, data, t0, 0, steps, readouts, [&](std::size_t k) {
            for (std::size_t w = 0; w < save_steps.size(); ++w)
                if (save_steps[w] == k) (*window_states)[w] = world->state();
            if (progress && k % 200 == 0)
                progress(static_cast<double>(k) / static_cast<double>(steps));
        });
    if (!out.failure.empty()) return out;
    out.steps = steps;
    out.t0_s = t0;
    out.h_s = h;
    out.step_region.reserve(readouts.size());
    for (const host_sim::WorldReadout& r : readouts)
        out.step_region.push_back(r.tip_region);
    size_outputs(data, out);
    fill_outputs(data, readouts, t0, h, 0, -std::numeric_limits<double>::infinity(),
                 std::numeric_limits<double>::infinity(), out);
    out.ok = true;
    return out;
}

ModelPrediction predict_windows(const ModelSpec& model, const nlohmann::json& extra_effects,
                                const MeasuredRecording& data,
                                const std::vector<RunWindow>& windows,
                                const std::vector<model::World::State>& states,
                                const std::vector<std::size_t>& which) {
    const model::Scenario scenario =
        scenario_for_run(model, extra_effects, data.initial_insertion_mm);
    std::unique_ptr<model::World> world = model::build_world(scenario);
    const double h = world->time_step_s();
    const double t0 = world_origin_s(data, h);
    ModelPrediction out;
    out.t0_s = t0;
    out.h_s = h;
    size_outputs(data, out);
    for (std::size_t w : which) {
        const RunWindow& window = windows.at(w);
        const std::size_t from = step_at(window.start_s, t0, h);
        const auto to = static_cast<std::size_t>(std::ceil((window.end_s - t0) / h - 1e-9));
        world->restore(states.at(w));
        host_sim::WorldReader reader(*world);
        std::vector<host_sim::WorldReadout> readouts(to - from + 1);
        readouts[0] = reader.read(*world);
        out.failure = run_steps(*world, scenario, reader, data, t0, from, to, readouts, {});
        if (!out.failure.empty()) return out;
        out.steps += to - from;
        fill_outputs(data, readouts, t0, h, from, window.score_from_s, window.end_s, out);
    }
    out.ok = true;
    return out;
}

}  // namespace scopekin::discrepancy
