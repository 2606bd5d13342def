#include "host_sim/sensors/sensor_config.hpp"

#include <cmath>
#include <cstdio>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace scopekin::sensors {

namespace {

using model::ModelError;
using model::number_text;
using model::io::JsonObject;

// Resolutions of the wire (scopekin.dbc, em_tracker_serial.md): the smallest quanta.
constexpr double kForceStep_N = 0.005;
constexpr double kTorqueStep_Nmm = 0.1;
constexpr double kInsertionStep_mm = 0.01;
constexpr double kRollStep_rad = 0.0001;
constexpr double kPositionStep_mm = 0.001;
constexpr double kTipForceStep_N = 0.001;
constexpr double kTickToleranceUs = 1.0;  // a period or latency within 1 µs of whole ticks

std::string join(const std::string& path, const std::string& key) {
    if (path.empty()) return key;
    return path.back() == ':' ? path + " " + key : path + "." + key;
}

std::string fixed(double value, int decimals) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
    return buffer;
}

void require_range(double value, double lo, double hi, const std::string& field, const char* unit) {
    if (!std::isfinite(value) || value < lo || value > hi) {
        const std::string u = *unit == '\0' ? "" : std::string(" ") + unit;
        throw ModelError(field + ": " + number_text(value) + u + " is outside [" + number_text(lo) +
                         ", " + number_text(hi) + "]" + u);
    }
}

void require_quantum(double value, double wire_step, double hi, const std::string& field,
                     const char* unit) {
    if (!std::isfinite(value) || value < wire_step * (1.0 - 1e-9))
        throw ModelError(field + ": " + number_text(value) + " " + unit +
                         " is finer than the wire's resolution " + number_text(wire_step) + " " +
                         unit + " (the recording could not carry it)");
    require_range(value, wire_step, hi, field, unit);
}

void validate_sampling(const SamplingConfig& s, const std::string& path) {
    (void)period_ticks(s.rate_Hz, join(path, "rate_Hz"));
    (void)latency_ticks(s.latency_s, join(path, "latency_s"));
    require_range(s.dropout_probability, 0.0, 1.0, join(path, "dropout_probability"), "");
}

void read_sampling(const JsonObject& o, SamplingConfig& s) {
    s.enabled = o.boolean_or("enabled", s.enabled);
    s.rate_Hz = o.number_or("rate_Hz", s.rate_Hz);
    s.latency_s = o.number_or("latency_s", s.latency_s);
    s.dropout_probability = o.number_or("dropout_probability", s.dropout_probability);
}

std::array<double, 3> array3_or(const JsonObject& o, const char* key,
                                const std::array<double, 3>& fallback) {
    if (!o.has(key)) return fallback;
    const Eigen::Vector3d v = o.vector3(key);
    return {v.x(), v.y(), v.z()};
}

constexpr std::array<const char*, 4> kEmSensorNames{"tip", "20cm", "handle", "sigmoid"};

}  // namespace

std::int64_t period_ticks(double rate_Hz, const std::string& field) {
    if (!std::isfinite(rate_Hz) || rate_Hz <= 0 || rate_Hz > 1000.0 * (1.0 + 1e-9))
        throw ModelError(field + ": " + number_text(rate_Hz) +
                         " Hz is outside (0, 1000] Hz (one sample per 1 ms tick at most)");
    const double period_us = 1e6 / rate_Hz;
    const double ticks = std::round(period_us / static_cast<double>(kTickUs));
    if (std::abs(period_us - ticks * static_cast<double>(kTickUs)) > kTickToleranceUs) {
        const double below = std::floor(period_us / static_cast<double>(kTickUs));
        const double above = below + 1.0;
        std::string nearest = " (nearest: ";
        if (below >= 1.0)
            nearest += fixed(1000.0 / below, 5) + " Hz = " + fixed(below, 0) + " ms, ";
        nearest += fixed(1000.0 / above, 5) + " Hz = " + fixed(above, 0) + " ms)";
        throw ModelError(field + ": " + number_text(rate_Hz) + " Hz is a sample period of " +
                         fixed(period_us / 1000.0, 3) +
                         " ms, not a whole number of the simulator's 1 ms ticks" + nearest);
    }
    return static_cast<std::int64_t>(ticks);
}

