// slack_regressor.hpp — the scope's slack (insertion depth - tip along the colon) regressed on the
// handle's history by a boosted ensemble of small regression trees, learned on a population of
// virtual patients and physicians.
//
//   SlackRegressor::State state{};   // zero-initialised
//   SlackRegressor::Outputs out = SlackRegressor::step(trees, config, inputs, state);
//
// Why a learned regressor
// -----------------------
// How much scope a loop has taken up, or how much colon has pleated onto the scope, is not a
// function of the handle's present reading: it is the history of pushes and pulls that built it.
// The tip observer (tip_observer.hpp) integrates one physical law of that history (push-gated
// dead reckoning); on the development set its tip error is 76 / 112 mm (median / 90th percentile
// of the cases' RMS). Gradient-boosted regression trees (Friedman, Ann. Statist. 29(5), 2001) on
// fourteen features of the same history, including the observer's own slack, reach 48 / 95 mm on
// patients they were not fitted on (leave-one-patient-out on the 12 development patients,
// host_sim/evaluate/README.md, "The slack regressor"). The trees are small (depth 4), a fixed
// number, and their inputs are physical quantities the box measures in every patient; they were
// fitted on the development set only and never on the validation set.
//
// Features (SlackFeature; all Q16.16, units in the names)
// ---------------------------------------------------------
//   depth_mm, handle_force_N               the validated inputs of this step
//   advanced_mm, withdrawn_mm              hand travel in and out since the start (each <= 30000)
//   below_deepest_mm                       deepest depth so far - depth
//   observer_slack_mm                      depth - the tip observer's tip
//   force_N_ema_{1,5,20,60}s               the handle force, exponentially averaged over 1-60 s
//   speed_mm_per_s_ema_{1,5,20,60}s        the hand's speed (depth change / period), likewise
//
// Fixed point. Each average is kept in 64 bits with 32 fraction bits (Q31.32):
//   acc += (x_raw - (acc >> 16)) * alpha_raw,  alpha = period / tau (Q16.16, in (0, 1])
// |x| < 32768 and alpha_raw <= 65536, so each product is below 2^48 and acc below 2^47: no
// overflow, and a difference of one raw unit still moves the average (no dead band). The speed is
// the depth change over the period (Q16.16 division, saturating; |speed| <= 1000 mm/s after the
// depth's rate limit, kinetics.hpp). A split compares a feature's raw value with a raw threshold
// (left if x_raw <= threshold_raw, the learner's own rule x <= t with t rounded down to the
// grid). The prediction sums base and one leaf per tree in 64 bits and saturates once.
#pragma once

#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::kinetics {

using fixed_point::Q16_16;

enum SlackFeature : std::size_t {
    kSlackDepth,
    kSlackHandleForce,
    kSlackAdvanced,
    kSlackWithdrawn,
    kSlackBelowDeepest,
    kSlackObserverSlack,
    kSlackForceEma1s,
    kSlackForceEma5s,
    kSlackForceEma20s,
    kSlackForceEma60s,
    kSlackSpeedEma1s,
    kSlackSpeedEma5s,
    kSlackSpeedEma20s,
    kSlackSpeedEma60s,
    kSlackFeatureCount
};

inline constexpr std::size_t kSlackAverages = 4;  ///< time constants per averaged signal
inline constexpr std::size_t kMaxSlackTrees = 512;
inline constexpr std::size_t kMaxSlackTreeDepth = 8;

/// The ensemble: complete binary trees of one depth D, stored one after the other. Tree t's
/// internal nodes are feature[t * (2^D - 1) + i] / threshold_raw[...] in heap order (children of
/// node i: 2i + 1 left, 2i + 2 right); its leaves are leaf_raw[t * 2^D + k], the learning rate
/// already applied. slack = base + sum of one leaf per tree.
struct SlackTrees {
    std::size_t tree_count{0};
    std::size_t depth{0};
    const std::uint8_t* feature{nullptr};
    const std::int32_t* threshold_raw{nullptr};
    const std::int32_t* leaf_raw{nullptr};
    std::int32_t base_raw{0};
    std::int32_t average_tau_s_raw[kSlackAverages]{};  ///< the averages' time constants [s]
    /// Uncertainty (one SD, in the prediction's unit): floor + per_prediction * |prediction| +
    /// per_metre * depth [m] (for the slack: of the published tip, mm).
    std::int32_t sigma_floor_raw{0};
    std::int32_t sigma_per_prediction_raw{0};
    std::int32_t sigma_per_metre_raw{0};
    const char* source{""};  ///< what it was fitted on, for reports

    /// Counts within the capacities, every array present, every feature index < the count,
    /// time constants positive, sigma terms non-negative.
    [[nodiscard]] bool valid() const noexcept;
};

/// The trees fitted on the development set (firmware/kinetics/generated/slack_trees.cpp, written by
/// host_sim/evaluate/fit_slack_regressor.py).
[[nodiscard]] const SlackTrees& default_slack_trees() noexcept;

/// Trees on the same features for the largest station contact force [N] (uncertainty law in N:
/// floor + per_slack * |force| + per_metre * depth), fitted on the development set
/// (firmware/kinetics/generated/contact_force_trees.cpp, fit_slack_regressor.py --target
/// contact_force).
[[nodiscard]] const SlackTrees& default_contact_force_trees() noexcept;

/// The same averages (time constants), so one feature vector serves both ensembles.
[[nodiscard]] bool same_features(const SlackTrees& a, const SlackTrees& b) noexcept;

struct SlackRegressor {
    struct State {
        bool started{false};
        Q16_16 last_depth_mm{};
        Q16_16 deepest_mm{};
        Q16_16 advanced_mm{};
        Q16_16 withdrawn_mm{};
        std::int64_t force_ema_q32[kSlackAverages]{};
        std::int64_t speed_ema_q32[kSlackAverages]{};
    };
    struct Inputs {
        Q16_16 depth_mm{};        ///< validated, rate-limited insertion depth
        Q16_16 handle_force_N{};  ///< validated (the last valid value while stale)
        /// false while the force cell is stale: the force averages are held, not fed the held
        /// reading, so they resume from what the cell last said when it returns.
        bool force_fresh{true};
        Q16_16 observer_slack_mm{};  ///< depth - the tip observer's tip
        Q16_16 period_s{};           ///< (0, 1] s
    };
    struct Outputs {
        Q16_16 slack_mm{};        ///< the regressed depth - tip
        Q16_16 uncertainty_mm{};  ///< one SD of depth - slack as the tip
        Q16_16 features[kSlackFeatureCount]{};
    };
    /// Updates the history and evaluates the trees (which must be valid()).
    [[nodiscard]] static Outputs step(const SlackTrees& trees, const Inputs& inputs,
                                      State& state) noexcept;
    /// The ensemble's prediction for one feature vector (exposed for tests and the fit's check).
    [[nodiscard]] static Q16_16 predict(const SlackTrees& trees,
                                        const Q16_16 (&features)[kSlackFeatureCount]) noexcept;
    /// The trees' uncertainty law at this prediction and depth (one SD, the prediction's unit).
    [[nodiscard]] static Q16_16 uncertainty(const SlackTrees& trees, Q16_16 prediction,
                                            Q16_16 depth_mm) noexcept;
};

}  // namespace scopekin::kinetics
