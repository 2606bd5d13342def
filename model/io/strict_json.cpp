#include "model/io/strict_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include "model/model_error.hpp"

namespace scopekin::model::io {

namespace {

/// A UTF-8 continuation byte (10xxxxxx): not the start of a character.
bool continuation(char c) {
    return (static_cast<unsigned char>(c) & 0xC0U) == 0x80U;
}

/// Bounded, never deeper than `budget` (each level writes at least one character).
void excerpt_into(const nlohmann::json& v, std::string& out, std::size_t budget) {
    if (out.size() > budget) return;
    if (v.is_array() || v.is_object()) {
        out += v.is_array() ? '[' : '{';
        bool first = true;
        for (auto it = v.begin(); it != v.end(); ++it) {
            if (out.size() > budget) return;
            if (!first) out += ',';
            first = false;
            if (v.is_object()) {
                excerpt_into(nlohmann::json(it.key()), out, budget);
                out += ':';
            }
            excerpt_into(*it, out, budget);
        }
        out += v.is_array() ? ']' : '}';
        return;
    }
    if (v.is_string()) {
        // Dump a prefix only: a 20 MB string is not copied whole into a message.
        const std::string& text = v.get_ref<const std::string&>();
        std::size_t n = std::min(text.size(), budget + 1 - out.size());
        while (n > 0 && n < text.size() && continuation(text[n]))
            --n;
        const std::string part =
            nlohmann::json(text.substr(0, n))
                .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        out += n < text.size() ? part.substr(0, part.size() - 1) : part;  // an open string: cut
        return;
    }
    out += v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

/// A key as a path shows it: as written if short and printable, else quote_text() (bounded).
std::string shown_key(const std::string& key) {
    const bool plain = key.size() <= kMaxQuoted && std::none_of(key.begin(), key.end(), [](char c) {
                           return static_cast<unsigned char>(c) < 0x20U || c == 0x7F;
                       });
    return plain ? key : quote_text(key);
}

/// Line and column (1-based, in bytes) of a byte offset.
struct TextPosition {
    std::size_t line = 1, column = 1;
};

TextPosition position_of(const std::string& text, std::size_t offset) {
    TextPosition p;
    for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++p.line;
            p.column = 1;
        } else {
            ++p.column;
        }
    }
    return p;
}

std::string where(const std::string& text, std::size_t offset) {
    const TextPosition p = position_of(text, offset);
    return "line " + std::to_string(p.line) + ", column " + std::to_string(p.column);
}

/// What the structure scan found first: a problem nlohmann's parser does not report (or
/// reports without the place), at a byte offset.
struct ScanProblem {
    std::size_t offset = 0;
    std::string message;  ///< without the file name
};

/// Walks the text's tokens (strings, numbers, brackets) without building a value, keeping the
/// JSON path, the keys of every open object and the depth. Up to the first syntax error the text
/// is valid JSON (the caller checks with the real parser), so the tokens are found right; after
/// it, whatever this finds is ignored.
std::optional<ScanProblem> scan_json(const std::string& text) {
    struct Frame {
        bool object = false;
        bool expect_key = false;
        std::size_t index = 0;
        std::string key;                                 ///< the key whose value is being read
        std::map<std::string, std::size_t> key_offsets;  ///< key -> offset of its first '"'
    };
    std::vector<Frame> stack;
    auto path = [&stack]() {  // as JsonObject::field writes it, at most ~kMaxQuoted characters
        std::string p;
        for (const Frame& f : stack) {
            if (p.size() > kMaxQuoted) break;
            if (f.object) {
                if (!p.empty()) p += '.';
                p += shown_key(f.key);
            } else {
                p += '[';
                p += std::to_string(f.index);
                p += ']';
            }
        }
        if (p.size() > kMaxQuoted) p = p.substr(0, kMaxQuoted) + "…";
        return p.empty() ? std::string("the top level") : p;
    };
    std::size_t i = 0;
    if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) i = 3;  // a UTF-8 byte-order mark
    const std::size_t n = text.size();
    while (i < n) {
        const char c = text[i];
        if (c == '{' || c == '[') {
            if (stack.size() >= kMaxJsonDepth)
                return ScanProblem{i, path() + ": arrays and objects nested deeper than " +
                                          std::to_string(kMaxJsonDepth) + " levels"};
            Frame f;
            f.object = c == '{';
            f.expect_key = f.object;
            stack.push_back(std::move(f));
            ++i;
        } else if (c == '}' || c == ']') {
            if (!stack.empty()) stack.pop_back();
            ++i;
        } else if (c == ',') {
            if (!stack.empty()) {
                if (stack.back().object)
                    stack.back().expect_key = true;
                else
                    ++stack.back().index;
            }
            ++i;
        } else if (c == ':') {
            if (!stack.empty()) stack.back().expect_key = false;
            ++i;
        } else if (c == '"') {
            const std::size_t start = i++;
            while (i < n && text[i] != '"')
                i += text[i] == '\\' ? std::size_t{2} : std::size_t{1};
            if (i >= n) return std::nullopt;  // unterminated: the parser says so
            ++i;
            if (stack.empty() || !stack.back().object || !stack.back().expect_key) continue;
            Frame& f = stack.back();
            // The key as the parser decodes it ("\u0061" is "a").
            const nlohmann::json key = nlohmann::json::parse(
                text.begin() + static_cast<std::ptrdiff_t>(start),
                text.begin() + static_cast<std::ptrdiff_t>(i), nullptr, false);
            if (!key.is_string()) return std::nullopt;  // a bad escape: the parser says so
            f.key = key.get<std::string>();
            const auto [it, inserted] = f.key_offsets.emplace(f.key, start);
            if (!inserted)
                return ScanProblem{start, path() + ": key given twice in one object (first at " +
                                              where(text, it->second) +
                                              ", again here); a key may appear only once"};
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            const std::size_t start = i;
            while (i < n && (text[i] == '-' || text[i] == '+' || text[i] == '.' || text[i] == 'e' ||
                             text[i] == 'E' || (text[i] >= '0' && text[i] <= '9')))
                ++i;
            const std::string token = text.substr(start, i - start);
            const double value = std::strtod(token.c_str(), nullptr);
            if (std::isinf(value))
                return ScanProblem{start, path() + ": " + quote_text(token) +
                                              " is out of range (a number's magnitude must be "
                                              "below 1.8e308)"};
        } else {
            ++i;  // blanks, true/false/null, and what the parser will refuse
        }
    }
    return std::nullopt;
}

