// protocol_codec_tool.cpp — the box's typed CAN encoders/decoders behind a JSON-lines interface,
// for tests/hal/can/check_dbc.py (which checks them against scopekin.dbc with python3-canmatrix).
//
// One JSON object per line on stdin, one answer per line on stdout:
//   {"cmd":"layouts"}
//     -> {"messages":[{"name","id","length","signals":[{"name","start_bit","bit_length",
//         "signed","factor_num","factor_den"}...]}...], "mapped":[message names the tool maps]}
//   {"cmd":"encode","message":NAME,"values":{SIGNAL: physical value, ...}}
//     -> {"id","length","extended","remote","error_frame","data":"hex of `length` bytes",
//         "tail_zero": bytes past `length` are 0, "saturated":[signals clamped to Q16.16]}
//   {"cmd":"decode","message":NAME,"data":"hex" [,"id":N,"extended":b,"remote":b,"error_frame":b]}
//     -> {"result":"ok|wrong_id|not_data|bad_length|out_of_range","values":{SIGNAL: value},
//         "untouched": the output struct is unchanged (expected whenever result != ok)}
//   anything wrong with a request -> {"error":"..."} (and the tool carries on).
//
// The typed codecs (protocol::encode(const T&) / protocol::decode(frame, T&)) are what is tested,
// so values travel through the message STRUCTS: physical doubles become Q16.16 fields with
// Q16_16::from_raw(llround(v * 65536)) (exact: a Q16.16 value is a double with 16 fraction bits),
// integers, flags and enumerations go into their fields as such.  The mapping between the
// structs' fields and the DBC's signal names is written by hand below (bind() per message): that
// mapping is part of what the check verifies — a field wired to the wrong signal shows up as a
// mismatch against canmatrix.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "hal/can_bus.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

using nlohmann::json;
using scopekin::hal::CanFrame;
using namespace scopekin::protocol;  // NOLINT(google-build-using-namespace): test tool

// ---- field <-> signal mapping (by hand, from scopekin.dbc and scopekin_messages.hpp) ----------

// Each bind() names every signal of the message and the struct field that carries it.  A Visitor
// has q16(name, Q16_16&), integer(name, unsigned field&), flag(name, bool&), enumeration(name,
// enum&).
template <typename Visitor>
void bind(Visitor& v, HandleForceTorque& m) {
    v.q16("HandleForce", m.force_N);
    v.q16("HandleTorque", m.torque_Nmm);
    v.integer("CellStatus", m.status);
    v.integer("CellCounter", m.counter);
}

template <typename Visitor>
void bind(Visitor& v, InsertionRoll& m) {
    v.q16("Insertion", m.insertion_mm);
    v.q16("Roll", m.roll_rad);
    v.integer("EncoderStatus", m.status);
    v.integer("EncoderCounter", m.counter);
}

template <typename Visitor>
void bind(Visitor& v, BoxStatus& m) {
    v.integer("HeartbeatCounter", m.heartbeat);
    v.enumeration("BoxState", m.state);
    v.enumeration("CanState", m.can_state);
    v.integer("KineticFaults", m.kinetic_faults);
    v.integer("DriverFaults", m.driver_faults);
    v.integer("PeriodOverruns", m.period_overruns);
    v.integer("TrackerFaults", m.tracker_faults);
}

template <typename Visitor>
void bind(Visitor& v, KineticEstimate& m) {
    v.q16("TipPath", m.tip_path_mm);
    v.q16("TipVelocity", m.tip_velocity_mm_per_s);
    v.q16("AdvanceEfficiency", m.advance_efficiency);
    v.flag("EstimateValid", m.estimate_valid);
    v.flag("InputsStale", m.inputs_stale);
    v.flag("DepthClamped", m.depth_clamped);
    v.q16("TipUncertainty", m.tip_uncertainty_mm);
    v.integer("StepCounter", m.step_counter);
}

template <typename Visitor>
void bind(Visitor& v, ContactSummary& m) {
    v.q16("MaxContactForce", m.max_contact_force_N);
    v.q16("MaxContactPath", m.max_contact_path_mm);
    v.integer("MaxContactStation", m.max_contact_station);
    v.integer("ActiveStations", m.active_stations);
    v.integer("DistalSticking", m.distal_sticking);
    v.integer("StickingMask", m.sticking_mask);
    v.integer("StepCounter", m.step_counter);
}

