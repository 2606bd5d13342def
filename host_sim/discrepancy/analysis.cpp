#include "host_sim/discrepancy/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

namespace scopekin::discrepancy {

int block_of(const MeasuredRecording& data, double t) {
    if (!(data.duration_s > 0.0)) return 0;
    const double x = (t - data.start_s) / data.duration_s * kBlocks;
    return std::clamp(static_cast<int>(std::floor(x)), 0, kBlocks - 1);
}

bool is_held_out_block(int block) {
    return block % 3 == 1;
}

bool is_screening_block(int block) {
    return block % 3 == 0;
}

bool in_set(const MeasuredRecording& data, double t, SampleSet set) {
    if (set == SampleSet::all) return true;
    if (set == SampleSet::fit_training || set == SampleSet::fit_held_out) {
        if (!data.fit_spans_s.empty() &&
            std::none_of(
                data.fit_spans_s.begin(), data.fit_spans_s.end(),
                [t](const std::pair<double, double>& s) { return t >= s.first && t <= s.second; }))
            return false;
        set = set == SampleSet::fit_training ? SampleSet::training : SampleSet::held_out;
    }
    return is_held_out_block(block_of(data, t)) == (set == SampleSet::held_out);
}

std::size_t samples_in_set(const MeasuredRecording& data, const MeasuredSeries& series,
                           SampleSet set) {
    std::size_t n = 0;
    for (double t : series.time_s)
        n += in_set(data, t, set) ? 1U : 0U;
    return n;
}

namespace {

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

}  // namespace

std::vector<double> estimate_noise(const MeasuredRecording& data) {
    std::vector<double> sigma;
    for (const MeasuredSeries& s : data.outputs) {
        // The tip force sensor reads compression only: where it reads 0 the noise is clipped away,
        // so only triples of positive readings count.
        const bool clipped_at_zero = s.id == OutputId::tip_force;
        // A thinned output's noise from every sample the sensor delivered: over 33 ms the handle
        // force's own curvature (a scope sticking and slipping) is (33)^2 times what it is over
        // 1 ms, and the thinned series read its noise 1.7 (slow) to 13 (deep, fast) times too high.
        const bool full = !s.full_rate.empty();
        const std::size_t n = full ? s.full_rate.size() : s.value.size();
        const auto at = [&](std::size_t i, int c) { return full ? s.full_rate[i] : s.value[i][c]; };
        double variance = 0.0;
        bool enough = true;
        for (int c = 0; c < s.components; ++c) {
            std::vector<double> d2;
            for (std::size_t i = 1; i + 1 < n; ++i) {
                if (clipped_at_zero &&
                    !(at(i - 1, c) > 0.0 && at(i, c) > 0.0 && at(i + 1, c) > 0.0))
                    continue;
                d2.push_back(std::abs(at(i + 1, c) - 2.0 * at(i, c) + at(i - 1, c)));
            }
            if (d2.size() < kMinNoiseSamples) enough = false;
            // 1.4826 x median absolute value: the SD of a normal variable; / sqrt(6): see the header.
            const double sd = 1.4826 * median(d2) / std::sqrt(6.0);
            variance += sd * sd;
        }
        sigma.push_back(enough && variance > 0.0 ? std::sqrt(variance) : 0.0);
    }
    return sigma;
}

bool assessable(const std::vector<double>& sigma, std::size_t output) {
    return sigma[output] > 0.0;
}

double rms_error(const MeasuredRecording& data, const ModelPrediction& p, std::size_t o,
                 SampleSet set) {
    const MeasuredSeries& m = data.outputs[o];
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < m.time_s.size(); ++i) {
        if (!in_set(data, m.time_s[i], set)) continue;
        sum += (m.value[i] - p.outputs[o][i]).squaredNorm();
        ++n;
    }
    return n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
}

