#include "host_sim/discrepancy/candidates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "host_sim/discrepancy/analysis.hpp"

namespace scopekin::discrepancy {
namespace {

/// entry = {"name": name} + held + {key_i: value_i}
std::function<nlohmann::json(const std::vector<double>&, const nlohmann::json&)> plain_entry(
    std::string name, std::vector<std::string> keys) {
    return [name, keys](const std::vector<double>& values, const nlohmann::json& held) {
        nlohmann::json e = held.is_object() ? held : nlohmann::json::object();
        e["name"] = name;
        for (std::size_t i = 0; i < keys.size(); ++i)
            e[keys[i]] = values[i];
        return e;
    };
}

std::function<nlohmann::json(const MeasuredRecording&, const ModelPrediction&)> constant(
    nlohmann::json held) {
    return [held](const MeasuredRecording&, const ModelPrediction&) { return held; };
}

}  // namespace

namespace {

/// The residuals' periodogram: power and scatter of the position residuals per grid frequency.
/// The grid reaches `extension_Hz` beyond the searched band on both sides (down to 0.01 Hz), so
/// that a line near the band's ends has a neighbourhood on both sides; [first, last] is the band.
struct Periodogram {
    std::vector<double> frequency_Hz, power;
    std::vector<Eigen::Matrix3d> scatter;
    std::size_t first = 0, last = 0;
};

/// The 0.01 Hz grid: the band's points accumulated from its low end (as the band was always
/// stepped), and the extension's points below and above it.
std::vector<double> periodogram_grid(double extension_Hz, std::size_t& first, std::size_t& last) {
    std::vector<double> grid;
    for (int j = static_cast<int>(std::round(extension_Hz / 0.01)); j >= 1; --j)
        if (const double f = kPeriodicLow_Hz - 0.01 * j; f >= 0.01 - 1e-9) grid.push_back(f);
    first = grid.size();
    double f = kPeriodicLow_Hz;
    for (; f <= kPeriodicHigh_Hz + 1e-9; f += 0.01)
        grid.push_back(f);
    last = grid.size() - 1;
    for (; f <= kPeriodicHigh_Hz + extension_Hz + 1e-9; f += 0.01)
        grid.push_back(f);
    return grid;
}

Periodogram residual_periodogram(const MeasuredRecording& data, const ModelPrediction& baseline,
                                 const std::vector<double>& sigma, double extension_Hz) {
    Periodogram pg;
    pg.frequency_Hz = periodogram_grid(extension_Hz, pg.first, pg.last);
    // Least-squares sinusoid amplitudes (a periodogram for uneven samples) on a 0.01 Hz grid, of
    // every assessed output's residual in units of its noise; the direction from the positions.
    for (const double f : pg.frequency_Hz) {
        const double w = 2.0 * M_PI * f;
        double power = 0.0;
        Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
        for (std::size_t o = 0; o < data.outputs.size(); ++o) {
            if (!(sigma[o] > 0.0)) continue;
            const MeasuredSeries& m = data.outputs[o];
            Eigen::Vector3d s = Eigen::Vector3d::Zero(), c = Eigen::Vector3d::Zero();
            for (std::size_t i = 0; i < m.time_s.size(); ++i) {
                const Eigen::Vector3d r = (m.value[i] - baseline.outputs[o][i]) / sigma[o];
                s += r * std::sin(w * m.time_s[i]);
                c += r * std::cos(w * m.time_s[i]);
            }
            const double n = static_cast<double>(std::max<std::size_t>(m.time_s.size(), 1));
            s *= 2.0 / n;
            c *= 2.0 / n;
            power += s.squaredNorm() + c.squaredNorm();
            if (m.components == 3) scatter += s * s.transpose() + c * c.transpose();
        }
        pg.power.push_back(power);
        pg.scatter.push_back(scatter);
    }
    return pg;
}

/// The band's grid index of the largest power within half_width of `around` (the whole band
/// when half_width is infinite); the first of equals.
std::size_t strongest(const Periodogram& pg, double around, double half_width) {
    std::size_t best = pg.first;
    double best_power = -1.0;
    for (std::size_t k = pg.first; k <= pg.last; ++k)
        if (std::abs(pg.frequency_Hz[k] - around) <= half_width + 1e-9 &&
            pg.power[k] > best_power) {
            best_power = pg.power[k];
            best = k;
        }
    return best;
}

/// The most prominent line in the band: the grid index whose power stands highest over the
/// median power of its neighbourhood (beyond its own main lobe, `lobe_Hz`, up to `band_Hz` away).
std::size_t most_prominent(const Periodogram& pg, double lobe_Hz, double band_Hz) {
    std::size_t best = pg.first;
    double best_ratio = -1.0;
    std::vector<double> around;
    for (std::size_t k = pg.first; k <= pg.last; ++k) {
        around.clear();
        for (std::size_t j = 0; j < pg.power.size(); ++j) {
            const double d = std::abs(pg.frequency_Hz[j] - pg.frequency_Hz[k]);
            if (d > lobe_Hz + 1e-9 && d <= band_Hz + 1e-9) around.push_back(pg.power[j]);
        }
        if (around.empty()) continue;
        auto mid = around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2);
        std::nth_element(around.begin(), mid, around.end());
        const double ratio = pg.power[k] / std::max(*mid, 1e-300);
        if (ratio > best_ratio) {
            best_ratio = ratio;
            best = k;
        }
    }
    return best;
}

}  // namespace

