#pragma once
// Reading JSON input strictly: every object may hold only the keys its reader knows, every
// value must have the expected type and range, and every error names the full path of the
// field ("scenario.supports[1].node: ..."). Throws ModelError.
#include <Eigen/Dense>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

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

/// Parses a file; a syntax error names the file, line and column.
nlohmann::json parse_json_file(const std::string& filename);

}  // namespace scopekin::model::io
