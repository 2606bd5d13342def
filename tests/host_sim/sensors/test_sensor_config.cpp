// The sensor configuration's JSON: defaults, every key, and strict refusals naming `path.key`.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "host_sim/sensors/sensor_config.hpp"
#include "model/model_error.hpp"

namespace {

using scopekin::model::ModelError;
using scopekin::sensors::read_sensor_config;
using scopekin::sensors::SensorSuiteConfig;

std::string error_of(const std::string& text, const std::string& path = "sensors.json:") {
    try {
        (void)read_sensor_config(nlohmann::json::parse(text), path);
    } catch (const ModelError& e) {
        return e.what();
    }
    ADD_FAILURE() << "accepted: " << text;
    return "";
}

TEST(SensorConfig, EmptyObjectGivesTheDocumentedDefaults) {
    const SensorSuiteConfig c = read_sensor_config(nlohmann::json::object(), "sensors.json:");
    EXPECT_TRUE(c.handle_force_torque.sampling.enabled);
    EXPECT_EQ(c.handle_force_torque.sampling.rate_Hz, 1000.0);  // DBC GenMsgCycleTime 1 ms
    EXPECT_EQ(c.handle_force_torque.force_quantum_N, 0.005);    // DBC HandleForce factor
    EXPECT_EQ(c.handle_force_torque.torque_quantum_Nmm, 0.1);   // DBC HandleTorque factor
    EXPECT_EQ(c.insertion_roll.sampling.rate_Hz, 1000.0);
    EXPECT_EQ(c.insertion_roll.insertion_quantum_mm, 0.01);    // DBC Insertion factor
    EXPECT_EQ(c.insertion_roll.roll_quantum_rad, 0.0001);      // DBC Roll factor
    EXPECT_NEAR(c.em_tracker.sampling.rate_Hz, 30.303, 1e-3);  // the bench's 30 Hz at a whole 33 ms
    EXPECT_EQ(c.em_tracker.position_noise_mm, 0.5);
    EXPECT_EQ(c.em_tracker.position_quantum_mm, 0.001);  // µm on the serial line
    EXPECT_NEAR(c.tip_force.sampling.rate_Hz, 30.303, 1e-3);
    EXPECT_EQ(c.tip_force.force_noise_N, 0.075);  // thesis §5.3, beside Fig. 5.21
    EXPECT_TRUE(c.tip_force.single_axis);
    EXPECT_EQ(scopekin::sensors::period_ticks(c.em_tracker.sampling.rate_Hz, "x"), 33);
}

TEST(SensorConfig, ReadsEveryKey) {
    const auto c = read_sensor_config(nlohmann::json::parse(R"({
    "handle_force_torque": {"enabled": true, "rate_Hz": 500, "latency_s": 0.002, "dropout_probability": 0.01,
                            "force_noise_N": 0.1, "force_bias_N": -0.2, "force_quantum_N": 0.01,
                            "torque_noise_Nmm": 2, "torque_bias_Nmm": 3, "torque_quantum_Nmm": 0.5},
    "insertion_roll": {"rate_Hz": 250, "insertion_noise_mm": 0.1, "insertion_bias_mm": 1, "insertion_quantum_mm": 0.05,
                       "roll_noise_rad": 0.001, "roll_bias_rad": 0.01, "roll_quantum_rad": 0.001},
    "em_tracker": {"rate_Hz": 40, "latency_s": 0.01, "sensors": ["tip", "sigmoid"], "position_noise_mm": 0.3,
                   "position_bias_mm": [1, 2, 3], "position_quantum_mm": 0.01, "orientation_noise_rad": 0.01,
                   "orientation_bias_rad": [0, 0, 0.1]},
    "tip_force": {"enabled": false, "rate_Hz": 30.30303, "single_axis": false, "force_noise_N": 0.05,
                  "force_bias_N": 0.1, "force_quantum_N": 0.002}
  })"),
                                      "s");
    EXPECT_EQ(c.handle_force_torque.sampling.rate_Hz, 500);
    EXPECT_EQ(c.handle_force_torque.sampling.latency_s, 0.002);
    EXPECT_EQ(c.handle_force_torque.sampling.dropout_probability, 0.01);
    EXPECT_EQ(c.handle_force_torque.force_bias_N, -0.2);
    EXPECT_EQ(c.handle_force_torque.torque_quantum_Nmm, 0.5);
    EXPECT_EQ(c.insertion_roll.insertion_bias_mm, 1);
    EXPECT_EQ(c.insertion_roll.roll_quantum_rad, 0.001);
    EXPECT_EQ(c.em_tracker.sensors, (std::array<bool, 4>{true, false, false, true}));
    EXPECT_EQ(c.em_tracker.position_bias_mm, (std::array<double, 3>{1, 2, 3}));
    EXPECT_EQ(c.em_tracker.orientation_bias_rad[2], 0.1);
    EXPECT_FALSE(c.tip_force.sampling.enabled);
    EXPECT_FALSE(c.tip_force.single_axis);
    EXPECT_EQ(c.tip_force.force_quantum_N, 0.002);
}

