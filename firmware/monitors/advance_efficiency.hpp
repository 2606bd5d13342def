// advance_efficiency.hpp — tip advance / handle advance over a sliding window.
//
//   AdvanceEfficiency<> efficiency;                     // capacity kAdvanceWindowCapacity steps
//   efficiency.init(config);                            // once; false = config rejected
//   auto out = efficiency.step({tip_path_mm, handle_insertion_mm});   // every period (5 ms)
//
// What it computes
// ----------------
// Two ring buffers (WindowCapacity + 1 slots each) keep the latest samples of the tip's position
// along the colon centerline (kinetics Outputs::tip_path_mm) and of the handle's insertion depth (the validated
// insertion input).  At step n, with N = window_steps:
//   tip_advance    = tip[n]    - tip[n - N]
//   handle_advance = handle[n] - handle[n - N]
//   efficiency     = tip_advance / handle_advance, clamped to [-2, 2]
// A free scope that follows the hand gives 1.  A tip held in a self-locked bend while the hand
// pushes gives a value falling towards 0.  Negative values come from paradoxical motion (the tip
// moves back while the loop grows).  |e| > 2 is outside physics for a pushed scope and comes from
// estimator noise over a small handle advance.  Such values are clamped (Outputs::clamped).
// The efficiency is "undefined" (Outputs::defined = false) when:
//   * the handle advance over the window is below min_handle_advance_mm (default 2 mm in
//     0.25 s = 8 mm/s): the hand is not pushing (holding, withdrawing, creeping), and the ratio
//     of two small numbers would be noise; or
//   * the window is not full yet (fewer than N + 1 samples since init).
// Then the last defined value is held (1 before the first defined value: "no evidence of lost
// advance").
// `handle_advancing` answers "is the hand pushing *now*?" over a short recent window:
// handle[n] - handle[n - advancing_steps] >= min_advancing_mm (defaults 10 steps = 50 ms and
// 0.4 mm, the same 8 mm/s).  SelfLockMonitor uses it.  Why it must be short is explained in
// self_lock_monitor.hpp.  It is false until advancing_steps + 1 samples have arrived.
// Both windows use only the two end samples.  A window of N steps spans N periods (0.25 s for
// 50 steps at 5 ms).
//
// Latency of the efficiency to a change: for a tip that stops dead at step n0 under a handle at
// constant speed, efficiency = 1 - j/N at n0 + j (j <= N).  It reaches 0.5 at j = N/2 (25 steps,
// 0.125 s) and 0 at j = N.  A shorter window reacts faster but is noisier.
//
// Capacity and configuration
// --------------------------
// The template parameter WindowCapacity (default kAdvanceWindowCapacity = 64 steps = 0.32 s)
// fixes the storage: 2 ring buffers x (WindowCapacity + 1) x 4 bytes (520 bytes by default).
// Config::window_steps (default 50 = 0.25 s) can be anything in [1, WindowCapacity].
// Config::advancing_steps must lie in [1, window_steps].  init() with an invalid config returns
// false, sets config_fault() and uses Config{}; if the default window does not fit a smaller
// capacity, both windows are clamped to the capacity.
//
// Validation of inputs (a defined state for absurd values)
// --------------------------------------------------------
// A position is absurd when it is saturated (raw INT32_MIN/INT32_MAX) or |x| >
// max_abs_position_mm (default 5000 mm; the scope is 1.7 m, the colon 1.6 m).  The absurd sample
// is replaced by that signal's last valid sample (0 before any valid sample), so the window keeps
// its time base.  Outputs::input_fault is set for that step.  Outputs::window_has_substitute
// stays set while a replaced sample is still inside the efficiency window (N + 1 steps).
// Only the two end samples of a window matter.  A single replaced sample therefore shifts the
// efficiency only on the steps where it is a window end, by about one step's advance out of N
// (e.g. 49/50 instead of 1; see the tests).  A held handle reads as "no handle motion", so a
// long handle fault makes the efficiency undefined (held), not wrong.
//
// Scaling and overflow
// --------------------
// Positions are Q16.16 mm (resolution 15 nm), validated to |x| <= max_abs_position_mm (default
// 5000 mm, at most 10000 mm by config), so every advance (a difference of two samples) is
// <= 20000 mm in magnitude: sub_sat is exact there and cannot saturate.  The ratio uses
// fixed_point::div_sat, which returns the correctly rounded quotient (to nearest, ties away from
// zero) and saturates.  The divisor is the handle advance, >= min_handle_advance_mm >= 1 LSB > 0,
// so no division by zero.  With the defaults the quotient is <= 10000 mm / 2 mm = 5000, inside
// Q16.16 (a smaller configured minimum may make div_sat saturate; the clamp to [-2, 2] follows
// either way).
// Error of the result.  The division adds 0.5 LSB.  Each advance is a difference of two rounded
// samples, so it is off by <= 1 LSB (2^-16 mm) from the true advance.  That moves e = T / H by
// <= dT / H + |e| dH / H: with H >= 2 mm and |e| <= 2, at most 0.5 + 1 LSB.  So |e - exact|
// <= 2 LSB (3e-5) at the minimum advance, and less for larger advances (the 0.3 ramp test: 1 LSB).
// Ring indices are uint16_t modulo (WindowCapacity + 1).  No floating point, so results are
// bit-identical on every target.
//
// Cost: O(1) per step: two buffer writes, four reads, one division.  No loops, no heap.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::monitors {

