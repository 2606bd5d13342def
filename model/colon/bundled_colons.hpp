#pragma once
// Colons that ship with scopekin: a human-like default colon and two simple tubes for tests.
#include "model/colon/colon_tube.hpp"

namespace scopekin::model {

/// Default colon, anus to cecum, centerline sampled every 10 mm. Frame: origin at the anus,
/// x to the patient's left, y cranial, z anterior (patient supine), mm.
/// Dimensions (documented in model/PHYSICS.md §3.3):
///  - total length 1.60 m: CT colonography mean 150.3 +- 18.5 cm (Utano et al., Jpn J Radiol
///    2022;40:298); transverse the longest segment, then the sigmoid (cadaver study, Ann R Coll
///    Surg Engl 2015;97:439);
///  - a redundant sigmoid (40 cm) forming an anterior loop in the pelvis, the loop-prone case;
///    transverse 42 cm, descending 25 cm, ascending 15 cm, rectum 16 cm;
///  - lumen diameters: cecum/ascending ~46 mm, transverse ~44 mm, descending ~30 mm, sigmoid
///    ~28 mm, narrowing to 25 mm at the sigmoid-descending junction (model/PHYSICS.md §3.3; CT median
///    diameters ascending 46 mm, descending 29 mm), rectum ~36 mm.
ColonTube default_colon(double scope_radius_mm);

/// A straight tube along +x from the origin (region `region`), for tests.
ColonTube straight_tube(double length_mm, double inner_radius_mm, ColonRegion region,
                        double scope_radius_mm);

/// A straight entry of `lead_mm` along +x, then a circular bend of centerline radius
/// `bend_radius_mm` through `bend_angle_rad` in the x-y plane (turning towards +y), then a straight
/// exit of `lead_mm`; for tests of contact on the outer wall and of self-locking.
ColonTube single_bend(double lead_mm, double bend_radius_mm, double bend_angle_rad,
                      double inner_radius_mm, ColonRegion region, double scope_radius_mm);

}  // namespace scopekin::model
