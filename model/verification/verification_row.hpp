#pragma once
// One line of `scopekin verify`: a computed figure against an independent reference.
#include <functional>
#include <string>
#include <vector>

namespace scopekin::model {

struct VerificationRow {
    std::string case_name;  ///< e.g. "mattiasson/PL2_EI=5/w_over_L"
    double reference = 0;   ///< the independent number (published or closed form)
    double value = 0;       ///< what scopekin computes
    double error = 0;       ///< as defined by the case (absolute or relative), see `error_kind`
    double tolerance = 0;   ///< pass if error <= tolerance
    bool pass = false;
    std::string unit;        ///< unit of reference and value
    std::string error_kind;  ///< "abs", "rel" or "abs/L"
};

/// A named group of rows (one CTest test each): runs the computation and returns its rows.
struct VerificationCase {
    std::string name;
    std::string description;
    std::function<std::vector<VerificationRow>()> run;
};

/// All cases of `scopekin verify`, in the order they are printed.
std::vector<VerificationCase> verification_cases();

VerificationRow make_row(std::string case_name, double reference, double value, double error,
                         double tolerance, std::string unit, std::string error_kind);

}  // namespace scopekin::model
