#include "model/scenario/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "model/model_error.hpp"
#include "model/physician/physician_source.hpp"

namespace scopekin::model {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;
/// The name of the effect that is the assistant's hand (model/scenario/abdominal_pressure.hpp).
constexpr const char* kAssistantPressureEffect = "abdominal_pressure";
/// Below this the hand is only resting on the abdomen [N].
constexpr double kAssistantPressingForce_N = 0.1;

void note_assistant_pressure(double force_N, double h_s, SimulationSummary& sum) {
    sum.max_assistant_pressure_force_N = std::max(sum.max_assistant_pressure_force_N, force_N);
    if (!(force_N > kAssistantPressingForce_N)) return;
    sum.assistant_pressing_s += h_s;
    sum.assistant_pressure_impulse_Ns += force_N * h_s;
}

std::size_t region_index(ColonRegion r) {
    return static_cast<std::size_t>(r);
}

}  // namespace

std::unique_ptr<World> build_world(const Scenario& scenario) {
    if (scenario.kind != ScenarioKind::world || !scenario.colon)
        throw ModelError(scenario.source + ": not a world scenario (no colon)");
    try {
        return std::make_unique<World>(scenario.scope, *scenario.colon, scenario.colon_properties,
                                       scenario.settings, scenario.effects);
    } catch (const ModelError& e) {
        throw ModelError(scenario.source + ": " + e.what());
    }
}

std::vector<std::size_t> output_nodes(const Scenario& scenario) {
    std::vector<std::size_t> nodes;
    for (double arc : scenario.outputs.nodes_from_tip_mm)
        nodes.push_back(
            scope_node_from_tip(arc, scenario.scope.length_mm, scenario.scope.elements));
    return nodes;
}

WorldRow sample_world(const World& world, const WorldStepReport* last_step,
                      const std::vector<std::size_t>& output_nodes) {
    WorldRow s;
    s.time_s = world.time_s();
    s.handle_force_N = world.handle_force_N();
    s.handle_torque_Nmm = world.handle_torque_Nmm();
    s.insertion_depth_mm = world.insertion_depth_mm();
    s.roll_deg = world.roll_rad() * kDegPerRad;
    s.tip_mm = world.node_position_mm(world.scope_node_count() - 1);
    for (std::size_t node : output_nodes)
        s.nodes_mm.push_back(world.node_position_mm(node));
    double tip_arc = INFINITY;
    for (const WorldContact& c : world.contacts()) {
        if (!(c.normal_force_N > 0.0)) continue;
        ++s.contact_count;
        s.contact_force_total_N += c.normal_force_N;
        s.contact_force_max_N = std::max(s.contact_force_max_N, c.normal_force_N);
        double& region_max = s.max_contact_force_by_region_N[region_index(c.region)];
        region_max = std::max(region_max, c.normal_force_N);
        if (c.state == contact::ContactState::sticking) ++s.sticking_contacts;
        if (c.state == contact::ContactState::slipping) ++s.slipping_contacts;
        if (c.arc_from_tip_mm < tip_arc) {
            tip_arc = c.arc_from_tip_mm;
            s.has_tip_driving_angle = true;
            s.tip_driving_angle_deg = c.driving_angle_rad * kDegPerRad;
        }
    }
    s.gs_sweeps = last_step != nullptr ? last_step->sweeps : 0;
    s.assistant_pressure_force_N = world.effect_force_N(kAssistantPressureEffect);
    return s;
}

namespace {

/// Keeps each mobile stretch's peak and latest pleated fraction (summary.json world.telescoping).
void note_pleating(const World& world, std::vector<StretchPleating>& stretches) {
    const ColonPleating& pleating = world.telescoping();
    if (stretches.size() != pleating.stretch_count()) {
        stretches.assign(pleating.stretch_count(), StretchPleating{});
        for (std::size_t k = 0; k < stretches.size(); ++k) {
            stretches[k].region = world.colon().points()[pleating.first_node(k)].region;
            stretches[k].rest_length_mm = pleating.rest_length_mm(k);
            stretches[k].max_fraction = pleating.max_fraction(k);
        }
    }
    for (std::size_t k = 0; k < stretches.size(); ++k) {
        const double p = pleating.state().fraction[k];
        stretches[k].final_fraction = p;
        stretches[k].peak_fraction = std::max(stretches[k].peak_fraction, p);
    }
}

/// A scripted procedure's player, watching the tip's arrival at the cecum as a physician would
/// see it (WorldObserver) and telling what the hand does (procedure.csv).
class ScriptedSource final : public HandCommandSource {
public:
    ScriptedSource(const World& world, const Scenario& scenario)
        : world_(world),
          scenario_(scenario),
          player_(scenario.procedure, world.insertion_depth_mm(), world.scope_length_mm(),
                  world.roll_rad()),
          observer_(world) {}

