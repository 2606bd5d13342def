// Gauss-Seidel contact solver instantiated with the firmware's Q16_16 (fixed_point/q_format.hpp).
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4 (firmware
// flags, no heap; all problem storage is static).
//
// * Hand-worked single-contact cases (exact inputs, expected raw values from closed forms).
// * Q16_16 against the SAME solver in double, same settings (fixed sweeps, as the firmware runs
//   it, cold and then warm-started after delta_free moved), on the same inputs: the double
//   problem is the Q16.16 problem converted back exactly, so the difference measured is the
//   fixed-point arithmetic alone, not the quantisation of W and delta_free (that is RANGES.md's
//   business).  Problems: (a) a 12-station cantilever (W up to 2057 mm/N laterally, 0.47 mm/N
//   axially, in rotated station frames), 10 sweeps x 12 local iterations, and the same with 4
//   local iterations, where the solve is not converged and only reported on; (b) random SPD
//   problems with diagonal compliances 0.05..10 mm/N, 8 sweeps x 3 local iterations.  Bound:
//   0.01 N for contacts up to 50 N (the physical range), 1e-4 relative above; state
//   mismatches only where borderline.  The double reference is computed here in the test (soft-
//   float double on Cortex-M4).
// * Garbage inputs (saturated raw values) give defined, projected forces (UBSan on asan).
// * Cross-target identity: a problem built from integers only must give bit-identical forces on
//   x86-64, aarch64 and Cortex-M4 (a hash recorded on x86-64; it is a regression and identity
//   check, not a correctness check — the comparisons above are).
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "contact/gauss_seidel_contact.hpp"
#include "fixed_point/q_format.hpp"
#include "portable_check.hpp"

#if defined(SCOPEKIN_PORTABLE_CHECK_GTEST)
#include <cstdio>
#endif

namespace {

namespace sc = scopekin::contact;
using scopekin::fixed_point::Q16_16;

constexpr std::size_t capacity = 12;
using ProblemQ = sc::ContactProblem<Q16_16, capacity>;
using ForcesQ = sc::ContactForces<Q16_16, capacity>;
using ProblemD = sc::ContactProblem<double, capacity>;
using ForcesD = sc::ContactForces<double, capacity>;
using sc::ContactState;

// ------------------------------------------------------------------------------------------------
// Test-only conversions (the firmware itself has no floating point).
// ------------------------------------------------------------------------------------------------
Q16_16 to_q(double x) {
    const double scaled = std::round(x * 65536.0);
    if (!(scaled < 2147483647.0)) {
        return Q16_16::max();
    }
    if (!(scaled > -2147483648.0)) {
        return Q16_16::min();
    }
    return Q16_16::from_raw(static_cast<std::int32_t>(scaled));
}

double to_d(Q16_16 x) {
    return static_cast<double>(x.raw()) / 65536.0;
}

Q16_16 raw(std::int32_t r) {
    return Q16_16::from_raw(r);
}

bool within_lsb(Q16_16 actual, std::int32_t expected_raw, std::int32_t lsb) {
    const std::int64_t diff = std::int64_t{actual.raw()} - expected_raw;
    return diff <= lsb && -diff <= lsb;
}

// Reporting: measured numbers in millionths (µN, or ppm), through printf (hosted) or the runner's
// console (bare metal).
void report_millionths(const char* label, double value, const char* unit) {
    const auto micro = static_cast<std::int64_t>(std::llround(value * 1e6));
#if defined(SCOPEKIN_PORTABLE_CHECK_GTEST)
    std::printf("[ q16-vs-double ] %s: %lld %s\n", label, static_cast<long long>(micro), unit);
#else
    scopekin::portable_check::write_text("[ q16-vs-double ] ");
    scopekin::portable_check::write_text(label);
    scopekin::portable_check::write_text(": ");
    scopekin::portable_check::write_signed(micro);
    scopekin::portable_check::write_text(" ");
    scopekin::portable_check::write_text(unit);
    scopekin::portable_check::write_text("\n");
#endif
}

void report(const char* label, double value_n) {
    report_millionths(label, value_n, "uN");
}

void report_count(const char* label, std::size_t count) {
#if defined(SCOPEKIN_PORTABLE_CHECK_GTEST)
    std::printf("[ q16-vs-double ] %s: %zu\n", label, count);
#else
    scopekin::portable_check::write_text("[ q16-vs-double ] ");
    scopekin::portable_check::write_text(label);
    scopekin::portable_check::write_text(": ");
    scopekin::portable_check::write_unsigned(count);
    scopekin::portable_check::write_text("\n");
#endif
}

/// splitmix64: the same sequence on every target.
struct Rng {
    std::uint64_t state;
    std::uint64_t next() {
        state += 0x9E3779B97F4A7C15ULL;
        std::uint64_t z = state;
        z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
        return z ^ (z >> 31U);
    }
    double uniform(double lo, double hi) {
        return lo + (hi - lo) * static_cast<double>(next() >> 11U) * (1.0 / 9007199254740992.0);
    }
};

// Static storage: a 12-contact double problem is 10 KiB.
ProblemQ problem_q{};
ProblemD problem_d{};
ProblemD spec{};
ForcesQ forces_q{};
ForcesD forces_d{};
std::array<std::array<double, 3 * capacity>, 3 * capacity> scratch{};

sc::GaussSeidelSettings<Q16_16> firmware_settings_q(std::size_t sweeps, std::size_t local) {
    sc::GaussSeidelSettings<Q16_16> s{};
    s.mode = sc::SweepMode::fixed;
    s.max_sweeps = sweeps;
    s.local_iterations = local;
    s.tolerance = Q16_16{};
    return s;
}

sc::GaussSeidelSettings<double> firmware_settings_d(std::size_t sweeps, std::size_t local) {
    sc::GaussSeidelSettings<double> s{};
    s.mode = sc::SweepMode::fixed;
    s.max_sweeps = sweeps;
    s.local_iterations = local;
    s.tolerance = 0.0;
    return s;
}

// ------------------------------------------------------------------------------------------------
// Problem generators (double `spec`, then quantised).
// ------------------------------------------------------------------------------------------------
using Vec3 = std::array<double, 3>;

Vec3 normalized(const Vec3& v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return {v[0] / n, v[1] / n, v[2] / n};
}

Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

/// A unit 2-vector uniformly on the circle (rejection, no trigonometry).
void unit_pair(Rng& rng, double& u, double& v) {
    for (int attempt = 0; attempt < 64; ++attempt) {  // bound: 64 (acceptance 0.75 - 0.04)
        u = rng.uniform(-1.0, 1.0);
        v = rng.uniform(-1.0, 1.0);
        const double r2 = u * u + v * v;
        if (r2 > 0.04 && r2 <= 1.0) {
            const double r = std::sqrt(r2);
            u /= r;
            v /= r;
            return;
        }
    }
    u = 1.0;
    v = 0.0;
}

/// (a) Cantilever along x clamped at x = 0, stations x_k = 50 (k + 1) mm, k = 0..n-1:
///   lateral (y, z):  w_ij = x_i^2 (3 x_j - x_i) / (6 EI) for x_i <= x_j, EI = 35000 N mm^2
///   axial (x):       min(x_i, x_j) / EA,                            EA = 3200 N
/// plus 0.28 mm/N isotropic wall compliance on the diagonal blocks, in station frames (n, t, s):
/// n mostly lateral (random direction around the axis, tilted up to ±0.3 towards the axis),
/// t the axis projected off n and then twisted about n by a random angle, s = n x t.
void make_cantilever(Rng& rng, std::size_t n, double mu, double max_push_mm) {
    constexpr double ei = 35000.0;
    constexpr double ea = 3200.0;
    constexpr double spacing = 50.0;
    constexpr double wall = 0.28;
    std::array<std::array<Vec3, 3>, capacity> frames{};
    for (std::size_t a = 0; a < n; ++a) {
        double y = 0.0;
        double z = 0.0;
        unit_pair(rng, y, z);
        const Vec3 normal = normalized(Vec3{rng.uniform(-0.3, 0.3), y, z});
        const double axial = normal[0];
        const Vec3 t0 =
            normalized(Vec3{1.0 - axial * normal[0], -axial * normal[1], -axial * normal[2]});
        const Vec3 s0 = cross(normal, t0);
        double c = 1.0;
        double s = 0.0;
        unit_pair(rng, c, s);
        const Vec3 t{c * t0[0] + s * s0[0], c * t0[1] + s * s0[1], c * t0[2] + s * s0[2]};
        frames[a] = {normal, t, cross(normal, t)};
    }
    spec = ProblemD{};
    spec.contact_count = n;
    for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t b = 0; b < n; ++b) {
            const double xa = spacing * static_cast<double>(a + 1U);
            const double xb = spacing * static_cast<double>(b + 1U);
            const double x_lo = xa < xb ? xa : xb;
            const double x_hi = xa < xb ? xb : xa;
            const double lateral = x_lo * x_lo * (3.0 * x_hi - x_lo) / (6.0 * ei);
            const Vec3 beam{x_lo / ea, lateral, lateral};  // diagonal in beam axes (x, y, z)
            for (std::size_t i = 0; i < 3U; ++i) {
                for (std::size_t j = 0; j < 3U; ++j) {
                    double w = 0.0;
                    for (std::size_t k = 0; k < 3U; ++k) {
                        w += frames[a][i][k] * beam[k] * frames[b][j][k];
                    }
                    if (a == b && i == j) {
                        w += wall;
                    }
                    spec.block(a, b)[3U * i + j] = w;
                }
            }
        }
        spec.free_displacement[a] = {rng.uniform(-max_push_mm, 0.3 * max_push_mm),
                                     rng.uniform(-max_push_mm, max_push_mm),
                                     rng.uniform(-max_push_mm, max_push_mm)};
        spec.friction[a] = mu;
    }
}

