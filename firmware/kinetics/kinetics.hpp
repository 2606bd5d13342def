// kinetics.hpp — the firmware's kinetic estimator: one call per period.
//
//   init(config, state)          once at start-up: validates the configuration and the reduced
//                                model's tables (shape, segments, checksum); the only place
//                                anything is set up
//   step(inputs, state, outputs) every period (default 5 ms = 200 Hz): pure function of its
//                                arguments, no heap, no static mutable data, fixed work
//
// One step:
//   1. Input validation (see "Bad input" below): every signal is range-checked, held when stale,
//      and the insertion depth is rate-limited; each fault sets its Outputs::fault_flags bit.
//   2. The reduced-order model (reduced_kinetics.hpp) at the validated depth: the Gauss-Seidel
//      contact solve of the stations in Q16.16, a fixed number of sweeps and local iterations.
//   3. The tip observer (tip_observer.hpp): the tip along the colon from the handle's evidence
//      (depth and push force), with its uncertainty, at every depth. The model evidence
//      (model_evidence.hpp): whether the handle force agrees with what the model's training run
//      needed; while it does, the model's tip is published and the observer continues from it.
//      The slack regressor (slack_regressor.hpp): depth - tip regressed on the handle's history,
//      the observer's slack among its inputs, by trees fitted on a population of patients.
//      The tip odometer (tip_odometer.hpp): only while the test bench's EM tracker is connected,
//      the tip sensor's travel along the scope's axis, fused with the handle's tip above by a
//      scalar Kalman filter; without tracker samples the handle's tip is published unchanged.
//      The slack excess (slack_excess.hpp): with the tracker, the scope taken up since the tip
//      last kept pace with the hand (the truth's pace rule on the odometer's travel).
//   4. Outputs: the published tip (the model's while trusted, else the regressor's, else the
//      observer's when no trees are configured), its
//      uncertainty and its velocity (mean over the last
//      kVelocityWindow steps, so it lags by half that window); the reduced model's own tip
//      (model_tip_path_mm); each station's forces and stick / slip state, placed behind the
//      published tip as on the scope; the largest contact force (the model's while trusted, else
//      the contact force trees' regression on the slack regressor's features, with its
//      uncertainty; the model's own in model_max_contact_force_N) and where it acts (the model's).
//   5. Monitors (firmware/monitors): advance efficiency, self-lock (the tip station stuck while
//      the handle advances, T_on = 36 steps; confirmed by falling efficiency), contact-force
//      warning / critical. Efficiency and self-lock read the reduced model (its tip and stick
//      states, on which they were designed and verified). While the model is not trusted the
//      published self-lock alarm is the loop alarm from evidence (evidence_alarm.hpp: trees on
//      the slack regressor's features, debounced; with the tracker, the score counts only past
//      the slack excess's gate, at its own level); the model's own is model_self_lock_alarm.
//      The published contact-force level reads the published largest force (the model's while
//      trusted, else the force trees'); the model's own level is model_contact_force_level.
//
// Bad input (Config limits; all Q16.16):
//   * no fresh sample: the last valid value is held and the signal's "stale" flag is set for as
//     long as it lasts;
//   * outside its range: saturated to the range, "range" flag;
//   * insertion depth moving faster than max_insertion_speed (a hand cannot move the scope 1 m in
//     5 ms; the encoder can glitch): the depth used moves toward the reading by at most
//     max_insertion_speed * period per step and the "jump" flag is set until it has caught up —
//     so a genuine re-zeroing is followed, slowly, and a one-sample spike moves it by one limit.
//   * tables that fail init's checks: every step returns the fault kFaultModelTables and no
//     estimate (zeros); nothing is computed from data that is not what the generator wrote.
//
// A stale force cell (the handle's force/torque sensor silent, unplugged or failing):
//   Every stale period sets kFaultForceStale. The estimate then runs on what is still measured,
//   the depth, and on the force history up to the cell's last valid reading: the tip observer
//   loses its force evidence (the tip follows the depth, tip_observer.hpp), the model evidence
//   stops weighing, and the slack regressor's force averages hold where the cell left them
//   (slack_regressor.hpp) instead of averaging a held reading as if it were measured, so when
//   the cell returns the estimator resumes from them in its first fresh period. After
//   force_blind_after_steps stale periods in a row (default 20: 100 ms, so a dropped sample or
//   two does not count) kFaultForceBlind says the handle force is lost, for as long as it lasts.
//   Measured on the development set with the cell silent for 20 s from 40 % of each case
//   (firmware/README.md, "A stale force cell"): tip 17.8 / 38.1 mm (median / 90th percentile
//   of the cases' RMS in the silent window; 17.0 / 38.0 mm with the cell working), largest
//   contact force 4.5 N RMS (3.3 N). Falling back further, to the observer's dead reckoning and
//   the reduced model's force and loop alarm (depth alone, no force history), was worse: tip
//   19.0 / 39.5 mm, force 7.5 N, and the model's loop alarm was raised in 53 % of the window's
//   loop-free time.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "contact/gauss_seidel_contact.hpp"
#include "kinetics/evidence_alarm.hpp"
#include "kinetics/kinetics_io.hpp"
#include "kinetics/model_evidence.hpp"
#include "kinetics/reduced_kinetics.hpp"
#include "kinetics/reduced_tables.hpp"
#include "kinetics/slack_excess.hpp"
#include "kinetics/slack_regressor.hpp"
#include "kinetics/tip_observer.hpp"
#include "kinetics/tip_odometer.hpp"
#include "monitors/advance_efficiency.hpp"
#include "monitors/contact_force_monitor.hpp"
#include "monitors/self_lock_monitor.hpp"

