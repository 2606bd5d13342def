// scopekin_generate_reduced_tables TRAINING.json OUTPUT.cpp
// Build-time generator of the firmware's reduced model: runs the training scenario in the
// full-order model (build_reduced_model), converts to Q16.16 (to_q16_tables) and writes the C++
// source of default_reduced_tables(). Progress goes to stderr; the output is written to a
// temporary file and renamed, so an interrupted run never leaves a half-written table behind.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "model/model_error.hpp"
#include "model/reduction/reduced_model.hpp"
#include "model/reduction/reduced_table_writer.hpp"
#include "model/scenario/scenario.hpp"

int main(int argc, char** argv) {
  using namespace scopekin::model;
  if (argc != 3 || std::string(argv[1]) == "--help") {
    std::cerr << "usage: scopekin_generate_reduced_tables TRAINING.json OUTPUT.cpp\n"
                 "Runs the training scenario in the full-order model and writes the firmware's\n"
                 "reduced-model tables (Q16.16, with checksum) as C++ source.\n";
    return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 2;
  }
  try {
    const std::filesystem::path training_path(argv[1]);
    const Scenario training = read_scenario_file(training_path.string());
    const ReductionSettings settings;
    int last_percent = -1;
    const ReducedModelData data = build_reduced_model(training, settings, [&](const ReductionProgress& p) {
      const int percent = static_cast<int>(100.0 * p.depth_mm / p.end_depth_mm);
      if (percent / 10 != last_percent / 10) std::cerr << "reduced tables: depth " << p.depth_mm << " of " << p.end_depth_mm << " mm\n";
      last_percent = percent;
    });
    const ReducedTablesRaw raw = to_q16_tables(data);
    std::ostringstream provenance;
    provenance << "training " << training_path.filename().string() << ", " << settings.stations << " stations "
               << settings.station_spacing_mm << " mm apart, depth " << settings.depth_start_mm << ".."
               << settings.depth_end_mm << " mm every " << settings.depth_step_mm << " mm";
    const std::filesystem::path out(argv[2]);
    const std::filesystem::path temporary = out.string() + ".part";
    {
      std::ofstream file(temporary, std::ios::binary);
      if (!file) throw ModelError("cannot write " + temporary.string());
      write_reduced_tables_source(raw, provenance.str(), file);
      if (!file.flush()) throw ModelError("cannot write " + temporary.string());
    }
    std::filesystem::rename(temporary, out);
    std::cerr << "reduced tables: " << raw.values.size() << " values, checksum " << raw.checksum << " -> " << out.string() << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "scopekin_generate_reduced_tables: " << e.what() << "\n";
    return 1;
  }
}
