// Compile-only check, built on EVERY preset with the firmware flags (cmake/firmware_flags.cmake:
// strict warnings, -fno-exceptions, -fno-rtti): the contact solver template,
// explicitly instantiated for float, double and the firmware's Q16_16.  On host/asan/aarch64 the
// float and Q16_16 test executables are built with GoogleTest (exceptions on), so this object
// library is what proves the firmware build of the header there.  Nothing links it.
#include "contact/gauss_seidel_contact.hpp"

namespace scopekin::contact {

template ContactSolveReport<float, 16> solve_contacts<float, 16>(
    const ContactProblem<float, 16>&, const GaussSeidelSettings<float>&,
    ContactForces<float, 16>&) noexcept;
template ContactResiduals<float> evaluate_contact_residuals<float, 16>(
    const ContactProblem<float, 16>&, const ContactForces<float, 16>&) noexcept;
template LocalContactSolution<float> solve_local_contact<float>(const ContactBlock3<float>&,
                                                                const ContactVec3<float>&, float,
                                                                std::size_t, bool,
                                                                const ContactVec3<float>*) noexcept;
template ContactSolveReport<double, 16> solve_contacts<double, 16>(
    const ContactProblem<double, 16>&, const GaussSeidelSettings<double>&,
    ContactForces<double, 16>&) noexcept;
template ContactSolveReport<fixed_point::Q16_16, 16> solve_contacts<fixed_point::Q16_16, 16>(
    const ContactProblem<fixed_point::Q16_16, 16>&, const GaussSeidelSettings<fixed_point::Q16_16>&,
    ContactForces<fixed_point::Q16_16, 16>&) noexcept;
template ContactResiduals<fixed_point::Q16_16> evaluate_contact_residuals<fixed_point::Q16_16, 16>(
    const ContactProblem<fixed_point::Q16_16, 16>&,
    const ContactForces<fixed_point::Q16_16, 16>&) noexcept;
template LocalContactSolution<fixed_point::Q16_16> solve_local_contact<fixed_point::Q16_16>(
    const ContactBlock3<fixed_point::Q16_16>&, const ContactVec3<fixed_point::Q16_16>&,
    fixed_point::Q16_16, std::size_t, bool, const ContactVec3<fixed_point::Q16_16>*) noexcept;

}  // namespace scopekin::contact
