#pragma once
// truth.csv: what the box claims to estimate, true, one row per box period (host_sim/README.md,
// "truth.csv"; the definitions in model/truth/README.md). The world is read after every world
// step (model::truth::TruthReader); a period at T takes the two readouts around T, blended
// linearly (labels from the nearer one), as the sensors sample between steps. Episodes need the
// whole run (an onset is dated back to where the excess began to grow), so the file is written
// at the end: rows at exactly the periods the firmware ran, with the same time_s text as
// firmware.csv, so the two join row by row.
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/truth/truth_readout.hpp"

namespace scopekin::host_sim {

/// One world readout, the part truth.csv needs.
struct TruthSample {
    double time_s = 0;
    double insertion_mm = 0;
    double tip_path_mm = 0;
    double tip_displaced_path_mm = 0;
    model::ColonRegion tip_region = model::ColonRegion::rectum;
    std::vector<Eigen::Vector3d> station_force_N;  ///< (n, t, s), tip first
    std::vector<bool> station_inside;
    double max_station_force_N = 0;
    std::size_t max_station = 0;
    double max_wall_force_N = 0;
    double max_wall_path_mm = 0;
    model::ColonRegion max_wall_region = model::ColonRegion::rectum;
    bool has_wall_force = false;
    model::ColonRegion bow_region = model::ColonRegion::rectum;
    double bow_mm = 0;
    model::truth::RegionBow region_bow_mm{};
    bool scope_crosses = false;
    double scope_beyond_wall_mm = 0;  ///< TruthReadout::scope_beyond_wall_mm
};

TruthSample truth_sample(const model::truth::TruthReadout& r);
/// Linear blend (labels and flags from the nearer one).
TruthSample blend(const TruthSample& a, const TruthSample& b, double weight_b);

/// Collects a run's readouts and, at the end, writes truth.csv at the box's periods.
class TruthRecorder {
public:
    void add(const TruthSample& sample);  ///< every world step, in time order
    /// The samples at the given period times [us] (each blended between the readouts around it;
    /// clamped to the first and last readout).
    std::vector<TruthSample> at_periods(const std::vector<std::uint64_t>& period_us) const;
    /// Writes truth.csv for those periods and returns the "truth" section of summary.json
    /// (definitions' constants, loop and force episodes).
    nlohmann::ordered_json write(std::ostream* out, const std::vector<std::uint64_t>& period_us,
                                 std::size_t stations) const;
    std::size_t size() const { return samples_.size(); }

private:
    std::vector<TruthSample> samples_;
};

std::string truth_csv_header(std::size_t stations);

}  // namespace scopekin::host_sim
