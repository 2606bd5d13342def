// Virtual patients (model/patient/): the family's ranges and distributions against the numbers
// stated in model/patient/README.md and the CT colonography study it cites, the centerline's
// length against the sum of the drawn region lengths (closed form: equal chords), the drawn sag
// and flexure angles measured back on the centerline, reproducibility, the JSON round trip, and
// bad patient files refused with the field named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "model/model_error.hpp"
#include "model/patient/patient.hpp"
#include "model/patient/patient_random.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::expect_model_error;

constexpr double kScopeRadius_mm = 6.65;
constexpr std::size_t kPatients = 1000;

std::size_t at(ColonRegion r) {
    return static_cast<std::size_t>(r);
}

/// The patients of seeds 0 .. n - 1 (drawn once per test process; each CTest test is a process,
/// so the tests that need all 1,000 are few: they take half a minute each under the sanitizers).
const std::vector<PatientSpec>& population(std::size_t n = kPatients) {
    static std::vector<PatientSpec> patients;
    while (patients.size() < n)
        patients.push_back(draw_patient(patients.size()));
    static std::vector<PatientSpec> first;
    first.assign(patients.begin(), patients.begin() + static_cast<std::ptrdiff_t>(n));
    return first;
}

double mean_of(const std::vector<double>& v) {
    double s = 0;
    for (double x : v)
        s += x;
    return s / static_cast<double>(v.size());
}

