// gauss_seidel_contact.hpp — ONE frictional contact solver for the firmware and the model.
//
// Header-only C++20 template, instantiated for `double` by the reference model (model/, now) and
// for the firmware's fixed-point scalar (later).  Portable on purpose: no Eigen, no heap, no
// exceptions, no RTTI, no recursion, every loop bounded by MaxContacts, an explicitly passed
// count, or a settings field.  Only +, -, *, /, comparisons and ContactScalarTraits<Scalar>
// (zero, one, epsilon, abs, sqrt) are applied to Scalar.
//
// ------------------------------------------------------------------------------------------------
// Problem (thesis 4.4, Eq. 4.19-4.23; Duriez et al. 2006; SOFA LCPcalc)
// ------------------------------------------------------------------------------------------------
// n contacts a = 0..n-1, each with a local frame (n, t, s): n = outward normal of the obstacle
// (positive delta_n = separating), t and s span the tangent plane.  Per contact, the 3-vectors are
// ordered (normal, t, s).
//
//   delta = W f + delta_free                                               (Eq. 4.23, stacked)
//   Signorini (Eq. 4.19):   0 <= f_n  ⟂  delta_n >= 0
//   Coulomb   (Eq. 4.21-4.22), friction coefficient mu_a >= 0 per contact:
//       ||f_T|| <= mu_a f_n;
//       stick: ||f_T|| <  mu_a f_n  ⇒  delta_T = 0
//       slip:  ||f_T|| == mu_a f_n  and  f_T = -mu_a f_n delta_T / ||delta_T||
//   W (Eq. 4.20/4.24): the Delassus operator, 3n x 3n, symmetric positive definite in its 3x3
//   diagonal blocks W_aa (the global W may be semidefinite), blocks W_ab.
//
// Units: delta, delta_free in mm (a displacement over the step; a velocity in mm/s works the same
// way with W in mm/(N s)), f in N, W in mm/N, mu dimensionless.  The sweep tolerance and every
// reported residual are in N.
//
// ------------------------------------------------------------------------------------------------
// Algorithm: projected block Gauss-Seidel with an exact local 3x3 solve
// ------------------------------------------------------------------------------------------------
// One sweep visits a = 0..n-1 in order.  For contact a (Eq. 4.23):
//     d_a = delta_free_a + sum_{b != a} W_ab f_b          (uses the f_b already updated this sweep)
// then solves the ONE-contact problem  delta_a = W_aa f_a + d_a  with Signorini + Coulomb exactly:
//   (1) separation: d_a,n >= 0  ⇒  f_a = 0.
//   (2) stick:      f_a = -W_aa^-1 d_a (delta_a = 0); accepted if f_n >= 0 and ||f_T|| <= mu f_n.
//   (3) slip:       delta_n = 0 eliminates f_n = c - b·f_T with c = -d_n / W_nn > 0 and
//                   b = W_nT / W_nn.  Then delta_T = S f_T + e, S = W_TT - W_Tn b^T (2x2 Schur
//                   complement, SPD), e = d_T + c W_Tn.  Slip means delta_T = -kappa f_T with
//                   kappa > 0, i.e.   f_T(kappa) = -(S + kappa I)^-1 e,   and kappa is the root of
//                       phi(kappa) = ||f_T(kappa)|| - mu (c - b·f_T(kappa)) = 0     (in N).
//                   kappa = 0 is the stick solution, so phi(0) > 0 whenever (2) was rejected; and
//                   since ||f_T(kappa)|| <= ||e|| / (s_min + kappa),
//                       kappa_hi = (1 + mu ||b||_1) ||e||_1 / (mu c)   gives phi(kappa_hi) < 0.
//                   The root is found by safeguarded Newton (Newton step if it stays inside the
//                   bracket [lo, hi], else bisection), at most `local_iterations` steps, started
//                   from the isotropic closed form kappa_0 = ||e|| / (mu c) - (S_tt + S_ss)/2,
//                   which is the exact root when S = s I and b = 0 (diagonal W_aa with equal
//                   tangential terms): then one evaluation suffices.  Without the Newton steps
//                   the bracket halves each step, so the worst case is a bisection of
//                   [0, kappa_hi] to kappa_hi / 2^local_iterations.  Any root gives a valid
//                   slip state: delta_n = 0, f_T antiparallel to delta_T, ||f_T|| = mu f_n (hence
//                   f_n >= 0).  mu = 0 is the frictionless case f = (c, 0, 0).
//                   Finally f_n is clamped to >= 0 and f_T is scaled back onto the cone if
//                   rounding left it outside.
// Over-relaxation (projected SOR, optional): with omega = settings.relaxation in (0, 2) each local
// result is moved to f_a + omega (f_local - f_a) and projected back (f_n >= 0, ||f_T|| <= mu f_n).
// Contacts along a beam lying on a wall couple strongly (smooth, slowly converging modes), and
// omega ~ 1.3-1.5 cuts the sweeps there; the fixed point is the same, so the residuals are judged
// as before.  A projected state is reported as the local solve's state.
// Warm start: the caller passes f in/out; the sweep starts from it.
// Stopping: `until_converged` stops after the first sweep whose largest change of any force
// component (N) is <= tolerance, or after max_sweeps; `fixed` always does exactly max_sweeps sweeps
// and every slip solve does all local_iterations steps, so the work per call is bounded by the
// worst case below and the sweep count does not depend on the data (the per-contact branch —
// separated, stick, slip — still does; the slip branch is the most expensive).  Worst case work:
// max_sweeps * n * (n-1) 3x3 block products plus max_sweeps * n local solves of at most
// local_iterations root-finder steps each (each step: one 2x2 solve, one sqrt).
//
// Convergence assumptions: each W_aa is positive definite (checked: W_nn > 0 and det S > 0; a
// contact that fails is reported `degenerate` and gets f = 0).  For mu = 0 the sweep is projected
// Gauss-Seidel on the normal LCP, which converges for symmetric positive definite W (Cryer 1971);
// for semidefinite W only when the LCP is solvable, and then it is delta that converges, not
// necessarily f (Cottle, Pang & Stone 1992, ch. 5).  With friction there is no general
// convergence proof (the Coulomb problem is not a minimisation); it converges in practice for
// moderate mu and W_aa dominant (tests: 1000 random problems, n = 2..20, mu in [0, 1], W of full
// rank: all converge, median 12 sweeps to 1e-6 N).  With redundant contacts (W rank-deficient
// before regularisation, 3n > number of DOFs) frictional Gauss-Seidel can cycle: in a trial with
// rank(J) = 3n/2 + 1 and 1e-3 mm/N regularisation, 2 of 1000 problems did not converge in 20000
// sweeps.  That is why the report always carries the residuals — callers judge the result by them,
// not by the sweep count.
//
// Residuals (evaluate_contact_residuals; reported after every solve), all in N, max over contacts:
//   complementarity = |min(f_n, delta_n / W_aa,nn)|   (Signorini natural map in force units; it
//                     also catches f_n < 0 and delta_n < 0)
//   cone_violation  = max(0, ||f_T|| - mu f_n)
//   friction        = ||f_T - proj_{||x|| <= mu f_n}(f_T - delta_T / w_T)||, w_T = (W_tt + W_ss)/2
//                     (Coulomb natural map: zero iff f_T is in the disc and -delta_T lies in the
//                     disc's normal cone at f_T, i.e. stick with delta_T = 0 or slip opposite delta_T)
//
// ------------------------------------------------------------------------------------------------
// Scaling and overflow (to be completed with the fixed-point instantiation, firmware issue)
// ------------------------------------------------------------------------------------------------
// A fixed-point Scalar must provide +, -, *, / (saturating), comparisons, value-initialisation to
// zero and a ContactScalarTraits specialisation (sqrt by integer Newton/bit-by-bit, abs,
// epsilon = 1 LSB).  Quantities and what their format must hold:
//   * W entries (mm/N): the compliance of a scope contact station is ~0.01-10 mm/N, so W needs
//     fractional resolution (e.g. Q8.24 or Q16.16 with care); off-diagonal terms are smaller.
//   * delta, d (mm): |d| up to a few tens of mm (tube diameter 25 mm) — Q16.16 is ample.
//   * f (N): 0..~50 N.
//   * products W_ab f_b and the sum over b need a 64-bit accumulator (dot products, DESIGN.md) —
//     here the sum over up to MaxContacts blocks is done in Scalar, so guard bits for
//     log2(3 MaxContacts) extra terms are needed or the accumulation must move into the scalar's
//     own wide dot product.
//   * The slip solve forms kappa (mm/N) up to kappa_hi = (1 + mu ||b||_1) ||e||_1 / (mu c):
//     unbounded as mu -> 0 or c -> 0.  A fixed-point instantiation must treat mu below a threshold
//     as frictionless and clamp kappa_hi to the format's range (phi(kappa) is still < 0 there when
//     ||e|| / kappa_max < mu c; otherwise the clamp is the answer to within the format).
//   * ||x|| = sqrt(x_t^2 + x_s^2) squares forces (N^2) and displacements: the squares need range
//     (50 N -> 2500) or a pre-scaled hypot.
//   * det S and (S + kappa I)^-1 square compliances: det of ~1e-2 mm/N terms is ~1e-4 and must
//     not underflow; scale W per contact (divide the local problem by W_nn) if needed.
//   * Divisions: by W_nn (> 0 checked), by det(S + kappa I) (> det S > 0), by mu c (> 0 in the
//     slip branch), by ||f_T|| (guarded).  Every division's divisor is checked > 0 before use.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace scopekin::contact {

