// The truth effects (model/effects/, EFFECTS.md). Expected numbers are independent of the code
// under test: closed forms (Timoshenko cantilever, the exponential wall law), hand computations
// on hand-built geometry, and bit-identity with a world without effects.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_beam.hpp"
#include "model/effects/effect_library.hpp"
#include "model/effects/ei_profile.hpp"
#include "model/effects/ei_scale.hpp"
#include "model/effects/mesenteric_retraction.hpp"
#include "model/effects/sigmoid_mobility.hpp"
#include "model/effects/tissue_stiffening.hpp"
#include "model/effects/viscoadhesive_friction.hpp"
#include "model/model_error.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/world/world.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

const double kScopeRadius = cf_q160l::kRadius_mm;

ScopeSpec short_scope() {
    ScopeSpec spec;
    spec.length_mm = 400.0;
    spec.elements = 40;
    spec.radius_mm = kScopeRadius;
    spec.section = cf_q160l::section();
    return spec;
}

std::shared_ptr<const WorldEffect> effect(const std::string& json) {
    return make_world_effect(nlohmann::json::parse(json), "t.json: truth_effects[0]");
}

/// Expects make_world_effect to throw a ModelError containing every fragment.
void expect_effect_error(const std::string& json, std::initializer_list<std::string> fragments) {
    try {
        effect(json);
        ADD_FAILURE() << "accepted " << json;
    } catch (const ModelError& e) {
        for (const std::string& f : fragments)
            EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
}

// --- library and factory --------------------------------------------------------------------------

TEST(WorldEffectLibrary, NamesAreExactlyTheSix) {
    const std::vector<std::string> expected{
        "viscoadhesive_friction", "mesenteric_retraction", "ei_profile", "ei_scale",
        "sigmoid_mobility",       "tissue_stiffening"};
    EXPECT_EQ(world_effect_names(), expected);
    for (const std::string& name : expected)
        EXPECT_EQ(effect(R"({"name": ")" + name + R"("})")->name(), name);
}

TEST(WorldEffectLibrary, ParametersRoundTripThroughTheFactory) {
    for (const std::string& name : world_effect_names()) {
        const auto first = effect(R"({"name": ")" + name + R"("})");
        nlohmann::json spec = first->parameters();
        ASSERT_TRUE(spec.is_object()) << name;
        EXPECT_FALSE(spec.empty()) << name;
        spec["name"] = name;
        const auto second = make_world_effect(spec, "again");
        EXPECT_EQ(second->parameters(), first->parameters()) << name;
    }
    // Given values are reported as given (direction normalised).
    EXPECT_EQ(effect(R"({"name": "ei_scale", "factor": 0.8})")->parameters(),
              nlohmann::json({{"factor", 0.8}}));
    const nlohmann::json p =
        effect(
            R"({"name": "sigmoid_mobility", "amplitude_N_per_mm": 0.01, "direction": [0, 0, -3]})")
            ->parameters();
    EXPECT_EQ(p["direction"], nlohmann::json({0.0, 0.0, -1.0}));
    EXPECT_EQ(p["amplitude_N_per_mm"], 0.01);
    // reference_force_N is the other spelling of stiffening_per_N = 1 / f_ref.
    EXPECT_EQ(effect(R"({"name": "tissue_stiffening", "reference_force_N": 4})")->parameters(),
              nlohmann::json({{"stiffening_per_N", 0.25}}));
}

TEST(WorldEffectLibrary, FactoryRejectsBadSpecsNamingTheField) {
    expect_effect_error(
        R"({"name": "sticky_walls"})",
        {"t.json: truth_effects[0].name", "unknown truth effect 'sticky_walls'", "ei_scale"});
    expect_effect_error(R"({"factor": 0.8})", {"t.json: truth_effects[0].name", "missing"});
    expect_effect_error(R"({"name": "ei_scale", "facter": 0.8})",
                        {"t.json: truth_effects[0].facter", "unknown key"});
    expect_effect_error(R"({"name": "ei_scale", "factor": "soft"})",
                        {"t.json: truth_effects[0].factor", "expected a number"});
    expect_effect_error(R"({"name": "ei_scale", "factor": 0})",
                        {"t.json: truth_effects[0].factor", "(0, 10]"});
    expect_effect_error(R"({"name": "mesenteric_retraction", "stiffness_N_per_mm2": -0.001})",
                        {"t.json: truth_effects[0].stiffness_N_per_mm2", "-0.001"});
    expect_effect_error(R"({"name": "mesenteric_retraction", "exponent": 0.5})",
                        {"truth_effects[0].exponent"});
    expect_effect_error(R"({"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": -1})",
                        {"truth_effects[0].viscous_coefficient_s_per_mm"});
    expect_effect_error(R"({"name": "sigmoid_mobility", "direction": [0, 0, 0]})",
                        {"truth_effects[0].direction"});
    expect_effect_error(R"({"name": "sigmoid_mobility", "frequency_Hz": 0})",
                        {"truth_effects[0].frequency_Hz"});
    expect_effect_error(
        R"({"name": "tissue_stiffening", "stiffening_per_N": 1, "reference_force_N": 1})",
        {"truth_effects[0].reference_force_N", "not both"});
    expect_effect_error(R"({"name": "tissue_stiffening", "reference_force_N": -2})",
                        {"truth_effects[0].reference_force_N"});
    expect_effect_error(R"({"name": "ei_profile", "tip_factor": -0.5})",
                        {"truth_effects[0].tip_factor"});
    expect_effect_error(R"(["ei_scale"])", {"t.json: truth_effects[0]", "expected a JSON object"});
    // In code: the effect's name prefixes the field.
    try {
        MesentericRetraction({-1.0, 1.0, 10.0});
        ADD_FAILURE() << "accepted";
    } catch (const ModelError& e) {
        EXPECT_NE(std::string(e.what()).find("mesenteric_retraction.stiffness_N_per_mm2"),
                  std::string::npos)
            << e.what();
    }
}

TEST(WorldEffectLibrary, DuplicateEffectsAreRejected) {
    const auto list = nlohmann::json::parse(
        R"([{"name": "ei_scale"}, {"name": "ei_profile"}, {"name": "ei_scale", "factor": 0.9}])");
    try {
        read_world_effects(list, "s.json: truth_effects");
        ADD_FAILURE() << "accepted";
    } catch (const ModelError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("s.json: truth_effects[2].name"), std::string::npos) << m;
        EXPECT_NE(m.find("truth_effects[0]"), std::string::npos) << m;
    }
    EXPECT_EQ(read_world_effects(nlohmann::json::array(), "x").size(), 0u);
    EXPECT_THROW(read_world_effects(nlohmann::json::object(), "x"), ModelError);
}

