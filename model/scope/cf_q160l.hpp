#pragma once
// Olympus CF-Q160L adult colonoscope: the one documented place for its parameters
// (thesis 4.2, App. B, F, H, I; model/PHYSICS.md §2.5). Units: mm, N, s, t.
//
// Choices where the thesis is inconsistent:
// * Radius 6.65 mm (App. F code); App. B's "diameter 13.6 mm" differs by 0.15 mm. Only the
//   contact geometry and the mass/rotary-inertia ratios use it.
// * EI = 350 N cm^2 = 35 000 N mm^2, the average the thesis uses for its ch. 5 validation;
//   App. F/I code uses 400 N cm^2, and the measured range is 260-660 N cm^2 (distal part softer).
// * Weight per length 4 N per 350 mm = 0.011 43 N/mm (App. B), because it is stated as a weight
//   of a length of this scope; App. I's "0.4 kg for 300 mm" (0.0131 N/mm) comes with a 200 mm
//   beam in the same code and is not self-consistent. The cantilever check (scopekin verify)
//   fits EI / weight and reports what the measured shape supports.
// * GJ = 7000 N mm^2 (Hellier et al. 2011, as quoted in thesis 4.2.2 and 5.3, Step 2).
// * EA: App. F derives E = EI / I and uses E A; that gives EA = 3.17 kN (a 45 N push shortens
//   the scope by 1.4 %). Kept as the thesis's choice.
// * Transverse shear: not measured. The shear modulus is taken from the torsion test,
//   G = GJ / J, with kappa = 0.9 (solid circle), i.e. kappa G A = 285 N. This makes shear
//   matter only below ~1 cm wavelengths (sqrt(EI / kappa G A) = 11 mm).
// * Rayleigh damping alpha = 0.3864, beta = 0.0164 in the thesis's Hz convention (Eq. 4.15),
//   converted in rayleigh_damping.hpp.
#include "model/beam/beam_section.hpp"
#include "model/solvers/rayleigh_damping.hpp"

namespace scopekin::model::cf_q160l {

inline constexpr double kRadius_mm = 6.65;
inline constexpr double kBendingStiffness_Nmm2 = 35000.0;  ///< 350 N cm^2
inline constexpr double kBendingStiffnessAppF_Nmm2 = 40000.0;
inline constexpr double kTorsionalStiffness_Nmm2 = 7000.0;
inline constexpr double kWeightPerLength_N_per_mm = 4.0 / 350.0;
inline constexpr double kShearCorrection = 0.9;
inline constexpr double kWorkingLength_mm = 1700.0;

/// Section with the parameters above (EI can be overridden, e.g. for the 260-660 N cm^2 range).
BeamSection section(double bending_stiffness_Nmm2 = kBendingStiffness_Nmm2,
                    double weight_per_length_N_per_mm = kWeightPerLength_N_per_mm);

RayleighDamping damping();

}  // namespace scopekin::model::cf_q160l
