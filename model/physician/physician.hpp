#pragma once
// The physician: a procedure generator that drives any patient towards the cecum the way
// endoscopists do (model/physician/README.md). It is the physician's hands, not the box: it
// decides from what a physician sees on the video (how far along the colon the tip is, whether
// it keeps pace with the hand, which part of the colon it is in) and feels at the handle (push
// force), never from the firmware's outputs. This file is the decision logic alone, free of any
// world: each step it takes a PhysicianObservation and returns the hand's command for the step,
// whether it steers the tip and where the assistant presses. physician_source.hpp connects it to
// a simulated World.
//
// Styles (every number in physician_style_parameters, with its source or "stated guess" in the
// README): careful_expert, hurried_trainee, bench_operator. Randomness: std::mt19937_64 seeded
// from the seed, turned into numbers by our own transforms (PatientRandom), drawn only when a
// bout of advancing starts, so the same style and seed give the same hands in the same world and
// other hands where the world answers otherwise.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/colon/colon_region.hpp"
#include "model/patient/patient_random.hpp"
#include "model/scenario/hand_command_source.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

enum class PhysicianStyle {
    careful_expert,
    hurried_trainee,
    bench_operator
};

std::string_view physician_style_name(PhysicianStyle style);
std::optional<PhysicianStyle> physician_style_from_name(std::string_view name);
/// "careful_expert, hurried_trainee, bench_operator"
std::string physician_style_list();

/// Every parameter of a style (model/physician/README.md gives each its source).
struct PhysicianStyleParameters {
    // Advancing, in bouts: each bout draws its speed and length.
    double speed_min_mm_per_s = 10;
    double speed_max_mm_per_s = 25;
    double bout_min_s = 2;
    double bout_max_s = 6;
    // After a bout: a pause (holds still) with this probability, else a jiggle with its own,
    // else straight on into the next bout.
    double pause_probability = 0.4;
    double pause_min_s = 0.5;
    double pause_max_s = 2.0;
    double jiggle_probability = 0.3;
    double jiggle_amplitude_mm = 8;  ///< in/out: depth = anchor + A sin(2 pi f t), whole cycles
    double jiggle_frequency_Hz = 1.0;
    std::size_t jiggle_cycles = 3;
    // Torque steering: at a bout's start, with this probability, the shaft is turned by
    // +-[min, max] degrees (sign drawn) at the rate, kept within +-torque_range_deg of the start.
    double torque_probability = 0.5;
    double torque_min_deg = 10;
    double torque_max_deg = 30;
    double torque_rate_deg_per_s = 20;
    double torque_range_deg = 90;
    // Tip steering down the lumen (tip_steering.hpp) while advancing, pausing and jiggling.
    bool steers = true;
    double steering_gain = 1.0;         ///< the expert angulates the tip fully into the lumen
    bool steering_follows_turn = true;  ///< ... and around a flexure (tip_steering.hpp)
    /// ... with the wheels' law (held curvature) rather than a couple (tip_steering.hpp).
    bool steering_holds_curvature = false;
    // What makes the hand stop pushing.
    /// Scope taken up while the tip did not follow (the loop watch): at the first threshold the
    /// hand jiggles (once, until the tip keeps pace again; 0 = never), at the second it reduces.
    double loop_notice_excess_mm = 20;
    double loop_reduce_excess_mm = 60;
    double resistance_N = 30;  ///< push force felt as resistance
    /// The hand is not a rigid clamp: beyond this |handle force| it gives way at once (no
    /// reaction time), moving the depth back at give_way_speed until the force is below it.
    double max_push_N = 40;
    double give_way_speed_mm_per_s = 20;
    double discomfort_N = 20;  ///< largest wall force (the patient's discomfort); 0 = none
    double reaction_s = 0.5;   ///< from noticing to acting
    /// Resistance felt while the tip lags (excess >= the lag threshold) is taken for a loop: the
    /// hand reduces instead of pausing and pushing again (a push that does not move the tip is a
    /// loop: the 1:1 rule).
    bool resistance_with_lag_reduces = true;
    // Loop reduction: turn clockwise, withdraw until the tip comes back with the hand.
    bool reduces_loops = true;
    double reduce_roll_deg =
        90;  ///< clockwise (+), at reduce_roll_rate, capped at +180 deg overall
    double reduce_roll_rate_deg_per_s = 45;
    double withdraw_speed_mm_per_s = 15;
    double min_withdraw_mm = 30;
    double max_withdraw_mm = 300;  ///< and at most the excess noticed + 100 mm
    /// The assistant presses from this reduction on (1 = the first; 0 = never).
    std::size_t pressure_from_reduction = 1;
    /// The assistant's firmness when pressing (model/scenario/abdominal_pressure.hpp) [N/mm per mm
    /// of scope], a stated guess: ten times the demo's 0.07, a hand that holds the bowel where it
    /// is rather than one that leans on it. Its net force on the scope stays a hand's: on the 12
    /// development experts 20 N (median of the runs' means while pressing; 16 N at 0.07), and at
    /// most pressure_max_force_N per region (model/physician/README.md).
    double pressure_stiffness_N_per_mm2 = 0.7;
    /// The most the assistant's hand gives over one region [N] (the net force on the region's
    /// nodes; SceneControl::pressure_max_force_N): a stated guess, a firm two-handed press of
    /// about 5 kg; no measured figure for an assistant's hand was found.
    double pressure_max_force_N = 50;
    std::size_t max_reductions = 8;  ///< a loop after this many: gives up
    // Giving up.
    double stall_give_up_s = 90;  ///< no new ground (20 mm along the colon) for this long
    double default_max_duration_s = 600;
};

