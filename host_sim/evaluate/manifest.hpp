#pragma once
// Evaluation manifests (host_sim/evaluate/README.md, "Manifests"): a JSON file naming a set of
// cases, each a scenario made of the documented base scenario (base_scenario()), the manifest's
// "base" keys over it, and the case's own keys over those:
//
//   {"name": "development", "description": "...", "base": {...optional scenario keys...},
//    "cases": [{"name": "p0003-expert-s1", "patient": {"seed": 3},
//               "physician": {"style": "careful_expert", "seed": 1}}, ...]}
//
// Read strictly: unknown top-level keys, a case without a file-safe name, names given twice
// (also when they differ only in case), and any case whose scenario the scenario reader
// refuses are ModelErrors naming the manifest and the case ("dev.json: cases[3] 'x': ...").
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace scopekin::evaluate {

struct ManifestCase {
    std::size_t index = 0;          ///< its place in "cases"
    std::string name;               ///< file-safe, unique: its folder's name
    std::uint64_t sensor_seed = 1;  ///< "sensor_seed": the sensor models' seed (default 1)
    /// The scenario document: the base, the manifest's "base" and the case's keys (shallow: a key
    /// replaces the whole value below it); a relative patient "file" made absolute.
    nlohmann::json scenario;
    std::string style;  ///< the case's "physician"."style", or "scripted" without a physician
};

struct Manifest {
    std::filesystem::path path;
    std::string name;  ///< file-safe
    std::string description;
    std::vector<ManifestCase> cases;
};

/// The base scenario every case starts from: CF-Q160L (1,700 mm, 170 elements), gravity along
/// −z, 20 mm inserted at the start, the default solver (h = 10 ms) and sensors, 30 Hz world.csv
/// rows. It has neither a colon nor a procedure: each case (or the manifest's base) gives them.
nlohmann::json base_scenario();

/// True for a name of 1-64 characters from [A-Za-z0-9._-] that starts with a letter or digit.
bool is_file_safe(const std::string& name);

/// Reads and checks a manifest and every case's scenario (model::read_scenario on it).
/// Throws ModelError naming the manifest, the case and the field.
Manifest read_manifest(const std::filesystem::path& path);

}  // namespace scopekin::evaluate
