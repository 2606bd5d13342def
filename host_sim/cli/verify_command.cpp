#include "host_sim/cli/verify_command.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/verification/verification_row.hpp"

namespace scopekin::cli {
namespace {

struct VerifyOptions {
    bool json = false;
    std::vector<std::string> cases;
    bool list = false;
};

std::string number(double v) {
    if (std::isnan(v)) return "-";
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.6g", v);
    return buffer;
}

nlohmann::json to_json(const model::VerificationRow& row) {
    auto num = [](double v) {
        return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
    };
    const bool informational = std::isnan(row.tolerance);
    return {{"case", row.case_name},
            {"reference", num(row.reference)},
            {"value", num(row.value)},
            {"error", num(row.error)},
            {"tolerance", num(row.tolerance)},
            {"pass", informational ? nlohmann::json(nullptr) : nlohmann::json(row.pass)},
            {"unit", row.unit},
            {"error_kind", row.error_kind}};
}

int run_verify(const VerifyOptions& options) {
    std::vector<model::VerificationCase> selected;
    const std::vector<model::VerificationCase> all = model::verification_cases();
    if (options.list) {
        for (const auto& c : all)
            std::cout << c.name << "  " << c.description << "\n";
        return 0;
    }
    for (const auto& c : all)
        if (options.cases.empty() ||
            std::find(options.cases.begin(), options.cases.end(), c.name) != options.cases.end())
            selected.push_back(c);
    for (const std::string& wanted : options.cases) {
        bool known = false;
        for (const auto& c : all)
            known = known || c.name == wanted;
        if (!known) {
            std::cerr << "scopekin verify: unknown case '" << wanted
                      << "' (see scopekin verify --list)\n";
            return 2;
        }
    }
    std::vector<model::VerificationRow> rows;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < selected.size(); ++i) {
        std::cerr << "[" << i + 1 << "/" << selected.size() << "] " << selected[i].name << ": "
                  << selected[i].description << " ..." << std::flush;
        const auto case_start = std::chrono::steady_clock::now();
        std::vector<model::VerificationRow> case_rows = selected[i].run();
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - case_start).count();
        std::cerr << " done (" << number(seconds) << " s)\n";
        rows.insert(rows.end(), case_rows.begin(), case_rows.end());
    }
    bool all_pass = true;
    int checks = 0, passed = 0;
    for (const auto& r : rows) {
        all_pass = all_pass && r.pass;
        if (!std::isnan(r.tolerance)) {
            ++checks;
            passed += r.pass ? 1 : 0;
        }
    }
    if (options.json) {
        nlohmann::json array = nlohmann::json::array();
        for (const auto& r : rows)
            array.push_back(to_json(r));
        std::cout << array.dump(2) << "\n";
    } else {
        std::printf("%-82s %12s %12s %10s %10s  %s\n", "case", "reference", "scopekin", "error",
                    "tolerance", "pass");
        for (const auto& r : rows) {
            const bool informational = std::isnan(r.tolerance);
            std::printf("%-82s %12s %12s %10s %10s  %s\n",
                        (r.case_name + " [" + r.unit + "]").c_str(), number(r.reference).c_str(),
                        number(r.value).c_str(), number(r.error).c_str(),
                        number(r.tolerance).c_str(),
                        informational ? "(figure)" : (r.pass ? "PASS" : "FAIL"));
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("\n%d of %d checks passed in %.1f s%s\n", passed, checks, seconds,
                    all_pass ? "" : "  -- FAILURES above");
    }
    return all_pass ? 0 : 1;
}

}  // namespace

void add_verify_command(CLI::App& app) {
    auto options = std::make_shared<VerifyOptions>();
    CLI::App* verify = app.add_subcommand("verify",
                                          "Check the reference beam model against measured and "
                                          "published numbers: the thesis's measured "
                                          "cantilever (Table 4.2), Mattiasson's large-deflection "
                                          "cantilever, the roll-up circle, a Timoshenko "
                                          "tip load, Euler-Bernoulli frequencies and the measured "
                                          "Rayleigh damping. Prints a table (case, "
                                          "reference, scopekin, error, tolerance, pass); exit "
                                          "status 0 when every check passes, 1 otherwise.");
    verify->add_flag("--json", options->json,
                     "Print a JSON array of objects {case, reference, value, error, tolerance, "
                     "pass, unit, error_kind}; "
                     "reported figures without a check have tolerance and pass null");
    verify->add_option("--case", options->cases, "Run only this case (repeatable); see --list");
    verify->add_flag("--list", options->list, "List the cases and exit");
    verify->callback([options]() { throw CLI::RuntimeError(run_verify(*options)); });
}

}  // namespace scopekin::cli