    HandleCommand command_for_step(std::size_t step, double t_s, double h_s, double depth_now_mm,
                                   double roll_now_rad) override {
        if (!outcome_.cecum_reached) {
            const PhysicianObservation seen = observer_.observe(world_);
            if (seen.tip_path_mm >= seen.cecum_path_mm - kCecumReach_mm) {
                outcome_.cecum_reached = true;
                outcome_.cecum_time_s = seen.time_s;
                outcome_.insertion_at_cecum_mm = seen.insertion_mm;
            }
        }
        const HandleCommand c = player_.command(t_s, h_s, depth_now_mm, roll_now_rad);
        const int action = player_.current_action();
        const auto& actions = scenario_.procedure.actions();
        state_.state =
            action < 0 ? std::string("hold")
                       : std::string(action_name(actions[static_cast<std::size_t>(action)].kind));
        state_.speed_mm_per_s = c.force_controlled ? 0.0 : (c.insertion_mm - depth_now_mm) / h_s;
        state_.roll_deg = (c.torque_controlled ? roll_now_rad : c.roll_rad) * kDegPerRad;
        const double t_end = t_s + h_s;  // the effects' windows are judged at the step's end
        state_.steering = false;
        for (const SteeringWindow& w : scenario_.steering)
            state_.steering = state_.steering || (t_end >= w.start_s && t_end < w.end_s);
        state_.pressure = false;
        for (const AbdominalPressureWindow& w : scenario_.abdominal_pressure)
            state_.pressure = state_.pressure || (t_end >= w.start_s && t_end < w.end_s);
        if (state_.pressure) outcome_.abdominal_pressure_s += h_s;
        (void)step;
        return c;
    }
    std::vector<std::string> warnings() const override { return player_.warnings(); }
    HandState hand_state() const override { return state_; }
    ProcedureOutcome outcome() const override { return outcome_; }

private:
    const World& world_;
    const Scenario& scenario_;
    ProcedurePlayer player_;
    WorldObserver observer_;
    HandState state_;
    ProcedureOutcome outcome_;
};

}  // namespace

SimulationSummary run_simulation(World& world, const Scenario& scenario,
                                 const SimulationCallbacks& callbacks) {
    const double h = world.time_step_s();
    if (scenario.physician) {
        const double end = scenario.physician->max_duration_s;
        const auto step_count = static_cast<std::size_t>(std::max(0.0, std::ceil(end / h - 1e-9)));
        PhysicianSource physician(world, *scenario.physician, scenario.scene_control);
        SimulationSummary sum =
            run_simulation(world, scenario, physician, {0, step_count, end}, callbacks);
        if (sum.procedure.end_reason.empty()) sum.procedure.end_reason = "max_duration";
        return sum;
    }
    const double end = scenario.procedure.end_s();
    const auto step_count = static_cast<std::size_t>(std::max(0.0, std::ceil(end / h - 1e-9)));
    ScriptedSource player(world, scenario);
    SimulationSummary sum =
        run_simulation(world, scenario, player, {0, step_count, end}, callbacks);
    if (sum.procedure.end_reason.empty()) sum.procedure.end_reason = "end_of_procedure";
    return sum;
}