/// (b) Random SPD: W = D^1/2 C D^1/2, C the correlation matrix of a random Gram matrix J J^T
/// (J: 3n x 6n, entries uniform in [-1, 1]), D log-uniform in [0.05, 10] mm/N.
void make_random_spd(Rng& rng, std::size_t n, double mu, double max_push_mm) {
    const std::size_t rows = 3U * n;
    const std::size_t cols = 2U * rows;
    constexpr std::size_t max_cols = 6U * capacity;
    static std::array<std::array<double, max_cols>, 3U * capacity> j{};
    for (std::size_t r = 0; r < rows; ++r) {
        for (std::size_t c = 0; c < cols; ++c) {
            j[r][c] = rng.uniform(-1.0, 1.0);
        }
    }
    for (std::size_t r = 0; r < rows; ++r) {
        for (std::size_t c = 0; c <= r; ++c) {
            double g = 0.0;
            for (std::size_t k = 0; k < cols; ++k) {
                g += j[r][k] * j[c][k];
            }
            scratch[r][c] = g;
            scratch[c][r] = g;
        }
    }
    std::array<double, 3U * capacity> diag{};
    for (std::size_t r = 0; r < rows; ++r) {
        diag[r] = 0.05 * std::exp(rng.uniform(0.0, std::log(200.0)));
    }
    spec = ProblemD{};
    spec.contact_count = n;
    for (std::size_t r = 0; r < rows; ++r) {
        for (std::size_t c = 0; c < rows; ++c) {
            const double correlation = scratch[r][c] / std::sqrt(scratch[r][r] * scratch[c][c]);
            spec.delassus_entry(r, c) = std::sqrt(diag[r] * diag[c]) * correlation;
        }
    }
    for (std::size_t a = 0; a < n; ++a) {
        spec.free_displacement[a] = {rng.uniform(-max_push_mm, 0.3 * max_push_mm),
                                     rng.uniform(-max_push_mm, max_push_mm),
                                     rng.uniform(-max_push_mm, max_push_mm)};
        spec.friction[a] = mu;
    }
}

