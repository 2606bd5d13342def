#include "model/scenario/procedure.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

/// Largest and smallest of sin(x) for x in [0, x_end] (x_end >= 0).
std::pair<double, double> sine_range(double x_end) {
    const double hi = x_end >= 0.5 * M_PI ? 1.0 : std::sin(x_end);
    double lo = 0.0;
    if (x_end >= 1.5 * M_PI)
        lo = -1.0;
    else if (x_end > M_PI)
        lo = std::sin(x_end);
    return {hi, lo};
}

bool axial_position_controlled(ActionKind k) {
    return k != ActionKind::push;
}
bool roll_position_controlled(ActionKind k) {
    return k != ActionKind::twist;
}

}  // namespace

std::string_view action_name(ActionKind kind) {
    switch (kind) {
        case ActionKind::advance: return "advance";
        case ActionKind::withdraw: return "withdraw";
        case ActionKind::hold: return "hold";
        case ActionKind::push: return "push";
        case ActionKind::twist: return "twist";
        case ActionKind::rotate: return "rotate";
        case ActionKind::dither: return "dither";
    }
    return "unknown";
}

Procedure::Procedure(std::vector<ProcedureAction> actions, const std::string& path)
    : actions_(std::move(actions)) {
    if (actions_.empty()) throw ModelError(path + ": needs at least one action");
    for (std::size_t i = 0; i < actions_.size(); ++i) {
        const ProcedureAction& a = actions_[i];
        const std::string at = path + "[" + std::to_string(i) + "]";
        require_non_negative(a.start_s, at + ".start_s");
        require_finite(a.end_s, at + ".end_s");
        if (!(a.end_s > a.start_s))
            throw ModelError(at + ".end_s: " + number_text(a.end_s) +
                             " s must be later than start_s (" + number_text(a.start_s) + " s)");
        if (a.end_s > kMaxProcedureDuration_s)
            throw ModelError(at + ".end_s: " + number_text(a.end_s) +
                             " s is beyond the longest procedure accepted (" +
                             number_text(kMaxProcedureDuration_s) + " s = 1 h)");
        if (i > 0 && a.start_s < actions_[i - 1].end_s) {
            const ProcedureAction& prev = actions_[i - 1];
            const std::string what = a.start_s < prev.start_s ? "goes backwards in time"
                                                              : "overlaps the previous action";
            throw ModelError(at + ".start_s: " + number_text(a.start_s) + " s " + what +
                             " (action " + std::to_string(i - 1) + ", " +
                             std::string(action_name(prev.kind)) + ", runs " +
                             number_text(prev.start_s) + " .. " + number_text(prev.end_s) +
                             " s); actions must be in time order, each starting at or after the "
                             "previous one's end_s");
        }
        switch (a.kind) {
            case ActionKind::advance:
            case ActionKind::withdraw:
                require_positive(a.speed_mm_per_s, at + ".speed_mm_per_s");
                break;
            case ActionKind::push: require_finite(a.force_N, at + ".force_N"); break;
            case ActionKind::twist: require_finite(a.torque_Nmm, at + ".torque_Nmm"); break;
            case ActionKind::rotate:
                require_finite(a.speed_deg_per_s, at + ".speed_deg_per_s");
                break;
            case ActionKind::dither:
                require_positive(a.amplitude_mm, at + ".amplitude_mm");
                require_positive(a.frequency_Hz, at + ".frequency_Hz");
                break;
            case ActionKind::hold: break;
        }
    }
}

void Procedure::check_depths(double initial_insertion_mm, double scope_length_mm,
                             const std::string& path) const {
    double depth = initial_insertion_mm;
    for (std::size_t i = 0; i < actions_.size(); ++i) {
        const ProcedureAction& a = actions_[i];
        if (a.kind == ActionKind::push) return;  // from here on the depth depends on the world
        const double duration = a.end_s - a.start_s;
        double lo = depth, hi = depth, end = depth, t_lo = a.start_s, t_hi = a.start_s;
        switch (a.kind) {
            case ActionKind::advance:
                end = hi = depth + a.speed_mm_per_s * duration;
                t_hi = a.end_s;
                break;
            case ActionKind::withdraw:
                end = lo = depth - a.speed_mm_per_s * duration;
                t_lo = a.end_s;
                break;
            case ActionKind::dither: {
                const double x_end = 2.0 * M_PI * a.frequency_Hz * duration;
                const auto [s_hi, s_lo] = sine_range(x_end);
                hi = depth + a.amplitude_mm * s_hi;
                lo = depth + a.amplitude_mm * s_lo;
                t_hi = a.start_s + std::min(duration, 0.25 / a.frequency_Hz);
                t_lo = a.start_s + std::min(duration, 0.75 / a.frequency_Hz);
                end = depth + a.amplitude_mm * std::sin(x_end);
                break;
            }
            default: break;
        }
        const std::string at =
            path + "[" + std::to_string(i) + "] (" + std::string(action_name(a.kind)) + ")";
        if (lo < 0.0)
            throw ModelError(at + ": the prescribed insertion depth would reach " +
                             number_text(lo) + " mm at t = " + number_text(t_lo) +
                             " s; it must stay >= 0 mm (the tip at the anus)");
        if (hi >= scope_length_mm)
            throw ModelError(at + ": the prescribed insertion depth would reach " +
                             number_text(hi) + " mm at t = " + number_text(t_hi) +
                             " s; it must stay below the scope's length (" +
                             number_text(scope_length_mm) + " mm)");
        depth = end;
    }
}

