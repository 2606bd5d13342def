#include "model/reduction/reduced_model_json.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <ostream>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

nlohmann::json segment_json(const kinetics::ReducedSegment<double>& s) {
    return {{"kind", s.kind},
            {"direction", s.direction},
            {"key_start", s.key_start},
            {"key_step", s.key_step},
            {"hold_depth_mm", s.hold_depth_mm},
            {"knots", s.knots},
            {"first_knot", s.first_knot},
            {"first_compliance", s.first_compliance}};
}

kinetics::ReducedSegment<double> read_segment(const io::JsonObject& o) {
    o.allow_only({"kind", "direction", "key_start", "key_step", "hold_depth_mm", "knots",
                  "first_knot", "first_compliance"});
    kinetics::ReducedSegment<double> s;
    s.kind = static_cast<int>(o.index("kind"));
    const double direction = o.number("direction");
    if (direction != 1.0 && direction != -1.0)
        throw ModelError(o.field("direction") + ": must be 1 or -1");
    s.direction = static_cast<int>(direction);
    s.key_start = o.number("key_start");
    s.key_step = o.number("key_step");
    s.hold_depth_mm = o.number("hold_depth_mm");
    s.knots = o.index("knots");
    s.first_knot = o.index("first_knot");
    s.first_compliance = o.index("first_compliance");
    return s;
}

/// Records of `size` finite numbers each.
std::vector<std::vector<double>> read_records(const io::JsonObject& root, const char* key,
                                              std::size_t size) {
    const nlohmann::json& array = root.array(key);
    std::vector<std::vector<double>> records;
    records.reserve(array.size());
    for (std::size_t r = 0; r < array.size(); ++r) {
        const std::string where = root.field(key) + "[" + std::to_string(r) + "]";
        const nlohmann::json& record = array[r];
        if (!record.is_array() || record.size() != size)
            throw ModelError(where + ": must be an array of " + std::to_string(size) + " numbers");
        std::vector<double>& values = records.emplace_back(size);
        for (std::size_t i = 0; i < size; ++i) {
            if (!record[i].is_number() || !std::isfinite(record[i].get<double>()))
                throw ModelError(where + "[" + std::to_string(i) + "]: must be a finite number");
            values[i] = record[i].get<double>();
        }
    }
    return records;
}

void require_match(const io::JsonObject& root, const char* key, double in_file, double in_spec) {
    if (in_file != in_spec)
        throw ModelError(root.field(key) + ": " + std::to_string(in_file) + " in the file, " +
                         std::to_string(in_spec) + " in the spec (made by another spec?)");
}

}  // namespace

void write_reduced_model_json(const ReducedModelData& data, std::ostream& out) {
    nlohmann::json segments = nlohmann::json::array();
    for (std::size_t i = 0; i < data.head.segment_count; ++i)
        segments.push_back(segment_json(data.head.segments[i]));
    const nlohmann::json root = {
        {"stations", data.head.stations}, {"compliance_every", data.head.compliance_every},
        {"friction", data.head.friction}, {"station_spacing_mm", data.head.station_spacing_mm},
        {"segments", segments},           {"knots", data.knots},
        {"compliances", data.compliances}};
    out << root.dump() << "\n";
}

ReducedModelData read_reduced_model_json(const std::string& path,
                                         const ReductionSettings& settings) {
    const nlohmann::json parsed = io::parse_json_file(path);
    const io::JsonObject root(parsed, path + ":");
    root.allow_only({"stations", "compliance_every", "friction", "station_spacing_mm", "segments",
                     "knots", "compliances"});
    ReducedModelData data;
    data.settings = settings;
    data.head.stations = root.index("stations");
    data.head.compliance_every = root.index("compliance_every");
    data.head.friction = root.number("friction");
    data.head.station_spacing_mm = root.number("station_spacing_mm");
    require_match(root, "stations", static_cast<double>(data.head.stations),
                  static_cast<double>(settings.stations));
    require_match(root, "station_spacing_mm", data.head.station_spacing_mm,
                  settings.station_spacing_mm);
    require_match(root, "compliance_every", static_cast<double>(data.head.compliance_every),
                  static_cast<double>(settings.compliance_every));
    const nlohmann::json& segments = root.array("segments");
    require_match(root, "segments", static_cast<double>(segments.size()),
                  static_cast<double>(settings.segments.size()));
    if (segments.size() > data.head.segments.size())
        throw ModelError(root.field("segments") + ": more than the tables hold");
    data.head.segment_count = segments.size();
    for (std::size_t i = 0; i < segments.size(); ++i) {
        const std::string where = root.field("segments") + "[" + std::to_string(i) + "]";
        if (!segments[i].is_object()) throw ModelError(where + ": must be an object");
        data.head.segments[i] = read_segment(io::JsonObject(segments[i], where));
    }
    data.knots = read_records(root, "knots", kinetics::reduced_knot_size(data.head.stations));
    data.compliances =
        read_records(root, "compliances", kinetics::reduced_compliance_size(data.head.stations));
    for (std::size_t i = 0; i < data.head.segment_count; ++i) {
        const kinetics::ReducedSegment<double>& s = data.head.segments[i];
        const std::size_t records = (s.knots - 1) / data.head.compliance_every + 1;
        if (s.knots < 2 || s.first_knot + s.knots > data.knots.size() ||
            s.first_compliance + records > data.compliances.size())
            throw ModelError(root.field("segments") + "[" + std::to_string(i) +
                             "]: its records lie outside the file's knots or compliances");
    }
    return data;
}

}  // namespace scopekin::model