PhysicianStyleParameters physician_style_parameters(PhysicianStyle style);

/// "physician": {"style": ..., "seed": N, "max_duration_s": S} of a scenario.
struct PhysicianSpec {
    PhysicianStyle style = PhysicianStyle::careful_expert;
    std::uint64_t seed = 0;
    double max_duration_s = 600;
    /// The angulation law (tip_steering.hpp): the style's (couple) unless given; true = the
    /// wheels' held curvature.
    std::optional<bool> steering_holds_curvature;
    /// The assistant's firmness [N/mm per mm]: the style's unless given (0, 1].
    std::optional<double> pressure_stiffness_N_per_mm2;
};

/// What the physician sees and feels at the start of a step.
struct PhysicianObservation {
    double time_s = 0;
    double insertion_mm = 0;    ///< the hand's own position (depth past the anus)
    double handle_force_N = 0;  ///< felt: + = the colon pushes back on the hand pushing in
    double tip_path_mm = 0;     ///< the video: where the tip is along the colon (its coordinate)
    ColonRegion tip_region = ColonRegion::rectum;  ///< the video: landmarks
    double cecum_path_mm = 0;     ///< where the cecal pole is along the colon (the colon's length)
    double max_wall_force_N = 0;  ///< the patient's discomfort: the largest wall force (normal)
};

/// The tip is at the cecum when it is within this distance of the cecal pole along the colon
/// (a stated guess: the appendiceal orifice and ileocecal valve are in view from there; the
/// family's cecum is 50-70 mm long).
inline constexpr double kCecumReach_mm = 30.0;
/// Pace judged over this trailing window (a physician's look at the video, a stated guess) ...
inline constexpr double kPhysicianPaceWindow_s = 1.0;
/// ... when the hand moved at least this much in it; the tip keeps pace at half the hand's motion.
inline constexpr double kPhysicianPaceMinHand_mm = 2.0;
inline constexpr double kPhysicianPaceFraction = 0.5;
/// New ground: the tip's farthest place along the colon grows by this much.
inline constexpr double kNewGround_mm = 20.0;
/// The hand stops this far short of the scope's full length (the handle's bending relief).
inline constexpr double kHandleMargin_mm = 10.0;
/// The hand withdraws no further than this depth while reducing a loop.
inline constexpr double kMinReduceDepth_mm = 100.0;
/// Longest max_duration_s accepted [s].
inline constexpr double kMaxPhysicianDuration_s = 3600.0;

/// The hand's decision for one step.
struct HandDecision {
    HandleCommand command;
    HandState state;
    bool steering = false;
    /// Regions the assistant presses (kColonRegionsInOrder order): true from the step it starts.
    std::array<bool, 8> pressure{};
};

class Physician {
public:
    Physician(const PhysicianSpec& spec, double initial_insertion_mm, double initial_roll_rad,
              double scope_length_mm);
    /// Same, with a style's parameters given (tests).
    Physician(const PhysicianSpec& spec, const PhysicianStyleParameters& parameters,
              double initial_insertion_mm, double initial_roll_rad, double scope_length_mm);

    /// What the hand does over [seen.time_s, seen.time_s + h_s]. Once finished() the hand holds.
    HandDecision decide(const PhysicianObservation& seen, double h_s);

    bool finished() const { return !end_reason_.empty(); }
    /// "cecum_reached", "max_duration", "gave_up" ("" while going on).
    const std::string& end_reason() const { return end_reason_; }
    ProcedureOutcome outcome() const;
    const PhysicianStyleParameters& parameters() const { return p_; }
    /// Why it gave up ("" if it did not).
    const std::string& give_up_reason() const { return give_up_reason_; }

private:
    enum class Mode {
        advance,
        pause,
        jiggle,
        reduce_turn,
        reduce_withdraw,
        reduce_settle,
        done
    };
    struct Seen {
        double t = 0;
        double insertion = 0;
        double tip = 0;
    };
    void start_bout(double t);
    void after_bout(double t);
    void start_reduction(const PhysicianObservation& seen);
    void track_pace(const PhysicianObservation& seen);
    bool keeps_pace(double sign) const;
    void give_up(const std::string& why);
    static std::string_view mode_name(Mode mode);

    PhysicianSpec spec_;
    PhysicianStyleParameters p_;
    PatientRandom random_;
    double scope_length_mm_;
    double initial_roll_rad_;
    double depth_mm_;
    double roll_rad_;
    Mode mode_ = Mode::advance;
    double mode_until_s_ = 0;  ///< advance, pause, reduce_settle: when the mode ends
    double speed_mm_per_s_ = 0;
    double roll_target_rad_ = 0;
    double jiggle_anchor_mm_ = 0;
    double jiggle_start_s_ = 0;
    double reduce_start_depth_mm_ = 0;
    double reduce_max_withdraw_mm_ = 0;
    bool started_ = false;
    // Loop watch.
    std::deque<Seen> history_;
    double slack_baseline_mm_ = 0;  ///< least (insertion - tip) since the tip last kept pace
    double excess_mm_ = 0;
    std::optional<double> noticed_s_;
    bool jiggled_ = false;  ///< jiggled for the lag now (until the tip keeps pace again)
    // Progress.
    double best_tip_mm_ = 0;
    double best_tip_since_s_ = 0;
    std::size_t reductions_ = 0;
    std::array<bool, 8> pressure_{};
    double pressure_s_ = 0;
    bool cecum_reached_ = false;
    double cecum_time_s_ = 0;
    double cecum_insertion_mm_ = 0;
    double time_s_ = 0;
    std::string end_reason_;
    std::string give_up_reason_;
};

}  // namespace scopekin::model
