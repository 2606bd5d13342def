#pragma once
// Configuration of the sensor models (host_sim/sensors/SENSORS.md lists every default and its
// source).  Read from JSON by read_sensor_config: every key optional, strict like
// model/io/strict_json (unknown key, wrong type or out-of-range value -> ModelError naming
// `path.key`).
#include <array>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

namespace scopekin::sensors {

/// The simulator's tick: the sensor suite is stepped every millisecond.  Sample periods and
/// latencies are whole numbers of ticks.
inline constexpr std::int64_t kTickUs = 1000;

/// When a sensor samples and how its samples travel.
struct SamplingConfig {
    bool enabled = true;
    double rate_Hz = 1000.0;  ///< the period 1/rate must be a whole number of ticks (within 1 µs)
    double latency_s = 0.0;   ///< sample -> arrival; a whole number of ticks (within 1 µs)
    double dropout_probability = 0.0;  ///< per sample, independent
};

/// Handle force/torque cell (CAN 0x110).
struct HandleForceTorqueConfig {
    SamplingConfig sampling{true, 1000.0, 0.0, 0.0};
    double force_noise_N = 0.02;
    double force_bias_N = 0.0;
    double force_quantum_N = 0.005;  ///< >= the DBC's 0.005 N
    double torque_noise_Nmm = 0.5;
    double torque_bias_Nmm = 0.0;
    double torque_quantum_Nmm = 0.1;  ///< >= the DBC's 0.1 N·mm
};

/// Insertion/roll encoder (CAN 0x111).
struct InsertionRollConfig {
    SamplingConfig sampling{true, 1000.0, 0.0, 0.0};
    double insertion_noise_mm = 0.0;
    double insertion_bias_mm = 0.0;
    double insertion_quantum_mm = 0.01;  ///< >= the DBC's 0.01 mm
    double roll_noise_rad = 0.0;
    double roll_bias_rad = 0.0;
    double roll_quantum_rad = 0.0001;  ///< >= the DBC's 0.0001 rad
};

/// The thesis bench's trakSTAR: 30 Hz, rounded to a whole 33 ms period of the 1 ms tick.
inline constexpr double kBenchRate_Hz = 1000.0 / 33.0;

/// EM tracker, four 6-DOF sensors (serial pose frames).  Each sensor samples, drops and draws its
/// noise independently, with the same settings.
struct EmTrackerConfig {
    SamplingConfig sampling{true, kBenchRate_Hz, 0.0, 0.0};
    std::array<bool, 4> sensors{true, true, true,
                                true};             ///< by wire id: tip, 20 cm, handle, sigmoid
    double position_noise_mm = 0.5;                ///< per axis, SD
    std::array<double, 3> position_bias_mm{};      ///< colon frame
    double position_quantum_mm = 0.001;            ///< >= the wire's 1 µm
    double orientation_noise_rad = 0.002;          ///< per body axis, SD of the rotation vector
    std::array<double, 3> orientation_bias_rad{};  ///< rotation vector, body frame
};

/// Tip contact force sensor (serial tip force frames).
struct TipForceConfig {
    SamplingConfig sampling{true, kBenchRate_Hz, 0.0, 0.0};
    bool single_axis = true;         ///< Flexiforce: z only (>= 0), x = y = 0
    double force_noise_N = 0.075;    ///< per measured axis, SD
    double force_bias_N = 0.0;       ///< per measured axis
    double force_quantum_N = 0.001;  ///< >= the wire's 1 mN
};

struct SensorSuiteConfig {
    HandleForceTorqueConfig handle_force_torque;
    InsertionRollConfig insertion_roll;
    EmTrackerConfig em_tracker;
    TipForceConfig tip_force;
};

/// Reads a configuration object (keys handle_force_torque, insertion_roll, em_tracker, tip_force;
/// all optional).  `path` names the object in error messages ("sensors.json:" for a file's root,
/// "scenario.sensors" below it).  Throws scopekin::model::ModelError.
SensorSuiteConfig read_sensor_config(const nlohmann::json& json, const std::string& path);

/// Checks a configuration built in code (the same rules); throws ModelError naming `path.key`.
void validate_sensor_config(const SensorSuiteConfig& config, const std::string& path = "sensors");

/// Whole ticks of a rate's period / of a latency; throws ModelError naming `field` otherwise.
std::int64_t period_ticks(double rate_Hz, const std::string& field);
std::int64_t latency_ticks(double latency_s, const std::string& field);

}  // namespace scopekin::sensors