// ------------------------------------------------------------------------------------------------
// Scalar traits: the only non-arithmetic operations the solver applies to Scalar.
// ------------------------------------------------------------------------------------------------
template <typename Scalar>
struct ContactScalarTraits;  // specialise for every Scalar the solver is instantiated with

template <>
struct ContactScalarTraits<double> {
    static constexpr double zero() noexcept { return 0.0; }
    static constexpr double one() noexcept { return 1.0; }
    static constexpr double epsilon() noexcept { return std::numeric_limits<double>::epsilon(); }
    static double abs(double x) noexcept { return std::fabs(x); }
    static double sqrt(double x) noexcept { return std::sqrt(x); }
};

template <>
struct ContactScalarTraits<float> {
    static constexpr float zero() noexcept { return 0.0F; }
    static constexpr float one() noexcept { return 1.0F; }
    static constexpr float epsilon() noexcept { return std::numeric_limits<float>::epsilon(); }
    static float abs(float x) noexcept { return std::fabs(x); }
    static float sqrt(float x) noexcept { return std::sqrt(x); }
};

// ------------------------------------------------------------------------------------------------
// Data
// ------------------------------------------------------------------------------------------------
/// Per-contact 3-vector in the contact frame, ordered (n, t, s).
template <typename Scalar>
using ContactVec3 = std::array<Scalar, 3>;

