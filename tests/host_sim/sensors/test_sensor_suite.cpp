// The sensor suite: noise statistics, quantisation to the configured step, latency, rate, dropout
// fraction, seeds, limits — each against numbers that do not come from the code under test
// (the configuration's own values, statistical bounds for N samples).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <set>
#include <sstream>
#include <vector>

#include "host_sim/recording/recording_format.hpp"
#include "host_sim/recording/recording_reader.hpp"
#include "host_sim/sensors/sensor_suite.hpp"
#include "model/model_error.hpp"

namespace {

using scopekin::recording::RecordingRow;
using scopekin::sensors::kTickUs;
using scopekin::sensors::SensorSuite;
using scopekin::sensors::SensorSuiteConfig;
using scopekin::sensors::TruthSample;

/// A configuration with no noise, bias or dropout, every sensor at 1 kHz, no latency.
SensorSuiteConfig ideal_config() {
    SensorSuiteConfig c;
    c.handle_force_torque.force_noise_N = 0;
    c.handle_force_torque.torque_noise_Nmm = 0;
    c.em_tracker.sampling.rate_Hz = 1000;
    c.em_tracker.position_noise_mm = 0;
    c.em_tracker.orientation_noise_rad = 0;
    c.tip_force.sampling.rate_Hz = 1000;
    c.tip_force.force_noise_N = 0;
    return c;
}

TruthSample truth_at(std::int64_t tick) {
    TruthSample t;
    t.time_us = tick * kTickUs;
    t.handle_force_N = 10.0;
    t.handle_torque_Nmm = -50.0;
    t.insertion_mm = 300.0;
    t.roll_rad = 0.5;
    for (std::size_t i = 0; i < 4; ++i) {
        t.em[i].position_mm = Eigen::Vector3d(10.0 * static_cast<double>(i), 20.0, -30.0);
        t.em[i].orientation = Eigen::Quaterniond(
            Eigen::AngleAxisd(0.3 * static_cast<double>(i), Eigen::Vector3d::UnitZ()));
    }
    t.tip_force_N = Eigen::Vector3d(0.5, -0.5, 4.0);
    t.region = "sigmoid";
    return t;
}

/// Runs `ticks` ticks from tick 0, the truth from `truth` (default truth_at), and returns the rows.
std::vector<RecordingRow> run(SensorSuite& suite, std::int64_t ticks,
                              const std::function<TruthSample(std::int64_t)>& truth = truth_at) {
    std::vector<RecordingRow> rows;
    rows.reserve(static_cast<std::size_t>(ticks));
    for (std::int64_t k = 0; k < ticks; ++k)
        rows.push_back(suite.tick(truth(k)));
    return rows;
}

struct Stats {
    double n = 0, sum = 0, sum2 = 0;
    void add(double x) {
        n += 1;
        sum += x;
        sum2 += x * x;
    }
    [[nodiscard]] double mean() const { return sum / n; }
    [[nodiscard]] double sd() const { return std::sqrt(sum2 / n - mean() * mean()); }
};

/// 5-sigma bounds for the mean and the SD of n normal samples with SD sigma; the quantisation
/// adds quantum²/12 to the variance (uniform rounding error).
void expect_normal(const Stats& s, double mean, double sigma, double quantum, const char* what) {
    const double sd = std::sqrt(sigma * sigma + quantum * quantum / 12.0);
    EXPECT_NEAR(s.mean(), mean, 5.0 * sd / std::sqrt(s.n)) << what;
    EXPECT_NEAR(s.sd(), sd, 5.0 * sd / std::sqrt(2.0 * s.n)) << what;
}

TEST(SensorSuite, NoiseAndBiasHaveTheConfiguredMeanAndSd) {
    SensorSuiteConfig c = ideal_config();
    c.handle_force_torque.force_noise_N = 0.5;
    c.handle_force_torque.force_bias_N = 0.2;
    c.handle_force_torque.torque_noise_Nmm = 3.0;
    c.handle_force_torque.torque_bias_Nmm = -1.0;
    c.insertion_roll.insertion_noise_mm = 0.4;
    c.insertion_roll.roll_noise_rad = 0.01;
    c.em_tracker.position_noise_mm = 0.5;
    c.em_tracker.position_bias_mm = {1.0, 0.0, -2.0};
    c.tip_force.single_axis = false;
    c.tip_force.force_noise_N = 0.075;
    c.tip_force.force_bias_N = 0.05;
    SensorSuite suite(c, 1);
    Stats force, torque, insertion, roll, tip_x, tip_z, em_x, em_z;
    for (std::int64_t k = 0; k < 100000; ++k) {
        const RecordingRow row = suite.tick(truth_at(k));
        ASSERT_TRUE(row.handle && row.insertion_roll && row.em[3] && row.tip_force);
        force.add(row.handle->force_N);
        torque.add(row.handle->torque_Nmm);
        insertion.add(row.insertion_roll->insertion_mm);
        roll.add(row.insertion_roll->roll_rad);
        em_x.add(row.em[3]->position_mm[0]);
        em_z.add(row.em[3]->position_mm[2]);
        tip_x.add(row.tip_force->force_N[0]);
        tip_z.add(row.tip_force->force_N[2]);
    }
    expect_normal(force, 10.2, 0.5, 0.005, "force");
    expect_normal(torque, -51.0, 3.0, 0.1, "torque");
    expect_normal(insertion, 300.0, 0.4, 0.01, "insertion");
    expect_normal(roll, 0.5, 0.01, 0.0001, "roll");
    expect_normal(em_x, 31.0, 0.5, 0.001, "EM x");
    expect_normal(em_z, -32.0, 0.5, 0.001, "EM z");
    expect_normal(tip_x, 0.55, 0.075, 0.001, "tip x");
    expect_normal(tip_z, 4.05, 0.075, 0.001, "tip z");
}

TEST(SensorSuite, OrientationNoiseIsARotationVectorWithTheConfiguredSd) {
    SensorSuiteConfig c = ideal_config();
    c.em_tracker.orientation_noise_rad = 0.01;
    c.em_tracker.orientation_bias_rad = {0.0, 0.02, 0.0};
    SensorSuite suite(c, 5);
    Stats rx, ry, rz;
    for (std::int64_t k = 0; k < 100000; ++k) {
        TruthSample t = truth_at(k);
        const Eigen::Quaterniond truth = t.em[1].orientation;
        const RecordingRow row = suite.tick(t);
        const auto& q = row.em[1]->quaternion_wxyz;
        const Eigen::Quaterniond measured(q[0], q[1], q[2], q[3]);
        ASSERT_NEAR(measured.norm(), 1.0, 1e-12);
        // Body-frame error rotation: truth⁻¹ · measured, as a rotation vector.
        const Eigen::AngleAxisd error(truth.conjugate() * measured);
        const Eigen::Vector3d v = error.angle() * error.axis();
        rx.add(v.x());
        ry.add(v.y());
        rz.add(v.z());
    }
    expect_normal(rx, 0.0, 0.01, 0.0, "rx");
    expect_normal(ry, 0.02, 0.01, 0.0, "ry");
    expect_normal(rz, 0.0, 0.01, 0.0, "rz");
}

TEST(SensorSuite, ValuesAreMultiplesOfTheQuantum) {
    SensorSuiteConfig c = ideal_config();
    c.handle_force_torque.force_noise_N = 0.3;
    c.handle_force_torque.force_quantum_N = 0.005;  // the DBC's step
    c.handle_force_torque.torque_noise_Nmm = 5.0;
    c.handle_force_torque.torque_quantum_Nmm = 0.5;  // coarser than the DBC
    c.insertion_roll.insertion_noise_mm = 1.0;
    c.insertion_roll.insertion_quantum_mm = 0.01;
    c.em_tracker.position_noise_mm = 0.5;
    c.em_tracker.position_quantum_mm = 0.25;
    c.tip_force.force_noise_N = 0.1;
    c.tip_force.force_quantum_N = 0.02;
    SensorSuite suite(c, 3);
    auto on_grid = [](double value, double step) {
        const double k = value / step;
        return std::abs(k - std::round(k)) < 1e-6;
    };
    std::set<double> distinct_forces;
    for (const RecordingRow& row : run(suite, 20000)) {
        ASSERT_TRUE(on_grid(row.handle->force_N, 0.005)) << row.handle->force_N;
        ASSERT_TRUE(on_grid(row.handle->torque_Nmm, 0.5)) << row.handle->torque_Nmm;
        ASSERT_TRUE(on_grid(row.insertion_roll->insertion_mm, 0.01))
            << row.insertion_roll->insertion_mm;
        for (const double p : row.em[0]->position_mm)
            ASSERT_TRUE(on_grid(p, 0.25)) << p;
        ASSERT_TRUE(on_grid(row.tip_force->force_N[2], 0.02)) << row.tip_force->force_N[2];
        distinct_forces.insert(row.handle->force_N);
    }
    EXPECT_GT(distinct_forces.size(), 100u);  // noise 0.3 N over 0.005 N steps: many levels seen
}

TEST(SensorSuite, LatencyShiftsArrivalByExactlyTheLatency) {
    SensorSuiteConfig c = ideal_config();
    c.handle_force_torque.sampling.latency_s = 0.007;
    c.em_tracker.sampling.rate_Hz = 1000.0 / 33.0;
    c.em_tracker.sampling.latency_s = 0.010;
    SensorSuite suite(c, 1);
    // Force = 0.005 N × tick (on the DBC grid): the arriving value names the tick it was taken at.
    auto truth = [](std::int64_t k) {
        TruthSample t = truth_at(k);
        t.handle_force_N = 0.005 * static_cast<double>(k);
        t.em[0].position_mm.x() = static_cast<double>(k);
        return t;
    };
    const auto rows = run(suite, 1000, truth);
    for (std::int64_t k = 0; k < 1000; ++k) {
        const RecordingRow& row = rows[static_cast<std::size_t>(k)];
        EXPECT_EQ(row.time_us, k * 1000);
        if (k < 7) {
            EXPECT_FALSE(row.handle.has_value()) << k;
        } else {
            ASSERT_TRUE(row.handle.has_value()) << k;
            EXPECT_NEAR(row.handle->force_N, 0.005 * static_cast<double>(k - 7), 1e-9) << k;
        }
        // EM: taken at multiples of 33 ms, arriving 10 ms later.
        const bool em_arrives = k >= 10 && (k - 10) % 33 == 0;
        ASSERT_EQ(row.em[0].has_value(), em_arrives) << k;
        if (em_arrives) {
            EXPECT_EQ(row.em[0]->position_mm[0], static_cast<double>(k - 10)) << k;
        }
        EXPECT_TRUE(row.insertion_roll.has_value());  // no latency: every tick
    }
    EXPECT_EQ(suite.counters().handle_force_torque.taken, 1000u);
    EXPECT_EQ(suite.counters().handle_force_torque.delivered, 993u);  // 7 still in flight
    EXPECT_EQ(suite.counters().em[0].taken, 31u);                     // 0, 33, ..., 990 ms
    EXPECT_EQ(suite.counters().em[0].delivered, 30u);                 // 990 arrives at 1000
}

TEST(SensorSuite, DefaultRatesAreTheDbcsAndTheBenchs) {
    SensorSuite suite(SensorSuiteConfig{}, 8);
    const auto rows = run(suite, 3300);
    int handle = 0, em = 0, tip = 0;
    for (const RecordingRow& row : rows) {
        handle += row.handle ? 1 : 0;
        em += row.em[2] ? 1 : 0;
        tip += row.tip_force ? 1 : 0;
        if (row.em[2]) {
            EXPECT_EQ(row.time_us % 33000, 0);
        }
    }
    EXPECT_EQ(handle, 3300);  // 1 kHz
    EXPECT_EQ(em, 100);       // every 33 ms
    EXPECT_EQ(tip, 100);
}

TEST(SensorSuite, DropoutFractionIsWithinBinomialBounds) {
    SensorSuiteConfig c = ideal_config();
    c.handle_force_torque.sampling.dropout_probability = 0.2;
    c.em_tracker.sampling.dropout_probability = 0.05;
    SensorSuite suite(c, 17);
    constexpr double kN = 100000;
    std::uint64_t missing_rows = 0;
    for (const RecordingRow& row : run(suite, static_cast<std::int64_t>(kN)))
        missing_rows += row.handle ? 0U : 1U;
    const auto& counters = suite.counters();
    EXPECT_EQ(counters.handle_force_torque.taken, 100000u);
    EXPECT_EQ(counters.handle_force_torque.dropped, missing_rows);
    EXPECT_EQ(counters.handle_force_torque.dropped + counters.handle_force_torque.delivered,
              100000u);
    EXPECT_NEAR(static_cast<double>(counters.handle_force_torque.dropped), 0.2 * kN,
                5.0 * std::sqrt(kN * 0.2 * 0.8));
    for (std::size_t i = 0; i < 4; ++i)
        EXPECT_NEAR(static_cast<double>(counters.em[i].dropped), 0.05 * kN,
                    5.0 * std::sqrt(kN * 0.05 * 0.95))
            << i;
    EXPECT_EQ(counters.insertion_roll.dropped, 0u);
    // Independent per EM sensor: not all four drop together.
    EXPECT_NE(counters.em[0].dropped, counters.em[1].dropped);
}

TEST(SensorSuite, SameSeedSameRowsOtherSeedOtherRows) {
    const SensorSuiteConfig c;  // defaults: noise on every sensor
    SensorSuite a(c, 42), b(c, 42), other(c, 43);
    const auto rows_a = run(a, 3000);
    const auto rows_b = run(b, 3000);
    const auto rows_other = run(other, 3000);
    EXPECT_EQ(rows_a, rows_b);
    std::size_t differing = 0;
    for (std::size_t i = 0; i < rows_a.size(); ++i)
        differing += rows_a[i] == rows_other[i] ? 0U : 1U;
    EXPECT_GT(differing, 2900u);
}

TEST(SensorSuite, OneSensorsSettingsNeverChangeAnothersNumbers) {
    SensorSuiteConfig c;
    SensorSuiteConfig changed = c;
    changed.tip_force.force_noise_N = 0.5;
    changed.em_tracker.sampling.dropout_probability = 0.3;
    changed.handle_force_torque.torque_noise_Nmm =
        7.0;  // same channel, other signal: force unchanged
    SensorSuite a(c, 9), b(changed, 9);
    const auto rows_a = run(a, 2000);
    const auto rows_b = run(b, 2000);
    for (std::size_t i = 0; i < rows_a.size(); ++i) {
        ASSERT_EQ(rows_a[i].handle->force_N, rows_b[i].handle->force_N) << i;
        ASSERT_EQ(rows_a[i].insertion_roll, rows_b[i].insertion_roll) << i;
    }
}

TEST(SensorSuite, SaturatesAtFullScaleAndTheFlexiforceReadsNoTension) {
    SensorSuiteConfig c = ideal_config();
    c.tip_force.force_noise_N = 0.2;
    SensorSuite suite(c, 2);
    auto truth = [](std::int64_t k) {
        TruthSample t = truth_at(k);
        t.handle_force_N = 500.0;
        t.insertion_mm = -100.0;
        t.tip_force_N = Eigen::Vector3d(3.0, 3.0, 0.0);
        return t;
    };
    bool zero_seen = false;
    for (const RecordingRow& row : run(suite, 2000, truth)) {
        EXPECT_EQ(row.handle->force_N, 163.835);
        EXPECT_EQ(row.insertion_roll->insertion_mm, -50.0);
        EXPECT_EQ(row.tip_force->force_N[0], 0.0);  // single axis: z only
        EXPECT_EQ(row.tip_force->force_N[1], 0.0);
        EXPECT_GE(row.tip_force->force_N[2], 0.0);
        zero_seen = zero_seen || row.tip_force->force_N[2] == 0.0;
        EXPECT_EQ(row.region, "sigmoid");
    }
    EXPECT_TRUE(zero_seen);
}

TEST(SensorSuite, DisabledSensorsAndEmSubsetsDeliverNothing) {
    SensorSuiteConfig c;
    c.tip_force.sampling.enabled = false;
    c.em_tracker.sensors = {true, false, false, true};
    SensorSuite suite(c, 4);
    for (const RecordingRow& row : run(suite, 200)) {
        EXPECT_FALSE(row.tip_force.has_value());
        EXPECT_FALSE(row.em[1].has_value());
        EXPECT_FALSE(row.em[2].has_value());
    }
    EXPECT_EQ(suite.counters().tip_force.taken, 0u);
    EXPECT_EQ(suite.counters().em[0].taken, 7u);  // 0, 33, ..., 198 ms
    EXPECT_EQ(suite.counters().em[3].taken, 7u);
    EXPECT_EQ(suite.counters().em[1].taken, 0u);
}

TEST(SensorSuite, RefusesBadTicksAndBadConfigurations) {
    SensorSuite suite(SensorSuiteConfig{}, 1);
    TruthSample t = truth_at(0);
    t.time_us = 1500;
    EXPECT_THROW((void)suite.tick(t), std::invalid_argument);
    (void)suite.tick(truth_at(5));
    EXPECT_THROW((void)suite.tick(truth_at(7)), std::invalid_argument);  // skipped a tick
    EXPECT_THROW((void)suite.tick(truth_at(5)), std::invalid_argument);  // repeated
    t = truth_at(6);
    t.handle_force_N = std::nan("");
    EXPECT_THROW((void)suite.tick(t), std::invalid_argument);
    (void)suite.tick(truth_at(6));

    SensorSuiteConfig bad;
    bad.em_tracker.sampling.rate_Hz = 30.0;
    try {
        SensorSuite refused(bad, 1);
        FAIL() << "30 Hz accepted";
    } catch (const scopekin::model::ModelError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(
                      "sensors.em_tracker.rate_Hz: 30 Hz is a sample period of 33.333 ms", 0),
                  0u)
            << e.what();
    }
}

TEST(SensorSuite, ItsRowsAreAValidRecording) {
    SensorSuiteConfig c;
    c.handle_force_torque.sampling.dropout_probability = 0.01;
    SensorSuite suite(c, 77);
    std::ostringstream out;
    {
        scopekin::recording::RecordingWriter writer(out);
        for (const RecordingRow& row : run(suite, 5000))
            if (row.has_sensor_data()) writer.write(row);
    }
    std::istringstream in(out.str());
    const auto recording = scopekin::recording::RecordingReader().read(in);
    EXPECT_EQ(recording.rows.size(), 5000u);  // the encoder delivers every tick
    EXPECT_TRUE(recording.gaps.empty());
    std::size_t em = 0;
    for (const auto& row : recording.rows)
        em += row.em[0] ? 1U : 0U;
    EXPECT_EQ(em, suite.counters().em[0].delivered);
}

}  // namespace