// --- each effect against hand computations -----------------------------------------------------

TEST(WorldEffectViscoadhesive, CoefficientGrowsWithSlidingSpeedUpToTheCap) {
    const ViscoadhesiveFriction e({0.003, 0.2});
    EXPECT_NEAR(e.effective_coefficient(0.25, 10.0), 0.25 + 0.003 * 10.0, 1e-15);  // 0.28
    EXPECT_NEAR(e.effective_coefficient(0.25, -10.0), 0.28, 1e-15);                // |v|
    EXPECT_NEAR(e.effective_coefficient(0.25, 1000.0), 0.25 + 0.2, 1e-15);  // capped: 3 > 0.2
    const WorldEffect& base = e;
    EXPECT_NEAR(
        base.friction_coefficient(ContactFrictionView{50.0, ColonRegion::sigmoid, 0.1, 20.0}), 0.16,
        1e-15);
    // Zero strength: exactly mu, whatever the speed.
    const ViscoadhesiveFriction off({0.0, 0.2});
    EXPECT_EQ(off.effective_coefficient(0.25, 1e6), 0.25);
}

TEST(WorldEffectTissueStiffening, SecantAndTangentComplianceOfTheExponentialLaw) {
    const double c0 = 0.28, f_ref = 2.0;
    const TissueStiffening e({1.0 / f_ref});
    // Secant at f = f_ref: delta(f_ref) / f_ref = c0 ln 2.
    EXPECT_NEAR(e.secant_compliance_mm_per_N(c0, f_ref), c0 * std::log(2.0), 1e-15);
    const WorldEffect& base = e;
    EXPECT_NEAR(
        base.wall_compliance_mm_per_N(ContactWallView{10.0, ColonRegion::sigmoid, f_ref, c0}),
        c0 * std::log(2.0), 1e-15);
    // Tangent d delta / d f at f = f_ref is c0 / 2 (central difference of delta(f) = c(f) f).
    const double df = 1e-5;
    const double tangent =
        (e.indentation_mm(c0, f_ref + df) - e.indentation_mm(c0, f_ref - df)) / (2.0 * df);
    EXPECT_NEAR(tangent, c0 / 2.0, 1e-9);
    // The indentation satisfies the force law f = f_ref (exp(delta / (c0 f_ref)) - 1).
    for (double f : {0.01, 0.5, 2.0, 7.0}) {
        const double delta = e.indentation_mm(c0, f);
        EXPECT_NEAR(f_ref * (std::exp(delta / (c0 * f_ref)) - 1.0), f, 1e-12 * (1.0 + f)) << f;
    }
    // Unloaded (or tiny force): the linear wall; zero strength: exactly c0.
    EXPECT_EQ(e.secant_compliance_mm_per_N(c0, 0.0), c0);
    EXPECT_NEAR(e.secant_compliance_mm_per_N(c0, 1e-9), c0, 1e-9);  // continuous at f = 0
    EXPECT_EQ(TissueStiffening({0.0}).secant_compliance_mm_per_N(c0, 5.0), c0);
}

