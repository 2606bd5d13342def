#pragma once
// Building the firmware's reduced-order model from the full-order one (trajectory piecewise-
// linear reduction: firmware/kinetics/reduced_kinetics.hpp explains the model and its step).
// A training scenario (a slow advance through the colon) is run in the full-order world; at
// every grid depth the state is probed at K stations (World::probe_stations) and written as one
// record of the firmware's table layout. The result is plain double data, which
//   * the host uses directly (the "reduced double" model of the accuracy tests), and
//   * reduced_table_writer turns into the firmware's Q16.16 constant tables.
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "kinetics/reduced_kinetics.hpp"  // firmware/: layout of a record
#include "model/scenario/scenario.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

struct ReductionSettings {
  std::size_t stations = 12;           ///< K: station j is j * spacing from the tip
  double station_spacing_mm = 50.0;
  double depth_start_mm = 30.0;        ///< first grid depth
  double depth_step_mm = 10.0;         ///< grid step (a multiple of the training's depth per step)
  double depth_end_mm = 750.0;         ///< last grid depth (<= where the training procedure goes)
  void validate() const;
};

/// The reduced model's data in double: header + one record per grid depth.
class ReducedModelData {
 public:
  std::string training_source;        ///< the training scenario file
  std::string colon_name;
  ReductionSettings settings;
  kinetics::ReducedModelHeader<double> head;
  std::vector<std::vector<double>> records;  ///< [grid point][index in record]

  const kinetics::ReducedModelHeader<double>& header() const { return head; }
  double value(std::size_t grid_point, std::size_t index) const { return records[grid_point][index]; }
};

struct ReductionProgress {
  double depth_mm = 0;
  double end_depth_mm = 0;
};

/// Runs the training scenario (a world scenario whose procedure must take the depth past
/// settings.depth_end_mm under position control) and probes the grid. Throws ModelError if the
/// training run fails or never reaches a grid depth.
ReducedModelData build_reduced_model(const Scenario& training, const ReductionSettings& settings,
                                     const std::function<void(const ReductionProgress&)>& on_progress = {});

/// Scope nodes of the stations, station 0 (the tip) first.
std::vector<std::size_t> station_nodes(const World& world, const ReductionSettings& settings);

/// The full-order world's contact forces gathered per station: the resultant of the wall forces
/// on the scope over the station's stretch (arc from the tip in [sigma - spacing/2, sigma +
/// spacing/2)), in the station's frame (n, t, s) [N]. `probe` = World::probe_stations of the
/// station nodes in increasing node order (station K-1 first).
std::vector<Eigen::Vector3d> station_forces(const World& world, const StationCompliance& probe,
                                            const ReductionSettings& settings);

}  // namespace scopekin::model
