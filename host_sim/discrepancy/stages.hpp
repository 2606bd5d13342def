#pragma once
// The stages of the discrepancy workflow (host_sim/discrepancy/README.md, steps 2 and 4), each a
// function in its own file, in the order workflow.cpp calls them. Each works from the context
// (context.hpp); what one finds, the next takes, and the report reads (Findings).
//   stage_significance.cpp  is any output's held-out error beyond its noise? If not: verdict none
//   stage_screening.cpp     per candidate: a coarse grid over its range, and one Gauss-Newton
//                           step from a shared Jacobian; the better is its start
//   stage_refinement.cpp    Levenberg-Marquardt on the best (and on a runner-up that comes close),
//                           then derivative-free searches (line, box) and nested restarts
//   stage_valley_walk.cpp   two-parameter candidates: the training cost's valley walked
//   stage_pairs.cpp         pairs or not (the score test), then the two best pairs side by side
//   stage_verdict.cpp       named or unexplained; the named effects' uncertainty (and, fitted on
//                           windows, their run over the whole recording)
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/context.hpp"
#include "host_sim/discrepancy/fit.hpp"
#include "host_sim/discrepancy/report.hpp"

namespace scopekin::discrepancy {

/// Candidates refined after screening (the rest keep their one-step fit).
inline constexpr std::size_t kRefined = 2;
/// The progress bar's steps: the model as given, screening, the refinements, pairs, verdict, report.
inline constexpr double kProgressSteps = static_cast<double>(kRefined + 5);

struct Significance {
    nlohmann::ordered_json outputs =
        nlohmann::ordered_json::object();  ///< per output (report.json "significance")
    std::size_t most_affected =
        0;             ///< the assessed output with the largest held-out RMS error over its noise
    bool any = false;  ///< an output's ratio exceeds the options' significance
};

struct Verdict {
    std::string verdict = "none";         ///< none, named, unexplained (or disagrees: compare only)
    std::optional<std::size_t> named;     ///< index into the candidates of the effects named
    nlohmann::ordered_json confirmation;  ///< fitted on windows: the named effects' full run
    /// The other candidates that explain the held-out data as well (equally_consistent).
    std::vector<std::size_t> equally_consistent;
};

/// What the screening found: one fit per candidate, and how it got there.
struct Screening {
    std::vector<EffectSetFit> fits;  ///< library order, no SDs
    nlohmann::ordered_json report;   ///< report.json "screening": the starts tried, the profiles
};

/// What the stages found.
struct Findings {
    Significance significance;
    nlohmann::ordered_json screening;      ///< the screening's starts and profiles
    std::vector<EffectSetFit> candidates;  ///< every fit, best first (held-out cost)
    nlohmann::ordered_json pair_test;      ///< the score test before pairs (when it ran)
    Verdict verdict;
};

/// Significance: each output's held-out RMS error against its noise.
Significance assess_significance(const DiscrepancyContext& context);

/// Screening: every candidate of the library gets one Gauss-Newton step from its neutral values,
/// with the Jacobian of all their parameters computed at the model as given (one run per
/// parameter, in parallel), and one run at the step; and, beside it, a coarse grid over its
/// parameters' ranges (screen_grid, training data only). The lower training cost of the step and
/// the grid's best point is the candidate's screened fit (the refinement's start).
Screening screen_candidates(const DiscrepancyContext& context);

/// Refinement: the best screened candidate refined by Levenberg-Marquardt, a one-parameter one
/// then searched between its grid neighbours and around its screening profile's other dips; the
/// runner-up too when the best explains too little, or (not on windows) when its screening
/// explained a quarter of the excess; a nested candidate that fits worse than the one it contains
/// refitted from it; a two-parameter one searched on a grid in the box of its parameters' second
/// neighbours; a contained candidate that fits worse than the richer one refitted from the
/// richer's values. Returns every fit, ranked (by_held_out, prefer_simpler).
std::vector<EffectSetFit> refine_candidates(const DiscrepancyContext& context,
                                            const std::vector<EffectSetFit>& screened,
                                            StageLog& stages);

/// The parameters of a working fit (one candidate or a pair) that has two in all, both with
/// screening axes: what the box search and the valley walk work on. Empty otherwise.
std::vector<FittedParameter> two_screened_parameters(const EffectSetFit& fit);

/// Whether a fit with `training_cost` still leaves kMinRestCost (ranking.hpp) or more above
/// `training_noise_floor` (what noise alone gives): one that leaves less cannot be told from the
/// truth by this recording, so the box search skips it and the valley walk does not narrow its
/// floor down (its steps still give the SD the valley's width). Measured on the robustness sweep:
/// all 7 walks (of 22) that started there ended where they began.
bool leaves_training_excess(double training_cost, double training_noise_floor);

/// Whether a single fit with `training_cost` leaves any excess over `training_noise_floor` for a
/// partner to remove: a partner's screened gain is a share of that excess, so with none left
/// (or a NaN cost) every gain is 0 and the partner screen is not run. Measured on the
/// `ei_profile` check: walked to 4.90 against a floor of 5.0, its 120 screen runs all gained 0.
bool leaves_excess_for_a_partner(double training_cost, double training_noise_floor);

/// Two-parameter fits (two_screened_parameters; not on windows, the 10-minute recording's budget,
/// nor at the noise floor, leaves_training_excess) after Levenberg-Marquardt: a derivative-free
/// search on a 5 x 5 grid inside the box of each parameter's second neighbours on its screening
/// axis, two rounds, each around the best so far, then Levenberg-Marquardt from the best point;
/// kept where it fits the training blocks better.
/// Why: a training cost that steps with event timing stops the finite-difference iteration short
/// (stage_refinement.cpp has the case).
void refine_in_box(const DiscrepancyContext& context, EffectSetFit& fit, StageLog& stages);

/// Two-parameter fits (two_screened_parameters: a candidate, or a pair) not on windows: the valley
/// of the training cost walked from the fit. The parameter the cost changes least along is stepped
/// by its finite-difference step (6 steps each way at most, stopping after 2 that rise), the other
/// searched across the valley at each (2 rounds of 7 runs within ± 0.4 of its step about the
/// floor the valley's slope predicts); the lowest floor point, unless at the noise floor
/// (leaves_training_excess), is narrowed down at half and a quarter of the step either side, then
/// Levenberg-Marquardt from there; kept where it fits better.
/// Why: a hidden distal softening (ei_profile tip 0.6, handle 1.0) on procedure B leaves a
/// valley about 0.02 wide in the tip factor whose floor falls smoothly from ei_scale's (0.645,
/// 0.645) at 7.5 to 4.6 at the truth, while a tip factor 0.01 low lets a stick-and-release go at
/// another time (19 to 20): finite differences of 0.1 and the box's grid both cross it, and
/// the fit stayed at the uniform (0.645, 0.645). And a pair (try_pairs walks each fitted pair):
/// hidden viscous friction 0.006 s/mm with tissue stiffening 0.3 /N on procedure C, fitted from
/// the partner screen's grid point (0.00594 s/mm, 0.15 /N), made no step (training cost 119,
/// held-out 179 against a noise floor of 5; the box's 5 x 5 grid, 0.0023 s/mm apart, missed the
/// valley), and stiffening was named at half its value. The floor is in report.json's candidates
/// ("valley_walk").
void walk_valley(const DiscrepancyContext& context, EffectSetFit& fit, StageLog& stages);

/// A partner of the best single effect screened on what the single leaves: the single held at
/// its refined values, the partner over its screening grid (sigmoid_mobility at its screened
/// values), training runs only; then each partner point run again with the single re-adjusted by
/// its least-squares step on a secant Jacobian about its refined values (two effects can trade off
/// along a narrow valley the single alone sits beside). The lowest cost per partner, best first.
struct PartnerScreen {
    std::size_t screened = 0;    ///< index of the partner's fit in the screened list
    std::vector<double> values;  ///< the partner's values at its lowest cost
    double training_cost = 0;    ///< the pair's there (a run's)
    /// The single's values there: its refined ones, or re-adjusted (`readjusted`).
    std::vector<double> single_values;
    bool readjusted = false;
    std::size_t single = 0;      ///< the single's candidate (index into the library)
    nlohmann::json single_held;  ///< and its held parameters
};
std::vector<PartnerScreen> screen_partners(const DiscrepancyContext& context,
                                           const EffectSetFit& single,
                                           const std::vector<EffectSetFit>& screened);

struct PairsOutcome {
    std::optional<std::size_t> chosen;  ///< index into the candidates of the set to name, if any
    nlohmann::ordered_json pair_test;   ///< the score test and the partner screen (when they ran)
};
/// Pairs: names the best single effect when it explains enough and leaves nothing significant.
/// When it explains enough and leaves an output significant, screens the partners on its residual
/// (screen_partners; on the runner-up single's too when it explains at least half as much) and
/// fits the two best single-and-partner points when the best removes enough (else,
/// when the score test predicts enough, the pairs below); when it explains too little but
/// something, fits the two pairs best by their linearised joint step side by side. Names the best
/// pair when it does better. Adds the pairs to `candidates` (ahead of the singles when chosen).
PairsOutcome try_pairs(const DiscrepancyContext& context, const std::vector<EffectSetFit>& screened,
                       std::vector<EffectSetFit>& candidates, StageLog& stages);

/// Verdict: `chosen` is named, with its parameters' uncertainty; fitted on windows, only if its
/// run over the whole recording explains min_share too (its prediction is then that run's).
Verdict give_verdict(const DiscrepancyContext& context, std::optional<std::size_t> chosen,
                     std::vector<EffectSetFit>& candidates, StageLog& stages);

}  // namespace scopekin::discrepancy