/// 3x3 block, row-major, rows and columns ordered (n, t, s).
template <typename Scalar>
using ContactBlock3 = std::array<Scalar, 9>;

/// Contact problem of at most MaxContacts contacts.  All storage is inline (no heap): the Delassus
/// operator is MaxContacts x MaxContacts blocks of 3x3 (9 * MaxContacts^2 scalars), of which the
/// leading contact_count x contact_count blocks are used.
template <typename Scalar, std::size_t MaxContacts>
struct ContactProblem {
    static_assert(MaxContacts >= 1, "a contact problem needs room for at least one contact");

    /// Number of active contacts, <= MaxContacts (checked by solve_contacts).
    std::size_t contact_count{0};
    /// W (mm/N), block (a, b) at index a * MaxContacts + b.
    std::array<ContactBlock3<Scalar>, MaxContacts * MaxContacts> delassus{};
    /// delta_free (mm), gap along n first.
    std::array<ContactVec3<Scalar>, MaxContacts> free_displacement{};
    /// Coulomb friction coefficient mu_a >= 0 per contact.
    std::array<Scalar, MaxContacts> friction{};

    ContactBlock3<Scalar>& block(std::size_t a, std::size_t b) noexcept {
        return delassus[a * MaxContacts + b];
    }
    const ContactBlock3<Scalar>& block(std::size_t a, std::size_t b) const noexcept {
        return delassus[a * MaxContacts + b];
    }
    /// Entry (i, j) of the 3n x 3n matrix W, i = 3 a + local row, j = 3 b + local column.
    Scalar& delassus_entry(std::size_t i, std::size_t j) noexcept {
        return delassus[(i / 3U) * MaxContacts + j / 3U][(i % 3U) * 3U + j % 3U];
    }
    const Scalar& delassus_entry(std::size_t i, std::size_t j) const noexcept {
        return delassus[(i / 3U) * MaxContacts + j / 3U][(i % 3U) * 3U + j % 3U];
    }
};