std::int64_t latency_ticks(double latency_s, const std::string& field) {
    require_range(latency_s, 0.0, 10.0, field, "s");
    const double latency_us = latency_s * 1e6;
    const double ticks = std::round(latency_us / static_cast<double>(kTickUs));
    if (std::abs(latency_us - ticks * static_cast<double>(kTickUs)) > kTickToleranceUs)
        throw ModelError(field + ": " + number_text(latency_s) +
                         " s is not a whole number of the simulator's 1 ms ticks");
    return static_cast<std::int64_t>(ticks);
}

void validate_sensor_config(const SensorSuiteConfig& c, const std::string& path) {
    {
        const std::string p = join(path, "handle_force_torque");
        const auto& h = c.handle_force_torque;
        validate_sampling(h.sampling, p);
        require_range(h.force_noise_N, 0, 50, join(p, "force_noise_N"), "N");
        require_range(h.force_bias_N, -50, 50, join(p, "force_bias_N"), "N");
        require_quantum(h.force_quantum_N, kForceStep_N, 10, join(p, "force_quantum_N"), "N");
        require_range(h.torque_noise_Nmm, 0, 1000, join(p, "torque_noise_Nmm"), "N·mm");
        require_range(h.torque_bias_Nmm, -1000, 1000, join(p, "torque_bias_Nmm"), "N·mm");
        require_quantum(h.torque_quantum_Nmm, kTorqueStep_Nmm, 100, join(p, "torque_quantum_Nmm"),
                        "N·mm");
    }
    {
        const std::string p = join(path, "insertion_roll");
        const auto& e = c.insertion_roll;
        validate_sampling(e.sampling, p);
        require_range(e.insertion_noise_mm, 0, 100, join(p, "insertion_noise_mm"), "mm");
        require_range(e.insertion_bias_mm, -100, 100, join(p, "insertion_bias_mm"), "mm");
        require_quantum(e.insertion_quantum_mm, kInsertionStep_mm, 10,
                        join(p, "insertion_quantum_mm"), "mm");
        require_range(e.roll_noise_rad, 0, 1, join(p, "roll_noise_rad"), "rad");
        require_range(e.roll_bias_rad, -1, 1, join(p, "roll_bias_rad"), "rad");
        require_quantum(e.roll_quantum_rad, kRollStep_rad, 0.1, join(p, "roll_quantum_rad"), "rad");
    }
    {
        const std::string p = join(path, "em_tracker");
        const auto& m = c.em_tracker;
        validate_sampling(m.sampling, p);
        require_range(m.position_noise_mm, 0, 100, join(p, "position_noise_mm"), "mm");
        for (std::size_t i = 0; i < 3; ++i)
            require_range(m.position_bias_mm[i], -100, 100,
                          join(p, "position_bias_mm") + "[" + std::to_string(i) + "]", "mm");
        require_quantum(m.position_quantum_mm, kPositionStep_mm, 10, join(p, "position_quantum_mm"),
                        "mm");
        require_range(m.orientation_noise_rad, 0, 1, join(p, "orientation_noise_rad"), "rad");
        for (std::size_t i = 0; i < 3; ++i)
            require_range(m.orientation_bias_rad[i], -3.14159, 3.14159,
                          join(p, "orientation_bias_rad") + "[" + std::to_string(i) + "]", "rad");
    }
    {
        const std::string p = join(path, "tip_force");
        const auto& t = c.tip_force;
        validate_sampling(t.sampling, p);
        require_range(t.force_noise_N, 0, 25, join(p, "force_noise_N"), "N");
        require_range(t.force_bias_N, -25, 25, join(p, "force_bias_N"), "N");
        require_quantum(t.force_quantum_N, kTipForceStep_N, 1, join(p, "force_quantum_N"), "N");
    }
}

