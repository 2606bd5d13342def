#pragma once
// Runs a model under a recording's hand motion and reads it where the recording measured:
// the model (model_spec.hpp) plus candidate effects, its scope started at the recording's first
// insertion and then driven, step by step, to the encoder's insertion and roll (linear between
// samples, position control as the bench's hand: RecordingDrive, stepped by the same loop as a
// scenario's procedure, model::run_simulation). The outputs are read after every step as the
// host simulator's sensors read them (host_sim/simulator/world_readout.hpp) and interpolated to
// each measured sample's time. A run may also cover only some windows of the recording,
// restarted from saved states (fit_windows.hpp).
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/fit_windows.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_spec.hpp"
#include "model/scenario/hand_command_source.hpp"
#include "model/world/world.hpp"

namespace scopekin::discrepancy {

struct ModelPrediction {
    bool ok = false;
    std::string failure;  ///< why the run stopped early (ok = false)
    /// Per MeasuredRecording::outputs entry, one value per measured sample (same layout).
    std::vector<std::vector<Eigen::Vector3d>> outputs;
    /// The model tip's region after each step (index 0 = the start; "" outside the colon).
    std::vector<std::string> step_region;
    double t0_s = 0;  ///< recording time of world time 0
    double h_s = 0.01;
    std::size_t steps = 0;
    /// The model tip's region at recording time t.
    std::string region_at(double time_s) const;
};

/// The recording's encoder as the hand: step k goes to the insertion and roll read at recording
/// time t0_s + k h (world time 0 is recording time t0_s).
class RecordingDrive final : public model::HandCommandSource {
public:
    RecordingDrive(const MeasuredRecording& data, double t0_s) : data_(data), t0_s_(t0_s) {}
    model::HandleCommand command_for_step(std::size_t step, double t_s, double h_s,
                                          double depth_now_mm, double roll_now_rad) override;

private:
    const MeasuredRecording& data_;
    double t0_s_;
};

/// World time 0 in recording time: the last multiple of h at or before the first encoder sample
/// (a recording from `scopekin simulate` starts at 0, as its world did).
double world_origin_s(const MeasuredRecording& data, double h_s);

/// Runs the model with `extra_effects` (truth_effects entries) under the recording. `progress`
/// (may be empty) gets the fraction done now and then. `windows` (may be null): the world's state
/// at each window's start is saved into `window_states`. Throws model::ModelError for a bad
/// effect; a run that fails part-way (a failed or unphysical step, judged as for any scenario by
/// model::run_simulation) returns ok = false.
ModelPrediction predict(const ModelSpec& model, const nlohmann::json& extra_effects,
                        const MeasuredRecording& data,
                        const std::function<void(double)>& progress = {},
                        const std::vector<RunWindow>* windows = nullptr,
                        std::vector<model::World::State>* window_states = nullptr);

/// Runs only the windows `which` (indices into `windows`), each restarted from its saved state
/// (fit_windows.hpp). Outputs are NaN outside the windows' scored spans; step_region is empty.
ModelPrediction predict_windows(const ModelSpec& model, const nlohmann::json& extra_effects,
                                const MeasuredRecording& data,
                                const std::vector<RunWindow>& windows,
                                const std::vector<model::World::State>& states,
                                const std::vector<std::size_t>& which);

}  // namespace scopekin::discrepancy
