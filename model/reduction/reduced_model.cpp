#include "model/reduction/reduced_model.hpp"

#include <cmath>
#include <filesystem>
#include <memory>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::model {

namespace {

/// A stretch "slid" between two knots if its path position moved, in the run's direction, by
/// more than this fraction of the knot spacing (~1 per mm while sliding, ~0 when stuck).
constexpr double kSlidThreshold = 0.2;

/// A station slid between two knots of a hold run if it moved by more than this [mm].
constexpr double kHoldSlidThreshold_mm = 0.01;

bool is_hold(const ReductionSegmentSpec& s) {
    return s.kind == kinetics::kSegmentHold;
}

std::size_t segment_knots(const ReductionSegmentSpec& s) {
    const double intervals = is_hold(s) ? s.duration_s / s.step_s
                                        : std::fabs(s.depth_to_mm - s.depth_from_mm) / s.step_mm;
    return static_cast<std::size_t>(std::lround(intervals)) + 1;
}

}  // namespace

void ReductionSettings::validate() const {
    if (stations < 1 || stations > 64) throw ModelError(source + ": stations must be in [1, 64]");
    require_positive(station_spacing_mm, source + ": station_spacing_mm");
    if (compliance_every < 1) throw ModelError(source + ": compliance_every must be at least 1");
    if (segments.empty() || segments.size() > kinetics::kMaxReducedSegments)
        throw ModelError(source + ": between 1 and " +
                         std::to_string(kinetics::kMaxReducedSegments) + " segments");
    for (std::size_t i = 0; i < segments.size(); ++i) {
        const ReductionSegmentSpec& s = segments[i];
        const std::string where = source + ": segments[" + std::to_string(i) + "]";
        if (i == 0 && (is_hold(s) || s.direction != 1))
            throw ModelError(where +
                             ": segment 0 must advance (it covers the model's depth range)");
        require_non_negative(s.after_s, where + ".after_s");
        double intervals = 0;
        if (is_hold(s)) {
            require_positive(s.duration_s, where + ".duration_s");
            require_positive(s.step_s, where + ".step_s");
            intervals = s.duration_s / s.step_s;
        } else {
            if (s.direction != 1 && s.direction != -1)
                throw ModelError(where + ".direction: advance or withdraw");
            require_non_negative(s.depth_from_mm, where + ".depth_from_mm");
            require_non_negative(s.depth_to_mm, where + ".depth_to_mm");
            require_positive(s.step_mm, where + ".step_mm");
            if (!((s.depth_to_mm - s.depth_from_mm) * s.direction > 0))
                throw ModelError(
                    where + ": depth_to_mm must lie past depth_from_mm in the segment's direction");
            intervals = std::fabs(s.depth_to_mm - s.depth_from_mm) / s.step_mm;
        }
        if (std::fabs(intervals - std::round(intervals)) > 1e-9)
            throw ModelError(where + ": the range must be a whole number of steps");
        if ((segment_knots(s) - 1) % compliance_every != 0)
            throw ModelError(where + ": the knot intervals (" +
                             std::to_string(segment_knots(s) - 1) +
                             ") must be a multiple of compliance_every (" +
                             std::to_string(compliance_every) + ")");
        if (s.scenario.kind != ScenarioKind::world)
            throw ModelError(where + ": the training scenario must be a world scenario");
    }
}

ReductionSettings read_reduction_spec(const std::string& filename) {
    const nlohmann::json document = io::parse_json_file(filename);
    const io::JsonObject root(document, filename + ":");
    root.allow_only(
        {"description", "stations", "station_spacing_mm", "compliance_every", "segments"});
    ReductionSettings settings;
    settings.source = filename;
    settings.stations = root.index_or("stations", settings.stations);
    settings.station_spacing_mm = root.number_or("station_spacing_mm", settings.station_spacing_mm);
    settings.compliance_every = root.index_or("compliance_every", settings.compliance_every);
    const nlohmann::json& segments = root.array("segments");
    const std::filesystem::path directory = std::filesystem::path(filename).parent_path();
    for (std::size_t i = 0; i < segments.size(); ++i) {
        const io::JsonObject o(segments[i], root.field("segments") + "[" + std::to_string(i) + "]");
        ReductionSegmentSpec s;
        const std::string direction = o.string("direction");
        if (direction == "hold") {
            o.allow_only({"scenario", "direction", "after_s", "duration_s", "step_s"});
            s.kind = kinetics::kSegmentHold;
            s.after_s = o.number("after_s");
            s.duration_s = o.number("duration_s");
            s.step_s = o.number("step_s");
        } else if (direction == "advance" || direction == "withdraw") {
            o.allow_only(
                {"scenario", "direction", "depth_from_mm", "depth_to_mm", "step_mm", "after_s"});
            s.direction = direction == "advance" ? 1 : -1;
            s.depth_from_mm = o.number("depth_from_mm");
            s.depth_to_mm = o.number("depth_to_mm");
            s.step_mm = o.number("step_mm");
            s.after_s = o.number_or("after_s", 0.0);
        } else {
            throw ModelError(o.field("direction") + ": '" + direction +
                             "' (known: advance, withdraw, hold)");
        }
        s.scenario = read_scenario_file((directory / o.string("scenario")).string());
        settings.segments.push_back(std::move(s));
    }
    settings.validate();
    return settings;
}

