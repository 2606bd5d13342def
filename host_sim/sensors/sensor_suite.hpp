#pragma once
// Sensor models between the world's true state and the recording rows (SENSORS.md).
//
// Each tick (kTickUs = 1 ms) the caller gives the world's state at that instant (TruthSample,
// interpolated by the caller) and gets back the RecordingRow of what ARRIVES at the box (or the
// bench logger) at that tick.  Per sensor:
//   rate      a sample is taken at every tick whose time is a multiple of the period
//             (time_us % period_us == 0), so all sensors sample at t = 0 and at common multiples;
//   noise     value + bias + SD × N(0, 1) per sample (independent draws per signal and axis);
//   quantum   rounded to a multiple of the quantum (ties away from zero), then limited to the
//             recording's plausible range (the sensor's full scale: RecordingLimits);
//   dropout   each sample is lost with the configured probability (counted as dropped);
//   latency   a kept sample arrives exactly `latency` after it was taken.
// The EM tracker's four sensors are independent channels with the same settings; orientation
// noise is a random rotation vector (plus the bias) applied in the sensor's frame.
//
// Determinism: every channel has its own two xoshiro256** streams (noise, dropout), seeded from
// the suite's seed and the channel's index through SplitMix64, and normal deviates come from the
// portable Box–Muller of random.hpp: the same seed gives the same rows on every platform, and
// changing one sensor's settings never changes another sensor's numbers.
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "host_sim/recording/recording_row.hpp"
#include "host_sim/sensors/random.hpp"
#include "host_sim/sensors/sensor_config.hpp"

namespace scopekin::sensors {

/// A 6-DOF pose in the colon frame.
struct Pose {
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Quaterniond orientation =
        Eigen::Quaterniond::Identity();  ///< unit; Quaterniond(w, x, y, z)
};

/// The world's true state at one tick.
struct TruthSample {
    std::int64_t time_us = 0;  ///< a multiple of kTickUs; successive ticks exactly kTickUs apart
    double handle_force_N = 0;
    double handle_torque_Nmm = 0;
    double insertion_mm = 0;
    double roll_rad = 0;
    std::array<Pose, 4> em{};  ///< by EM wire id: tip, 20 cm from the tip, handle, sigmoid
    Eigen::Vector3d tip_force_N =
        Eigen::Vector3d::Zero();  ///< tip frame: x, y across, z along the axis
    std::string region;           ///< colon region of the tip ("" = unknown); copied into every row
};

struct SensorCounters {
    std::uint64_t taken = 0;      ///< samples taken (rate)
    std::uint64_t dropped = 0;    ///< of those, lost (dropout)
    std::uint64_t delivered = 0;  ///< arrived (taken − dropped − still in flight)
    friend bool operator==(const SensorCounters&, const SensorCounters&) = default;
};

struct SensorSuiteCounters {
    SensorCounters handle_force_torque;
    SensorCounters insertion_roll;
    std::array<SensorCounters, 4> em;  ///< by EM wire id
    SensorCounters tip_force;
};

class SensorSuite {
public:
    /// Validates the configuration (ModelError naming "sensors.<key>").
    SensorSuite(const SensorSuiteConfig& config, std::uint64_t seed);

    /// One tick: samples taken now, and what arrives now.  Throws std::invalid_argument if the time
    /// is not a multiple of kTickUs, not exactly one tick after the previous call's, or a truth value
    /// is not finite.
    recording::RecordingRow tick(const TruthSample& truth);

    [[nodiscard]] const SensorSuiteCounters& counters() const { return counters_; }
    [[nodiscard]] const SensorSuiteConfig& config() const { return config_; }

private:
    struct Timing {
        bool enabled = true;
        std::int64_t period_us = kTickUs;
        std::int64_t latency_us = 0;
        double dropout_probability = 0;
    };
    /// The random streams of one channel.
    struct Streams {
        Xoshiro256StarStar noise;
        Xoshiro256StarStar dropout;
        NormalSampler normal{};
        Streams(std::uint64_t seed, std::uint64_t channel);
        double gaussian() { return normal.next(noise); }
    };
    template <typename Value>
    struct Channel {
        Timing timing;
        Streams streams;
        std::deque<std::pair<std::int64_t, Value>> in_flight;  ///< (arrival time, value), in order
    };
    /// Takes a sample if due (measure() draws the noise), queues it unless dropped, and returns the
    /// sample that arrives now, if any.
    template <typename Value, typename Measure>
    std::optional<Value> step(Channel<Value>& channel, SensorCounters& counters,
                              std::int64_t now_us, Measure measure);

    recording::ForceTorqueCells measure_force_torque(const TruthSample& truth,
                                                     Streams& streams) const;
    recording::InsertionRollCells measure_insertion_roll(const TruthSample& truth,
                                                         Streams& streams) const;
    recording::EmPoseCells measure_pose(const Pose& truth, Streams& streams) const;
    recording::TipForceCells measure_tip_force(const TruthSample& truth, Streams& streams) const;

    SensorSuiteConfig config_;
    Channel<recording::ForceTorqueCells> force_torque_;
    Channel<recording::InsertionRollCells> insertion_roll_;
    std::array<Channel<recording::EmPoseCells>, 4> em_;
    Channel<recording::TipForceCells> tip_force_;
    SensorSuiteCounters counters_{};
    bool started_ = false;
    std::int64_t last_time_us_ = 0;
};

/// value rounded to a multiple of quantum (ties away from zero); quantum <= 0 leaves it alone.
double quantize(double value, double quantum);

}  // namespace scopekin::sensors