PeriodicResidual strongest_periodic_residual(const MeasuredRecording& data,
                                             const ModelPrediction& baseline,
                                             const std::vector<double>& sigma) {
    const double span_s = std::max(data.end_s - data.start_s, 1e-3);
    // The main lobe of a line is about 1/span wide; its neighbourhood reaches 4/span (at least
    // 0.02 and 0.1 Hz). Only when that neighbourhood holds enough independent frequency cells
    // (1/span each) is its median a continuum to stand a line against: then the most prominent
    // line, at its lobe's strongest power. On a short recording, the strongest power in the band.
    const double lobe_Hz = std::max(0.02, 1.0 / span_s);
    const double band_Hz = std::max(0.1, 4.0 / span_s);
    const bool continuum = 2.0 * (band_Hz - lobe_Hz) * span_s >= kMinContinuumCells;
    const Periodogram pg = residual_periodogram(data, baseline, sigma, continuum ? band_Hz : 0.0);
    const std::size_t k =
        continuum ? strongest(pg, pg.frequency_Hz[most_prominent(pg, lobe_Hz, band_Hz)], lobe_Hz)
                  : strongest(pg, 0.0, std::numeric_limits<double>::infinity());
    PeriodicResidual best;
    best.frequency_Hz = pg.frequency_Hz[k];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(pg.scatter[k]);
    best.direction = eig.eigenvectors().col(2);
    Eigen::Index axis = 0;
    best.direction.cwiseAbs().maxCoeff(&axis);
    if (best.direction[axis] < 0.0) best.direction = -best.direction;
    return best;
}

bool within_a_step(std::size_t c, const std::vector<double>& a, const std::vector<double>& b) {
    const std::vector<Candidate>& library = candidate_library();
    if (c >= library.size()) return false;
    const std::vector<FittedParameter>& params = library[c].parameters;
    if (a.size() != params.size() || b.size() != params.size()) return false;
    for (std::size_t j = 0; j < params.size(); ++j)
        if (!(std::abs(a[j] - b[j]) <= params[j].step)) return false;
    return true;
}

bool reduces_to(std::size_t c, const std::vector<double>& values, std::size_t simpler) {
    const std::vector<Candidate>& library = candidate_library();
    if (c >= library.size() || simpler >= library.size()) return false;
    if (library[c].name == "ei_profile" && library[simpler].name == "ei_scale")
        return values.size() == 2 &&
               std::abs(values[0] - values[1]) <= library[c].parameters[0].step;
    return false;
}

std::vector<double> nested_start(std::size_t c, std::size_t simpler,
                                 const std::vector<double>& simpler_values) {
    const std::vector<Candidate>& library = candidate_library();
    if (c >= library.size() || simpler >= library.size()) return {};
    if (library[c].name == "ei_profile" && library[simpler].name == "ei_scale" &&
        simpler_values.size() == 1)
        return {simpler_values[0], simpler_values[0]};
    return {};
}

std::vector<std::vector<double>> nested_projections(std::size_t c, std::size_t simpler,
                                                    const std::vector<double>& values) {
    const std::vector<Candidate>& library = candidate_library();
    if (c >= library.size() || simpler >= library.size()) return {};
    if (library[c].name == "ei_profile" && library[simpler].name == "ei_scale" &&
        values.size() == 2)
        return {{values[0]}, {0.5 * (values[0] + values[1])}};
    return {};
}

