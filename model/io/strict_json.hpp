#pragma once
// Reading JSON input strictly: every object may hold only the keys its reader knows, every
// value must have the expected type and range, and every error names the full path of the
// field ("scenario.supports[1].node: ..."). Throws ModelError.
//
// Reading a file (parse_json_file, parse_json_text) refuses, with the file, line and column:
// a syntax error; arrays and objects nested deeper than kMaxJsonDepth; a key twice in one object
// (naming both places); a number beyond double's range ("1e400": out of range). A value or text
// quoted in any message is at most kMaxQuoted characters (quote_text(), json_excerpt()).
#include <Eigen/Dense>
#include <cstddef>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace scopekin::model::io {

/// A JSON object being read, with its path for error messages.
class JsonObject {
public:
    JsonObject(const nlohmann::json& value, std::string path);
    /// Throws if the object holds a key not in `allowed` (names the key and lists the allowed ones).
    void allow_only(std::initializer_list<const char*> allowed) const;
    bool has(const char* key) const;
    const std::string& path() const { return path_; }
    /// "file.json: beam.section" for the root (path ending in ':'), "...beam.section" below it.
    std::string field(const std::string& key) const {
        return path_.back() == ':' ? path_ + " " + key : path_ + "." + key;
    }

    double number(const char* key) const;
    double number_or(const char* key, double fallback) const;
    std::size_t index(const char* key) const;  ///< a non-negative integer
    std::size_t index_or(const char* key, std::size_t fallback) const;
    bool boolean_or(const char* key, bool fallback) const;
    std::string string(const char* key) const;
    Eigen::Vector3d vector3(const char* key) const;
    Eigen::Vector3d vector3_or(const char* key, const Eigen::Vector3d& fallback) const;
    JsonObject object(const char* key) const;
    const nlohmann::json& array(const char* key) const;
    const nlohmann::json& raw(const char* key) const;

private:
    const nlohmann::json& value_;
    std::string path_;
};

/// Arrays and objects nested deeper than this are refused (a scenario file needs 5 levels).
inline constexpr std::size_t kMaxJsonDepth = 64;
/// Characters of a value or a line quoted in an error message at most.
inline constexpr std::size_t kMaxQuoted = 80;

/// `text` in single quotes for an error message: whole if at most `max` bytes, else its first
/// `max` bytes (cut at a character boundary), "…" and its length: 'abc…' (20971520 bytes).
/// Control characters are shown as \xNN.
std::string quote_text(std::string_view text, std::size_t max = kMaxQuoted);
/// A JSON value as an error message shows it: its compact text, cut after `max` characters
/// with "…". Never recurses deeper than `max` levels, whatever the value's depth.
std::string json_excerpt(const nlohmann::json& value, std::size_t max = kMaxQuoted);

/// Parses JSON text strictly (see above); `name` (the file) starts every message.
nlohmann::json parse_json_text(const std::string& text, const std::string& name);
/// Reads and parses a file strictly; a file that cannot be read is a ModelError too.
nlohmann::json parse_json_file(const std::string& filename);

}  // namespace scopekin::model::io
