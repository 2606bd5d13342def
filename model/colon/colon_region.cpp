#include "model/colon/colon_region.hpp"

namespace scopekin::model {

std::string_view region_name(ColonRegion region) {
    switch (region) {
        case ColonRegion::rectum: return "rectum";
        case ColonRegion::sigmoid: return "sigmoid";
        case ColonRegion::descending: return "descending";
        case ColonRegion::splenic_flexure: return "splenic_flexure";
        case ColonRegion::transverse: return "transverse";
        case ColonRegion::hepatic_flexure: return "hepatic_flexure";
        case ColonRegion::ascending: return "ascending";
        case ColonRegion::cecum: return "cecum";
    }
    return "unknown";
}

std::optional<ColonRegion> region_from_name(std::string_view name) {
    for (ColonRegion r : kColonRegionsInOrder)
        if (region_name(r) == name) return r;
    return std::nullopt;
}

ColonRegionProperties default_region_properties(ColonRegion region) {
    constexpr double kWall_mm = 2.0;
    constexpr double kMesentery_N_per_mm2 = 2e-3;
    switch (region) {
        case ColonRegion::rectum: return {398.0, kWall_mm, ColonAttachment::fixed, 0.0};
        case ColonRegion::sigmoid:
            return {360.0, kWall_mm, ColonAttachment::mesentery, kMesentery_N_per_mm2};
        case ColonRegion::descending: return {318.0, kWall_mm, ColonAttachment::fixed, 0.0};
        case ColonRegion::splenic_flexure: return {318.0, kWall_mm, ColonAttachment::fixed, 0.0};
        case ColonRegion::transverse:
            return {892.0, kWall_mm, ColonAttachment::mesentery, kMesentery_N_per_mm2};
        case ColonRegion::hepatic_flexure: return {781.0, kWall_mm, ColonAttachment::fixed, 0.0};
        case ColonRegion::ascending: return {781.0, kWall_mm, ColonAttachment::fixed, 0.0};
        case ColonRegion::cecum: return {781.0, kWall_mm, ColonAttachment::fixed, 0.0};
    }
    return {};
}

}  // namespace scopekin::model
