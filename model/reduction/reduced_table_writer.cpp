#include "model/reduction/reduced_table_writer.hpp"

#include <cmath>
#include <ostream>

#include "kinetics/reduced_tables.hpp"  // firmware/: the checksum the firmware checks at init
#include "model/model_error.hpp"

namespace scopekin::model {

std::int32_t q16_raw(double x, const std::string& what) {
    const double scaled = x * 65536.0;
    if (!std::isfinite(scaled) || scaled >= 2147483647.5 || scaled < -2147483648.5)
        throw ModelError(what + ": " + number_text(x) + " does not fit Q16.16 ([-32768, 32768))");
    // Ties away from zero, as the firmware's own rounding (q_format.hpp).
    const double rounded = scaled < 0.0 ? -std::floor(-scaled + 0.5) : std::floor(scaled + 0.5);
    return static_cast<std::int32_t>(rounded);
}

namespace {

template <typename From, typename To, typename Convert>
kinetics::ReducedModelHeader<To> convert_header(const kinetics::ReducedModelHeader<From>& h,
                                                Convert convert) {
    kinetics::ReducedModelHeader<To> out;
    out.stations = h.stations;
    out.compliance_every = h.compliance_every;
    out.friction = convert(h.friction, "friction");
    out.station_spacing_mm = convert(h.station_spacing_mm, "station_spacing_mm");
    out.segment_count = h.segment_count;
    for (std::size_t i = 0; i < kinetics::kMaxReducedSegments; ++i) {
        const auto& s = h.segments[i];
        auto& o = out.segments[i];
        o.kind = s.kind;
        o.direction = s.direction;
        o.key_start = convert(s.key_start, "segment key_start");
        o.key_step = convert(s.key_step, "segment key_step");
        o.hold_depth_mm = convert(s.hold_depth_mm, "segment hold_depth_mm");
        o.knots = s.knots;
        o.first_knot = s.first_knot;
        o.first_compliance = s.first_compliance;
    }
    return out;
}

void append_records(const std::vector<std::vector<double>>& records, std::size_t size,
                    const char* what, std::vector<std::int32_t>& out) {
    for (std::size_t g = 0; g < records.size(); ++g) {
        if (records[g].size() != size)
            throw ModelError(std::string("reduced model: ") + what + " record " +
                             std::to_string(g) + " has the wrong size");
        for (std::size_t i = 0; i < size; ++i)
            out.push_back(q16_raw(records[g][i], std::string(what) + " record " +
                                                     std::to_string(g) + " value " +
                                                     std::to_string(i)));
    }
}

/// The knot records in the firmware's stored layout: each station's values but its slip sign,
/// then the knot values; the signs apart (exactly -1, 0 or +1, else ModelError).
void append_knots(const std::vector<std::vector<double>>& knots, std::size_t stations,
                  ReducedTablesRaw& raw) {
    const std::size_t size = kinetics::reduced_knot_size(stations);
    for (std::size_t g = 0; g < knots.size(); ++g) {
        if (knots[g].size() != size)
            throw ModelError("reduced model: knot record " + std::to_string(g) +
                             " has the wrong size");
        const std::string where = "knot record " + std::to_string(g) + " value ";
        for (std::size_t j = 0; j < stations; ++j) {
            const std::size_t base = j * kinetics::kStationValueCount;
            for (std::size_t v = 0; v < kinetics::kStationSlid; ++v)
                raw.knot_values.push_back(
                    q16_raw(knots[g][base + v], where + std::to_string(base + v)));
            const double sign = knots[g][base + kinetics::kStationSlid];
            if (sign != -1.0 && sign != 0.0 && sign != 1.0)
                throw ModelError("reduced model: " + where +
                                 std::to_string(base + kinetics::kStationSlid) +
                                 ": a slip sign must be -1, 0 or 1, not " + number_text(sign));
            raw.slid_values.push_back(static_cast<std::int8_t>(sign));
        }
        for (std::size_t v = 0; v < kinetics::kKnotValueCount; ++v) {
            const std::size_t index = stations * kinetics::kStationValueCount + v;
            raw.knot_values.push_back(q16_raw(knots[g][index], where + std::to_string(index)));
        }
    }
}

template <typename Int>
void write_array(std::ostream& out, const char* type, const char* name,
                 const std::vector<Int>& values, std::size_t record, const char* label) {
    out << "constexpr " << type << " " << name << "[" << values.size() << "] = {\n";
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (i % record == 0) out << "    // " << label << ' ' << i / record << "\n   ";
        out << ' ' << static_cast<long long>(values[i]) << ',';
        if (i % 8 == 7 || i % record == record - 1)
            out << '\n' << (i % record == record - 1 ? "" : "   ");
    }
    out << "};\n\n";
}

std::string q16_text(std::int32_t raw) {
    return "Q16_16::from_raw(" + std::to_string(raw) + ")";
}

}  // namespace

