#include "model/reduction/reduced_model.hpp"

#include <cmath>
#include <sstream>

#include "model/model_error.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::model {

void ReductionSettings::validate() const {
  if (stations < 1 || stations > 64) throw ModelError("reduction.stations: must be in [1, 64]");
  require_positive(station_spacing_mm, "reduction.station_spacing_mm");
  require_non_negative(depth_start_mm, "reduction.depth_start_mm");
  require_positive(depth_step_mm, "reduction.depth_step_mm");
  if (!(depth_end_mm >= depth_start_mm + depth_step_mm))
    throw ModelError("reduction.depth_end_mm: must be at least one grid step past depth_start_mm");
}

std::vector<std::size_t> station_nodes(const World& world, const ReductionSettings& settings) {
  const std::size_t tip = world.scope_node_count() - 1;
  const double element_mm = world.scope_length_mm() / static_cast<double>(tip);
  std::vector<std::size_t> nodes;
  for (std::size_t j = 0; j < settings.stations; ++j) {
    const double steps = settings.station_spacing_mm * static_cast<double>(j) / element_mm;
    const auto back = static_cast<std::size_t>(std::lround(steps));
    if (std::fabs(steps - static_cast<double>(back)) > 1e-9 || back > tip)
      throw ModelError("reduction.station_spacing_mm: stations must fall on scope nodes (element length " +
                       number_text(element_mm) + " mm) and on the scope");
    nodes.push_back(tip - back);
  }
  return nodes;
}

std::vector<Eigen::Vector3d> station_forces(const World& world, const StationCompliance& probe,
                                            const ReductionSettings& settings) {
  const std::size_t k = settings.stations;
  std::vector<Eigen::Vector3d> body(k, Eigen::Vector3d::Zero());
  const double half = 0.5 * settings.station_spacing_mm;
  for (const WorldContact& c : world.contacts()) {
    const double j = std::floor((c.arc_from_tip_mm + half) / settings.station_spacing_mm);
    if (j < 0.0 || j >= static_cast<double>(k)) continue;
    body[static_cast<std::size_t>(j)] += c.force_N;
  }
  std::vector<Eigen::Vector3d> local(k, Eigen::Vector3d::Zero());
  for (std::size_t j = 0; j < k; ++j) local[j] = probe.stations[k - 1 - j].frame.transpose() * body[j];
  return local;
}

namespace {

/// A stretch "slid" between two grid depths if its path position advanced by more than this
/// fraction of the depth step (the tip advances ~1 mm per mm while sliding, ~0 when stuck).
constexpr double kSlidThreshold = 0.2;
/// A station's force is the resultant over a curved stretch whose nodes' normals spread, so it
/// can lie outside the mu-cone of the station frame; where the stretch stuck, the station's cone
/// is widened to hold it with this margin.
constexpr double kStuckMargin = 1.05;

/// One grid record in the firmware's layout (station 0 = tip first).
std::vector<double> record_of(World& world, const std::vector<std::size_t>& nodes_increasing,
                              const ReductionSettings& settings, std::vector<bool>& inside) {
  const std::size_t k = settings.stations;
  const StationCompliance probe = world.probe_stations(nodes_increasing);
  const std::vector<Eigen::Vector3d> forces = station_forces(world, probe, settings);
  std::vector<double> record(kinetics::reduced_record_size(k), 0.0);
  inside.assign(k, false);
  for (std::size_t j = 0; j < k; ++j) {
    const StationProbe& p = probe.stations[k - 1 - j];
    inside[j] = p.inside;
    const std::size_t base = j * kinetics::kStationValueCount;
    record[base + kinetics::kStationPath] = p.path_mm;
    // A station whose stretch carries a wall force is in contact: its gap is 0 even when its own
    // node (the stretch's centre) stands off the wall.
    record[base + kinetics::kStationGap] = forces[j](0) > 0.0 ? 0.0 : std::max(0.0, p.gap_mm);
    for (std::size_t c = 0; c < 3; ++c) record[base + kinetics::kStationForceN + c] = forces[j](static_cast<Eigen::Index>(c));
  }
  const Eigen::Vector3d tip = world.node_position_mm(world.scope_node_count() - 1);
  for (std::size_t c = 0; c < 3; ++c) record[k * kinetics::kStationValueCount + c] = tip(static_cast<Eigen::Index>(c));
  // Each station's compliance with the other stations held: the inverse of its diagonal block of
  // the stations' stiffness W^-1 (static condensation onto one station). Inside stations only.
  std::vector<std::size_t> in;
  for (std::size_t j = 0; j < k; ++j)
    if (inside[j]) in.push_back(j);
  const auto m = static_cast<Eigen::Index>(3 * in.size());
  Eigen::MatrixXd w(m, m);
  for (std::size_t ia = 0; ia < in.size(); ++ia)
    for (std::size_t ib = 0; ib < in.size(); ++ib)
      w.block<3, 3>(static_cast<Eigen::Index>(3 * ia), static_cast<Eigen::Index>(3 * ib)) =
          probe.compliance_mm_per_N.block<3, 3>(static_cast<Eigen::Index>(3 * (k - 1 - in[ia])),
                                                 static_cast<Eigen::Index>(3 * (k - 1 - in[ib])));
  const Eigen::MatrixXd stiffness = Eigen::MatrixXd(0.5 * (w + w.transpose())).ldlt().solve(Eigen::MatrixXd::Identity(m, m));
  for (std::size_t ia = 0; ia < in.size(); ++ia) {
    const Eigen::Matrix3d block = stiffness.block<3, 3>(static_cast<Eigen::Index>(3 * ia), static_cast<Eigen::Index>(3 * ia));
    const Eigen::Matrix3d held = Eigen::Matrix3d(0.5 * (block + block.transpose())).inverse();
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t c = i; c < 3; ++c)
        record[kinetics::compliance_index(k, in[ia], i, c)] = held(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c));
  }
  return record;
}

}  // namespace

