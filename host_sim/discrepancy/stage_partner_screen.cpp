// The pairs' global screen (issue 22, "pairs when a single leaves a structured residual"): a
// partner's effect on the model as given (the score test's neutral Jacobian) can differ a lot from
// its effect on top of the refined single, which is where it has to act. So each partner's grid is
// run with the single held at its refined values, and what it removes is measured, not predicted.
#include <algorithm>
#include <cmath>
#include <limits>

#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// Nested effects pair with nothing new: ei_scale on top of ei_profile is ei_profile.
bool nested(std::size_t a, const EffectSetFit& fa, std::size_t b, const EffectSetFit& fb) {
    return !nested_start(a, b, fb.values).empty() || !nested_start(b, a, fa.values).empty();
}

/// The partner's points: its grid without the all-neutral point (that is the single alone), and
/// its screening start; sigmoid_mobility (no grid) at its screened values.
std::vector<std::vector<double>> partner_points(const Candidate& c, const EffectSetFit& screened) {
    std::vector<std::vector<double>> points;
    if (c.name != "sigmoid_mobility") {
        points = screen_grid(c.parameters);
        if (!points.empty()) points.erase(points.begin());
    }
    points.push_back(screened.values);
    return points;
}

}  // namespace

std::vector<PartnerScreen> screen_partners(const DiscrepancyContext& context,
                                           const EffectSetFit& single,
                                           const std::vector<EffectSetFit>& screened) {
    const std::vector<Candidate>& library = candidate_library();
    if (!single.ok || single.candidates.size() != 1) return {};
    const std::size_t s = single.candidates[0];
    const nlohmann::json single_entry = library[s].entry(single.values, single.held[0]);
    std::vector<nlohmann::json> lists;
    std::vector<std::pair<std::size_t, std::vector<double>>> of;  // (screened index, values)
    for (std::size_t k = 0; k < screened.size(); ++k) {
        const EffectSetFit& f = screened[k];
        if (f.candidates.size() != 1 || f.candidates[0] == s || f.values.empty() || f.held.empty())
            continue;
        if (!f.ok && f.neutral_jacobian.cols() == 0)
            continue;  // carried by the model, or its runs failed
        const std::size_t c = f.candidates[0];
        if (nested(c, f, s, single)) continue;
        for (const std::vector<double>& v : partner_points(library[c], f)) {
            lists.push_back(nlohmann::json::array({single_entry, library[c].entry(v, f.held[0])}));
            of.emplace_back(k, v);
        }
    }
    const std::vector<ModelPrediction> runs =
        context.evaluator.run_all(lists, RunScope::fit_training);
    std::vector<PartnerScreen> best;
    for (std::size_t r = 0; r < runs.size(); ++r) {
        if (!runs[r].ok) continue;
        const double cost = context.residuals(runs[r], SampleSet::fit_training).squaredNorm();
        auto it = std::find_if(best.begin(), best.end(),
                               [&](const PartnerScreen& p) { return p.screened == of[r].first; });
        if (it == best.end())
            best.push_back({of[r].first, of[r].second, cost});
        else if (cost < it->training_cost)
            *it = {of[r].first, of[r].second, cost};
    }
    std::sort(best.begin(), best.end(), [](const PartnerScreen& a, const PartnerScreen& b) {
        return a.training_cost < b.training_cost;
    });
    return best;
}

}  // namespace scopekin::discrepancy
