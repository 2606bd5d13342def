// scopekin_generate_reduced_tables SPEC.json OUTPUT.cpp [DOUBLE_OUTPUT.json]
// Build-time generator of the firmware's reduced model: runs the training runs of the reduction
// spec (model/reduction/training.json) in the full-order model (build_reduced_model), converts to
// Q16.16 (to_q16_tables) and writes the C++ source of default_reduced_tables(); with a third
// argument also the same data in double (reduced_model_json.hpp), which the accuracy tests compare
// the firmware with. Progress goes to stderr; each output is written to a temporary file and
// renamed, so an interrupted run never leaves a half-written table behind.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "model/model_error.hpp"
#include "model/reduction/reduced_model.hpp"
#include "model/reduction/reduced_model_json.hpp"
#include "model/reduction/reduced_table_writer.hpp"
#include "model/scenario/scenario.hpp"

namespace {

/// Writes `path` through a temporary file renamed into place.
template <typename Write>
void write_atomically(const std::filesystem::path& path, Write write) {
    using scopekin::model::ModelError;
    const std::filesystem::path temporary = path.string() + ".part";
    {
        std::ofstream file(temporary, std::ios::binary);
        if (!file) throw ModelError("cannot write " + temporary.string());
        write(file);
        if (!file.flush()) throw ModelError("cannot write " + temporary.string());
    }
    std::filesystem::rename(temporary, path);
}

}  // namespace

int main(int argc, char** argv) {
    using namespace scopekin::model;
    if (argc < 3 || argc > 4 || std::string(argv[1]) == "--help") {
        std::cerr
            << "usage: scopekin_generate_reduced_tables SPEC.json OUTPUT.cpp [DOUBLE_OUTPUT.json]\n"
               "Runs the training runs of the reduction spec (model/reduction/training.json) in\n"
               "the full-order model and writes the firmware's reduced-model tables (Q16.16,\n"
               "with checksum) as C++ source; DOUBLE_OUTPUT.json gets the same data in double.\n";
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
        write_atomically(out, [&](std::ostream& file) {
            write_reduced_tables_source(raw, provenance.str(), file);
        });
        if (argc == 4) {
            write_atomically(argv[3],
                             [&](std::ostream& file) { write_reduced_model_json(data, file); });
            std::cerr << "reduced tables: the same data in double -> " << argv[3] << "\n";
        }
        std::cerr << "reduced tables: " << raw.knot_values.size() + raw.compliance_values.size()
                  << " Q16.16 values and " << raw.slid_values.size() << " slip signs, checksum "
                  << raw.checksum << " -> " << out.string() << "\n";
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "scopekin_generate_reduced_tables: " << e.what() << "\n";
        return 1;
    }
}
