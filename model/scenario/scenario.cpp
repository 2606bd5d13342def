#include "model/scenario/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <tuple>
#include <utility>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_beam.hpp"
#include "model/effects/effect_library.hpp"
#include "model/effects/ei_profile.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"
#include "model/scenario/abdominal_pressure.hpp"
#include "model/scenario/tip_steering.hpp"
#include "model/scope/cf_q160l.hpp"

namespace scopekin::model {
namespace {

using io::JsonObject;

std::string item(const std::string& path, std::size_t i) {
    return path + "[" + std::to_string(i) + "]";
}

std::string region_list() {
    std::string list;
    for (ColonRegion r : kColonRegionsInOrder)
        list += std::string(list.empty() ? "" : ", ") + std::string(region_name(r));
    return list;
}

ColonRegion read_region(const JsonObject& o, const char* key) {
    const std::string name = o.string(key);
    const auto region = region_from_name(name);
    if (!region)
        throw ModelError(o.field(key) + ": unknown region " + io::quote_text(name) +
                         " (known: " + region_list() + ")");
    return *region;
}

ColonRegion read_region_or(const JsonObject& o, const char* key, ColonRegion fallback) {
    return o.has(key) ? read_region(o, key) : fallback;
}

/// start_s and end_s of a time window (steering, abdominal pressure): start >= 0, end > start [s].
std::pair<double, double> read_window_times(const JsonObject& w) {
    const double start_s = w.number("start_s");
    const double end_s = w.number("end_s");
    require_non_negative(start_s, w.field("start_s"));
    if (!(end_s > start_s))
        throw ModelError(w.field("end_s") + ": " + number_text(end_s) +
                         " s must be later than start_s");
    return {start_s, end_s};
}

double positive(const JsonObject& o, const char* key) {
    const double v = o.number(key);
    require_positive(v, o.field(key));
    return v;
}

double positive_or(const JsonObject& o, const char* key, double fallback) {
    return o.has(key) ? positive(o, key) : fallback;
}

double non_negative_or(const JsonObject& o, const char* key, double fallback) {
    if (!o.has(key)) return fallback;
    const double v = o.number(key);
    require_non_negative(v, o.field(key));
    return v;
}

ScopeSpec read_scope(const JsonObject& o, std::string& model) {
    o.allow_only({"model", "length_mm", "elements", "bending_stiffness_Nmm2", "radius_mm"});
    model = o.string("model");
    if (model != "cf_q160l")
        throw ModelError(o.field("model") + ": unknown scope model " + io::quote_text(model) +
                         " (known: cf_q160l)");
    ScopeSpec s;
    s.length_mm = positive_or(o, "length_mm", cf_q160l::kWorkingLength_mm);
    s.elements = o.index_or("elements", 170);
    if (s.elements < 2 || s.elements > 2000)
        throw ModelError(o.field("elements") + ": " + std::to_string(s.elements) +
                         " must be in 2..2000");
    s.radius_mm = positive_or(o, "radius_mm", cf_q160l::kRadius_mm);
    s.section = cf_q160l::section(
        positive_or(o, "bending_stiffness_Nmm2", cf_q160l::kBendingStiffness_Nmm2));
    return s;
}

ColonTube read_colon(const JsonObject& o, double scope_radius_mm) {
    if (o.has("bundled") == o.has("waypoints"))
        throw ModelError(o.path() +
                         ": give exactly one of 'bundled' (a bundled colon) or 'waypoints' (your "
                         "own centerline)");
    try {
        if (o.has("bundled")) {
            const std::string name = o.string("bundled");
            if (name == "default") {
                o.allow_only({"bundled"});
                return default_colon(scope_radius_mm);
            }
            if (name == "straight_tube") {
                o.allow_only({"bundled", "length_mm", "inner_radius_mm", "region"});
                return straight_tube(positive(o, "length_mm"), positive(o, "inner_radius_mm"),
                                     read_region_or(o, "region", ColonRegion::sigmoid),
                                     scope_radius_mm);
            }
            if (name == "single_bend") {
                o.allow_only({"bundled", "lead_mm", "bend_radius_mm", "bend_angle_deg",
                              "inner_radius_mm", "region"});
                const double angle = positive(o, "bend_angle_deg");
                if (angle > 180.0)
                    throw ModelError(o.field("bend_angle_deg") + ": " + number_text(angle) +
                                     " must be <= 180");
                return single_bend(positive(o, "lead_mm"), positive(o, "bend_radius_mm"),
                                   angle * M_PI / 180.0, positive(o, "inner_radius_mm"),
                                   read_region_or(o, "region", ColonRegion::sigmoid),
                                   scope_radius_mm);
            }
            throw ModelError(o.field("bundled") + ": unknown bundled colon " +
                             io::quote_text(name) +
                             " (known: default, straight_tube, single_bend)");
        }
        o.allow_only({"waypoints", "spacing_mm"});
        const nlohmann::json& list = o.array("waypoints");
        const std::string list_path = o.field("waypoints");
        if (list.size() < 2) throw ModelError(list_path + ": needs at least 2 waypoints");
        std::vector<ColonPoint> waypoints;
        for (std::size_t i = 0; i < list.size(); ++i) {
            const JsonObject w(list[i], item(list_path, i));
            w.allow_only({"position_mm", "inner_radius_mm", "region"});
            ColonPoint p;
            p.position_mm = w.vector3("position_mm");
            p.inner_radius_mm = positive(w, "inner_radius_mm");
            if (p.inner_radius_mm <= scope_radius_mm)
                throw ModelError(w.field("inner_radius_mm") + ": " +
                                 number_text(p.inner_radius_mm) +
                                 " mm is not larger than the scope's radius (" +
                                 number_text(scope_radius_mm) + " mm)");
            p.region = read_region(w, "region");
            if (i > 0 && !((p.position_mm - waypoints.back().position_mm).norm() > 1e-6))
                throw ModelError(w.field("position_mm") + ": coincides with the previous waypoint");
            waypoints.push_back(p);
        }
        const double spacing = positive_or(o, "spacing_mm", 10.0);
        return ColonTube("waypoints", sample_centerline(waypoints, spacing), scope_radius_mm);
    } catch (const ModelError& e) {
        const std::string message = e.what();
        // Messages that already carry the file's path pass through; the colon's own checks get it.
        if (message.rfind(o.path(), 0) == 0) throw;
        throw ModelError(o.path() + ": " + message);
    }
}

ProcedureAction read_action(const JsonObject& o) {
    ProcedureAction a;
    const std::string name = o.string("action");
    a.start_s = o.number("start_s");
    a.end_s = o.number("end_s");
    if (name == "advance" || name == "withdraw") {
        o.allow_only({"action", "start_s", "end_s", "speed_mm_per_s"});
        a.kind = name == "advance" ? ActionKind::advance : ActionKind::withdraw;
        a.speed_mm_per_s = o.number("speed_mm_per_s");
    } else if (name == "hold") {
        o.allow_only({"action", "start_s", "end_s"});
        a.kind = ActionKind::hold;
    } else if (name == "push") {
        o.allow_only({"action", "start_s", "end_s", "force_N"});
        a.kind = ActionKind::push;
        a.force_N = o.number("force_N");
    } else if (name == "twist") {
        o.allow_only({"action", "start_s", "end_s", "torque_Nmm"});
        a.kind = ActionKind::twist;
        a.torque_Nmm = o.number("torque_Nmm");
    } else if (name == "rotate") {
        o.allow_only({"action", "start_s", "end_s", "speed_deg_per_s"});
        a.kind = ActionKind::rotate;
        a.speed_deg_per_s = o.number("speed_deg_per_s");
    } else if (name == "dither") {
        o.allow_only({"action", "start_s", "end_s", "amplitude_mm", "frequency_Hz"});
        a.kind = ActionKind::dither;
        a.amplitude_mm = o.number("amplitude_mm");
        a.frequency_Hz = o.number("frequency_Hz");
    } else {
        throw ModelError(o.field("action") + ": unknown action " + io::quote_text(name) +
                         " (known: advance, withdraw, hold, push, twist, rotate, dither)");
    }
    return a;
}

WorldContactSettings read_contact(const JsonObject& o) {
    o.allow_only({"friction_coefficient", "friction_zones", "activation_distance_mm",
                  "wall_compliance_mm_per_N", "tolerance_N", "max_sweeps", "relaxation"});
    WorldContactSettings c;
    c.friction_coefficient = non_negative_or(o, "friction_coefficient", c.friction_coefficient);
    c.activation_distance_mm =
        non_negative_or(o, "activation_distance_mm", c.activation_distance_mm);
    c.wall_compliance_mm_per_N =
        non_negative_or(o, "wall_compliance_mm_per_N", c.wall_compliance_mm_per_N);
    c.tolerance_N = positive_or(o, "tolerance_N", c.tolerance_N);
    c.max_sweeps = o.index_or("max_sweeps", c.max_sweeps);
    if (c.max_sweeps < 1 || c.max_sweeps > 1000000)
        throw ModelError(o.field("max_sweeps") + ": " + std::to_string(c.max_sweeps) +
                         " must be in 1..1000000");
    c.relaxation = o.number_or("relaxation", c.relaxation);
    if (!(c.relaxation > 0.0 && c.relaxation < 2.0))
        throw ModelError(o.field("relaxation") + ": " + number_text(c.relaxation) +
                         " must be in (0, 2)");
    if (o.has("friction_zones")) {
        const nlohmann::json& zones = o.array("friction_zones");
        for (std::size_t i = 0; i < zones.size(); ++i) {
            const JsonObject z(zones[i], item(o.field("friction_zones"), i));
            z.allow_only({"from_tip_mm", "to_tip_mm", "coefficient"});
            FrictionZone zone;
            zone.from_tip_mm = z.number("from_tip_mm");
            require_non_negative(zone.from_tip_mm, z.field("from_tip_mm"));
            zone.to_tip_mm = z.number("to_tip_mm");
            if (!(zone.to_tip_mm > zone.from_tip_mm))
                throw ModelError(z.field("to_tip_mm") + ": " + number_text(zone.to_tip_mm) +
                                 " mm must be greater than from_tip_mm (" +
                                 number_text(zone.from_tip_mm) + " mm)");
            zone.coefficient = z.number("coefficient");
            require_non_negative(zone.coefficient, z.field("coefficient"));
            c.friction_zones.push_back(zone);
        }
    }
    return c;
}

/// "telescoping": the colon's mobile stretches pleat onto the scope (model/colon/colon_pleating.hpp).
TelescopingLaw read_telescoping(const JsonObject& o) {
    o.allow_only({"enabled", "onset_drag_N", "stiffening_drag_N", "recoil_time_s", "rate_per_N_s",
                  "max_fraction"});
    TelescopingLaw t;
    t.enabled = o.boolean_or("enabled", t.enabled);
    t.onset_drag_N = non_negative_or(o, "onset_drag_N", t.onset_drag_N);
    t.stiffening_drag_N = positive_or(o, "stiffening_drag_N", t.stiffening_drag_N);
    t.recoil_time_s = positive_or(o, "recoil_time_s", t.recoil_time_s);
    t.rate_per_N_s = positive_or(o, "rate_per_N_s", t.rate_per_N_s);
    t.max_fraction = o.number_or("max_fraction", t.max_fraction);
    if (!(t.max_fraction >= 0.0 && t.max_fraction < 1.0))
        throw ModelError(o.field("max_fraction") + ": " + number_text(t.max_fraction) +
                         " must be in [0, 1)");
    return t;
}

void read_solver(const JsonObject& o, WorldSettings& s) {
    o.allow_only({"time_step_s", "newton_iterations", "damping", "contact"});
    s.time_step_s = positive_or(o, "time_step_s", s.time_step_s);
    if (s.time_step_s < 0.001 - 1e-12 || s.time_step_s > 0.033 + 1e-12)
        throw ModelError(o.field("time_step_s") + ": " + number_text(s.time_step_s) +
                         " s is outside [0.001, 0.033] s");
    const std::size_t newton =
        o.index_or("newton_iterations", static_cast<std::size_t>(s.newton_iterations));
    if (newton < 1 || newton > 50)
        throw ModelError(o.field("newton_iterations") + ": " + std::to_string(newton) +
                         " must be in 1..50");
    s.newton_iterations = static_cast<int>(newton);
    if (o.has("damping")) {
        const JsonObject d = o.object("damping");
        d.allow_only({"alpha_hz_convention", "beta_hz_convention"});
        s.damping =
            RayleighDamping::from_hz_convention(non_negative_or(d, "alpha_hz_convention", 0.3864),
                                                non_negative_or(d, "beta_hz_convention", 0.0164));
    }
    if (o.has("contact")) s.contact = read_contact(o.object("contact"));
}

ScenarioOutputs read_outputs(const JsonObject& o, double scope_length_mm, std::size_t elements,
                             double time_step_s) {
    o.allow_only({"sample_rate_Hz", "nodes_from_tip_mm", "contacts_file"});
    ScenarioOutputs out;
    out.sample_rate_Hz = positive_or(o, "sample_rate_Hz", out.sample_rate_Hz);
    if (out.sample_rate_Hz > (1.0 + 1e-9) / time_step_s)
        throw ModelError(o.field("sample_rate_Hz") + ": " + number_text(out.sample_rate_Hz) +
                         " Hz is above the step rate 1 / solver.time_step_s = " +
                         number_text(1.0 / time_step_s) + " Hz");
    if (o.has("nodes_from_tip_mm")) {
        const nlohmann::json& nodes = o.array("nodes_from_tip_mm");
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const std::string at = item(o.field("nodes_from_tip_mm"), i);
            if (!nodes[i].is_number())
                throw ModelError(at + ": expected a number (mm from the tip)");
            const double arc = nodes[i].get<double>();
            require_non_negative(arc, at);
            if (arc > scope_length_mm)
                throw ModelError(at + ": " + number_text(arc) +
                                 " mm is beyond the scope's length (" +
                                 number_text(scope_length_mm) + " mm)");
            const std::size_t node = scope_node_from_tip(arc, scope_length_mm, elements);
            for (std::size_t j = 0; j < out.nodes_from_tip_mm.size(); ++j)
                if (scope_node_from_tip(out.nodes_from_tip_mm[j], scope_length_mm, elements) ==
                    node)
                    throw ModelError(
                        at + ": " + number_text(arc) + " mm gives the same scope node as [" +
                        std::to_string(j) + "] (" + number_text(out.nodes_from_tip_mm[j]) +
                        " mm; nodes are every " +
                        number_text(scope_length_mm / static_cast<double>(elements)) + " mm)");
            out.nodes_from_tip_mm.push_back(arc);
        }
    }
    out.contacts_file = o.boolean_or("contacts_file", false);
    return out;
}

}  // namespace