using fixed_point::Q16_16;

/// Default compile-time capacity of the efficiency window: 64 steps = 0.32 s at 5 ms.
inline constexpr std::size_t kAdvanceWindowCapacity = 64;

template <std::size_t WindowCapacity = kAdvanceWindowCapacity>
class AdvanceEfficiency {
    static_assert(WindowCapacity >= 1 && WindowCapacity < 65535,
                  "window steps and ring indices are uint16_t");

public:
    static constexpr std::size_t capacity = WindowCapacity;

    struct Config {
        std::uint16_t window_steps = 50;     ///< N: 0.25 s at 5 ms; 1..WindowCapacity
        std::uint16_t advancing_steps = 10;  ///< short window of handle_advancing: 50 ms
        Q16_16 min_handle_advance_mm = Q16_16::from_int(2);   ///< over the window; below: undefined
        Q16_16 min_advancing_mm = Q16_16::from_ratio(2, 5);   ///< 0.4 mm over advancing_steps
        Q16_16 max_abs_position_mm = Q16_16::from_int(5000);  ///< beyond: absurd input
    };

    struct Inputs {
        Q16_16 tip_path_mm{};          ///< tip position along the colon centerline
        Q16_16 handle_insertion_mm{};  ///< insertion depth at the handle
    };

    struct Outputs {
        Q16_16 efficiency{Q16_16::from_int(1)};  ///< in [-2, 2]; held when !defined
        bool defined{false};                     ///< efficiency computed this step
        bool clamped{false};                     ///< the ratio was outside [-2, 2]
        Q16_16 tip_advance_mm{};                 ///< over the window (0 while it fills)
        Q16_16 handle_advance_mm{};              ///< over the window (0 while it fills)
        Q16_16 handle_recent_advance_mm{};       ///< over advancing_steps (0 while it fills)
        bool handle_advancing{false};            ///< recent advance >= min_advancing_mm
        bool input_fault{false};                 ///< an input was absurd this step (replaced)
        bool window_has_substitute{false};       ///< a replaced sample is inside the window
    };

    AdvanceEfficiency() noexcept = default;

    /// Validates and stores `config` and empties the window.  Invalid: returns false, sets
    /// config_fault() and uses Config{} (windows clamped to the capacity).
    bool init(const Config& config) noexcept {
        const bool ok = valid(config);
        config_ = ok ? config : clamped_default();
        config_fault_ = !ok;
        reset();
        return ok;
    }

