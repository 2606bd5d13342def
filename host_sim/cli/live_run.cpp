#include "host_sim/cli/live_run.hpp"

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/simulator/live_simulation.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Json vec(const Eigen::Vector3d& v) {
    return Json::array({v.x(), v.y(), v.z()});
}

template <typename T>
Json optional_json(const std::optional<T>& v) {
    return v ? Json(*v) : Json(nullptr);
}

}  // namespace

Json procedure_json(const model::ProcedureOutcome& o) {
    Json j;
    j["kind"] = o.kind;
    const bool physician = o.kind == "physician";
    if (physician) {
        j["style"] = o.style;
        j["seed"] = o.seed;
    }
    j["cecum_reached"] = o.cecum_reached;
    j["cecum_time_s"] = optional_json(o.cecum_time_s);
    j["insertion_at_cecum_mm"] = optional_json(o.insertion_at_cecum_mm);
    if (physician) j["loop_reductions"] = o.loop_reductions;
    j["abdominal_pressure_s"] = o.abdominal_pressure_s;
    j["duration_s"] = o.duration_s;
    j["end_reason"] = o.end_reason;
    return j;
}

namespace {}  // namespace

LiveRunReport run_live_to_folder(const model::Scenario& sc, const LiveRunOptions& options) {
    const sensors::SensorSuiteConfig sensor_config =
        sensors::read_sensor_config(sc.sensors, sc.sensors_path);
    const fs::path dir = options.out;
    prepare_directory(
        dir, {"summary.json", "recording.csv", "recording.incomplete.csv", "world.csv",
              "world.incomplete.csv", "firmware.csv", "firmware.incomplete.csv", "truth.csv",
              "truth.incomplete.csv", "contacts.csv", "contacts.incomplete.csv", "procedure.csv",
              "procedure.incomplete.csv", "frames.jsonl", "frames.incomplete.jsonl",
              "snapshots.json", "forces.png", "advance.png", "snapshots.png"});
    PartFile recording(dir / "recording.csv", dir / "recording.incomplete.csv");
    PartFile world(dir / "world.csv", dir / "world.incomplete.csv");
    PartFile firmware(dir / "firmware.csv", dir / "firmware.incomplete.csv");
    PartFile truth(dir / "truth.csv", dir / "truth.incomplete.csv");
    PartFile procedure(dir / "procedure.csv", dir / "procedure.incomplete.csv");
    std::unique_ptr<PartFile> contacts;
    if (sc.outputs.contacts_file)
        contacts =
            std::make_unique<PartFile>(dir / "contacts.csv", dir / "contacts.incomplete.csv");
    std::unique_ptr<PartFile> frames;
    if (options.frames_hz > 0)
        frames = std::make_unique<PartFile>(dir / "frames.jsonl", dir / "frames.incomplete.jsonl");
    if (!options.quiet && sc.physician)
        std::cerr << options.command << ": " << sc.source << ": a physician ("
                  << model::physician_style_name(sc.physician->style) << ", seed "
                  << sc.physician->seed << ") for at most " << sc.physician->max_duration_s
                  << " s, in world steps of " << sc.settings.time_step_s << " s, colon '"
                  << sc.colon->name() << "', sensors every 1 ms, firmware every "
                  << host_sim::kBoxPeriodUs / 1000 << " ms, seed " << options.seed << std::endl;
    else if (!options.quiet)
        std::cerr << options.command << ": " << sc.source << ": " << sc.procedure.end_s()
                  << " s in world steps of " << sc.settings.time_step_s << " s, colon '"
                  << sc.colon->name() << "', sensors every 1 ms, firmware every "
                  << host_sim::kBoxPeriodUs / 1000 << " ms, seed " << options.seed << std::endl;
    ProgressBar bar(options.quiet);
    LiveRunReport report;
    host_sim::LiveStreams streams;
    streams.recording = &recording.stream();
    streams.world = &world.stream();
    streams.firmware = &firmware.stream();
    streams.contacts = contacts ? &contacts->stream() : nullptr;
    streams.truth = &truth.stream();
    streams.procedure = &procedure.stream();
    streams.frames = frames ? &frames->stream() : nullptr;
    streams.frames_period_s = options.frames_hz > 0 ? 1.0 / options.frames_hz : 0.0;
    streams.view_step = options.view_step;
    report.result = host_sim::run_live(sc, sensor_config, options.seed, streams,
                                       [&](const model::SimulationProgress& p) { bar.update(p); });
    bar.done();
    const host_sim::LiveResult& r = report.result;
    const model::SimulationSummary& sum = r.world;
    report.complete = sum.complete;
    Json files = Json::object();
    files["recording"] = recording.finish(sum.complete).filename().string();
    files["world"] = world.finish(sum.complete).filename().string();
    files["firmware"] = firmware.finish(sum.complete).filename().string();
    files["truth"] = truth.finish(sum.complete).filename().string();
    files["procedure"] = procedure.finish(sum.complete).filename().string();
    if (contacts) files["contacts"] = contacts->finish(sum.complete).filename().string();
    if (frames) files["frames"] = frames->finish(sum.complete).filename().string();
    write_json(dir / "snapshots.json", r.snapshots);
    files["snapshots"] = "snapshots.json";

    Json s;
    s["scenario"] = sc.source;
    s["kind"] = "world";
    s["description"] = sc.description;
    s["status"] = sum.complete ? "complete" : "failed";
    s["message"] = sum.message;
    s["failure_time_s"] = sum.complete ? Json(nullptr) : Json(sum.failure_time_s);
    s["seed"] = options.seed;
    s["duration_s"] = sum.simulated_time_s;
    s["end_time_s"] = sum.end_time_s;
    s["time_step_s"] = sc.settings.time_step_s;
    s["steps"] = sum.steps;
    s["wall_time_s"] = r.wall_time_s;
    s["real_time_factor"] = r.wall_time_s > 0 ? sum.simulated_time_s / r.wall_time_s : 0.0;
    s["peak_handle_force_N"] = {{"true", sum.max_handle_force_N},
                                {"measured", r.peak_measured_handle_force_N}};
    s["max_handle_torque_Nmm"] = sum.max_handle_torque_Nmm;
    const host_sim::BoxObservation& box = r.box;
    s["peak_estimated_contact_force"] = {
        {"force_N", box.peak_contact_force_N},
        {"time_s", box.peak_contact_time_s},
        {"path_mm", box.peak_contact_path_mm},
        {"region", host_sim::region_at_path(*sc.colon, box.peak_contact_path_mm)},
        {"station", box.peak_contact_station}};
    s["peak_true_contact_force"] = {{"force_N", r.peak_true_contact_force_N},
                                    {"region", r.peak_true_contact_region}};
    s["peak_true_tip_contact_force_N"] = r.peak_true_tip_contact_force_N;
    Json efficiency = Json::object();
    for (model::ColonRegion region : model::kColonRegionsInOrder) {
        const auto it = r.advance_by_region.find(std::string(model::region_name(region)));
        if (it == r.advance_by_region.end() || !(it->second.handle_advance_mm > 0)) continue;
        efficiency[it->first] = {
            {"handle_advance_mm", it->second.handle_advance_mm},
            {"tip_advance_mm", it->second.tip_advance_mm},
            {"efficiency", it->second.tip_advance_mm / it->second.handle_advance_mm}};
    }
    s["advance_efficiency_by_region"] = efficiency;
    s["final_tip"] = {{"path_mm", r.final_tip_path_mm},
                      {"region", r.final_tip_region},
                      {"position_mm", vec(sum.final_tip_mm)}};
    s["final_insertion_depth_mm"] = sum.final_insertion_depth_mm;
    s["procedure"] = procedure_json(sum.procedure);
    s["alarms"] = r.box_json["alarms"];
    s["firmware"] = r.box_json;
    s["firmware"]["estimator_periods"] = r.firmware_periods;
    s["box"] = r.box_section;
    s["sensors"] = r.sensor_counters;
    s["truth"] = r.truth;
    s["rows_delivered"] = r.rows_delivered;
    Json world_stats;
    world_stats["max_contact_force_N"] = sum.max_contact_force_N;
    world_stats["max_simultaneous_contacts"] = sum.max_simultaneous_contacts;
    world_stats["gs_sweeps_mean"] = sum.gs_sweeps_mean;
    world_stats["gs_sweeps_max"] = sum.gs_sweeps_max;
    world_stats["dropped_contacts_total"] = sum.dropped_contacts_total;
    world_stats["material_tangent_fallbacks"] = sum.material_tangent_fallbacks;
    world_stats["under_relaxed_steps"] = sum.under_relaxed_steps;
    world_stats["assistant_pressure"] = {
        {"max_force_N", sum.max_assistant_pressure_force_N},
        {"pressing_s", sum.assistant_pressing_s},
        {"mean_force_while_pressing_N",
         sum.assistant_pressing_s > 0 ? sum.assistant_pressure_impulse_Ns / sum.assistant_pressing_s
                                      : 0.0}};
    Json pleats = Json::array();
    for (const model::StretchPleating& k : sum.telescoping)
        pleats.push_back({{"region", std::string(model::region_name(k.region))},
                          {"rest_length_mm", k.rest_length_mm},
                          {"max_fraction", k.max_fraction},
                          {"peak_fraction", k.peak_fraction},
                          {"final_fraction", k.final_fraction}});
    world_stats["telescoping"] = pleats;
    world_stats["max_penetration_mm"] = sum.max_penetration_mm;
    world_stats["friction_work_Nmm"] = sum.friction_work_Nmm;
    s["world"] = world_stats;
    Json effects = Json::array();
    for (const auto& e : sc.effects)
        effects.push_back({{"name", e->name()}, {"parameters", e->parameters()}});
    s["truth_effects"] = effects;
    if (sc.patient) s["patient"] = model::patient_to_json(*sc.patient);
    s["warnings"] = sum.warnings;
    s["files"] = files;
    report.summary = s;
    const fs::path summary_part = write_json_part(dir / "summary.json", s);
    if (options.before_summary) options.before_summary(summary_part, report.complete);
    commit_part(dir / "summary.json");
    return report;
}

