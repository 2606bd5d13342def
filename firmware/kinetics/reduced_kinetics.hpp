// reduced_kinetics.hpp — the reduced-order model of the scope in the colon: one template for the
// firmware's fixed-point scalar and for double (the "reduced double" the tests compare with).
//
// ------------------------------------------------------------------------------------------------
// The reduction (trajectory piecewise-linear, Rewieński & White 2003; built by model/reduction)
// ------------------------------------------------------------------------------------------------
// The scope inside the colon stays close to a path that insertion depth s moves it along. The
// full-order model (model/world: co-rotational Timoshenko scope, hollow-beam colon, Gauss-Seidel
// contact, implicit dynamics) is run offline over a training procedure — a slow advance through
// the colon — and at every grid depth s_g (a fixed step apart) it leaves:
//   * K contact STATIONS: scope points at fixed distances from the tip (station 0 = the tip),
//     each with its contact frame (n from the wall to the scope, t along the colon, s = n x t);
//   * per station: its position along the colon centerline p_g [mm], its gap to the wall g_g
//     [mm, >= 0] and the resultant wall force over the stretch of scope it stands for,
//     f_g = (f_n, f_t, f_s) [N] in its frame;
//   * the quasi-static compliance between the stations W_g [mm/N] (3K x 3K, symmetric): the
//     scope's tangent compliance with the handle held + the colon's compliance + the wall's.
// Station friction: a station's force is the resultant over a curved stretch of scope whose
// nodes each slide with |f_T| = mu f_n on their own wall normal, so the resultant's |f_T| / f_n
// is not mu — below it on a straight stretch, above it where the normals spread around a bend.
// Where the training slid a stretch (its path position advanced), the station's coefficient is
// that ratio: the training state then lies on the station's cone, as a sliding contact must;
// where the stretch stuck, it is max(mu, 1.05 x ratio), so the training state lies inside.
// Station gap: 0 where the stretch carries a wall force (in contact, even if the station's own
// node stands off the wall), the node's gap otherwise.
// What is kept: the contact mechanics at the stations (Signorini + Coulomb, the thesis's
// Delassus form, Eq. 4.19-4.24) linearised about the training state at the current depth, and
// history (stick, slip, the elastic deviation it causes). What is dropped: inertia and damping
// (the hand moves the scope slowly: the training procedure is quasi-static), contacts away from
// the stations (each station carries its stretch's resultant), the scope's own rotation (in the
// full-order model contacts act on the centerline, so roll does not load them either), and the
// nonlinearity between grid points (linear interpolation), and the coupling between stations:
// W_g is block diagonal, each station's compliance with the other stations held (the inverse of
// its diagonal block of the stations' stiffness W^-1, static condensation). The coupling the
// training state carries is kept; a deviation at one station does not spread to the next.
// (The full coupled quasi-static compliance — a cantilever's, up to ~1300 mm/N at the tip —
// made the deviations drift without bound and Gauss-Seidel stall: the stations have no opposite
// wall in this model to stop them.) Why the error should stay small: on the training procedure
// the model follows the training state (u stays near 0) and elsewhere deviates from it only
// through the contact solve — stations sticking where the training slid, or slipping backwards on
// withdrawal — and those deviations are elastic and local, u = W (f - f_g).
// Because W is block diagonal the station problems are independent: the Gauss-Seidel solve
// (the one solver, ContactProblem::block_diagonal set) is exact after one sweep.
// STATUS (issue 4, in progress): the firmware's step runs this model (kinetics.cpp). Measured
// against the full-order model on the reference scenarios (tests/model/test_reduced_accuracy):
// straight advance tip RMS 2.1 mm, station force RMS 0.91 N; sigmoid loop 9.6 mm, 1.75 N;
// withdrawal 9.3 mm, 2.6 N — not yet the 3 mm / 0.2 N. Two causes found so far: the
// full-order model's stick-slip between 340 and 560 mm depends on speed and on its own time step
// (tip up to 20-28 mm apart between runs at 17 and 25 mm/s, or 5 and 10 ms steps), which no
// depth-indexed table can follow; and at the locked tip the station frame (n from the station
// node's wall) does not match the force, which pushes head-on into the bend (|f_T| / f_n ~ 3).
//
// ------------------------------------------------------------------------------------------------
// One step (period h; units mm, N)
// ------------------------------------------------------------------------------------------------
// Interpolate p, g, f_ref, W at the depth s. State: u_prev (the elastic deviation of each
// station from the training state, station frame) and p_prev (the training path position of
// each station at the previous step). The contact problem of the step, per station a
// (delta = W f + delta_free, solved by the one Gauss-Seidel solver, fixed sweeps, warm start):
//   normal   : delta_n = gap after the step          = g_a + (W (f - f_ref))_a,n
//   tangents : delta_T = slip over the step          = training slip + u_a,T - u_prev,a,T
// with u = W (f - f_ref), hence
//   delta_free,a = ( g_a,  Delta p_a - u_prev,a,t,  r_a Delta p_a - u_prev,a,s ) - (W f_ref)_a,
// Delta p_a = p_a - p_prev,a, where r_a = f_ref,s / f_ref,t (clamped to +-1) turns the
// training's advance into its slip direction: Coulomb slip is opposite the friction force, so
// the training state solves the step when the inputs repeat the training's.
// After the solve u = W (f - f_ref); the tip's position along the colon is p_0 + u_0,t.
// Stations not yet inside the body (s <= arc from the tip) are left out; they enter with
// u = 0 and the training force as warm start.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "contact/gauss_seidel_contact.hpp"

