#pragma once
// firmware.csv: the box's estimator outputs, one row per period (host_sim/README.md, "Commands"),
// then the box's own fault bits of the period (box_faults: messages::BoxFault, tracker_faults:
// messages::TrackerFault, as BoxStatus carries them). Q16.16 values are printed with 5 decimals,
// enough to give back the raw value exactly (|error| <= 5e-6 < half of 2^-16), so two files are
// equal exactly when the outputs are.
#include <cstdint>
#include <ostream>
#include <string>

#include "kinetics/kinetics_io.hpp"

namespace scopekin::host_sim {

std::string firmware_csv_header();
std::string firmware_csv_row(std::uint64_t time_us, const kinetics::Outputs& outputs,
                             std::uint16_t box_faults, std::uint8_t tracker_faults);

}  // namespace scopekin::host_sim
