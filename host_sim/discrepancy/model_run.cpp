#include "host_sim/discrepancy/model_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "host_sim/simulator/world_readout.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::discrepancy {

nlohmann::json default_model() {
  return nlohmann::json::parse(R"({
    "description": "The default model: CF-Q160L in the bundled default colon, as the firmware's reduced model was built from it",
    "colon": {"bundled": "default"},
    "scope": {"model": "cf_q160l", "length_mm": 1700, "elements": 170},
    "gravity_mm_per_s2": [0, 0, -9810],
    "solver": {"time_step_s": 0.01}
  })");
}

std::string ModelPrediction::region_at(double t) const {
  if (step_region.empty()) return "";
  const double x = std::round((t - t0_s) / h_s);
  return step_region[static_cast<std::size_t>(std::clamp(x, 0.0, static_cast<double>(step_region.size() - 1)))];
}

nlohmann::json scenario_for_run(const nlohmann::json& model, const nlohmann::json& extra_effects, const BenchData& data) {
  nlohmann::json doc = model;
  nlohmann::json effects = doc.contains("truth_effects") ? doc["truth_effects"] : nlohmann::json::array();
  for (const auto& e : extra_effects) effects.push_back(e);
  if (effects.empty())
    doc.erase("truth_effects");
  else
    doc["truth_effects"] = effects;
  doc["initial_insertion_mm"] = data.initial_insertion_mm;
  doc["procedure"] = nlohmann::json::array({{{"action", "hold"}, {"start_s", 0.0}, {"end_s", data.duration_s + 1.0}}});
  return doc;
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
      const Eigen::Vector3d axis = r.em[host_sim::kEmTip].orientation * Eigen::Vector3d::UnitX();
      return {std::max(0.0, axis.dot(r.tip_force_N)), 0.0, 0.0};
    }
    case OutputId::handle_force: return {r.handle_force_N, 0.0, 0.0};
    case OutputId::handle_torque: return {r.handle_torque_Nmm, 0.0, 0.0};
  }
  return Eigen::Vector3d::Zero();
}

/// Largest penetration and contact force a step may report before the run counts as unphysical
/// (as model/scenario/simulation.cpp).
constexpr double kMaxPenetration_mm = 1.0;

}  // namespace