/// problem_q = quantised spec; problem_d = problem_q converted back exactly.
void quantise_spec() {
    problem_q = ProblemQ{};
    problem_d = ProblemD{};
    const std::size_t n = spec.contact_count;
    problem_q.contact_count = n;
    problem_d.contact_count = n;
    for (std::size_t i = 0; i < 3U * n; ++i) {
        for (std::size_t k = 0; k < 3U * n; ++k) {
            problem_q.delassus_entry(i, k) = to_q(spec.delassus_entry(i, k));
            problem_d.delassus_entry(i, k) = to_d(problem_q.delassus_entry(i, k));
        }
    }
    for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t k = 0; k < 3U; ++k) {
            problem_q.free_displacement[a][k] = to_q(spec.free_displacement[a][k]);
            problem_d.free_displacement[a][k] = to_d(problem_q.free_displacement[a][k]);
        }
        problem_q.friction[a] = to_q(spec.friction[a]);
        problem_d.friction[a] = to_d(problem_q.friction[a]);
    }
}

struct Comparison {
    double max_force_difference{0.0};  ///< N, any component of any contact
    double max_in_range{0.0};          ///< N, contacts whose |force components| <= 50 N
    double max_relative_above{0.0};    ///< |difference| / largest |component|, contacts above 50 N
    double max_force{0.0};             ///< N, largest |component| seen (double run)
    std::size_t contacts{0};
    std::size_t state_mismatches{0};
    std::size_t non_borderline_mismatches{0};
    std::size_t solves{0};
};

void raise_to(double& maximum, double value) {
    maximum = value > maximum ? value : maximum;
}

constexpr double force_bound_n = 0.01;  // the target: Q16_16 within 0.01 N of double
/// Contact forces the firmware expects (RANGES.md: up to ~50 N); the random SPD problems reach
/// ~500 N at 0.05 mm/N, where the bound is relative instead.
constexpr double physical_force_n = 50.0;
constexpr double relative_bound_above = 1e-4;

