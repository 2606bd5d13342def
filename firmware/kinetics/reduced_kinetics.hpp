// reduced_kinetics.hpp — the reduced-order model of the scope in the colon: one template for the
// firmware's fixed-point scalar and for double (the "reduced double" the tests compare with).
//
// ------------------------------------------------------------------------------------------------
// The reduction (trajectory piecewise-linear, Rewieński & White 2003; built by model/reduction)
// ------------------------------------------------------------------------------------------------
// The scope inside the colon stays close to states that the hand's history moves it through.
// The full-order model (model/world: co-rotational Timoshenko scope, hollow-beam colon,
// Gauss-Seidel contact, implicit dynamics) is run offline over TRAINING RUNS
// (model/reduction/training.json), and along each run it leaves, at every KNOT:
//   * K contact STATIONS: scope points at fixed distances from the tip (station 0 = the tip),
//     each with its contact frame (n from the wall to the scope, t along the colon, s = n x t);
//   * per station: its position along the colon centerline p [mm], its gap to the wall g
//     [mm, >= 0], the resultant wall force over the stretch of scope it stands for,
//     f_ref = (f_n, f_t, f_s) [N] in its frame, and the sign of the stretch's slip to the next
//     knot (+1, -1, 0 = stuck);
//   * the handle force the run needed at the knot [N, + pushing in] and the training tip's
//     position (body frame), so that the model predicts what the box measures
//     (model_evidence.hpp weighs the model by that prediction);
//   * every `compliance_every` knots, each station's compliance [mm/N] (see "Compliance").
// Training runs (segments), and which one a step uses:
//   * travel runs, keyed by depth [mm]: segment 0 advances from the shallowest depth (default:
//     20 -> 760 mm at 20 mm/s, a knot every 1 mm); others advance or withdraw over other depths
//     (default: the withdrawal 680 -> 560 mm that straightens the sigmoid loop, a knot every
//     0.75 mm; the re-advance after it, 752 -> 1692 mm, a knot every 2 mm);
//   * hold runs, keyed by the time the hand has held the depth still [s] (default: 2.5 s at
//     680 mm, in which the loaded scope relaxes and is rolled 90°, a knot every 0.05 s).
// The step latches the hand's DIRECTION (reversed once the depth has gone back 0.5 mm from its
// extreme since the last turn; the first move after a hold sets it at once) and counts the HOLD
// time (consecutive steps that move the depth by <= 0.01 mm; a hold counts from 4 such steps).
// While held within 0.5 mm of a hold run's depth it uses that run; otherwise the last travel run
// in its direction whose depths hold the depth; otherwise the last travel run in the other
// direction that holds it (withdrawing beyond the withdrawal runs: an advance run, backwards);
// otherwise segment 0. Moving to another run starts every station on that run's state.
// Station friction: a station's force is the resultant over a curved stretch of scope whose
// nodes each slide with |f_T| = mu f_n on their own wall normal, so the resultant's |f_T| / f_n
// is not mu — below it on a straight stretch, above it where the normals spread around a bend.
// The step derives each station's coefficient from the training force: where the training slid
// the stretch it is that ratio (the training force lies on the station's cone, as a sliding
// contact's must); where the stretch stuck, max(mu, 1.05 x ratio) (the force lies inside). The
// training's slip over a step is |Delta p| against the friction force, -f_T / |f_T| (Coulomb:
// slip opposite the friction force) — so the training state solves every step that repeats the
// training's inputs, in either direction of travel.
// Passive stations: a stretch whose resultant pulls (f_n < 0, its nodes press on opposite
// walls) or lies far outside any cone (|f_T| > 8 f_n) is no single contact; such a station
// follows the training (f = f_ref, u = 0) for as long as that holds.
// Station gap: 0 where the training force presses on the wall, the station node's gap otherwise.
// Compliance: each station's compliance with the other stations held (the inverse of its
// diagonal block of the stations' stiffness W^-1, static condensation), split into the normal
// compliance W_nn and the tangential block with the normal held by the wall, W_TT - W_Tn W_nT /
// W_nn. Normal and tangential deviations are decoupled: with a strong n-T coupling and station
// friction ratios up to ~2, the linear station problem has two solutions near the locked tip
// (stay in contact, or spring off the wall) and Gauss-Seidel took the wrong one.
// What is kept: the contact mechanics at the stations (Signorini + Coulomb, the thesis's
// Delassus form, Eq. 4.19-4.24) linearised about the training state, and history (stick, slip,
// the elastic deviation u it causes). What is dropped: inertia and damping beyond what the
// training runs carried, contacts away from the stations (each station carries its stretch's
// resultant), the coupling between stations (a deviation at one station does not spread to the
// next; the full coupled quasi-static compliance — a cantilever's, up to ~1300 mm/N at the tip —
// made deviations drift without bound), and the nonlinearity between knots (linear
// interpolation).
// Why the error stays small: on a training run the model reproduces the full-order state at the
// knots (u = 0, f = f_ref; tests/model/test_reduced_model.cpp), and between knots it interpolates
// — knots 1 mm apart (0.05 s at 20 mm/s) follow the full-order model's stick-slip. Away from the
// training runs it deviates only through the contact solve (stations sticking where the training
// slid, slipping backwards on a reversal), elastically and locally, u = W (f - f_ref); there its
// error grows with the distance from the training (firmware/README.md, "Firmware accuracy": measured on a
// procedure it was not trained on).
// Because W is block diagonal the station problems are independent: the Gauss-Seidel solve
// (the one solver, ContactProblem::block_diagonal set) is exact after one sweep.
//
// ------------------------------------------------------------------------------------------------
// One step (period h; units mm, N)
// ------------------------------------------------------------------------------------------------
// Choose the run, interpolate p, g, f_ref, the slip signs s and W at its key. State: u_prev (the
// elastic deviation of each station from the training state, station frame) and p_prev (the
// training path position of each station at the previous step). The contact problem of the
// step, per station a (delta = W f + delta_free, solved by the one Gauss-Seidel solver, fixed
// sweeps, warm start):
//   normal   : delta_n = gap after the step          = g_a + (W (f - f_ref))_a,n
//   tangents : delta_T = slip over the step          = training slip + u_a,T - u_prev,a,T
// with u = W (f - f_ref), hence
//   delta_free,a = ( g_a,  slip_a - u_prev,a,T ) - (W f_ref)_a,
//   slip_a = s_a (p_a - p_prev,a) (-f_ref,T / |f_ref,T|)  (0 where the training stuck).
// After the solve u = W (f - f_ref); the tip's position along the colon is p_0 + u_0,t.
// Stations not yet inside the body (depth <= arc from the tip) are left out; they enter with
// u = 0 and the training force as warm start.
//
// Fixed point (Q16.16, fixed_point/RANGES.md): keys are divided by the knot step (no rounded
// reciprocal); ratios |f_T| / f_n are formed only when |f_T| <= 8 f_n (<= 8, no saturation); the
// slip direction f_T / |f_T| is <= 1 in magnitude; the hold time is counted in integer steps
// (capped at 30000) and is period x steps <= 151 s.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "contact/gauss_seidel_contact.hpp"