TEST(WorldEffectEiProfile, SectionsFollowTheProfileAtElementMidpoints) {
    const EiProfile e({0.5, 1.5, 120.0, 0.5});
    const BeamSection s0 = cf_q160l::section();
    std::vector<BeamSection> sections(10, s0);
    e.adjust_scope_sections(sections, 1000.0);
    // Element i (node 0 = handle) has its midpoint 1000 - (i + 0.5) 100 mm from the tip.
    for (std::size_t i = 0; i < 10; ++i) {
        const double mid = 1000.0 - (static_cast<double>(i) + 0.5) * 100.0;
        double f = 0.5 + 1.0 * mid / 1000.0;
        if (mid < 120.0) f *= 0.5;  // only element 9 (midpoint 50 mm)
        EXPECT_NEAR(sections[i].bending_stiffness_y_Nmm2, f * s0.bending_stiffness_y_Nmm2, 1e-9)
            << i;
        EXPECT_NEAR(sections[i].bending_stiffness_z_Nmm2, f * s0.bending_stiffness_z_Nmm2, 1e-9)
            << i;
        EXPECT_EQ(sections[i].torsional_stiffness_Nmm2, s0.torsional_stiffness_Nmm2);
        EXPECT_EQ(sections[i].axial_stiffness_N, s0.axial_stiffness_N);
        EXPECT_EQ(sections[i].mass_per_length_t_per_mm, s0.mass_per_length_t_per_mm);
    }
    EXPECT_NEAR(sections[0].bending_stiffness_y_Nmm2, 1.45 * s0.bending_stiffness_y_Nmm2, 1e-9);
    EXPECT_NEAR(sections[9].bending_stiffness_y_Nmm2, 0.275 * s0.bending_stiffness_y_Nmm2, 1e-9);
}

