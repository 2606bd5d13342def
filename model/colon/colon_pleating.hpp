#pragma once
// Telescoping: a mobile stretch of colon (sigmoid, transverse, and the descending or ascending
// colon where a patient has them on a mesentery) pleats along the scope when the scope drags it
// towards the anus (the withdrawal with the tip hooked that endoscopists use to straighten a loop)
// and stays pleated while the scope holds it (Cotton & Williams, Practical Gastrointestinal
// Endoscopy, 7th ed. 2014, ch. 7: the colon "concertinas" onto the straightened instrument).
//
// The law (model/README.md, "Telescoping"), one state per stretch, the pleated fraction p of its
// length, p in [0, p_max]:
//   D       net drag of the scope's forces on the stretch towards the anus [N]: every contact force
//           on the colon projected on its segment's direction towards the anus, summed;
//   D_p(p)  pleating resistance, stiffening as the folds pack: D_0 + D_h q / (1 - q), q = p/p_max;
//   dp/dt = r (D - D_p(p))   while D > D_p(p)   (pleats form; a Bingham-like law, rate r);
//   dp/dt = -p / tau         while |D| < D_0    (a stretch the scope hardly drags recoils);
//   dp/dt = 0                otherwise          (the scope holds the pleats, also while it is pushed
//                                                on towards the cecum).
// At a constant drag D > D_0 it settles where D = D_p: q* = (D - D_0) / (D - D_0 + D_h).
// The stretch's rest shape for a given p: every node at its arc fraction between the stretch's
// fixed ends, blended from the chord towards the unpleated curve, chord + lambda (curve - chord),
// with lambda such that the stretch is (1 - p) of its unpleated length (bisection): the mesentery
// keeps the shortened colon as near its place as its length allows. p_max is capped at 90 % of
// 1 - chord / length, so a pleated stretch never reaches its chord.
// Parameters: stated guesses (no measurement of colon pleating forces is known to us); D_0 = 1 N
// is the drag of a withdrawal through a straight mobile stretch at mu = 0.25 with a few newtons on
// the wall. Left out: suction (it pleats too), the fixed regions' haustra (they shorten a little on
// the scope as well), the compliance of the pleated shape (the colon's elastic compliance stays
// the unpleated colon's, about its new rest shape).
#include <Eigen/Dense>
#include <vector>

#include "model/colon/colon_compliance.hpp"

namespace scopekin::model {

struct TelescopingLaw {
    bool enabled = false;            ///< off unless a scenario asks for it (model/README.md)
    double onset_drag_N = 1.0;       ///< D_0: drag at which pleats begin to form
    double stiffening_drag_N = 2.0;  ///< D_h: at half the pleatable length D_p = D_0 + D_h
    double recoil_time_s = 30.0;     ///< tau: a stretch the scope hardly drags recoils
    double rate_per_N_s = 0.2;       ///< r [1/(N s)]
    double max_fraction = 0.6;       ///< p_max before the chord cap
    void validate() const;           ///< throws ModelError naming "telescoping.<field>"
};

/// The pleating state of the colon's mobile stretches and the rest shape it gives.
class ColonPleating {
public:
    /// `rest_mm`: the colon's centerline nodes at rest; `mobile`: per node, hangs on a mesentery
    /// (ColonStructure::mobile). Stretches are the maximal runs of mobile nodes.
    ColonPleating(std::vector<Eigen::Vector3d> rest_mm, const std::vector<bool>& mobile,
                  TelescopingLaw law);

    struct State {
        std::vector<double> fraction;                 ///< p per stretch
        std::vector<Eigen::Vector3d> position_mm;     ///< rest shape, every colon node
        std::vector<Eigen::Vector3d> last_motion_mm;  ///< how far the last advance moved each node
    };
    const State& state() const { return state_; }
    /// Continues from `s`; ModelError when it is another colon's.
    void restore(const State& s);

    std::size_t stretch_count() const { return stretches_.size(); }
    /// Largest pleated fraction of stretch `k` (p_max, capped by the chord).
    double max_fraction(std::size_t k) const { return stretches_[k].max_fraction; }
    /// The stretch's unpleated length and its length now [mm] (fixed end to fixed end).
    double rest_length_mm(std::size_t k) const { return stretches_[k].length_mm; }
    double length_now_mm(std::size_t k) const;
    /// First and last mobile node of stretch k (first - 1 and last + 1 are fixed).
    std::size_t first_node(std::size_t k) const { return stretches_[k].first; }
    std::size_t last_node(std::size_t k) const { return stretches_[k].last; }

    /// D per stretch [N]: the given forces on the colon projected towards the anus, summed.
    std::vector<double> drag_towards_anus_N(const std::vector<ColonPointForce>& forces) const;
    /// One step of h [s] under the scope's forces on the colon; false when nothing moved.
    bool advance(const std::vector<ColonPointForce>& forces, double h_s);
    /// Puts stretch k in the rest shape of pleated fraction p (exposed for tests).
    void solve_shape(std::size_t k, double p);

private:
    struct Stretch {
        std::size_t first = 0, last = 0;
        double length_mm = 0;
        double max_fraction = 0;
    };
    std::vector<Eigen::Vector3d> rest_mm_;
    std::vector<double> segment_mm_;  ///< rest length of segment j (nodes j, j + 1)
    std::vector<Stretch> stretches_;
    TelescopingLaw law_;
    State state_;
    /// dp/dt of stretch k at pleated fraction p under drag D [1/s].
    double rate_per_s(std::size_t k, double p, double drag_N) const;
};

}  // namespace scopekin::model
