#pragma once
// Virtual patients (model/patient/README.md): a colon and a scope drawn from a documented family,
// reproducible from a seed. A patient is an ordinary scenario colon: a ColonTube (same checks as
// any scenario colon), per-region properties (ColonRegionProperties), a friction coefficient and
// the scope's bending stiffness factors, which a scenario applies as an "ei_profile" effect.
//
// Geometry: the centerline is built region by region from straight runs and circular arcs whose
// lengths add up exactly to the drawn region lengths (each sampled as equal chords of at most
// 10 mm), so the colon's length is the sum of its eight drawn region lengths.
#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/colon/colon_region.hpp"
#include "model/colon/colon_tube.hpp"
#include "model/io/strict_json.hpp"

namespace scopekin::model {

/// The resting sigmoid's loop: in the frontal plane (N-prone) or turned towards the sagittal
/// plane, its limbs one in front of the other (alpha-prone); model/patient/README.md.
enum class SigmoidShape {
    n_prone,
    alpha_prone
};

struct PatientSpec {
    std::uint64_t seed = 0;   ///< the seed it was drawn from (informative in a file)
    std::size_t redraws = 0;  ///< draws refused before this one (model/patient/README.md)

    // Geometry.
    std::array<double, 8> region_length_mm{};  ///< along the centerline, kColonRegionsInOrder order
    std::array<double, 8> lumen_radius_mm{};   ///< inner radius per region
    SigmoidShape sigmoid_shape = SigmoidShape::n_prone;
    double sigmoid_loop_radius_mm = 30;     ///< radius of the loop's turn
    double sigmoid_loop_tilt_deg = 15;      ///< loop plane out of the frontal plane
    double splenic_flexure_angle_deg = 45;  ///< interior angle, descending vs transverse limb
    double hepatic_flexure_angle_deg = 60;  ///< interior angle, transverse limb vs ascending
    double transverse_sag_mm = 120;         ///< lowest transverse point below the splenic flexure

    // Mechanics.
    double friction_coefficient = 0.25;  ///< scope on mucosa, whole scope
    double wall_modulus_factor = 1;      ///< times Table 4.6's modulus, every region
    /// Times the default mesentery stiffness (2e-3 N/mm per mm), per region that can be mobile:
    /// sigmoid, transverse, descending, ascending (the last two used only when mobile; the
    /// ascending factor also serves the cecum, which moves with it).
    std::array<double, 4> mesentery_factor{1, 1, 1, 1};
    bool descending_mobile = false;  ///< on a mesentery instead of fixed
    bool ascending_mobile = false;   ///< ascending colon and cecum on a mesentery

    // Scope.
    double ei_factor = 1;                 ///< bending stiffness times this, whole scope
    double distal_section_length_mm = 0;  ///< softer distal section; 0 = none
    double distal_section_factor = 1;     ///< its extra EI factor

    double total_length_mm() const;
};

/// Indices into PatientSpec::mesentery_factor.
enum class MobileRegion : std::size_t {
    sigmoid = 0,
    transverse = 1,
    descending = 2,
    ascending = 3
};

/// Draws the patient of `seed`: attempt k = 0, 1, ... draws from std::mt19937_64 seeded with
/// patient_sub_seed(seed, k) until a draw passes every check (patient_problem); `redraws` is k.
/// Throws ModelError after kMaxPatientDraws refused draws (never seen for any seed tested).
PatientSpec draw_patient(std::uint64_t seed);
/// As draw_patient, also returning why each refused draw was refused.
PatientSpec draw_patient(std::uint64_t seed, std::vector<std::string>& refusals);
inline constexpr std::size_t kMaxPatientDraws = 1000;
/// splitmix64(seed + k * 0x9E3779B97F4A7C15): the engine seed of draw k of `seed`.
std::uint64_t patient_sub_seed(std::uint64_t seed, std::size_t k);

/// The centerline (points every <= 10 mm, regions and radii) of a patient; no checks.
std::vector<ColonPoint> patient_centerline(const PatientSpec& p);
/// The patient's colon: ColonTube named "patient <seed>" (ModelError for an impossible colon).
ColonTube patient_colon(const PatientSpec& p, double scope_radius_mm);
/// Region properties: Table 4.6 modulus x factor, the default wall, attachments and mesentery
/// stiffness (default x factor) per model/patient/README.md.
std::array<ColonRegionProperties, 8> patient_colon_properties(const PatientSpec& p);

/// Smallest radius of curvature of a centerline: the circumradius of every three consecutive
/// points [mm] (infinite for a straight line), and the index of the middle point.
std::pair<double, std::size_t> smallest_bend_radius_mm(const std::vector<ColonPoint>& points);
/// No patient bends tighter than the default colon's tightest bend (13.4 mm), which the scope
/// passes in the demo (model/patient/README.md).
inline constexpr double kMinPatientBendRadius_mm = 13.0;

/// Why a patient is not acceptable ("" if it is): a parameter outside its range, a transverse
/// colon too narrow or too wide, a cecum below the anus, a bend tighter than
/// kMinPatientBendRadius_mm, or a colon that ColonTube refuses (self-intersection, lumen).
/// `scope_radius_mm`: the CF-Q160L's radius in draw_patient.
std::string patient_problem(const PatientSpec& p, double scope_radius_mm);

/// Derived measures (model/patient/README.md), for reports and tests.
struct PatientMeasures {
    double sigmoid_chord_mm = 0;           ///< straight distance between the sigmoid's ends
    double sigmoid_redundancy = 0;         ///< 1 - chord / sigmoid length
    double transverse_sag_mm = 0;          ///< measured on the centerline
    double transverse_width_mm = 0;        ///< |x| distance, transverse start to end
    double splenic_flexure_angle_deg = 0;  ///< measured between the neighbouring straight runs
    double hepatic_flexure_angle_deg = 0;
    double smallest_bend_radius_mm = 0;
    double lowest_y_mm = 0;  ///< lowest point cranial of the anus (y, mm)
    /// The scope's path to the cecal pole with the mobile regions drawn straight
    /// (model/colon/straightened_path.hpp): the least insertion at the cecum pleating gives [mm].
    double straightened_path_mm = 0;
};
PatientMeasures measure_patient(const PatientSpec& p);

/// The patient as JSON (model/patient/README.md), with "derived": {"total_length_mm": ...}.
nlohmann::ordered_json patient_to_json(const PatientSpec& p);
/// Reads a patient strictly: every key required, ranges as documented, "derived" (optional)
/// must match; `path` names the document in messages. ModelError naming the field.
PatientSpec read_patient(const nlohmann::json& document, const std::string& path);
/// A seed: a JSON whole number from 0 to 2^64 - 1 (ModelError naming the field otherwise).
std::uint64_t read_patient_seed(const io::JsonObject& o, const char* key);
/// Reads a patient file (strict JSON, model/io/strict_json.hpp).
PatientSpec read_patient_file(const std::string& filename);

std::string_view sigmoid_shape_name(SigmoidShape shape);

}  // namespace scopekin::model