/// Thrown by the parser's callback at the depth limit (the scan names the place).
struct TooDeep {};

/// nlohmann's message without its "[json.exception...] " tag, at most 160 characters.
std::string parser_message(const std::exception& e) {
    std::string m = e.what();
    const std::size_t tag = m.find("] ");
    if (m.rfind("[json.exception.", 0) == 0 && tag != std::string::npos) m.erase(0, tag + 2);
    if (m.size() > 160) {
        std::size_t cut = 160;
        while (cut > 0 && continuation(m[cut]))
            --cut;
        m = m.substr(0, cut) + "…";
    }
    return m;
}

}  // namespace

std::string quote_text(std::string_view text, std::size_t max) {
    std::size_t n = std::min(text.size(), max);
    while (n > 0 && n < text.size() && continuation(text[n]))
        --n;
    std::string out = "'";
    for (std::size_t i = 0; i < n; ++i) {
        const auto byte = static_cast<unsigned char>(text[i]);
        if (byte < 0x20U || byte == 0x7FU) {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02X", static_cast<unsigned>(byte));
            out += hex;
        } else {
            out += text[i];
        }
    }
    out += "'";
    if (n < text.size()) {
        out.insert(out.size() - 1, "…");
        out += " (" + std::to_string(text.size()) + " bytes)";
    }
    return out;
}

std::string json_excerpt(const nlohmann::json& value, std::size_t max) {
    std::string out;
    excerpt_into(value, out, max);
    if (out.size() <= max) return out;
    std::size_t cut = max;
    while (cut > 0 && continuation(out[cut]))
        --cut;
    return out.substr(0, cut) + "…";
}

JsonObject::JsonObject(const nlohmann::json& value, std::string path)
    : value_(value), path_(std::move(path)) {
    if (!value_.is_object())
        throw ModelError(path_ + ": expected a JSON object, got " +
                         std::string(value_.type_name()));
}

void JsonObject::allow_only(std::initializer_list<const char*> allowed) const {
    for (auto it = value_.begin(); it != value_.end(); ++it) {
        bool known = false;
        for (const char* a : allowed)
            known = known || it.key() == a;
        if (!known) {
            std::string list;
            for (const char* a : allowed)
                list += std::string(list.empty() ? "" : ", ") + a;
            throw ModelError(field(shown_key(it.key())) + ": unknown key (allowed here: " + list +
                             ")");
        }
    }
}

bool JsonObject::has(const char* key) const {
    return value_.contains(key);
}

const nlohmann::json& JsonObject::raw(const char* key) const {
    if (!value_.contains(key)) throw ModelError(field(key) + ": missing");
    return value_.at(key);
}