const std::vector<Candidate>& candidate_library() {
    static const std::vector<Candidate> library = [] {
        std::vector<Candidate> c;
        c.push_back({"viscoadhesive_friction",
                     "every contact, growing with the sliding speed",
                     {{"viscous_coefficient_s_per_mm",
                       "s/mm",
                       0.0,
                       0.05,
                       0.0,
                       0.002,
                       {0.0005, 0.001, 0.002, 0.004, 0.008, 0.016, 0.032}}},
                     constant({{"max_friction_increase", 0.25}}),
                     plain_entry("viscoadhesive_friction", {"viscous_coefficient_s_per_mm"})});
        c.push_back({"mesenteric_retraction",
                     "scope nodes bowing the sigmoid out",
                     {{"stiffness_N_per_mm2",
                       "N/mm^2",
                       0.0,
                       0.1,
                       0.0,
                       0.002,
                       {0.0005, 0.001, 0.002, 0.004, 0.008, 0.016, 0.032}}},
                     constant({{"exponent", 1.0}, {"reference_excess_mm", 10.0}}),
                     plain_entry("mesenteric_retraction", {"stiffness_N_per_mm2"})});
        c.push_back(
            {"ei_profile",
             "the scope's bending stiffness along its length",
             {{"tip_factor", "1", 0.3, 2.0, 1.0, 0.1, {0.5, 0.7, 1.4, 2.0}},
              {"handle_factor", "1", 0.3, 2.0, 1.0, 0.1, {0.5, 0.7, 1.4, 2.0}}},
             constant({{"bending_section_length_mm", 0.0}, {"bending_section_factor", 1.0}}),
             plain_entry("ei_profile", {"tip_factor", "handle_factor"})});
        c.push_back(
            {"ei_scale",
             "the scope's bending stiffness, uniformly",
             {{"factor", "1", 0.3, 2.0, 1.0, 0.1, {0.5, 0.6, 0.7, 0.8, 0.9, 1.12, 1.25, 1.4, 2.0}}},
             constant(nlohmann::json::object()),
             plain_entry("ei_scale", {"factor"})});
        c.push_back({"sigmoid_mobility",
                     "scope nodes in the sigmoid, periodically",
                     {{"amplitude_cos_phase_N_per_mm", "N/mm", -0.1, 0.1, 0.0, 0.002, {}},
                      {"amplitude_sin_phase_N_per_mm", "N/mm", -0.1, 0.1, 0.0, 0.002, {}},
                      {"direction_polar_rad", "rad", 0.0, M_PI, M_PI / 2.0, 0.05, {}},
                      {"direction_azimuth_rad", "rad", -M_PI, M_PI, M_PI / 2.0, 0.05, {}}},
                     [](const MeasuredRecording& data, const ModelPrediction& baseline) {
                         const PeriodicResidual p =
                             strongest_periodic_residual(data, baseline, estimate_noise(data));
                         return nlohmann::json{{"frequency_Hz", p.frequency_Hz}};
                     },
                     [](const std::vector<double>& v, const nlohmann::json& held) {
                         // A sin(w t + phi) d = A cos(phi) sin(w t) d + A sin(phi) cos(w t) d
                         nlohmann::json e = held;
                         e["name"] = "sigmoid_mobility";
                         e["amplitude_N_per_mm"] = std::hypot(v[0], v[1]);
                         e["phase_rad"] = std::atan2(v[1], v[0]);
                         e["direction"] = {std::sin(v[2]) * std::cos(v[3]),
                                           std::sin(v[2]) * std::sin(v[3]), std::cos(v[2])};
                         return e;
                     }});
        c.push_back({"tissue_stiffening",
                     "the colon wall at every contact, stiffening with the force",
                     {{"stiffening_per_N",
                       "1/N",
                       0.0,
                       20.0,
                       0.0,
                       0.3,
                       {0.075, 0.15, 0.3, 0.6, 1.2, 2.4, 4.8, 9.6, 19.2}}},
                     constant(nlohmann::json::object()),
                     plain_entry("tissue_stiffening", {"stiffening_per_N"})});
        return c;
    }();
    return library;
}

}  // namespace scopekin::discrepancy