TEST(WorldEffectMesentericRetraction, ForceOnNodesDisplacedBeyondTheRestWall) {
    const ColonTube tube = straight_tube(400.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    const WorldEffectView view = testing::three_node_view(tube);
    const double free_play = 15.0 - kScopeRadius;  // 8.35 mm: the node touches the rest wall there
    std::vector<NodalLoad> loads;
    MesentericRetraction({0.002, 1.0, 10.0}).add_scope_loads(view, loads);
    // Node 0: 12 mm off the axis along +y, carries 5 mm of scope (half an element at the end);
    // node 1: 20 mm along +z, carries 10 mm; the tip is 5 mm off the axis: inside the lumen, no force.
    ASSERT_EQ(loads.size(), 2u);
    EXPECT_EQ(loads[0].node, 0u);
    EXPECT_LT(
        (loads[0].force_N - Eigen::Vector3d(0.0, -0.002 * 5.0 * (12.0 - free_play), 0.0)).norm(),
        1e-14);
    EXPECT_EQ(loads[1].node, 1u);
    EXPECT_LT(
        (loads[1].force_N - Eigen::Vector3d(0.0, 0.0, -0.002 * 10.0 * (20.0 - free_play))).norm(),
        1e-14);
    EXPECT_NEAR(loads[1].force_N.z(), -0.233, 1e-12);  // 0.002 x 10 x 11.65
    EXPECT_EQ(loads[1].moment_Nmm.norm(), 0.0);

    // Nonlinear: k l e_ref (excess / e_ref)^p = 0.002 x 10 x 10 x 1.165^2.
    loads.clear();
    MesentericRetraction({0.002, 2.0, 10.0}).add_scope_loads(view, loads);
    ASSERT_EQ(loads.size(), 2u);
    EXPECT_NEAR(loads[1].force_N.z(), -0.002 * 10.0 * 10.0 * 1.165 * 1.165, 1e-12);

    // Only the sigmoid retracts; held nodes and nodes outside the body are left alone.
    const ColonTube descending = straight_tube(400.0, 15.0, ColonRegion::descending, kScopeRadius);
    loads.clear();
    MesentericRetraction({0.002, 1.0, 10.0})
        .add_scope_loads(testing::three_node_view(descending), loads);
    EXPECT_TRUE(loads.empty());
    WorldEffectView held = view;
    held.scope_node_held = {true, true, false};
    loads.clear();
    MesentericRetraction({0.002, 1.0, 10.0}).add_scope_loads(held, loads);
    EXPECT_TRUE(loads.empty());
    WorldEffectView shallow = view;
    shallow.insertion_depth_mm = 0.0;  // nothing past the anus
    loads.clear();
    MesentericRetraction({0.002, 1.0, 10.0}).add_scope_loads(shallow, loads);
    EXPECT_TRUE(loads.empty());
    // Zero stiffness: nothing.
    loads.clear();
    MesentericRetraction({0.0, 1.0, 10.0}).add_scope_loads(view, loads);
    EXPECT_TRUE(loads.empty());
}

TEST(WorldEffectSigmoidMobility, LoadAtAQuarterPeriodIsAmplitudeTimesLength) {
    const ColonTube tube = straight_tube(400.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    WorldEffectView view = testing::three_node_view(tube);
    const double f = 0.5, a = 0.01;
    view.time_s = 1.0 / (4.0 * f);  // sin(pi / 2) = 1
    std::vector<NodalLoad> loads;
    SigmoidMobility::Parameters p;
    p.amplitude_N_per_mm = a;
    p.frequency_Hz = f;
    p.direction = {0.0, 2.0, 0.0};  // normalised to +y
    p.phase_rad = 0.0;
    SigmoidMobility(p).add_scope_loads(view, loads);
    ASSERT_EQ(loads.size(), 3u);
    const double lengths[3] = {5.0, 10.0, 5.0};
    for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(loads[k].node, k);
        EXPECT_LT((loads[k].force_N - Eigen::Vector3d(0.0, a * lengths[k], 0.0)).norm(), 1e-15)
            << k;
    }
    // A quarter period later with phase pi / 2: sin(pi + pi / 2) = -1.
    p.phase_rad = M_PI / 2.0;
    view.time_s = 1.0 / (2.0 * f);
    loads.clear();
    SigmoidMobility(p).add_scope_loads(view, loads);
    ASSERT_EQ(loads.size(), 3u);
    EXPECT_NEAR(loads[1].force_N.y(), -a * 10.0, 1e-15);
    // Outside the sigmoid: nothing.
    const ColonTube rectum = straight_tube(400.0, 15.0, ColonRegion::rectum, kScopeRadius);
    loads.clear();
    SigmoidMobility(p).add_scope_loads(testing::three_node_view(rectum), loads);
    EXPECT_TRUE(loads.empty());
}

// --- in the world --------------------------------------------------------------------------------

/// Tip deflection of the scope inserted `inserted_mm` into a wide, straight tube under gravity,
/// handle held (the node at the anus is clamped on the entry axis): a cantilever.
double cantilever_tip_sag_mm(const std::vector<std::shared_ptr<const WorldEffect>>& effects,
                             double inserted_mm) {
    const ColonTube tube = straight_tube(400.0, 100.0, ColonRegion::descending, kScopeRadius);
    WorldSettings settings;
    settings.initial_insertion_mm = inserted_mm;
    World world(short_scope(), tube, default_colon_properties(), settings, effects);
    HandleCommand hold;
    hold.insertion_mm = inserted_mm;
    double before = 0.0;
    for (int i = 0; i < 600; ++i) {
        if (i == 590) before = world.node_position_mm(world.scope_node_count() - 1).z();
        const WorldStepReport r = world.step(hold);
        EXPECT_TRUE(r.ok) << r.failure;
        EXPECT_EQ(r.contacts, 0u);
    }
    const double sag = -world.node_position_mm(world.scope_node_count() - 1).z();
    EXPECT_NEAR(-before, sag, 1e-4 * sag);  // settled
    return sag;
}

TEST(WorldEffectEiScale, CantileverTipDeflectionFollowsTimoshenko) {
    // Closed form, uniform load w on a cantilever of length L: w L^4 / (8 EI) + w L^2 / (2 kappa G A).
    // w: the scope's weight per length under the world's gravity (9810 mm/s^2; the section's mass is
    // weight / 9806.65); kappa G A = 0.9 (GJ / J) A from the CF-Q160L's GJ and radius.
    const double length = 100.0;
    const double w = cf_q160l::kWeightPerLength_N_per_mm * 9810.0 / kGravity_mm_per_s2;
    const double r = kScopeRadius;
    const double area = M_PI * r * r, polar = M_PI * std::pow(r, 4) / 2.0;
    const double kga = 0.9 * (cf_q160l::kTorsionalStiffness_Nmm2 / polar) * area;
    const double ei = cf_q160l::kBendingStiffness_Nmm2;
    const double shear_part = w * length * length / (2.0 * kga);
    auto closed_form = [&](double factor) {
        return w * std::pow(length, 4) / (8.0 * factor * ei) + shear_part;
    };

    const double plain = cantilever_tip_sag_mm({}, length);
    const double scaled =
        cantilever_tip_sag_mm({std::make_shared<EiScale>(EiScale::Parameters{0.8})}, length);
    EXPECT_NEAR(plain, closed_form(1.0), 0.005 * closed_form(1.0));
    EXPECT_NEAR(scaled, closed_form(0.8), 0.005 * closed_form(0.8));
    // Euler-Bernoulli part alone: divided by 0.8.
    EXPECT_NEAR((scaled - shear_part) / (plain - shear_part), 1.0 / 0.8, 0.005);
}

/// Scope 300 mm into a straight, rigid (fixed) tube under gravity: it rests on the bottom wall.
constexpr double kResting_mm = 300.0;
World resting_scope(const std::vector<std::shared_ptr<const WorldEffect>>& effects) {
    const ColonTube tube = straight_tube(500.0, 15.0, ColonRegion::descending, kScopeRadius);
    WorldSettings settings;
    settings.initial_insertion_mm = kResting_mm;
    return World(short_scope(), tube, default_colon_properties(), settings, effects);
}

TEST(WorldEffectTissueStiffening, ScopeSinksIntoTheWallByTheExponentialLaw) {
    // The wall's indentation is the node's geometric penetration of the rigid tube's rest wall.
    const double c0 = WorldContactSettings{}.wall_compliance_mm_per_N, f_ref = 0.05;
    for (const bool stiffening : {false, true}) {
        std::vector<std::shared_ptr<const WorldEffect>> effects;
        if (stiffening)
            effects.push_back(
                std::make_shared<TissueStiffening>(TissueStiffening::Parameters{1.0 / f_ref}));
        World world = resting_scope(effects);
        HandleCommand hold;
        hold.insertion_mm = kResting_mm;
        for (int i = 0; i < 300; ++i)
            ASSERT_TRUE(world.step(hold).ok);
        std::size_t checked = 0;
        for (const WorldContact& c : world.contacts()) {
            if (!(c.normal_force_N > 0.02)) continue;
            const Eigen::Vector3d x = world.node_position_mm(c.scope_node);
            const double penetration = std::hypot(x.y(), x.z()) - (15.0 - kScopeRadius);
            const double f = c.normal_force_N;
            const double expected = stiffening ? c0 * f_ref * std::log(1.0 + f / f_ref) : c0 * f;
            EXPECT_NEAR(penetration, expected, 0.01 * expected + 1e-5)
                << "stiffening " << stiffening << " f " << f;
            ++checked;
        }
        EXPECT_GT(checked, 3u);
    }
}

TEST(WorldEffectViscoadhesive, SlidingScopeSeesTheSpeedDependentCoefficient) {
    // Advancing at v = 20 mm/s along a straight rigid tube, the shaft lying on the bottom wall slides
    // at about v: mu_eff = 0.25 + c_v |v_slide|. The sliding speed the hook sees is the node's motion
    // over the previous step across the contact normal (the rigid wall does not move), computed here
    // from the node's positions; on average it is the handle's speed, so mu_eff ~ 0.25 + 0.005 x 20.
    const double c_v = 0.005, v = 20.0, h = WorldSettings{}.time_step_s;
    World world = resting_scope(
        {std::make_shared<ViscoadhesiveFriction>(ViscoadhesiveFriction::Parameters{c_v, 1.0})});
    HandleCommand c;
    c.insertion_mm = kResting_mm;
    for (int i = 0; i < 100; ++i)
        ASSERT_TRUE(world.step(c).ok);
    auto positions = [&] {
        std::vector<Eigen::Vector3d> x;
        for (std::size_t k = 0; k < world.scope_node_count(); ++k)
            x.push_back(world.node_position_mm(k));
        return x;
    };
    std::vector<Eigen::Vector3d> two_ago = positions(), one_ago = positions();
    std::size_t checked = 0;
    double mu_sum = 0.0;
    for (int i = 1; i <= 200; ++i) {
        c.insertion_mm = kResting_mm + v * h * i;
        ASSERT_TRUE(world.step(c).ok);
        for (const WorldContact& k : world.contacts()) {
            if (i < 3 || !(k.normal_force_N > 0.0)) continue;
            const Eigen::Vector3d u = (one_ago[k.scope_node] - two_ago[k.scope_node]) / h;
            const double sliding = (u - u.dot(k.normal) * k.normal).norm();
            EXPECT_NEAR(k.friction_coefficient, 0.25 + c_v * sliding, 1e-9)
                << k.arc_from_tip_mm << " mm from the tip, step " << i;
            ++checked;
            mu_sum += k.friction_coefficient;
        }
        two_ago = std::move(one_ago);
        one_ago = positions();
    }
    ASSERT_GT(checked, 1000u);
    EXPECT_NEAR(mu_sum / static_cast<double>(checked), 0.25 + c_v * v, 0.1 * c_v * v);
}

std::vector<std::shared_ptr<const WorldEffect>> all_effects(bool zero_strength) {
    const nlohmann::json list = zero_strength ? nlohmann::json::parse(R"([
      {"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0},
      {"name": "mesenteric_retraction", "stiffness_N_per_mm2": 0, "exponent": 2},
      {"name": "ei_profile", "tip_factor": 1, "handle_factor": 1, "bending_section_length_mm": 100, "bending_section_factor": 1},
      {"name": "ei_scale", "factor": 1},
      {"name": "sigmoid_mobility", "amplitude_N_per_mm": 0, "frequency_Hz": 1, "phase_rad": 0.3},
      {"name": "tissue_stiffening", "stiffening_per_N": 0}])")
                                              : nlohmann::json::parse(R"([
      {"name": "viscoadhesive_friction"}, {"name": "mesenteric_retraction", "stiffness_N_per_mm2": 0.02},
      {"name": "ei_profile", "bending_section_length_mm": 100, "bending_section_factor": 0.7}, {"name": "ei_scale"},
      {"name": "sigmoid_mobility", "amplitude_N_per_mm": 0.02, "frequency_Hz": 1}, {"name": "tissue_stiffening"}])");
    return read_world_effects(list, "effects");
}