std::size_t scope_node_from_tip(double arc_from_tip_mm, double scope_length_mm,
                                std::size_t elements) {
    const double from_tip =
        std::round(arc_from_tip_mm / scope_length_mm * static_cast<double>(elements));
    const auto k =
        static_cast<std::size_t>(std::clamp(from_tip, 0.0, static_cast<double>(elements)));
    return elements - k;
}

namespace {

/// "procedure": the actions, each at least one time step long, dithers slow enough for the step.
void read_procedure(const JsonObject& root, Scenario& sc) {
    const nlohmann::json& steps = root.array("procedure");
    const std::string procedure_path = root.field("procedure");
    std::vector<ProcedureAction> actions;
    for (std::size_t i = 0; i < steps.size(); ++i) {
        const JsonObject a(steps[i], item(procedure_path, i));
        actions.push_back(read_action(a));
        const ProcedureAction& act = actions.back();
        const double h = sc.settings.time_step_s;
        if (std::isfinite(act.end_s - act.start_s) && act.end_s > act.start_s &&
            act.end_s - act.start_s < h * (1.0 - 1e-9))
            throw ModelError(
                a.path() + ": lasts " + number_text(act.end_s - act.start_s) +
                " s, shorter than one time step (solver.time_step_s = " + number_text(h) + " s)");
        if (act.kind == ActionKind::dither && act.frequency_Hz > 0.25 / h * (1.0 + 1e-9))
            throw ModelError(a.field("frequency_Hz") + ": " + number_text(act.frequency_Hz) +
                             " Hz is too fast for solver.time_step_s = " + number_text(h) +
                             " s (at least 4 steps per period: <= " + number_text(0.25 / h) +
                             " Hz)");
    }
    sc.procedure = Procedure(std::move(actions), procedure_path);
    sc.procedure.check_depths(sc.settings.initial_insertion_mm, sc.scope.length_mm, procedure_path);
}

/// "physician": {"style": ..., "seed": N, "max_duration_s": S, "angulation": "couple" | "wheels",
/// "pressure_stiffness_N_per_mm2": k};
/// the steering and pressure effects
/// it switches are added to the scenario's effects.
void read_physician(const JsonObject& root, Scenario& sc) {
    const JsonObject o = root.object("physician");
    o.allow_only({"style", "seed", "max_duration_s", "angulation", "pressure_stiffness_N_per_mm2"});
    PhysicianSpec spec;
    const std::string style = o.string("style");
    const auto known = physician_style_from_name(style);
    if (!known)
        throw ModelError(o.field("style") + ": unknown style " + io::quote_text(style) +
                         " (known: " + physician_style_list() + ")");
    spec.style = *known;
    spec.seed = read_patient_seed(o, "seed");
    spec.max_duration_s = physician_style_parameters(spec.style).default_max_duration_s;
    if (o.has("max_duration_s")) {
        spec.max_duration_s = o.number("max_duration_s");
        if (!(spec.max_duration_s > 0.0 && spec.max_duration_s <= kMaxPhysicianDuration_s))
            throw ModelError(o.field("max_duration_s") + ": " + number_text(spec.max_duration_s) +
                             " s must be in (0, " + number_text(kMaxPhysicianDuration_s) +
                             "] (1 h at most)");
        if (spec.max_duration_s < sc.settings.time_step_s * (1.0 - 1e-9))
            throw ModelError(o.field("max_duration_s") + ": " + number_text(spec.max_duration_s) +
                             " s is shorter than one time step (solver.time_step_s = " +
                             number_text(sc.settings.time_step_s) + " s)");
    }
    if (o.has("angulation")) {
        const std::string law = o.string("angulation");
        if (law != "couple" && law != "wheels")
            throw ModelError(o.field("angulation") + ": unknown law " + io::quote_text(law) +
                             " (known: couple, wheels)");
        spec.steering_holds_curvature = law == "wheels";
    }
    if (o.has("pressure_stiffness_N_per_mm2")) {
        const double k = o.number("pressure_stiffness_N_per_mm2");
        if (!(k > 0.0 && k <= 1.0))
            throw ModelError(o.field("pressure_stiffness_N_per_mm2") + ": " + number_text(k) +
                             " N/mm per mm must be in (0, 1]");
        spec.pressure_stiffness_N_per_mm2 = k;
    }
    sc.physician = spec;
    sc.scene_control = std::make_shared<SceneControl>();
}

/// "patient": {"seed": N} (draw_patient) or {"file": "patient.json"} (relative to the scenario
/// file, read_patient_file).
PatientSpec read_patient_key(const JsonObject& o, const std::string& source) {
    if (o.has("seed") == o.has("file"))
        throw ModelError(o.path() +
                         ": give exactly one of 'seed' (a patient drawn from the family) or "
                         "'file' (a patient file, relative to this scenario)");
    if (o.has("seed")) {
        o.allow_only({"seed"});
        return draw_patient(read_patient_seed(o, "seed"));
    }
    o.allow_only({"file"});
    const std::string name = o.string("file");
    if (name.empty()) throw ModelError(o.field("file") + ": empty file name");
    const std::filesystem::path file =
        std::filesystem::path(source).parent_path() / std::filesystem::path(name);
    try {
        return read_patient_file(file.string());
    } catch (const ModelError& e) {
        throw ModelError(o.field("file") + ": " + e.what());
    }
}

/// The patient's scope: EI x ei_factor everywhere, x distal_section_factor over its distal
/// section (an ei_profile with equal tip and handle factors).
std::shared_ptr<const WorldEffect> make_patient_scope(const PatientSpec& p) {
    EiProfile::Parameters e;
    e.tip_factor = p.ei_factor;
    e.handle_factor = p.ei_factor;
    e.bending_section_length_mm = p.distal_section_length_mm;
    e.bending_section_factor = p.distal_section_factor;
    return std::make_shared<EiProfile>(e);
}

std::shared_ptr<const WorldEffect> make_tip_steering(const Scenario& sc) {
    const double element_mm = sc.scope.length_mm / static_cast<double>(sc.scope.elements);
    return std::make_shared<TipSteering>(sc.steering, *sc.colon,
                                         sc.scope.section.bending_stiffness_z_Nmm2, element_mm);
}

/// A scenario document; `with_run`: also its run (procedure, initial insertion), which a world
/// model leaves to whoever runs it (read_world_model).
Scenario read_document(const nlohmann::json& document, const std::string& source, bool with_run) {
    const JsonObject root(document, source + ":");
    Scenario sc;
    sc.source = source;
    const bool beam = root.has("beam"), colon = root.has("colon"), patient = root.has("patient");
    if (beam && (colon || patient))
        throw ModelError(source + ": has both 'beam' (a free beam scenario) and '" +
                         (colon ? "colon" : "patient") + "' (a world scenario); give one");
    if (!beam && !colon && !patient)
        throw ModelError(source +
                         ": has neither 'colon' or 'patient' (a world scenario: the scope in a "
                         "colon) nor 'beam' (a free beam scenario: a beam problem file)");
    if (colon && patient)
        throw ModelError(root.field("patient") +
                         ": a scenario takes either 'patient' (its colon, regions, friction and "
                         "scope stiffness) or 'colon', not both");
    if (patient && root.has("colon_regions"))
        throw ModelError(root.field("colon_regions") +
                         ": the patient gives the region properties; remove 'colon_regions' or "
                         "'patient'");
    if (root.has("description")) sc.description = root.string("description");
    if (beam) {
        sc.kind = ScenarioKind::free_beam;
        sc.beam_problem = io::read_beam_problem(document, source);
        return sc;
    }

    sc.kind = ScenarioKind::world;
    root.allow_only({"description", "colon", "colon_regions", "scope", "gravity_mm_per_s2",
                     "initial_insertion_mm", "solver", "procedure", "outputs", "truth_effects",
                     "sensors", "steering", "abdominal_pressure", "patient", "physician",
                     "telescoping"});
    sc.scope = read_scope(root.object("scope"), sc.scope_model);
    if (patient) {
        const JsonObject key = root.object("patient");
        sc.patient = read_patient_key(key, source);
        try {
            sc.colon = patient_colon(*sc.patient, sc.scope.radius_mm);
        } catch (const ModelError& e) {
            throw ModelError(key.path() + ": " + e.what());
        }
    } else {
        sc.colon = read_colon(root.object("colon"), sc.scope.radius_mm);
    }

    sc.colon_properties =
        sc.patient ? patient_colon_properties(*sc.patient) : default_colon_properties();
    if (root.has("colon_regions")) {
        const JsonObject regions = root.object("colon_regions");
        const nlohmann::json& raw = root.raw("colon_regions");
        for (auto it = raw.begin(); it != raw.end(); ++it) {
            const auto region = region_from_name(it.key());
            if (!region)
                throw ModelError(regions.field(it.key()) +
                                 ": unknown region (allowed here: " + region_list() + ")");
            const JsonObject r(it.value(), regions.field(it.key()));
            r.allow_only({"young_modulus_kPa", "wall_thickness_mm", "attachment",
                          "mesentery_stiffness_N_per_mm2"});
            ColonRegionProperties& p = sc.colon_properties[static_cast<std::size_t>(*region)];
            p.young_modulus_kPa = positive_or(r, "young_modulus_kPa", p.young_modulus_kPa);
            p.wall_thickness_mm = positive_or(r, "wall_thickness_mm", p.wall_thickness_mm);
            if (r.has("attachment")) {
                const std::string a = r.string("attachment");
                if (a == "fixed")
                    p.attachment = ColonAttachment::fixed;
                else if (a == "mesentery")
                    p.attachment = ColonAttachment::mesentery;
                else
                    throw ModelError(r.field("attachment") + ": unknown attachment " +
                                     io::quote_text(a) + " (known: fixed, mesentery)");
            }
            p.mesentery_stiffness_N_per_mm2 = non_negative_or(r, "mesentery_stiffness_N_per_mm2",
                                                              p.mesentery_stiffness_N_per_mm2);
            if (p.attachment == ColonAttachment::mesentery &&
                !(p.mesentery_stiffness_N_per_mm2 > 0.0))
                throw ModelError(
                    r.field("mesentery_stiffness_N_per_mm2") +
                    ": must be > 0 for a region on a mesentery (else nothing holds it)");
        }
    }

    sc.settings.gravity_mm_per_s2 =
        root.vector3_or("gravity_mm_per_s2", sc.settings.gravity_mm_per_s2);
    if (with_run) set_initial_insertion(sc, non_negative_or(root, "initial_insertion_mm", 0.0));
    if (root.has("solver")) read_solver(root.object("solver"), sc.settings);
    if (root.has("telescoping"))
        sc.settings.telescoping = read_telescoping(root.object("telescoping"));
    if (sc.patient) {
        const nlohmann::json* contact = root.has("solver") && root.raw("solver").contains("contact")
                                            ? &root.raw("solver").at("contact")
                                            : nullptr;
        if (contact != nullptr && contact->contains("friction_coefficient"))
            throw ModelError(root.field("solver") +
                             ".contact.friction_coefficient: the patient gives the friction "
                             "coefficient; remove it or 'patient' (friction_zones still apply)");
        sc.settings.contact.friction_coefficient = sc.patient->friction_coefficient;
    }
    try {
        sc.settings.validate();  // backstop: every field above is already checked with its path
    } catch (const ModelError& e) {
        throw ModelError(source + ": " + e.what());
    }

    if (with_run) {
        if (root.has("procedure") && root.has("physician"))
            throw ModelError(root.field("physician") +
                             ": a scenario takes either 'procedure' (the hand's scripted "
                             "timeline) or 'physician' (a procedure generator that reacts to the "
                             "world), not both");
        if (!root.has("procedure") && !root.has("physician"))
            throw ModelError(root.field("procedure") +
                             ": missing; give 'procedure' (the hand's scripted timeline) or "
                             "'physician' (a procedure generator that reacts to the world)");
        for (const char* key : {"steering", "abdominal_pressure"})
            if (root.has("physician") && root.has(key))
                throw ModelError(root.field(key) +
                                 ": the physician decides when to steer the tip and when the "
                                 "assistant presses; remove '" +
                                 std::string(key) + "' or 'physician'");
        if (root.has("physician"))
            read_physician(root, sc);
        else
            read_procedure(root, sc);
    }

    if (root.has("truth_effects"))
        sc.effects = read_world_effects(root.array("truth_effects"), root.field("truth_effects"));
    if (sc.patient) {
        for (std::size_t i = 0; i < sc.effects.size(); ++i)
            if (sc.effects[i]->name() == EiProfile::kName)
                throw ModelError(item(root.field("truth_effects"), i) +
                                 ".name: 'ei_profile' is the patient's scope already (patient "
                                 "scope.ei_factor, distal_section_*); remove one");
        sc.effects.push_back(make_patient_scope(*sc.patient));
    }
    if (root.has("sensors")) {
        (void)root.object(
            "sensors");  // an object; its keys are read by the host simulator's sensor models
        sc.sensors = root.raw("sensors");
        sc.sensors_path = root.field("sensors");
    }
    if (root.has("steering")) {
        const nlohmann::json& windows = root.array("steering");
        const std::string path = root.field("steering");
        for (std::size_t i = 0; i < windows.size(); ++i) {
            const JsonObject w(windows[i], item(path, i));
            w.allow_only({"start_s", "end_s", "lookahead_mm", "bending_section_mm", "gain",
                          "holds_curvature"});
            SteeringWindow window;
            std::tie(window.start_s, window.end_s) = read_window_times(w);
            window.lookahead_mm = positive_or(w, "lookahead_mm", window.lookahead_mm);
            window.bending_section_mm =
                positive_or(w, "bending_section_mm", window.bending_section_mm);
            window.gain = positive_or(w, "gain", window.gain);
            if (window.gain > 1.0)
                throw ModelError(w.field("gain") + ": " + number_text(window.gain) +
                                 " must be in (0, 1]");
            window.holds_curvature = w.boolean_or("holds_curvature", window.holds_curvature);
            sc.steering.push_back(window);
        }
        sc.effects.push_back(make_tip_steering(sc));
    }
    if (root.has("abdominal_pressure")) {
        const nlohmann::json& windows = root.array("abdominal_pressure");
        const std::string path = root.field("abdominal_pressure");
        for (std::size_t i = 0; i < windows.size(); ++i) {
            const JsonObject w(windows[i], item(path, i));
            w.allow_only({"start_s", "end_s", "regions", "stiffness_N_per_mm2", "ramp_s"});
            AbdominalPressureWindow window;
            std::tie(window.start_s, window.end_s) = read_window_times(w);
            window.stiffness_N_per_mm2 =
                positive_or(w, "stiffness_N_per_mm2", window.stiffness_N_per_mm2);
            window.ramp_s =
                w.number_or("ramp_s", std::min(window.ramp_s, window.end_s - window.start_s));
            if (!(window.ramp_s >= 0.0 && window.ramp_s <= window.end_s - window.start_s))
                throw ModelError(w.field("ramp_s") + ": " + number_text(window.ramp_s) +
                                 " s must be in [0, end_s - start_s]");
            if (window.stiffness_N_per_mm2 > 1.0)
                throw ModelError(w.field("stiffness_N_per_mm2") + ": " +
                                 number_text(window.stiffness_N_per_mm2) + " must be in (0, 1]");
            if (w.has("regions")) {
                const nlohmann::json& names = w.array("regions");
                window.regions.clear();
                for (std::size_t r = 0; r < names.size(); ++r) {
                    const std::string at = item(w.field("regions"), r);
                    if (!names[r].is_string())
                        throw ModelError(at + ": must be a region name (string)");
                    const auto region = region_from_name(names[r].get<std::string>());
                    if (!region)
                        throw ModelError(at + ": unknown region " +
                                         io::quote_text(names[r].get<std::string>()) +
                                         " (known: " + region_list() + ")");
                    window.regions.push_back(*region);
                }
                if (window.regions.empty())
                    throw ModelError(w.field("regions") + ": name at least one region");
            }
            sc.abdominal_pressure.push_back(window);
        }
        sc.effects.push_back(std::make_shared<AbdominalPressure>(sc.abdominal_pressure));
    }
    if (sc.physician) {
        sc.effects.push_back(std::make_shared<TipSteering>(
            sc.scene_control, *sc.colon, sc.scope.section.bending_stiffness_z_Nmm2,
            sc.scope.length_mm / static_cast<double>(sc.scope.elements)));
        sc.effects.push_back(std::make_shared<AbdominalPressure>(sc.scene_control));
    }
    if (root.has("outputs"))
        sc.outputs = read_outputs(root.object("outputs"), sc.scope.length_mm, sc.scope.elements,
                                  sc.settings.time_step_s);
    return sc;
}

}  // namespace

