#pragma once
// reduced_model_json — the reduced model's double data (ReducedModelData: header, knot and
// compliance records) written to and read back from JSON, exactly: nlohmann-json writes each double
// with the shortest decimal that reads back to the same bits.
//
// Why: building the data runs every training run in the full-order model (about a minute); the
// build does it once for the firmware's Q16.16 tables (scopekin_generate_reduced_tables), and the
// tests that compare the firmware with the same model in double read that run's data instead of
// repeating it.
#include <iosfwd>
#include <string>

#include "model/reduction/reduced_model.hpp"

namespace scopekin::model {

/// Writes `data`'s header and records (not its settings: the reader takes them from the spec).
void write_reduced_model_json(const ReducedModelData& data, std::ostream& out);

/// Reads a file written by write_reduced_model_json for the reduction spec `settings` (whose
/// training runs made it). Throws ModelError naming the file and field for a malformed file, a
/// record of the wrong length, a value that is not a finite number, or a header that does not
/// match `settings` (stations, station spacing, compliance interval, segment count).
ReducedModelData read_reduced_model_json(const std::string& path,
                                         const ReductionSettings& settings);

}  // namespace scopekin::model
