#pragma once
// The fits' objective, robust to event timing (issue 22, "an objective that does not flip on event
// timing"). Where a tip stuck at a junction lets go a little earlier or later as a parameter
// changes, the model's state differs for the rest of that block and the block's cost jumps by
// hundreds of noise units while every other block changes smoothly: on the robustness sweep's
// viscous friction 0.006 s/mm with tissue stiffening 0.3 /N on procedure C, training block 5 held
// 1,131 of a training cost of 1,340 at stiffening 0.15, and 0.1 of 3.7 at the truth; the training
// cost along stiffening read 1,340, 3.7, 1,476 at 0.15, 0.3, 0.6 while the held-out cost fell
// smoothly towards the truth. So each training block's cost is capped at kBlockCapOverMedian times
// the median block's (at least kBlockCapOverNoise times the block's noise floor): a block that
// stands out from its candidate's others by an event shifted in time counts as that cap, and the
// fit follows the blocks that change smoothly. A block within its cap counts in full, so a model
// that fits everywhere is scored exactly as before. Held-out blocks are not capped: every
// held-out cost, share explained and verdict is the plain mean square.
//
// As a residual: block b's rows are scaled by sqrt(min(C_b, cap) / C_b), so the squared norm is
// the sum of the capped block costs and Levenberg–Marquardt works on it unchanged.
#include <vector>

#include <Eigen/Dense>

#include "host_sim/discrepancy/analysis.hpp"

namespace scopekin::discrepancy {

inline constexpr double kBlockCapOverMedian = 10.0;
inline constexpr double kBlockCapOverNoise = 10.0;

/// Which block each row of normalised_residuals(data, ·, sigma, set) falls in, and each block's
/// noise floor (the cost noise alone gives there: its share of each assessed output's samples).
struct BlockRows {
    std::vector<int> block_of_row;
    std::vector<double> noise_floor;  ///< per block (kBlocks)
};
BlockRows block_rows(const MeasuredRecording& data, const std::vector<double>& sigma,
                     SampleSet set);

/// The residual with each block's cost capped (the header's rule). Blocks without rows are
/// ignored for the median.
Eigen::VectorXd cap_outlier_blocks(const BlockRows& rows, Eigen::VectorXd r);
/// The factor cap_outlier_blocks scales each row of `r` by (1 within the cap).
Eigen::VectorXd outlier_block_weights(const BlockRows& rows, const Eigen::VectorXd& r);

/// 0 on the rows of every block where one of `changes`' columns (each a run's change of the
/// normalised residual from a common reference) stands out as cap_outlier_blocks would cap it,
/// 1 elsewhere: the blocks where a small change of the model moved an event in time, so the
/// change there is not proportional to the model's change (a linear fit leaves them out).
Eigen::VectorXd response_event_weights(const BlockRows& rows, const Eigen::MatrixXd& changes);

/// The capped cost over the blocks `keep` accepts only: the other blocks' rows (a run over the
/// kept blocks' windows leaves them unrun, NaN) count nothing and take no part in the median.
double capped_cost_on_blocks(BlockRows rows, Eigen::VectorXd r, bool (*keep)(int block));

}  // namespace scopekin::discrepancy
