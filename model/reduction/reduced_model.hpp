#pragma once
// Building the firmware's reduced-order model from the full-order one (trajectory piecewise-
// linear reduction: firmware/kinetics/reduced_kinetics.hpp explains the model and its step).
// Each training run (a segment: a scenario, the direction it moves the scope in, and the depths
// to probe) is run in the full-order world; at every knot depth the state is probed at K
// stations (World::probe_stations) and written as one knot record of the firmware's layout, and
// every `compliance_every` knots the stations' compliance as one compliance record. The result
// is plain double data, which
//   * the host uses directly (the "reduced double" model of the accuracy tests), and
//   * reduced_table_writer turns into the firmware's Q16.16 constant tables.
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "kinetics/reduced_kinetics.hpp"  // firmware/: layout of the records
#include "model/scenario/scenario.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

/// One training run: a travel run probed at depths (advancing or withdrawing), or a hold run
/// probed at times while the hand holds the depth still.
struct ReductionSegmentSpec {
    Scenario scenario;  ///< a world scenario under position control (no push)
    int kind = kinetics::kSegmentTravel;
    int direction = 1;            ///< travel: +1 probed while advancing, -1 while withdrawing
    double depth_from_mm = 20.0;  ///< travel: first knot the run passes
    double depth_to_mm = 760.0;   ///< travel: last knot it passes
    double step_mm = 1.0;  ///< travel: knot spacing (a multiple of the run's depth per solver step)
    double after_s = 0.0;  ///< travel: knots are probed from this time on; hold: the hold's start
    double duration_s = 0.0;  ///< hold: knots from after_s to after_s + duration_s
    double step_s = 0.05;     ///< hold: knot spacing (a multiple of the solver step)
};

struct ReductionSettings {
    std::size_t stations = 12;  ///< K: station j is j * spacing from the tip
    double station_spacing_mm = 50.0;
    std::size_t compliance_every = 10;  ///< knots per compliance record interval
    std::vector<ReductionSegmentSpec>
        segments;        ///< segment 0 advances over the model's depth range
    std::string source;  ///< the spec file, for messages and provenance
    void validate() const;
};

/// Reads a reduction spec (model/reduction/training.json): stations, spacing, compliance_every
/// and segments [{scenario (a path relative to the spec), direction "advance"|"withdraw",
/// depth_from_mm, depth_to_mm, step_mm, after_s} or {scenario, direction "hold", after_s,
/// duration_s, step_s}], strictly (unknown keys rejected).
ReductionSettings read_reduction_spec(const std::string& filename);

/// The reduced model's data in double: header + knot and compliance records.
class ReducedModelData {
public:
    ReductionSettings settings;
    kinetics::ReducedModelHeader<double> head;
    std::vector<std::vector<double>> knots;        ///< [knot][index in knot record]
    std::vector<std::vector<double>> compliances;  ///< [record][index in compliance record]

    const kinetics::ReducedModelHeader<double>& header() const { return head; }
    double value(std::size_t knot, std::size_t index) const { return knots[knot][index]; }
    double station_value(std::size_t knot, std::size_t station, std::size_t v) const {
        return knots[knot][station * kinetics::kStationValueCount + v];
    }
    double slid(std::size_t knot, std::size_t station) const {
        return station_value(knot, station, kinetics::kStationSlid);
    }
    double knot_value(std::size_t knot, std::size_t v) const {
        return knots[knot][head.stations * kinetics::kStationValueCount + v];
    }
    double compliance(std::size_t record, std::size_t index) const {
        return compliances[record][index];
    }
};

struct ReductionProgress {
    std::size_t segment = 0;
    std::size_t segments = 0;
    std::size_t knot = 0;   ///< knots probed in this segment
    std::size_t knots = 0;  ///< knots of this segment
};

/// Runs every segment's scenario and probes its knots. Throws ModelError if a run fails, never
/// reaches a knot, or passes one between solver steps.
ReducedModelData build_reduced_model(
    const ReductionSettings& settings,
    const std::function<void(const ReductionProgress&)>& on_progress = {});

/// Scope nodes of the stations, station 0 (the tip) first.
std::vector<std::size_t> station_nodes(const World& world, std::size_t stations,
                                       double station_spacing_mm);

/// The full-order world's contact forces gathered per station: the resultant of the wall forces
/// on the scope over the station's stretch (arc from the tip in [sigma - spacing/2, sigma +
/// spacing/2)), in the station's frame (n, t, s) [N]. `probe` = World::probe_stations of the
/// station nodes in increasing node order (station K-1 first).
std::vector<Eigen::Vector3d> station_forces(const World& world, const StationCompliance& probe,
                                            std::size_t stations, double station_spacing_mm);

}  // namespace scopekin::model