/// A contact whose state may legitimately differ between precisions: close to opening
/// (f_n <= bound in either run) or close to the cone's edge (| |f_T| - mu f_n | <= bound).
bool borderline(double fn, double ft, double fs, double mu) {
    const double cone = std::sqrt(ft * ft + fs * fs) - mu * fn;
    return fn <= force_bound_n || (cone <= force_bound_n && -cone <= force_bound_n);
}

void compare_forces(Comparison& c, const sc::ContactSolveReport<Q16_16, capacity>& rq,
                    const sc::ContactSolveReport<double, capacity>& rd) {
    ++c.solves;
    for (std::size_t a = 0; a < problem_d.contact_count; ++a) {
        ++c.contacts;
        double contact_difference = 0.0;
        double contact_force = 0.0;
        for (std::size_t k = 0; k < 3U; ++k) {
            const double fd = forces_d[a][k];
            const double diff = std::fabs(to_d(forces_q[a][k]) - fd);
            contact_difference = diff > contact_difference ? diff : contact_difference;
            contact_force = std::fabs(fd) > contact_force ? std::fabs(fd) : contact_force;
        }
        raise_to(c.max_force_difference, contact_difference);
        raise_to(c.max_force, contact_force);
        if (contact_force <= physical_force_n) {
            raise_to(c.max_in_range, contact_difference);
        } else {
            raise_to(c.max_relative_above, contact_difference / contact_force);
        }
        if (rq.states[a] != rd.states[a]) {
            ++c.state_mismatches;
            const double mu = problem_d.friction[a];
            const bool border =
                borderline(forces_d[a][0], forces_d[a][1], forces_d[a][2], mu) ||
                borderline(to_d(forces_q[a][0]), to_d(forces_q[a][1]), to_d(forces_q[a][2]), mu);
            if (!border) {
                ++c.non_borderline_mismatches;
            }
        }
    }
}

/// Cold solve of spec, then one warm-started solve after the free displacement moved by up to
/// ±0.5 mm (the next firmware step), both in Q16_16 and in double with the same settings.
void run_pair(Rng& rng, Comparison& c, std::size_t sweeps, std::size_t local) {
    quantise_spec();
    forces_q = ForcesQ{};
    forces_d = ForcesD{};
    const auto settings_q = firmware_settings_q(sweeps, local);
    const auto settings_d = firmware_settings_d(sweeps, local);
    auto rq = sc::solve_contacts(problem_q, settings_q, forces_q);
    auto rd = sc::solve_contacts(problem_d, settings_d, forces_d);
    compare_forces(c, rq, rd);
    for (std::size_t a = 0; a < spec.contact_count; ++a) {
        for (std::size_t k = 0; k < 3U; ++k) {
            spec.free_displacement[a][k] += rng.uniform(-0.5, 0.5);
        }
    }
    quantise_spec();
    // Warm start: the double run continues from its own forces, the Q16_16 run from its own.
    rq = sc::solve_contacts(problem_q, settings_q, forces_q);
    rd = sc::solve_contacts(problem_d, settings_d, forces_d);
    compare_forces(c, rq, rd);
}

// The same problems on every target (about 10 s under qemu-system-arm with the soft-float double
// reference; a few hundred ms on x86-64).
constexpr std::size_t problems_per_set = 40;

constexpr std::array<double, 4> friction_values{0.25, 0.0, 0.05, 1.2};

