#pragma once
// A procedure: what the physician's hand does at the handle over time, as a validated timeline
// of actions (model/scenario/README.md), and the player that turns it into one HandleCommand per
// world step. Independent of files and of the command line.
//
// Actions run in order and never overlap; a gap between two actions is a hold. Axially the hand
// either prescribes the insertion depth (advance, withdraw, hold, dither, and during twist and
// rotate) or pushes with a force (push); about the entry axis it either prescribes the roll
// (every action but twist) or applies a torque (twist). Prescribed motions are relative to where
// the action starts: after a prescribed action, the value it ended at (the timeline is
// continuous); after a push / twist, the world's depth / roll at that moment.
#include <string>
#include <string_view>
#include <vector>

#include "model/scenario/hand_command_source.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

enum class ActionKind {
    advance,
    withdraw,
    hold,
    push,
    twist,
    rotate,
    dither
};

std::string_view action_name(ActionKind kind);

struct ProcedureAction {
    ActionKind kind = ActionKind::hold;
    double start_s = 0;
    double end_s = 0;
    double speed_mm_per_s = 0;   ///< advance, withdraw: > 0
    double force_N = 0;          ///< push: along the entry axis, + = in
    double torque_Nmm = 0;       ///< twist: about the entry axis (sign = direction)
    double speed_deg_per_s = 0;  ///< rotate: roll rate (sign = direction)
    double amplitude_mm = 0;     ///< dither: > 0
    double frequency_Hz = 0;     ///< dither: > 0
};

/// Longest procedure accepted [s].
inline constexpr double kMaxProcedureDuration_s = 3600.0;

class Procedure {
public:
    Procedure() = default;
    /// Validates: at least one action, finite times, 0 <= start_s < end_s <= 1 h, each action
    /// starting at or after the previous one's end, parameters finite and in range. Messages name
    /// the field as `<path>[i].<key>` (path e.g. "scenario.json: procedure").
    explicit Procedure(std::vector<ProcedureAction> actions, const std::string& path = "procedure");

    const std::vector<ProcedureAction>& actions() const { return actions_; }
    /// The end of the last action: where the simulation stops [s].
    double end_s() const { return actions_.empty() ? 0.0 : actions_.back().end_s; }

    /// Checks the prescribed depth stays within [0, scope length) wherever it is known before
    /// running: from t = 0 until the first push (after a push it depends on the world).
    void check_depths(double initial_insertion_mm, double scope_length_mm,
                      const std::string& path = "procedure") const;

private:
    std::vector<ProcedureAction> actions_;
};

/// Plays a procedure step by step. The world steps from t to t + h; `command` returns what the
/// hand does at t + h given the world's state at t. As a HandCommandSource it ignores the step's
/// index: the procedure's timeline is in world time.
class ProcedurePlayer final : public HandCommandSource {
public:
    ProcedurePlayer(const Procedure& procedure, double initial_insertion_mm, double scope_length_mm,
                    double initial_roll_rad = 0.0);

    /// The command for the step [t_s, t_s + h_s]; `depth_now_mm` and `roll_now_rad` are the world's
    /// insertion depth and roll at t_s (World::insertion_depth_mm(), World::roll_rad()). They are
    /// used only where position control resumes after a push or twist. A prescribed depth outside
    /// [0, scope length) (possible only after a push) is clamped and a warning recorded.
    HandleCommand command(double t_s, double h_s, double depth_now_mm, double roll_now_rad);
    HandleCommand command_for_step(std::size_t /*step*/, double t_s, double h_s,
                                   double depth_now_mm, double roll_now_rad) override {
        return command(t_s, h_s, depth_now_mm, roll_now_rad);
    }

    double end_s() const { return end_s_; }
    /// Index into Procedure::actions() of the action playing at the last command, or -1 in a gap.
    int current_action() const;
    std::vector<std::string> warnings() const override { return warnings_; }

private:
    struct Segment {
        ProcedureAction action;
        int index = -1;  ///< action index, -1 for an implicit hold (gap)
    };
    double depth_at(const Segment& s, double t_s) const;
    double roll_at(const Segment& s, double t_s) const;
    void enter(std::size_t next, double depth_now_mm, double roll_now_rad);

    std::vector<Segment> segments_;
    std::size_t current_ = 0;
    double depth_anchor_mm_ = 0;
    double roll_anchor_rad_ = 0;
    double scope_length_mm_ = 0;
    double end_s_ = 0;
    int clamp_warned_for_ = -2;
    std::vector<std::string> warnings_;
};

}  // namespace scopekin::model
