#include "model/io/strict_json.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "model/model_error.hpp"

namespace scopekin::model::io {

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
            throw ModelError(field(it.key()) + ": unknown key (allowed here: " + list + ")");
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
        throw ModelError(field(key) + ": expected a non-negative integer, got " + v.dump());
    return static_cast<std::size_t>(v.get<long long>());
}

std::size_t JsonObject::index_or(const char* key, std::size_t fallback) const {
    return has(key) ? index(key) : fallback;
}

bool JsonObject::boolean_or(const char* key, bool fallback) const {
    if (!has(key)) return fallback;
    const nlohmann::json& v = raw(key);
    if (!v.is_boolean()) throw ModelError(field(key) + ": expected true or false, got " + v.dump());
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
        throw ModelError(field(key) + ": expected an array of 3 numbers, got " + v.dump());
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

nlohmann::json parse_json_file(const std::string& filename) {
    std::ifstream in(filename);
    if (!in) throw ModelError(filename + ": cannot open file");
    std::stringstream buffer;
    buffer << in.rdbuf();
    try {
        return nlohmann::json::parse(buffer.str());
    } catch (const nlohmann::json::parse_error& e) {
        throw ModelError(filename + ": not valid JSON: " + e.what());
    }
}

}  // namespace scopekin::model::io
