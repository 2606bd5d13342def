// self_lock_monitor.hpp — self-locking / loop-onset alarm (thesis 2.2.1 and 6.3 (i)).
//
//   SelfLockMonitor monitor;
//   monitor.init(config);                               // once; false = config rejected
//   SelfLockMonitor::Outputs out = monitor.step(in);    // every period (5 ms)
//
// Physics (model/PHYSICS.md §1, thesis 2.2.1, Eq. 2.1-2.4)
// --------------------------------------------------------
// Looping starts with self-locking: a contact near the distal end goes into *stick*.  Its
// driving-force angle alpha, tan(alpha) = ||[f_t f_s]|| / |f_n|, is then below the friction
// angle beta = atan(mu_s).  Pushing at the handle stops advancing the tip and starts to stretch
// the loop.  The thesis's alarm (6.3 (i)): "no relative motion between colonoscope and colon" at
// the distal part while the physician pushes.  classify_stick() below tests stick without atan.
// tan is increasing on [0, pi/2), so alpha < beta  <=>  |f_T| < mu f_n  (f_n > 0).  The test adds
// a margin: |f_T| < stick_ratio * mu * f_n, with stick_ratio = 0.95 by default.  A slipping
// contact lies on the cone, |f_T| = mu f_n.  After the fixed-point contact solve it can sit a few
// LSB inside the cone, and the margin keeps such a contact out of "stick".
//
// Decision rule (chosen for latency; the reasoning follows)
// ---------------------------------------------------------
//   condition  C = (distal stations in stick >= min_sticking_stations) AND handle_advancing
//   raise      when C has held on on_steps consecutive steps (default 20 = 0.1 s);
//   clear      when C has been false on off_steps consecutive steps (default 100 = 0.5 s)
//              AND the advance efficiency is *defined* and >= clear_efficiency (default 0.7);
//   confirmed  = alarm AND efficiency defined AND efficiency < confirm_efficiency (default 0.5):
//              the tip's motion now confirms the stick.  Extra information only: not needed to
//              raise, and it does not hold the alarm.
// `handle_advancing` comes from AdvanceEfficiency::Outputs::handle_advancing: handle advance
// over a *short* recent window (default 10 steps = 50 ms) >= 0.4 mm, i.e. >= 8 mm/s, the same
// speed as the efficiency's "hand is pushing" minimum of 2 mm per 0.25 s.
//
// Why the efficiency does not take part in raising: with the default 0.25 s window, a tip that
// stops dead under a handle moving at constant speed gives efficiency 1 - j/50 at j steps after
// onset.  The efficiency falls below 0.5 only at j = 26 (0.13 s, about half a window).  Adding
// T_on makes j = 45 (0.225 s), too close to the 0.25 s the acceptance test allows.  The stick
// state is known at once, so raising on it leaves the efficiency for clearing and confirming.
// The reference model agrees.  In model/scenarios/self_locking_bend.json (50 mm/s, mu = 1.2),
// the tip contact goes into stick at t ~ 2.64 s (alpha ~ 45° < beta = 50.2°).  For the next
// second the tip still moves ~1:1 with the handle in world coordinates, because the compliant
// bend moves with it.  A rule that needs the efficiency to fall would fire late or never.
// Stick AND advancing fires 0.1 s after the stick.
// Why "advancing" uses a short window: with the 0.25 s window, the handle advance stays above
// 2 mm for up to 0.15 s after the hand stops at 20 mm/s.  Every contact sticks during a hold, so
// C would then hold for more than T_on and *every stop would raise the alarm*.  With the 50 ms
// window, C lasts at most 10 steps after the handle stops.  That is half of T_on.
//
// Latency (defaults, 5 ms period)
// -------------------------------
//   * The handle is already pushing (>= 8 mm/s) when a distal contact sticks, the normal way
//     self-locking begins: C holds from the first stick step n0 and the alarm is true at step
//     n0 + 19, 95 ms later (within 0.1 s).
//   * Worst case: the handle starts from rest at the same step as the stick.  `advancing` then
//     needs the recent advance to reach 0.4 mm: at most 9 steps later at 8 mm/s, 3 at 25 mm/s,
//     1 at 50 mm/s.  The alarm comes at most 9 + 19 = 28 steps = 140 ms after the first
//     moving sample.
//   => worst case <= 0.15 s after the stick state appears in the estimate, leaving >= 0.1 s of
//      the 0.25 s acceptance bound for the estimator's own lag behind the reference model.
//   The efficiency confirms (< 0.5) about 26 steps (0.13 s) after a dead stop of the tip.
//   The kinetic estimator (kinetics.hpp, kSelfLockConfig) sets on_steps = 36 instead: in the
//   reference model the tip stalls for up to 31 steps in the stick-slip of a normal advance, so
//   20 would raise the alarm where no loop forms (firmware/README.md, "Alarms"). Its latency is then 0.175 s
//   with the hand pushing, at most 0.22 s from rest.
//
// False alarms kept out
// ---------------------
//   * A normal advance: the distal contacts slip, so C is false and the alarm never fires,
//     whatever the efficiency.
//   * A hold (handle not advancing): `advancing` is false, so C is false and the alarm never
//     fires, although every contact sticks.  At the hold's start, C can last at most the 10
//     steps of the advancing window (< on_steps = 20).
//   * A withdrawal: the handle advance is negative, so not advancing and no alarm.
//   * Starting a push from a hold is the one case to watch.  At rest the distal contacts stick
//     (static friction).  If the tip has not begun to slip T_on after `advancing` turns true,
//     the alarm fires.  That is the thesis's criterion (no distal relative motion while
//     pushing), so it is not a false alarm by definition.  If it proves a nuisance, raise
//     on_steps: each extra step adds one step of latency.
// Clearing needs evidence: a hold or a withdrawal after an alarm keeps the alarm.  While the
// handle does not push, the efficiency is undefined.  The alarm clears only after a push in
// which the distal contacts slip for 0.5 s and the tip follows the handle again (>= 0.7).  So
// the alarm means "the last push showed self-locking, and no push since has shown the tip
// following".
//
// Validation of inputs (a defined state for absurd values)
// --------------------------------------------------------
// step() marks its inputs absurd if distal_sticking > max_distal_stations, or if the efficiency
// is outside [-2, 2] (AdvanceEfficiency clamps to that range).  It then sets
// Outputs::input_fault, holds the alarm, the confirmed flag and both counters, and returns
// the last step's outputs with input_fault set.
// classify_stick() returns StickState::invalid for a negative, saturated or too large
// (> max_valid_force_N) normal or tangential force, and for mu < 0 or mu > max_valid_mu.
// count_sticking() reports such stations in StickCount::invalid and does not count them as
// stick.  The caller passes `invalid` on as a fault (e.g. it skips step() or flags the output).
// init() with an invalid config returns false, sets config_fault() and uses Config{}.
//
// Scaling and overflow
// --------------------
// Forces are Q16.16 N and mu and the ratios are Q16.16 numbers.  The stick test forms
// mu_eff = mul_sat(stick_ratio, mu): one exact 64-bit product, one rounding to nearest.
// With stick_ratio <= 1 and mu <= max_valid_mu (2) it is <= 2, so it cannot saturate.  Then it
// compares exactly in 64 bits: |f_T|_raw * 2^16 < mu_eff_raw * f_n_raw.  The left side is
// < 2^47; the right side is <= 2^17 * 2^31 = 2^48 (mu_eff <= 2).  No overflow and no rounding
// beyond the 0.5 LSB (7.6e-6) of mu_eff, negligible next to the 5 % margin.
// The monitor itself only compares Q16.16 values and counts in uint16 capped at on_steps /
// off_steps.  There is no division and no floating point.
//
// Cost: O(1) per step (count_sticking: one bounded loop over a compile-time number of distal
// stations), no heap, a few words of state.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::monitors {

