#pragma once
// What the sensors and the outputs read off the world after a step: the handle's signals, the
// poses where the test bed's EM sensors sit, the tip's contact force, and where the tip is along
// the colon. Positions in the colon (body) frame [mm], forces [N], torque [N mm], angles [rad].
//
// EM sensor poses (thesis test bed, model/PHYSICS.md §6): S1 the tip node, S2 the node 200 mm from
// the tip, S3 the handle end of the shaft (node 0, where the box sits), S4 a point sutured on the
// sigmoid (the colon centerline halfway along the sigmoid, displaced with the colon). A node's
// orientation is the shortest rotation taking +x to the scope's axis there, then the handle's
// roll about that axis (torsion along the shaft is small, GJ/L ~ 4 N mm/rad per m, and is left
// out); S4's is the shortest rotation taking +x to the colon's tangent.
#include <Eigen/Dense>
#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/world/world.hpp"

namespace scopekin::host_sim {

/// Wall forces on the scope within this distance of the tip make the "tip contact force" (the
/// firmware's tip station carries the resultant of its 50 mm stretch, half on each side).
inline constexpr double kTipStretch_mm = 25.0;

struct Pose {
    Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

enum EmSensorIndex : std::size_t {
    kEmTip = 0,
    kEm20cm = 1,
    kEmHandle = 2,
    kEmSigmoid = 3
};

struct WorldReadout {
    double time_s = 0;
    double handle_force_N = 0;
    double handle_torque_Nmm = 0;
    double insertion_mm = 0;
    double roll_rad = 0;
    std::array<Pose, 4> em;
    Eigen::Vector3d tip_force_N =
        Eigen::Vector3d::Zero();  ///< resultant wall force on the tip stretch
    double tip_path_mm = 0;       ///< the tip's closest centerline point, arc length from the anus
    std::string tip_region;       ///< region there
};

/// Reads the world after a step. Keeps the tip's place along the colon from one call to the
/// next, so the tip is never matched to another turn of a loop that happens to be near.
class WorldReader {
public:
    explicit WorldReader(const model::World& world);
    WorldReadout read(const model::World& world);
    /// A snapshot for snapshots.json: the inserted scope, the displaced colon, the loaded contacts.
    nlohmann::ordered_json snapshot(const model::World& world, const std::string& label) const;
    /// The colon at rest for snapshots.json.
    static nlohmann::ordered_json colon_json(const model::ColonTube& colon);

private:
    double locate_tip(const Eigen::Vector3d& tip_mm, std::string& region);
    const model::ColonTube* colon_ = nullptr;  // the world's, at rest, body frame
    std::size_t sigmoid_point_ = 0;
    std::size_t node_20cm_ = 0;
    double tip_path_mm_ = 0;
};

/// Linear blend of two readouts (positions, forces, handle signals; orientations by nlerp):
/// the sensors sample at 1 kHz between world steps.
WorldReadout blend(const WorldReadout& a, const WorldReadout& b, double weight_b);

}  // namespace scopekin::host_sim
