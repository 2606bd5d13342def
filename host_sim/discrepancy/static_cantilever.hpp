#pragma once
// The discrepancy workflow on real data: the thesis's measured cantilever (4.2.4, Table 4.2;
// model/verification/measured_cantilever.hpp) as a static case. The "recording" is the nine
// measured points 2..10 (x, y), the model as given the CF-Q160L at the thesis's chapter-5 EI
// (350 N cm^2) and App. B's weight with the clamp horizontal. Candidates:
//   ei_scale                 one EI along the scope (fitted as EI / w)
//   ei_profile               EI linear from the clamp to the tip (EI_clamp / w, EI_tip / w)
//   ei_scale + clamp_pitch   and the clamp's pitch, which the thesis did not record
//   ei_profile + clamp_pitch
// Under self weight the shape depends on EI / w only: EI and the weight cannot be told apart,
// so EI is quoted at App. B's weight. Nine points are too few for blocks: every score is
// leave-one-point-out (each point predicted by a fit to the other eight). Fits: Nelder-Mead on
// the sum of squared point errors, in log(EI / w) and degrees; EI kept within 150-1000 N cm^2
// (the thesis measured 260-660 N cm^2 along the scope) and the pitch within 15 degrees.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace scopekin::discrepancy {

struct CantileverCandidate {
    std::string name;
    std::vector<std::string> parameters;  ///< fitted, in order
    std::vector<double>
        values;  ///< fitted on all nine points (EI in N mm^2 at App. B's weight; pitch deg)
    double rms_all_mm = 0;       ///< fit to all points
    double rms_held_out_mm = 0;  ///< leave-one-point-out
    double bic = 0;              ///< on all points (18 coordinates)
    int solves = 0;
};

struct CantileverReport {
    double rms_as_given_mm = 0;
    std::vector<CantileverCandidate> candidates;  ///< best held-out first
    nlohmann::ordered_json json;                  ///< report.json
    std::string markdown;                         ///< report.md
};

CantileverReport run_thesis_cantilever();

}  // namespace scopekin::discrepancy