namespace scopekin::kinetics {

/// Values per station per knot, in this order.
enum ReducedStationValue : std::size_t {
    kStationPath = 0,    ///< p [mm]
    kStationGap = 1,     ///< g [mm]
    kStationForceN = 2,  ///< f_n [N]
    kStationForceT = 3,  ///< f_t [N]
    kStationForceS = 4,  ///< f_s [N]
    kStationSlid = 5,    ///< the training's slip from this knot to the next: +1 the stretch slid
                         ///< towards larger path positions, -1 towards smaller ones, 0 it stuck
    kStationValueCount = 6,
};

/// Values after the K station records of a knot record, in this order.
enum ReducedKnotValue : std::size_t {
    kKnotTipX = 0,  ///< the training tip's position, body frame [mm]
    kKnotTipY = 1,
    kKnotTipZ = 2,
    kKnotHandleForce = 3,  ///< the handle force the training run needed at the knot [N]
    kKnotValueCount = 4,
};

/// Size of one knot record: K station records, then the kKnotValueCount values above.
constexpr std::size_t reduced_knot_size(std::size_t stations) noexcept {
    return stations * kStationValueCount + kKnotValueCount;
}

/// Values per station per compliance record [mm/N]: the normal compliance and the tangential
/// 2x2 block (see "Compliance"), in this order.
enum ReducedComplianceValue : std::size_t {
    kComplianceNN = 0,
    kComplianceTT = 1,
    kComplianceTS = 2,
    kComplianceSS = 3,
    kComplianceValueCount = 4,
};

constexpr std::size_t reduced_compliance_size(std::size_t stations) noexcept {
    return stations * kComplianceValueCount;
}

/// Training runs (segments) the tables can hold.
constexpr std::size_t kMaxReducedSegments = 4;

/// Integer <-> Scalar (exact for the small counts used here).
template <typename Scalar>
struct ReducedScalarTraits {
    static Scalar from_int(int value) noexcept { return static_cast<Scalar>(value); }
    /// floor(x) for 0 <= x < 2^31.
    static int floor_int(Scalar x) noexcept { return static_cast<int>(x); }
};

/// Kinds of training run.
enum ReducedSegmentKind : int {
    kSegmentTravel = 0,  ///< keyed by depth [mm]: the hand advancing or withdrawing
    kSegmentHold = 1,    ///< keyed by the time the hand has held the depth still [s]
};

/// One training run: knots at key_start + i * key_step, i < knots (a travel run's in increasing
/// depth whatever the direction it moved in; a hold run's in increasing hold time from 0).
template <typename Scalar>
struct ReducedSegment {
    int kind{kSegmentTravel};
    int direction{1};                 ///< travel: +1 trained advancing, -1 withdrawing; hold: +1
    Scalar key_start{};               ///< travel: first knot's depth [mm]; hold: 0 [s]
    Scalar key_step{};                ///< travel: [mm]; hold: [s]
    Scalar hold_depth_mm{};           ///< hold: the depth held; travel: 0
    std::size_t knots{0};             ///< >= 2, (knots - 1) a multiple of compliance_every
    std::size_t first_knot{0};        ///< index of knot 0 in the tables' knot records
    std::size_t first_compliance{0};  ///< index of its compliance record 0
};

/// The tables' fixed facts (same meaning for every Scalar).
template <typename Scalar>
struct ReducedModelHeader {
    std::size_t stations{0};          ///< K, <= the state's capacity
    std::size_t compliance_every{1};  ///< knots per compliance record interval
    Scalar friction{};                ///< Coulomb mu of the colon wall
    Scalar station_spacing_mm{};      ///< station j is j * spacing from the tip
    std::size_t segment_count{0};     ///< 1..kMaxReducedSegments; segment 0 trained advancing
    std::array<ReducedSegment<Scalar>, kMaxReducedSegments> segments{};
};

/// What a Tables type provides (duck-typed, no virtual calls), in the record layout above:
///   const ReducedModelHeader<Scalar>& header() const;
///   Scalar station_value(std::size_t knot, std::size_t station, std::size_t value) const;
///       value < kStationSlid: p, g, f_n, f_t, f_s of the station at the knot
///   Scalar slid(std::size_t knot, std::size_t station) const;  ///< kStationSlid: -1, 0 or +1
///   Scalar knot_value(std::size_t knot, std::size_t value) const;  ///< ReducedKnotValue
///   Scalar compliance(std::size_t record, std::size_t index_in_compliance_record) const;
/// (How a type stores them is its own: the firmware's Q16.16 tables keep the slip signs apart,
/// one byte each, reduced_tables.hpp.)

template <typename Scalar, std::size_t Stations>
struct ReducedState {
    contact::ContactProblem<Scalar, Stations> problem{};
    contact::ContactForces<Scalar, Stations> force_N{};  ///< last solution (warm start)
    std::array<contact::ContactVec3<Scalar>, Stations> reference_force_N{};
    std::array<contact::ContactVec3<Scalar>, Stations> elastic_mm{};  ///< u, station frame
    std::array<Scalar, Stations> reference_path_mm{};                 ///< p at the last step
    std::array<contact::ContactState, Stations> contact_state{};
    std::array<bool, Stations> passive{};  ///< the station follows the training this step
    std::size_t active_stations{0};
    std::size_t segment{0};  ///< training run in use
    int direction{1};        ///< +1 advancing, -1 withdrawing (latched, see "Direction")
    Scalar
        turn_depth_mm{};  ///< deepest (advancing) / shallowest (withdrawing) depth since the last turn
    Scalar last_depth_mm{};       ///< the depth of the last step
    std::uint32_t hold_steps{0};  ///< consecutive steps the depth has been held still (capped)
    Scalar tip_path_mm{};
    std::array<Scalar, 3> tip_position_mm{};  ///< training tip position at the depth (body frame)
    Scalar training_handle_force_N{};         ///< the handle force the training run needed here [N]
    bool started{false};
};

template <typename Scalar, std::size_t Stations>
struct ReducedStepReport {
    contact::ContactSolveReport<Scalar, Stations> contact{};
    bool depth_clamped{
        false};  ///< the depth was outside the travel run in use and was clamped to it
};

/// Cap of a station's friction ratio |f_T| / f_n; beyond it the station is passive.
constexpr int kMaxStationFrictionRatio = 8;

/// Where the training stuck, the station's cone is widened to hold its force with this margin.
template <typename Scalar>
Scalar stuck_margin() noexcept {
    return ReducedScalarTraits<Scalar>::from_int(21) /
           ReducedScalarTraits<Scalar>::from_int(20);  // 1.05
}

/// Depth the hand must go back before the model takes the travel direction as reversed, and
/// the distance from a hold run's depth within which a hold uses that run [mm].
template <typename Scalar>
Scalar reverse_hysteresis_mm() noexcept {
    return ReducedScalarTraits<Scalar>::from_int(1) /
           ReducedScalarTraits<Scalar>::from_int(2);  // 0.5 mm
}

/// A step that moves the depth by at most this much holds it still [mm] (2 mm/s at 200 Hz).
template <typename Scalar>
Scalar still_step_mm() noexcept {
    return ReducedScalarTraits<Scalar>::from_int(1) /
           ReducedScalarTraits<Scalar>::from_int(100);  // 0.01 mm
}

/// A hold counts (for the hold runs and for setting the direction on the next move) from this
/// many still steps on (20 ms): one stale sample, which the estimator holds, is not a hold.
constexpr std::uint32_t kMinHoldSteps = 4U;

/// Hold steps are counted up to this (150 s at 5 ms; past a hold run's last knot its last state
/// is used). Counted in integer steps and turned into seconds by one product (RANGES.md: elapsed
/// time is never summed from the period).
constexpr std::uint32_t kMaxHoldSteps = 30000U;

namespace detail {

template <typename Scalar>
Scalar lerp(Scalar a, Scalar b, Scalar weight) noexcept {
    return a + weight * (b - a);
}

/// Last knot's key of a segment.
template <typename Scalar>
Scalar segment_end_mm(const ReducedSegment<Scalar>& segment) noexcept {
    return segment.key_start + segment.key_step * ReducedScalarTraits<Scalar>::from_int(
                                                      static_cast<int>(segment.knots - 1U));
}

/// Interval index and weight of x in [0, intervals] (clamped).
template <typename Scalar>
std::size_t interval_of(Scalar x, std::size_t intervals, Scalar& weight) noexcept {
    const int floor_x = ReducedScalarTraits<Scalar>::floor_int(x);
    std::size_t index = floor_x < 0 ? 0U : static_cast<std::size_t>(floor_x);
    if (index + 1U > intervals) index = intervals - 1U;
    weight = x - ReducedScalarTraits<Scalar>::from_int(static_cast<int>(index));
    return index;
}

}  // namespace detail

/// One step at insertion depth `depth_mm` (validated by the caller), `period_s` after the last
/// one.  Fixed work: K stations, `gauss_seidel.max_sweeps` sweeps when gauss_seidel.mode is fixed.
template <typename Scalar, std::size_t Stations, typename Tables>
ReducedStepReport<Scalar, Stations> reduced_step(
    const Tables& tables, Scalar depth_mm, Scalar period_s, ReducedState<Scalar, Stations>& state,
    const contact::GaussSeidelSettings<Scalar>& gauss_seidel) noexcept {
    using T = contact::ContactScalarTraits<Scalar>;
    using R = ReducedScalarTraits<Scalar>;
    const ReducedModelHeader<Scalar>& head = tables.header();
    ReducedStepReport<Scalar, Stations> report{};
    const std::size_t k_stations = head.stations <= Stations ? head.stations : Stations;

    // Holds and direction (see "Training runs"). A step that moves the depth by no more than
    // still_step holds it; the hold time counts consecutive such steps. The direction is
    // latched: it reverses once the depth has gone back by the hysteresis from its extreme since
    // the last turn, and the first move after a hold (>= kMinHoldSteps) sets it at once.
    const bool still =
        state.started && !(T::abs(depth_mm - state.last_depth_mm) > still_step_mm<Scalar>());
    if (!state.started) {
        state.direction = 1;
        state.turn_depth_mm = depth_mm;
    } else if (!still && state.hold_steps >= kMinHoldSteps) {
        state.direction = depth_mm < state.last_depth_mm ? -1 : 1;
        state.turn_depth_mm = depth_mm;
    } else if (state.direction > 0) {
        if (depth_mm > state.turn_depth_mm)
            state.turn_depth_mm = depth_mm;
        else if (depth_mm < state.turn_depth_mm - reverse_hysteresis_mm<Scalar>()) {
            state.direction = -1;
            state.turn_depth_mm = depth_mm;
        }
    } else {
        if (depth_mm < state.turn_depth_mm)
            state.turn_depth_mm = depth_mm;
        else if (depth_mm > state.turn_depth_mm + reverse_hysteresis_mm<Scalar>()) {
            state.direction = 1;
            state.turn_depth_mm = depth_mm;
        }
    }
    if (still) {
        if (state.hold_steps < kMaxHoldSteps) ++state.hold_steps;
    } else {
        state.hold_steps = 0U;
    }
    const Scalar hold_s = period_s * R::from_int(static_cast<int>(state.hold_steps));
    state.last_depth_mm = depth_mm;

    // Training run: while held, a hold run at this depth; else the last travel run in this
    // direction whose depths hold the depth; else the last travel run in the other direction
    // whose depths hold it (travelled backwards); else segment 0 (trained advancing from the
    // shallowest depth; the depth is clamped to it).
    std::size_t segment_index = 0;
    const std::size_t segment_count =
        head.segment_count <= kMaxReducedSegments ? head.segment_count : kMaxReducedSegments;
    bool holding = false;
    bool same_direction = false;
    for (std::size_t i = 0; i < segment_count; ++i) {  // bound: kMaxReducedSegments
        const ReducedSegment<Scalar>& candidate = head.segments[i];
        if (candidate.kind == kSegmentHold) {
            if (state.hold_steps >= kMinHoldSteps &&
                !(T::abs(depth_mm - candidate.hold_depth_mm) > reverse_hysteresis_mm<Scalar>())) {
                segment_index = i;
                holding = true;
            }
        } else if (!holding && !(depth_mm < candidate.key_start) &&
                   !(depth_mm > detail::segment_end_mm(candidate))) {
            const bool same = candidate.direction == state.direction;
            if (same || !same_direction) {
                segment_index = i;
                same_direction = same;
            }
        }
    }
    const ReducedSegment<Scalar>& segment = head.segments[segment_index];
    // A change of training run starts every station again on the new run's state.
    if (state.started && segment_index != state.segment) state.active_stations = 0;
    state.segment = segment_index;

    // Knot interval and weight; the key is clamped to the run (a travel run's depth: flagged).
    Scalar key = holding ? hold_s : depth_mm;
    if (key < segment.key_start) {
        key = segment.key_start;
        report.depth_clamped = !holding;
    }
    if (key > detail::segment_end_mm(segment)) {
        key = detail::segment_end_mm(segment);
        report.depth_clamped = !holding;
    }
    const Scalar depth = holding ? segment.hold_depth_mm : key;
    // Divided, not multiplied by a rounded reciprocal: in Q16.16 that would shift the interval
    // by up to 1/2 LSB of 1/step per interval.
    const Scalar cells = (key - segment.key_start) / segment.key_step;
    Scalar weight{};
    const std::size_t cell = detail::interval_of(cells, segment.knots - 1U, weight);
    const std::size_t knot = segment.first_knot + cell;
    const std::size_t next = knot + 1U;
    Scalar compliance_weight{};
    const std::size_t compliance_cell =
        detail::interval_of(cells / R::from_int(static_cast<int>(head.compliance_every)),
                            (segment.knots - 1U) / head.compliance_every, compliance_weight);
    const std::size_t record = segment.first_compliance + compliance_cell;

    // Stations inside the body: station j at j * spacing from the tip is inside once the depth
    // exceeds that (a prefix of the stations, the tip first).
    std::size_t active = 0;
    for (std::size_t j = 0; j < k_stations; ++j) {  // bound: Stations
        if (head.station_spacing_mm * R::from_int(static_cast<int>(j)) < depth) active = j + 1U;
    }

    // Interpolated training state.
    std::array<Scalar, Stations> path{};
    std::array<Scalar, Stations> gap{};
    for (std::size_t j = 0; j < active; ++j) {  // bound: Stations
        path[j] = detail::lerp(tables.station_value(knot, j, kStationPath),
                               tables.station_value(next, j, kStationPath), weight);
        gap[j] = detail::lerp(tables.station_value(knot, j, kStationGap),
                              tables.station_value(next, j, kStationGap), weight);
        for (std::size_t c = 0; c < 3U; ++c) {
            state.reference_force_N[j][c] =
                detail::lerp(tables.station_value(knot, j, kStationForceN + c),
                             tables.station_value(next, j, kStationForceN + c), weight);
        }
    }
    for (std::size_t c = 0; c < 3U; ++c) {
        state.tip_position_mm[c] = detail::lerp(tables.knot_value(knot, kKnotTipX + c),
                                                tables.knot_value(next, kKnotTipX + c), weight);
    }
    state.training_handle_force_N = detail::lerp(tables.knot_value(knot, kKnotHandleForce),
                                                 tables.knot_value(next, kKnotHandleForce), weight);
    auto& problem = state.problem;
    problem.contact_count = active;
    problem.block_diagonal = true;              // the off-diagonal blocks are never read
    for (std::size_t a = 0; a < active; ++a) {  // bound: Stations blocks of 9
        const std::size_t base = a * kComplianceValueCount;
        const auto compliance = [&](std::size_t v) {
            return detail::lerp(tables.compliance(record, base + v),
                                tables.compliance(record + 1U, base + v), compliance_weight);
        };
        auto& block = problem.block(a, a);
        block = {};
        block[0] = compliance(kComplianceNN);
        block[4] = compliance(kComplianceTT);
        block[5] = compliance(kComplianceTS);
        block[7] = block[5];
        block[8] = compliance(kComplianceSS);
    }

    // Newly entered stations start on the training state.
    if (!state.started) state.active_stations = 0;
    for (std::size_t a = state.active_stations; a < active; ++a) {  // bound: Stations
        state.reference_path_mm[a] = path[a];
        state.elastic_mm[a] = contact::ContactVec3<Scalar>{};
        state.force_N[a] = state.reference_force_N[a];
    }
    for (std::size_t a = active; a < Stations; ++a) {  // bound: Stations
        state.force_N[a] = contact::ContactVec3<Scalar>{};
        state.elastic_mm[a] = contact::ContactVec3<Scalar>{};
        state.contact_state[a] = contact::ContactState::separated;
        state.passive[a] = false;
    }

    // Station friction and the training's slip over the step (see "Station friction"):
    //   ratio = |f_ref,T| / f_ref,n;  mu_a = ratio where the training slid, max(mu, 1.05 ratio)
    //   where it stuck;  slip = (s_a Delta p_a) (-f_ref,T / |f_ref,T|) where it slid, 0 where
    //   it stuck (s_a = the training's slip sign, kStationSlid).
    // delta_free = (g, slip - u_prev,T) - W f_ref  (W block diagonal).
    const Scalar max_ratio = R::from_int(kMaxStationFrictionRatio);
    std::array<bool, Stations> training_slid{};
    for (std::size_t a = 0; a < active; ++a) {  // bound: Stations
        const contact::ContactVec3<Scalar>& f_ref = state.reference_force_N[a];
        const Scalar tangential = T::hypot(f_ref[1], f_ref[2]);
        const Scalar slip_sign = tables.slid(knot, a);
        const bool slid = !(slip_sign == T::zero());
        training_slid[a] = slid;
        // A stretch whose resultant pulls (f_n < 0: its nodes touch opposite walls) or lies far
        // outside any cone: the station follows the training (see "Passive stations").
        state.passive[a] = f_ref[0] < T::zero() || tangential > max_ratio * f_ref[0];
        const Scalar ratio =
            f_ref[0] > T::zero() && !state.passive[a] ? tangential / f_ref[0] : T::zero();
        const Scalar stuck_mu = stuck_margin<Scalar>() * ratio;
        problem.friction[a] = slid ? ratio : (stuck_mu < head.friction ? head.friction : stuck_mu);

        // The path moved by Delta p this step; the training slid by |Delta p| against its
        // friction force when the motion has the training's sign.
        const Scalar moved = path[a] - state.reference_path_mm[a];
        const Scalar along = slip_sign * moved;
        Scalar slip_t = T::zero();
        Scalar slip_s = T::zero();
        if (slid) {
            if (tangential > T::zero()) {
                slip_t = T::zero() - along * (f_ref[1] / tangential);
                slip_s = T::zero() - along * (f_ref[2] / tangential);
            } else {
                slip_t = moved;
            }
        }
        contact::ContactVec3<Scalar> w_f{};
        const auto& block = problem.block(a, a);
        for (std::size_t i = 0; i < 3U; ++i) {
            for (std::size_t j = 0; j < 3U; ++j)
                w_f[i] = w_f[i] + block[3U * i + j] * f_ref[j];
        }
        // A station whose training force presses on the wall is in contact (its interpolated
        // gap can be > 0 next to a knot where the stretch pulled or stood off).
        const Scalar gap_mm = f_ref[0] > T::zero() ? T::zero() : gap[a];
        problem.free_displacement[a] = {gap_mm - w_f[0], slip_t - state.elastic_mm[a][1] - w_f[1],
                                        slip_s - state.elastic_mm[a][2] - w_f[2]};
    }

    report.contact = contact::solve_contacts(problem, gauss_seidel, state.force_N);

    // u = W (f - f_ref); the tip's position along the colon.
    for (std::size_t a = 0; a < active; ++a) {  // bound: Stations
        contact::ContactVec3<Scalar> u{};
        const auto& block = problem.block(a, a);
        for (std::size_t i = 0; i < 3U; ++i) {
            for (std::size_t j = 0; j < 3U; ++j) {
                u[i] = u[i] +
                       block[3U * i + j] * (state.force_N[a][j] - state.reference_force_N[a][j]);
            }
        }
        if (state.passive[a]) {
            state.force_N[a] = state.reference_force_N[a];
            u = contact::ContactVec3<Scalar>{};
            report.contact.states[a] = training_slid[a] ? contact::ContactState::slipping
                                                        : contact::ContactState::sticking;
        }
        state.elastic_mm[a] = u;
        state.reference_path_mm[a] = path[a];
        state.contact_state[a] = report.contact.states[a];
    }
    state.active_stations = active;
    state.started = true;
    state.tip_path_mm = active > 0U ? path[0] + state.elastic_mm[0][1] : depth;
    return report;
}

}  // namespace scopekin::kinetics