ReducedModelData build_reduced_model(const Scenario& training, const ReductionSettings& settings,
                                     const std::function<void(const ReductionProgress&)>& on_progress) {
  settings.validate();
  if (training.kind != ScenarioKind::world) throw ModelError(training.source + ": the training scenario must be a world scenario");
  std::unique_ptr<World> world = build_world(training);
  const std::vector<std::size_t> tip_first = station_nodes(*world, settings);
  const std::vector<std::size_t> increasing(tip_first.rbegin(), tip_first.rend());
  ProcedurePlayer player(training.procedure, training.settings.initial_insertion_mm, training.scope.length_mm);

  ReducedModelData data;
  data.training_source = training.source;
  data.colon_name = training.colon ? training.colon->name() : std::string{};
  data.settings = settings;
  const auto grid_points = static_cast<std::size_t>(std::lround((settings.depth_end_mm - settings.depth_start_mm) / settings.depth_step_mm)) + 1;
  data.head.stations = settings.stations;
  data.head.grid_points = grid_points;
  data.head.depth_start_mm = settings.depth_start_mm;
  data.head.depth_step_mm = settings.depth_step_mm;
  data.head.inverse_depth_step = 1.0 / settings.depth_step_mm;
  data.head.friction = training.settings.contact.friction_coefficient;
  data.head.station_spacing_mm = settings.station_spacing_mm;
  data.records.resize(grid_points);
  std::vector<std::vector<bool>> inside(grid_points);

  const double h = world->time_step_s();
  std::size_t next = 0;
  const double tolerance = 1e-6;
  while (next < grid_points) {
    const double target = settings.depth_start_mm + settings.depth_step_mm * static_cast<double>(next);
    const double depth = world->insertion_depth_mm();
    if (std::fabs(depth - target) <= tolerance) {
      data.records[next] = record_of(*world, increasing, settings, inside[next]);
      ++next;
      if (on_progress) on_progress({depth, settings.depth_end_mm});
      continue;
    }
    if (depth > target + tolerance)
      throw ModelError(training.source + ": the training run passed the grid depth " + number_text(target) +
                       " mm between steps (depth now " + number_text(depth) +
                       " mm); make the grid step a multiple of the depth per step, or start the grid on a step");
    if (world->time_s() >= training.procedure.end_s() - 1e-9)
      throw ModelError(training.source + ": the training procedure ends at depth " + number_text(depth) +
                       " mm, before the last grid depth " + number_text(settings.depth_end_mm) + " mm");
    const HandleCommand command = player.command(world->time_s(), h, depth, world->roll_rad());
    if (command.force_controlled) throw ModelError(training.source + ": the training procedure must prescribe the depth (no push)");
    const WorldStepReport report = world->step(command);
    if (!report.ok) throw ModelError(training.source + ": the training run failed at t = " + number_text(world->time_s()) + " s: " + report.failure);
  }
  // Station friction (reduced_kinetics.hpp): the training's |f_T| / f_n where the stretch slid
  // between this grid depth and the next (or the previous one, at the end), mu where it stuck.
  const double mu = training.settings.contact.friction_coefficient;
  for (std::size_t g = 0; g < grid_points; ++g)
    for (std::size_t j = 0; j < settings.stations; ++j) {
      const std::size_t base = j * kinetics::kStationValueCount;
      const std::size_t a = g + 1 < grid_points ? g : g - 1;
      const double advance = data.records[a + 1][base + kinetics::kStationPath] - data.records[a][base + kinetics::kStationPath];
      const double fn = data.records[g][base + kinetics::kStationForceN];
      const double ft = std::hypot(data.records[g][base + kinetics::kStationForceT], data.records[g][base + kinetics::kStationForceS]);
      const bool slid = advance > kSlidThreshold * settings.depth_step_mm;
      const double ratio = fn > 0.0 ? ft / fn : 0.0;
      data.records[g][base + kinetics::kStationFriction] = slid ? ratio : std::max(mu, kStuckMargin * ratio);
    }
  // A station outside the body at a grid depth takes its values from the first grid depth where
  // it is inside: interpolation just after it enters then starts from real data.
  for (std::size_t j = 0; j < settings.stations; ++j) {
    std::size_t first_inside = grid_points;
    for (std::size_t g = 0; g < grid_points && first_inside == grid_points; ++g)
      if (inside[g][j]) first_inside = g;
    if (first_inside == grid_points) continue;
    for (std::size_t g = 0; g < first_inside; ++g) {
      const std::size_t base = j * kinetics::kStationValueCount;
      for (std::size_t v = 0; v < kinetics::kStationValueCount; ++v) data.records[g][base + v] = data.records[first_inside][base + v];
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t c = i; c < 3; ++c) {
          const std::size_t index = kinetics::compliance_index(settings.stations, j, i, c);
          data.records[g][index] = data.records[first_inside][index];
        }
    }
  }
  return data;
}

}  // namespace scopekin::model
