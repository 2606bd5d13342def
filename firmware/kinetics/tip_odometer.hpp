// tip_odometer.hpp — the tip along the colon from the test bench's EM tracker, fused with the
// handle's estimate. An optional input: without tracker samples the published tip is the
// handle's estimate, unchanged.
//
//   TipOdometer::Config config{};  // the defaults below (chosen on the development set)
//   TipOdometer::State state{};    // zero-initialised: starts at the first fresh tip pose
//   TipOdometer::Outputs out = TipOdometer::step(config, inputs, state);  // every period
//
// The physics: odometry along the scope's own axis
// -------------------------------------------------
// The tip sensor (S1) gives the tip's position p and orientation q at ~30 Hz. Its local x axis is
// the scope's axis, pointing the way the tip advances (host_sim/simulator/world_readout.cpp
// builds it that way; the bench's sensor is mounted along the shaft), a = R(q) e_x = (1 - 2(y^2 + z^2), 2(xy + wz), 2(xz - wy)). A tip that
// slides along the lumen moves along its own axis; a tip carried sideways by the colon, or
// jittering across the lumen, moves across it. So the tip's advance along the colon between two
// samples is the displacement projected on the axis, taken midway: dx = (p_k - p_{k-1}) .
// (a_k + a_{k-1}) / 2 (mm; the mid-interval axis, so a tip that turns between samples is not
// measured along one end's axis). Summed, the position noise telescopes (0.5 mm per sample does
// not accumulate while the axis turns slowly).
// What it cannot see alone is a mobile colon carried along the axis with the tip (the sigmoid
// pushed ahead of a stuck tip): the tip moves in space but not along the colon. The bench's
// sensor S4 is sutured on the sigmoid (thesis §5.2.1); while the tip is within sigmoid_reach_mm
// of it, the sigmoid's own displacement is taken off the tip's first (p_k - p_{k-1} - (s_k -
// s_{k-1})): the tip's motion relative to the colon around it. On the development set, with the
// handle's tip held out, the fused tip is 31.7 / 58.0 mm RMS (median / 90th percentile case)
// without that correction (it over-counts wherever the sigmoid is carried) and 22.9 / 37.2 mm
// with it (tune_tip_odometer.py; a reach of 60 mm 24.2 / 42.8, of 150 mm 29.4 / 59.6).
//
// The fusion: a scalar Kalman filter whose measurement is the handle's estimate
// ----------------------------------------------------------------------------
//   predict (each fresh pose):  x += dx;   P += q_mm2_per_mm * |dx|
//   update (every update_steps periods, T = update_steps * period):
//       r = P / R,  R = sigma_handle^2 (the handle estimate's stated SD, floored at 1 mm),
//       K = r / (r + correlation_s / T),   x += K (x_handle - x),   P *= (1 - K)
// The handle estimate's error is correlated over tens of seconds (on a new patient its trees are
// off by much the same for long stretches of a procedure), so each update counts as
// T / correlation_s of an independent measurement: its variance is R * correlation_s / T. Then
// x is kept within the handle tip's bounds (TipObserver::bounded: inside the colon, not beyond
// the depth's allowances), given by the caller. uncertainty_mm = sqrt(P).
// While the model evidence trusts the reduced model (the training patient: its tip is within a
// millimetre there, firmware/README.md "Firmware accuracy"), the filter is set to the handle's
// estimate at every period and publishes it; the odometry continues from it when the trust ends.
// The first fresh pose starts the filter at the handle's estimate and its variance. A tip sensor
// that goes stale (no valid sample within the driver's timeout: TrackerInputs::stale_mask) stops
// the filter; the published tip is the handle's again until a fresh pose restarts it.
// The three numbers (sigmoid_reach_mm 100 mm, correlation_s 30 s, q 0.5 mm^2/mm) were chosen on
// the development set only. x depends on q and correlation_s through their ratio alone; q then
// sets the width of sqrt(P). The correlation time is chosen by host_sim/evaluate/
// tune_tip_odometer.py against the handle's tip held out (trees fitted without the case's
// patient): the development set's own firmware has the trees fitted on those very cases, whose
// tip is twice as good as on a new patient (27.6 against 48.4 mm RMS in the median case), and
// tuned on it (5 s) the filter leaned on the handle too much (validation 31.7 / 74.7 mm, 42 % of
// the periods within 1 SD; with 30 s 25.1 / 47.6 mm and 61 %). firmware/README.md, "The tip
// odometer", has the figures.
//
// Fixed point (Q16.16): positions within +-1000 mm (the serial receiver's limit,
// em_tracker_serial.md), so a displacement component is < 4000 mm (sigmoid-corrected) and the
// unit axis components are <= 1 in magnitude (a valid quaternion, norm within 1e-3), their
// mid-interval mean too: |dx| < 7000 mm, no saturation. The tip-sigmoid distance is a hypot of
// hypots, saturating (never wrapping) far beyond the reach it is compared with. P is kept in mm^2
// and clamped to max_variance_mm2 (<= 30000 by Config::valid: an SD of 173 mm); q * |dx|
// saturates rather than wraps. r = P / R with R >= 1 mm^2 is <= 30000; correlation_s / T < 32767
// by Config::valid; K in [0, 1] (resolution 1.5e-5: with T = 0.1 s and correlation 30 s, K is
// r / (r + 300), >= 5e-5 for r >= 0.015); K * (x_handle - x) with |x_handle - x| < 4100 mm.
#pragma once