using fixed_point::Q16_16;

// ---- stick test for one contact ----------------------------------------------------------

struct StickCriterion {
    Q16_16 stick_ratio = Q16_16::from_ratio(95, 100);       ///< stick iff |f_T| < ratio*mu*f_n
    Q16_16 min_normal_force_N = Q16_16::from_ratio(1, 20);  ///< 0.05 N; below: no contact
    Q16_16 max_valid_force_N = Q16_16::from_int(1000);      ///< above: invalid input
    Q16_16 max_valid_mu = Q16_16::from_int(2);              ///< above (or mu < 0): invalid
};

/// true if 0 < stick_ratio <= 1, 0 <= min_normal_force_N < max_valid_force_N < 32767 N,
/// 0 < max_valid_mu <= 2.
[[nodiscard]] bool valid(const StickCriterion& criterion) noexcept;

enum class StickState : std::uint8_t {
    no_contact,
    slipping,
    sticking,
    invalid
};

/// Stick test of one contact (see "Physics").  `tangential_N` = ||[f_t f_s]|| (>= 0).
/// An invalid `criterion` gives StickState::invalid.
[[nodiscard]] StickState classify_stick(Q16_16 normal_N, Q16_16 tangential_N, Q16_16 mu,
                                        const StickCriterion& criterion = {}) noexcept;

