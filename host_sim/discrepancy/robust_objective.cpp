#include "host_sim/discrepancy/robust_objective.hpp"

#include <algorithm>
#include <cmath>

namespace scopekin::discrepancy {

BlockRows block_rows(const MeasuredRecording& data, const std::vector<double>& sigma,
                     SampleSet set) {
    // The same order as normalised_residuals: outputs, samples in the set, components.
    BlockRows rows;
    rows.noise_floor.assign(kBlocks, 0.0);
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        if (!assessable(sigma, o)) continue;
        const MeasuredSeries& m = data.outputs[o];
        const std::size_t n = samples_in_set(data, m, set);
        if (n == 0) continue;
        for (std::size_t i = 0; i < m.time_s.size(); ++i) {
            if (!in_set(data, m.time_s[i], set)) continue;
            const int b = block_of(data, m.time_s[i]);
            rows.noise_floor[static_cast<std::size_t>(b)] += 1.0 / static_cast<double>(n);
            for (int c = 0; c < m.components; ++c)
                rows.block_of_row.push_back(b);
        }
    }
    return rows;
}

Eigen::VectorXd outlier_block_weights(const BlockRows& rows, const Eigen::VectorXd& r) {
    Eigen::VectorXd weight = Eigen::VectorXd::Ones(r.size());
    if (static_cast<std::size_t>(r.size()) != rows.block_of_row.size()) return weight;
    std::vector<double> cost(kBlocks, 0.0);
    for (Eigen::Index k = 0; k < r.size(); ++k)
        cost[static_cast<std::size_t>(rows.block_of_row[static_cast<std::size_t>(k)])] +=
            r[k] * r[k];
    std::vector<double> present;
    for (std::size_t b = 0; b < cost.size(); ++b)
        if (rows.noise_floor[b] > 0.0) present.push_back(cost[b]);
    if (present.size() < 3) return weight;  // no median to stand out from
    std::nth_element(present.begin(),
                     present.begin() + static_cast<std::ptrdiff_t>(present.size() / 2),
                     present.end());
    const double median = present[present.size() / 2];
    std::vector<double> scale(kBlocks, 1.0);
    for (std::size_t b = 0; b < cost.size(); ++b) {
        const double cap =
            std::max(kBlockCapOverMedian * median, kBlockCapOverNoise * rows.noise_floor[b]);
        if (cost[b] > cap) scale[b] = std::sqrt(cap / cost[b]);
    }
    for (Eigen::Index k = 0; k < r.size(); ++k)
        weight[k] = scale[static_cast<std::size_t>(rows.block_of_row[static_cast<std::size_t>(k)])];
    return weight;
}

Eigen::VectorXd cap_outlier_blocks(const BlockRows& rows, Eigen::VectorXd r) {
    const Eigen::VectorXd weight = outlier_block_weights(rows, r);
    return r.cwiseProduct(weight);
}

Eigen::VectorXd response_event_weights(const BlockRows& rows, const Eigen::MatrixXd& changes) {
    Eigen::VectorXd weight = Eigen::VectorXd::Ones(changes.rows());
    for (Eigen::Index k = 0; k < changes.cols(); ++k) {
        const Eigen::VectorXd capped = outlier_block_weights(rows, changes.col(k));
        for (Eigen::Index i = 0; i < weight.size(); ++i)
            if (capped[i] < 1.0) weight[i] = 0.0;
    }
    return weight;
}

double capped_cost_on_blocks(BlockRows rows, Eigen::VectorXd r, bool (*keep)(int block)) {
    if (static_cast<std::size_t>(r.size()) != rows.block_of_row.size()) return r.squaredNorm();
    for (int b = 0; b < kBlocks; ++b)
        if (!keep(b)) rows.noise_floor[static_cast<std::size_t>(b)] = 0.0;
    for (Eigen::Index k = 0; k < r.size(); ++k)
        if (!keep(rows.block_of_row[static_cast<std::size_t>(k)])) r[k] = 0.0;
    return cap_outlier_blocks(rows, std::move(r)).squaredNorm();
}

}  // namespace scopekin::discrepancy