namespace scopekin::kinetics {

/// Values per station per grid point, in this order.
enum ReducedStationValue : std::size_t {
    kStationPath = 0,    ///< p [mm]
    kStationGap = 1,     ///< g [mm]
    kStationForceN = 2,  ///< f_n [N]
    kStationForceT = 3,  ///< f_t [N]
    kStationForceS = 4,  ///< f_s [N]
    kStationFriction = 5,  ///< Coulomb coefficient of the station (see "Station friction")
    kStationValueCount = 6,
};

/// Size of one grid point's record: K station records, the tip's position (x, y, z) [mm, body
/// frame] and, per station, the upper triangle (00 01 02 11 12 22) of its 3x3 compliance block.
constexpr std::size_t reduced_record_size(std::size_t stations) noexcept {
    return stations * kStationValueCount + 3U + stations * 6U;
}

/// Index of W_aa(i, j) (i, j < 3) of station a in the record.
constexpr std::size_t compliance_index(std::size_t stations, std::size_t station, std::size_t i, std::size_t j) noexcept {
    const std::size_t r = i < j ? i : j;
    const std::size_t c = i < j ? j : i;
    // Row r of a 3x3 upper triangle starts at 0, 3, 5.
    const std::size_t row_start = r == 0U ? 0U : (r == 1U ? 3U : 5U);
    return stations * kStationValueCount + 3U + station * 6U + row_start + (c - r);
}

/// Integer -> Scalar (exact for the small counts used here).
template <typename Scalar>
struct ReducedScalarTraits {
    static Scalar from_int(int value) noexcept { return static_cast<Scalar>(value); }
};

/// The tables' fixed facts (same meaning for every Scalar).
template <typename Scalar>
struct ReducedModelHeader {
    std::size_t stations{0};        ///< K, <= the state's capacity
    std::size_t grid_points{0};     ///< >= 2
    Scalar depth_start_mm{};        ///< s_0
    Scalar depth_step_mm{};         ///< grid step
    Scalar inverse_depth_step{};    ///< 1 / grid step [1/mm]
    Scalar friction{};              ///< Coulomb mu of every station
    Scalar station_spacing_mm{};    ///< station j is j * spacing from the tip
};

/// What a Tables type provides (duck-typed, no virtual calls):
///   const ReducedModelHeader<Scalar>& header() const;
///   Scalar value(std::size_t grid_point, std::size_t index_in_record) const;

template <typename Scalar, std::size_t Stations>
struct ReducedState {
    contact::ContactProblem<Scalar, Stations> problem{};
    contact::ContactForces<Scalar, Stations> force_N{};                   ///< last solution (warm start)
    std::array<contact::ContactVec3<Scalar>, Stations> reference_force_N{};
    std::array<contact::ContactVec3<Scalar>, Stations> elastic_mm{};      ///< u, station frame
    std::array<Scalar, Stations> reference_path_mm{};                     ///< p at the last step
    std::array<contact::ContactState, Stations> contact_state{};
    std::size_t active_stations{0};
    Scalar tip_path_mm{};
    std::array<Scalar, 3> tip_position_mm{};  ///< training tip position at the depth (body frame)
    bool started{false};
};

template <typename Scalar, std::size_t Stations>
struct ReducedStepReport {
    contact::ContactSolveReport<Scalar, Stations> contact{};
    bool depth_clamped{false};  ///< the depth was outside the grid and was clamped to it
};

namespace detail {

template <typename Scalar>
Scalar lerp(Scalar a, Scalar b, Scalar weight) noexcept {
    return a + weight * (b - a);
}

}  // namespace detail

/// One step at insertion depth `depth_mm` (validated by the caller).  Fixed work: K stations,
/// `gauss_seidel.max_sweeps` sweeps when gauss_seidel.mode is fixed.
template <typename Scalar, std::size_t Stations, typename Tables>
ReducedStepReport<Scalar, Stations> reduced_step(const Tables& tables, Scalar depth_mm,
                                                 ReducedState<Scalar, Stations>& state,
                                                 const contact::GaussSeidelSettings<Scalar>& gauss_seidel) noexcept {
    using T = contact::ContactScalarTraits<Scalar>;
    const ReducedModelHeader<Scalar>& head = tables.header();
    ReducedStepReport<Scalar, Stations> report{};
    const std::size_t k_stations = head.stations <= Stations ? head.stations : Stations;

    // Grid cell and weight; the depth is clamped to the grid.
    const Scalar last_depth = head.depth_start_mm + head.depth_step_mm * ReducedScalarTraits<Scalar>::from_int(static_cast<int>(head.grid_points - 1U));
    Scalar depth = depth_mm;
    if (depth < head.depth_start_mm) {
        depth = head.depth_start_mm;
        report.depth_clamped = true;
    }
    if (depth > last_depth) {
        depth = last_depth;
        report.depth_clamped = true;
    }
    // Divided, not multiplied by the stored 1/step: in Q16.16 the rounded reciprocal (6554 raw for
    // 1/10 mm) would shift the cell by 6e-5 per cell, 0.04 mm of path at 700 mm.
    const Scalar cells = (depth - head.depth_start_mm) / head.depth_step_mm;
    std::size_t cell = 0;
    for (std::size_t g = 1; g + 1U < head.grid_points; ++g) {  // bound: grid points
        if (ReducedScalarTraits<Scalar>::from_int(static_cast<int>(g)) <= cells) cell = g;
    }
    const Scalar weight = cells - ReducedScalarTraits<Scalar>::from_int(static_cast<int>(cell));
    const std::size_t next = cell + 1U;

    // Stations inside the body: station j at j * spacing from the tip is inside once the depth
    // exceeds that (a prefix of the stations, the tip first).
    std::size_t active = 0;
    for (std::size_t j = 0; j < k_stations; ++j) {  // bound: Stations
        if (head.station_spacing_mm * ReducedScalarTraits<Scalar>::from_int(static_cast<int>(j)) < depth) active = j + 1U;
    }

    // Interpolated training state.
    std::array<Scalar, Stations> path{};
    std::array<Scalar, Stations> gap{};
    for (std::size_t j = 0; j < active; ++j) {  // bound: Stations
        const std::size_t base = j * kStationValueCount;
        path[j] = detail::lerp(tables.value(cell, base + kStationPath), tables.value(next, base + kStationPath), weight);
        gap[j] = detail::lerp(tables.value(cell, base + kStationGap), tables.value(next, base + kStationGap), weight);
        for (std::size_t c = 0; c < 3U; ++c) {
            state.reference_force_N[j][c] = detail::lerp(tables.value(cell, base + kStationForceN + c),
                                                         tables.value(next, base + kStationForceN + c), weight);
        }
    }
    const std::size_t tip_base = k_stations * kStationValueCount;
    for (std::size_t c = 0; c < 3U; ++c) {
        state.tip_position_mm[c] = detail::lerp(tables.value(cell, tip_base + c), tables.value(next, tip_base + c), weight);
    }
    auto& problem = state.problem;
    problem.contact_count = active;
    problem.block_diagonal = true;  // the off-diagonal blocks are never read
    for (std::size_t a = 0; a < active; ++a) {  // bound: Stations blocks of 9
        for (std::size_t i = 0; i < 3U; ++i) {
            for (std::size_t j = 0; j < 3U; ++j) {
                const std::size_t index = compliance_index(k_stations, a, i, j);
                problem.block(a, a)[3U * i + j] = detail::lerp(tables.value(cell, index), tables.value(next, index), weight);
            }
        }
        const std::size_t base = a * kStationValueCount + kStationFriction;
        problem.friction[a] = detail::lerp(tables.value(cell, base), tables.value(next, base), weight);
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
    }

    // delta_free = (g, p - p_prev - u_prev,t, -u_prev,s) - W f_ref  (W block diagonal).
    for (std::size_t a = 0; a < active; ++a) {  // bound: Stations
        contact::ContactVec3<Scalar> w_f{};
        const auto& block = problem.block(a, a);
        for (std::size_t i = 0; i < 3U; ++i) {
            for (std::size_t j = 0; j < 3U; ++j) w_f[i] = w_f[i] + block[3U * i + j] * state.reference_force_N[a][j];
        }
        // The training's slip over the step: along the path by the advance, and sideways as its
        // friction force says (Coulomb: slip opposite f_T, so slip_s / slip_t = f_s / f_t),
        // the ratio clamped to +-1 where f_t is small.
        const Scalar advance = path[a] - state.reference_path_mm[a];
        const Scalar ft = state.reference_force_N[a][1];
        const Scalar fs = state.reference_force_N[a][2];
        const Scalar one = ReducedScalarTraits<Scalar>::from_int(1);
        Scalar lateral_ratio = T::zero();
        if (T::abs(fs) < T::abs(ft)) {
            lateral_ratio = fs / ft;
        } else if (!(fs == T::zero())) {
            lateral_ratio = (fs < T::zero()) == (ft < T::zero()) ? one : T::zero() - one;
        }
        problem.free_displacement[a] = {gap[a] - w_f[0],
                                        advance - state.elastic_mm[a][1] - w_f[1],
                                        advance * lateral_ratio - state.elastic_mm[a][2] - w_f[2]};
    }

    report.contact = contact::solve_contacts(problem, gauss_seidel, state.force_N);

    // u = W (f - f_ref); the tip's position along the colon.
    for (std::size_t a = 0; a < active; ++a) {  // bound: Stations
        contact::ContactVec3<Scalar> u{};
        const auto& block = problem.block(a, a);
        for (std::size_t i = 0; i < 3U; ++i) {
            for (std::size_t j = 0; j < 3U; ++j) {
                u[i] = u[i] + block[3U * i + j] * (state.force_N[a][j] - state.reference_force_N[a][j]);
            }
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