std::vector<std::size_t> station_nodes(const World& world, std::size_t stations,
                                       double station_spacing_mm) {
    const std::size_t tip = world.scope_node_count() - 1;
    const double element_mm = world.scope_length_mm() / static_cast<double>(tip);
    std::vector<std::size_t> nodes;
    for (std::size_t j = 0; j < stations; ++j) {
        const double steps = station_spacing_mm * static_cast<double>(j) / element_mm;
        const auto back = static_cast<std::size_t>(std::lround(steps));
        if (std::fabs(steps - static_cast<double>(back)) > 1e-9 || back > tip)
            throw ModelError(
                "reduction station_spacing_mm: stations must fall on scope nodes (element length " +
                number_text(element_mm) + " mm) and on the scope");
        nodes.push_back(tip - back);
    }
    return nodes;
}

std::vector<Eigen::Vector3d> station_forces(const World& world, const StationCompliance& probe,
                                            std::size_t stations, double station_spacing_mm) {
    const std::size_t k = stations;
    std::vector<Eigen::Vector3d> body(k, Eigen::Vector3d::Zero());
    const double half = 0.5 * station_spacing_mm;
    for (const WorldContact& c : world.contacts()) {
        const double j = std::floor((c.arc_from_tip_mm + half) / station_spacing_mm);
        if (j < 0.0 || j >= static_cast<double>(k)) continue;
        body[static_cast<std::size_t>(j)] += c.force_N;
    }
    std::vector<Eigen::Vector3d> local(k, Eigen::Vector3d::Zero());
    for (std::size_t j = 0; j < k; ++j)
        local[j] = probe.stations[k - 1 - j].frame.transpose() * body[j];
    return local;
}