TEST(SensorConfig, UnknownKeysAreRefusedWithTheirPath) {
    EXPECT_EQ(error_of(R"({"em_tracker": {"rate": 30}})")
                  .rfind("sensors.json: em_tracker.rate: unknown key", 0),
              0u);
    EXPECT_EQ(error_of(R"({"cameras": {}})").rfind("sensors.json: cameras: unknown key", 0), 0u);
    EXPECT_EQ(error_of(R"({"tip_force": {"noise_N": 1}})", "scenario.sensors")
                  .rfind("scenario.sensors.tip_force.noise_N: unknown key", 0),
              0u);
}

TEST(SensorConfig, WrongTypesAreRefused) {
    EXPECT_EQ(error_of(R"({"tip_force": {"force_noise_N": "0.1"}})"),
              "sensors.json: tip_force.force_noise_N: expected a number, got string");
    EXPECT_EQ(error_of(R"({"handle_force_torque": {"enabled": 1}})"),
              "sensors.json: handle_force_torque.enabled: expected true or false, got 1");
    EXPECT_EQ(error_of(R"({"em_tracker": []})"),
              "sensors.json: em_tracker: expected a JSON object, got array");
    EXPECT_EQ(
        error_of(R"({"em_tracker": {"position_bias_mm": [1, 2]}})"),
        "sensors.json: em_tracker.position_bias_mm: expected an array of 3 numbers, got [1,2]");
    EXPECT_EQ(error_of(R"({"em_tracker": {"sensors": ["tip", 3]}})"),
              "sensors.json: em_tracker.sensors[1]: expected a string, got number");
    EXPECT_EQ(error_of(R"({"em_tracker": {"sensors": ["tip", "s5"]}})"),
              "sensors.json: em_tracker.sensors[1]: unknown EM sensor 's5' (known: tip, 20cm, "
              "handle, sigmoid)");
    EXPECT_EQ(error_of(R"({"em_tracker": {"sensors": ["tip", "tip"]}})"),
              "sensors.json: em_tracker.sensors[1]: 'tip' is listed twice");
}

TEST(SensorConfig, OutOfRangeValuesAreRefused) {
    EXPECT_EQ(error_of(R"({"handle_force_torque": {"dropout_probability": 1.5}})"),
              "sensors.json: handle_force_torque.dropout_probability: 1.5 is outside [0, 1]");
    EXPECT_EQ(error_of(R"({"em_tracker": {"position_noise_mm": -0.1}})"),
              "sensors.json: em_tracker.position_noise_mm: -0.1 mm is outside [0, 100] mm");
    EXPECT_EQ(error_of(R"({"handle_force_torque": {"force_quantum_N": 0.001}})"),
              "sensors.json: handle_force_torque.force_quantum_N: 0.001 N is finer than the wire's "
              "resolution "
              "0.005 N (the recording could not carry it)");
    EXPECT_EQ(error_of(R"({"insertion_roll": {"rate_Hz": 2000}})"),
              "sensors.json: insertion_roll.rate_Hz: 2000 Hz is outside (0, 1000] Hz (one sample "
              "per 1 ms tick at most)");
    EXPECT_EQ(error_of(R"({"insertion_roll": {"rate_Hz": 0}})")
                  .rfind("sensors.json: insertion_roll.rate_Hz: 0 Hz", 0),
              0u);
}

TEST(SensorConfig, RatesAndLatenciesMustBeWholeTicks) {
    EXPECT_EQ(error_of(R"({"em_tracker": {"rate_Hz": 30}})"),
              "sensors.json: em_tracker.rate_Hz: 30 Hz is a sample period of 33.333 ms, not a "
              "whole number of the "
              "simulator's 1 ms ticks (nearest: 30.30303 Hz = 33 ms, 29.41176 Hz = 34 ms)");
    EXPECT_EQ(error_of(R"({"tip_force": {"rate_Hz": 1500}})")
                  .rfind("sensors.json: tip_force.rate_Hz: 1500 Hz is outside", 0),
              0u);
    EXPECT_EQ(error_of(R"({"handle_force_torque": {"rate_Hz": 400}})"),
              "sensors.json: handle_force_torque.rate_Hz: 400 Hz is a sample period of 2.500 ms, "
              "not a whole number of "
              "the simulator's 1 ms ticks (nearest: 500.00000 Hz = 2 ms, 333.33333 Hz = 3 ms)");
    EXPECT_EQ(error_of(R"({"handle_force_torque": {"latency_s": 0.0005}})"),
              "sensors.json: handle_force_torque.latency_s: 0.0005 s is not a whole number of the "
              "simulator's 1 ms ticks");
    EXPECT_EQ(scopekin::sensors::period_ticks(30.30303, "x"), 33);
    EXPECT_EQ(scopekin::sensors::period_ticks(1000, "x"), 1);
    EXPECT_EQ(scopekin::sensors::period_ticks(1, "x"), 1000);
    EXPECT_EQ(scopekin::sensors::latency_ticks(0.007, "x"), 7);
    EXPECT_EQ(scopekin::sensors::latency_ticks(0, "x"), 0);
}

}  // namespace
