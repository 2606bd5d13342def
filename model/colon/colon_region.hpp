#pragma once
// The named regions of the colon, in order from the anus (thesis 4.3, model/PHYSICS.md §3.2), and
// their mechanical properties.
#include <array>
#include <optional>
#include <string_view>

namespace scopekin::model {

enum class ColonRegion {
    rectum,
    sigmoid,
    descending,
    splenic_flexure,
    transverse,
    hepatic_flexure,
    ascending,
    cecum
};

inline constexpr std::array<ColonRegion, 8> kColonRegionsInOrder{
    ColonRegion::rectum,          ColonRegion::sigmoid,    ColonRegion::descending,
    ColonRegion::splenic_flexure, ColonRegion::transverse, ColonRegion::hepatic_flexure,
    ColonRegion::ascending,       ColonRegion::cecum};

std::string_view region_name(ColonRegion region);
std::optional<ColonRegion> region_from_name(std::string_view name);

/// How a region hangs in the abdomen: fixed to the retroperitoneum (rectum, descending,
/// ascending) or mobile on a mesentery (sigmoid, transverse; the flexures and the cecum are
/// treated as fixed: they are tethered by ligaments).
enum class ColonAttachment {
    fixed,
    mesentery
};

struct ColonRegionProperties {
    double young_modulus_kPa = 0;  ///< longitudinal, porcine, thesis Table 4.6
    double wall_thickness_mm = 0;
    ColonAttachment attachment = ColonAttachment::fixed;
    /// Mesentery stiffness per unit length of colon [N/mm per mm] (0 for fixed regions).
    double mesentery_stiffness_N_per_mm2 = 0;
};

/// Defaults. Young's modulus: thesis Table 4.6, longitudinal (flexures take the neighbouring
/// region's value: splenic -> descending, hepatic -> ascending; cecum -> ascending).
/// Wall thickness 2 mm: the distended colon wall is < 3 mm at CT.
/// Mesentery stiffness: not measured anywhere we know; a stated guess of 2e-3 N/mm per mm of
/// colon, i.e. a 10 cm loop pulled with 2 N moves 10 mm, the same order as the 6-7 cm mesocolon
/// heights (sigmoid 6.3 cm, transverse 7.4 cm; Ann R Coll Surg Engl 2015;97:439) lets it travel.
ColonRegionProperties default_region_properties(ColonRegion region);

}  // namespace scopekin::model