/// The scope advanced 150 mm into a sigmoid bend under gravity; every step's state recorded.
std::vector<Eigen::Vector3d> bend_run(
    const std::vector<std::shared_ptr<const WorldEffect>>& effects, std::size_t* contacts_seen,
    std::vector<double>* forces) {
    const ColonTube tube = single_bend(100.0, 40.0, 2.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    WorldSettings settings;
    settings.initial_insertion_mm = 50.0;
    World world(short_scope(), tube, default_colon_properties(), settings, effects);
    HandleCommand c;
    std::vector<Eigen::Vector3d> states;
    *contacts_seen = 0;
    for (int i = 1; i <= 150; ++i) {
        c.insertion_mm = 50.0 + 1.0 * i;
        const WorldStepReport r = world.step(c);
        EXPECT_TRUE(r.ok) << r.failure;
        if (!r.ok) break;
        *contacts_seen += r.contacts;
        for (std::size_t k = 0; k < world.scope_node_count(); ++k) {
            states.push_back(world.node_position_mm(k));
            states.push_back(world.node_velocity_mm_per_s(k));
        }
        for (const WorldContact& k : world.contacts()) {
            forces->push_back(k.normal_force_N);
            forces->push_back(k.tangential_force_N);
            forces->push_back(k.friction_coefficient);
        }
        forces->push_back(world.handle_force_N());
    }
    return states;
}

TEST(WorldEffectZeroStrength, EveryEffectAtZeroLeavesTheWorldBitIdentical) {
    std::size_t contacts_plain = 0, contacts_zero = 0, contacts_on = 0;
    std::vector<double> forces_plain, forces_zero, forces_on;
    const auto plain = bend_run({}, &contacts_plain, &forces_plain);
    const auto zero = bend_run(all_effects(true), &contacts_zero, &forces_zero);
    ASSERT_GT(contacts_plain, 100u);  // the hooks on contacts were exercised
    ASSERT_EQ(plain.size(), zero.size());
    for (std::size_t i = 0; i < plain.size(); ++i)
        ASSERT_TRUE(plain[i] == zero[i]) << "state " << i;
    EXPECT_EQ(contacts_plain, contacts_zero);
    EXPECT_TRUE(forces_plain == forces_zero);
    // At their defaults (stronger where noted) the effects run and change the world.
    const auto on = bend_run(all_effects(false), &contacts_on, &forces_on);
    ASSERT_EQ(on.size(), plain.size());
    double largest = 0.0;
    for (std::size_t i = 0; i < plain.size(); i += 2)
        largest = std::max(largest, (on[i] - plain[i]).norm());
    EXPECT_GT(largest, 0.1);
}

// --- scenario files ------------------------------------------------------------------------------

nlohmann::json scenario_with_effects() {
    return nlohmann::json::parse(R"({
    "colon": {"bundled": "single_bend", "lead_mm": 100, "bend_radius_mm": 40, "bend_angle_deg": 115,
              "inner_radius_mm": 15},
    "scope": {"model": "cf_q160l", "length_mm": 300, "elements": 30},
    "initial_insertion_mm": 40,
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 0.3, "speed_mm_per_s": 50}],
    "truth_effects": [
      {"name": "ei_scale", "factor": 0.9},
      {"name": "viscoadhesive_friction", "viscous_coefficient_s_per_mm": 0.004, "max_friction_increase": 0.1},
      {"name": "sigmoid_mobility", "amplitude_N_per_mm": 0.002, "frequency_Hz": 0.3, "direction": [0, 0, 1]}
    ]
  })");
}