template <typename Visitor>
void bind(Visitor& v, Alarms& m) {
    v.flag("SelfLockAlarm", m.self_lock);
    v.integer("ContactForceLevel", m.contact_force_level);
    v.flag("AlarmsValid", m.valid);
    v.flag("TipFromModel", m.tip_from_model);
    v.integer("SelfLockRaised", m.self_lock_raised);
    v.integer("CriticalRaised", m.critical_raised);
    v.integer("StepCounter", m.step_counter);
}

template <typename Visitor>
void bind(Visitor& v, BoxCounter& m) {
    v.enumeration("CounterIndex", m.index);
    v.integer("CounterValue", m.value);
}

template <typename Visitor>
void bind(Visitor& v, EstimateEvidence& m) {
    v.q16("MaxContactForceUncertainty", m.max_contact_force_uncertainty_N);
    v.q16("LoopScore", m.loop_score);
    v.q16("ModelLogLikelihoodRatio", m.model_log_likelihood_ratio);
    v.flag("ModelSelfLockAlarm", m.model_self_lock);
    v.flag("TipFromTracker", m.tip_from_tracker);
    v.integer("StepCounter", m.step_counter);
}

template <typename Visitor>
void bind(Visitor& v, StationForces& m) {
    v.integer("StationIndex", m.station);
    v.integer("StationState", m.state);
    v.q16("StationNormalForce", m.normal_force_N);
    v.q16("StationTangentialForce", m.tangential_force_N);
    v.q16("StationPath", m.path_mm);
    v.q16("StationArc", m.arc_from_tip_mm);
}

// ---- visitors -----------------------------------------------------------------------------------

constexpr double kQ16One = 65536.0;

/// Struct -> {"Signal": physical value}.  Q16.16 values as doubles (exact: 16 fraction bits).
class ToJson {
public:
    json values = json::object();

    void q16(const char* name, const Q16_16& field) {
        values[name] = static_cast<double>(field.raw()) / kQ16One;
    }
    template <typename Unsigned>
    void integer(const char* name, const Unsigned& field) {
        static_assert(std::is_unsigned_v<Unsigned>);
        values[name] = static_cast<std::uint64_t>(field);
    }
    void flag(const char* name, const bool& field) { values[name] = field ? 1 : 0; }
    template <typename Enum>
    void enumeration(const char* name, const Enum& field) {
        values[name] = static_cast<std::uint64_t>(static_cast<std::underlying_type_t<Enum>>(field));
    }
};

/// {"Signal": physical value} -> struct.  Every signal of the message must be given, and nothing
/// else; integers must fit their field (the tool never wraps silently).
class FromJson {
public:
    explicit FromJson(const json& values) : values_(values) {
        if (!values_.is_object()) {
            throw std::runtime_error("\"values\" must be an object");
        }
    }

    std::vector<std::string> saturated;

    void q16(const char* name, Q16_16& field) {
        const double scaled = number(name).get<double>() * kQ16One;
        if (!std::isfinite(scaled)) {
            throw std::runtime_error(std::string{"not finite: "} + name);
        }
        // Round half away from zero (llround's rule), then saturate to Q16.16 like the firmware;
        // a value that does not fit is reported (the check expects the encoder's saturation).
        const double rounded = std::round(scaled);
        constexpr double kMax = std::numeric_limits<std::int32_t>::max();
        constexpr double kMin = std::numeric_limits<std::int32_t>::min();
        std::int32_t raw = 0;
        if (rounded > kMax) {
            raw = std::numeric_limits<std::int32_t>::max();
            saturated.emplace_back(name);
        } else if (rounded < kMin) {
            raw = std::numeric_limits<std::int32_t>::min();
            saturated.emplace_back(name);
        } else {
            raw = static_cast<std::int32_t>(std::llround(scaled));
        }
        field = Q16_16::from_raw(raw);
    }
    template <typename Unsigned>
    void integer(const char* name, Unsigned& field) {
        static_assert(std::is_unsigned_v<Unsigned>);
        field = checked<Unsigned>(name);
    }
    void flag(const char* name, bool& field) {
        const auto value = checked<std::uint8_t>(name);
        if (value > 1U) {
            throw std::runtime_error(std::string{"flag must be 0 or 1: "} + name);
        }
        field = value != 0U;
    }
    template <typename Enum>
    void enumeration(const char* name, Enum& field) {
        // Any value of the underlying type (undefined enumerators included: they are what the
        // encoder must still put on the wire bit-exactly, and the decoder must refuse).
        field = static_cast<Enum>(checked<std::underlying_type_t<Enum>>(name));
    }

