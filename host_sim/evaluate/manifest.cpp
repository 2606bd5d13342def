#include "host_sim/evaluate/manifest.hpp"

#include <algorithm>
#include <cctype>
#include <map>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"
#include "model/scenario/scenario.hpp"

namespace scopekin::evaluate {
namespace {

namespace fs = std::filesystem;
using model::ModelError;
using Json = nlohmann::json;

std::string lower(std::string s) {
    for (char& c : s)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string name_rule() {
    return "1-64 characters from A-Z a-z 0-9 . _ -, starting with a letter or digit";
}

}  // namespace

Json base_scenario() {
    return Json{{"scope", {{"model", "cf_q160l"}, {"length_mm", 1700}, {"elements", 170}}},
                {"gravity_mm_per_s2", {0, 0, -9810}},
                {"initial_insertion_mm", 20},
                {"outputs", {{"sample_rate_Hz", 30}}}};
}

bool is_file_safe(const std::string& name) {
    if (name.empty() || name.size() > 64) return false;
    if (!std::isalnum(static_cast<unsigned char>(name[0]))) return false;
    return std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
    });
}

Manifest read_manifest(const fs::path& path) {
    const std::string file = path.string();
    const Json document = model::io::parse_json_file(file);  // syntax: file, line, column
    const model::io::JsonObject root(document, file + ":");
    root.allow_only({"name", "description", "base", "cases"});
    Manifest m;
    m.path = path;
    m.name = root.string("name");
    if (!is_file_safe(m.name))
        throw ModelError(root.field("name") + ": " + model::io::quote_text(m.name) +
                         " is not a file-safe name (" + name_rule() + ")");
    if (root.has("description")) m.description = root.string("description");
    Json base = base_scenario();
    if (root.has("base")) {
        const model::io::JsonObject b = root.object("base");
        for (const auto& [key, value] : root.raw("base").items()) {
            if (key == "model" || key == "sensor_seed" || key == "name")
                throw ModelError(b.field(key) + ": not taken in a manifest's base (give " +
                                 (key == "model" ? std::string("the model's keys themselves")
                                                 : std::string("it in a case")) +
                                 ")");
            base[key] = value;
        }
    }
    const Json& cases = root.array("cases");
    if (cases.empty()) throw ModelError(root.field("cases") + ": lists no case");
    std::map<std::string, std::size_t> seen;  // lower-case name -> index
    const fs::path folder = path.parent_path();
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const std::string where = root.field("cases") + "[" + std::to_string(i) + "]";
        const model::io::JsonObject c(cases[i], where);
        if (!c.has("name")) throw ModelError(where + ": has no 'name'");
        ManifestCase mc;
        mc.index = i;
        mc.name = c.string("name");
        if (!is_file_safe(mc.name))
            throw ModelError(c.field("name") + ": " + model::io::quote_text(mc.name) +
                             " is not a file-safe name (" + name_rule() + ")");
        const auto [it, fresh] = seen.emplace(lower(mc.name), i);
        if (!fresh)
            throw ModelError(c.field("name") + ": " + model::io::quote_text(mc.name) +
                             " is also the name of cases[" + std::to_string(it->second) +
                             "] (names must differ, also in letter case: they name folders)");
        const std::string source = file + ": cases[" + std::to_string(i) + "] '" + mc.name + "'";
        Json scenario = base;
        for (const auto& [key, value] : cases[i].items()) {
            if (key == "name") continue;
            if (key == "sensor_seed") {
                if (!value.is_number_unsigned())
                    throw ModelError(c.field("sensor_seed") +
                                     ": expected a whole number from 0 to 2^64-1");
                mc.sensor_seed = value.get<std::uint64_t>();
                continue;
            }
            if (key == "model")
                throw ModelError(c.field("model") +
                                 ": not taken in a manifest case (give the model's keys in the "
                                 "case or the manifest's base)");
            scenario[key] = value;
        }
        // A patient file is relative to the manifest; the case's scenario.json is written
        // elsewhere, so it names the file absolutely.
        if (scenario.contains("patient") && scenario["patient"].is_object() &&
            scenario["patient"].contains("file") && scenario["patient"]["file"].is_string()) {
            const fs::path p = scenario["patient"]["file"].get<std::string>();
            if (!p.empty() && p.is_relative())
                scenario["patient"]["file"] = fs::absolute(folder / p).lexically_normal().string();
        }
        if (!scenario.contains("description"))
            scenario["description"] =
                "evaluation case '" + mc.name + "' of the manifest '" + m.name + "' (" + file + ")";
        mc.style = "scripted";
        if (scenario.contains("physician") && scenario["physician"].is_object() &&
            scenario["physician"].contains("style") && scenario["physician"]["style"].is_string())
            mc.style = scenario["physician"]["style"].get<std::string>();
        const model::Scenario sc = model::read_scenario(scenario, source);
        if (sc.kind != model::ScenarioKind::world)
            throw ModelError(source + ": a case must be a world scenario (a colon or a patient)");
        mc.scenario = std::move(scenario);
        m.cases.push_back(std::move(mc));
    }
    return m;
}

}  // namespace scopekin::evaluate
