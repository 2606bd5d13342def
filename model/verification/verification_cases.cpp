// The cases of `scopekin verify`: each compares the model with an independent number
// (measurement, published table or closed form). See model/README.md, "Verification".
#include <array>
#include <cmath>
#include <limits>

#include "model/beam/rotation.hpp"
#include "model/beam/scope_beam.hpp"
#include "model/modal/planar_modes.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/solvers/static_solver.hpp"
#include "model/verification/contact_verification.hpp"
#include "model/verification/measured_cantilever.hpp"
#include "model/verification/verification_row.hpp"

namespace scopekin::model {
namespace {

constexpr double kInfo =
    std::numeric_limits<double>::quiet_NaN();  // tolerance of a figure that is only reported

/// A slender, practically inextensible test beam for the published elastica benchmarks:
/// EI = 1e6 N mm^2, EA = kappa G A = 1e8 N (P L / EA ~ 1e-7 L at the largest load).
BeamSection benchmark_section() {
    return BeamSection{.axial_stiffness_N = 1e8,
                       .bending_stiffness_y_Nmm2 = 1e6,
                       .bending_stiffness_z_Nmm2 = 1e6,
                       .torsional_stiffness_Nmm2 = 1e6,
                       .shear_stiffness_y_N = 1e8,
                       .shear_stiffness_z_N = 1e8};
}
constexpr double kBenchmarkLength_mm = 1000.0;
constexpr std::size_t kBenchmarkElements = 20;  // the benchmark's mesh: at most 20 elements

std::vector<VerificationRow> measured_cantilever_rows() {
    namespace mc = measured_cantilever;
    const double w = cf_q160l::kWeightPerLength_N_per_mm;
    const mc::Fit two = mc::fit_ei_over_weight_and_clamp_pitch();
    const mc::Fit one = mc::fit_ei_over_weight();
    const mc::Result thesis_ei = mc::simulate(cf_q160l::kBendingStiffness_Nmm2, w);
    std::vector<VerificationRow> rows;
    rows.push_back(make_row("measured_cantilever/rms_points_2_10_fit_EI_over_w_and_clamp_pitch",
                            0.0, two.rms_mm, two.rms_mm, 5.5, "mm", "abs"));
    // The fitted EI at App. B's weight must lie in the thesis's measured range 260-660 N cm^2.
    const double ei_fit_ncm2 = two.ei_over_weight_mm3 * w / 100.0;
    rows.push_back(
        make_row("measured_cantilever/fitted_EI_at_w_11.4_N_per_m_within_measured_260_660", 460.0,
                 ei_fit_ncm2, std::abs(ei_fit_ncm2 - 460.0), 200.0, "N cm^2", "abs"));
    rows.push_back(make_row("measured_cantilever/fitted_EI_over_w", kInfo, two.ei_over_weight_mm3,
                            kInfo, kInfo, "mm^3", ""));
    rows.push_back(make_row("measured_cantilever/fitted_clamp_pitch", kInfo, two.clamp_pitch_deg,
                            kInfo, kInfo, "deg", ""));
    // With EI / w alone (clamp exactly horizontal) the model should do no worse than the thesis's
    // own models (5.5-6.1 mm).
    rows.push_back(make_row("measured_cantilever/rms_points_2_10_fit_EI_over_w_only", 0.0,
                            one.rms_mm, one.rms_mm, 6.1, "mm", "abs"));
    rows.push_back(make_row("measured_cantilever/fitted_EI_over_w_only_EI_at_w_11.4_N_per_m", kInfo,
                            one.ei_over_weight_mm3 * w / 100.0, kInfo, kInfo, "N cm^2", ""));
    rows.push_back(
        make_row("measured_cantilever/rms_points_2_10_at_thesis_EI_350_Ncm2_w_11.4_N_per_m", kInfo,
                 thesis_ei.rms_mm, kInfo, kInfo, "mm", ""));
    return rows;
}

std::vector<VerificationRow> mattiasson_rows() {
    // Mattiasson (1981), Int. J. Numer. Meth. Eng. 17:145-153, Table I: cantilever under a
    // transverse tip load of fixed direction; tip deflection w/L and axial shortening u/L.
    struct Reference {
        double load_parameter, w_over_l, u_over_l;
    };
    const std::array<Reference, 4> table{{{1.0, 0.30172, 0.05643},
                                          {2.0, 0.49346, 0.16064},
                                          {5.0, 0.71379, 0.38763},
                                          {10.0, 0.81061, 0.55500}}};
    std::vector<VerificationRow> rows;
    for (const Reference& ref : table) {
        const BeamSection s = benchmark_section();
        ScopeBeam beam = straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                       kBenchmarkLength_mm, kBenchmarkElements, s);
        BeamLoads loads;
        const double load_N = ref.load_parameter * s.bending_stiffness_z_Nmm2 /
                              (kBenchmarkLength_mm * kBenchmarkLength_mm);
        loads.nodal.push_back(
            {kBenchmarkElements, Eigen::Vector3d(0.0, -load_N, 0.0), Eigen::Vector3d::Zero()});
        NodeSupport clamp;
        clamp.node = 0;
        const StaticReport report = solve_static(beam, loads, {clamp});
        const Eigen::Vector3d tip = beam.position(kBenchmarkElements);
        const double w = report.converged ? -tip.y() / kBenchmarkLength_mm : kInfo;
        const double u =
            report.converged ? (kBenchmarkLength_mm - tip.x()) / kBenchmarkLength_mm : kInfo;
        const std::string name =
            "mattiasson/PL2_over_EI=" + std::to_string(static_cast<int>(ref.load_parameter));
        rows.push_back(make_row(name + "/w_over_L", ref.w_over_l, w, std::abs(w - ref.w_over_l),
                                0.005, "1", "abs/L"));
        rows.push_back(make_row(name + "/u_over_L", ref.u_over_l, u, std::abs(u - ref.u_over_l),
                                0.005, "1", "abs/L"));
    }
    return rows;
}

std::vector<VerificationRow> roll_up_rows() {
    // End moment M = 2 pi EI / L bends a cantilever into a full circle (exact elastica).
    const BeamSection s = benchmark_section();
    ScopeBeam beam = straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                   kBenchmarkLength_mm, kBenchmarkElements, s);
    BeamLoads loads;
    const double moment = 2.0 * M_PI * s.bending_stiffness_z_Nmm2 / kBenchmarkLength_mm;
    loads.nodal.push_back(
        {kBenchmarkElements, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, moment)});
    NodeSupport clamp;
    clamp.node = 0;
    const StaticReport report = solve_static(beam, loads, {clamp});
    const double gap =
        (beam.position(kBenchmarkElements) - beam.position(0)).norm() / kBenchmarkLength_mm;
    // Total tip rotation, unwrapped: the sum of the (small) relative rotations between neighbours.
    double rotation = 0.0;
    for (std::size_t i = 0; i + 1 < beam.node_count(); ++i)
        rotation += rotation_log(beam.rotation(i + 1) * beam.rotation(i).transpose()).z();
    const double g = report.converged ? gap : kInfo;
    const double r = report.converged ? rotation : kInfo;
    return {make_row("roll_up/tip_to_clamp_distance_over_L", 0.0, g, g, 0.001, "1", "abs/L"),
            make_row("roll_up/tip_rotation", 2.0 * M_PI, r, std::abs(r - 2.0 * M_PI) / (2.0 * M_PI),
                     0.001, "rad", "rel")};
}

