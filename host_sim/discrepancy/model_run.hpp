#pragma once
// Runs a model under a recording's hand motion and reads it where the recording measured:
// the model (a scenario document without the procedure, README "Discrepancy workflow") plus
// candidate effects, its scope started at the recording's first insertion and then driven,
// step by step, to the encoder's insertion and roll (linear between samples, position control as
// the bench's hand). The outputs are read after every step as the host simulator's sensors read
// them (host_sim/simulator/world_readout.hpp) and interpolated to each measured sample's time.
// A run may also cover only some windows of the recording, restarted from saved states
// (fit_windows.hpp).
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/bench_data.hpp"
#include "host_sim/discrepancy/fit_windows.hpp"
#include "model/world/world.hpp"

namespace scopekin::discrepancy {

struct ModelPrediction {
  bool ok = false;
  std::string failure;                               ///< why the run stopped early (ok = false)
  /// Per BenchData::outputs entry, one value per measured sample (same layout).
  std::vector<std::vector<Eigen::Vector3d>> outputs;
  /// The model tip's region after each step (index 0 = the start; "" outside the colon).
  std::vector<std::string> step_region;
  double t0_s = 0;   ///< recording time of world time 0
  double h_s = 0.01;
  std::size_t steps = 0;
  /// The model tip's region at recording time t.
  std::string region_at(double time_s) const;
};

/// The model document completed for a run: `model` (colon, scope, solver, ... and its own
/// truth_effects) with `extra_effects` appended to truth_effects, the initial insertion and a
/// hold over the recording's span. Throws model::ModelError for a bad model or effect.
nlohmann::json scenario_for_run(const nlohmann::json& model, const nlohmann::json& extra_effects, const BenchData& data);

/// Runs it. `progress` (may be empty) gets the fraction done now and then. `windows` (may be
/// null): the world's state at each window's start is saved into `window_states`. Throws
/// model::ModelError for a bad model; a run that fails part-way returns ok = false.
ModelPrediction predict(const nlohmann::json& model, const std::string& model_source, const nlohmann::json& extra_effects,
                        const BenchData& data, const std::function<void(double)>& progress = {},
                        const std::vector<RunWindow>* windows = nullptr,
                        std::vector<model::World::State>* window_states = nullptr);

/// Runs only the windows `which` (indices into `windows`), each restarted from its saved state
/// (fit_windows.hpp). Outputs are NaN outside the windows' scored spans; step_region is empty.
ModelPrediction predict_windows(const nlohmann::json& model, const std::string& model_source,
                                const nlohmann::json& extra_effects, const BenchData& data,
                                const std::vector<RunWindow>& windows, const std::vector<model::World::State>& states,
                                const std::vector<std::size_t>& which);

/// The default model: the bundled default colon and the CF-Q160L as the firmware's model has
/// them (h = 10 ms), no truth effects.
nlohmann::json default_model();

}  // namespace scopekin::discrepancy