/// Contact forces (N), one (f_n, f_t, f_s) per contact: the solver's warm start in, solution out.
template <typename Scalar, std::size_t MaxContacts>
using ContactForces = std::array<ContactVec3<Scalar>, MaxContacts>;

enum class ContactState : std::uint8_t {
    separated,   ///< f = 0 (d_n >= 0 in the last local solve)
    sticking,    ///< delta = 0, ||f_T|| <= mu f_n
    slipping,    ///< delta_n = 0, ||f_T|| = mu f_n, f_T opposite delta_T
    degenerate,  ///< W_aa not positive definite: f = 0, contact ignored
};

enum class SweepMode : std::uint8_t {
    until_converged,  ///< stop at the first sweep with change <= tolerance, at most max_sweeps
    fixed,            ///< exactly max_sweeps sweeps, full local iterations (same work every call)
};

template <typename Scalar>
struct GaussSeidelSettings {
    SweepMode mode{SweepMode::until_converged};
    /// Upper bound on sweeps (until_converged) or the exact number of sweeps (fixed).
    std::size_t max_sweeps{100};
    /// Largest change of any force component between two sweeps (N) that counts as converged.
    Scalar tolerance{};
    /// Bound on the safeguarded-Newton steps of one local slip solve.
    std::size_t local_iterations{60};
    /// Over-relaxation omega in (0, 2): f_a <- f_a + omega (f_local - f_a), then projected back
    /// onto f_n >= 0 and the friction cone.  Zero (the default) means 1: plain Gauss-Seidel.
    Scalar relaxation{};
};

enum class ContactSolveStatus : std::uint8_t {
    converged,           ///< until_converged: last change <= tolerance
    max_sweeps_reached,  ///< until_converged: stopped by max_sweeps with change > tolerance
    fixed_sweeps_done,   ///< fixed: max_sweeps sweeps done (judge by the residuals)
    invalid_input,       ///< contact_count > MaxContacts, mu < 0 (or NaN), tolerance < 0,
                         ///< relaxation >= 2:
                         ///< nothing solved, forces left untouched, residuals zero
};

/// Residuals of a solution, all in N, maxima over contacts (definitions in the header comment).
template <typename Scalar>
struct ContactResiduals {
    Scalar complementarity{};
    Scalar cone_violation{};
    Scalar friction{};
};