Scenario read_scenario(const nlohmann::json& document, const std::string& source) {
    return read_document(document, source, true);
}

Scenario read_world_model(const nlohmann::json& document, const std::string& source) {
    Scenario sc = read_document(document, source, false);
    if (sc.kind != ScenarioKind::world)
        throw ModelError(source + ": not a world scenario (no colon or patient)");
    // Read (and so checked) with the rest; each run makes its own (scene_effects).
    sc.effects.clear();
    return sc;
}

void set_initial_insertion(Scenario& sc, double initial_insertion_mm) {
    const std::string field = sc.source + ": initial_insertion_mm";
    require_non_negative(initial_insertion_mm, field);
    if (initial_insertion_mm >= sc.scope.length_mm)
        throw ModelError(field + ": " + number_text(initial_insertion_mm) +
                         " mm must be shorter than the scope (" + number_text(sc.scope.length_mm) +
                         " mm)");
    sc.settings.initial_insertion_mm = initial_insertion_mm;
}

std::vector<std::shared_ptr<const WorldEffect>> scene_effects(const Scenario& sc) {
    std::vector<std::shared_ptr<const WorldEffect>> effects;
    if (sc.patient) effects.push_back(make_patient_scope(*sc.patient));
    if (!sc.steering.empty()) effects.push_back(make_tip_steering(sc));
    if (!sc.abdominal_pressure.empty())
        effects.push_back(std::make_shared<AbdominalPressure>(sc.abdominal_pressure));
    return effects;
}

nlohmann::json with_model_file(nlohmann::json document, const std::string& filename) {
    if (!document.is_object() || !document.contains("model")) return document;
    const nlohmann::json& reference = document["model"];
    if (!reference.is_string())
        throw ModelError(
            filename +
            ": model: expected the name of a model file (string), relative to this file");
    const std::filesystem::path model_path = std::filesystem::path(filename).parent_path() /
                                             std::filesystem::path(reference.get<std::string>());
    nlohmann::json merged = io::parse_json_file(model_path.string());
    if (!merged.is_object())
        throw ModelError(model_path.string() + ": expected a JSON object (a model)");
    if (merged.contains("model"))
        throw ModelError(model_path.string() + ": model: a model file cannot name another model");
    for (const auto& [key, value] : document.items()) {
        if (key == "model") continue;
        if (key == "truth_effects" && merged.contains("truth_effects") &&
            merged["truth_effects"].is_array() && value.is_array()) {
            for (const auto& e : value)
                merged["truth_effects"].push_back(e);
            continue;
        }
        merged[key] = value;
    }
    return merged;
}

Scenario read_scenario_file(const std::string& filename) {
    return read_scenario(with_model_file(io::parse_json_file(filename), filename), filename);
}

}  // namespace scopekin::model
