// The kinetic estimator's step (kinetics.hpp): input validation, the reduced model, outputs,
// monitors.  Fixed-point formats: every quantity is Q16.16 in the units of its name (RANGES.md).
//
// Scaling and overflow: depths stay in [-50, 2000] mm after validation and the depth step is at
// most 1000 mm/s * 1 s; the tip path is a table path (< 2000 mm) plus an elastic deviation
// (|W| < 32 mm/N times forces < 100 N, see RANGES.md); the observer's tip lies in [0, 2400] mm
// (tip_observer.hpp), so a station's path position plus the tip correction (observer - model,
// |.| < 4500 mm) stays below 10,000 mm; the velocity divides a path difference (< 4000 mm) by 10
// periods (>= 10 * 2^-16 s) — saturating division, flagged when it saturates.
#include "kinetics/kinetics.hpp"

#include <algorithm>
#include <memory>
#include <type_traits>

namespace scopekin::kinetics {

namespace {

using monitors::AdvanceEfficiency;
using monitors::ContactForceMonitor;
using monitors::SelfLockMonitor;

/// A contact solve residual above this (N) is reported (kFaultContactResidual).
constexpr Q16_16 kContactResidualBoundN = Q16_16::from_ratio(1, 20);
/// Normal force below which a distal station does not count as in contact (monitors' 0.05 N).
constexpr Q16_16 kMinContactForceN = Q16_16::from_ratio(1, 20);

bool limits_valid(const InputLimits& l) noexcept {
    const Q16_16 zero{};
    return l.insertion_min_mm < l.insertion_max_mm && l.max_insertion_speed_mm_per_s > zero &&
           l.force_max_abs_N > zero && l.torque_max_abs_Nmm > zero && l.roll_max_abs_rad > zero;
}

ConfigFault check_config(const Config& config, ReducedTablesFault& tables_fault) noexcept {
    tables_fault = check_reduced_tables(config.tables, kStationCapacity);
    if (!(config.period_s > Q16_16{}) || config.period_s > Q16_16::from_int(1))
        return ConfigFault::period;
    if (config.contact_sweeps == 0U || config.contact_sweeps > 64U ||
        config.contact_local_iterations == 0U || config.contact_local_iterations > 64U) {
        return ConfigFault::contact_settings;
    }
    if (!limits_valid(config.limits) || config.force_blind_after_steps == 0U ||
        config.force_blind_after_steps > 1000U) {
        return ConfigFault::limits;
    }
    if (tables_fault != ReducedTablesFault::none) return ConfigFault::tables;
    if (!AdvanceEfficiency<>::valid(config.efficiency) ||
        !SelfLockMonitor::valid(config.self_lock) ||
        !ContactForceMonitor::valid(config.contact_force) ||
        !ContactForceMonitor::valid(config.model_contact_force)) {
        return ConfigFault::monitors;
    }
    if (!config.tip_observer.valid()) return ConfigFault::tip_observer;
    if (!config.model_evidence.valid()) return ConfigFault::model_evidence;
    if (config.slack_trees != nullptr && !config.slack_trees->valid())
        return ConfigFault::slack_regressor;
    if (config.contact_force_trees != nullptr &&
        (config.slack_trees == nullptr || !config.contact_force_trees->valid() ||
         !same_features(*config.slack_trees, *config.contact_force_trees))) {
        return ConfigFault::contact_force_regressor;
    }
    if (config.loop_alarm_trees != nullptr &&
        (config.slack_trees == nullptr || !config.loop_alarm_trees->valid() ||
         !config.loop_alarm.valid() || !config.loop_alarm_with_tracker.valid() ||
         !config.slack_excess.valid() ||
         !same_features(*config.slack_trees, *config.loop_alarm_trees))) {
        return ConfigFault::loop_alarm;
    }
    if (!config.tip_odometer.valid(config.period_s)) return ConfigFault::tip_odometer;
    return ConfigFault::none;
}

/// A held, range-checked signal: returns the value to use, sets the stale / range bits.
Q16_16 validate_signal(bool fresh, Q16_16 reading, Q16_16 held, Q16_16 max_abs,
                       std::uint32_t stale_bit, std::uint32_t range_bit,
                       std::uint32_t& faults) noexcept {
    if (!fresh) {
        faults |= stale_bit;
        return held;
    }
    const Q16_16 limited = std::clamp(reading, fixed_point::neg_sat(max_abs), max_abs);
    if (!(limited == reading)) faults |= range_bit;
    return limited;
}

/// The depth the model uses: range-checked, then moved toward the reading by at most max_step.
void validate_insertion(const Inputs& inputs, State& state, std::uint32_t& faults) noexcept {
    const InputLimits& l = state.config.limits;
    if ((inputs.fresh_mask & kInsertion) == 0U) {
        faults |= kFaultInsertionStale;
        return;
    }
    const Q16_16 reading = std::clamp(inputs.insertion_mm, l.insertion_min_mm, l.insertion_max_mm);
    if (!(reading == inputs.insertion_mm)) faults |= kFaultInsertionRange;
    if (!state.insertion_seen) {
        state.insertion_mm = reading;
        state.insertion_seen = true;
        return;
    }
    const Q16_16 max_step = l.max_insertion_speed_mm_per_s * state.config.period_s;
    const Q16_16 move = reading - state.insertion_mm;
    if (move > max_step) {
        state.insertion_mm = state.insertion_mm + max_step;
        faults |= kFaultInsertionJump;
    } else if (move < fixed_point::neg_sat(max_step)) {
        state.insertion_mm = state.insertion_mm - max_step;
        faults |= kFaultInsertionJump;
    } else {
        state.insertion_mm = reading;
    }
}

StationState station_state(contact::ContactState s) noexcept {
    switch (s) {
        case contact::ContactState::sticking: return StationState::sticking;
        case contact::ContactState::slipping: return StationState::slipping;
        case contact::ContactState::degenerate: return StationState::degenerate;
        case contact::ContactState::separated: break;
    }
    return StationState::separated;
}

ContactForceLevel output_level(monitors::ContactForceLevel level) noexcept {
    switch (level) {
        case monitors::ContactForceLevel::warning: return ContactForceLevel::warning;
        case monitors::ContactForceLevel::critical: return ContactForceLevel::critical;
        case monitors::ContactForceLevel::normal: break;
    }
    return ContactForceLevel::normal;
}

/// Counts the stale force periods; true once there are force_blind_after_steps of them in a row
/// (kinetics.hpp, "A stale force cell").
bool force_blind(State& state, std::uint32_t faults) noexcept {
    if ((faults & kFaultForceStale) == 0U) {
        state.force_stale_steps = 0;
    } else if (state.force_stale_steps < state.config.force_blind_after_steps) {
        ++state.force_stale_steps;
    }
    return state.force_stale_steps >= state.config.force_blind_after_steps;
}

/// Tip velocity: mean over the ring (oldest to newest), 0 until it holds two samples.
Q16_16 tip_velocity(State& state, Q16_16 tip_mm, std::uint32_t& faults) noexcept {
    const std::size_t oldest =
        state.tip_history_count < kVelocityWindow ? 0U : state.tip_history_next;
    const Q16_16 first = state.tip_history_mm[oldest];
    const std::size_t spans =
        state.tip_history_count < kVelocityWindow ? state.tip_history_count : kVelocityWindow;
    state.tip_history_mm[state.tip_history_next] = tip_mm;
    state.tip_history_next = (state.tip_history_next + 1U) % kVelocityWindow;
    if (state.tip_history_count < kVelocityWindow) ++state.tip_history_count;
    if (spans == 0U) return Q16_16{};
    const Q16_16 elapsed_s = state.config.period_s * Q16_16::from_int(static_cast<int>(spans));
    const Q16_16 velocity = (tip_mm - first) / elapsed_s;
    if (velocity == Q16_16::max() || velocity == Q16_16::min()) faults |= kFaultSaturation;
    return velocity;
}

/// The model evidence's step: evidence is taken while the hand moves along a training run
/// trained in its direction of motion (model_evidence.hpp); `previous_depth_mm` is the depth of
/// the model's last step.
ModelEvidence::Outputs weigh_model(State& state,
                                   const ReducedStepReport<Q16_16, kStationCapacity>& report,
                                   Q16_16 previous_depth_mm, std::uint32_t faults) noexcept {
    const ReducedState<Q16_16, kStationCapacity>& model = state.model;
    const ReducedSegment<Q16_16>& run = state.config.tables->header().segments[model.segment];
    const Q16_16 moved_mm = state.insertion_mm - previous_depth_mm;
    const int motion = moved_mm > Q16_16{} ? 1 : (moved_mm < Q16_16{} ? -1 : 0);
    ModelEvidence::Inputs in{};
    in.handle_force_N = state.handle_force_N;
    in.training_force_N = model.training_handle_force_N;
    in.inside_model = !report.depth_clamped;
    in.on_trained_motion = model.hold_steps == 0U && run.kind == kSegmentTravel && motion != 0 &&
                           run.direction == motion;
    in.force_fresh = (faults & kFaultForceStale) == 0U;
    return ModelEvidence::step(state.config.model_evidence, in, state.model_evidence);
}

}  // namespace

void init(const Config& config, State& state) noexcept {
    // Built in place: `state = State{}` may build a temporary of the whole state on the stack
    // (6.9 KB on the Cortex-M4 with GCC 12).
    static_assert(std::is_trivially_destructible_v<State>);
    std::construct_at(&state);
    state.config = config;
    state.config_fault = check_config(config, state.tables_fault);
    (void)state.efficiency.init(config.efficiency);
    (void)state.self_lock.init(config.self_lock);
    (void)state.contact_force.init(config.contact_force);
    (void)state.model_contact_force.init(config.model_contact_force);
}

void step(const Inputs& inputs, State& state, Outputs& outputs) noexcept {
    outputs = Outputs{};
    outputs.step_index = state.steps++;
    if (state.config_fault != ConfigFault::none) {
        outputs.fault_flags = kFaultConfig;
        return;
    }
    const Config& config = state.config;
    std::uint32_t faults = 0;

    // 1. Inputs.
    validate_insertion(inputs, state, faults);
    state.handle_force_N = validate_signal(
        (inputs.fresh_mask & kHandleForce) != 0U, inputs.handle_force_N, state.handle_force_N,
        config.limits.force_max_abs_N, kFaultForceStale, kFaultForceRange, faults);
    state.handle_torque_Nmm =
        validate_signal((inputs.fresh_mask & kHandleTorque) != 0U, inputs.handle_torque_Nmm,
                        state.handle_torque_Nmm, config.limits.torque_max_abs_Nmm,
                        kFaultTorqueStale, kFaultTorqueRange, faults);
    state.roll_rad =
        validate_signal((inputs.fresh_mask & kRoll) != 0U, inputs.roll_rad, state.roll_rad,
                        config.limits.roll_max_abs_rad, kFaultRollStale, kFaultRollRange, faults);

    // 2. The reduced model (no estimate before the first insertion sample: the depth is unknown).
    if (!state.insertion_seen) {
        outputs.fault_flags = faults;
        return;
    }
    contact::GaussSeidelSettings<Q16_16> gauss_seidel{};
    gauss_seidel.mode = contact::SweepMode::fixed;
    gauss_seidel.max_sweeps = config.contact_sweeps;
    gauss_seidel.local_iterations = config.contact_local_iterations;
    const Q16_16 previous_depth_mm = state.model.last_depth_mm;
    const ReducedStepReport<Q16_16, kStationCapacity> report = reduced_step(
        *config.tables, state.insertion_mm, config.period_s, state.model, gauss_seidel);
    if (report.depth_clamped) faults |= kFaultDepthOutsideModel;
    const auto& residuals = report.contact.residuals;
    if (report.contact.status == contact::ContactSolveStatus::invalid_input ||
        residuals.complementarity > kContactResidualBoundN ||
        residuals.cone_violation > kContactResidualBoundN ||
        residuals.friction > kContactResidualBoundN) {
        faults |= kFaultContactResidual;
    }

    // 3. The tip observer, the model evidence and the slack regressor: the published tip.
    const bool force_fresh = (faults & kFaultForceStale) == 0U;
    if (force_blind(state, faults)) faults |= kFaultForceBlind;
    TipObserver::Inputs observer_inputs{};
    observer_inputs.depth_mm = state.insertion_mm;
    observer_inputs.handle_force_N = state.handle_force_N;
    observer_inputs.force_fresh = force_fresh;
    observer_inputs.period_s = config.period_s;
    TipObserver::Outputs observed =
        TipObserver::step(config.tip_observer, observer_inputs, state.tip_observer);
    const ModelEvidence::Outputs evidence = weigh_model(state, report, previous_depth_mm, faults);
    const ReducedState<Q16_16, kStationCapacity>& model = state.model;
    if (evidence.trusted) {
        // The handle says this is the training patient: the model's tip, and the observer's dead
        // reckoning continues from it when the evidence turns.
        observed.tip_mm = TipObserver::reseed(config.tip_observer, state.insertion_mm,
                                              model.tip_path_mm, state.tip_observer);
        observed.uncertainty_mm = config.model_evidence.trusted_tip_sd_mm;
    }
    SlackRegressor::Outputs regressed{};
    if (config.slack_trees != nullptr) {
        // The regressor reads the observer's slack (after any reseed) among its features.
        SlackRegressor::Inputs slack_inputs{};
        slack_inputs.depth_mm = state.insertion_mm;
        slack_inputs.handle_force_N = state.handle_force_N;
        slack_inputs.force_fresh = force_fresh;
        slack_inputs.observer_slack_mm = state.insertion_mm - state.tip_observer.tip_mm;
        slack_inputs.period_s = config.period_s;
        regressed = SlackRegressor::step(*config.slack_trees, slack_inputs, state.slack);
        if (!evidence.trusted) {
            observed.tip_mm = TipObserver::bounded(config.tip_observer, state.insertion_mm,
                                                   state.insertion_mm - regressed.slack_mm);
            observed.uncertainty_mm = regressed.uncertainty_mm;
        }
    }

    // The bench's EM tracker, when connected: the tip's odometry fused with the handle's tip.
    TipOdometer::Inputs odometer_inputs{};
    odometer_inputs.tracker = &inputs.tracker;
    odometer_inputs.handle_tip_mm = observed.tip_mm;
    odometer_inputs.handle_sd_mm = observed.uncertainty_mm;
    odometer_inputs.handle_trusted = evidence.trusted;
    odometer_inputs.tip_min_mm =
        TipObserver::bounded(config.tip_observer, state.insertion_mm, Q16_16::min());
    odometer_inputs.tip_max_mm =
        TipObserver::bounded(config.tip_observer, state.insertion_mm, Q16_16::max());
    odometer_inputs.period_s = config.period_s;
    const TipOdometer::Outputs odometer =
        TipOdometer::step(config.tip_odometer, odometer_inputs, state.tip_odometer);
    observed.tip_mm = odometer.tip_mm;
    observed.uncertainty_mm = odometer.uncertainty_mm;
    // With the tracker, the scope taken up since the tip last kept pace: the loop alarm's gate.
    SlackExcess::Inputs excess_inputs{};
    excess_inputs.active = odometer.active;
    excess_inputs.fresh = odometer.fresh;
    excess_inputs.step = outputs.step_index;
    excess_inputs.insertion_mm = state.insertion_mm;
    excess_inputs.travel_mm = odometer.travel_mm;
    const SlackExcess::Outputs excess =
        SlackExcess::step(config.slack_excess, excess_inputs, state.slack_excess);

    // 4. Outputs.
    outputs.tip_path_mm = observed.tip_mm;
    outputs.tip_from_tracker = odometer.active;
    outputs.tip_uncertainty_mm = observed.uncertainty_mm;
    outputs.tip_velocity_mm_per_s = tip_velocity(state, observed.tip_mm, faults);
    outputs.model_tip_path_mm = model.tip_path_mm;
    outputs.model_log_likelihood_ratio = evidence.log_ratio;
    outputs.tip_from_model = evidence.trusted;
    outputs.observer_tip_path_mm = state.tip_observer.tip_mm;
    // The stations stand behind the published tip as they stand behind the model's on the scope.
    const Q16_16 tip_correction_mm = observed.tip_mm - model.tip_path_mm;
    outputs.active_stations = static_cast<std::uint8_t>(model.active_stations);
    const Q16_16 spacing = config.tables->header().station_spacing_mm;
    for (std::size_t j = 0; j < kStationCapacity; ++j) {  // bound: kStationCapacity
        if (j >= model.active_stations) break;
        StationEstimate& out = outputs.stations[j];
        const auto& f = model.force_N[j];
        out.arc_from_tip_mm = spacing * Q16_16::from_int(static_cast<int>(j));
        out.path_position_mm =
            model.reference_path_mm[j] + model.elastic_mm[j][1] + tip_correction_mm;
        // A passive station's resultant can pull (f_n < 0: its stretch presses on opposite
        // walls, reduced_kinetics.hpp "Passive stations"); the published normal force is the
        // push on the station's own wall, >= 0, and the magnitude is the whole resultant's.
        out.normal_force_N = f[0] < Q16_16{} ? Q16_16{} : f[0];
        out.tangential_force_N = fixed_point::hypot_sat(f[1], f[2]);
        out.state = station_state(model.contact_state[j]);
        const Q16_16 magnitude = fixed_point::hypot_sat(f[0], out.tangential_force_N);
        if (magnitude > outputs.max_contact_force_N) {
            outputs.max_contact_force_N = magnitude;
            outputs.max_contact_station = static_cast<std::uint8_t>(j);
            outputs.max_contact_path_mm = out.path_position_mm;
        }
        if (j < kDistalStations && out.state == StationState::sticking &&
            !(out.normal_force_N < kMinContactForceN)) {
            ++outputs.distal_sticking;
        }
    }
    outputs.model_max_contact_force_N = outputs.max_contact_force_N;
    if (config.contact_force_trees != nullptr) {
        // The largest force from the handle's history (the slack regressor's features) unless
        // the evidence trusts the model; where and at which station stay the model's.
        const SlackTrees& trees = *config.contact_force_trees;
        const Q16_16 regressed_N =
            std::max(SlackRegressor::predict(trees, regressed.features), Q16_16{});
        if (!evidence.trusted) outputs.max_contact_force_N = regressed_N;
        outputs.max_contact_force_uncertainty_N =
            SlackRegressor::uncertainty(trees, regressed_N, state.insertion_mm);
    }
    if (outputs.tip_path_mm == Q16_16::max() || outputs.tip_path_mm == Q16_16::min() ||
        outputs.max_contact_force_N == Q16_16::max()) {
        faults |= kFaultSaturation;
    }

    // 5. Monitors (on the reduced model: kinetics.hpp, step 5).
    const AdvanceEfficiency<>::Outputs efficiency =
        state.efficiency.step({model.tip_path_mm, state.insertion_mm});
    outputs.advance_efficiency = efficiency.efficiency;
    SelfLockMonitor::Inputs lock_inputs{};
    // Self-locking is the tip's contact sticking (thesis 2.2.1): stations behind it stick in
    // stick-slip while the tip keeps pace with the hand.
    lock_inputs.distal_sticking = model.active_stations > 0U &&
                                          outputs.stations[0].state == StationState::sticking &&
                                          !(outputs.stations[0].normal_force_N < kMinContactForceN)
                                      ? 1U
                                      : 0U;
    lock_inputs.handle_advancing = efficiency.handle_advancing;
    lock_inputs.efficiency = efficiency.efficiency;
    lock_inputs.efficiency_defined = efficiency.defined;
    const SelfLockMonitor::Outputs lock = state.self_lock.step(lock_inputs);
    outputs.model_self_lock_alarm = lock.alarm;
    outputs.self_lock_alarm = lock.alarm;
    if (config.loop_alarm_trees != nullptr) {
        // Runs every period so its debounce is current when the evidence turns. With the
        // tracker, the score counts only once the tip has fallen the gate behind the hand, at the
        // level chosen for that gate (slack_excess.hpp); the published score is the trees'.
        const Q16_16 score = SlackRegressor::predict(*config.loop_alarm_trees, regressed.features);
        const bool loop_alarm =
            excess.valid
                ? EvidenceAlarm::debounce(config.loop_alarm_with_tracker,
                                          excess.gate_open ? score : Q16_16{}, state.loop_alarm)
                : EvidenceAlarm::debounce(config.loop_alarm, score, state.loop_alarm);
        outputs.loop_score = score;
        if (!evidence.trusted) outputs.self_lock_alarm = loop_alarm;
    }
    // The published level reads the published force: where the handle's evidence does not
    // trust the model, the model's force rings an alarm every half minute in other patients
    // (firmware/README.md, "The contact-force level from evidence").
    const ContactForceMonitor::Outputs force_level =
        state.contact_force.step(outputs.max_contact_force_N);
    outputs.contact_force_level = output_level(force_level.level);
    const ContactForceMonitor::Outputs model_level =
        state.model_contact_force.step(outputs.model_max_contact_force_N);
    outputs.model_contact_force_level = output_level(model_level.level);
    if (efficiency.input_fault || lock.input_fault || force_level.input_fault ||
        model_level.input_fault)
        faults |= kFaultMonitorInput;
    outputs.fault_flags = faults;
}

}  // namespace scopekin::kinetics
