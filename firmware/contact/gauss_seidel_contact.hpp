// gauss_seidel_contact.hpp — ONE frictional contact solver for the firmware and the model.
//
// Header-only C++20 template, instantiated for `double` by the reference model (model/), for
// `float` and for the firmware's fixed-point scalar fixed_point::Q16_16 (tests on every target).
// Portable on purpose: no Eigen, no heap, no exceptions, no RTTI, no recursion, every loop
// bounded by MaxContacts, an explicitly passed count, or a settings field.  Only +, -, *, /,
// comparisons and ContactScalarTraits<Scalar> (constants, abs, sqrt, hypot, a product
// accumulator, the local scale and the kappa limit — listed where the traits are declared) are
// applied to Scalar.
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
//                   rounding (or, in fixed point, the clamp of kappa_hi) left it outside.
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
// local_iterations root-finder steps each (each step: one 2x2 solve, one hypot), plus two more
// 2x2 solves per slip solve (the final f_T and, fixed point only, phi at the clamped kappa_hi).
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
// Scaling and overflow (CMSIS-DSP style; the Q16_16 instantiation)
// ------------------------------------------------------------------------------------------------
// For float and double the traits hooks below reduce to the plain expressions (the accumulator is
// the scalar, the local scale is 1, kappa_max is +infinity), so everything in this section is
// about Q16_16 (fixed_point/q_format.hpp: Q16.16 in int32, saturating +, -, *, /, correctly
// rounded /, sqrt and hypot, an exact 64-bit product accumulator).  Ranges of the physical
// inputs: firmware/fixed_point/RANGES.md.
//   Input format.  W (mm/N), delta_free (mm), f (N), mu, tolerance (N), omega: all Q16.16, LSB
//   1.5e-5 of each unit.  Every input value is accepted; the intermediates stay in range when
//   W entries are below 2^14 = 16384 mm/N (S + kappa I < 2^15; the handle-clamped scope reaches
//   ~2000) and |d| (1 + sqrt(cond W_aa)) < 2^15 mm (e = d_T - d_n A_Tn / A_nn), e.g. |d| < 500 mm
//   for condition numbers up to 4000.
//   Coupling sum.  d_a = delta_free_a + sum_{b != a} W_ab f_b goes through the traits'
//   accumulator: every product W_ab,ij f_b,j is exact (Q32.32, 64 bits) and so is the sum (the
//   ProductAccumulator is exact for 2^16 terms, 3 MaxContacts + 1 here); one rounding to Q16.16
//   per component, saturated only if |d| itself exceeds 32768 mm.  The residuals use the same sum.
//   Local scaling.  Each local solve multiplies W_aa and d_a by 2^k (traits' local_scale: k in
//   [0, 14], the largest with max diag(W_aa) 2^k < 128 and max |d_a| 2^k < 256): exact shifts,
//   the same solution f (delta = W f + d <=> 2^k delta = 2^k W f + 2^k d, and Signorini/Coulomb
//   only see signs and directions of delta).  It gives stiff contacts guard bits: the Schur
//   complement's smaller eigenvalue, which sets the relative precision of f, grows by 2^k (W_aa
//   = 0.05 mm/N, |d| = 10 mm: k = 4, 3277 -> 52429 LSB).  The |d| cap keeps e = d_T -
//   d_n A_Tn / A_nn in range.  Blocks above 128 mm/N are not scaled down (that would drop bits
//   of the small axial compliances next to the big lateral ones).  Dividing by W_nn instead (force
//   units) was rejected: for a lateral normal at the scope's tip (W_nn ~ 2000 mm/N next to an
//   axial 0.47 mm/N) it leaves the axial compliance 31 LSB.
//   Fused operations instead of squares.  No product of two compliances, two forces, a force
//   and a force-rate, or a compliance and a derivative is rounded to Q16.16 on its own:
//     S_ij = (A_ij A_nn - A_in A_nj) / A_nn,  e_i = (d_i A_nn - d_n A_in) / A_nn,
//     b·f_T = (A_nt f_t + A_ns f_s) / A_nn,  f_T = -adj(S + kappa I) e / p / (det / p),
//     the degeneracy test det S / p > eps trace S (trace S / p),  p = max(S_tt, S_ss) + kappa,
//   each numerator exact in the 64-bit accumulator and divided once (traits' quotient); p keeps
//   |S_ij| / p <= 1, so the Cramer numerators are displacements and det / p is at most the
//   smaller diagonal entry (det S of 2000 mm/N terms would be 4e6; of 0.01 mm/N terms 1e-4 = 7
//   LSB).  The Newton step phi / phi' is formed as phi det_p / (phi' det_p), because phi' itself
//   (N^2/mm) is a few LSB where kappa is hundreds of mm/N.  Norms |f_T|, |e|, |f_T - y| use
//   hypot (exact squares in 64 bits, correctly rounded root): forces above 181 N and
//   displacements above 181 mm have squares beyond Q16.16, their hypot does not.  The cone
//   projection scales each component as f limit / |f_T| (one rounding); the previous-force
//   guess divides by |f_T| twice instead of by |f_T|^2.
//   kappa.  kappa_hi = (1 + mu |b|_1) |e|_1 / (mu c) (one rounding) is unbounded as mu c -> 0
//   (and the local scale multiplies kappa by 2^k too); it is clamped to kappa_max = 16383 (scaled
//   units), so lo + hi never saturates and S + kappa I stays in range.  When the clamp engages,
//   phi(kappa_max) is evaluated once more: if it is still > 0 the root lies beyond the format
//   (a grazing contact: tiny f_n, millimetres of slip), where S + kappa I = kappa I to within
//   max(S) / kappa_max, so f_T takes the direction u of f_T(kappa_max) and the magnitude from the
//   cone itself, r = mu c / (1 + mu b·u) — not f_T(kappa_max), whose b·f_T would inflate f_n.
//   The direction is then off by at most max(S) / kappa_max (< 1% for scaled blocks, < 13% for
//   a 2000 mm/N block) of r.  Floating point never takes this branch (kappa_max = +infinity).
//   mu c below half an LSB (7.6e-6 N) rounds to zero and the contact is solved as frictionless
//   (the same branch as mu = 0).  The early stop of until_converged mode uses an absolute 4 LSB
//   on phi (traits' slip_tolerance), not 64 eps relative.
//   Divisions.  By W_nn (checked > 0), by p and det / p (checked > 0), by mu c (checked > 0), by
//   |f_T| and |f_T(prev)| (checked > 0), by phi' det_p (checked < 0), by w_t in the residuals
//   (checked > 0); any other division is of a quantity by a format constant.  A division that
//   still overflows saturates (q_format: toward the quotient's sign, x / 0 toward the sign of
//   x): never UB, never a trap.
//   Saturation.  Where an input is garbage (entries at min()/max(), W not positive definite) the
//   result is defined and projected (f_n >= 0, |f_T| <= mu f_n + 1 LSB), not accurate; detecting
//   that is the caller's job (the residuals, the kinetics fault flags).
//   Accuracy (tests/firmware/contact/test_gauss_seidel_contact_q16_16.cpp): a converged local
//   solve agrees with double on the same inputs to 0.8 mN for forces below 20 N and to 2e-5
//   relative above (1.5e5 local solves).  Whole fixed-sweep solves, warm-started or cold, agree
//   to ~1 mN where the forces are in the physical range (12-station cantilever, 0.47..2057 mm/N,
//   10 sweeps x 12 local iterations: 1.2 mN worst over 2400 problems; random SPD, 0.05..10
//   mm/N, 8 sweeps x 3: 3.5 mN for contacts up to 50 N, 3.3e-5 relative for the ~500 N ones).
//   With 3-4 local iterations the cantilever's slip solves are not converged (in double, 4 vs
//   60 local iterations differ by up to ~1.2 N) and the fixed-sweep result jumps with the last
//   root-finder decision: Q16_16 vs double then differs by up to ~1 N in a few percent of the
//   solves (91% within 0.01 N), and so does double with d and f merely rounded to Q16.16 around
//   each local solve.  The firmware should run enough local iterations for its stations'
//   anisotropy (12 for 2000:1).
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "fixed_point/q_format.hpp"