ProcedurePlayer::ProcedurePlayer(const Procedure& procedure, double initial_insertion_mm,
                                 double scope_length_mm, double initial_roll_rad)
    : depth_anchor_mm_(initial_insertion_mm),
      roll_anchor_rad_(initial_roll_rad),
      scope_length_mm_(scope_length_mm),
      end_s_(procedure.end_s()) {
    double t = 0.0;
    const auto& actions = procedure.actions();
    for (std::size_t i = 0; i < actions.size(); ++i) {
        if (actions[i].start_s > t) {
            ProcedureAction gap;
            gap.kind = ActionKind::hold;
            gap.start_s = t;
            gap.end_s = actions[i].start_s;
            segments_.push_back({gap, -1});
        }
        segments_.push_back({actions[i], static_cast<int>(i)});
        t = actions[i].end_s;
    }
    if (segments_.empty()) {  // an empty procedure: hold for ever
        ProcedureAction hold;
        hold.end_s = 0.0;
        segments_.push_back({hold, -1});
    }
}

int ProcedurePlayer::current_action() const {
    return segments_[current_].index;
}

double ProcedurePlayer::depth_at(const Segment& s, double t_s) const {
    const ProcedureAction& a = s.action;
    const double tau = std::clamp(t_s - a.start_s, 0.0, a.end_s - a.start_s);
    switch (a.kind) {
        case ActionKind::advance: return depth_anchor_mm_ + a.speed_mm_per_s * tau;
        case ActionKind::withdraw: return depth_anchor_mm_ - a.speed_mm_per_s * tau;
        case ActionKind::dither:
            return depth_anchor_mm_ + a.amplitude_mm * std::sin(2.0 * M_PI * a.frequency_Hz * tau);
        default: return depth_anchor_mm_;
    }
}

double ProcedurePlayer::roll_at(const Segment& s, double t_s) const {
    const ProcedureAction& a = s.action;
    if (a.kind != ActionKind::rotate) return roll_anchor_rad_;
    const double tau = std::clamp(t_s - a.start_s, 0.0, a.end_s - a.start_s);
    return roll_anchor_rad_ + a.speed_deg_per_s * M_PI / 180.0 * tau;
}

void ProcedurePlayer::enter(std::size_t next, double depth_now_mm, double roll_now_rad) {
    const Segment& leaving = segments_[current_];
    // Continuity of the prescribed timeline; after force / torque control, where the world is.
    depth_anchor_mm_ = axial_position_controlled(leaving.action.kind)
                           ? depth_at(leaving, leaving.action.end_s)
                           : depth_now_mm;
    roll_anchor_rad_ = roll_position_controlled(leaving.action.kind)
                           ? roll_at(leaving, leaving.action.end_s)
                           : roll_now_rad;
    current_ = next;
}

HandleCommand ProcedurePlayer::command(double t_s, double h_s, double depth_now_mm,
                                       double roll_now_rad) {
    const double t_end = t_s + h_s;
    // The segment holding the end of the step: the first whose end_s is not before it.
    const double eps = 1e-9 * std::max(1.0, end_s_);
    while (current_ + 1 < segments_.size() && t_end > segments_[current_].action.end_s + eps)
        enter(current_ + 1, depth_now_mm, roll_now_rad);
    const Segment& s = segments_[current_];
    HandleCommand c;
    if (s.action.kind == ActionKind::push) {
        c.force_controlled = true;
        c.push_force_N = s.action.force_N;
        c.insertion_mm = depth_now_mm;
    } else {
        const double depth = depth_at(s, t_end);
        c.insertion_mm = depth;
        const double upper = scope_length_mm_ * (1.0 - 1e-9);
        if (depth < 0.0 || depth > upper) {
            c.insertion_mm = std::clamp(depth, 0.0, upper);
            if (clamp_warned_for_ != static_cast<int>(current_)) {
                clamp_warned_for_ = static_cast<int>(current_);
                std::ostringstream m;
                m << "t = " << t_end << " s";
                if (s.index >= 0)
                    m << ", procedure[" << s.index << "] (" << action_name(s.action.kind) << ")";
                m << ": the prescribed insertion depth " << depth << " mm is outside [0, "
                  << scope_length_mm_
                  << ") mm (the depth after a push is known only while running); clamped to "
                  << c.insertion_mm << " mm";
                warnings_.push_back(m.str());
            }
        }
    }
    if (s.action.kind == ActionKind::twist) {
        c.torque_controlled = true;
        c.torque_Nmm = s.action.torque_Nmm;
        c.roll_rad = roll_now_rad;
    } else {
        c.roll_rad = roll_at(s, t_end);
    }
    return c;
}

}  // namespace scopekin::model