namespace {

struct Probe {
    std::vector<double> knot;        ///< knot record
    std::vector<double> compliance;  ///< compliance record
    std::vector<bool> inside;
    double hold_depth_mm = 0;  ///< hold runs: the depth held
};

/// One knot's records in the firmware's layout (station 0 = tip first).
Probe probe_knot(World& world, const std::vector<std::size_t>& nodes_increasing,
                 const ReductionSettings& settings) {
    const std::size_t k = settings.stations;
    const StationCompliance probe = world.probe_stations(nodes_increasing);
    const std::vector<Eigen::Vector3d> forces =
        station_forces(world, probe, k, settings.station_spacing_mm);
    Probe out;
    out.knot.assign(kinetics::reduced_knot_size(k), 0.0);
    out.compliance.assign(kinetics::reduced_compliance_size(k), 0.0);
    out.inside.assign(k, false);
    for (std::size_t j = 0; j < k; ++j) {
        const StationProbe& p = probe.stations[k - 1 - j];
        out.inside[j] = p.inside;
        const std::size_t base = j * kinetics::kStationValueCount;
        out.knot[base + kinetics::kStationPath] = p.path_mm;
        out.knot[base + kinetics::kStationGap] = std::max(0.0, p.gap_mm);
        for (std::size_t c = 0; c < 3; ++c)
            out.knot[base + kinetics::kStationForceN + c] = forces[j](static_cast<Eigen::Index>(c));
    }
    const Eigen::Vector3d tip = world.node_position_mm(world.scope_node_count() - 1);
    const std::size_t knot_base = k * kinetics::kStationValueCount;
    for (std::size_t c = 0; c < 3; ++c)
        out.knot[knot_base + kinetics::kKnotTipX + c] = tip(static_cast<Eigen::Index>(c));
    // What the box's force cell reads at this knot (the force the position-controlled hand needs).
    out.knot[knot_base + kinetics::kKnotHandleForce] = world.handle_force_N();
    // Compliance (reduced_kinetics.hpp, "Compliance"): each station's compliance with the other
    // stations held — the inverse of its diagonal block of the stations' stiffness W^-1 (static
    // condensation onto one station) — then split: the normal compliance, and the tangential
    // block with the normal held by the wall (Schur complement W_TT - W_Tn W_nT / W_nn).
    std::vector<std::size_t> in;
    for (std::size_t j = 0; j < k; ++j)
        if (out.inside[j]) in.push_back(j);
    const auto m = static_cast<Eigen::Index>(3 * in.size());
    Eigen::MatrixXd w(m, m);
    for (std::size_t ia = 0; ia < in.size(); ++ia)
        for (std::size_t ib = 0; ib < in.size(); ++ib)
            w.block<3, 3>(static_cast<Eigen::Index>(3 * ia), static_cast<Eigen::Index>(3 * ib)) =
                probe.compliance_mm_per_N.block<3, 3>(
                    static_cast<Eigen::Index>(3 * (k - 1 - in[ia])),
                    static_cast<Eigen::Index>(3 * (k - 1 - in[ib])));
    const Eigen::MatrixXd stiffness =
        Eigen::MatrixXd(0.5 * (w + w.transpose())).ldlt().solve(Eigen::MatrixXd::Identity(m, m));
    for (std::size_t ia = 0; ia < in.size(); ++ia) {
        const Eigen::Matrix3d block = stiffness.block<3, 3>(static_cast<Eigen::Index>(3 * ia),
                                                            static_cast<Eigen::Index>(3 * ia));
        const Eigen::Matrix3d held = Eigen::Matrix3d(0.5 * (block + block.transpose())).inverse();
        const Eigen::Matrix2d tangential =
            held.block<2, 2>(1, 1) - held.block<2, 1>(1, 0) * held.block<1, 2>(0, 1) / held(0, 0);
        const std::size_t base = in[ia] * kinetics::kComplianceValueCount;
        out.compliance[base + kinetics::kComplianceNN] = held(0, 0);
        out.compliance[base + kinetics::kComplianceTT] = tangential(0, 0);
        out.compliance[base + kinetics::kComplianceTS] =
            0.5 * (tangential(0, 1) + tangential(1, 0));
        out.compliance[base + kinetics::kComplianceSS] = tangential(1, 1);
    }
    return out;
}

/// Runs one segment and returns its probes in increasing depth.
std::vector<Probe> run_segment(const ReductionSettings& settings, std::size_t index,
                               const std::function<void(const ReductionProgress&)>& on_progress) {
    const ReductionSegmentSpec& spec = settings.segments[index];
    const Scenario& training = spec.scenario;
    std::unique_ptr<World> world = build_world(training);
    const std::vector<std::size_t> tip_first =
        station_nodes(*world, settings.stations, settings.station_spacing_mm);
    const std::vector<std::size_t> increasing(tip_first.rbegin(), tip_first.rend());
    ProcedurePlayer player(training.procedure, training.settings.initial_insertion_mm,
                           training.scope.length_mm);
    const std::size_t knots = segment_knots(spec);
    std::vector<Probe> probes;
    const double h = world->time_step_s();
    const double tolerance = 1e-6;
    const double sign = spec.direction;
    double hold_depth_mm = -1.0;
    while (probes.size() < knots) {
        const double depth = world->insertion_depth_mm();
        if (is_hold(spec)) {
            const double target_s = spec.after_s + spec.step_s * static_cast<double>(probes.size());
            if (std::fabs(world->time_s() - target_s) <= 1e-6) {
                if (probes.empty()) hold_depth_mm = depth;
                if (std::fabs(depth - hold_depth_mm) > tolerance)
                    throw ModelError(training.source + ": the depth moves during the hold run (" +
                                     number_text(hold_depth_mm) + " mm at " +
                                     number_text(spec.after_s) + " s, " + number_text(depth) +
                                     " mm at " + number_text(target_s) + " s)");
                probes.push_back(probe_knot(*world, increasing, settings));
                probes.back().hold_depth_mm = hold_depth_mm;
                if (on_progress)
                    on_progress({index, settings.segments.size(), probes.size(), knots});
                continue;
            }
            if (world->time_s() > target_s + 1e-6)
                throw ModelError(training.source + ": the hold knot at " + number_text(target_s) +
                                 " s falls between solver steps; make after_s and step_s multiples "
                                 "of the solver step");
        } else {
            const double target =
                spec.depth_from_mm + sign * spec.step_mm * static_cast<double>(probes.size());
            const bool probing = world->time_s() >= spec.after_s - 1e-9;
            if (probing && std::fabs(depth - target) <= tolerance) {
                probes.push_back(probe_knot(*world, increasing, settings));
                if (on_progress)
                    on_progress({index, settings.segments.size(), probes.size(), knots});
                continue;
            }
            if (probing && (depth - target) * sign > tolerance)
                throw ModelError(training.source + ": the training run passed the knot at " +
                                 number_text(target) + " mm between steps (depth now " +
                                 number_text(depth) +
                                 " mm); make the step a multiple of the depth per solver step, or "
                                 "start on a step");
        }
        if (world->time_s() >= training.procedure.end_s() - 1e-9)
            throw ModelError(training.source + ": the training procedure ends before knot " +
                             std::to_string(probes.size() + 1) + " of " + std::to_string(knots) +
                             " (depth " + number_text(depth) + " mm)");
        const HandleCommand command = player.command(world->time_s(), h, depth, world->roll_rad());
        if (command.force_controlled)
            throw ModelError(training.source +
                             ": the training procedure must prescribe the depth (no push)");
        const WorldStepReport report = world->step(command);
        if (!report.ok)
            throw ModelError(training.source + ": the training run failed at t = " +
                             number_text(world->time_s()) + " s: " + report.failure);
    }
    if (spec.direction < 0) std::reverse(probes.begin(), probes.end());
    return probes;
}

}  // namespace