namespace scopekin::contact {

// ------------------------------------------------------------------------------------------------
// Scalar traits: the only non-arithmetic operations the solver applies to Scalar.
// ------------------------------------------------------------------------------------------------
// Every specialisation provides:
//   zero(), one(), epsilon()        constants (epsilon: the relative resolution; 1 LSB for fixed
//                                   point)
//   abs(x), sqrt(x)                 |x|, square root (x >= 0)
//   hypot(x, y)                     sqrt(x^2 + y^2), for fixed point without forming the squares
//   Accumulator, accumulator(x),    a running sum of products started at x; multiply_accumulate
//   multiply_accumulate(sum, a, b), adds a*b (exactly, for fixed point: the 64-bit accumulator of
//   result(sum),                    DESIGN.md), result rounds it once to Scalar, quotient divides
//   quotient(sum, divisor)          it by a Scalar with one rounding (so (a b + c d) / e never
//                                   rounds the product a b to Scalar on its own)
//   local_scale(w_max, d_max)       a positive factor the local 3x3 problem (W_aa, d_a) is
//                                   multiplied by before the local solve; f is unchanged by it
//   kappa_max()                     the largest kappa the slip root-finder brackets
//   slip_tolerance(mu_c)            |phi| (N) at which the root-finder may stop early
//                                   (until_converged mode only)
// For floating point the accumulator is the scalar itself (sum = sum + a * b, the expressions the
// solver had before the hooks existed), local_scale is exactly 1, kappa_max is +infinity and
// slip_tolerance is 64 eps mu c (as before), so the hooks change nothing there.  The Q16_16
// choices are explained in "Scaling and overflow".
template <typename Scalar>
struct ContactScalarTraits;  // specialise for every Scalar the solver is instantiated with

namespace detail {

/// ContactScalarTraits of a floating-point type.
template <typename Float>
struct FloatingContactScalarTraits {
    using Accumulator = Float;
    static constexpr Float zero() noexcept { return Float{0}; }
    static constexpr Float one() noexcept { return Float{1}; }
    static constexpr Float epsilon() noexcept { return std::numeric_limits<Float>::epsilon(); }
    static Float abs(Float x) noexcept { return std::fabs(x); }
    static Float sqrt(Float x) noexcept { return std::sqrt(x); }
    static Float hypot(Float x, Float y) noexcept { return std::sqrt(x * x + y * y); }
    static constexpr Accumulator accumulator(Float initial) noexcept { return initial; }
    static constexpr void multiply_accumulate(Accumulator& sum, Float a, Float b) noexcept {
        sum = sum + a * b;
    }
    static constexpr Float result(const Accumulator& sum) noexcept { return sum; }
    static constexpr Float quotient(const Accumulator& sum, Float divisor) noexcept {
        return sum / divisor;
    }
    static constexpr Float local_scale(Float /*w_max*/, Float /*d_max*/) noexcept {
        return Float{1};
    }
    static constexpr Float kappa_max() noexcept { return std::numeric_limits<Float>::infinity(); }
    /// 64 eps relative to mu c.
    static constexpr Float slip_tolerance(Float mu_c) noexcept {
        return Float{8} * Float{8} * epsilon() * mu_c;
    }
};

}  // namespace detail

template <>
struct ContactScalarTraits<double> : detail::FloatingContactScalarTraits<double> {};

template <>
struct ContactScalarTraits<float> : detail::FloatingContactScalarTraits<float> {};

/// The firmware's Q16.16 (fixed_point/q_format.hpp): saturating arithmetic, 64-bit exact
/// accumulation, correctly rounded division, square root and hypot.
template <>
struct ContactScalarTraits<fixed_point::Q16_16> {
    using Scalar = fixed_point::Q16_16;
    using Accumulator = fixed_point::ProductAccumulator;

