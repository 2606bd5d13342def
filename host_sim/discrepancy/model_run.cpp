#include "host_sim/discrepancy/model_run.hpp"

#include <algorithm>
#include <cmath>

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

ModelPrediction predict(const nlohmann::json& model, const std::string& model_source, const nlohmann::json& extra_effects,
                        const BenchData& data, const std::function<void(double)>& progress) {
  const model::Scenario scenario = model::read_scenario(scenario_for_run(model, extra_effects, data), model_source);
  std::unique_ptr<model::World> world = model::build_world(scenario);
  host_sim::WorldReader reader(*world);
  const double h = world->time_step_s();
  // World time 0 is the last multiple of h at or before the first encoder sample (a recording
  // from `scopekin simulate` starts at 0, as its world did).
  const double t0 = std::floor(data.start_s / h + 1e-9) * h;
  const auto steps = static_cast<std::size_t>(std::ceil((data.end_s - t0) / h - 1e-9));
  std::vector<host_sim::WorldReadout> readouts;
  readouts.reserve(steps + 1);
  readouts.push_back(reader.read(*world));
  ModelPrediction out;
  for (std::size_t k = 1; k <= steps; ++k) {
    const double t = t0 + static_cast<double>(k) * h;
    model::HandleCommand command;
    command.insertion_mm = data.insertion_at(t);
    command.roll_rad = data.roll_at(t);
    const model::WorldStepReport report = world->step(command);
    if (!report.ok || report.max_penetration_mm > kMaxPenetration_mm) {
      out.failure = "t = " + std::to_string(t) + " s: " +
                    (report.ok ? "the scope penetrates the colon wall by " + std::to_string(report.max_penetration_mm) + " mm"
                               : report.failure);
      return out;
    }
    readouts.push_back(reader.read(*world));
    if (progress && k % 200 == 0) progress(static_cast<double>(k) / static_cast<double>(steps));
  }
  out.steps = steps;
  out.t0_s = t0;
  out.h_s = h;
  out.step_region.reserve(readouts.size());
  for (const host_sim::WorldReadout& r : readouts) out.step_region.push_back(r.tip_region);
  out.outputs.resize(data.outputs.size());
  for (std::size_t o = 0; o < data.outputs.size(); ++o) {
    const MeasuredSeries& m = data.outputs[o];
    out.outputs[o].reserve(m.time_s.size());
    for (double t : m.time_s) {
      const double x = std::clamp((t - t0) / h, 0.0, static_cast<double>(steps));
      const auto i = std::min(static_cast<std::size_t>(x), steps > 0 ? steps - 1 : 0);
      const double w = x - static_cast<double>(i);
      const host_sim::WorldReadout r = host_sim::blend(readouts[i], readouts[std::min(i + 1, steps)], w);
      out.outputs[o].push_back(output_of(r, m.id));
    }
  }
  out.ok = true;
  return out;
}

}  // namespace scopekin::discrepancy