struct DistalContact {
    Q16_16 normal_force_N{};
    Q16_16 tangential_force_N{};  ///< ||[f_t f_s]||
    Q16_16 mu{};                  ///< static friction coefficient at this contact
};

struct StickCount {
    std::uint8_t sticking{0};  ///< contacts in stick (valid ones only)
    std::uint8_t invalid{0};   ///< contacts with absurd inputs (not counted as stick)
};

/// Counts the first `active` (<= N) contacts.  The loop bound is the compile-time N.
template <std::size_t N>
[[nodiscard]] StickCount count_sticking(const std::array<DistalContact, N>& contacts,
                                        std::size_t active,
                                        const StickCriterion& criterion = {}) noexcept {
    static_assert(N <= 255, "StickCount counts in uint8_t");
    StickCount count{};
    for (std::size_t i = 0; i < N; ++i) {  // bound: N
        if (i >= active) {
            break;
        }
        const DistalContact& c = contacts[i];
        const StickState state =
            classify_stick(c.normal_force_N, c.tangential_force_N, c.mu, criterion);
        if (state == StickState::sticking) {
            ++count.sticking;
        } else if (state == StickState::invalid) {
            ++count.invalid;
        }
    }
    return count;
}

// ---- the monitor ---------------------------------------------------------------------------

class SelfLockMonitor {
public:
    /// Upper bound of on_steps / off_steps (5 s at 5 ms).
    static constexpr std::uint16_t kMaxHysteresisSteps = 1000;

    struct Config {
        std::uint8_t min_sticking_stations = 1;  ///< distal stations in stick needed for C
        std::uint8_t max_distal_stations = 3;    ///< inputs above this are absurd
        std::uint16_t on_steps = 20;             ///< T_on  = 0.1 s at 5 ms
        std::uint16_t off_steps = 100;           ///< T_off = 0.5 s at 5 ms
        Q16_16 confirm_efficiency = Q16_16::from_ratio(1, 2);  ///< 0.5
        Q16_16 clear_efficiency = Q16_16::from_ratio(7, 10);   ///< 0.7
    };

    struct Inputs {
        std::uint8_t distal_sticking{0};         ///< distal stations in stick this step
        bool handle_advancing{false};            ///< AdvanceEfficiency::Outputs::handle_advancing
        Q16_16 efficiency{Q16_16::from_int(1)};  ///< AdvanceEfficiency (held when undefined)
        bool efficiency_defined{false};
    };

    struct Outputs {
        bool alarm{false};
        bool confirmed{false};             ///< alarm and efficiency (defined) < confirm_efficiency
        bool condition{false};             ///< C this step
        std::uint16_t condition_steps{0};  ///< consecutive steps with C (capped at on_steps)
        bool input_fault{false};           ///< absurd inputs: everything held from last step
    };

    SelfLockMonitor() noexcept = default;

    /// Validates and stores `config`, clears the alarm and the counters.  Invalid config
    /// (see valid()): returns false, sets config_fault() and uses Config{}.
    bool init(const Config& config) noexcept;

    Outputs step(const Inputs& inputs) noexcept;

    [[nodiscard]] const Config& config() const noexcept { return config_; }
    [[nodiscard]] bool config_fault() const noexcept { return config_fault_; }
    [[nodiscard]] bool alarm() const noexcept { return last_.alarm; }

    /// true if 1 <= min_sticking_stations <= max_distal_stations, 1 <= on_steps, off_steps
    /// <= kMaxHysteresisSteps, 0 < confirm_efficiency <= clear_efficiency <= 2.
    [[nodiscard]] static bool valid(const Config& config) noexcept;

private:
    Config config_{};
    Outputs last_{};
    std::uint16_t off_count_{0};  ///< consecutive steps without C while the alarm is raised
    bool config_fault_{false};
};

}  // namespace scopekin::monitors
