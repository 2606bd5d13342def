#include "host_sim/discrepancy/candidates.hpp"

#include <cmath>

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

PeriodicResidual strongest_periodic_residual(const MeasuredRecording& data,
                                             const ModelPrediction& baseline,
                                             const std::vector<double>& sigma) {
    PeriodicResidual best;
    double best_power = -1.0;
    // Least-squares sinusoid amplitudes (a periodogram for uneven samples) on a 0.01 Hz grid, of
    // every assessed output's residual in units of its noise; the direction from the positions.
    for (double f = 0.05; f <= 2.0 + 1e-9; f += 0.01) {
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
        if (power > best_power) {
            best_power = power;
            best.frequency_Hz = f;
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
            best.direction = eig.eigenvectors().col(2);
            Eigen::Index k = 0;
            best.direction.cwiseAbs().maxCoeff(&k);
            if (best.direction[k] < 0.0) best.direction = -best.direction;
        }
    }
    return best;
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