template <typename Scalar, std::size_t MaxContacts>
struct ContactSolveReport {
    ContactSolveStatus status{ContactSolveStatus::invalid_input};
    std::size_t sweeps{0};
    /// Largest change of a force component (N) in the last sweep.
    Scalar last_change{};
    ContactResiduals<Scalar> residuals{};
    /// Number of contacts found degenerate in the last sweep.
    std::size_t degenerate_contacts{0};
    /// State of each contact after the last sweep (first contact_count entries are meaningful).
    std::array<ContactState, MaxContacts> states{};
};

/// Result of one local (single-contact) solve.
template <typename Scalar>
struct LocalContactSolution {
    ContactVec3<Scalar> force{};
    ContactState state{ContactState::separated};
    std::size_t iterations{0};  ///< slip root-finder steps
};

// ------------------------------------------------------------------------------------------------
// Implementation
// ------------------------------------------------------------------------------------------------
namespace detail {

/// f_old + omega (f_new - f_old), projected onto f_n >= 0 and ||f_T|| <= mu f_n.
template <typename Scalar>
ContactVec3<Scalar> relax_and_project(const ContactVec3<Scalar>& f_old, const ContactVec3<Scalar>& f_new,
                                      Scalar omega, Scalar mu) noexcept {
    using T = ContactScalarTraits<Scalar>;
    ContactVec3<Scalar> f{};
    for (std::size_t i = 0; i < 3U; ++i) {
        f[i] = f_old[i] + omega * (f_new[i] - f_old[i]);
    }
    if (f[0] < T::zero()) {
        return ContactVec3<Scalar>{T::zero(), T::zero(), T::zero()};
    }
    const Scalar tangential = T::sqrt(f[1] * f[1] + f[2] * f[2]);
    const Scalar limit = mu * f[0];
    if (tangential > limit) {
        const Scalar scale = tangential > T::zero() ? limit / tangential : T::zero();
        f[1] = f[1] * scale;
        f[2] = f[2] * scale;
    }
    return f;
}


template <typename Scalar>
Scalar norm2(Scalar x, Scalar y) noexcept {
    using T = ContactScalarTraits<Scalar>;
    return T::sqrt(x * x + y * y);
}

template <typename Scalar>
Scalar max_of(Scalar a, Scalar b) noexcept {
    return a < b ? b : a;
}

/// f_T(kappa) = -(S + kappa I)^-1 e and d f_T / d kappa = -(S + kappa I)^-1 f_T.
/// Returns false if det(S + kappa I) <= 0.
template <typename Scalar>
bool tangential_force(const std::array<Scalar, 4>& s, const std::array<Scalar, 2>& e,
                      Scalar kappa, std::array<Scalar, 2>& f_t,
                      std::array<Scalar, 2>& df_t) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar m00 = s[0] + kappa;
    const Scalar m11 = s[3] + kappa;
    const Scalar det = m00 * m11 - s[1] * s[2];
    if (!(det > T::zero())) {
        return false;
    }
    // inverse = [m11 -s01; -s10 m00] / det
    f_t[0] = -(m11 * e[0] - s[1] * e[1]) / det;
    f_t[1] = -(m00 * e[1] - s[2] * e[0]) / det;
    df_t[0] = -(m11 * f_t[0] - s[1] * f_t[1]) / det;
    df_t[1] = -(m00 * f_t[1] - s[2] * f_t[0]) / det;
    return true;
}

}  // namespace detail

