// BoxObserver (host_sim/simulator/box_observer.hpp): the box's own fault bits (BoxFault,
// TrackerFault) reach firmware.csv's last two columns and summary.json's "box" section (periods
// set, first time set), and the section carries the box's counters after the last period.
#include <gtest/gtest.h>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "host_sim/recording/recording_row.hpp"
#include "host_sim/simulator/box_observer.hpp"
#include "host_sim/simulator/firmware_loop.hpp"
#include "kinetics/kinetics_io.hpp"
#include "messages/box_faults.hpp"

namespace scopekin::host_sim {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        lines.push_back(line);
    return lines;
}

std::string last_cells(const std::string& line, int n) {
    std::size_t pos = line.size();
    for (int k = 0; k < n; ++k)
        pos = line.rfind(',', pos - 1);
    return line.substr(pos + 1);
}

/// The cell of `line` in the column that `header` names `name` ("" when there is none).
std::string cell(const std::string& header, const std::string& line, const std::string& name) {
    std::vector<std::string> names, cells;
    for (auto [text, out] : {std::pair{&header, &names}, std::pair{&line, &cells}}) {
        std::stringstream in(*text);
        for (std::string c; std::getline(in, c, ',');)
            out->push_back(c);
    }
    for (std::size_t i = 0; i < names.size() && i < cells.size(); ++i)
        if (names[i] == name) return cells[i];
    return {};
}

TEST(BoxObserver, BoxFaultBitsAreCountedWithTheirFirstTime) {
    // Six periods; counter_gap (bit 6) in the 2nd to 4th, receive_backlog (bit 14) in the 3rd.
    std::ostringstream csv;
    BoxObserver observer(&csv);
    const kinetics::Outputs outputs{};
    for (std::uint64_t k = 1; k <= 6; ++k) {
        std::uint16_t faults = 0;
        if (k >= 2 && k <= 4) faults |= messages::kBoxFaultCounterGap;
        if (k == 3) faults |= messages::kBoxFaultReceiveBacklog;
        observer.observe({k * 5000, &outputs, faults, nullptr});
    }
    const auto box = observer.box_section();
    EXPECT_EQ(box["periods"], 6);
    EXPECT_EQ(box["fault_periods"]["counter_gap"], 3);
    EXPECT_EQ(box["fault_periods"]["receive_backlog"], 1);
    EXPECT_EQ(box["fault_periods"]["force_torque_stale"], 0);
    EXPECT_DOUBLE_EQ(box["fault_first_s"]["counter_gap"].get<double>(), 0.010);
    EXPECT_DOUBLE_EQ(box["fault_first_s"]["receive_backlog"].get<double>(), 0.015);
    EXPECT_FALSE(box["fault_first_s"].contains("force_torque_stale"));  // never set
    EXPECT_TRUE(box["tracker_fault_first_s"].empty());
    EXPECT_FALSE(box.contains("counters"));  // no box given: its counters are unknown

    const auto lines = lines_of(csv.str());
    ASSERT_EQ(lines.size(), 7U);
    // box_faults, tracker_faults, then the eleven columns added after them (zero outputs here).
    EXPECT_EQ(last_cells(lines[0], 13),
              "box_faults,tracker_faults,tip_uncertainty_mm,model_tip_path_mm,"
              "model_log_likelihood_ratio,tip_from_model,observer_tip_path_mm,"
              "max_contact_force_uncertainty_N,model_max_contact_force_N,model_self_lock_alarm,"
              "loop_score,tip_from_tracker,model_contact_force_level");
    const std::string zeros = ",0.00000,0.00000,0.00000,0,0.00000,0.00000,0.00000,0,0.00000,0,0";
    EXPECT_EQ(last_cells(lines[1], 13), "0,0" + zeros);
    EXPECT_EQ(last_cells(lines[2], 13), "64,0" + zeros);
    EXPECT_EQ(last_cells(lines[3], 13), "16448,0" + zeros);  // 64 + 16384
    EXPECT_EQ(last_cells(lines[6], 13), "0,0" + zeros);
}

TEST(BoxObserver, TheBoxSectionCarriesTheBoxCountersAndItsTrackerFaults) {
    // The firmware in the loop on 100 ms of handle rows (no EM tracker data): the section's
    // counters are the box's, and every row's tracker_faults is the box's of that period.
    std::ostringstream csv;
    BoxObserver observer(&csv);
    std::vector<unsigned> tracker;
    FirmwareLoop loop([&](const BoxPeriod& p) {
        ASSERT_NE(p.box, nullptr);
        tracker.push_back(p.box->tracker_faults());
        observer.observe(p);
    });
    for (std::int64_t ms = 1; ms <= 100; ++ms) {
        recording::RecordingRow row;
        row.time_us = ms * 1000;
        row.handle = recording::ForceTorqueCells{1.0, 0.0};
        row.insertion_roll = recording::InsertionRollCells{100.0, 0.0};
        loop.deliver(row);
    }
    loop.finish(100'000);
    const auto box = observer.box_section();
    EXPECT_EQ(box["periods"], 20);
    EXPECT_EQ(box["counters"]["periods"], loop.box().counters().periods);
    EXPECT_EQ(box["counters"]["frames_read"], 200);  // 100 rows, two handle frames each
    EXPECT_EQ(box["handle_sensors"]["force_torque_samples"], 100);
    EXPECT_EQ(box["handle_sensors"]["counter_gaps"], 0);
    EXPECT_EQ(box["can"]["received"], loop.box().can_counters().received);
    EXPECT_EQ(box["em_tracker"]["poses_ok"], 0);
    // No EM tracker frame ever came: its sources are stale from the first period on.
    EXPECT_EQ(box["tracker_fault_periods"]["stale"], 20);
    EXPECT_DOUBLE_EQ(box["tracker_fault_first_s"]["stale"].get<double>(), 0.005);
    const auto lines = lines_of(csv.str());
    ASSERT_EQ(lines.size(), tracker.size() + 1);
    for (std::size_t k = 0; k < tracker.size(); ++k)
        EXPECT_EQ(cell(lines[0], lines[k + 1], "tracker_faults"), std::to_string(tracker[k]))
            << "period " << k;
}

}  // namespace
}  // namespace scopekin::host_sim
