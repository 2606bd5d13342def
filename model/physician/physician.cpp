#include "model/physician/physician.hpp"

#include <algorithm>
#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
constexpr double kEps_s = 1e-9;

/// Moves `value` towards `target` by at most `step` (> 0).
double move_towards(double value, double target, double step) {
    if (value < target) return std::min(target, value + step);
    return std::max(target, value - step);
}

}  // namespace

std::string_view physician_style_name(PhysicianStyle style) {
    switch (style) {
        case PhysicianStyle::careful_expert: return "careful_expert";
        case PhysicianStyle::hurried_trainee: return "hurried_trainee";
        case PhysicianStyle::bench_operator: return "bench_operator";
    }
    return "unknown";
}

std::optional<PhysicianStyle> physician_style_from_name(std::string_view name) {
    for (PhysicianStyle s : {PhysicianStyle::careful_expert, PhysicianStyle::hurried_trainee,
                             PhysicianStyle::bench_operator})
        if (physician_style_name(s) == name) return s;
    return std::nullopt;
}

std::string physician_style_list() {
    return "careful_expert, hurried_trainee, bench_operator";
}

PhysicianStyleParameters physician_style_parameters(PhysicianStyle style) {
    PhysicianStyleParameters p;  // the defaults are the careful expert's
    switch (style) {
        case PhysicianStyle::careful_expert: break;
        case PhysicianStyle::hurried_trainee:
            p.speed_min_mm_per_s = 25;
            p.speed_max_mm_per_s = 40;
            p.bout_min_s = 4;
            p.bout_max_s = 10;
            p.pause_probability = 0.15;
            p.pause_min_s = 0.3;
            p.pause_max_s = 1.0;
            p.jiggle_probability = 0.1;
            p.jiggle_amplitude_mm = 10;
            p.jiggle_frequency_Hz = 1.0;
            p.jiggle_cycles = 2;
            p.torque_probability = 0.2;
            p.steering_gain = 0.5;  // half-hearted angulation
            p.steering_follows_turn = false;
            p.loop_notice_excess_mm = 0;  // pushes on
            p.loop_reduce_excess_mm = 100;
            p.resistance_N = 45;
            p.max_push_N = 60;
            p.discomfort_N = 0;
            p.reaction_s = 2.0;
            p.resistance_with_lag_reduces = false;  // pushes on
            p.withdraw_speed_mm_per_s = 25;
            p.min_withdraw_mm = 30;
            p.max_withdraw_mm = 200;
            p.pressure_from_reduction = 2;
            p.max_reductions = 4;
            p.stall_give_up_s = 60;
            p.default_max_duration_s = 600;
            break;
        case PhysicianStyle::bench_operator:
            p.speed_min_mm_per_s = 8;
            p.speed_max_mm_per_s = 10;
            p.bout_min_s = 5;
            p.bout_max_s = 6;
            p.pause_probability = 1.0;
            p.pause_min_s = 2;
            p.pause_max_s = 3;
            p.jiggle_probability = 0;
            p.torque_probability = 0;
            p.steers = false;
            p.loop_notice_excess_mm = 0;  // watches no loop
            p.loop_reduce_excess_mm = 0;
            p.resistance_N = 25;
            p.max_push_N = 30;
            p.discomfort_N = 0;
            p.reaction_s = 0.5;
            p.reduces_loops = false;
            p.resistance_with_lag_reduces = false;
            p.pressure_from_reduction = 0;
            p.max_reductions = 0;
            p.stall_give_up_s = 30;
            p.default_max_duration_s = 300;
            break;
    }
    return p;
}

namespace {
/// The style's parameters with what the spec changes.
PhysicianStyleParameters spec_parameters(const PhysicianSpec& spec) {
    PhysicianStyleParameters p = physician_style_parameters(spec.style);
    if (spec.steering_holds_curvature) p.steering_holds_curvature = *spec.steering_holds_curvature;
    if (spec.pressure_stiffness_N_per_mm2)
        p.pressure_stiffness_N_per_mm2 = *spec.pressure_stiffness_N_per_mm2;
    return p;
}
}  // namespace

Physician::Physician(const PhysicianSpec& spec, double initial_insertion_mm,
                     double initial_roll_rad, double scope_length_mm)
    : Physician(spec, spec_parameters(spec), initial_insertion_mm, initial_roll_rad,
                scope_length_mm) {}

