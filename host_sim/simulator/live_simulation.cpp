#include "host_sim/simulator/live_simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "host_sim/recording/recording_format.hpp"
#include "host_sim/recording/wire_values.hpp"
#include "host_sim/simulator/firmware_loop.hpp"
#include "host_sim/simulator/truth_csv.hpp"
#include "host_sim/simulator/world_csv.hpp"
#include "host_sim/simulator/world_readout.hpp"
#include "kinetics/default_reduced_tables.hpp"

namespace scopekin::host_sim {
namespace {

using Json = nlohmann::ordered_json;

/// Snapshots kept at most (the plot has a panel each).
constexpr std::size_t kMaxSnapshots = 6;

std::int64_t to_us(double t_s) {
    return std::llround(t_s * 1e6);
}

sensors::TruthSample truth_of(const WorldReadout& r, std::int64_t time_us) {
    sensors::TruthSample t;
    t.time_us = time_us;
    t.handle_force_N = r.handle_force_N;
    t.handle_torque_Nmm = r.handle_torque_Nmm;
    t.insertion_mm = r.insertion_mm;
    t.roll_rad = r.roll_rad;
    for (std::size_t k = 0; k < r.em.size(); ++k) {
        t.em[k].position_mm = r.em[k].position_mm;
        t.em[k].orientation = r.em[k].orientation;
    }
    // The tip sensor's frame: x, y across the tip, z along its axis (the readout's tip orientation
    // takes +x to the axis).
    const Eigen::Vector3d local = r.em[kEmTip].orientation.conjugate() * r.tip_force_N;
    t.tip_force_N = Eigen::Vector3d(local.y(), local.z(), local.x());
    t.region = r.tip_region;
    return t;
}

Json counters_json(const sensors::SensorCounters& c) {
    return {{"taken", c.taken}, {"dropped", c.dropped}, {"delivered", c.delivered}};
}

Json sensor_counters_json(const sensors::SensorSuiteCounters& c) {
    Json em = Json::object();
    for (std::size_t k = 0; k < c.em.size(); ++k)
        em[std::string(recording::em_slot_prefix(k))] = counters_json(c.em[k]);
    return {{"handle_force_torque", counters_json(c.handle_force_torque)},
            {"insertion_roll", counters_json(c.insertion_roll)},
            {"em_tracker", em},
            {"tip_force", counters_json(c.tip_force)}};
}

/// Appends x to 0.1 (mm, N): frames.jsonl's resolution ("-0.0" written as "0").
void append_tenth(std::string& out, double x) {
    char text[32];
    const double rounded = std::round(x * 10.0) / 10.0;
    std::snprintf(text, sizeof text, "%.1f", rounded == 0.0 ? 0.0 : rounded);
    out += text;
}

void append_point(std::string& out, const Eigen::Vector3d& p) {
    out += '[';
    append_tenth(out, p.x());
    out += ',';
    append_tenth(out, p.y());
    out += ',';
    append_tenth(out, p.z());
    out += ']';
}

/// One line of frames.jsonl, written as text (the view's shapes at every frame: a JSON object
/// built and dumped would cost the run several per cent; host_sim/view/README.md, "frames.jsonl"):
/// time_s, scope_mm (the inserted nodes), colon_mm (displaced), contacts (position_mm, force_N,
/// normal_force_N).
std::string frame_text(const model::World& world) {
    std::string out;
    out.reserve(16384);
    char time[32];
    std::snprintf(time, sizeof time, "%.6g", world.time_s());
    out += "{\"time_s\":";
    out += time;
    out += ",\"scope_mm\":[";
    const double depth = world.insertion_depth_mm();
    bool first = true;
    for (std::size_t k = 0; k < world.scope_node_count(); ++k) {
        if (world.arc_from_tip_mm(k) > depth + 1e-9) continue;
        if (!first) out += ',';
        first = false;
        append_point(out, world.node_position_mm(k));
    }
    out += "],\"colon_mm\":[";
    first = true;
    for (const Eigen::Vector3d& p : world.colon_positions_mm()) {
        if (!first) out += ',';
        first = false;
        append_point(out, p);
    }
    out += "],\"contacts\":[";
    first = true;
    for (const model::WorldContact& c : world.contacts()) {
        if (!(c.normal_force_N > 0.0)) continue;
        if (!first) out += ',';
        first = false;
        out += "{\"position_mm\":";
        append_point(out, c.scope_point_mm);
        out += ",\"force_N\":";
        append_point(out, c.force_N);
        out += ",\"normal_force_N\":";
        append_tenth(out, c.normal_force_N);
        out += '}';
    }
    out += "]}";
    return out;
}

/// The live view's row at a world step: the handle (true), the truth's tip and largest station
/// force, the box's last period (host_sim/view/README.md, "Live").
Json view_row(const WorldReadout& world, const model::truth::TruthReadout& truth,
              const kinetics::Outputs& box) {
    Json row = box_view_row(
        world.time_s, {world.handle_force_N, world.handle_torque_Nmm, world.insertion_mm}, box);
    row["true_tip_path_mm"] = truth.tip_path_mm;
    row["true_max_force_N"] = truth.max_station_force_N;
    return row;
}

}  // namespace

namespace {
double q16(fixed_point::Q16_16 v) {
    return static_cast<double>(v.raw()) / 65536.0;
}
}  // namespace

nlohmann::ordered_json box_view_row(double time_s, const HandleReading& handle,
                                    const kinetics::Outputs& box) {
    Json stations = Json::array();
    for (std::size_t k = 0; k < box.active_stations && k < box.stations.size(); ++k)
        stations.push_back(Json::array(
            {q16(box.stations[k].path_position_mm), q16(box.stations[k].normal_force_N)}));
    return {{"time_s", time_s},
            {"handle_force_N", handle.force_N},
            {"handle_torque_Nmm", handle.torque_Nmm},
            {"insertion_mm", handle.insertion_mm},
            {"box_tip_path_mm", q16(box.tip_path_mm)},
            {"box_tip_sd_mm", q16(box.tip_uncertainty_mm)},
            {"box_max_force_N", q16(box.max_contact_force_N)},
            {"self_lock", box.self_lock_alarm ? 1 : 0},
            {"contact_level", static_cast<int>(box.contact_force_level)},
            {"fault_flags", box.fault_flags},
            {"stations", stations}};
}

std::string region_at_path(const model::ColonTube& colon, double path_mm) {
    std::size_t i = 0;
    while (i + 1 < colon.point_count() && colon.arc_length_mm(i + 1) <= path_mm)
        ++i;
    return std::string(model::region_name(colon.points()[i].region));
}

LiveResult run_live(const model::Scenario& scenario,
                    const sensors::SensorSuiteConfig& sensor_config, std::uint64_t seed,
                    const LiveStreams& streams,
                    const std::function<void(const model::SimulationProgress&)>& on_progress) {
    const auto wall_start = std::chrono::steady_clock::now();
    LiveResult result;
    std::unique_ptr<model::World> world = model::build_world(scenario);
    WorldReader reader(*world);
    // Ground truth at the estimator's stations (the firmware's tables say how many and where).
    const auto& tables_header = kinetics::default_reduced_tables().header();
    const model::truth::TruthReader truth_reader(
        *world,
        model::truth::nearest_station_layout(
            *world, tables_header.stations,
            static_cast<double>(tables_header.station_spacing_mm.raw()) / 65536.0),
        scenario.settings.gravity_mm_per_s2);
    TruthRecorder truth;
    std::vector<std::uint64_t> period_times_us;
    sensors::SensorSuite suite(sensor_config, seed);
    std::unique_ptr<recording::RecordingWriter> recording_writer;
    if (streams.recording != nullptr)
        recording_writer = std::make_unique<recording::RecordingWriter>(*streams.recording);

    bool snapshot_wanted = false;
    std::string snapshot_label;
    BoxObserver observer(streams.firmware);
    FirmwareLoop firmware([&](const BoxPeriod& period) {
        period_times_us.push_back(period.time_us);
        const std::size_t alarms_before = observer.observation().alarms.size();
        observer.observe(period);
        const auto& alarms = observer.observation().alarms;
        if (alarms.size() > alarms_before && !snapshot_wanted) {
            bool first_of_kind = true;
            for (std::size_t i = 0; i + 1 < alarms.size(); ++i)
                first_of_kind = first_of_kind && alarms[i].kind != alarms.back().kind;
            if (first_of_kind && alarms.back().kind != "contact_force_warning") {
                snapshot_wanted = true;
                snapshot_label = alarms.back().kind + " alarm raised";
            }
        }
    });

    Json snapshots = Json::array();
    auto take_snapshot = [&](const std::string& label, bool last = false) {
        if (!last && snapshots.size() >= kMaxSnapshots - 1) return;  // room for the last one
        Json snap = reader.snapshot(*world, label);
        Json estimated = Json::array();  // the box's stations in the last period
        const kinetics::Outputs& o = firmware.box().outputs();
        for (std::size_t k = 0; k < o.active_stations && k < o.stations.size(); ++k) {
            const kinetics::StationEstimate& st = o.stations[k];
            estimated.push_back(
                {{"station", k},
                 {"path_mm", static_cast<double>(st.path_position_mm.raw()) / 65536.0},
                 {"normal_N", static_cast<double>(st.normal_force_N.raw()) / 65536.0},
                 {"tangential_N", static_cast<double>(st.tangential_force_N.raw()) / 65536.0}});
        }
        snap["estimated"] = estimated;
        snapshots.push_back(snap);
    };

    // A frame for the view (frames.jsonl): the shapes and the contacts, to 0.1 mm.
    double next_frame_s = -1.0;
    auto write_frame = [&](double time_s) {
        if (streams.frames == nullptr || time_s + 1e-9 < next_frame_s) return;
        next_frame_s = time_s + streams.frames_period_s;
        *streams.frames << frame_text(*world) << '\n';
    };

    WorldReadout previous = reader.read(*world);
    truth.add(truth_sample(truth_reader.read(*world)));
    WorldReadout latest = previous;
    std::int64_t last_tick_us = to_us(world->time_s());
    std::int64_t last_delivered_us = 0;  // the box runs up to the last row, as `scopekin run` does
    std::size_t next_action = 1;
    const auto& actions = scenario.procedure.actions();

    if (streams.world != nullptr)
        *streams.world << world_csv_header(scenario, model::output_nodes(scenario)) << '\n';
    if (streams.contacts != nullptr) *streams.contacts << contacts_csv_header() << '\n';
    if (streams.procedure != nullptr) *streams.procedure << procedure_csv_header() << '\n';

    model::SimulationCallbacks callbacks;
    callbacks.on_step = [&](const model::World& w, const model::WorldStepReport&) {
        latest = reader.read(w);
        const model::truth::TruthReadout truth_now = truth_reader.read(w);
        truth.add(truth_sample(truth_now));
        const std::int64_t now_us = to_us(w.time_s());
        const double span_us = static_cast<double>(now_us - to_us(previous.time_s));
        for (std::int64_t t = last_tick_us + sensors::kTickUs; t <= now_us; t += sensors::kTickUs) {
            const double weight =
                span_us > 0 ? static_cast<double>(t - to_us(previous.time_s)) / span_us : 1.0;
            recording::RecordingRow row = suite.tick(truth_of(blend(previous, latest, weight), t));
            if (!row.has_sensor_data()) continue;
            row = recording::wire::quantize_to_wire(row);
            if (row.handle)
                result.peak_measured_handle_force_N =
                    std::max(result.peak_measured_handle_force_N, std::abs(row.handle->force_N));
            if (recording_writer) recording_writer->write(row);
            firmware.deliver(row);
            last_delivered_us = t;
            ++result.rows_delivered;
            last_tick_us = t;
        }
        last_tick_us = std::max(last_tick_us, now_us - (now_us % sensors::kTickUs));
        // True advance efficiency per region (hand advancing only).
        const double handle_step = latest.insertion_mm - previous.insertion_mm;
        if (handle_step > 0.0) {
            RegionAdvance& bucket = result.advance_by_region[latest.tip_region];
            bucket.handle_advance_mm += handle_step;
            bucket.tip_advance_mm += latest.tip_path_mm - previous.tip_path_mm;
        }
        result.peak_true_tip_contact_force_N =
            std::max(result.peak_true_tip_contact_force_N, latest.tip_force_N.norm());
        for (const model::WorldContact& c : w.contacts())
            if (c.normal_force_N > result.peak_true_contact_force_N) {
                result.peak_true_contact_force_N = c.normal_force_N;
                result.peak_true_contact_region = std::string(model::region_name(c.region));
            }
        previous = latest;
        write_frame(w.time_s());
        if (streams.view_step)
            streams.view_step(
                {w.time_s(), [&] { return view_row(latest, truth_now, firmware.box().outputs()); },
                 [&] { return frame_text(w); }});
        if (snapshot_wanted) {
            take_snapshot(snapshot_label);
            snapshot_wanted = false;
        }
        while (next_action < actions.size() && w.time_s() + 1e-9 >= actions[next_action].start_s) {
            // Where the hand changes course: the shape the last action left.
            const model::ActionKind kind = actions[next_action].kind;
            if (kind != model::ActionKind::hold && kind != model::ActionKind::rotate)
                take_snapshot(std::string(model::action_name(kind)) + " starts");
            ++next_action;
        }
    };
    callbacks.on_sample = [&](const model::WorldRow& s, const model::World& w) {
        if (streams.world != nullptr) write_world_csv_row(*streams.world, s, latest);
        if (streams.contacts != nullptr) write_contacts_csv_rows(*streams.contacts, s.time_s, w);
    };
    std::string last_hand_state;
    callbacks.on_hand_sample = [&](double time_s, const model::HandState& hand) {
        if (streams.procedure != nullptr) write_procedure_csv_row(*streams.procedure, time_s, hand);
        // Where the physician starts a loop reduction: the shape the loop has then.
        if (scenario.physician && hand.state != last_hand_state && hand.state == "reduce_loop_turn")
            take_snapshot("loop reduction starts");
        last_hand_state = hand.state;
    };
    callbacks.on_progress = on_progress;

    result.world = model::run_simulation(*world, scenario, callbacks);
    firmware.finish(static_cast<std::uint64_t>(last_delivered_us));
    snapshots.erase(
        snapshots.begin() + static_cast<long>(std::min(snapshots.size(), kMaxSnapshots - 1)),
        snapshots.end());
    take_snapshot(result.world.complete ? "end" : "failure", true);
    result.snapshots = {{"colon", WorldReader::colon_json(world->colon())},
                        {"snapshots", snapshots}};
    result.box = observer.observation();
    result.box_json = observer.to_json();
    result.box_section = observer.box_section();
    result.firmware_periods = firmware.periods();
    result.final_tip_path_mm = latest.tip_path_mm;
    result.final_tip_region = latest.tip_region;
    result.sensor_counters = sensor_counters_json(suite.counters());
    result.truth = truth.write(streams.truth, period_times_us, truth_reader.layout().stations);
    result.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    return result;
}

}  // namespace scopekin::host_sim
