#include "host_sim/discrepancy/measured_recording.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "host_sim/recording/recording_row.hpp"

namespace scopekin::discrepancy {
namespace {

std::string number(double v) {
    std::ostringstream s;
    s << std::setprecision(6) << v;
    return s.str();
}

/// Linear interpolation in a sorted drive; clamped at the ends.
template <typename Get>
double interpolate(const std::vector<DriveSample>& d, double t, Get get) {
    if (d.empty()) return 0.0;
    if (t <= d.front().time_s) return get(d.front());
    if (t >= d.back().time_s) return get(d.back());
    const auto it = std::upper_bound(d.begin(), d.end(), t,
                                     [](double x, const DriveSample& s) { return x < s.time_s; });
    const DriveSample& b = *it;
    const DriveSample& a = *(it - 1);
    const double w = (t - a.time_s) / (b.time_s - a.time_s);
    return (1.0 - w) * get(a) + w * get(b);
}

/// Every 33rd ms: the EM tracker's rate, for outputs sampled faster.
constexpr double kThinning_s = 0.033;

}  // namespace

const char* output_name(OutputId id) {
    static constexpr std::array<const char*, kOutputCount> names{
        "tip_position_mm", "p20_position_mm", "sigmoid_position_mm",
        "tip_force_N",     "handle_force_N",  "handle_torque_Nmm"};
    return names[static_cast<std::size_t>(id)];
}

const char* output_unit(OutputId id) {
    static constexpr std::array<const char*, kOutputCount> units{"mm", "mm", "mm",
                                                                 "N",  "N",  "N mm"};
    return units[static_cast<std::size_t>(id)];
}

std::string MeasuredRecording::region_at(double t) const {
    if (region_time_s.empty()) return "";
    auto it = std::upper_bound(region_time_s.begin(), region_time_s.end(), t);
    if (it == region_time_s.begin()) return region.front();
    return region[static_cast<std::size_t>(it - region_time_s.begin()) - 1];
}

double MeasuredRecording::insertion_at(double t) const {
    return interpolate(drive, t, [](const DriveSample& s) { return s.insertion_mm; });
}

double MeasuredRecording::roll_at(double t) const {
    return interpolate(drive, t, [](const DriveSample& s) { return s.roll_rad; });
}

namespace {

/// The drive: every encoder sample, checked for units and length.
void extract_drive(const recording::Recording& rec, const std::string& where,
                   MeasuredRecording& data) {
    std::int64_t t0_us = -1;
    double roll0 = 0.0;
    for (const recording::RecordingRow& row : rec.rows) {
        if (!row.insertion_roll) continue;
        if (t0_us < 0) {
            t0_us = row.time_us;
            roll0 = row.insertion_roll->roll_rad;
        }
        data.drive.push_back({static_cast<double>(row.time_us) * 1e-6,
                              row.insertion_roll->insertion_mm,
                              row.insertion_roll->roll_rad - roll0});
    }
    if (data.drive.size() < 2)
        throw DiscrepancyInputError(
            where +
            "no handle motion: the model is driven by the insertion/roll encoder "
            "(columns insertion_mm, roll_rad), and this recording has " +
            std::to_string(data.drive.size()) + " sample(s) of it");
    double max_insertion = -1e300, min_insertion = 1e300, max_roll = 0.0;
    for (const DriveSample& s : data.drive) {
        max_insertion = std::max(max_insertion, s.insertion_mm);
        min_insertion = std::min(min_insertion, s.insertion_mm);
        max_roll = std::max(max_roll, std::abs(s.roll_rad));
    }
    if (min_insertion < 0.0 || max_insertion > 2000.0)
        throw DiscrepancyInputError(where + "insertion_mm runs from " + number(min_insertion) +
                                    " to " + number(max_insertion) +
                                    ": needs millimetres of scope past the anus, 0 to 2000 mm");
    if (max_insertion - min_insertion < 5.0)
        throw DiscrepancyInputError(
            where + "insertion_mm moves only " + number(max_insertion - min_insertion) + " (from " +
            number(min_insertion) + " to " + number(max_insertion) +
            "): metres instead of millimetres? The workflow needs the hand to move the scope "
            "(at least 5 mm)");
    if (max_roll > 60.0)
        throw DiscrepancyInputError(where + "roll_rad reaches " + number(max_roll) +
                                    " from its start: degrees instead of radians? Needs radians "
                                    "(at most 60 rad, ~10 turns)");
    data.start_s = data.drive.front().time_s;
    data.end_s = data.drive.back().time_s;
    data.duration_s = data.end_s - data.start_s;
    data.initial_insertion_mm = data.drive.front().insertion_mm;
    if (data.duration_s < kMinDuration_s)
        throw DiscrepancyInputError(where + "the handle motion lasts " + number(data.duration_s) +
                                    " s: too short to hold "
                                    "data out; needs at least " +
                                    number(kMinDuration_s) + " s");
}

/// The measured outputs within the drive's span (handle signals thinned), and the region labels.
std::array<MeasuredSeries, kOutputCount> extract_outputs(const recording::Recording& rec,
                                                         const std::string& where,
                                                         MeasuredRecording& data) {
    std::array<MeasuredSeries, kOutputCount> series;
    for (std::size_t k = 0; k < kOutputCount; ++k) {
        series[k].id = static_cast<OutputId>(k);
        series[k].components = k <= 2 ? 3 : 1;
    }
    double last_handle_s = -1e300;
    std::string last_region = "\x01";
    for (const recording::RecordingRow& row : rec.rows) {
        const double t = static_cast<double>(row.time_us) * 1e-6;
        if (t < data.start_s || t > data.end_s) continue;
        const std::array<std::pair<recording::EmSlot, OutputId>, 3> em{
            {{recording::EmSlot::tip, OutputId::tip_position},
             {recording::EmSlot::twenty_cm, OutputId::p20_position},
             {recording::EmSlot::sigmoid, OutputId::sigmoid_position}}};
        for (const auto& [slot, id] : em) {
            const auto& cell = row.em[static_cast<std::size_t>(slot)];
            if (!cell) continue;
            const Eigen::Vector3d p(cell->position_mm[0], cell->position_mm[1],
                                    cell->position_mm[2]);
            if (p.norm() > 3000.0)
                throw DiscrepancyInputError(
                    where + "EM position " + number(p.norm()) + " from the origin at t = " +
                    number(t) + " s: needs millimetres in the colon frame (at most 3000 mm)");
            series[static_cast<std::size_t>(id)].time_s.push_back(t);
            series[static_cast<std::size_t>(id)].value.push_back(p);
        }
        if (row.tip_force) {
            const double f = row.tip_force->force_N[2];  // along the tip's axis
            if (std::abs(f) > 100.0)
                throw DiscrepancyInputError(where + "tip force " + number(f) +
                                            " at t = " + number(t) +
                                            " s: needs newtons (at most 100 N; mN or grams?)");
            series[static_cast<std::size_t>(OutputId::tip_force)].time_s.push_back(t);
            series[static_cast<std::size_t>(OutputId::tip_force)].value.emplace_back(f, 0.0, 0.0);
        }
        if (row.handle) {
            series[static_cast<std::size_t>(OutputId::handle_force)].full_rate.push_back(
                row.handle->force_N);
            series[static_cast<std::size_t>(OutputId::handle_torque)].full_rate.push_back(
                row.handle->torque_Nmm);
            if (std::abs(row.handle->force_N) > 200.0)
                throw DiscrepancyInputError(where + "handle force " + number(row.handle->force_N) +
                                            " at t = " + number(t) +
                                            " s: needs newtons (at most 200 N; mN or grams?)");
            if (t - last_handle_s >= kThinning_s - 1e-9) {
                last_handle_s = t;
                series[static_cast<std::size_t>(OutputId::handle_force)].time_s.push_back(t);
                series[static_cast<std::size_t>(OutputId::handle_force)].value.emplace_back(
                    row.handle->force_N, 0.0, 0.0);
                series[static_cast<std::size_t>(OutputId::handle_torque)].time_s.push_back(t);
                series[static_cast<std::size_t>(OutputId::handle_torque)].value.emplace_back(
                    row.handle->torque_Nmm, 0.0, 0.0);
            }
        }
        if (!row.region.empty() && row.region != last_region) {
            data.region_time_s.push_back(t);
            data.region.push_back(row.region);
            last_region = row.region;
        }
    }
    return series;
}

}  // namespace

MeasuredRecording extract_measured_recording(const recording::Recording& rec,
                                             const std::string& source) {
    MeasuredRecording data;
    data.source = source;
    const std::string where = source + ": ";
    extract_drive(rec, where, data);
    std::array<MeasuredSeries, kOutputCount> series = extract_outputs(rec, where, data);
    for (MeasuredSeries& s : series)
        if (s.time_s.size() >= 20) data.outputs.push_back(std::move(s));
    const bool has_tip_output =
        std::any_of(data.outputs.begin(), data.outputs.end(), [](const MeasuredSeries& s) {
            return s.id == OutputId::tip_position || s.id == OutputId::p20_position ||
                   s.id == OutputId::tip_force;
        });
    if (!has_tip_output)
        throw DiscrepancyInputError(
            where +
            "no measured output to compare with: needs at least 20 samples of the tip's "
            "or the 20 cm point's EM pose (em_tip_*, em_20cm_*) or of the tip force (tip_force_*)");
    return data;
}

}  // namespace scopekin::discrepancy