Physician::Physician(const PhysicianSpec& spec, const PhysicianStyleParameters& parameters,
                     double initial_insertion_mm, double initial_roll_rad, double scope_length_mm)
    : spec_(spec),
      p_(parameters),
      random_(spec.seed),
      scope_length_mm_(scope_length_mm),
      initial_roll_rad_(initial_roll_rad),
      depth_mm_(initial_insertion_mm),
      roll_rad_(initial_roll_rad),
      roll_target_rad_(initial_roll_rad) {
    if (!(spec.max_duration_s > 0.0 && spec.max_duration_s <= kMaxPhysicianDuration_s))
        throw ModelError("physician.max_duration_s: " + number_text(spec.max_duration_s) +
                         " s must be in (0, " + number_text(kMaxPhysicianDuration_s) + "]");
}

std::string_view Physician::mode_name(Mode mode) {
    switch (mode) {
        case Mode::advance: return "advance";
        case Mode::pause: return "pause";
        case Mode::jiggle: return "jiggle";
        case Mode::reduce_turn: return "reduce_loop_turn";
        case Mode::reduce_withdraw: return "reduce_loop_withdraw";
        case Mode::reduce_settle: return "reduce_loop_settle";
        case Mode::done: return "done";
    }
    return "unknown";
}

void Physician::start_bout(double t) {
    // Always the same five draws per bout, whatever is used.
    speed_mm_per_s_ = random_.uniform(p_.speed_min_mm_per_s, p_.speed_max_mm_per_s);
    const double duration = random_.uniform(p_.bout_min_s, p_.bout_max_s);
    const bool turn = random_.bernoulli(p_.torque_probability);
    const double magnitude_deg = random_.uniform(p_.torque_min_deg, p_.torque_max_deg);
    const bool clockwise = random_.bernoulli(0.5);
    mode_ = Mode::advance;
    mode_until_s_ = t + duration;
    if (turn) {
        // Within [-range, +range] of the start, and never past the reductions' +180 deg.
        double delta = (clockwise ? 1.0 : -1.0) * magnitude_deg * kRadPerDeg;
        const double lo = initial_roll_rad_ - p_.torque_range_deg * kRadPerDeg;
        const double hi = std::max(initial_roll_rad_ + p_.torque_range_deg * kRadPerDeg, roll_rad_);
        if (roll_rad_ + delta > std::min(hi, initial_roll_rad_ + M_PI) || roll_rad_ + delta < lo)
            delta = -delta;
        roll_target_rad_ = std::clamp(roll_rad_ + delta, lo, initial_roll_rad_ + M_PI);
    } else {
        roll_target_rad_ = roll_rad_;
    }
}

void Physician::after_bout(double t) {
    const double u = random_.unit();
    const double pause = random_.uniform(p_.pause_min_s, p_.pause_max_s);
    if (u < p_.pause_probability) {
        mode_ = Mode::pause;
        mode_until_s_ = t + pause;
    } else if (u < p_.pause_probability + p_.jiggle_probability) {
        mode_ = Mode::jiggle;
        jiggle_anchor_mm_ = depth_mm_;
        jiggle_start_s_ = t;
    } else {
        start_bout(t);
    }
}

void Physician::track_pace(const PhysicianObservation& seen) {
    history_.push_back({seen.time_s, seen.insertion_mm, seen.tip_path_mm});
    while (history_.size() > 2 && history_[1].t <= seen.time_s - kPhysicianPaceWindow_s + kEps_s)
        history_.pop_front();
    const double slack = seen.insertion_mm - seen.tip_path_mm;
    if (history_.size() == 1 || keeps_pace(1.0))
        slack_baseline_mm_ = slack;
    else
        slack_baseline_mm_ = std::min(slack_baseline_mm_, slack);
    excess_mm_ = slack - slack_baseline_mm_;
}

bool Physician::keeps_pace(double sign) const {
    if (history_.size() < 2) return false;
    const Seen& a = history_.front();
    const Seen& b = history_.back();
    const double hand = sign * (b.insertion - a.insertion);
    const double tip = sign * (b.tip - a.tip);
    return hand >= kPhysicianPaceMinHand_mm && tip >= kPhysicianPaceFraction * hand;
}

void Physician::give_up(const std::string& why) {
    mode_ = Mode::done;
    end_reason_ = "gave_up";
    give_up_reason_ = why;
}

void Physician::start_reduction(const PhysicianObservation& seen) {
    ++reductions_;
    mode_ = Mode::reduce_turn;
    reduce_start_depth_mm_ = depth_mm_;
    reduce_max_withdraw_mm_ =
        std::clamp(excess_mm_ + 100.0, p_.min_withdraw_mm, p_.max_withdraw_mm);
    roll_target_rad_ =
        std::min(roll_rad_ + p_.reduce_roll_deg * kRadPerDeg, initial_roll_rad_ + M_PI);
    roll_target_rad_ = std::max(roll_target_rad_, roll_rad_);  // never counter-clockwise here
    (void)seen;
}

