#pragma once
// reduced_table_writer — the firmware's Q16.16 constant tables from the reduced model's double
// data: every value rounded to nearest (Q16.16 raw = round(x * 2^16)), the slip signs apart as
// int8 (reduced_tables.hpp, "Format"), the FNV-1a checksum of
// firmware/kinetics/reduced_tables.hpp, and a C++ source file that defines
// scopekin::kinetics::default_reduced_tables() (declared in kinetics/default_reduced_tables.hpp).
// The output depends only on the data: the same training runs give the same bytes.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "model/reduction/reduced_model.hpp"

namespace scopekin::model {

struct ReducedTablesRaw {
    kinetics::ReducedModelHeader<std::int32_t> head;  ///< Q16.16 raw (counts and directions plain)
    std::vector<std::int32_t>
        knot_values;                       ///< knot records without slip signs, one after the other
    std::vector<std::int8_t> slid_values;  ///< the slip signs, [knot][station]
    std::vector<std::int32_t> compliance_values;  ///< compliance records one after the other
    std::uint32_t checksum = 0;
};

/// Q16.16 raw of x, rounded to nearest (ties away from zero). Throws ModelError naming `what` if
/// x is not finite or outside [-32768, 32768).
std::int32_t q16_raw(double x, const std::string& what);

/// Converts and checksums (throws ModelError for a value outside Q16.16).
ReducedTablesRaw to_q16_tables(const ReducedModelData& data);

/// Writes the C++ source (deterministic text; `provenance` goes into a comment and the tables'
/// source string).
void write_reduced_tables_source(const ReducedTablesRaw& tables, const std::string& provenance,
                                 std::ostream& out);

}  // namespace scopekin::model