TEST(WorldEffectScenario, TruthEffectsAreReadAndBuilt) {
    const Scenario s = read_scenario(scenario_with_effects(), "s.json");
    ASSERT_EQ(s.effects.size(), 3u);
    EXPECT_EQ(s.effects[0]->name(), "ei_scale");
    EXPECT_EQ(s.effects[0]->parameters(), nlohmann::json({{"factor", 0.9}}));
    EXPECT_EQ(s.effects[1]->name(), "viscoadhesive_friction");
    EXPECT_EQ(s.effects[2]->name(), "sigmoid_mobility");
    auto world = build_world(s);
    const SimulationSummary sum = run_simulation(*world, s, {});
    EXPECT_TRUE(sum.complete) << sum.message;
    EXPECT_EQ(sum.steps, 30u);
    // Without the key: no effects.
    nlohmann::json doc = scenario_with_effects();
    doc.erase("truth_effects");
    EXPECT_TRUE(read_scenario(doc, "s.json").effects.empty());
}

TEST(WorldEffectScenario, BadTruthEffectsNameTheirPath) {
    auto expect = [](const nlohmann::json& doc, const std::string& fragment) {
        try {
            read_scenario(doc, "s.json");
            ADD_FAILURE() << "accepted; expected " << fragment;
        } catch (const ModelError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    nlohmann::json doc = scenario_with_effects();
    doc["truth_effects"].push_back({{"name", "ei_scale"}});
    expect(
        doc,
        "s.json: truth_effects[3].name: 'ei_scale' is already given in s.json: truth_effects[0]");
    doc = scenario_with_effects();
    doc["truth_effects"][1]["bogus"] = 1;
    expect(doc, "s.json: truth_effects[1].bogus: unknown key");
    doc = scenario_with_effects();
    doc["truth_effects"][0]["factor"] = -0.9;
    expect(doc, "s.json: truth_effects[0].factor");
    doc = scenario_with_effects();
    doc["truth_effects"] = {{"name", "ei_scale"}};
    expect(doc, "s.json: truth_effects: expected an array");
}

}  // namespace
}  // namespace scopekin::model