    /// Throws if `values` has a key no bind() call named.
    void check_all_used() const {
        for (const auto& item : values_.items()) {
            if (used_.count(item.key()) == 0U) {
                throw std::runtime_error("no such signal in this message: " + item.key());
            }
        }
    }

private:
    const json& number(const char* name) {
        const auto it = values_.find(name);
        if (it == values_.end()) {
            throw std::runtime_error(std::string{"missing signal: "} + name);
        }
        if (!it->is_number()) {
            throw std::runtime_error(std::string{"not a number: "} + name);
        }
        used_.insert(name);
        return *it;
    }
    template <typename Unsigned>
    Unsigned checked(const char* name) {
        const json& value = number(name);
        if (!value.is_number_integer()) {
            throw std::runtime_error(std::string{"not an integer: "} + name);
        }
        if (value.is_number_unsigned()) {
            const auto v = value.get<std::uint64_t>();
            if (v <= std::numeric_limits<Unsigned>::max()) {
                return static_cast<Unsigned>(v);
            }
        } else {
            const auto v = value.get<std::int64_t>();
            if (v >= 0 && static_cast<std::uint64_t>(v) <= std::numeric_limits<Unsigned>::max()) {
                return static_cast<Unsigned>(v);
            }
        }
        throw std::runtime_error(std::string{"does not fit its field: "} + name + " = " +
                                 value.dump());
    }

    const json& values_;
    std::set<std::string> used_;
};

// ---- frames <-> JSON ------------------------------------------------------------------------------

std::string to_hex(const std::uint8_t* bytes, std::size_t count) {
    static constexpr char kDigits[] = "0123456789ABCDEF";
    std::string text;
    for (std::size_t i = 0; i < count; ++i) {
        text.push_back(kDigits[bytes[i] >> 4U]);
        text.push_back(kDigits[bytes[i] & 0xFU]);
    }
    return text;
}

int hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

const char* result_name(DecodeResult result) {
    switch (result) {
        case DecodeResult::ok: return "ok";
        case DecodeResult::wrong_id: return "wrong_id";
        case DecodeResult::not_data: return "not_data";
        case DecodeResult::bad_length: return "bad_length";
        case DecodeResult::out_of_range: return "out_of_range";
    }
    return "unknown";
}

template <typename Message>
json encode_message(const json& request) {
    Message message{};
    FromJson reader{request.at("values")};
    bind(reader, message);
    reader.check_all_used();
    const CanFrame frame = encode(message);  // the typed encoder under test
    bool tail_zero = true;
    for (std::size_t i = frame.length; i < frame.data.size(); ++i) {
        tail_zero = tail_zero && frame.data[i] == 0U;
    }
    json answer;
    answer["id"] = frame.id;
    answer["length"] = frame.length;
    answer["extended"] = frame.extended;
    answer["remote"] = frame.remote;
    answer["error_frame"] = frame.error;
    answer["data"] = to_hex(frame.data.data(), frame.length <= 8U ? frame.length : 8U);
    answer["tail_zero"] = tail_zero;
    answer["saturated"] = reader.saturated;
    return answer;
}

/// Fills every field with recognisable, non-default content (the decoder's output before a
/// decode: refusals must leave it as is).
class Filler {
public:
    void q16(const char*, Q16_16& field) {
        field = Q16_16::from_raw(static_cast<std::int32_t>(step() >> 1U));
    }
    template <typename Unsigned>
    void integer(const char*, Unsigned& field) {
        field = static_cast<Unsigned>(step());
    }
    void flag(const char*, bool& field) { field = true; }
    template <typename Enum>
    void enumeration(const char*, Enum& field) {
        field = static_cast<Enum>(static_cast<std::underlying_type_t<Enum>>(step()));
    }

private:
    std::uint32_t step() { return state_ = state_ * 1664525U + 1013904223U; }
    std::uint32_t state_ = 0x5A5A5A5AU;
};

template <typename Message>
Message sentinel() {
    Message message{};
    Filler filler;
    bind(filler, message);
    return message;
}

template <typename Message>
json values_of(Message message) {
    ToJson writer;
    bind(writer, message);
    return writer.values;
}

