#pragma once
// How short the scope's path to the cecum can get when the colon's mobile regions are straightened
// and nothing else gives: every maximal run of segments on a mesentery (sigmoid, transverse; the
// descending and ascending colon when a patient has them mobile) is replaced by the straight line
// between the fixed points at its ends, and the scope follows the centerline everywhere else.
// It is a lower bound on the insertion at cecal intubation that a straightened scope with the mobile
// regions pleated onto it can reach, before any corner cutting inside the lumen (at most about a
// lumen radius per flexure) and before any shortening of the fixed regions. Standard teaching puts
// the straightened scope at the cecum with 70-90 cm inserted (Cotton & Williams, Practical
// Gastrointestinal Endoscopy, ch. 7); a colon whose bound is longer cannot show that by pleating of
// its mobile regions alone (model/patient/README.md, "Derived measures").
#include <array>
#include <vector>

#include "model/colon/colon_region.hpp"
#include "model/colon/colon_tube.hpp"

namespace scopekin::model {

/// The path length [mm] from the first centerline point to the last with every run of mesentery
/// segments (segment k runs from point k to k + 1 and has point k's region) replaced by its chord.
double straightened_path_mm(const std::vector<ColonPoint>& points,
                            const std::array<ColonRegionProperties, 8>& properties);

}  // namespace scopekin::model