std::vector<VerificationRow> tip_load_rows() {
    // A short CF-Q160L cantilever (100 mm), where shear adds ~4 % to the bending deflection (Timoshenko).
    const BeamSection s = cf_q160l::section();
    const double length = 100.0, load = 1e-3;
    ScopeBeam beam =
        straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), length, 10, s);
    BeamLoads loads;
    loads.nodal.push_back({10, Eigen::Vector3d(0.0, -load, 0.0), Eigen::Vector3d::Zero()});
    NodeSupport clamp;
    clamp.node = 0;
    solve_static(beam, loads, {clamp});
    const double reference = load * std::pow(length, 3) / (3.0 * s.bending_stiffness_z_Nmm2) +
                             load * length / s.shear_stiffness_y_N;
    const double value = -beam.position(10).y();
    return {make_row("linear/tip_load_deflection_PL3_3EI_plus_PL_kGA", reference, value,
                     std::abs(value - reference) / reference, 0.001, "mm", "rel")};
}

std::vector<VerificationRow> frequency_rows() {
    // Euler-Bernoulli cantilever: f_n = (beta_n L)^2 / (2 pi L^2) sqrt(EI / rho A).
    const BeamSection s = cf_q160l::section();
    const double length = cf_q160l::kWorkingLength_mm;
    const ScopeBeam beam =
        straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), length, 40, s);
    const std::vector<PlanarMode> modes = planar_bending_modes(beam, cf_q160l::damping(), 3);
    const std::array<double, 3> beta_l{1.8751, 4.6941, 7.8548};
    std::vector<VerificationRow> rows;
    for (std::size_t i = 0; i < 3; ++i) {
        const double reference = beta_l[i] * beta_l[i] / (2.0 * M_PI * length * length) *
                                 std::sqrt(s.bending_stiffness_z_Nmm2 / s.mass_per_length_t_per_mm);
        rows.push_back(make_row("linear/cantilever_1.7m_frequency_mode_" + std::to_string(i + 1),
                                reference, modes[i].frequency_hz,
                                std::abs(modes[i].frequency_hz - reference) / reference, 0.01, "Hz",
                                "rel"));
    }
    return rows;
}