ReducedTablesRaw to_q16_tables(const ReducedModelData& data) {
    ReducedTablesRaw raw;
    raw.head = convert_header<double, std::int32_t>(
        data.header(), [](double x, const char* what) { return q16_raw(x, what); });
    const std::size_t k = data.header().stations;
    append_knots(data.knots, k, raw);
    append_records(data.compliances, kinetics::reduced_compliance_size(k), "compliance",
                   raw.compliance_values);
    kinetics::ReducedTablesQ16 view;
    view.head = convert_header<std::int32_t, fixed_point::Q16_16>(
        raw.head, [](std::int32_t x, const char*) { return fixed_point::Q16_16::from_raw(x); });
    view.knot_values = raw.knot_values.data();
    view.knot_value_count = raw.knot_values.size();
    view.slid_values = raw.slid_values.data();
    view.slid_value_count = raw.slid_values.size();
    view.compliance_values = raw.compliance_values.data();
    view.compliance_value_count = raw.compliance_values.size();
    raw.checksum = kinetics::reduced_tables_checksum(view);
    view.checksum = raw.checksum;
    const kinetics::ReducedTablesFault fault = kinetics::check_reduced_tables(&view, k);
    if (fault != kinetics::ReducedTablesFault::none)
        throw ModelError("reduced model: the tables fail the firmware's own check (fault " +
                         std::to_string(static_cast<int>(fault)) +
                         ", reduced_tables.hpp ReducedTablesFault)");
    return raw;
}

void write_reduced_tables_source(const ReducedTablesRaw& t, const std::string& provenance,
                                 std::ostream& out) {
    const std::size_t k = t.head.stations;
    out << "// GENERATED by scopekin_generate_reduced_tables (model/reduction) — do not edit.\n"
        << "// " << provenance << "\n"
        << "// " << t.knot_values.size() / kinetics::reduced_stored_knot_size(k)
        << " knot records x " << kinetics::reduced_stored_knot_size(k) << " Q16.16 values and " << k
        << " int8 slip signs, and "
        << t.compliance_values.size() / kinetics::reduced_compliance_size(k)
        << " compliance records x " << kinetics::reduced_compliance_size(k)
        << " Q16.16 values (reduced_tables.hpp, \"Format\").\n"
        << "#include \"kinetics/default_reduced_tables.hpp\"\n\n"
        << "namespace scopekin::kinetics {\n\nnamespace {\n\n";
    write_array(out, "std::int32_t", "kKnotValues", t.knot_values,
                kinetics::reduced_stored_knot_size(k), "knot");
    write_array(out, "std::int8_t", "kSlidValues", t.slid_values, k, "knot");
    write_array(out, "std::int32_t", "kComplianceValues", t.compliance_values,
                kinetics::reduced_compliance_size(k), "compliance record");
    out << "constexpr ReducedTablesQ16 kTables{\n"
        << "    {" << k << "U, " << t.head.compliance_every << "U, " << q16_text(t.head.friction)
        << ", " << q16_text(t.head.station_spacing_mm) << ", " << t.head.segment_count
        << "U,\n     {{\n";
    for (std::size_t i = 0; i < kinetics::kMaxReducedSegments; ++i) {
        const auto& s = t.head.segments[i];
        out << "         {" << s.kind << ", " << s.direction << ", " << q16_text(s.key_start)
            << ", " << q16_text(s.key_step) << ", " << q16_text(s.hold_depth_mm) << ", " << s.knots
            << "U, " << s.first_knot << "U, " << s.first_compliance << "U},\n";
    }
    out << "     }}},\n"
        << "    kKnotValues,\n    " << t.knot_values.size() << "U,\n"
        << "    kSlidValues,\n    " << t.slid_values.size() << "U,\n"
        << "    kComplianceValues,\n    " << t.compliance_values.size() << "U,\n"
        << "    " << t.checksum << "U,\n"
        << "    \"" << provenance << "\",\n};\n\n}  // namespace\n\n"
        << "const ReducedTablesQ16& default_reduced_tables() noexcept { return kTables; }\n\n"
        << "}  // namespace scopekin::kinetics\n";
}

}  // namespace scopekin::model