double JsonObject::number(const char* key) const {
    const nlohmann::json& v = raw(key);
    if (!v.is_number())
        throw ModelError(field(key) + ": expected a number, got " + std::string(v.type_name()));
    const double d = v.get<double>();
    require_finite(d, field(key));
    return d;
}

double JsonObject::number_or(const char* key, double fallback) const {
    return has(key) ? number(key) : fallback;
}

std::size_t JsonObject::index(const char* key) const {
    const nlohmann::json& v = raw(key);
    if (!v.is_number_integer() || v.get<long long>() < 0)
        throw ModelError(field(key) + ": expected a non-negative integer, got " + json_excerpt(v));
    return static_cast<std::size_t>(v.get<long long>());
}

std::size_t JsonObject::index_or(const char* key, std::size_t fallback) const {
    return has(key) ? index(key) : fallback;
}

bool JsonObject::boolean_or(const char* key, bool fallback) const {
    if (!has(key)) return fallback;
    const nlohmann::json& v = raw(key);
    if (!v.is_boolean())
        throw ModelError(field(key) + ": expected true or false, got " + json_excerpt(v));
    return v.get<bool>();
}

std::string JsonObject::string(const char* key) const {
    const nlohmann::json& v = raw(key);
    if (!v.is_string())
        throw ModelError(field(key) + ": expected a string, got " + std::string(v.type_name()));
    return v.get<std::string>();
}

Eigen::Vector3d JsonObject::vector3(const char* key) const {
    const nlohmann::json& v = raw(key);
    if (!v.is_array() || v.size() != 3)
        throw ModelError(field(key) + ": expected an array of 3 numbers, got " + json_excerpt(v));
    Eigen::Vector3d out;
    for (std::size_t i = 0; i < 3; ++i) {
        if (!v[i].is_number())
            throw ModelError(field(key) + "[" + std::to_string(i) + "]: expected a number");
        out(static_cast<Eigen::Index>(i)) = v[i].get<double>();
        require_finite(out(static_cast<Eigen::Index>(i)),
                       field(key) + "[" + std::to_string(i) + "]");
    }
    return out;
}

Eigen::Vector3d JsonObject::vector3_or(const char* key, const Eigen::Vector3d& fallback) const {
    return has(key) ? vector3(key) : fallback;
}

JsonObject JsonObject::object(const char* key) const {
    return JsonObject(raw(key), field(key));
}

const nlohmann::json& JsonObject::array(const char* key) const {
    const nlohmann::json& v = raw(key);
    if (!v.is_array())
        throw ModelError(field(key) + ": expected an array, got " + std::string(v.type_name()));
    return v;
}

nlohmann::json parse_json_text(const std::string& text, const std::string& name) {
    const std::optional<ScanProblem> problem = scan_json(text);
    auto refuse = [&](const ScanProblem& p) {
        throw ModelError(name + ": " + where(text, p.offset) + ": " + p.message);
    };
    // The parser builds nothing deeper than the limit (its callback stops it there).
    const nlohmann::json::parser_callback_t stop_deep =
        [](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
            if ((event == nlohmann::json::parse_event_t::object_start ||
                 event == nlohmann::json::parse_event_t::array_start) &&
                depth >= static_cast<int>(kMaxJsonDepth))
                throw TooDeep{};
            return true;
        };
    nlohmann::json value;
    try {
        value = nlohmann::json::parse(text, stop_deep);
    } catch (const nlohmann::json::parse_error& e) {
        // A problem the scan found before the syntax error comes first (the text is valid up
        // to the syntax error, so the scan saw it right).
        if (problem && problem->offset + 1 < e.byte) refuse(*problem);
        throw ModelError(name + ": not valid JSON: " + parser_message(e));
    } catch (const TooDeep&) {
        if (problem) refuse(*problem);
        throw ModelError(name + ": arrays and objects nested deeper than " +
                         std::to_string(kMaxJsonDepth) + " levels");
    } catch (const nlohmann::json::exception& e) {  // e.g. 406: a number out of range
        if (problem) refuse(*problem);
        throw ModelError(name + ": " + parser_message(e));
    }
    if (problem) refuse(*problem);  // a duplicate key: the parser kept the last one
    return value;
}

nlohmann::json parse_json_file(const std::string& filename) {
    std::ifstream in(filename, std::ios::binary);
    if (!in) throw ModelError(filename + ": cannot open file");
    std::stringstream buffer;
    buffer << in.rdbuf();
    if (in.bad()) throw ModelError(filename + ": read error");
    return parse_json_text(buffer.str(), filename);
}

}  // namespace scopekin::model::io