#include <array>
#include <cstdint>

#include "fixed_point/q_format.hpp"
#include "kinetics/kinetics_io.hpp"

namespace scopekin::kinetics {

using fixed_point::Q16_16;

struct TipOdometer {
    struct Config {
        bool enabled{true};                                 ///< false: the handle's tip only
        Q16_16 q_mm2_per_mm = Q16_16::from_ratio(1, 2);     ///< variance per mm of odometry
        Q16_16 correlation_s = Q16_16::from_int(30);        ///< the handle error's memory
        std::uint16_t update_steps = 20;                    ///< periods between updates (0.1 s)
        Q16_16 sigmoid_reach_mm = Q16_16::from_int(100);    ///< the tip moves with the sigmoid
        Q16_16 max_variance_mm2 = Q16_16::from_int(30000);  ///< SD at most 173 mm
        /// q >= 0; correlation_s > 0; update_steps in [1, 1000]; sigmoid reach >= 0; max
        /// variance in [1, 30000].
        [[nodiscard]] bool valid(Q16_16 period_s) const noexcept;
    };
    struct State {
        bool running{false};
        std::array<Q16_16, 3> last_position_mm{};
        std::array<Q16_16, 3> last_axis{};
        bool sigmoid_seen{false};  ///< the sigmoid sensor was usable at the last tip sample
        std::array<Q16_16, 3> last_sigmoid_mm{};
        Q16_16 tip_mm{};
        Q16_16 variance_mm2{};
        std::uint16_t steps_since_update{0};
        Q16_16 travel_mm{};  ///< the odometry's own sum of advances (no handle pulls)
    };
    struct Inputs {
        const TrackerInputs* tracker{nullptr};  ///< nullptr: no tracker
        Q16_16 handle_tip_mm{};                 ///< the handle's estimate (published without it)
        Q16_16 handle_sd_mm{};                  ///< its stated SD
        /// The handle's estimate is the trusted reduced model's (model_evidence.hpp): taken as
        /// it is (x = it, P = its SD^2) and the odometer continues from it.
        bool handle_trusted{false};
        Q16_16 tip_min_mm{};  ///< the tip's bounds at this depth
        Q16_16 tip_max_mm{};  ///< (TipObserver::bounded)
        Q16_16 period_s{};
    };
    struct Outputs {
        bool active{false};  ///< the tracker's tip is in use this period
        bool fresh{false};   ///< a fresh pose moved the odometry this period
        Q16_16 tip_mm{};     ///< the fused tip (the handle's when not active)
        Q16_16 uncertainty_mm{};
        Q16_16 travel_mm{};  ///< State::travel_mm (slack_excess.hpp reads it)
    };

    [[nodiscard]] static Outputs step(const Config& config, const Inputs& inputs,
                                      State& state) noexcept;
};

}  // namespace scopekin::kinetics