SimulationSummary run_simulation(World& world, const Scenario& scenario, HandCommandSource& hand,
                                 const SimulationSpan& span, const SimulationCallbacks& callbacks) {
    using Clock = std::chrono::steady_clock;
    const auto wall_start = Clock::now();
    SimulationSummary sum;
    const double h = world.time_step_s();
    const double end = span.end_s;
    sum.end_time_s = end;
    const double rate = scenario.outputs.sample_rate_Hz;
    const double eps = 1e-6 * h;
    const std::vector<std::size_t> nodes = output_nodes(scenario);

    std::size_t next_sample = 0;  // index k of the next sample time k / rate
    auto maybe_sample = [&](const WorldStepReport* last) {
        if (world.time_s() + eps < static_cast<double>(next_sample) / rate) return;
        if (callbacks.on_sample) callbacks.on_sample(sample_world(world, last, nodes), world);
        if (callbacks.on_hand_sample) callbacks.on_hand_sample(world.time_s(), hand.hand_state());
        ++sum.samples;
        while (static_cast<double>(next_sample) / rate <= world.time_s() + eps)
            ++next_sample;
    };
    maybe_sample(nullptr);

    std::size_t sweeps_total = 0;
    sum.complete = true;
    for (std::size_t step = span.first_step + 1; step <= span.last_step; ++step) {
        if (hand.finished()) {
            sum.end_time_s = world.time_s();  // the source ended the run here
            break;
        }
        const HandleCommand command = hand.command_for_step(
            step, world.time_s(), h, world.insertion_depth_mm(), world.roll_rad());
        const WorldStepReport report = world.step(command);
        if (!report.ok) {
            std::ostringstream m;
            m << "t = " << world.time_s() + h << " s: the step failed: " << report.failure;
            sum.complete = false;
            sum.message = m.str();
            sum.failure_time_s = world.time_s() + h;
            break;
        }
        ++sum.steps;
        sweeps_total += report.sweeps;
        sum.gs_sweeps_max = std::max(sum.gs_sweeps_max, report.sweeps);
        sum.dropped_contacts_total += report.dropped_contacts;
        if (report.material_tangent_fallback) ++sum.material_tangent_fallbacks;
        if (report.under_relaxed) ++sum.under_relaxed_steps;
        note_pleating(world, sum.telescoping);
        sum.max_penetration_mm = std::max(sum.max_penetration_mm, report.max_penetration_mm);
        sum.friction_work_Nmm += report.friction_work_Nmm;
        sum.max_handle_force_N = std::max(sum.max_handle_force_N, std::abs(world.handle_force_N()));
        sum.max_handle_torque_Nmm =
            std::max(sum.max_handle_torque_Nmm, std::abs(world.handle_torque_Nmm()));
        note_assistant_pressure(world.effect_force_N(kAssistantPressureEffect), h, sum);
        std::size_t loaded = 0;
        const WorldContact* strongest = nullptr;
        const WorldContact* deepest = nullptr;
        for (const WorldContact& c : world.contacts()) {
            if (deepest == nullptr || c.gap_mm < deepest->gap_mm) deepest = &c;
            if (!(c.normal_force_N > 0.0)) continue;
            ++loaded;
            sum.max_contact_force_N = std::max(sum.max_contact_force_N, c.normal_force_N);
            double& region_max = sum.max_contact_force_by_region_N[region_index(c.region)];
            region_max = std::max(region_max, c.normal_force_N);
            if (strongest == nullptr || c.normal_force_N > strongest->normal_force_N)
                strongest = &c;
        }
        sum.max_simultaneous_contacts = std::max(sum.max_simultaneous_contacts, loaded);

        // A step the solvers accepted may still be unphysical.
        std::ostringstream unphysical;
        if (strongest != nullptr && strongest->normal_force_N > kMaxPhysicalContactForce_N)
            unphysical << "t = " << world.time_s() << " s: contact normal force "
                       << strongest->normal_force_N << " N at " << strongest->arc_from_tip_mm
                       << " mm from the tip (" << region_name(strongest->region) << ") exceeds "
                       << kMaxPhysicalContactForce_N
                       << " N: the run is no longer physical (check the procedure's forces and "
                          "speeds, or reduce "
                          "solver.time_step_s)";
        else if (report.max_penetration_mm > kMaxPhysicalPenetration_mm) {
            unphysical << "t = " << world.time_s() << " s: the scope penetrates the colon wall by "
                       << report.max_penetration_mm << " mm";
            if (deepest != nullptr)
                unphysical << " at " << deepest->arc_from_tip_mm << " mm from the tip ("
                           << region_name(deepest->region) << ")";
            unphysical << ", more than " << kMaxPhysicalPenetration_mm
                       << " mm: the contact solution is no longer physical (tighten "
                          "solver.contact.tolerance_N, raise "
                          "solver.contact.max_sweeps or reduce solver.time_step_s)";
        }
        if (!unphysical.str().empty()) {
            sum.complete = false;
            sum.message = unphysical.str();
            sum.failure_time_s = world.time_s();
            break;
        }

        if (callbacks.on_step) callbacks.on_step(world, report);
        maybe_sample(&report);
        if (callbacks.on_progress)
            callbacks.on_progress({world.time_s(), end, loaded, world.handle_force_N()});
    }

    sum.simulated_time_s = world.time_s();
    sum.wall_time_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
    sum.real_time_factor = sum.wall_time_s > 0.0 ? sum.simulated_time_s / sum.wall_time_s : 0.0;
    sum.gs_sweeps_mean =
        sum.steps > 0 ? static_cast<double>(sweeps_total) / static_cast<double>(sum.steps) : 0.0;
    note_pleating(world, sum.telescoping);
    sum.final_tip_mm = world.node_position_mm(world.scope_node_count() - 1);
    sum.final_insertion_depth_mm = world.insertion_depth_mm();
    sum.final_roll_deg = world.roll_rad() * kDegPerRad;
    sum.warnings = hand.warnings();
    sum.procedure = hand.outcome();
    sum.procedure.duration_s = world.time_s();
    if (!sum.complete) sum.procedure.end_reason = "failed_step";
    return sum;
}

}  // namespace scopekin::model