HandDecision Physician::decide(const PhysicianObservation& seen, double h_s) {
    const double t = seen.time_s;
    time_s_ = t;
    if (!started_) {
        started_ = true;
        best_tip_mm_ = seen.tip_path_mm;
        best_tip_since_s_ = t;
        start_bout(t);
    }
    if (mode_ != Mode::done) {
        if (seen.tip_path_mm >= seen.cecum_path_mm - kCecumReach_mm) {
            cecum_reached_ = true;
            cecum_time_s_ = t;
            cecum_insertion_mm_ = seen.insertion_mm;
            end_reason_ = "cecum_reached";
            mode_ = Mode::done;
        } else if (t >= spec_.max_duration_s - kEps_s) {
            end_reason_ = "max_duration";
            mode_ = Mode::done;
        }
    }
    track_pace(seen);
    if (mode_ != Mode::done) {
        if (seen.tip_path_mm >= best_tip_mm_ + kNewGround_mm) {
            best_tip_mm_ = seen.tip_path_mm;
            best_tip_since_s_ = t;
        } else if (t - best_tip_since_s_ >= p_.stall_give_up_s) {
            give_up("no new ground (" + number_text(kNewGround_mm) + " mm along the colon) for " +
                    number_text(p_.stall_give_up_s) + " s");
        }
    }

    const double cap_mm = scope_length_mm_ - kHandleMargin_mm;
    double speed = 0;
    if (mode_ == Mode::advance || mode_ == Mode::pause || mode_ == Mode::jiggle) {
        // What makes the hand stop pushing: the tip not following (first a jiggle, then, as the
        // loop grows, a reduction), resistance or discomfort, or the scope all in.
        const bool advancing = mode_ == Mode::advance;
        const bool loop = p_.loop_reduce_excess_mm > 0.0 && excess_mm_ >= p_.loop_reduce_excess_mm;
        const bool lagging =
            p_.loop_notice_excess_mm > 0.0 && excess_mm_ >= p_.loop_notice_excess_mm && !jiggled_;
        const bool resist = seen.handle_force_N >= p_.resistance_N ||
                            (p_.discomfort_N > 0.0 && seen.max_wall_force_N >= p_.discomfort_N);
        const bool all_in = depth_mm_ >= cap_mm - 1e-9;
        const bool resisted_loop = p_.resistance_with_lag_reduces && resist &&
                                   p_.loop_notice_excess_mm > 0.0 &&
                                   excess_mm_ >= p_.loop_notice_excess_mm;
        const bool trigger = loop || lagging || resist || all_in;
        if (excess_mm_ < 0.5 * p_.loop_notice_excess_mm) jiggled_ = false;  // keeps pace again
        if (advancing && trigger && !noticed_s_) noticed_s_ = t;
        if (noticed_s_ && !trigger) noticed_s_.reset();  // the tip caught up before the reaction
        if (noticed_s_ && t - *noticed_s_ >= p_.reaction_s - kEps_s) {
            noticed_s_.reset();
            if (p_.reduces_loops && (loop || all_in || resisted_loop)) {
                if (reductions_ >= p_.max_reductions)
                    give_up("a loop again after " + std::to_string(reductions_) +
                            " loop reductions");
                else
                    start_reduction(seen);
            } else if (resist || all_in || loop) {
                // Stop pushing for a while, then try again.
                mode_ = Mode::pause;
                mode_until_s_ = t + p_.pause_max_s;
            } else {
                // The tip lags: jiggle the shaft to let the colon pleat onto it, then go on.
                jiggled_ = true;
                mode_ = Mode::jiggle;
                jiggle_anchor_mm_ = depth_mm_;
                jiggle_start_s_ = t;
            }
        }
    }

    const Mode acting = mode_;  // what the hand does over this step (reported)
    const double depth_at_start_mm = depth_mm_;
    switch (mode_) {
        case Mode::advance:
            speed = speed_mm_per_s_;
            depth_mm_ = std::min(cap_mm, depth_mm_ + speed * h_s);
            roll_rad_ = move_towards(roll_rad_, roll_target_rad_,
                                     p_.torque_rate_deg_per_s * kRadPerDeg * h_s);
            if (t + h_s >= mode_until_s_ - kEps_s) after_bout(t + h_s);
            break;
        case Mode::pause:
            if (t + h_s >= mode_until_s_ - kEps_s) start_bout(t + h_s);
            break;
        case Mode::jiggle: {
            const double tau = t + h_s - jiggle_start_s_;
            const double w = 2.0 * M_PI * p_.jiggle_frequency_Hz;
            const double period_end =
                static_cast<double>(p_.jiggle_cycles) / p_.jiggle_frequency_Hz;
            if (tau >= period_end - kEps_s) {
                depth_mm_ = jiggle_anchor_mm_;
                start_bout(t + h_s);
            } else {
                const double next = std::min(
                    cap_mm, jiggle_anchor_mm_ + p_.jiggle_amplitude_mm * std::sin(w * tau));
                speed = (next - depth_mm_) / h_s;
                depth_mm_ = next;
            }
            break;
        }
        case Mode::reduce_turn:
            roll_rad_ = move_towards(roll_rad_, roll_target_rad_,
                                     p_.reduce_roll_rate_deg_per_s * kRadPerDeg * h_s);
            if (std::abs(roll_rad_ - roll_target_rad_) < 1e-12) mode_ = Mode::reduce_withdraw;
            break;
        case Mode::reduce_withdraw: {
            const double floor_mm = std::min(reduce_start_depth_mm_, kMinReduceDepth_mm);
            const double before = depth_mm_;
            depth_mm_ = std::max(floor_mm, depth_mm_ - p_.withdraw_speed_mm_per_s * h_s);
            speed = (depth_mm_ - before) / h_s;
            const double withdrawn = reduce_start_depth_mm_ - depth_mm_;
            const bool straight = withdrawn >= p_.min_withdraw_mm && keeps_pace(-1.0);
            if (straight || withdrawn >= reduce_max_withdraw_mm_ - 1e-9 ||
                depth_mm_ <= floor_mm + 1e-9) {
                mode_ = Mode::reduce_settle;
                mode_until_s_ = t + h_s + 1.0;
                if (p_.pressure_from_reduction > 0 && reductions_ >= p_.pressure_from_reduction) {
                    pressure_[static_cast<std::size_t>(ColonRegion::sigmoid)] = true;
                    if (static_cast<std::size_t>(seen.tip_region) >=
                        static_cast<std::size_t>(ColonRegion::splenic_flexure))
                        pressure_[static_cast<std::size_t>(ColonRegion::transverse)] = true;
                }
            }
            break;
        }
        case Mode::reduce_settle:
            if (t + h_s >= mode_until_s_ - kEps_s) {
                history_.clear();
                excess_mm_ = 0;
                slack_baseline_mm_ = seen.insertion_mm - seen.tip_path_mm;
                start_bout(t + h_s);
            }
            break;
        case Mode::done: break;
    }
    // The hand gives way: a push (or pull) beyond max_push_N replaces the step's own motion
    // towards the colon (away from it) by a move back (forward) at give_way_speed, at once; what
    // the hand was doing goes on from there.
    bool gave_way = false;
    if (mode_ != Mode::done && std::abs(seen.handle_force_N) >= p_.max_push_N) {
        const double give = p_.give_way_speed_mm_per_s * h_s;
        const double before = depth_mm_;
        depth_mm_ = seen.handle_force_N > 0.0 ? std::min(depth_mm_, depth_at_start_mm) - give
                                              : std::max(depth_mm_, depth_at_start_mm) + give;
        depth_mm_ = std::clamp(depth_mm_, 0.0, cap_mm);
        jiggle_anchor_mm_ -= before - depth_mm_;
        speed = (depth_mm_ - depth_at_start_mm) / h_s;
        gave_way = true;
    }

    bool pressing = false;
    for (bool on : pressure_)
        pressing = pressing || on;
    if (pressing) pressure_s_ += h_s;

    HandDecision d;
    d.command.insertion_mm = depth_mm_;
    d.command.roll_rad = roll_rad_;
    d.steering = p_.steers && mode_ != Mode::reduce_turn && mode_ != Mode::reduce_withdraw &&
                 mode_ != Mode::done;
    d.pressure = pressure_;
    d.state.state = gave_way ? std::string("give_way") : std::string(mode_name(acting));
    d.state.speed_mm_per_s = speed;
    d.state.roll_deg = roll_rad_ / kRadPerDeg;
    d.state.steering = d.steering;
    d.state.pressure = pressing;
    return d;
}

ProcedureOutcome Physician::outcome() const {
    ProcedureOutcome o;
    o.kind = "physician";
    o.style = std::string(physician_style_name(spec_.style));
    o.seed = spec_.seed;
    o.cecum_reached = cecum_reached_;
    if (cecum_reached_) {
        o.cecum_time_s = cecum_time_s_;
        o.insertion_at_cecum_mm = cecum_insertion_mm_;
    }
    o.loop_reductions = reductions_;
    o.abdominal_pressure_s = pressure_s_;
    o.duration_s = time_s_;
    o.end_reason = end_reason_;
    return o;
}

}  // namespace scopekin::model
