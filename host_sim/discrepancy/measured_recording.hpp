#pragma once
// What the discrepancy workflow takes from a recording (host_sim/recording/RECORDING.md): the
// hand's motion that drives the model (the insertion/roll encoder) and the measured outputs it is
// compared with (EM positions of the tip, the 20 cm point and the sigmoid; the tip contact force
// along the tip's axis; the handle's force and torque). Checked before anything runs: a
// recording that cannot drive the model, whose units look wrong, that is too short to hold data
// out, or that has no output, is refused with a message that says what is needed.
#include <Eigen/Dense>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "host_sim/recording/recording_reader.hpp"

namespace scopekin::discrepancy {

/// A recording the workflow cannot use; the message says what is needed.
class DiscrepancyInputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The measured outputs, in report order.
enum class OutputId {
    tip_position,
    p20_position,
    sigmoid_position,
    tip_force,
    handle_force,
    handle_torque
};
inline constexpr std::size_t kOutputCount = 6;

/// Report name ("tip_position_mm", ...) and unit of an output.
const char* output_name(OutputId id);
const char* output_unit(OutputId id);

struct DriveSample {
    double time_s = 0;  ///< the recording's time
    double insertion_mm = 0;
    double roll_rad = 0;  ///< relative to the first sample
};

/// One measured output: samples at their times (recording time, within the drive's span) (3 components; scalars use x only).
struct MeasuredSeries {
    OutputId id = OutputId::tip_position;
    int components = 3;
    std::vector<double> time_s;
    std::vector<Eigen::Vector3d> value;
    /// A scalar output thinned from a faster sensor (the handle's 1 kHz to every 33 ms): every
    /// sample it delivered, from which its noise is estimated (estimate_noise); else empty.
    std::vector<double> full_rate;
};

/// Any recording's drive and measured outputs: a bench's, a patient's or one `scopekin simulate`
/// wrote.
struct MeasuredRecording {
    std::string source;
    std::vector<DriveSample> drive;       ///< every encoder sample
    std::vector<MeasuredSeries> outputs;  ///< only outputs the recording has (>= 20 samples)
    std::vector<double> region_time_s;    ///< where the recording labels the tip's region
    std::vector<std::string> region;
    double start_s = 0;     ///< the first encoder sample [s, recording time]
    double end_s = 0;       ///< the last one
    double duration_s = 0;  ///< end_s - start_s
    double initial_insertion_mm = 0;
    /// The spans the fits score (the windows' scored parts, fit_windows.hpp); empty = all of it.
    std::vector<std::pair<double, double>> fit_spans_s;
    /// The tip's region at t ("" = the recording does not say).
    std::string region_at(double time_s) const;
    /// Insertion [mm] and its rate [mm/s], roll rate [rad/s] at t (linear between samples).
    double insertion_at(double time_s) const;
    double roll_at(double time_s) const;
};

/// Shortest recording accepted [s]: the held-out blocks need room (host_sim/discrepancy/README.md).
inline constexpr double kMinDuration_s = 12.0;

/// Extracts and checks. Samples of outputs sampled at 1 kHz (handle) are thinned to the EM
/// tracker's rate (every 33 ms) so that no output outweighs another by its rate alone.
MeasuredRecording extract_measured_recording(const recording::Recording& recording,
                                             const std::string& source);

}  // namespace scopekin::discrepancy