    Outputs step(const Inputs& inputs) noexcept {
        Outputs out{};
        bool fault = false;
        Q16_16 tip = inputs.tip_path_mm;
        Q16_16 handle = inputs.handle_insertion_mm;
        if (!valid_position(tip)) {
            tip = last_tip_;
            fault = true;
        }
        if (!valid_position(handle)) {
            handle = last_handle_;
            fault = true;
        }
        last_tip_ = tip;
        last_handle_ = handle;

        head_ = static_cast<std::uint16_t>(head_ + 1U == kSlots ? 0U : head_ + 1U);
        tip_[head_] = tip;
        handle_[head_] = handle;
        if (count_ < kSlots) {
            ++count_;
        }
        if (fault) {
            steps_since_substitute_ = 0U;
        } else if (steps_since_substitute_ < kSlots) {
            ++steps_since_substitute_;
        }
        out.input_fault = fault;
        out.window_has_substitute = steps_since_substitute_ <= config_.window_steps;

        if (count_ > config_.advancing_steps) {
            out.handle_recent_advance_mm =
                sub_sat(handle, handle_[lagged(config_.advancing_steps)]);
            out.handle_advancing = out.handle_recent_advance_mm >= config_.min_advancing_mm;
        }
        if (count_ > config_.window_steps) {
            const std::uint16_t oldest = lagged(config_.window_steps);
            out.tip_advance_mm = sub_sat(tip, tip_[oldest]);
            out.handle_advance_mm = sub_sat(handle, handle_[oldest]);
            if (out.handle_advance_mm >= config_.min_handle_advance_mm) {
                Q16_16 ratio = fixed_point::div_sat(out.tip_advance_mm, out.handle_advance_mm);
                if (ratio > kMaxEfficiency) {
                    ratio = kMaxEfficiency;
                    out.clamped = true;
                } else if (ratio < kMinEfficiency) {
                    ratio = kMinEfficiency;
                    out.clamped = true;
                }
                efficiency_ = ratio;
                out.defined = true;
            }
        }
        out.efficiency = efficiency_;
        return out;
    }

    [[nodiscard]] const Config& config() const noexcept { return config_; }
    [[nodiscard]] bool config_fault() const noexcept { return config_fault_; }
    /// The current (or held) efficiency.
    [[nodiscard]] Q16_16 efficiency() const noexcept { return efficiency_; }

    /// true if 1 <= advancing_steps <= window_steps <= WindowCapacity, 1 LSB <=
    /// min_advancing_mm, min_handle_advance_mm and 0 < max_abs_position_mm <= 10000 mm.
    [[nodiscard]] static constexpr bool valid(const Config& config) noexcept {
        const Q16_16 lsb = Q16_16::from_raw(1);
        return config.window_steps >= 1U && config.window_steps <= WindowCapacity &&
               config.advancing_steps >= 1U && config.advancing_steps <= config.window_steps &&
               config.min_handle_advance_mm >= lsb && config.min_advancing_mm >= lsb &&
               config.max_abs_position_mm > Q16_16{} &&
               config.max_abs_position_mm <= Q16_16::from_int(10000);
    }

private:
    static constexpr std::uint16_t kSlots = static_cast<std::uint16_t>(WindowCapacity + 1U);
    static constexpr Q16_16 kMaxEfficiency = Q16_16::from_int(2);
    static constexpr Q16_16 kMinEfficiency = Q16_16::from_int(-2);

    /// Config{} with both windows clamped to the capacity.
    [[nodiscard]] static constexpr Config clamped_default() noexcept {
        Config c{};
        if (c.window_steps > WindowCapacity) {
            c.window_steps = static_cast<std::uint16_t>(WindowCapacity);
        }
        if (c.advancing_steps > c.window_steps) {
            c.advancing_steps = c.window_steps;
        }
        return c;
    }

    [[nodiscard]] bool valid_position(Q16_16 x) const noexcept {
        return x != Q16_16::max() && x != Q16_16::min() && x <= config_.max_abs_position_mm &&
               x >= neg_sat(config_.max_abs_position_mm);
    }

    /// Slot of the sample `lag` steps before the newest (lag <= WindowCapacity).
    [[nodiscard]] std::uint16_t lagged(std::uint16_t lag) const noexcept {
        return static_cast<std::uint16_t>(head_ >= lag ? head_ - lag : head_ + kSlots - lag);
    }

    void reset() noexcept {
        tip_ = {};
        handle_ = {};
        head_ = 0U;
        count_ = 0U;
        steps_since_substitute_ = kSlots;
        last_tip_ = Q16_16{};
        last_handle_ = Q16_16{};
        efficiency_ = Q16_16::from_int(1);
    }

    Config config_{clamped_default()};
    std::array<Q16_16, kSlots> tip_{};
    std::array<Q16_16, kSlots> handle_{};
    std::uint16_t head_{0};   ///< slot of the newest sample
    std::uint16_t count_{0};  ///< samples stored (capped at kSlots)
    std::uint16_t steps_since_substitute_{kSlots};
    Q16_16 last_tip_{};
    Q16_16 last_handle_{};
    Q16_16 efficiency_{Q16_16::from_int(1)};
    bool config_fault_{false};
};

}  // namespace scopekin::monitors