/// Exact solve of one contact: delta = A f + d with Signorini and Coulomb (coefficient mu).
/// A is W_aa (row-major (n, t, s)).  `full_iterations` makes the slip root-finder do all
/// `local_iterations` steps (fixed work).  `previous` (optional): this contact's force from the
/// last sweep, used only to start the slip root-finder (any start inside the bracket converges).
template <typename Scalar>
LocalContactSolution<Scalar> solve_local_contact(const ContactBlock3<Scalar>& a,
                                                 const ContactVec3<Scalar>& d, Scalar mu,
                                                 std::size_t local_iterations,
                                                 bool full_iterations,
                                                 const ContactVec3<Scalar>* previous = nullptr) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar zero = T::zero();
    const Scalar one = T::one();
    const Scalar two = one + one;
    LocalContactSolution<Scalar> out{};
    out.force = {zero, zero, zero};

    // (1) Separation.
    if (d[0] >= zero) {
        out.state = ContactState::separated;
        return out;
    }
    const Scalar a_nn = a[0];
    if (!(a_nn > zero)) {
        out.state = ContactState::degenerate;
        return out;
    }
    // Eliminate delta_n = 0:  f_n = c - b·f_T,  delta_T = S f_T + e.
    const Scalar c = -d[0] / a_nn;
    const std::array<Scalar, 2> b{a[1] / a_nn, a[2] / a_nn};
    const std::array<Scalar, 4> s{a[4] - a[3] * b[0], a[5] - a[3] * b[1],  //
                                  a[7] - a[6] * b[0], a[8] - a[6] * b[1]};
    const std::array<Scalar, 2> e{d[1] + c * a[3], d[2] + c * a[6]};
    const Scalar det_s = s[0] * s[3] - s[1] * s[2];
    // Relative test: det S > eps * (trace S)^2 (and trace S > 0).
    const Scalar trace_s = s[0] + s[3];
    if (!(trace_s > zero) || !(det_s > T::epsilon() * trace_s * trace_s)) {
        out.state = ContactState::degenerate;
        return out;
    }

    // (2) Stick: kappa = 0.
    std::array<Scalar, 2> f_t{zero, zero};
    std::array<Scalar, 2> df_t{zero, zero};
    detail::tangential_force(s, e, zero, f_t, df_t);
    {
        const Scalar f_n = c - (b[0] * f_t[0] + b[1] * f_t[1]);
        if (f_n >= zero && detail::norm2(f_t[0], f_t[1]) <= mu * f_n) {
            out.force = {f_n, f_t[0], f_t[1]};
            out.state = ContactState::sticking;
            return out;
        }
    }

    // (3) Slip.
    out.state = ContactState::slipping;
    if (!(mu > zero)) {
        out.force = {c, zero, zero};  // frictionless: delta_n = 0, f_T = 0
        return out;
    }
    const Scalar mu_c = mu * c;
    const Scalar b_1 = T::abs(b[0]) + T::abs(b[1]);
    const Scalar e_1 = T::abs(e[0]) + T::abs(e[1]);
    Scalar lo = zero;                              // phi(lo) > 0 (stick rejected)
    Scalar hi = (one + mu * b_1) * e_1 / mu_c;     // phi(hi) < 0 (see header)
    Scalar kappa = detail::norm2(e[0], e[1]) / mu_c - trace_s / two;  // isotropic closed form
    if (previous != nullptr) {
        // Gauss-Seidel revisits the contact with a slightly different d: the kappa of the last
        // slip force, kappa = -(S f_T + e).f_T / |f_T|^2, is then a much closer start.
        const Scalar pt = (*previous)[1];
        const Scalar ps = (*previous)[2];
        const Scalar p2 = pt * pt + ps * ps;
        if (p2 > zero) {
            const Scalar dt = s[0] * pt + s[1] * ps + e[0];
            const Scalar ds = s[2] * pt + s[3] * ps + e[1];
            const Scalar guess = -(dt * pt + ds * ps) / p2;
            if (guess > lo && guess < hi) {
                kappa = guess;
            }
        }
    }
    if (!(kappa > lo && kappa < hi)) {
        kappa = (lo + hi) / two;
    }
    const Scalar eight = two * two * two;
    const Scalar phi_tolerance = eight * eight * T::epsilon() * mu_c;  // 64 eps relative
    for (std::size_t it = 0; it < local_iterations; ++it) {
        out.iterations = it + 1U;
        if (!detail::tangential_force(s, e, kappa, f_t, df_t)) {
            break;  // unreachable for kappa >= 0 and det S > 0; keeps the last f_t
        }
        const Scalar norm_t = detail::norm2(f_t[0], f_t[1]);
        const Scalar phi = norm_t - mu * (c - (b[0] * f_t[0] + b[1] * f_t[1]));
        if (phi > zero) {
            lo = kappa;
        } else {
            hi = kappa;
        }
        if (!full_iterations && T::abs(phi) <= phi_tolerance) {
            break;
        }
        Scalar next = (lo + hi) / two;
        if (norm_t > zero) {
            const Scalar dphi =
                (f_t[0] * df_t[0] + f_t[1] * df_t[1]) / norm_t +
                mu * (b[0] * df_t[0] + b[1] * df_t[1]);
            if (dphi < zero) {
                const Scalar newton = kappa - phi / dphi;
                if (newton >= lo && newton <= hi) {
                    next = newton;
                }
            }
        }
        kappa = next;
    }
    detail::tangential_force(s, e, kappa, f_t, df_t);
    Scalar f_n = c - (b[0] * f_t[0] + b[1] * f_t[1]);
    if (f_n < zero) {
        f_n = zero;
    }
    const Scalar norm_t = detail::norm2(f_t[0], f_t[1]);
    const Scalar limit = mu * f_n;
    if (norm_t > limit && norm_t > zero) {
        const Scalar scale = limit / norm_t;
        f_t[0] = f_t[0] * scale;
        f_t[1] = f_t[1] * scale;
    }
    out.force = {f_n, f_t[0], f_t[1]};
    return out;
}