Eigen::VectorXd normalised_residuals(const MeasuredRecording& data, const ModelPrediction& p,
                                     const std::vector<double>& sigma, SampleSet set) {
    std::vector<double> r;
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        if (!assessable(sigma, o)) continue;
        const MeasuredSeries& m = data.outputs[o];
        const std::size_t n = samples_in_set(data, m, set);
        if (n == 0) continue;
        const double scale = 1.0 / (std::max(sigma[o], 1e-9) * std::sqrt(static_cast<double>(n)));
        for (std::size_t i = 0; i < m.time_s.size(); ++i) {
            if (!in_set(data, m.time_s[i], set)) continue;
            for (int c = 0; c < m.components; ++c)
                r.push_back((m.value[i][c] - p.outputs[o][i][c]) * scale);
        }
    }
    return Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
}

std::string phase_at(const MeasuredRecording& data, double t) {
    const double dt = 0.1;
    const double speed = (data.insertion_at(t + dt) - data.insertion_at(t - dt)) / (2.0 * dt);
    const double roll_rate = (data.roll_at(t + dt) - data.roll_at(t - dt)) / (2.0 * dt);
    if (std::abs(roll_rate) > 0.05) return "twist";  // rad/s: 3 deg/s
    if (speed > 1.0) return "push";                  // mm/s
    if (speed < -1.0) return "pull";
    return "hold";
}

nlohmann::ordered_json locate(const MeasuredRecording& data, const ModelPrediction& p,
                              const std::vector<double>& sigma, double threshold) {
    using Json = nlohmann::ordered_json;
    auto speed_band = [&](double t) {
        const double v = std::abs(data.insertion_at(t + 0.1) - data.insertion_at(t - 0.1)) / 0.2;
        if (v < 5.0) return std::string("0-5 mm/s");
        if (v < 15.0) return std::string("5-15 mm/s");
        if (v < 30.0) return std::string("15-30 mm/s");
        return std::string(">= 30 mm/s");
    };
    auto depth_band = [&](double t) {
        const int lo = static_cast<int>(std::floor(data.insertion_at(t) / 200.0)) * 200;
        return std::to_string(lo) + "-" + std::to_string(lo + 200) + " mm";
    };
    auto region = [&](double t) {
        std::string r = data.region_at(t);
        if (r.empty()) r = p.region_at(t);
        return r.empty() ? std::string("outside") : r;
    };
    const std::vector<std::pair<std::string, std::function<std::string(double)>>> groupings{
        {"region", region},
        {"phase", [&](double t) { return phase_at(data, t); }},
        {"speed", speed_band},
        {"depth", depth_band}};
    Json out = Json::object();
    for (const auto& [grouping, key_of] : groupings) {
        // group -> per output (sum of squares, count)
        std::map<std::string, std::vector<std::pair<double, std::size_t>>> acc;
        for (std::size_t o = 0; o < data.outputs.size(); ++o) {
            const MeasuredSeries& m = data.outputs[o];
            for (std::size_t i = 0; i < m.time_s.size(); ++i) {
                auto& slot = acc[key_of(m.time_s[i])];
                slot.resize(data.outputs.size());
                slot[o].first += (m.value[i] - p.outputs[o][i]).squaredNorm();
                ++slot[o].second;
            }
        }
        Json groups = Json::array();
        for (const auto& [key, per_output] : acc) {
            Json g{{"group", key}};
            Json outputs = Json::object();
            bool significant = false;
            for (std::size_t o = 0; o < data.outputs.size(); ++o) {
                const auto [sum, n] = per_output[o];
                if (n == 0) continue;
                const double rms = std::sqrt(sum / static_cast<double>(n));
                if (!assessable(sigma, o)) continue;
                const double ratio = rms / sigma[o];
                const bool sig = n >= 10 && ratio > threshold;
                significant = significant || sig;
                outputs[output_name(data.outputs[o].id)] = {
                    {"samples", n}, {"rms", rms}, {"rms_over_noise", ratio}, {"significant", sig}};
            }
            g["significant"] = significant;
            g["outputs"] = outputs;
            groups.push_back(g);
        }
        out[grouping] = groups;
    }
    return out;
}

}  // namespace scopekin::discrepancy
