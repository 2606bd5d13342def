// scopekin_generate_reduced_tables SPEC.json OUTPUT.cpp
// Build-time generator of the firmware's reduced model: runs the training runs of the reduction
// spec (model/reduction/training.json) in the full-order model (build_reduced_model), converts to Q16.16 (to_q16_tables) and writes the C++
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
        std::cerr
            << "usage: scopekin_generate_reduced_tables SPEC.json OUTPUT.cpp\n"
               "Runs the training runs of the reduction spec (model/reduction/training.json) in\n"
               "the full-order model and writes the firmware's reduced-model tables (Q16.16,\n"
               "with checksum) as C++ source.\n";
        return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 2;
    }
    try {
        const std::filesystem::path spec_path(argv[1]);
        const ReductionSettings settings = read_reduction_spec(spec_path.string());
        int last_tenth = -1;
        const ReducedModelData data =
            build_reduced_model(settings, [&](const ReductionProgress& p) {
                const int tenth = static_cast<int>(10 * p.knot / p.knots);
                if (tenth != last_tenth || p.knot == p.knots)
                    std::cerr << "reduced tables: training run " << p.segment + 1 << " of "
                              << p.segments << ", knot " << p.knot << " of " << p.knots << "\n";
                last_tenth = tenth;
            });
        const ReducedTablesRaw raw = to_q16_tables(data);
        std::ostringstream provenance;
        provenance << "spec " << spec_path.filename().string() << ": " << settings.stations
                   << " stations " << settings.station_spacing_mm << " mm apart";
        for (const ReductionSegmentSpec& s : settings.segments)
            provenance << "; " << std::filesystem::path(s.scenario.source).filename().string()
                       << " " << (s.direction > 0 ? "advancing " : "withdrawing ")
                       << s.depth_from_mm << ".." << s.depth_to_mm << " mm every " << s.step_mm
                       << " mm";
        const std::filesystem::path out(argv[2]);
        const std::filesystem::path temporary = out.string() + ".part";
        {
            std::ofstream file(temporary, std::ios::binary);
            if (!file) throw ModelError("cannot write " + temporary.string());
            write_reduced_tables_source(raw, provenance.str(), file);
            if (!file.flush()) throw ModelError("cannot write " + temporary.string());
        }
        std::filesystem::rename(temporary, out);
        std::cerr << "reduced tables: " << raw.knot_values.size() + raw.compliance_values.size()
                  << " values, checksum " << raw.checksum << " -> " << out.string() << "\n";
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "scopekin_generate_reduced_tables: " << e.what() << "\n";
        return 1;
    }
}