void report_comparison(const char* name, const Comparison& c) {
    report(name, c.max_force_difference);
    report("  the same over contacts with |f| <= 50 N", c.max_in_range);
    report_millionths("  the same over contacts with |f| > 50 N, relative to |f|",
                      c.max_relative_above, "ppm");
    report("  largest |force component| (double)", c.max_force);
    report_count("  contact solves compared", c.contacts);
    report_count("  state mismatches", c.state_mismatches);
    report_count("  state mismatches not borderline", c.non_borderline_mismatches);
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Hand-worked single contacts.
// ------------------------------------------------------------------------------------------------

SCOPEKIN_TEST(GaussSeidelContactQ16, SingleContactStickSlipSeparation) {
    // W = diag(2, 0.5, 0.5) mm/N, mu = 0.5.
    problem_q = ProblemQ{};
    forces_q = ForcesQ{};
    problem_q.contact_count = 1;
    problem_q.block(0, 0) = {Q16_16::from_int(2), Q16_16{}, Q16_16{}, Q16_16{},
                             raw(32768),          Q16_16{}, Q16_16{}, Q16_16{},
                             raw(32768)};
    problem_q.friction[0] = raw(32768);
    const auto settings = firmware_settings_q(4, 4);
    // Stick: d = (-1, 0.0625, -0.03125) mm: f = -W^-1 d = (0.5, -0.125, 0.0625) N exactly
    // (|f_T| = 0.140 <= mu f_n = 0.25).
    problem_q.free_displacement[0] = {Q16_16::from_int(-1), raw(4096), raw(-2048)};
    auto r = sc::solve_contacts(problem_q, settings, forces_q);
    SCOPEKIN_EXPECT_TRUE(r.states[0] == ContactState::sticking);
    SCOPEKIN_EXPECT_EQ(forces_q[0][0].raw(), 32768);
    SCOPEKIN_EXPECT_EQ(forces_q[0][1].raw(), -8192);
    SCOPEKIN_EXPECT_EQ(forces_q[0][2].raw(), 4096);
    // Slip: d = (-1, 0.75, -1) mm: c = 0.5 N, e = (0.75, -1), kappa = |e| / (mu c) - 0.5 = 4.5,
    // f_T = -e / (0.5 + 4.5) = (-0.15, 0.2) N: raw (32768, -9830.4, 13107.2).
    problem_q.free_displacement[0] = {Q16_16::from_int(-1), raw(49152), Q16_16::from_int(-1)};
    r = sc::solve_contacts(problem_q, settings, forces_q);
    SCOPEKIN_EXPECT_TRUE(r.states[0] == ContactState::slipping);
    SCOPEKIN_EXPECT_EQ(forces_q[0][0].raw(), 32768);
    SCOPEKIN_EXPECT_TRUE(within_lsb(forces_q[0][1], -9830, 1));
    SCOPEKIN_EXPECT_TRUE(within_lsb(forces_q[0][2], 13107, 1));
    // Separation: d_n = 0.2 > 0: f = 0.
    problem_q.free_displacement[0] = {raw(13107), raw(49152), Q16_16::from_int(-1)};
    r = sc::solve_contacts(problem_q, settings, forces_q);
    SCOPEKIN_EXPECT_TRUE(r.states[0] == ContactState::separated);
    SCOPEKIN_EXPECT_EQ(forces_q[0][0].raw(), 0);
    SCOPEKIN_EXPECT_EQ(forces_q[0][1].raw(), 0);
}

SCOPEKIN_TEST(GaussSeidelContactQ16, AnisotropicBlockSlipsOnTheCone) {
    // A station near a cantilever's tip: W = diag(2000, 0.5, 2000) mm/N (normal and s lateral, t
    // axial), mu = 1.25, d = (-10, 5, 0) mm.  Stick would need f_t = -10 N against f_n = 0.005 N,
    // so it slips: f = (10 / 2000, -mu f_n, 0) = (0.005, -0.00625, 0) N = raw (327.68, -409.6, 0).
    // (|f_T| = 5 / (0.5 + kappa) = 0.00625 at kappa = 799.5: far outside a Q16.16 product of
    // compliances, 2000^2 = 4e6, which the solver never forms.)
    problem_q = ProblemQ{};
    forces_q = ForcesQ{};
    problem_q.contact_count = 1;
    problem_q.block(0, 0) = {Q16_16::from_int(2000),
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             raw(32768),
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             Q16_16::from_int(2000)};
    problem_q.friction[0] = raw(81920);
    problem_q.free_displacement[0] = {Q16_16::from_int(-10), Q16_16::from_int(5), Q16_16{}};
    const auto r = sc::solve_contacts(problem_q, firmware_settings_q(3, 4), forces_q);
    SCOPEKIN_EXPECT_TRUE(r.states[0] == ContactState::slipping);
    SCOPEKIN_EXPECT_TRUE(within_lsb(forces_q[0][0], 328, 1));
    SCOPEKIN_EXPECT_TRUE(within_lsb(forces_q[0][1], -410, 1));
    SCOPEKIN_EXPECT_EQ(forces_q[0][2].raw(), 0);
}

SCOPEKIN_TEST(GaussSeidelContactQ16, StiffSmallCompliancePushesHard) {
    // W = 0.05 I mm/N, d = (-10, 0, 0): f_n = 200 N = raw 13107200 (forces above 181 N have
    // squares beyond Q16.16: the solver only forms hypot, never f^2).  With d_t = 4 mm and
    // mu = 0.5, stick needs f_t = -80 N <= 100 N: sticks, f = (200, -80, 0).
    problem_q = ProblemQ{};
    forces_q = ForcesQ{};
    problem_q.contact_count = 1;
    const Q16_16 w = raw(3277);  // 0.0500030518 mm/N
    problem_q.block(0, 0) = {w, Q16_16{}, Q16_16{}, Q16_16{}, w, Q16_16{}, Q16_16{}, Q16_16{}, w};
    problem_q.friction[0] = raw(32768);
    problem_q.free_displacement[0] = {Q16_16::from_int(-10), Q16_16::from_int(4), Q16_16{}};
    const auto r = sc::solve_contacts(problem_q, firmware_settings_q(3, 4), forces_q);
    SCOPEKIN_EXPECT_TRUE(r.states[0] == ContactState::sticking);
    // 10 / 0.0500030518 = 199.98779 N: raw 13106400.2; 4 / w = 79.99512 N: raw 5242560.1.
    SCOPEKIN_EXPECT_TRUE(within_lsb(forces_q[0][0], 13106400, 1));
    SCOPEKIN_EXPECT_TRUE(within_lsb(forces_q[0][1], -5242560, 1));
}

SCOPEKIN_TEST(GaussSeidelContactQ16, TinyFrictionIsFrictionlessAndDegenerateIsIgnored) {
    problem_q = ProblemQ{};
    forces_q = ForcesQ{};
    problem_q.contact_count = 2;
    // Contact 0: W = I, d = (-0.25, 1, 0), mu = 1 LSB: mu c = 0.25 LSB rounds to 0 -> frictionless
    // slip, f = (0.25, 0, 0).
    problem_q.block(0, 0) = {Q16_16::from_int(1), Q16_16{}, Q16_16{}, Q16_16{},
                             Q16_16::from_int(1), Q16_16{}, Q16_16{}, Q16_16{},
                             Q16_16::from_int(1)};
    problem_q.free_displacement[0] = {raw(-16384), Q16_16::from_int(1), Q16_16{}};
    problem_q.friction[0] = raw(1);
    // Contact 1: tangential block singular (W_tt = W_ss = 0): degenerate, f = 0.
    problem_q.block(1, 1) = {Q16_16::from_int(1),
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             Q16_16{},
                             Q16_16{}};
    problem_q.free_displacement[1] = {Q16_16::from_int(-1), Q16_16{}, Q16_16{}};
    problem_q.friction[1] = raw(16384);
    const auto r = sc::solve_contacts(problem_q, firmware_settings_q(2, 4), forces_q);
    SCOPEKIN_EXPECT_TRUE(r.states[0] == ContactState::slipping);
    SCOPEKIN_EXPECT_EQ(forces_q[0][0].raw(), 16384);
    SCOPEKIN_EXPECT_EQ(forces_q[0][1].raw(), 0);
    SCOPEKIN_EXPECT_TRUE(r.states[1] == ContactState::degenerate);
    SCOPEKIN_EXPECT_EQ(forces_q[1][0].raw(), 0);
    SCOPEKIN_EXPECT_EQ(r.degenerate_contacts, std::size_t{1});
}

// ------------------------------------------------------------------------------------------------
// Q16_16 against double, same solver, same settings, same inputs.
// ------------------------------------------------------------------------------------------------

SCOPEKIN_TEST(GaussSeidelContactQ16, CantileverMatchesDouble) {
    // 12 local iterations, not 3-4: see CantileverWithFourLocalIterations below for why (in
    // double, on these problems, 4 steps leave forces up to ~1.2 N from the converged local
    // solves, 8 steps up to ~0.09 N, 12 steps 0.2 mN).
    Rng rng{0x5C0BE5EEDULL};
    Comparison all{};
    for (double mu : friction_values) {
        for (std::size_t k = 0; k < problems_per_set; ++k) {
            make_cantilever(rng, capacity, mu, 10.0);
            run_pair(rng, all, 10, 12);
        }
    }
    report_comparison("cantilever, 10 sweeps x 12 local iterations: max |f_q16 - f_double|", all);
    SCOPEKIN_EXPECT_TRUE(all.max_force_difference <= force_bound_n);
    // All forces in the physical range, so the bound above is the absolute one.
    SCOPEKIN_EXPECT_TRUE(all.max_force <= physical_force_n);
    SCOPEKIN_EXPECT_EQ(all.non_borderline_mismatches, std::size_t{0});
}

SCOPEKIN_TEST(GaussSeidelContactQ16, CantileverWithFourLocalIterations) {
    // With 3-4 root-finder steps the slip solves at the cantilever's anisotropic stations (2057
    // vs 0.47 mm/N) are not converged (in double, 4 vs 60 steps differ by up to ~1.2 N on these
    // problems), and where the last step was a Newton step in one run and a bisection in the
    // other, the unconverged kappa, hence the direction of f_T, jumps; the ill-conditioned
    // coupling (neighbouring stations' lateral compliances nearly equal) carries that to the
    // other stations.  Any solver that stores d and f in Q16.16 sees it: the reference here is
    // the double solver with d and f rounded to Q16.16 around every local solve (double
    // arithmetic otherwise), and it departs from plain double by the same order.  So this test
    // reports both and asserts only that 90% of the solves agree to 0.01 N and none is absurd.
    Rng rng{0x5C0BE5EEDULL};
    Comparison all{};
    double rounded_double = 0.0;
    std::size_t within_bound = 0;
    std::size_t compared = 0;
    static ForcesD rounded{};
    for (double mu : friction_values) {
        for (std::size_t k = 0; k < problems_per_set; ++k) {
            make_cantilever(rng, capacity, mu, 10.0);
            quantise_spec();
            forces_q = ForcesQ{};
            forces_d = ForcesD{};
            const auto rq = sc::solve_contacts(problem_q, firmware_settings_q(10, 4), forces_q);
            const auto rd = sc::solve_contacts(problem_d, firmware_settings_d(10, 4), forces_d);
            const double before = all.max_force_difference;
            all.max_force_difference = 0.0;
            compare_forces(all, rq, rd);
            ++compared;
            if (all.max_force_difference <= force_bound_n) {
                ++within_bound;
            }
            all.max_force_difference =
                all.max_force_difference > before ? all.max_force_difference : before;
            // The same sweeps in double with d and f rounded to Q16.16 (no relaxation).
            rounded = ForcesD{};
            for (std::size_t sweep = 0; sweep < 10U; ++sweep) {
                for (std::size_t a = 0; a < problem_d.contact_count; ++a) {
                    sc::ContactVec3<double> d = problem_d.free_displacement[a];
                    for (std::size_t b = 0; b < problem_d.contact_count; ++b) {
                        if (b == a) {
                            continue;
                        }
                        const auto& w = problem_d.block(a, b);
                        for (std::size_t i = 0; i < 3U; ++i) {
                            d[i] += w[3U * i] * rounded[b][0] + w[3U * i + 1U] * rounded[b][1] +
                                    w[3U * i + 2U] * rounded[b][2];
                        }
                    }
                    for (double& v : d) {
                        v = to_d(to_q(v));
                    }
                    const auto local = sc::solve_local_contact(
                        problem_d.block(a, a), d, problem_d.friction[a], 4, true, &rounded[a]);
                    for (std::size_t i = 0; i < 3U; ++i) {
                        rounded[a][i] = to_d(to_q(local.force[i]));
                    }
                }
            }
            for (std::size_t a = 0; a < problem_d.contact_count; ++a) {
                for (std::size_t i = 0; i < 3U; ++i) {
                    const double diff = std::fabs(rounded[a][i] - forces_d[a][i]);
                    rounded_double = diff > rounded_double ? diff : rounded_double;
                }
            }
        }
    }
    report_comparison("cantilever, 10 sweeps x 4 local iterations: max |f_q16 - f_double|", all);
    report("  double with d, f rounded to Q16.16 vs double: max |difference|", rounded_double);
    report_count("  solves with max |f_q16 - f_double| <= 0.01 N", within_bound);
    report_count("  solves", compared);
    SCOPEKIN_EXPECT_TRUE(10U * within_bound >= 9U * compared);
    SCOPEKIN_EXPECT_TRUE(all.max_force_difference <= 2.0);
}

SCOPEKIN_TEST(GaussSeidelContactQ16, RandomSpdMatchesDouble) {
    Rng rng{0xD1A55E5ULL};
    Comparison all{};
    for (double mu : friction_values) {
        for (std::size_t k = 0; k < problems_per_set; ++k) {
            const std::size_t n = 2U + static_cast<std::size_t>(rng.next() % (capacity - 1U));
            make_random_spd(rng, n, mu, 10.0);
            run_pair(rng, all, 8, 3);
        }
    }
    report_comparison(
        "random SPD 0.05..10 mm/N, 8 sweeps x 3 local iterations: max |f_q16 - f_double|", all);
    SCOPEKIN_EXPECT_TRUE(all.max_in_range <= force_bound_n);
    SCOPEKIN_EXPECT_TRUE(all.max_relative_above <= relative_bound_above);
    SCOPEKIN_EXPECT_EQ(all.non_borderline_mismatches, std::size_t{0});
}

// ------------------------------------------------------------------------------------------------
// Robustness and cross-target identity.
// ------------------------------------------------------------------------------------------------

SCOPEKIN_TEST(GaussSeidelContactQ16, SaturatedInputsGiveProjectedForces) {
    // Raw garbage including min() and max(): the solve must stay defined (UBSan on the asan
    // preset) and return forces on the cone: f_n >= 0, |f_T| <= mu f_n (up to rounding).
    Rng rng{0xBADF00DULL};
    constexpr std::array<std::int32_t, 6> extremes{std::numeric_limits<std::int32_t>::min(),
                                                   std::numeric_limits<std::int32_t>::max(),
                                                   -1,
                                                   1,
                                                   0,
                                                   65536};
    for (int trial = 0; trial < 20; ++trial) {
        problem_q = ProblemQ{};
        forces_q = ForcesQ{};
        problem_q.contact_count = 4;
        for (std::size_t i = 0; i < 12U; ++i) {
            for (std::size_t k = 0; k < 12U; ++k) {
                const std::uint64_t pick = rng.next();
                const auto bits =
                    static_cast<std::int32_t>(static_cast<std::uint32_t>(pick >> 32U));
                problem_q.delassus_entry(i, k) =
                    (pick & 3U) == 0U ? raw(extremes[static_cast<std::size_t>((pick >> 8U) % 6U)])
                                      : raw(bits);
            }
        }
        for (std::size_t a = 0; a < 4U; ++a) {
            for (std::size_t k = 0; k < 3U; ++k) {
                problem_q.free_displacement[a][k] =
                    raw(static_cast<std::int32_t>(static_cast<std::uint32_t>(rng.next() >> 32U)));
            }
            problem_q.friction[a] = raw(static_cast<std::int32_t>(rng.next() % 131072U));
        }
        auto settings = firmware_settings_q(3, 4);
        if (trial % 2 == 1) {
            settings.relaxation = raw(91750);  // omega = 1.4: the projected SOR path too
        }
        const auto r = sc::solve_contacts(problem_q, settings, forces_q);
        SCOPEKIN_EXPECT_TRUE(r.status == sc::ContactSolveStatus::fixed_sweeps_done);
        for (std::size_t a = 0; a < 4U; ++a) {
            SCOPEKIN_EXPECT_TRUE(forces_q[a][0] >= Q16_16{});
            const Q16_16 norm_t = scopekin::fixed_point::hypot_sat(forces_q[a][1], forces_q[a][2]);
            const Q16_16 limit = problem_q.friction[a] * forces_q[a][0];
            SCOPEKIN_EXPECT_TRUE(norm_t.raw() <= std::int64_t{limit.raw()} + 2);
        }
    }
}

SCOPEKIN_TEST(GaussSeidelContactQ16, IntegerProblemIsBitIdenticalOnEveryTarget) {
    // W = G / 512 + 0.28 I mm/N with G = J J^T, J (36 x 72) integers in [-8, 8]; d in
    // [-10, 3] x [-5, 5]^2 mm; mu = 0.25.  Everything in integers: the inputs are the same bits
    // on every target, so must the forces be.
    Rng rng{0x1DE471CA1ULL};
    constexpr std::size_t rows = 3U * capacity;
    static std::array<std::array<std::int32_t, 2U * rows>, rows> j{};
    for (auto& row : j) {
        for (auto& v : row) {
            v = static_cast<std::int32_t>(rng.next() % 17U) - 8;
        }
    }
    problem_q = ProblemQ{};
    forces_q = ForcesQ{};
    problem_q.contact_count = capacity;
    for (std::size_t r = 0; r < rows; ++r) {
        for (std::size_t c = 0; c < rows; ++c) {
            std::int32_t g = 0;
            for (std::size_t k = 0; k < 2U * rows; ++k) {
                g += j[r][k] * j[c][k];
            }
            problem_q.delassus_entry(r, c) = raw(g * 128 + (r == c ? 18350 : 0));  // g / 512 mm/N
        }
    }
    for (std::size_t a = 0; a < capacity; ++a) {
        problem_q.free_displacement[a] = {
            raw(static_cast<std::int32_t>(rng.next() % (13U * 65536U)) - 10 * 65536),
            raw(static_cast<std::int32_t>(rng.next() % (10U * 65536U)) - 5 * 65536),
            raw(static_cast<std::int32_t>(rng.next() % (10U * 65536U)) - 5 * 65536)};
        problem_q.friction[a] = raw(16384);
    }
    const auto r = sc::solve_contacts(problem_q, firmware_settings_q(10, 4), forces_q);
    std::uint32_t hash = 2166136261U;  // FNV-1a over the raw forces and the states
    for (std::size_t a = 0; a < capacity; ++a) {
        for (std::size_t k = 0; k < 3U; ++k) {
            const auto bits = static_cast<std::uint32_t>(forces_q[a][k].raw());
            for (unsigned shift = 0; shift < 32U; shift += 8U) {
                hash = (hash ^ ((bits >> shift) & 0xFFU)) * 16777619U;
            }
        }
        hash = (hash ^ static_cast<std::uint32_t>(r.states[a])) * 16777619U;
    }
    report_count("integer problem force hash", hash);
    // Recorded on x86-64 (GCC 12, -O2/-O1 sanitized/-Os all alike): the same bits everywhere.
    SCOPEKIN_EXPECT_EQ(hash, std::uint32_t{1263619505U});
}