void print_box_faults(const Json& box) {
    if (!box.is_object() || !box.contains("fault_first_s")) return;
    const auto periods_total = box["periods"].get<std::uint64_t>();
    for (const char* group : {"fault", "tracker_fault"}) {
        const std::string kind = std::string(group) == "fault" ? "box fault " : "tracker fault ";
        for (const auto& [name, first] : box[std::string(group) + "_first_s"].items()) {
            const auto periods = box[std::string(group) + "_periods"][name].get<std::uint64_t>();
            std::printf("  %8.3f s  %-31s first set; set in %llu of %llu periods (%.2f s)\n",
                        first.get<double>(), (kind + name).c_str(),
                        static_cast<unsigned long long>(periods),
                        static_cast<unsigned long long>(periods_total),
                        static_cast<double>(periods) * host_sim::kBoxPeriodUs * 1e-6);
        }
    }
}

void print_run_tables(const LiveRunReport& report) {
    const Json& s = report.summary;
    std::printf("\nAlarm timeline (the box's outputs):\n");
    if (s["alarms"].empty()) std::printf("  no alarm\n");
    for (const Json& a : s["alarms"]) {
        const std::string cleared =
            a["cleared_s"].is_null()
                ? std::string("still up at the end")
                : "cleared at " + std::to_string(a["cleared_s"].get<double>()).substr(0, 7) + " s";
        std::printf("  %8.3f s  %-24s raised (estimated tip at %.0f mm), %s\n",
                    a["raised_s"].get<double>(), a["kind"].get<std::string>().c_str(),
                    a["estimated_tip_path_mm"].get<double>(), cleared.c_str());
    }
    // Fault flags the box raised: what its estimates above are worth (e.g. depth_outside_model:
    // beyond the reduced model's depth range the box holds its last estimate).
    const Json& firmware = s["firmware"];
    for (const auto& [name, first] : firmware["fault_first_s"].items()) {
        const auto periods = firmware["fault_periods"][name].get<std::uint64_t>();
        std::printf("  %8.3f s  fault flag %-20s first set; set in %llu of %llu periods (%.2f s)\n",
                    first.get<double>(), name.c_str(), static_cast<unsigned long long>(periods),
                    static_cast<unsigned long long>(firmware["periods"].get<std::uint64_t>()),
                    static_cast<double>(periods) * host_sim::kBoxPeriodUs * 1e-6);
    }
    print_box_faults(s["box"]);
    std::printf("\nSummary:\n");
    std::printf("  %-40s %.2f s (%s)\n", "duration", s["duration_s"].get<double>(),
                s["status"].get<std::string>().c_str());
    std::printf("  %-40s %.2f N (measured %.2f N)\n", "peak handle force",
                s["peak_handle_force_N"]["true"].get<double>(),
                s["peak_handle_force_N"]["measured"].get<double>());
    const Json& pe = s["peak_estimated_contact_force"];
    std::printf("  %-40s %.2f N at %.0f mm along the colon (%s), t = %.2f s\n",
                "peak estimated contact force", pe["force_N"].get<double>(),
                pe["path_mm"].get<double>(), pe["region"].get<std::string>().c_str(),
                pe["time_s"].get<double>());
    std::printf("  %-40s %.2f N (%s)\n", "peak true contact force",
                s["peak_true_contact_force"]["force_N"].get<double>(),
                s["peak_true_contact_force"]["region"].get<std::string>().c_str());
    std::printf("  %-40s %.0f mm along the colon (%s)\n", "tip at the end",
                s["final_tip"]["path_mm"].get<double>(),
                s["final_tip"]["region"].get<std::string>().c_str());
    std::printf(
        "  advance efficiency by region (true tip advance / handle advance while advancing):\n");
    for (const auto& [region, e] : s["advance_efficiency_by_region"].items())
        std::printf("    %-20s %5.2f  (%.0f mm of %.0f mm)\n", region.c_str(),
                    e["efficiency"].get<double>(), e["tip_advance_mm"].get<double>(),
                    e["handle_advance_mm"].get<double>());
    std::printf("  %-40s %zu\n", "alarms", s["alarms"].size());
    std::printf("  %-40s %.2f x real time (%.1f s wall)\n", "speed",
                s["real_time_factor"].get<double>(), s["wall_time_s"].get<double>());
}

}  // namespace scopekin::cli
