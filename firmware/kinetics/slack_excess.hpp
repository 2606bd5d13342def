// slack_excess.hpp — the scope taken up since the tip last kept pace with the hand, measured from
// the bench's EM tracker's tip odometry (tip_odometer.hpp) instead of estimated from the handle.
// An optional input like the tracker itself: without it the output is not valid and nothing
// reads it.
//
//   SlackExcess::Config config{};  // the truth's pace rule and the loop alarm's gate
//   SlackExcess::State state{};    // zero-initialised: starts at the first fresh pose
//   SlackExcess::Outputs out = SlackExcess::step(config, inputs, state);  // every period
//
// Why
// ---
// A loop is scope taken up in the colon instead of advancing the tip. The truth dates a loop
// episode by that (model/truth/README.md, "Loop episodes"): with L = depth - tip along the colon,
// the tip keeps pace at a sample when over the trailing 0.5 s the hand advanced >= 1 mm and the
// tip >= half of that; the excess is L less the smallest L since one pace window before the last
// sample that kept pace. The handle alone cannot see the tip stop; the tracker's odometry can.
// This is the same rule on the odometer's travel (its own sum of advances, without the handle's
// pulls), evaluated at each fresh tip pose and held between poses.
// The loop alarm from evidence (evidence_alarm.hpp) uses it as a gate: with the tracker, a
// period's loop score counts only when at least gate_mm have been taken up, and then a lower
// raise level applies (kinetics.hpp, Config::loop_alarm_with_tracker). Chosen on the development
// set with the alarm's trees held out (host_sim/evaluate/tune_loop_gate.py): 6 mm and 0.625.
//
// Bounded. The ring holds the poses of the last window_steps periods: at most one pose per
// period, so window_steps + 1 <= kCapacity entries (Config::valid). On a pose that keeps pace
// the base is the least L in the ring (<= kCapacity subtractions, at the tracker's ~30 Hz).
//
// Fixed point (Q16.16, mm). Insertion and travel are within a few metres (the tracker's
// positions within +-1000 mm, the depth within the scope's length); L = insertion - travel and
// the differences are saturating subtractions, far from the limit. pace_fraction * hand advance
// is one saturating multiply.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::kinetics {

using fixed_point::Q16_16;

struct SlackExcess {
    static constexpr std::size_t kCapacity = 128;  ///< poses within one pace window

    struct Config {
        std::uint16_t window_steps = 100;                 ///< the pace window: 0.5 s at 200 Hz
        Q16_16 min_hand_mm = Q16_16::from_int(1);         ///< the hand's least advance over it
        Q16_16 pace_fraction = Q16_16::from_ratio(1, 2);  ///< the tip's share that keeps pace
        Q16_16 gate_mm = Q16_16::from_int(6);             ///< the loop alarm counts from here
        /// window_steps in [1, kCapacity - 1]; min_hand_mm > 0; pace_fraction in (0, 1];
        /// gate_mm >= 0.
        [[nodiscard]] bool valid() const noexcept;
    };
    struct Sample {
        std::uint32_t step{0};
        Q16_16 insertion_mm{};
        Q16_16 travel_mm{};
    };
    struct State {
        std::array<Sample, kCapacity> ring{};
        std::size_t oldest{0};
        std::size_t count{0};
        bool started{false};
        Q16_16 base_mm{};    ///< the least L since one window before the last pace
        Q16_16 excess_mm{};  ///< held between poses
    };
    struct Inputs {
        bool active{false};  ///< the tracker's odometry runs (TipOdometer::Outputs::active)
        bool fresh{false};   ///< a fresh pose moved it this period
        std::uint32_t step{0};
        Q16_16 insertion_mm{};  ///< the depth this period
        Q16_16 travel_mm{};     ///< the odometer's travel (TipOdometer::Outputs::travel_mm)
    };
    struct Outputs {
        bool valid{false};  ///< the tracker's odometry runs and has had a pose
        Q16_16 excess_mm{};
        bool gate_open{false};  ///< valid and excess_mm >= gate_mm
    };

    [[nodiscard]] static Outputs step(const Config& config, const Inputs& inputs,
                                      State& state) noexcept;
};

}  // namespace scopekin::kinetics
