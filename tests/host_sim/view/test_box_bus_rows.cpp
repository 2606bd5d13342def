// The box's display (host_sim/view/box_bus_rows.hpp): the frames the box sends, made with the
// protocol's encoders at values the DBC's resolutions carry exactly, become one row per period
// with those values; a StationForces frame fills its station until the next one for it; frames
// that do not decode are counted and change nothing; foreign and error frames are ignored.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "host_sim/view/box_bus_rows.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
namespace hal = scopekin::hal;
namespace protocol = scopekin::protocol;

struct Row {
    double time_s;
    nlohmann::ordered_json json;
};

Q16_16 tenths(std::int32_t n) {
    return Q16_16::from_ratio(n, 10);
}

TEST(BoxBusRows, APeriodsFramesBecomeOneRowWithTheirValues) {
    std::vector<Row> rows;
    scopekin::view::BoxBusRows display([&](double t, const nlohmann::ordered_json& row) {
        rows.push_back({t, row});
    });
    const std::uint64_t t0 = 5'000'000;
    protocol::HandleForceTorque handle{};
    handle.force_N = tenths(125);  // 12.5 N
    handle.torque_Nmm = tenths(-30);
    protocol::InsertionRoll insertion{};
    insertion.insertion_mm = Q16_16::from_int(412);
    display.feed(t0, protocol::encode(handle));
    display.feed(t0, protocol::encode(insertion));

    protocol::KineticEstimate estimate{};
    estimate.tip_path_mm = tenths(3875);  // 387.5 mm
    estimate.tip_uncertainty_mm = Q16_16::from_int(20);
    protocol::ContactSummary summary{};
    summary.max_contact_force_N = tenths(75);
    summary.active_stations = 3;
    protocol::Alarms alarms{};
    alarms.self_lock = true;
    alarms.contact_force_level = 2;
    alarms.valid = true;
    protocol::StationForces station{};
    station.station = 2;
    station.normal_force_N = tenths(15);
    station.path_mm = tenths(2875);
    protocol::BoxStatus status{};
    status.kinetic_faults = 1U << 3U;  // kFaultForceStale
    display.feed(t0 + 1000, protocol::encode(estimate));
    display.feed(t0 + 1000, protocol::encode(summary));
    display.feed(t0 + 1000, protocol::encode(alarms));
    display.feed(t0 + 1000, protocol::encode(station));
    display.feed(t0 + 1000, protocol::encode(status));
    EXPECT_TRUE(rows.empty()) << "the period is open until the next KineticEstimate";

    // The next period: its KineticEstimate closes the first.
    estimate.tip_path_mm = tenths(3880);
    display.feed(t0 + 6000, protocol::encode(estimate));
    ASSERT_EQ(rows.size(), 1U);
    const nlohmann::ordered_json& r = rows[0].json;
    EXPECT_DOUBLE_EQ(rows[0].time_s, 0.001);  // from the first frame heard
    EXPECT_NEAR(r["box_tip_path_mm"].get<double>(), 387.5, 1e-4);
    EXPECT_NEAR(r["box_tip_sd_mm"].get<double>(), 20.0, 1e-4);
    EXPECT_NEAR(r["box_max_force_N"].get<double>(), 7.5, 1e-4);
    EXPECT_NEAR(r["handle_force_N"].get<double>(), 12.5, 1e-4);
    EXPECT_NEAR(r["handle_torque_Nmm"].get<double>(), -3.0, 1e-4);
    EXPECT_NEAR(r["insertion_mm"].get<double>(), 412.0, 1e-4);
    EXPECT_EQ(r["self_lock"], 1);
    EXPECT_EQ(r["contact_level"], 2);
    EXPECT_EQ(r["fault_flags"], 8);
    ASSERT_EQ(r["stations"].size(), 1U) << "only the station heard so far";
    EXPECT_NEAR(r["stations"][0][0].get<double>(), 287.5, 1e-4);
    EXPECT_NEAR(r["stations"][0][1].get<double>(), 1.5, 1e-4);

    // A ContactSummary of the wrong length is refused and changes nothing; an error frame and a
    // foreign identifier are ignored.
    hal::CanFrame bad = protocol::encode(summary);
    bad.length = 3;
    display.feed(t0 + 6000, bad);
    hal::CanFrame error{};
    error.error = true;
    error.id = hal::kCanErrorBusError;
    display.feed(t0 + 6000, error);
    hal::CanFrame foreign{};
    foreign.id = 0x321;
    foreign.length = 1;
    display.feed(t0 + 6000, foreign);
    display.flush();
    ASSERT_EQ(rows.size(), 2U);
    EXPECT_NEAR(rows[1].json["box_tip_path_mm"].get<double>(), 388.0, 1e-4);
    EXPECT_NEAR(rows[1].json["box_max_force_N"].get<double>(), 7.5, 1e-4);
    EXPECT_EQ(display.periods(), 2U);
    EXPECT_EQ(display.refused(), 1U);
    EXPECT_EQ(display.ignored(), 2U);
    display.flush();
    EXPECT_EQ(rows.size(), 2U) << "no period open: nothing more";
}

}  // namespace
