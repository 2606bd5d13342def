#pragma once
// Ground truth in the firmware's own terms: the definitions the firmware accuracy tests, the
// `truth.csv` of `scopekin simulate` and a scorecard share. Pure functions over a sampled run
// (no world): time, insertion depth, the tip's place along the colon, the largest station force.
// model/truth/README.md states every definition, its constants and units; the constants are
// here, in one place.
//
// Inputs are checked: series of different lengths, non-finite values, time that does not
// increase, or a bad threshold throw ModelError naming the series and the sample.
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "model/colon/colon_region.hpp"

namespace scopekin::model::truth {

// --- Loop episodes (model/truth/README.md, "Loop episodes") -------------------------------------
/// The tip keeps pace at a sample when, over the trailing kPaceWindow_s, the hand advanced at
/// least kPaceMinHandle_mm and the tip at least kPaceFraction of that.
inline constexpr double kPaceWindow_s = 0.5;
inline constexpr double kPaceFraction = 0.5;
inline constexpr double kPaceMinHandle_mm = 1.0;
/// A loop episode starts when the excess (scope taken up in the colon since the tip last kept
/// pace) reaches kLoopOnsetExcess_mm: more than a scope can take up by bowing inside the lumen
/// (about 10 mm over a 200 mm stretch) and 2.5x what the stick-slip stall of a normal advance
/// takes up (0.2 s at 40 mm/s: 8 mm).
inline constexpr double kLoopOnsetExcess_mm = 20.0;
/// It ends when the excess is given back down to kLoopEndExcess_mm, or when the tip has kept
/// pace for kLoopEndPace_s without a break.
inline constexpr double kLoopEndExcess_mm = 5.0;
inline constexpr double kLoopEndPace_s = 1.0;

// --- Advance efficiency -------------------------------------------------------------------------
/// Tip advance / handle advance over the trailing kEfficiencyWindow_s; undefined (NaN) while the
/// hand advanced less than kEfficiencyMinHandle_mm over that window.
inline constexpr double kEfficiencyWindow_s = 0.5;
inline constexpr double kEfficiencyMinHandle_mm = 1.0;

// --- Force episodes -----------------------------------------------------------------------------
/// On the largest station force: an episode starts at the first sample >= the threshold and
/// ends at the first sample below kForceClearFraction x the threshold.
inline constexpr double kForceWarning_N = 10.0;
inline constexpr double kForceCritical_N = 14.0;
inline constexpr double kForceClearFraction = 0.9;
/// An episode that starts less than kForceMergeGap_s after the previous one ended continues it
/// (a force that dips below the clear level for a moment is one episode, not several).
inline constexpr double kForceMergeGap_s = 0.5;

/// A sampled run: one entry per sample, time strictly increasing.
struct RunSeries {
    std::vector<double> time_s;
    std::vector<double> insertion_mm;  ///< scope past the anus
    std::vector<double> tip_path_mm;   ///< the tip's place along the colon (colon coordinate)
    /// Throws ModelError unless the three series have the same length, are finite, and time
    /// strictly increases. `what` names the run in the message.
    void validate(const std::string& what) const;
};

struct LoopEpisode {
    std::size_t onset = 0;  ///< sample index where the excess began to grow
    double onset_s = 0;
    std::size_t detected = 0;  ///< sample index where the excess reached kLoopOnsetExcess_mm
    double detected_s = 0;
    std::optional<std::size_t> end;  ///< first sample after the episode; none: up at the end
    std::optional<double> end_s;
    std::size_t peak = 0;  ///< sample of the largest excess
    double peak_excess_mm = 0;
    std::string end_reason;  ///< "given_back", "tip_keeps_pace" or "" (still up at the end)
};

struct LoopAnalysis {
    std::vector<double> excess_mm;  ///< per sample
    std::vector<int> episode;       ///< per sample: 1-based episode number, 0 outside
    std::vector<bool> keeps_pace;   ///< per sample
    std::vector<LoopEpisode> episodes;
};

/// The loop episodes of a run (model/truth/README.md, "Loop episodes").
LoopAnalysis loop_episodes(const RunSeries& run);

/// The first loop episode's onset [s], if any: the reference onset the self-lock alarm is
/// judged against.
std::optional<double> loop_onset_s(const RunSeries& run);

/// Tip advance / handle advance over the trailing kEfficiencyWindow_s (from the run's start while
/// the run is younger), per sample; NaN while the hand advanced less than kEfficiencyMinHandle_mm
/// over it.
std::vector<double> advance_efficiency(const RunSeries& run);

/// A loop's type from its region and whether the inserted scope crosses itself in the frontal
/// view (model/truth/README.md, "Type and region"). Sigmoid: "alpha" if it crosses, else "N";
/// splenic flexure, transverse, hepatic flexure: "gamma" if it crosses, else "transverse";
/// elsewhere "other".
std::string loop_type(ColonRegion region, bool scope_crosses);

/// How far each region's centerline has moved from rest [mm] (the largest over its points), in
/// kColonRegionsInOrder order.
using RegionBow = std::array<double, 8>;
struct LoopShape {
    ColonRegion region = ColonRegion::rectum;
    std::string type;
};
/// A loop episode's region and type: the region whose bow grew most from the onset to the
/// largest excess (where the scope took the colon with it; if none grew, the one that bows most
/// at the largest excess), typed by loop_type with the crossing at the largest excess.
LoopShape classify_loop(const RegionBow& at_onset, const RegionBow& at_peak, bool crosses_at_peak);

struct ForceEpisode {
    std::size_t onset = 0;
    double onset_s = 0;
    std::optional<std::size_t> end;  ///< first sample below the clear level; none: up at the end
    std::optional<double> end_s;
    std::size_t peak = 0;
    double peak_N = 0;
};

/// Episodes of `force_N` >= `threshold_N`, each ending at the first sample below
/// `clear_fraction` x `threshold_N`; one that starts less than `merge_gap_s` after the previous
/// one's end continues it. Throws ModelError for a threshold that is not positive, a
/// fraction outside (0, 1], forces that are negative or not finite, or lengths that differ.
std::vector<ForceEpisode> force_episodes(const std::vector<double>& time_s,
                                         const std::vector<double>& force_N, double threshold_N,
                                         double clear_fraction = kForceClearFraction,
                                         double merge_gap_s = kForceMergeGap_s);

/// Per sample: 0 normal, 1 in a warning episode (>= kForceWarning_N), 2 in a critical one.
std::vector<int> force_levels(const std::vector<double>& time_s,
                              const std::vector<double>& force_N);

}  // namespace scopekin::model::truth
