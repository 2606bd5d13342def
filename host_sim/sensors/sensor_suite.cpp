#include "host_sim/sensors/sensor_suite.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "host_sim/recording/recording_format.hpp"

namespace scopekin::sensors {

namespace {

using recording::RecordingLimits;

// Channel indices for seeding (fixed forever: changing them changes every recording).
constexpr std::uint64_t kChannelForceTorque = 0;
constexpr std::uint64_t kChannelInsertionRoll = 1;
constexpr std::uint64_t kChannelEm0 = 2;  // 2..5
constexpr std::uint64_t kChannelTipForce = 6;

double clamp(double value, double lo, double hi) {
    return std::min(std::max(value, lo), hi);
}

std::string time_text(std::int64_t time_us) {
    return recording::format_time_s(time_us) + " s";
}

void require_finite(double value, const char* what, std::int64_t time_us) {
    if (!std::isfinite(value))
        throw std::invalid_argument("SensorSuite::tick at " + time_text(time_us) + ": truth " +
                                    what + " is not finite");
}

struct Quaternion {
    double w, x, y, z;
};

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
    return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
            a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

Quaternion normalized(const Quaternion& q) {
    const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    return {q.w / n, q.x / n, q.y / n, q.z / n};
}

/// The unit quaternion of rotation vector v (angle |v| about v / |v|).
Quaternion from_rotation_vector(double vx, double vy, double vz) {
    const double angle = std::sqrt(vx * vx + vy * vy + vz * vz);
    if (angle == 0.0) return {1.0, 0.0, 0.0, 0.0};
    double s = 0;
    double c = 0;
    portable_sin_cos(0.5 * angle, s, c);
    const double k = s / angle;
    return {c, k * vx, k * vy, k * vz};
}

}  // namespace

double quantize(double value, double quantum) {
    if (!(quantum > 0)) return value;
    return std::round(value / quantum) * quantum;
}

SensorSuite::Streams::Streams(std::uint64_t seed, std::uint64_t channel)
    : noise(SplitMix64(seed ^ (0x9e3779b97f4a7c15ULL * (2 * channel + 1))).next()),
      dropout(SplitMix64(seed ^ (0x9e3779b97f4a7c15ULL * (2 * channel + 2))).next()) {}

namespace {

template <typename Channel, typename Timing>
Channel make_channel(const SamplingConfig& sampling, bool enabled, std::uint64_t seed,
                     std::uint64_t index, const std::string& path) {
    Timing timing;
    timing.enabled = sampling.enabled && enabled;
    timing.period_us = period_ticks(sampling.rate_Hz, path + ".rate_Hz") * kTickUs;
    timing.latency_us = latency_ticks(sampling.latency_s, path + ".latency_s") * kTickUs;
    timing.dropout_probability = sampling.dropout_probability;
    return Channel{timing, {seed, index}, {}};
}

}  // namespace

SensorSuite::SensorSuite(const SensorSuiteConfig& config, std::uint64_t seed)
    : config_((validate_sensor_config(config, "sensors"), config)),
      force_torque_(make_channel<Channel<recording::ForceTorqueCells>, Timing>(
          config.handle_force_torque.sampling, true, seed, kChannelForceTorque,
          "sensors.handle_force_torque")),
      insertion_roll_(make_channel<Channel<recording::InsertionRollCells>, Timing>(
          config.insertion_roll.sampling, true, seed, kChannelInsertionRoll,
          "sensors.insertion_roll")),
      em_{make_channel<Channel<recording::EmPoseCells>, Timing>(
              config.em_tracker.sampling, config.em_tracker.sensors[0], seed, kChannelEm0 + 0,
              "sensors.em_tracker"),
          make_channel<Channel<recording::EmPoseCells>, Timing>(
              config.em_tracker.sampling, config.em_tracker.sensors[1], seed, kChannelEm0 + 1,
              "sensors.em_tracker"),
          make_channel<Channel<recording::EmPoseCells>, Timing>(
              config.em_tracker.sampling, config.em_tracker.sensors[2], seed, kChannelEm0 + 2,
              "sensors.em_tracker"),
          make_channel<Channel<recording::EmPoseCells>, Timing>(
              config.em_tracker.sampling, config.em_tracker.sensors[3], seed, kChannelEm0 + 3,
              "sensors.em_tracker")},
      tip_force_(make_channel<Channel<recording::TipForceCells>, Timing>(
          config.tip_force.sampling, true, seed, kChannelTipForce, "sensors.tip_force")) {}

template <typename Value, typename Measure>
std::optional<Value> SensorSuite::step(Channel<Value>& channel, SensorCounters& counters,
                                       std::int64_t now_us, Measure measure) {
    const Timing& timing = channel.timing;
    if (timing.enabled && now_us % timing.period_us == 0) {
        ++counters.taken;
        // Both streams advance on every sample, whatever the settings: the noise of a sample never
        // depends on the dropout probability, nor the dropouts on the noise levels.
        const double u =
            channel.streams.dropout.uniform();  // [0, 1): p = 0 never drops, p = 1 always
        Value value = measure(channel.streams);
        if (u < timing.dropout_probability) {
            ++counters.dropped;
        } else {
            channel.in_flight.emplace_back(now_us + timing.latency_us, std::move(value));
        }
    }
    if (!channel.in_flight.empty() && channel.in_flight.front().first <= now_us) {
        Value arrived = std::move(channel.in_flight.front().second);
        channel.in_flight.pop_front();
        ++counters.delivered;
        return arrived;
    }
    return std::nullopt;
}

recording::ForceTorqueCells SensorSuite::measure_force_torque(const TruthSample& truth,
                                                              Streams& streams) const {
    const auto& c = config_.handle_force_torque;
    const double force =
        truth.handle_force_N + c.force_bias_N + c.force_noise_N * streams.gaussian();
    const double torque =
        truth.handle_torque_Nmm + c.torque_bias_Nmm + c.torque_noise_Nmm * streams.gaussian();
    return {clamp(quantize(force, c.force_quantum_N), RecordingLimits::force_min_N,
                  RecordingLimits::force_max_N),
            clamp(quantize(torque, c.torque_quantum_Nmm), RecordingLimits::torque_min_Nmm,
                  RecordingLimits::torque_max_Nmm)};
}

recording::InsertionRollCells SensorSuite::measure_insertion_roll(const TruthSample& truth,
                                                                  Streams& streams) const {
    const auto& c = config_.insertion_roll;
    const double insertion =
        truth.insertion_mm + c.insertion_bias_mm + c.insertion_noise_mm * streams.gaussian();
    const double roll = truth.roll_rad + c.roll_bias_rad + c.roll_noise_rad * streams.gaussian();
    return {clamp(quantize(insertion, c.insertion_quantum_mm), RecordingLimits::insertion_min_mm,
                  RecordingLimits::insertion_max_mm),
            clamp(quantize(roll, c.roll_quantum_rad), RecordingLimits::roll_min_rad,
                  RecordingLimits::roll_max_rad)};
}

recording::EmPoseCells SensorSuite::measure_pose(const Pose& truth, Streams& streams) const {
    const auto& c = config_.em_tracker;
    recording::EmPoseCells cells;
    for (std::size_t i = 0; i < 3; ++i) {
        const double p = truth.position_mm(static_cast<Eigen::Index>(i)) + c.position_bias_mm[i] +
                         c.position_noise_mm * streams.gaussian();
        cells.position_mm[i] =
            clamp(quantize(p, c.position_quantum_mm), -RecordingLimits::position_max_abs_mm,
                  RecordingLimits::position_max_abs_mm);
    }
    std::array<double, 3> v{};
    for (std::size_t i = 0; i < 3; ++i)
        v[i] = c.orientation_bias_rad[i] + c.orientation_noise_rad * streams.gaussian();
    const Quaternion q_true = normalized({truth.orientation.w(), truth.orientation.x(),
                                          truth.orientation.y(), truth.orientation.z()});
    const Quaternion q = normalized(multiply(q_true, from_rotation_vector(v[0], v[1], v[2])));
    cells.quaternion_wxyz = {q.w, q.x, q.y, q.z};
    return cells;
}

recording::TipForceCells SensorSuite::measure_tip_force(const TruthSample& truth,
                                                        Streams& streams) const {
    const auto& c = config_.tip_force;
    const double limit = RecordingLimits::tip_force_max_abs_N;
    recording::TipForceCells cells;
    if (c.single_axis) {
        // A force-sensing resistor reads compression only: never below zero.
        const double z =
            truth.tip_force_N.z() + c.force_bias_N + c.force_noise_N * streams.gaussian();
        cells.force_N = {0.0, 0.0, clamp(quantize(z, c.force_quantum_N), 0.0, limit)};
    } else {
        for (std::size_t i = 0; i < 3; ++i) {
            const double f = truth.tip_force_N(static_cast<Eigen::Index>(i)) + c.force_bias_N +
                             c.force_noise_N * streams.gaussian();
            cells.force_N[i] = clamp(quantize(f, c.force_quantum_N), -limit, limit);
        }
    }
    return cells;
}

recording::RecordingRow SensorSuite::tick(const TruthSample& truth) {
    const std::int64_t now = truth.time_us;
    if (now < 0 || now % kTickUs != 0)
        throw std::invalid_argument("SensorSuite::tick: time " + time_text(now) +
                                    " is not a non-negative multiple of the " +
                                    std::to_string(kTickUs) + " µs tick");
    if (started_ && now != last_time_us_ + kTickUs)
        throw std::invalid_argument("SensorSuite::tick: time " + time_text(now) +
                                    " is not one tick after the previous " +
                                    time_text(last_time_us_));
    require_finite(truth.handle_force_N, "handle_force_N", now);
    require_finite(truth.handle_torque_Nmm, "handle_torque_Nmm", now);
    require_finite(truth.insertion_mm, "insertion_mm", now);
    require_finite(truth.roll_rad, "roll_rad", now);
    for (const Pose& pose : truth.em) {
        if (!pose.position_mm.allFinite() || !pose.orientation.coeffs().allFinite() ||
            pose.orientation.norm() < 0.5)
            throw std::invalid_argument(
                "SensorSuite::tick at " + time_text(now) +
                ": an EM truth pose is not finite or its quaternion is not (close to) unit");
    }
    if (!truth.tip_force_N.allFinite())
        throw std::invalid_argument("SensorSuite::tick at " + time_text(now) +
                                    ": truth tip force is not finite");
    started_ = true;
    last_time_us_ = now;

    recording::RecordingRow row;
    row.time_us = now;
    row.region = truth.region;
    row.handle = step(force_torque_, counters_.handle_force_torque, now,
                      [&](Streams& s) { return measure_force_torque(truth, s); });
    row.insertion_roll = step(insertion_roll_, counters_.insertion_roll, now,
                              [&](Streams& s) { return measure_insertion_roll(truth, s); });
    for (std::size_t i = 0; i < em_.size(); ++i) {
        row.em[i] = step(em_[i], counters_.em[i], now,
                         [&](Streams& s) { return measure_pose(truth.em[i], s); });
    }
    row.tip_force = step(tip_force_, counters_.tip_force, now,
                         [&](Streams& s) { return measure_tip_force(truth, s); });
    return row;
}

}  // namespace scopekin::sensors