    /// Local scaling targets (see "Scaling and overflow"): the largest diagonal compliance of
    /// the scaled block stays below 2^7 = 128 and the largest |d| below 2^8 = 256 (scaled
    /// units), with at most 2^14 of magnification; blocks already above are not scaled down.
    static constexpr int local_compliance_bits = 7;
    static constexpr int local_displacement_bits = 8;
    static constexpr int local_max_shift = 14;

    static constexpr Scalar zero() noexcept { return Scalar{}; }
    static constexpr Scalar one() noexcept { return Scalar::from_int(1); }
    static constexpr Scalar epsilon() noexcept { return Scalar::from_raw(1); }
    static constexpr Scalar abs(Scalar x) noexcept { return fixed_point::abs_sat(x); }
    static constexpr Scalar sqrt(Scalar x) noexcept { return fixed_point::sqrt_sat(x); }
    static constexpr Scalar hypot(Scalar x, Scalar y) noexcept {
        return fixed_point::hypot_sat(x, y);
    }
    static constexpr Accumulator accumulator(Scalar initial) noexcept {
        return Accumulator{initial};
    }
    static constexpr void multiply_accumulate(Accumulator& sum, Scalar a, Scalar b) noexcept {
        sum.add_product(a, b);
    }
    static constexpr Scalar result(const Accumulator& sum) noexcept { return sum.result(); }
    static constexpr Scalar quotient(const Accumulator& sum, Scalar divisor) noexcept {
        return sum.quotient(divisor);
    }
    /// 2^k, k in [0, local_max_shift] the largest with w_max 2^k < 2^local_compliance_bits and
    /// d_max 2^k < 2^local_displacement_bits (k = 0 when either is already above).  Multiplying
    /// by 2^k is exact in Q16.16 (a shift, no rounding, no saturation by the choice of k).
    static constexpr Scalar local_scale(Scalar w_max, Scalar d_max) noexcept {
        const int w_bits = bit_width(w_max);
        const int d_bits = bit_width(d_max);
        int shift = local_max_shift;
        const int w_room = Scalar::fraction_bits + local_compliance_bits - w_bits;
        const int d_room = Scalar::fraction_bits + local_displacement_bits - d_bits;
        shift = w_room < shift ? w_room : shift;
        shift = d_room < shift ? d_room : shift;
        shift = shift < 0 ? 0 : shift;
        return Scalar::from_raw(Scalar::Raw{1} << (Scalar::fraction_bits + shift));
    }
    /// 2^14 - 1 mm/N (in the scaled local problem): lo + hi <= 2 kappa_max never saturates, and
    /// S + kappa I stays below 2^15 for diagonal entries below 2^14.
    static constexpr Scalar kappa_max() noexcept { return Scalar::from_int(16383); }
    /// 4 LSB (6.1e-5 N), absolute: phi = |f_T| - mu f_n is known to a few LSB whatever mu c is
    /// (a relative 64 eps would be 1e-3 of mu c here).
    static constexpr Scalar slip_tolerance(Scalar /*mu_c*/) noexcept { return Scalar::from_raw(4); }

private:
    /// Bits of a non-negative raw value (0 for x <= 0).
    static constexpr int bit_width(Scalar x) noexcept {
        return x.raw() <= 0 ? 0
                            : static_cast<int>(std::bit_width(static_cast<std::uint32_t>(x.raw())));
    }
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
    /// true: W has no coupling between contacts (every block (a, b), a != b, is zero and is
    /// neither read nor required to be set).  The coupling sums are then skipped — exactly what
    /// they would add — and one sweep solves the problem (the local problems are independent).
    bool block_diagonal{false};

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

template <typename Scalar>
Scalar max_of(Scalar a, Scalar b) noexcept {
    return a < b ? b : a;
}

template <typename Scalar>
Scalar norm2(Scalar x, Scalar y) noexcept {
    return ContactScalarTraits<Scalar>::hypot(x, y);
}

/// (a b + c d) / e with one rounding (the products are never rounded to Scalar on their own).
template <typename Scalar>
Scalar mul_add_div(Scalar a, Scalar b, Scalar c, Scalar d, Scalar e) noexcept {
    using T = ContactScalarTraits<Scalar>;
    typename T::Accumulator sum = T::accumulator(T::zero());
    T::multiply_accumulate(sum, a, b);
    T::multiply_accumulate(sum, c, d);
    return T::quotient(sum, e);
}

/// (a b - c d) / e with one rounding.
template <typename Scalar>
Scalar mul_sub_div(Scalar a, Scalar b, Scalar c, Scalar d, Scalar e) noexcept {
    return mul_add_div(a, b, -c, d, e);
}

/// a b / c with one rounding.
template <typename Scalar>
Scalar mul_div(Scalar a, Scalar b, Scalar c) noexcept {
    using T = ContactScalarTraits<Scalar>;
    typename T::Accumulator sum = T::accumulator(T::zero());
    T::multiply_accumulate(sum, a, b);
    return T::quotient(sum, c);
}

/// a b + c d + e with one rounding.
template <typename Scalar>
Scalar mul_add_add(Scalar a, Scalar b, Scalar c, Scalar d, Scalar e) noexcept {
    using T = ContactScalarTraits<Scalar>;
    typename T::Accumulator sum = T::accumulator(T::zero());
    T::multiply_accumulate(sum, a, b);
    T::multiply_accumulate(sum, c, d);
    T::multiply_accumulate(sum, e, T::one());
    return T::result(sum);
}

/// f_T scaled onto ||f_T|| = limit (each component f limit / ||f_T||, one rounding), if it is
/// outside that disc.
template <typename Scalar>
void project_onto_disc(Scalar& f_t, Scalar& f_s, Scalar limit) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar norm = norm2(f_t, f_s);
    if (norm > limit && norm > T::zero()) {
        f_t = mul_div(f_t, limit, norm);
        f_s = mul_div(f_s, limit, norm);
    }
}

/// f_old + omega (f_new - f_old), projected onto f_n >= 0 and ||f_T|| <= mu f_n.
template <typename Scalar>
ContactVec3<Scalar> relax_and_project(const ContactVec3<Scalar>& f_old,
                                      const ContactVec3<Scalar>& f_new, Scalar omega,
                                      Scalar mu) noexcept {
    using T = ContactScalarTraits<Scalar>;
    ContactVec3<Scalar> f{};
    for (std::size_t i = 0; i < 3U; ++i) {
        f[i] = f_old[i] + omega * (f_new[i] - f_old[i]);
    }
    if (f[0] < T::zero()) {
        return ContactVec3<Scalar>{T::zero(), T::zero(), T::zero()};
    }
    project_onto_disc(f[1], f[2], mu * f[0]);
    return f;
}

/// f_T(kappa) = -(S + kappa I)^-1 e and its derivative d f_T / d kappa = -(S + kappa I)^-1 f_T,
/// by Cramer's rule with the numerators and the determinant divided by p = max(S_tt, S_ss) +
/// kappa (so no squared compliance is ever rounded to Scalar; |S_ij| / p <= 1 for positive
/// definite S).  The derivative is returned as its numerator df_t_num = d f_T / d kappa * det_p
/// together with det_p = det(S + kappa I) / p, because d f_T / d kappa itself (N^2/mm) is tiny
/// where kappa is large; callers divide by det_p only where it is well scaled.
/// Returns false if p <= 0 or det_p <= 0.
template <typename Scalar>
bool tangential_force(const std::array<Scalar, 4>& s, const std::array<Scalar, 2>& e, Scalar kappa,
                      std::array<Scalar, 2>& f_t, std::array<Scalar, 2>& df_t_num,
                      Scalar& det_p) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar m00 = s[0] + kappa;
    const Scalar m11 = s[3] + kappa;
    const Scalar pivot = max_of(m00, m11);
    if (!(pivot > T::zero())) {
        return false;
    }
    det_p = mul_sub_div(m00, m11, s[1], s[2], pivot);  // det(S + kappa I) / p
    if (!(det_p > T::zero())) {
        return false;
    }
    // inverse = [m11 -s01; -s10 m00] / det
    f_t[0] = -mul_sub_div(m11, e[0], s[1], e[1], pivot) / det_p;
    f_t[1] = -mul_sub_div(m00, e[1], s[2], e[0], pivot) / det_p;
    df_t_num[0] = -mul_sub_div(m11, f_t[0], s[1], f_t[1], pivot);
    df_t_num[1] = -mul_sub_div(m00, f_t[1], s[2], f_t[0], pivot);
    return true;
}

}  // namespace detail