/// Residuals of forces f for a problem (definitions in the header comment); O(n^2) blocks.
/// Contacts beyond MaxContacts are ignored (count is clamped).
template <typename Scalar, std::size_t MaxContacts>
ContactResiduals<Scalar> evaluate_contact_residuals(
    const ContactProblem<Scalar, MaxContacts>& p,
    const ContactForces<Scalar, MaxContacts>& f) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar zero = T::zero();
    const Scalar one = T::one();
    const Scalar two = one + one;
    const std::size_t n = p.contact_count < MaxContacts ? p.contact_count : MaxContacts;
    ContactResiduals<Scalar> r{zero, zero, zero};
    for (std::size_t a = 0; a < n; ++a) {  // bound: MaxContacts
        ContactVec3<Scalar> delta = p.free_displacement[a];
        for (std::size_t b = 0; b < n; ++b) {  // bound: MaxContacts
            const ContactBlock3<Scalar>& w = p.block(a, b);
            for (std::size_t i = 0; i < 3U; ++i) {
                delta[i] = delta[i] + w[i * 3U] * f[b][0] + w[i * 3U + 1U] * f[b][1] +
                           w[i * 3U + 2U] * f[b][2];
            }
        }
        const ContactBlock3<Scalar>& w_aa = p.block(a, a);
        const Scalar f_n = f[a][0];
        // Signorini natural map in N.
        const Scalar scaled_gap = w_aa[0] > zero ? delta[0] / w_aa[0] : delta[0];
        const Scalar m = f_n < scaled_gap ? f_n : scaled_gap;
        r.complementarity = detail::max_of(r.complementarity, T::abs(m));
        // Cone.
        const Scalar mu = p.friction[a];
        const Scalar limit = f_n > zero ? mu * f_n : zero;
        const Scalar norm_t = detail::norm2(f[a][1], f[a][2]);
        r.cone_violation = detail::max_of(r.cone_violation, norm_t - mu * f_n);
        // Coulomb natural map in N.
        const Scalar w_t = (w_aa[4] + w_aa[8]) / two;
        if (w_t > zero) {
            Scalar y_t = f[a][1] - delta[1] / w_t;
            Scalar y_s = f[a][2] - delta[2] / w_t;
            const Scalar norm_y = detail::norm2(y_t, y_s);
            if (norm_y > limit) {
                if (norm_y > zero) {
                    y_t = y_t * (limit / norm_y);
                    y_s = y_s * (limit / norm_y);
                }
            }
            r.friction = detail::max_of(r.friction, detail::norm2(f[a][1] - y_t, f[a][2] - y_s));
        }
    }
    return r;
}