ReducedModelData build_reduced_model(
    const ReductionSettings& settings,
    const std::function<void(const ReductionProgress&)>& on_progress) {
    settings.validate();
    const std::size_t k = settings.stations;
    ReducedModelData data;
    data.settings = settings;
    data.head.stations = k;
    data.head.compliance_every = settings.compliance_every;
    data.head.friction = settings.segments[0].scenario.settings.contact.friction_coefficient;
    data.head.station_spacing_mm = settings.station_spacing_mm;
    data.head.segment_count = settings.segments.size();
    for (std::size_t i = 0; i < settings.segments.size(); ++i) {
        const ReductionSegmentSpec& spec = settings.segments[i];
        if (spec.scenario.settings.contact.friction_coefficient != data.head.friction)
            throw ModelError(spec.scenario.source +
                             ": every training run must use the same wall friction");
        std::vector<Probe> probes = run_segment(settings, i, on_progress);
        const std::size_t n = probes.size();
        // Slip signs (reduced_kinetics.hpp, "Station friction"): the sign of the stretch's path
        // motion, in the run's time order, from knot g to g + 1 where it moved by more than the
        // threshold (a travel run's knots are stored in increasing depth: a withdrawal runs them
        // backwards), 0 where it stuck.
        const double time_order = is_hold(spec) ? 1.0 : spec.direction;
        const double threshold =
            is_hold(spec) ? kHoldSlidThreshold_mm : kSlidThreshold * spec.step_mm;
        for (std::size_t g = 0; g < n; ++g)
            for (std::size_t j = 0; j < k; ++j) {
                const std::size_t base = j * kinetics::kStationValueCount;
                const std::size_t a = g + 1 < n ? g : g - 1;
                const double moved =
                    time_order * (probes[a + 1].knot[base + kinetics::kStationPath] -
                                  probes[a].knot[base + kinetics::kStationPath]);
                probes[g].knot[base + kinetics::kStationSlid] =
                    std::fabs(moved) > threshold ? (moved > 0 ? 1.0 : -1.0) : 0.0;
            }
        // A station outside the body at a knot takes its values from the first knot where it is
        // inside: interpolation just after it enters then starts from real data.
        for (std::size_t j = 0; j < k; ++j) {
            std::size_t first_inside = n;
            for (std::size_t g = 0; g < n && first_inside == n; ++g)
                if (probes[g].inside[j]) first_inside = g;
            if (first_inside == n) continue;
            for (std::size_t g = 0; g < first_inside; ++g) {
                for (std::size_t v = 0; v < kinetics::kStationValueCount; ++v)
                    probes[g].knot[j * kinetics::kStationValueCount + v] =
                        probes[first_inside].knot[j * kinetics::kStationValueCount + v];
                for (std::size_t v = 0; v < kinetics::kComplianceValueCount; ++v)
                    probes[g].compliance[j * kinetics::kComplianceValueCount + v] =
                        probes[first_inside].compliance[j * kinetics::kComplianceValueCount + v];
            }
        }
        kinetics::ReducedSegment<double>& segment = data.head.segments[i];
        segment.kind = spec.kind;
        segment.direction = spec.direction;
        segment.key_start = is_hold(spec) ? 0.0 : std::min(spec.depth_from_mm, spec.depth_to_mm);
        segment.key_step = is_hold(spec) ? spec.step_s : spec.step_mm;
        segment.hold_depth_mm = is_hold(spec) ? probes.front().hold_depth_mm : 0.0;
        segment.knots = n;
        segment.first_knot = data.knots.size();
        segment.first_compliance = data.compliances.size();
        for (std::size_t g = 0; g < n; ++g) {
            data.knots.push_back(probes[g].knot);
            if (g % settings.compliance_every == 0)
                data.compliances.push_back(probes[g].compliance);
        }
    }
    return data;
}

}  // namespace scopekin::model