/// Exact solve of one contact: delta = A f + d with Signorini and Coulomb (coefficient mu).
/// A is W_aa (row-major (n, t, s)).  `full_iterations` makes the slip root-finder do all
/// `local_iterations` steps (fixed work).  `previous` (optional): this contact's force from the
/// last sweep, used only to start the slip root-finder (any start inside the bracket converges).
template <typename Scalar>
LocalContactSolution<Scalar> solve_local_contact(
    const ContactBlock3<Scalar>& w_aa, const ContactVec3<Scalar>& d_a, Scalar mu,
    std::size_t local_iterations, bool full_iterations,
    const ContactVec3<Scalar>* previous = nullptr) noexcept {
    using T = ContactScalarTraits<Scalar>;
    const Scalar zero = T::zero();
    const Scalar one = T::one();
    const Scalar two = one + one;
    LocalContactSolution<Scalar> out{};
    out.force = {zero, zero, zero};

    // (1) Separation.
    if (d_a[0] >= zero) {
        out.state = ContactState::separated;
        return out;
    }
    if (!(w_aa[0] > zero)) {
        out.state = ContactState::degenerate;
        return out;
    }
    // The local problem A = scale W_aa, d = scale d_a (scale > 0; exactly 1 for floating point):
    // delta = A f + d has the same solution f (see "Scaling and overflow").
    const Scalar w_max = detail::max_of(w_aa[0], detail::max_of(w_aa[4], w_aa[8]));
    const Scalar d_max =
        detail::max_of(T::abs(d_a[0]), detail::max_of(T::abs(d_a[1]), T::abs(d_a[2])));
    const Scalar scale = T::local_scale(w_max, d_max);
    ContactBlock3<Scalar> a{};
    for (std::size_t i = 0; i < 9U; ++i) {
        a[i] = w_aa[i] * scale;
    }
    const ContactVec3<Scalar> d{d_a[0] * scale, d_a[1] * scale, d_a[2] * scale};

    // Eliminate delta_n = 0:  f_n = c - b·f_T,  delta_T = S f_T + e, every entry of S and e with
    // one rounding: S_ij = (A_ij A_nn - A_in A_nj) / A_nn, e_i = (d_i A_nn - d_n A_in) / A_nn.
    const Scalar a_nn = a[0];
    const Scalar c = -d[0] / a_nn;
    const std::array<Scalar, 2> b{a[1] / a_nn, a[2] / a_nn};
    const std::array<Scalar, 4> s{detail::mul_sub_div(a[4], a_nn, a[3], a[1], a_nn),
                                  detail::mul_sub_div(a[5], a_nn, a[3], a[2], a_nn),
                                  detail::mul_sub_div(a[7], a_nn, a[6], a[1], a_nn),
                                  detail::mul_sub_div(a[8], a_nn, a[6], a[2], a_nn)};
    const std::array<Scalar, 2> e{detail::mul_sub_div(d[1], a_nn, d[0], a[3], a_nn),
                                  detail::mul_sub_div(d[2], a_nn, d[0], a[6], a_nn)};
    // f_n = c - b·f_T = c - (A_nt f_t + A_ns f_s) / A_nn.
    const auto normal_force = [&](const std::array<Scalar, 2>& f) noexcept {
        return c - detail::mul_add_div(a[1], f[0], a[2], f[1], a_nn);
    };
    // The slip force of a tangential f_T: f_n from it, clamped >= 0, f_T scaled back onto the
    // cone if rounding left it outside.
    const auto slip_force = [&](std::array<Scalar, 2> f) noexcept {
        Scalar f_n = normal_force(f);
        if (f_n < zero) {
            f_n = zero;
        }
        detail::project_onto_disc(f[0], f[1], mu * f_n);
        return ContactVec3<Scalar>{f_n, f[0], f[1]};
    };
    // Relative test: det S > eps * (trace S)^2 (and trace S > 0), written with det S / p,
    // p = max(S_tt, S_ss) > 0, so that det S itself is never rounded to Scalar.
    const Scalar trace_s = s[0] + s[3];
    if (!(trace_s > zero)) {
        out.state = ContactState::degenerate;
        return out;
    }
    const Scalar pivot_s = detail::max_of(s[0], s[3]);
    const Scalar det_s_over_pivot = detail::mul_sub_div(s[0], s[3], s[1], s[2], pivot_s);
    if (!(det_s_over_pivot > T::epsilon() * trace_s * (trace_s / pivot_s))) {
        out.state = ContactState::degenerate;
        return out;
    }

    // (2) Stick: kappa = 0.
    std::array<Scalar, 2> f_t{zero, zero};
    std::array<Scalar, 2> df_t_num{zero, zero};
    Scalar det_p = one;
    detail::tangential_force(s, e, zero, f_t, df_t_num, det_p);
    {
        const Scalar f_n = normal_force(f_t);
        if (f_n >= zero && detail::norm2(f_t[0], f_t[1]) <= mu * f_n) {
            out.force = {f_n, f_t[0], f_t[1]};
            out.state = ContactState::sticking;
            return out;
        }
    }

    // (3) Slip.
    out.state = ContactState::slipping;
    const Scalar mu_c = mu * c;
    if (!(mu_c > zero)) {
        // Frictionless (mu = 0, or mu c below the format's resolution): delta_n = 0, f_T = 0.
        out.force = {c, zero, zero};
        return out;
    }
    const Scalar b_1 = T::abs(b[0]) + T::abs(b[1]);
    const Scalar e_1 = T::abs(e[0]) + T::abs(e[1]);
    Scalar lo = zero;                                        // phi(lo) > 0 (stick rejected)
    Scalar hi = detail::mul_div(one + mu * b_1, e_1, mu_c);  // phi(hi) < 0 (see header)
    if (hi > T::kappa_max()) {
        // Fixed point only (kappa_max is +infinity for floating point): the bracket is clamped to
        // the format.  If phi is still > 0 there, the root lies beyond it, where S + kappa I is
        // kappa I to within max(S) / kappa_max: take the direction u of f_T(kappa_max) and solve
        // the cone for the magnitude, |f_T| = r = mu (c - r b·u), i.e. r = mu c / (1 + mu b·u).
        // (Evaluating f_n from f_T(kappa_max) itself would couple b with a tangential force
        // far larger than mu f_n.)
        hi = T::kappa_max();
        if (detail::tangential_force(s, e, hi, f_t, df_t_num, det_p)) {
            const Scalar norm_t = detail::norm2(f_t[0], f_t[1]);
            if (norm_t > zero && norm_t - mu * normal_force(f_t) > zero) {
                const std::array<Scalar, 2> u{f_t[0] / norm_t, f_t[1] / norm_t};
                const Scalar denominator =
                    one + mu * detail::mul_add_div(a[1], u[0], a[2], u[1], a_nn);
                if (denominator > zero) {
                    const Scalar r = mu_c / denominator;
                    f_t = {r * u[0], r * u[1]};
                    out.force = slip_force(f_t);
                    return out;
                }
            }
        }
    }
    Scalar kappa = detail::norm2(e[0], e[1]) / mu_c - trace_s / two;  // isotropic closed form
    if (previous != nullptr) {
        // Gauss-Seidel revisits the contact with a slightly different d: the kappa of the last
        // slip force, kappa = -(S f_T + e).f_T / |f_T|^2, is then a much closer start.  The
        // division by |f_T|^2 is done as two divisions by |f_T| (no squared force).
        const Scalar pt = (*previous)[1];
        const Scalar ps = (*previous)[2];
        const Scalar p_norm = detail::norm2(pt, ps);
        if (p_norm > zero) {
            const Scalar dt = detail::mul_add_add(s[0], pt, s[1], ps, e[0]);
            const Scalar ds = detail::mul_add_add(s[2], pt, s[3], ps, e[1]);
            const Scalar guess = -detail::mul_add_div(dt, pt, ds, ps, p_norm) / p_norm;
            if (guess > lo && guess < hi) {
                kappa = guess;
            }
        }
    }
    if (!(kappa > lo && kappa < hi)) {
        kappa = (lo + hi) / two;
    }
    const Scalar phi_tolerance = T::slip_tolerance(mu_c);
    for (std::size_t it = 0; it < local_iterations; ++it) {
        out.iterations = it + 1U;
        if (!detail::tangential_force(s, e, kappa, f_t, df_t_num, det_p)) {
            break;  // unreachable for kappa >= 0 and det S > 0; keeps the last f_t
        }
        const Scalar norm_t = detail::norm2(f_t[0], f_t[1]);
        const Scalar phi = norm_t - mu * normal_force(f_t);
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
            // dphi/dkappa = (f_T·f_T' / |f_T| + mu b·f_T'), f_T' = df_t_num / det_p: the bracket
            // below is dphi * det_p (in N, well scaled), and the Newton step phi / dphi is
            // formed as phi det_p / (dphi det_p) with one rounding.
            const Scalar dphi_det =
                detail::mul_add_div(f_t[0], df_t_num[0], f_t[1], df_t_num[1], norm_t) +
                mu * detail::mul_add_div(a[1], df_t_num[0], a[2], df_t_num[1], a_nn);
            if (dphi_det < zero) {
                const Scalar newton = kappa - detail::mul_div(phi, det_p, dphi_det);
                if (newton >= lo && newton <= hi) {
                    next = newton;
                }
            }
        }
        kappa = next;
    }
    detail::tangential_force(s, e, kappa, f_t, df_t_num, det_p);
    out.force = slip_force(f_t);
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
        std::array<typename T::Accumulator, 3> sum{T::accumulator(p.free_displacement[a][0]),
                                                   T::accumulator(p.free_displacement[a][1]),
                                                   T::accumulator(p.free_displacement[a][2])};
        for (std::size_t b = 0; b < n; ++b) {  // bound: MaxContacts
            if (p.block_diagonal && b != a) {
                continue;
            }
            const ContactBlock3<Scalar>& w = p.block(a, b);
            for (std::size_t i = 0; i < 3U; ++i) {
                T::multiply_accumulate(sum[i], w[i * 3U], f[b][0]);
                T::multiply_accumulate(sum[i], w[i * 3U + 1U], f[b][1]);
                T::multiply_accumulate(sum[i], w[i * 3U + 2U], f[b][2]);
            }
        }
        const ContactVec3<Scalar> delta{T::result(sum[0]), T::result(sum[1]), T::result(sum[2])};
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
    report.status =
        fixed ? ContactSolveStatus::fixed_sweeps_done : ContactSolveStatus::max_sweeps_reached;

    for (std::size_t sweep = 0; sweep < settings.max_sweeps; ++sweep) {  // bound: max_sweeps
        Scalar change = zero;
        std::size_t degenerate = 0;
        for (std::size_t a = 0; a < n; ++a) {  // bound: MaxContacts
            // d_a = delta_free_a + sum_{b != a} W_ab f_b in the traits' accumulator (for Q16_16
            // exact in 64 bits, one rounding per component).
            std::array<typename T::Accumulator, 3> sum{T::accumulator(p.free_displacement[a][0]),
                                                       T::accumulator(p.free_displacement[a][1]),
                                                       T::accumulator(p.free_displacement[a][2])};
            for (std::size_t b = 0; b < n; ++b) {  // bound: MaxContacts
                if (b == a || p.block_diagonal) {
                    continue;
                }
                const ContactVec3<Scalar>& fb = forces[b];
                if (fb[0] == zero && fb[1] == zero && fb[2] == zero) {
                    continue;  // a separated contact adds nothing (exactly)
                }
                const ContactBlock3<Scalar>& w = p.block(a, b);
                for (std::size_t i = 0; i < 3U; ++i) {
                    T::multiply_accumulate(sum[i], w[i * 3U], fb[0]);
                    T::multiply_accumulate(sum[i], w[i * 3U + 1U], fb[1]);
                    T::multiply_accumulate(sum[i], w[i * 3U + 2U], fb[2]);
                }
            }
            const ContactVec3<Scalar> d{T::result(sum[0]), T::result(sum[1]), T::result(sum[2])};
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