/// Block Gauss-Seidel solve.  `forces` is the warm start on entry and the solution on return.
template <typename Scalar, std::size_t MaxContacts>
ContactSolveReport<Scalar, MaxContacts> solve_contacts(
    const ContactProblem<Scalar, MaxContacts>& p, const GaussSeidelSettings<Scalar>& settings,
    ContactForces<Scalar, MaxContacts>& forces) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar zero = T::zero();
    ContactSolveReport<Scalar, MaxContacts> report{};
    report.status = ContactSolveStatus::invalid_input;
    report.last_change = zero;
    report.residuals = ContactResiduals<Scalar>{zero, zero, zero};
    for (std::size_t a = 0; a < MaxContacts; ++a) {
        report.states[a] = ContactState::separated;
    }
    const std::size_t n = p.contact_count;
    if (n > MaxContacts || !(settings.tolerance >= zero)) {
        return report;
    }
    for (std::size_t a = 0; a < n; ++a) {  // bound: MaxContacts
        if (!(p.friction[a] >= zero)) {
            return report;
        }
    }
    const bool fixed = settings.mode == SweepMode::fixed;
    const bool relaxed = settings.relaxation > zero && !(settings.relaxation == T::one());
    if (relaxed && !(settings.relaxation < T::one() + T::one())) {
        return report;  // omega must be in (0, 2)
    }
    report.status = fixed ? ContactSolveStatus::fixed_sweeps_done
                          : ContactSolveStatus::max_sweeps_reached;

    for (std::size_t sweep = 0; sweep < settings.max_sweeps; ++sweep) {  // bound: max_sweeps
        Scalar change = zero;
        std::size_t degenerate = 0;
        for (std::size_t a = 0; a < n; ++a) {  // bound: MaxContacts
            ContactVec3<Scalar> d = p.free_displacement[a];
            for (std::size_t b = 0; b < n; ++b) {  // bound: MaxContacts
                if (b == a) {
                    continue;
                }
                const ContactVec3<Scalar>& fb = forces[b];
                if (fb[0] == zero && fb[1] == zero && fb[2] == zero) {
                    continue;  // a separated contact adds nothing (exactly)
                }
                const ContactBlock3<Scalar>& w = p.block(a, b);
                d[0] = d[0] + w[0] * fb[0] + w[1] * fb[1] + w[2] * fb[2];
                d[1] = d[1] + w[3] * fb[0] + w[4] * fb[1] + w[5] * fb[2];
                d[2] = d[2] + w[6] * fb[0] + w[7] * fb[1] + w[8] * fb[2];
            }
            LocalContactSolution<Scalar> local = solve_local_contact(
                p.block(a, a), d, p.friction[a], settings.local_iterations, fixed, &forces[a]);
            if (relaxed) {
                local.force = detail::relax_and_project(forces[a], local.force, settings.relaxation,
                                                        p.friction[a]);
            }
            for (std::size_t i = 0; i < 3U; ++i) {
                change = detail::max_of(change, T::abs(local.force[i] - forces[a][i]));
            }
            forces[a] = local.force;
            report.states[a] = local.state;
            if (local.state == ContactState::degenerate) {
                ++degenerate;
            }
        }
        report.sweeps = sweep + 1U;
        report.last_change = change;
        report.degenerate_contacts = degenerate;
        if (!fixed && change <= settings.tolerance) {
            report.status = ContactSolveStatus::converged;
            break;
        }
    }
    report.residuals = evaluate_contact_residuals(p, forces);
    return report;
}

}  // namespace scopekin::contact
