#include "host_sim/discrepancy/fit_windows.hpp"

#include <algorithm>
#include <cmath>

#include "host_sim/discrepancy/analysis.hpp"

namespace scopekin::discrepancy {

double hand_motion_mm(const MeasuredRecording& data, double from_s, double to_s) {
    // Sampled every 50 ms: the encoder's own rate may be 1 kHz, and hand motion is smooth.
    const double dt = 0.05;
    double motion = 0.0;
    double t = from_s;
    double insertion = data.insertion_at(t), roll = data.roll_at(t);
    while (t < to_s) {
        t = std::min(to_s, t + dt);
        const double i = data.insertion_at(t), r = data.roll_at(t);
        motion += std::abs(i - insertion) + kRollMotion_mm_per_rad * std::abs(r - roll);
        insertion = i;
        roll = r;
    }
    return motion;
}

std::vector<RunWindow> choose_fit_windows(const MeasuredRecording& data, double budget_s) {
    const double block = data.duration_s / kBlocks;
    const double length = budget_s / kBlocks;
    if (!(length < block)) return {};
    const double spin_up = std::min(kSpinUp_s, 0.5 * length);
    std::vector<RunWindow> windows;
    for (int b = 0; b < kBlocks; ++b) {
        const double first = data.start_s + block * b;
        const double last = first + block - length;
        // Candidate starts every 0.25 s; the most motion wins (the earliest of equals). At most
        // kMaxWindowStarts of them: a longer block spreads them evenly (the work stays bounded
        // whatever the recording's length).
        double best_start = first, best_motion = -1.0;
        const double span = last - first;
        const double step =
            span / 0.25 < kMaxWindowStarts - 1 ? 0.25 : span / (kMaxWindowStarts - 1);
        const int positions = static_cast<int>(std::floor(span / step)) + 1;
        for (int k = 0; k < positions; ++k) {
            const double start = first + step * k;
            const double motion = hand_motion_mm(data, start, start + length);
            if (motion > best_motion + 1e-9) {
                best_motion = motion;
                best_start = start;
            }
        }
        windows.push_back({b, best_start, best_start + spin_up, best_start + length});
    }
    return windows;
}

}  // namespace scopekin::discrepancy
