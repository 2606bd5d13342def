#pragma once
// Verification of the frictional contact (thesis 4.4) and of the scope in the colon, for
// `scopekin verify` and the tests: the Gauss-Seidel solver against closed forms and an
// active-set enumeration, and the world against geometry and the self-locking criterion.
#include <vector>

#include "model/verification/verification_row.hpp"
#include "model/world/world.hpp"

namespace scopekin::model::contact_verification {

/// Single-contact closed forms (separation, stick, slip), 1000 random well-posed problems
/// (residuals below tolerance), frictionless problems against active-set enumeration.
std::vector<VerificationRow> lcp_rows();

/// What a scope pushed through a tube did.
struct PushResult {
    bool ok = false;
    std::string failure;
    std::size_t steps = 0;
    double max_normal_force_N = 0;
    double max_lateral_tip_deviation_mm = 0;  ///< tip distance from the entry axis (straight tube)
    std::size_t loaded_contacts_in_bend = 0;
    std::size_t loaded_contacts_on_outer_wall = 0;
    double max_penetration_mm = 0;     ///< linearised, after correction
    double max_friction_work_Nmm = 0;  ///< per step; <= 0 when friction only dissipates
    double handle_advance_mm = 0;      ///< over the final window
    double tip_advance_mm = 0;         ///< along the colon at rest, over the final window
    double tip_sliding_mm = 0;         ///< tip contact's slip relative to the wall, final window
    double tip_driving_angle_rad = 0;  ///< at the end, at the tip contact
    bool tip_sticking = false;         ///< tip contact in stick at the end
    double handle_force_N = 0;         ///< at the end
};

/// Pushes a 600 mm CF-Q160L (60 elements) at 50 mm/s for `duration_s` into a rigid straight
/// tube (bend_angle_rad = 0) or a single bend of centerline radius 40 mm in a sigmoid-like tube
/// (mobile on its mesentery), inner radius 15 mm, no gravity, friction mu; the final window
/// for the advance ratios is the last `window_s`.
PushResult push_through_tube(double bend_angle_rad, double mu, double duration_s, double window_s);

/// Straight tube: no wall contact; bend: contact on the outer wall; self-locking with mu above
/// and below the friction angle criterion; no penetration; friction only dissipates.
std::vector<VerificationRow> world_rows();

}  // namespace scopekin::model::contact_verification