namespace scopekin::kinetics {

/// Steps over which the tip velocity is averaged (50 ms at 5 ms).
inline constexpr std::size_t kVelocityWindow = 10;

struct InputLimits {
    Q16_16 insertion_min_mm =
        Q16_16::from_int(-50);  ///< encoder reads a little below 0 at the anus
    Q16_16 insertion_max_mm = Q16_16::from_int(2000);  ///< longer than any colonoscope (1.7 m)
    Q16_16 max_insertion_speed_mm_per_s = Q16_16::from_int(1000);  ///< a fast hand: ~0.5 m/s
    Q16_16 force_max_abs_N = Q16_16::from_int(100);      ///< 2x the 43 N push of Appleyard 2000
    Q16_16 torque_max_abs_Nmm = Q16_16::from_int(2000);  ///< 2x the 1 N·m of Appleyard 2000
    Q16_16 roll_max_abs_rad = Q16_16::from_int(315);     ///< 50 turns, unwrapped
};

/// The kinetic estimator's self-lock settings: the monitor's defaults with T_on = 36 steps.
inline constexpr monitors::SelfLockMonitor::Config kSelfLockConfig = [] {
    monitors::SelfLockMonitor::Config config{};
    config.on_steps = 36;
    return config;
}();

/// The published contact-force level's settings: the monitor's thresholds (10 N, 14 N, 0.9)
/// raised after 20 steps (0.1 s) at or above them. Chosen on the development set as the
/// persistence that finds the most >= 10 N and >= 14 N episodes within 0.5 s while the false
/// alarms' 90th percentile over sets of 20 patients stays within 3 per 10 min (the handle force
/// monitor's budget): firmware/README.md, "The contact-force level from evidence".
inline constexpr monitors::ContactForceMonitor::Config kPublishedContactForceConfig = [] {
    monitors::ContactForceMonitor::Config config{};
    config.persistence_steps = 20;
    return config;
}();

struct Config {
    Q16_16 period_s = Q16_16::from_ratio(1, 200);  ///< step period (5 ms); (0, 1] s
    /// The reduced model (kinetics/default_reduced_tables.hpp for the generated default set).
    const ReducedTablesQ16* tables{nullptr};
    /// Sweeps of the station contact solve (fixed: same work every step; the stations' W is block
    /// diagonal, so one sweep solves it exactly) and safeguarded-Newton iterations per local slip
    /// solve (12: Q16.16 within 0.5 mN of double, see the solver tests).
    std::uint16_t contact_sweeps = 1;
    std::uint16_t contact_local_iterations = 6;
    InputLimits limits{};
    monitors::AdvanceEfficiency<>::Config efficiency{};
    /// Self-lock: raised after the tip station has stuck for 36 steps (0.18 s) while the hand
    /// advances (firmware/README.md, "Alarms": the reference model's tip stalls up to 31 steps in stick-slip
    /// where no loop forms, and 41 steps at the first stall of the sigmoid loop).
    monitors::SelfLockMonitor::Config self_lock{kSelfLockConfig};
    /// The published contact-force level (on max_contact_force_N).
    monitors::ContactForceMonitor::Config contact_force{kPublishedContactForceConfig};
    /// The reduced model's own level (on model_max_contact_force_N): the monitor's defaults, a
    /// force reported on its first step, as the model's level was published before.
    monitors::ContactForceMonitor::Config model_contact_force{};
    TipObserver::Config tip_observer{};
    ModelEvidence::Config model_evidence{};
    /// The slack regressor's trees (slack_regressor.hpp; default_config() sets the fitted ones).
    /// nullptr: no regressor, the observer's tip is published (as before it existed).
    const SlackTrees* slack_trees{nullptr};
    /// Trees on the same features for the largest contact force (default_config() sets the
    /// fitted ones). nullptr: the reduced model's largest force is published (as before).
    /// Needs slack_trees (the features are the slack regressor's) with the same time constants.
    const SlackTrees* contact_force_trees{nullptr};
    /// The loop alarm from evidence (evidence_alarm.hpp; default_config() sets the fitted trees
    /// and settings): the published self-lock alarm while the model is not trusted. nullptr: the
    /// reduced model's self-lock monitor alone (as before). Needs slack_trees, same averages.
    const SlackTrees* loop_alarm_trees{nullptr};
    EvidenceAlarm::Config loop_alarm{};
    /// The bench's EM tracker's tip, fused with the handle's tip when it is connected
    /// (tip_odometer.hpp); without tracker samples it changes nothing.
    TipOdometer::Config tip_odometer{};
    /// With the tracker: the scope taken up since the tip last kept pace (slack_excess.hpp); the
    /// loop score counts only from its gate_mm on, and loop_alarm_with_tracker debounces it
    /// (raise 0.625, clear 0.525, 10 and 100 periods: chosen on the development set with the
    /// alarm's trees held out and a margin under the false-alarm budget,
    /// host_sim/evaluate/tune_loop_gate.py). Without the tracker the loop alarm is loop_alarm's.
    SlackExcess::Config slack_excess{};
    EvidenceAlarm::Config loop_alarm_with_tracker{40960, 34406, 10U, 100U};
    /// Stale force periods in a row after which the handle force counts as lost
    /// (kFaultForceBlind, "A stale force cell" above); 1..1000.
    std::uint16_t force_blind_after_steps{20};
};

/// Why init refused a configuration (State::config_fault; none = accepted).
enum class ConfigFault : std::uint8_t {
    none,
    period,                   ///< period_s outside (0, 1] s
    contact_settings,         ///< sweeps or local iterations 0 or above 64
    limits,                   ///< an input range empty, a limit not positive, or
                              ///< force_blind_after_steps outside 1..1000
    tables,                   ///< the reduced model's tables failed check_reduced_tables
    monitors,                 ///< a monitor refused its Config
    tip_observer,             ///< the tip observer refused its Config
    model_evidence,           ///< the model evidence refused its Config
    slack_regressor,          ///< the slack regressor's trees are not valid()
    contact_force_regressor,  ///< the force trees not valid(), or without matching slack trees
    loop_alarm,               ///< the loop alarm's trees or settings (with the tracker's too) not
                              ///< valid(), or no slack trees
    tip_odometer,             ///< the tip odometer's settings not valid() at this period
};

/// All mutable data of the estimator (Drake-style context).  Sized at compile time.
struct State {
    Config config{};
    ConfigFault config_fault{ConfigFault::tables};
    ReducedTablesFault tables_fault{ReducedTablesFault::missing};
    std::uint32_t steps{0};
    // Last valid inputs (held while a signal is stale).
    Q16_16 insertion_mm{};  ///< the depth the model uses (rate-limited)
    Q16_16 handle_force_N{};
    Q16_16 handle_torque_Nmm{};
    Q16_16 roll_rad{};
    bool insertion_seen{false};  ///< the first valid insertion sample sets the depth directly
    std::uint16_t force_stale_steps{0};  ///< consecutive stale force periods (saturating)
    ReducedState<Q16_16, kStationCapacity> model{};
    std::array<Q16_16, kVelocityWindow> tip_history_mm{};  ///< ring, oldest at tip_history_next
    std::size_t tip_history_next{0};
    std::size_t tip_history_count{0};
    monitors::AdvanceEfficiency<> efficiency{};
    monitors::SelfLockMonitor self_lock{};
    monitors::ContactForceMonitor contact_force{};        ///< on the published largest force
    monitors::ContactForceMonitor model_contact_force{};  ///< on the reduced model's
    TipObserver::State tip_observer{};
    ModelEvidence::State model_evidence{};
    SlackRegressor::State slack{};
    EvidenceAlarm::State loop_alarm{};
    TipOdometer::State tip_odometer{};
    SlackExcess::State slack_excess{};
};

void init(const Config& config, State& state) noexcept;
void step(const Inputs& inputs, State& state, Outputs& outputs) noexcept;

}  // namespace scopekin::kinetics