double quantile(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

std::vector<double> collect(const std::function<double(const PatientSpec&)>& f) {
    std::vector<double> v;
    for (const PatientSpec& p : population())
        v.push_back(f(p));
    return v;
}

// ---- the random numbers ---------------------------------------------------------------------

TEST(PatientRandom, UniformAndNormalHaveTheirMoments) {
    PatientRandom r(42);
    constexpr int n = 200000;
    double su = 0, su2 = 0, sn = 0, sn2 = 0;
    for (int i = 0; i < n; ++i) {
        const double u = r.unit();
        ASSERT_GE(u, 0.0);
        ASSERT_LT(u, 1.0);
        su += u;
        su2 += u * u;
        const double z = r.normal();
        sn += z;
        sn2 += z * z;
    }
    // Uniform: mean 1/2, variance 1/12; standard normal: mean 0, variance 1 (5 standard errors).
    EXPECT_NEAR(su / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
    EXPECT_NEAR(su2 / n - (su / n) * (su / n), 1.0 / 12, 0.002);
    EXPECT_NEAR(sn / n, 0.0, 5 / std::sqrt(n));
    EXPECT_NEAR(sn2 / n, 1.0, 0.02);
}

TEST(PatientRandom, FirstOutputIsTheStandardsMt19937_64) {
    // C++ standard [rand.predef]: the 10000th output of a default-seeded mt19937_64 is
    // 9981545732273789042; so the engine is the portable one.
    std::mt19937_64 e;
    e.discard(9999);
    EXPECT_EQ(e(), 9981545732273789042ULL);
    // And unit() is its top 53 bits times 2^-53.
    std::mt19937_64 f(7);
    PatientRandom r(7);
    EXPECT_EQ(r.unit(), static_cast<double>(f() >> 11U) / 9007199254740992.0);
}

// ---- the family: every parameter within the ranges of model/patient/README.md ---------------

TEST(PatientFamily, EveryParameterOf1000PatientsInsideItsStatedRange) {
    // The table of model/patient/README.md, "The family".
    const double length_lo[8] = {110, 250, 170, 55, 300, 55, 100, 50};
    const double length_hi[8] = {170, 600, 250, 95, 700, 95, 180, 70};
    const double radius_lo[8] = {15, 11.5, 12, 14, 17, 17, 19, 20};
    const double radius_hi[8] = {22, 17, 18, 22, 27, 27, 28, 30};
    for (const PatientSpec& p : population()) {
        SCOPED_TRACE("seed " + std::to_string(p.seed));
        for (std::size_t i = 0; i < 8; ++i) {
            EXPECT_GE(p.region_length_mm[i], length_lo[i]);
            EXPECT_LE(p.region_length_mm[i], length_hi[i]);
            EXPECT_GE(p.lumen_radius_mm[i], radius_lo[i]);
            EXPECT_LE(p.lumen_radius_mm[i], radius_hi[i]);
        }
        EXPECT_GE(p.total_length_mm(), 1200.0);  // the 1.2 - 1.9 m
        EXPECT_LE(p.total_length_mm(), 1900.0);
        EXPECT_GE(p.sigmoid_loop_radius_mm, 25.0);
        EXPECT_LE(p.sigmoid_loop_radius_mm, 38.0);
        if (p.sigmoid_shape == SigmoidShape::n_prone) {
            EXPECT_GE(p.sigmoid_loop_tilt_deg, 0.0);
            EXPECT_LE(p.sigmoid_loop_tilt_deg, 30.0);
        } else {
            EXPECT_GE(p.sigmoid_loop_tilt_deg, 50.0);
            EXPECT_LE(p.sigmoid_loop_tilt_deg, 80.0);
        }
        EXPECT_GE(p.splenic_flexure_angle_deg, 20.0);
        EXPECT_LE(p.splenic_flexure_angle_deg, 60.0);
        EXPECT_GE(p.hepatic_flexure_angle_deg, 25.0);
        EXPECT_LE(p.hepatic_flexure_angle_deg, 70.0);
        EXPECT_GE(p.transverse_sag_mm, 60.0);
        EXPECT_LE(p.transverse_sag_mm, 250.0);
        EXPECT_GE(p.friction_coefficient, 0.10);  // the 0.10 - 0.45
        EXPECT_LE(p.friction_coefficient, 0.45);
        EXPECT_GE(p.wall_modulus_factor, 0.5);  // +- 50 % around Table 4.6
        EXPECT_LE(p.wall_modulus_factor, 1.5);
        for (double f : p.mesentery_factor) {
            EXPECT_GE(f, 0.3);  // x 0.3 - 3 of the default
            EXPECT_LE(f, 3.0);
        }
        EXPECT_GE(p.ei_factor, 0.85);  // EI x 0.85 - 1.15
        EXPECT_LE(p.ei_factor, 1.15);
        if (p.distal_section_length_mm > 0) {
            EXPECT_GE(p.distal_section_length_mm, 80.0);
            EXPECT_LE(p.distal_section_length_mm, 130.0);
            EXPECT_GE(p.distal_section_factor, 0.5);
            EXPECT_LE(p.distal_section_factor, 0.9);
        } else {
            EXPECT_EQ(p.distal_section_factor, 1.0);
        }
    }
}

TEST(PatientFamily, DistributionsOf1000PatientsMatchTheStatedOnes) {
    // Utano et al., Jpn J Radiol 2022;40:298: 150.3 +- 18.5 cm (range 109.7 - 195.9) in 295
    // patients. The family's mean within 3 %; its spread narrower than the CT's (model/patient/
    // README.md says so) but not degenerate.
    const std::vector<double> total =
        collect([](const PatientSpec& p) { return p.total_length_mm(); });
    EXPECT_NEAR(mean_of(total), 1503.0, 0.03 * 1503.0);
    EXPECT_LT(quantile(total, 0.05), 1400.0);
    EXPECT_GT(quantile(total, 0.95), 1600.0);

    // Parameters that take no part in the geometry's checks keep their stated distribution
    // whatever is redrawn: uniform friction on [0.10, 0.45] (mean 0.275, median 0.275), uniform
    // EI factor on [0.85, 1.15], log-uniform mesentery factors on [0.3, 3] (median sqrt(0.9)),
    // 10 % mobile descending colons, half the scopes with a softer distal section. Tolerances:
    // about 4 standard errors for 1000 draws.
    const auto friction = collect([](const PatientSpec& p) { return p.friction_coefficient; });
    EXPECT_NEAR(mean_of(friction), 0.275, 4 * 0.101 / std::sqrt(1000.0));
    EXPECT_NEAR(quantile(friction, 0.5), 0.275, 0.025);
    EXPECT_NEAR(quantile(friction, 0.1), 0.135, 0.02);
    const auto ei = collect([](const PatientSpec& p) { return p.ei_factor; });
    EXPECT_NEAR(mean_of(ei), 1.0, 4 * 0.0866 / std::sqrt(1000.0));
    const auto mesentery = collect([](const PatientSpec& p) { return p.mesentery_factor[0]; });
    EXPECT_NEAR(std::log(quantile(mesentery, 0.5)), std::log(std::sqrt(0.9)), 0.15);
    const auto mobile =
        collect([](const PatientSpec& p) { return p.descending_mobile ? 1.0 : 0.0; });
    EXPECT_NEAR(mean_of(mobile), 0.10, 4 * 0.3 / std::sqrt(1000.0));
    const auto distal =
        collect([](const PatientSpec& p) { return p.distal_section_length_mm > 0 ? 1.0 : 0.0; });
    EXPECT_NEAR(mean_of(distal), 0.5, 4 * 0.5 / std::sqrt(1000.0));

    // Cadaver study (Ann R Coll Surg Engl 2015;97:439): the transverse colon is the longest
    // segment on average, then the sigmoid; N loops are the common sigmoid loop (79 % of
    // procedures, Shah et al. 2000): alpha-prone shapes a minority (stated 20 %).
    const auto sigmoid =
        collect([](const PatientSpec& p) { return p.region_length_mm[at(ColonRegion::sigmoid)]; });
    const auto transverse = collect(
        [](const PatientSpec& p) { return p.region_length_mm[at(ColonRegion::transverse)]; });
    EXPECT_GT(mean_of(transverse), mean_of(sigmoid));
    for (ColonRegion r : kColonRegionsInOrder) {
        if (r == ColonRegion::sigmoid || r == ColonRegion::transverse) continue;
        EXPECT_GT(
            mean_of(sigmoid),
            mean_of(collect([r](const PatientSpec& p) { return p.region_length_mm[at(r)]; })));
    }
    const auto alpha = collect([](const PatientSpec& p) {
        return p.sigmoid_shape == SigmoidShape::alpha_prone ? 1.0 : 0.0;
    });
    EXPECT_GT(mean_of(alpha), 0.1);
    EXPECT_LT(mean_of(alpha), 0.3);
}

// ---- geometry ----------------------------------------------------------------------------------

TEST(PatientGeometry, CenterlineLengthIsTheSumOfTheDrawnRegionLengthsAndEverySeedIsValid) {
    for (const PatientSpec& p : population()) {
        SCOPED_TRACE("seed " + std::to_string(p.seed));
        const ColonTube colon = patient_colon(p, kScopeRadius_mm);
        // Every region is sampled as equal chords whose lengths add up to the drawn length.
        EXPECT_NEAR(colon.length_mm(), p.total_length_mm(), 1e-6 * p.total_length_mm());
        const auto lengths = colon.region_lengths_mm();
        for (std::size_t i = 0; i < 8; ++i)
            EXPECT_NEAR(lengths[i], p.region_length_mm[i], 1e-6 * p.region_length_mm[i]);
        // No chord longer than 10 mm.
        for (std::size_t i = 1; i < colon.point_count(); ++i)
            ASSERT_LE(colon.arc_length_mm(i) - colon.arc_length_mm(i - 1), 10.0 + 1e-9);
    }
    // ColonTube: lumen wider than the scope, regions in order, no self-intersection; plus the
    // family's own checks (bend radius, width, height), which draw_patient redraws for.
    std::size_t redraws = 0;
    for (const PatientSpec& p : population()) {
        EXPECT_NO_THROW((void)patient_colon(p, kScopeRadius_mm)) << "seed " << p.seed;
        EXPECT_EQ(patient_problem(p, kScopeRadius_mm), "") << "seed " << p.seed;
        EXPECT_GE(smallest_bend_radius_mm(patient_centerline(p)).first, kMinPatientBendRadius_mm);
        redraws += p.redraws;
    }
    // Redraws happen (the checks bite) but stay a minority of the work: < 2 per patient.
    EXPECT_GT(redraws, 0U);
    EXPECT_LT(redraws, 2 * kPatients);
}

TEST(PatientGeometry, SagAndFlexureAnglesMeasuredOnTheCenterlineAreTheDrawnOnes) {
    for (const PatientSpec& p : population(200)) {
        SCOPED_TRACE("seed " + std::to_string(p.seed));
        const PatientMeasures m = measure_patient(p);
        EXPECT_NEAR(m.transverse_sag_mm, p.transverse_sag_mm, 1e-6);
        EXPECT_NEAR(m.splenic_flexure_angle_deg, p.splenic_flexure_angle_deg, 1e-6);
        EXPECT_NEAR(m.hepatic_flexure_angle_deg, p.hepatic_flexure_angle_deg, 1e-6);
        EXPECT_GT(m.sigmoid_redundancy, 0.0);
        EXPECT_LT(m.sigmoid_redundancy, 1.0);
    }
}

TEST(PatientGeometry, BendRadiusOfACircleIsItsRadius) {
    // Points on a circle of radius 50 mm: every circumradius is 50 mm (closed form).
    std::vector<ColonPoint> points;
    for (int i = 0; i < 20; ++i) {
        const double a = 0.2 * i;
        points.push_back(
            {Eigen::Vector3d(50 * std::cos(a), 50 * std::sin(a), 0), 20, ColonRegion::sigmoid});
    }
    EXPECT_NEAR(smallest_bend_radius_mm(points).first, 50.0, 1e-9);
}

TEST(PatientGeometry, PropertiesFollowTheDrawnMechanics) {
    for (const PatientSpec& p : population(100)) {
        const auto props = patient_colon_properties(p);
        // Table 4.6's sigmoid modulus 360 kPa times the factor; the default mesentery 2e-3.
        EXPECT_NEAR(props[at(ColonRegion::sigmoid)].young_modulus_kPa,
                    360.0 * p.wall_modulus_factor, 1e-9);
        EXPECT_NEAR(props[at(ColonRegion::transverse)].mesentery_stiffness_N_per_mm2,
                    2e-3 * p.mesentery_factor[1], 1e-12);
        EXPECT_EQ(props[at(ColonRegion::descending)].attachment == ColonAttachment::mesentery,
                  p.descending_mobile);
        EXPECT_EQ(props[at(ColonRegion::cecum)].attachment == ColonAttachment::mesentery,
                  p.ascending_mobile);
        EXPECT_EQ(props[at(ColonRegion::rectum)].attachment, ColonAttachment::fixed);
    }
}

// ---- reproducibility and JSON -------------------------------------------------------------------

TEST(PatientJson, SameSeedSameJsonOtherSeedsDiffer) {
    EXPECT_EQ(patient_to_json(draw_patient(17)).dump(), patient_to_json(draw_patient(17)).dump());
    EXPECT_NE(patient_to_json(draw_patient(17)).dump(), patient_to_json(draw_patient(18)).dump());
    EXPECT_EQ(draw_patient(17).seed, 17U);
    // The largest seed works too.
    EXPECT_NO_THROW((void)draw_patient(18446744073709551615ULL));
}

TEST(PatientJson, RoundTripIsExact) {
    for (const PatientSpec& p : population(50)) {
        const nlohmann::ordered_json j = patient_to_json(p);
        const PatientSpec back = read_patient(nlohmann::json::parse(j.dump()), "p.json:");
        EXPECT_EQ(patient_to_json(back).dump(), j.dump());
        EXPECT_EQ(patient_centerline(back).size(), patient_centerline(p).size());
    }
}

nlohmann::json good_patient() {
    return nlohmann::json::parse(patient_to_json(draw_patient(5)).dump());
}

TEST(PatientJson, BadInputRefusedWithTheField) {
    auto refused = [](const std::function<void(nlohmann::json&)>& edit,
                      const std::string& fragment) {
        nlohmann::json j = good_patient();
        edit(j);
        expect_model_error([&] { (void)read_patient(j, "p.json:"); }, fragment);
    };
    refused([](nlohmann::json& j) { j["colon"].erase("transverse_sag_mm"); },
            "p.json: colon.transverse_sag_mm: missing");
    refused([](nlohmann::json& j) { j["colon"]["sag"] = 1; }, "p.json: colon.sag: unknown key");
    refused([](nlohmann::json& j) { j["extra"] = 1; }, "p.json: extra: unknown key");
    refused([](nlohmann::json& j) { j["colon"]["region_lengths_mm"]["sigmoid"] = -300; },
            "p.json: colon.region_lengths_mm.sigmoid: -300 must be in [250, 600]");
    refused([](nlohmann::json& j) { j["colon"]["region_lengths_mm"]["sigmoid"] = 700; },
            "colon.region_lengths_mm.sigmoid: 700 must be in [250, 600]");
    refused([](nlohmann::json& j) { j["mechanics"]["friction_coefficient"] = 0.9; },
            "mechanics.friction_coefficient: 0.9 must be in [0.1, 0.45]");
    refused([](nlohmann::json& j) { j["mechanics"]["ascending_attachment"] = "glued"; },
            "mechanics.ascending_attachment: unknown attachment 'glued'");
    refused([](nlohmann::json& j) { j["colon"]["sigmoid_shape"] = "omega"; },
            "colon.sigmoid_shape: unknown shape 'omega'");
    refused([](nlohmann::json& j) { j["scope"]["ei_factor"] = "stiff"; },
            "scope.ei_factor: expected a number");
    refused([](nlohmann::json& j) { j["derived"]["total_length_mm"] = 1.0; },
            "derived.total_length_mm: 1 mm is not the sum");
    refused([](nlohmann::json& j) { j["seed"] = -1; }, "p.json: seed: expected a whole number");
    refused([](nlohmann::json& j) { j["seed"] = 1e30; }, "seed: expected a whole number");
    refused([](nlohmann::json& j) { j["seed"] = "x"; }, "seed: expected a whole number");
    // A sag the transverse colon cannot make with its length: the geometry is refused.
    refused(
        [](nlohmann::json& j) {
            j.erase("derived");
            j["colon"]["region_lengths_mm"]["transverse"] = 300;
            j["colon"]["transverse_sag_mm"] = 250;
        },
        "not an acceptable patient");
}

}  // namespace
}  // namespace scopekin::model
