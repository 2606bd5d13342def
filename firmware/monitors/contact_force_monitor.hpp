// contact_force_monitor.hpp — perforation-risk alarm on the estimated maximum contact force.
//
//   ContactForceMonitor monitor;
//   monitor.init(config);                         // once at start-up; false = config rejected
//   ContactForceMonitor::Outputs out = monitor.step(max_contact_force_N);   // every period
//
// Thesis 6.3 (ii): warn "when the contact pressure on any particular section of colon tissue
// approaches the threshold of colon tissue perforation".  The kinetics estimates a force per
// contact station, not a pressure, so the monitor compares the largest estimated contact force
// of the step with two thresholds.
//
// Levels and hysteresis
// ---------------------
// Two independent two-state detectors, warning and critical, with the same rules:
//   * raise when force >= threshold on `persistence_steps` consecutive steps (1 = at once);
//   * clear when force <  clear_fraction * threshold (one step suffices: the band between the
//     clear level and the threshold is the debounce).
// level() = critical if the critical detector is active, else warning if the warning detector
// is active, else normal.  With warning_N <= critical_N (enforced) and the same persistence and
// fraction, an active critical detector implies an active warning detector.
//
// Default thresholds and their source
// -----------------------------------
// Johnson S, Schultz M, Scholze M, Smith T, Woodfield J, Hammer N (2019) "How much force is
// required to perforate a colon during colonoscopy? An experimental study", J Mech Behav Biomed
// Mater 91:139-148.  Porcine colon samples were loaded until they perforated by 3D-printed copies
// of two commercial colonoscope heads in three shapes: straight (I), 90° bent (L) and fully
// bent (U).  The straight tip of the larger head under angled loading perforated at 14.1 N
// (the L shape at 46.5 N).  That is the lowest mean they report for a realistic tip shape.
//   * critical_N = 14 N: the straight-tip perforation force, rounded down.
//   * warning_N = 10 N (~70 % of 14.1 N): leaves ~4 N for the estimator's error and for tissue
//     weaker than healthy porcine colon (the study itself says disease may lower the force).
//     It is also a force the physician seldom reaches at the handle: Appleyard MN et al. (2000)
//     "The measurement of forces exerted during colonoscopy", Gastrointest Endosc 52(2):237-240,
//     found a peak push of 4.4 kg (~43 N), but more than 1 kg (~9.8 N) only 5 % of the time.
//     So a 10 N warning is rare in a normal procedure and still comes well before 14 N.
//   * clear_fraction = 0.9: the warning clears below 9 N and the critical level below 12.6 N.
//     0.9 keeps the display from flickering when the estimate is noisy near a threshold.
//   * persistence_steps = 1: a perforation-level force is reported on the first step.  Set
//     2..kMaxPersistenceSteps to ignore single-step spikes of the estimate (delay: steps - 1
//     periods).
// These are ex-vivo porcine numbers for one kind of tip loading, not a clinical safety limit.
// For scale, the reference model's peak contact force is 9.45 N in the bundled default insertion
// and 9.8 N in the self-locking bend (summary.json).  Both stay just below the warning.
//
// Validation of inputs (a defined state for absurd values)
// --------------------------------------------------------
// A force estimate that is negative, saturated (raw INT32_MIN/INT32_MAX) or above
// max_valid_force_N (default 1000 N, 70x the critical level, far above anything a hand can
// produce at the tip) is treated as a fault.  step() then sets Outputs::input_fault and holds
// both detectors and their persistence counters exactly as they were.  A fault step neither
// raises nor clears a level and does not count towards persistence.  The caller must treat
// `input_fault` as "level is stale": the kinetics also reports its own saturation fault.
// init() with an invalid config returns false, sets config_fault() and runs with the default
// Config.  A config is invalid unless 0 < warning_N <= critical_N < max_valid_force_N,
// 0 < clear_fraction <= 1 and 1 <= persistence_steps <= kMaxPersistenceSteps.
//
// Scaling and overflow
// --------------------
// Inputs and thresholds are Q16.16 newtons (range ±32768 N, resolution 15 µN).  The only
// arithmetic is at init: clear level = mul_sat(threshold, clear_fraction).  That is an exact
// 64-bit product, rounded once to nearest (ties away from zero).  With threshold < 1000 N and
// fraction <= 1 it is below 1000 N, so it cannot saturate.
// Example: 14 N * from_ratio(9, 10) = 917504 * 58982 / 2^16 = 825748 raw = 12.59979 N (the
// fraction 0.9 itself is rounded to 58982 / 65536).  step() only compares raw int32 values
// and counts in uint16 capped at persistence_steps.  There is no overflow, no division and no
// floating point, so the results are bit-identical on every target.
//
// Cost: O(1) per step, no loops, no heap.  Storage is sizeof(ContactForceMonitor) (a few words).
#pragma once

#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::monitors {

using fixed_point::Q16_16;

enum class ContactForceLevel : std::uint8_t {
    normal,
    warning,
    critical
};

class ContactForceMonitor {
public:
    /// Upper bound of Config::persistence_steps (1 s at 5 ms).
    static constexpr std::uint16_t kMaxPersistenceSteps = 200;

    struct Config {
        Q16_16 warning_N = Q16_16::from_int(10);            ///< see "Default thresholds"
        Q16_16 critical_N = Q16_16::from_int(14);           ///< Johnson et al. 2019: 14.1 N
        Q16_16 clear_fraction = Q16_16::from_ratio(9, 10);  ///< clear below 90 % of a threshold
        std::uint16_t persistence_steps = 1;                ///< consecutive steps >= threshold
        Q16_16 max_valid_force_N = Q16_16::from_int(1000);  ///< above: input fault
    };

    struct Outputs {
        ContactForceLevel level{ContactForceLevel::normal};
        bool input_fault{false};  ///< this step's input was absurd; level held from last step
    };

    /// Ready to use with the default Config (as after init(Config{})).
    ContactForceMonitor() noexcept { configure(Config{}); }

    /// Validates and stores `config`, clears both detectors.  Invalid config: returns false,
    /// sets config_fault() and uses Config{}.
    bool init(const Config& config) noexcept;

    /// One period.  `max_contact_force_N`: the largest estimated contact force of the step (>= 0).
    Outputs step(Q16_16 max_contact_force_N) noexcept;

    [[nodiscard]] const Config& config() const noexcept { return config_; }
    [[nodiscard]] bool config_fault() const noexcept { return config_fault_; }
    [[nodiscard]] ContactForceLevel level() const noexcept;
    /// The levels at which the detectors clear (clear_fraction * threshold, rounded).
    [[nodiscard]] Q16_16 warning_clear_N() const noexcept { return warning_.clear; }
    [[nodiscard]] Q16_16 critical_clear_N() const noexcept { return critical_.clear; }

    [[nodiscard]] static bool valid(const Config& config) noexcept;

private:
    /// One threshold with hysteresis and persistence.
    struct Detector {
        Q16_16 raise{};
        Q16_16 clear{};
        std::uint16_t count{0};  ///< consecutive steps at or above `raise` (capped)
        bool active{false};
        void update(Q16_16 force, std::uint16_t persistence_steps) noexcept;
    };

    void configure(const Config& config) noexcept;

    Config config_{};
    Detector warning_{};
    Detector critical_{};
    bool config_fault_{false};
};

}  // namespace scopekin::monitors
