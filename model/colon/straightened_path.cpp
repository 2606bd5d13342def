#include "model/colon/straightened_path.hpp"

namespace scopekin::model {

double straightened_path_mm(const std::vector<ColonPoint>& points,
                            const std::array<ColonRegionProperties, 8>& properties) {
    auto on_mesentery = [&](std::size_t segment) {
        return properties[static_cast<std::size_t>(points[segment].region)].attachment ==
               ColonAttachment::mesentery;
    };
    double path_mm = 0.0;
    std::size_t k = 0;
    while (k + 1 < points.size()) {
        std::size_t end = k + 1;  // the point where this run of like segments ends
        if (on_mesentery(k))
            while (end + 1 < points.size() && on_mesentery(end))
                ++end;
        // A mobile run is drawn straight between its fixed ends; a fixed segment is its chord.
        path_mm += (points[end].position_mm - points[k].position_mm).norm();
        k = end;
    }
    return path_mm;
}

}  // namespace scopekin::model