namespace {

/// World time 0 is the last multiple of h at or before the first encoder sample (a recording
/// from `scopekin simulate` starts at 0, as its world did).
double world_origin_s(const BenchData& data, double h) { return std::floor(data.start_s / h + 1e-9) * h; }

/// The step at or before recording time t.
std::size_t step_at(double t, double t0, double h) {
  return static_cast<std::size_t>(std::max(0.0, std::floor((t - t0) / h + 1e-9)));
}

/// Steps the world from its step `from` to `to` under the recording's hand motion, reading it
/// after each step into readouts[k - first]. Returns "" or why the run stopped.
std::string run_steps(model::World& world, host_sim::WorldReader& reader, const BenchData& data, double t0, std::size_t from,
                      std::size_t to, std::size_t first, std::vector<host_sim::WorldReadout>& readouts,
                      const std::function<void(std::size_t)>& after_step) {
  const double h = world.time_step_s();
  for (std::size_t k = from + 1; k <= to; ++k) {
    const double t = t0 + static_cast<double>(k) * h;
    model::HandleCommand command;
    command.insertion_mm = data.insertion_at(t);
    command.roll_rad = data.roll_at(t);
    const model::WorldStepReport report = world.step(command);
    if (!report.ok || report.max_penetration_mm > kMaxPenetration_mm)
      return "t = " + std::to_string(t) + " s: " +
             (report.ok ? "the scope penetrates the colon wall by " + std::to_string(report.max_penetration_mm) + " mm"
                        : report.failure);
    readouts[k - first] = reader.read(world);
    if (after_step) after_step(k);
  }
  return "";
}

/// The outputs at the measured samples with time in [from_s, to_s], interpolated between the
/// readouts of steps first .. first + readouts.size() - 1.
void fill_outputs(const BenchData& data, const std::vector<host_sim::WorldReadout>& readouts, double t0, double h,
                  std::size_t first, double from_s, double to_s, ModelPrediction& out) {
  const std::size_t last = first + readouts.size() - 1;
  for (std::size_t o = 0; o < data.outputs.size(); ++o) {
    const MeasuredSeries& m = data.outputs[o];
    for (std::size_t i = 0; i < m.time_s.size(); ++i) {
      const double t = m.time_s[i];
      if (t < from_s || t > to_s) continue;
      const double x = std::clamp((t - t0) / h, static_cast<double>(first), static_cast<double>(last));
      const auto k = std::min(static_cast<std::size_t>(x), last > first ? last - 1 : first);
      const double w = x - static_cast<double>(k);
      const host_sim::WorldReadout r =
          host_sim::blend(readouts[k - first], readouts[std::min(k + 1, last) - first], w);
      out.outputs[o][i] = output_of(r, m.id);
    }
  }
}

void size_outputs(const BenchData& data, ModelPrediction& out) {
  out.outputs.resize(data.outputs.size());
  for (std::size_t o = 0; o < data.outputs.size(); ++o)
    out.outputs[o].assign(data.outputs[o].time_s.size(),
                          Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
}

}  // namespace

ModelPrediction predict(const nlohmann::json& model, const std::string& model_source, const nlohmann::json& extra_effects,
                        const BenchData& data, const std::function<void(double)>& progress,
                        const std::vector<RunWindow>* windows, std::vector<model::World::State>* window_states) {
  const model::Scenario scenario = model::read_scenario(scenario_for_run(model, extra_effects, data), model_source);
  std::unique_ptr<model::World> world = model::build_world(scenario);
  host_sim::WorldReader reader(*world);
  const double h = world->time_step_s();
  const double t0 = world_origin_s(data, h);
  const auto steps = static_cast<std::size_t>(std::ceil((data.end_s - t0) / h - 1e-9));
  // Where to save states: window w's start step (sorted by step, windows come in time order).
  std::vector<std::size_t> save_steps;
  if (windows != nullptr && window_states != nullptr) {
    window_states->assign(windows->size(), model::World::State{});
    for (const RunWindow& w : *windows) save_steps.push_back(step_at(w.start_s, t0, h));
    for (std::size_t w = 0; w < save_steps.size(); ++w)
      if (save_steps[w] == 0) (*window_states)[w] = world->state();
  }
  std::vector<host_sim::WorldReadout> readouts(steps + 1);
  readouts[0] = reader.read(*world);
  ModelPrediction out;
  out.failure = run_steps(*world, reader, data, t0, 0, steps, 0, readouts, [&](std::size_t k) {
    for (std::size_t w = 0; w < save_steps.size(); ++w)
      if (save_steps[w] == k) (*window_states)[w] = world->state();
    if (progress && k % 200 == 0) progress(static_cast<double>(k) / static_cast<double>(steps));
  });
  if (!out.failure.empty()) return out;
  out.steps = steps;
  out.t0_s = t0;
  out.h_s = h;
  out.step_region.reserve(readouts.size());
  for (const host_sim::WorldReadout& r : readouts) out.step_region.push_back(r.tip_region);
  size_outputs(data, out);
  fill_outputs(data, readouts, t0, h, 0, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
               out);
  out.ok = true;
  return out;
}

ModelPrediction predict_windows(const nlohmann::json& model, const std::string& model_source,
                                const nlohmann::json& extra_effects, const BenchData& data,
                                const std::vector<RunWindow>& windows, const std::vector<model::World::State>& states,
                                const std::vector<std::size_t>& which) {
  const model::Scenario scenario = model::read_scenario(scenario_for_run(model, extra_effects, data), model_source);
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
    out.failure = run_steps(*world, reader, data, t0, from, to, from, readouts, {});
    if (!out.failure.empty()) return out;
    out.steps += to - from;
    fill_outputs(data, readouts, t0, h, from, window.score_from_s, window.end_s, out);
  }
  out.ok = true;
  return out;
}

}  // namespace scopekin::discrepancy