template <typename Message>
json decode_message(const CanFrame& frame) {
    Message message = sentinel<Message>();
    const json before = values_of(message);
    const DecodeResult result = decode(frame, message);  // the typed decoder under test
    json answer;
    answer["result"] = result_name(result);
    answer["values"] = values_of(message);
    answer["untouched"] = answer["values"] == before;
    return answer;
}

struct Entry {
    const char* name;
    std::uint32_t id;
    json (*encode)(const json& request);
    json (*decode)(const CanFrame& frame);
};

template <typename Message>
constexpr Entry entry(const char* name, std::uint32_t id) {
    return Entry{name, id, &encode_message<Message>, &decode_message<Message>};
}

const Entry kEntries[] = {
    entry<HandleForceTorque>("HandleForceTorque", kHandleForceTorqueId),
    entry<InsertionRoll>("InsertionRoll", kInsertionRollId),
    entry<BoxStatus>("BoxStatus", kBoxStatusId),
    entry<KineticEstimate>("KineticEstimate", kKineticEstimateId),
    entry<ContactSummary>("ContactSummary", kContactSummaryId),
    entry<Alarms>("Alarms", kAlarmsId),
    entry<BoxCounter>("BoxCounters", kBoxCountersId),
    entry<EstimateEvidence>("EstimateEvidence", kEstimateEvidenceId),
    entry<StationForces>("StationForces", kStationForcesId),
};

const Entry& find_entry(const json& request) {
    const std::string name = request.at("message").get<std::string>();
    for (const Entry& e : kEntries) {
        if (name == e.name) {
            return e;
        }
    }
    throw std::runtime_error("unknown message: " + name);
}

CanFrame frame_from(const json& request, const Entry& e) {
    CanFrame frame{};
    frame.id = request.contains("id") ? request.at("id").get<std::uint32_t>() : e.id;
    frame.extended = request.value("extended", false);
    frame.remote = request.value("remote", false);
    frame.error = request.value("error_frame", false);
    const std::string hex = request.at("data").get<std::string>();
    if (hex.size() % 2U != 0U || hex.size() / 2U > frame.data.size()) {
        throw std::runtime_error("data: 0..8 bytes as hex pairs");
    }
    for (std::size_t i = 0; i < hex.size() / 2U; ++i) {
        const int high = hex_digit(hex[2U * i]);
        const int low = hex_digit(hex[2U * i + 1U]);
        if (high < 0 || low < 0) {
            throw std::runtime_error("data: not hex");
        }
        frame.data[i] = static_cast<std::uint8_t>((high << 4) | low);
    }
    frame.length = static_cast<std::uint8_t>(hex.size() / 2U);
    return frame;
}

json layouts() {
    json messages = json::array();
    for (const MessageLayout& layout : message_layouts()) {
        json signals = json::array();
        for (const CanSignal& signal : layout.signals) {
            signals.push_back({{"name", signal.name},
                               {"start_bit", signal.start_bit},
                               {"bit_length", signal.bit_length},
                               {"signed", signal.is_signed},
                               {"factor_num", signal.factor_numerator},
                               {"factor_den", signal.factor_denominator}});
        }
        messages.push_back({{"name", layout.name},
                            {"id", layout.id},
                            {"length", layout.length},
                            {"signals", signals}});
    }
    json mapped = json::array();
    for (const Entry& e : kEntries) {
        mapped.push_back({{"name", e.name}, {"id", e.id}});
    }
    return {{"messages", messages}, {"mapped", mapped}};
}

json handle(const json& request) {
    const std::string command = request.at("cmd").get<std::string>();
    if (command == "layouts") {
        return layouts();
    }
    if (command == "encode") {
        return find_entry(request).encode(request);
    }
    if (command == "decode") {
        const Entry& e = find_entry(request);
        return e.decode(frame_from(request, e));
    }
    throw std::runtime_error("unknown cmd: " + command);
}

}  // namespace

int main() {
    std::ios::sync_with_stdio(false);
    std::string line;
    while (std::getline(std::cin, line)) {
        if (line.empty()) {
            continue;
        }
        json answer;
        try {
            answer = handle(json::parse(line));
        } catch (const std::exception& e) {
            answer = json{{"error", e.what()}};
        }
        std::cout << answer.dump() << '\n' << std::flush;
    }
    return 0;
}