SensorSuiteConfig read_sensor_config(const nlohmann::json& json, const std::string& path) {
    const JsonObject root(json, path);
    root.allow_only({"handle_force_torque", "insertion_roll", "em_tracker", "tip_force"});
    SensorSuiteConfig c;
    if (root.has("handle_force_torque")) {
        const JsonObject o = root.object("handle_force_torque");
        o.allow_only({"enabled", "rate_Hz", "latency_s", "dropout_probability", "force_noise_N",
                      "force_bias_N", "force_quantum_N", "torque_noise_Nmm", "torque_bias_Nmm",
                      "torque_quantum_Nmm"});
        auto& h = c.handle_force_torque;
        read_sampling(o, h.sampling);
        h.force_noise_N = o.number_or("force_noise_N", h.force_noise_N);
        h.force_bias_N = o.number_or("force_bias_N", h.force_bias_N);
        h.force_quantum_N = o.number_or("force_quantum_N", h.force_quantum_N);
        h.torque_noise_Nmm = o.number_or("torque_noise_Nmm", h.torque_noise_Nmm);
        h.torque_bias_Nmm = o.number_or("torque_bias_Nmm", h.torque_bias_Nmm);
        h.torque_quantum_Nmm = o.number_or("torque_quantum_Nmm", h.torque_quantum_Nmm);
    }
    if (root.has("insertion_roll")) {
        const JsonObject o = root.object("insertion_roll");
        o.allow_only({"enabled", "rate_Hz", "latency_s", "dropout_probability",
                      "insertion_noise_mm", "insertion_bias_mm", "insertion_quantum_mm",
                      "roll_noise_rad", "roll_bias_rad", "roll_quantum_rad"});
        auto& e = c.insertion_roll;
        read_sampling(o, e.sampling);
        e.insertion_noise_mm = o.number_or("insertion_noise_mm", e.insertion_noise_mm);
        e.insertion_bias_mm = o.number_or("insertion_bias_mm", e.insertion_bias_mm);
        e.insertion_quantum_mm = o.number_or("insertion_quantum_mm", e.insertion_quantum_mm);
        e.roll_noise_rad = o.number_or("roll_noise_rad", e.roll_noise_rad);
        e.roll_bias_rad = o.number_or("roll_bias_rad", e.roll_bias_rad);
        e.roll_quantum_rad = o.number_or("roll_quantum_rad", e.roll_quantum_rad);
    }
    if (root.has("em_tracker")) {
        const JsonObject o = root.object("em_tracker");
        o.allow_only({"enabled", "rate_Hz", "latency_s", "dropout_probability", "sensors",
                      "position_noise_mm", "position_bias_mm", "position_quantum_mm",
                      "orientation_noise_rad", "orientation_bias_rad"});
        auto& m = c.em_tracker;
        read_sampling(o, m.sampling);
        if (o.has("sensors")) {
            const nlohmann::json& list = o.array("sensors");
            m.sensors = {false, false, false, false};
            for (std::size_t i = 0; i < list.size(); ++i) {
                const std::string field = o.field("sensors") + "[" + std::to_string(i) + "]";
                if (!list[i].is_string())
                    throw ModelError(field + ": expected a string, got " +
                                     std::string(list[i].type_name()));
                const std::string name = list[i].get<std::string>();
                bool known = false;
                for (std::size_t s = 0; s < kEmSensorNames.size(); ++s) {
                    if (name != kEmSensorNames[s]) continue;
                    if (m.sensors[s])
                        throw ModelError(field + ": " + model::io::quote_text(name) +
                                         " is listed twice");
                    m.sensors[s] = true;
                    known = true;
                }
                if (!known)
                    throw ModelError(field + ": unknown EM sensor " + model::io::quote_text(name) +
                                     " (known: tip, 20cm, handle, sigmoid)");
            }
        }
        m.position_noise_mm = o.number_or("position_noise_mm", m.position_noise_mm);
        m.position_bias_mm = array3_or(o, "position_bias_mm", m.position_bias_mm);
        m.position_quantum_mm = o.number_or("position_quantum_mm", m.position_quantum_mm);
        m.orientation_noise_rad = o.number_or("orientation_noise_rad", m.orientation_noise_rad);
        m.orientation_bias_rad = array3_or(o, "orientation_bias_rad", m.orientation_bias_rad);
    }
    if (root.has("tip_force")) {
        const JsonObject o = root.object("tip_force");
        o.allow_only({"enabled", "rate_Hz", "latency_s", "dropout_probability", "single_axis",
                      "force_noise_N", "force_bias_N", "force_quantum_N"});
        auto& t = c.tip_force;
        read_sampling(o, t.sampling);
        t.single_axis = o.boolean_or("single_axis", t.single_axis);
        t.force_noise_N = o.number_or("force_noise_N", t.force_noise_N);
        t.force_bias_N = o.number_or("force_bias_N", t.force_bias_N);
        t.force_quantum_N = o.number_or("force_quantum_N", t.force_quantum_N);
    }
    validate_sensor_config(c, path);
    return c;
}

}  // namespace scopekin::sensors