std::vector<VerificationRow> damping_rows() {
    // Table 4.1: measured modal damping at 1 / 7 / 44 Hz (0.364 at 44 Hz as used in the thesis's
    // computation; 0.384 measured). For each, a CF-Q160L cantilever is sized so that the model's
    // first mode sits at that frequency, and the model's own damping matrix gives zeta.
    const BeamSection s = cf_q160l::section();
    const std::array<double, 3> frequency{1.0, 7.0, 44.0};
    const std::array<double, 3> measured{0.209, 0.085, 0.364};
    std::vector<VerificationRow> rows;
    for (std::size_t i = 0; i < 3; ++i) {
        double length =
            std::sqrt(1.8751 * 1.8751 / (2.0 * M_PI * frequency[i]) *
                      std::sqrt(s.bending_stiffness_z_Nmm2 / s.mass_per_length_t_per_mm));
        PlanarMode mode;
        for (int it = 0; it < 6; ++it) {  // f ~ 1/L^2: rescale until the model's mode is on target
            const ScopeBeam beam =
                straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), length, 20, s);
            mode = planar_bending_modes(beam, cf_q160l::damping(), 1).front();
            length *= std::sqrt(mode.frequency_hz / frequency[i]);
        }
        rows.push_back(make_row("linear/rayleigh_damping_ratio_at_" +
                                    std::to_string(static_cast<int>(frequency[i])) + "Hz",
                                measured[i], mode.damping_ratio,
                                std::abs(mode.damping_ratio - measured[i]) / measured[i], 0.05, "1",
                                "rel"));
    }
    return rows;
}

}  // namespace

VerificationRow make_row(std::string case_name, double reference, double value, double error,
                         double tolerance, std::string unit, std::string error_kind) {
    VerificationRow row;
    row.case_name = std::move(case_name);
    row.reference = reference;
    row.value = value;
    row.error = error;
    row.tolerance = tolerance;
    // An informational figure (no tolerance) passes when it is a number; a check passes when its
    // error is a number within tolerance (a NaN from a failed solve never passes).
    row.pass =
        std::isnan(tolerance) ? std::isfinite(value) : (std::isfinite(error) && error <= tolerance);
    row.unit = std::move(unit);
    row.error_kind = std::move(error_kind);
    return row;
}

std::vector<VerificationCase> verification_cases() {
    return {
        {"measured_cantilever",
         "Thesis Table 4.2: CF-Q160L clamped 80 cm from the tip, hanging under its weight",
         measured_cantilever_rows},
        {"mattiasson", "Mattiasson 1981: large-deflection cantilever, tip load, 20 elements",
         mattiasson_rows},
        {"roll_up", "End moment 2 pi EI / L rolls the cantilever into a circle, 20 elements",
         roll_up_rows},
        {"tip_load", "Small tip load vs P L^3 / 3EI + P L / kappa G A", tip_load_rows},
        {"frequencies",
         "First three cantilever frequencies vs Euler-Bernoulli (beta L = 1.8751, 4.6941, 7.8548)",
         frequency_rows},
        {"damping",
         "Rayleigh damping (Hz convention resolved) vs measured zeta at 1 / 7 / 44 Hz (Table 4.1)",
         damping_rows},
        {"contact_lcp",
         "Gauss-Seidel frictional contact vs closed forms, 1000 random problems, active-set "
         "enumeration",
         contact_verification::lcp_rows},
        {"contact_world",
         "Scope pushed through a straight tube and a 115 deg bend; self-locking with mu "
         "above/below",
         contact_verification::world_rows},
    };
}

}  // namespace scopekin::model
