#pragma once
// world.csv: the true state of the world at the scenario's output rate (model/scenario/README.md,
// "Outputs"): the handle, the tip and the extra nodes, contact statistics by region, and where
// the tip is along the colon with the wall force on it.
#include <ostream>
#include <string>
#include <vector>

#include "host_sim/simulator/world_readout.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::host_sim {

std::string world_csv_header(const model::Scenario& scenario,
                             const std::vector<std::size_t>& nodes);
void write_world_csv_row(std::ostream& out, const model::WorldRow& row,
                         const WorldReadout& readout);

/// contacts.csv (scenario outputs.contacts_file): one row per loaded contact per sample.
std::string contacts_csv_header();
void write_contacts_csv_rows(std::ostream& out, double time_s, const model::World& world);

/// procedure.csv: what the hand did, one row per world.csv row (the same time_s): its state
/// (a scripted action's name, or the physician's state), the commanded insertion speed and
/// roll, tip steering and the assistant's pressure on (1) or off (0).
std::string procedure_csv_header();
void write_procedure_csv_row(std::ostream& out, double time_s, const model::HandState& hand);

}  // namespace scopekin::host_sim
