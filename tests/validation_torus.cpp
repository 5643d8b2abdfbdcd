// The tracer's torus (U-groove) intersections, trace/Intersect.cpp, against the exact reference
// validation/TorusReference.h (MPFR, exact roots rounded to double), and that reference against
// closed forms.
//
// How a traced ray is judged (compare() below; the tolerances and their derivations are in
// tests/Tolerances.h, "validation_torus"). The tracer's computed f is within E(t) of the exact f
// (torus_f_error), so:
//   - a reference crossing t* (multiplicity 1) gets the window t* +- e, e = torus_root(E, f', f'').
//     If the exact f has opposite signs at t* - e and t* + e and |f| > E at both, the tracer's f
//     changes sign in the window too: a guaranteed isolation MUST report exactly one root there
//     (a "robust crossing");
//   - otherwise the root is within the derived bound of tangency (the ray grazes the tube so
//     closely that rounding may merge the root with its partner, or a tangency: multiplicity >= 2):
//     the tracer may report it or not. Such roots are counted explicitly ("band") and printed;
//   - every traced root that is not the one root of a robust crossing's window must be one that a
//     perturbation of f by E can create: the exact |f| there must be at most E plus the slope
//     times the stopping slack (8 u |s| + 2 u |t|). Anything else is a spurious root.
// A missed robust crossing, a second root in its window or a spurious root fails the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "geometry/Surface.h"
#include "tests/Tolerances.h"
#include "trace/Intersect.h"
#include "validation/TorusReference.h"

using namespace ltm;
using ltm::validation::TorusReference;
using ltm::validation::TorusRoot;

namespace {

constexpr double u = tol::kEps / 2;

// Per ray class: what was compared and the largest error relative to its tolerance.
struct Stats {
    std::string name;
    long rays = 0, crossings = 0;  // robust crossings (each must be found)
    long band = 0;                 // reference roots within the tangency band (multiple roots included)
    long band_traced = 0;          // traced roots accepted by the band criterion
    long multiple = 0;             // reference roots of multiplicity >= 2
    double worst_crossing = 0;     // max |t_traced - t_ref| / e over robust crossings
    double worst_band = 0;         // max |f(t_traced)| / (E + slack) over band roots
    double worst_contact = 0;      // max |t_traced - t_ref| / contact window near multiple roots
    double largest_e_over_r = 0;   // the crossings' largest tolerance relative to the tube
    void print() const {
        std::printf("[torus %-30s] rays %5ld crossings %5ld max err/tol %.3g | band roots %4ld (multiple %ld), "
                    "traced there %ld, max |f|/(E+slack) %.3g, max dist/contact window %.3g | max e/r %.2g\n",
                    name.c_str(), rays, crossings, worst_crossing, band, multiple, band_traced, worst_band,
                    worst_contact, largest_e_over_r);
    }
};

// The ray-dependent quantities of Tolerances.h at parameter t (d unit).
struct Magnitudes {
    double tm, pp, pa, da, L;
};
Magnitudes magnitudes(const Surface& s, const Vec3& o, const Vec3& d) {
    const double tm = dot(s.origin - o, d);
    const Vec3 p = o + d * tm - s.origin;
    return {tm, dot(p, p), dot(p, s.axis), dot(d, s.axis), length(o) + std::fabs(tm) + length(s.origin)};
}
double f_error(const Surface& s, const Magnitudes& m, double t) {
    return tol::torus_f_error(s.radius, s.minor_radius, m.pp, m.pa, m.da, t - m.tm, m.L);
}

// Compares intersect(s, o, d) (d unit) with the reference. Returns the traced roots.
Roots compare(const Surface& s, const Vec3& o, const Vec3& d, Stats& st, const std::string& what) {
    const TorusReference ref(s.origin, s.axis, s.radius, s.minor_radius, o, d);
    const Roots got = intersect(s, o, d);
    const Magnitudes mg = magnitudes(s, o, d);
    ++st.rays;
    std::vector<bool> used(static_cast<size_t>(got.count), false);
    struct Contact {
        double t, window;
    };
    std::vector<Contact> contact;  // the reference's multiple roots and their contact windows
    for (int i = 0; i + 1 < got.count; ++i) EXPECT_LE(got.t[i], got.t[i + 1]) << "ascending: " << what;

    for (const TorusRoot& x : ref.roots()) {
        const double E = f_error(s, mg, x.t), sv = x.t - mg.tm;
        if (x.multiplicity >= 2) {
            ++st.band;
            ++st.multiple;
            contact.push_back({x.t, tol::torus_contact_window(E, x.multiplicity, ref.f(x.t, x.multiplicity), x.t, sv)});
            continue;
        }
        const double e = tol::torus_root(E, x.slope, x.curvature, x.t, sv);
        const double a = x.t - e, b = x.t + e, fa = ref.f(a), fb = ref.f(b);
        const bool robust = fa != 0 && fb != 0 && (fa < 0) != (fb < 0) && std::fabs(fa) > f_error(s, mg, a) &&
                            std::fabs(fb) > f_error(s, mg, b) && !ref.has_root_in(1, a, b);
        if (!robust) {
            ++st.band;
            continue;
        }
        ++st.crossings;
        st.largest_e_over_r = std::max(st.largest_e_over_r, e / s.minor_radius);
        int found = 0;
        for (int i = 0; i < got.count; ++i)
            if (got.t[i] >= a && got.t[i] <= b) {
                ++found;
                used[static_cast<size_t>(i)] = true;
                st.worst_crossing = std::max(st.worst_crossing, std::fabs(got.t[i] - x.t) / e);
            }
        EXPECT_EQ(found, 1) << "crossing at t = " << x.t << " (window +-" << e << "), traced " << got.count
                            << " roots: " << what;
    }
    for (int i = 0; i < got.count; ++i) {
        if (used[static_cast<size_t>(i)]) continue;
        const double t = got.t[i];
        const double bound = f_error(s, mg, t) + std::fabs(ref.f(t, 1)) * (8 * u * std::fabs(t - mg.tm) + 2 * u * std::fabs(t));
        const double residual = std::fabs(ref.f(t));
        EXPECT_LE(residual, bound) << "traced root " << t << " is not a root within rounding (|f| = " << residual
                                   << ", E = " << bound << "); reference has " << ref.roots().size() << " roots: " << what;
        ++st.band_traced;
        st.worst_band = std::max(st.worst_band, residual / bound);
        // When the nearest reference root is an exact tangency (a multiple root), the traced root
        // must also be within its contact window (Tolerances.h: the sqrt(eps) growth of the error).
        double nearest = INFINITY;
        for (const TorusRoot& x : ref.roots()) nearest = std::min(nearest, std::fabs(t - x.t));
        for (const Contact& c : contact)
            if (std::fabs(t - c.t) == nearest) {
                EXPECT_LE(std::fabs(t - c.t), c.window) << "traced root " << t << " near the tangency at " << c.t << ": " << what;
                st.worst_contact = std::max(st.worst_contact, std::fabs(t - c.t) / c.window);
            }
    }
    return got;
}

std::string ray_text(const Vec3& o, const Vec3& d) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "o (%.17g, %.17g, %.17g) d (%.17g, %.17g, %.17g)", o.x, o.y, o.z, d.x, d.y, d.z);
    return buf;
}

Vec3 random_unit(std::mt19937_64& g) {
    std::normal_distribution<double> n(0, 1);
    for (;;) {
        const Vec3 v{n(g), n(g), n(g)};
        if (length(v) > 1e-3) return normalize(v);
    }
}

// A point of the tube at azimuth phi and tube angle psi (from the outer equator towards +axis),
// with the outward normal.
struct TubePoint {
    Vec3 p, n;
};
TubePoint tube_point(const Surface& s, double phi, double psi) {
    Vec3 e0, e1;
    orthonormal_basis(s.axis, e0, e1);
    const Vec3 radial = e0 * std::cos(phi) + e1 * std::sin(phi);
    const Vec3 n = radial * std::cos(psi) + s.axis * std::sin(psi);
    return {s.origin + radial * s.radius + n * s.minor_radius, n};
}

}  // namespace

// ---- the reference against closed forms ----

TEST(TorusReference, ExactRootsOfAnEquatorialRay) {
    // From x = -2R along the equatorial diameter, the tube is crossed where |x| = R +- r: all four
    // roots are small dyadic numbers, so the reference must return them exactly, as exact roots.
    const double R = 5, r = 0.125;
    const TorusReference ref({0, 0, 0}, {0, 0, 1}, R, r, {-2 * R, 0, 0}, {1, 0, 0});
    ASSERT_EQ(ref.roots().size(), 4u);
    const double want[4] = {R - r, R + r, 3 * R - r, 3 * R + r};
    for (int i = 0; i < 4; ++i) {
        const TorusRoot& x = ref.roots()[static_cast<size_t>(i)];
        EXPECT_EQ(x.t, want[i]);
        EXPECT_EQ(x.lo, want[i]);
        EXPECT_EQ(x.hi, want[i]);
        EXPECT_EQ(x.multiplicity, 1);
        EXPECT_EQ(ref.f(x.t), 0.0);
        EXPECT_NE(x.slope, 0.0);
    }
    // Inside the tube f < 0, outside f > 0 (the sign convention of TorusReference.h).
    EXPECT_LT(ref.f(R), 0.0);
    EXPECT_GT(ref.f(2 * R), 0.0);
}

TEST(TorusReference, ScalingTheDirectionOrTheAxisIsExact) {
    // The line o + t (2 d) meets the torus at t / 2, and the axis 3 a is the same axis: with exact
    // arithmetic the rounded roots are exactly half (halving commutes with rounding) and the same.
    const Vec3 C{0.3, -1.7, 2.25}, a = normalize(Vec3{0.02, -0.05, 1.0}), o{-6.7, -0.23, 2.04};
    const Vec3 d = normalize(Vec3{1.0, -0.21, 0.03});
    const TorusReference base(C, a, 5.0, 0.4, o, d), twice(C, a, 5.0, 0.4, o, d * 2.0), axis3(C, a * 3.0, 5.0, 0.4, o, d);
    ASSERT_EQ(base.roots().size(), 4u);
    ASSERT_EQ(twice.roots().size(), 4u);
    ASSERT_EQ(axis3.roots().size(), 4u);
    for (size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(twice.roots()[i].t, base.roots()[i].t / 2);
        EXPECT_EQ(axis3.roots()[i].t, base.roots()[i].t);
        EXPECT_LE(base.roots()[i].lo, base.roots()[i].t);
        EXPECT_GE(base.roots()[i].hi, base.roots()[i].t);
        // Correctly rounded: the enclosing interval is within one ulp on each side.
        EXPECT_LE(base.roots()[i].hi - base.roots()[i].lo, 2 * std::nextafter(std::fabs(base.roots()[i].t), INFINITY) - 2 * std::fabs(base.roots()[i].t));
    }
}

TEST(TorusReference, GrazingChordsAgreeWithTheirClosedForm) {
    // The torus with its top circle in z = 0 (centre (0, 0, -r)) and the ray z = -delta along x:
    // (|x| - R)^2 + (r - delta)^2 = r^2, so x = +-R +- sqrt(2 r delta - delta^2) = +-R +- l. The
    // closed form in long double (64-bit significand, u_L = 2^-64): ~6 roundings relative to
    // |t| + 2R, i.e. within 8 u_L (|t| + 2R); the reference rounds to nearest, u |t|.
    const double R = 5, r = 0.125;
    for (double frac : {1e-1, 1e-3, 1e-5, 1e-7, 1e-9}) {
        const double c = frac * r, delta = (c * c / 4) / (r + std::sqrt(r * r - c * c / 4));
        const TorusReference ref({0, 0, -r}, {0, 0, 1}, R, r, {-2 * R, 0, -delta}, {1, 0, 0});
        ASSERT_EQ(ref.roots().size(), 4u) << frac;
        const long double dl = delta, l = std::sqrt(2.0L * r * dl - dl * dl);
        const long double want[4] = {R - l, R + l, 3.0L * R - l, 3.0L * R + l};
        const long double uL = std::numeric_limits<long double>::epsilon() / 2;
        for (size_t i = 0; i < 4; ++i) {
            const double t = ref.roots()[i].t;
            EXPECT_EQ(ref.roots()[i].multiplicity, 1);
            EXPECT_LE(std::fabs(static_cast<long double>(t) - want[i]), 8 * uL * (std::fabs(t) + 2 * R) + u * std::fabs(t))
                << "chord " << frac << " root " << i;
        }
    }
}

TEST(TorusReference, TangenciesAreMultipleRoots) {
    const double R = 5, r = 0.125;
    // Over the top of the tube (z = r) along the diameter: touching at x = -R and +R.
    {
        const TorusReference ref({0, 0, 0}, {0, 0, 1}, R, r, {-2 * R, 0, r}, {1, 0, 0});
        ASSERT_EQ(ref.roots().size(), 2u);
        EXPECT_EQ(ref.roots()[0].t, R);
        EXPECT_EQ(ref.roots()[1].t, 3 * R);
        for (const TorusRoot& x : ref.roots()) EXPECT_EQ(x.multiplicity, 2);
    }
    // Along the top circle's tangent at (R, 0, r): rho - R ~ y^2 / 2R, so f ~ y^4: multiplicity 4.
    {
        const TorusReference ref({0, 0, 0}, {0, 0, 1}, R, r, {R, -3, r}, {0, 1, 0});
        ASSERT_EQ(ref.roots().size(), 1u);
        EXPECT_EQ(ref.roots()[0].t, 3.0);
        EXPECT_EQ(ref.roots()[0].multiplicity, 4);
    }
    // In the equatorial plane at distance R - r from the centre: crosses the outer equator twice
    // and touches the inner one (from inside the tube) at x = 0: simple, double, simple.
    {
        const TorusReference ref({0, 0, 0}, {0, 0, 1}, R, r, {-10, R - r, 0}, {1, 0, 0});
        ASSERT_EQ(ref.roots().size(), 3u);
        EXPECT_EQ(ref.roots()[0].multiplicity, 1);
        EXPECT_EQ(ref.roots()[1].multiplicity, 2);
        EXPECT_EQ(ref.roots()[1].t, 10.0);
        EXPECT_EQ(ref.roots()[2].multiplicity, 1);
        // x = +-sqrt((R + r)^2 - (R - r)^2) = +-2 sqrt(R r): t = 10 -+ 2 sqrt(R r), correctly rounded.
        EXPECT_NEAR(ref.roots()[0].t, 10 - 2 * std::sqrt(R * r), 4 * u * 10);
        EXPECT_NEAR(ref.roots()[2].t, 10 + 2 * std::sqrt(R * r), 4 * u * 10);
    }
}

// ---- the tracer against the reference ----

TEST(TorusTrace, RandomRaysAroundToriOfEveryRatio) {
    std::mt19937_64 g(20240611);
    std::uniform_real_distribution<double> U(0, 1);
    for (double ratio : {1.1, 1.5, 2.0, 4.0, 10.0, 100.0, 1e3, 1e4}) {
        Stats st;
        st.name = "random R/r " + std::to_string(ratio).substr(0, 7);
        for (int k = 0; k < 2; ++k) {
            const double R = 0.5 * std::pow(100.0, U(g)), r = R / ratio;  // R in [0.5, 50]
            const Vec3 C{40 * U(g) - 20, 40 * U(g) - 20, 40 * U(g) - 20};
            const Surface s = Surface::torus(C, random_unit(g), R, r);
            for (int n = 0; n < 250; ++n) {
                const Vec3 d = random_unit(g);
                Vec3 o;
                if (n % 2 == 0) {
                    // Aimed at a point within 1.5 r of the centre circle, from 0.1 to 3 (R + r) back.
                    const TubePoint q = tube_point(s, 2 * M_PI * U(g), 2 * M_PI * U(g));
                    const Vec3 target = q.p + (q.n * (U(g) * 1.5 - 1.0)) * r;
                    o = target - d * ((0.1 + 2.9 * U(g)) * (R + r));
                } else {
                    // Anywhere in the box of half-size 2 (R + r) around the centre.
                    o = C + Vec3{U(g) - 0.5, U(g) - 0.5, U(g) - 0.5} * (4 * (R + r));
                }
                compare(s, o, d, st, s.describe() + " " + ray_text(o, d));
            }
        }
        st.print();
        EXPECT_GT(st.crossings, 400) << "the rays must actually cross the tube";
    }
}

TEST(TorusTrace, GrazingChordsDownToABillionthOfTheTube) {
    // Chords c = frac r through the tube, frac = 1e-1 .. 1e-9, at three kinds of place:
    //   top:   the top circle in z = 0 (centre (0, 0, -r)), the ray z = -delta along the diameter
    //          (it grazes the tube on both sides: 4 roots);
    //   outer: the outer equator through x = 0 (centre (-(R + r), 0, 0)), the ray parallel to the
    //          axis at x = -delta (2 roots);
    //   inner: the inner equator through x = 0 (centre (-(R - r), 0, 0)), the ray parallel to the
    //          axis at x = +delta, through the hole's edge (2 roots);
    // with delta = r - sqrt(r^2 - c^2 / 4) (c = 2 sqrt(2 r delta - delta^2)), exact in the ray's
    // coordinates because the grazed point is at 0. Chords below the derived band (a few 1e-6 r
    // here) may be lost by rounding and are counted as such; above it every chord must be found.
    // R and r are dyadic with few bits, so that R + r and R - r (the centres) are exact.
    for (const auto& [R, r] : {std::pair<double, double>{5.0, 0.125}, {40.0, 0.015625}}) {
        for (const char* where : {"top", "outer", "inner"}) {
            for (int dec = 1; dec <= 9; ++dec) {
                const double frac = std::pow(10.0, -dec), c = frac * r;
                const double delta = (c * c / 4) / (r + std::sqrt(r * r - c * c / 4));
                Surface s;
                Vec3 o, d;
                int expected = 2;
                if (where == std::string("top")) {
                    s = Surface::torus({0, 0, -r}, {0, 0, 1}, R, r);
                    o = {-2 * R, 0, -delta};
                    d = {1, 0, 0};
                    expected = 4;
                } else if (where == std::string("outer")) {
                    s = Surface::torus({-(R + r), 0, 0}, {0, 0, 1}, R, r);
                    o = {-delta, 0, -2 * r};
                    d = {0, 0, 1};
                } else {
                    s = Surface::torus({-(R - r), 0, 0}, {0, 0, 1}, R, r);
                    o = {delta, 0, -2 * r};
                    d = {0, 0, 1};
                }
                Stats st;
                st.name = std::string("grazing ") + where + " R/r " + std::to_string(int(R / r)) + " c/r 1e-" + std::to_string(dec);
                const TorusReference ref(s.origin, s.axis, s.radius, s.minor_radius, o, d);
                ASSERT_EQ(static_cast<int>(ref.roots().size()), expected) << st.name;
                const Roots got = compare(s, o, d, st, st.name + " " + ray_text(o, d));
                if (st.band == 0) {
                    EXPECT_EQ(got.count, expected) << st.name;
                }
                // Large chords must be outside the band (the bound is not so loose that it excuses
                // everything): with E ~ 512 u R^4 and f'' ~ 8 R^2 at the grazed point, the band's
                // half-chord is sqrt(2 E / f'') ~ 11 sqrt(u) R ~ 1.2e-7 R, chords of 1e-5 r (R/r 40)
                // and 6e-4 r (R/r 2560): every chord of 1e-3 r and more must be outside it.
                if (frac >= 1e-3) {
                    EXPECT_EQ(st.band, 0) << st.name;
                }
                st.print();
            }
        }
    }
    // The same in every orientation: a random point of the tube, a random tangent direction there,
    // the ray moved into the tube by delta. The rounding of the coordinates (~u |P|) exceeds delta
    // for the shortest chords, so the reference alone says what the chord is.
    std::mt19937_64 g(7);
    std::uniform_real_distribution<double> U(0, 1);
    for (double ratio : {1.1, 10.0, 1e3, 1e4}) {
        Stats st;
        st.name = "grazing random R/r " + std::to_string(ratio).substr(0, 6);
        for (int n = 0; n < 400; ++n) {
            const double R = 0.5 + 20 * U(g), r = R / ratio;
            const Surface s = Surface::torus({10 * U(g) - 5, 10 * U(g) - 5, 10 * U(g) - 5}, random_unit(g), R, r);
            const TubePoint q = tube_point(s, 2 * M_PI * U(g), 2 * M_PI * U(g));
            Vec3 t = random_unit(g);
            t = normalize(t - q.n * dot(t, q.n));
            const double frac = std::pow(10.0, -1 - 8 * U(g)), c = frac * r, delta = c * c / (8 * r);
            const Vec3 p = q.p - q.n * delta;
            compare(s, p - t * (2 * r), t, st, s.describe() + " " + ray_text(p - t * (2 * r), t));
        }
        st.print();
    }
}

TEST(TorusTrace, TangentRays) {
    const double R = 5, r = 0.125;
    struct Case {
        const char* name;
        Surface s;
        Vec3 o, d;
        size_t roots;  // distinct reference roots
    };
    const Surface at0 = Surface::torus({0, 0, 0}, {0, 0, 1}, R, r);
    const std::vector<Case> cases = {
        // From outside: over the top of the tube along the diameter (touching at x = -+R).
        {"top, diameter", at0, {-2 * R, 0, r}, {1, 0, 0}, 2},
        // Under the bottom of the tube.
        {"bottom, diameter", at0, {-2 * R, 0, -r}, {1, 0, 0}, 2},
        // Along the top circle's tangent (fourth-order contact).
        {"top, along the groove", at0, {R, -3, r}, {0, 1, 0}, 1},
        // In the equatorial plane, tangent to the outer equator.
        {"outer equator, in plane", at0, {-10, R + r, 0}, {1, 0, 0}, 1},
        // In the equatorial plane, tangent to the inner equator from inside the tube.
        {"inner equator, in plane", at0, {-10, R - r, 0}, {1, 0, 0}, 3},
        // Parallel to the axis, tangent to the outer equator.
        {"outer equator, axial", at0, {R + r, 0, -1}, {0, 0, 1}, 1},
        // Parallel to the axis through the hole, tangent to the inner equator.
        {"inner equator, axial (hole)", at0, {0, R - r, -1}, {0, 0, 1}, 1},
        // Along the axis, through the middle of the hole: nothing.
        {"axis (hole)", at0, {0, 0, -1}, {0, 0, 1}, 0},
        // The same with an offset centre whose coordinates keep the tangencies exact.
        {"top, diameter, offset", Surface::torus({0.5, -2, 3}, {0, 0, 1}, R, r), {0.5 - 2 * R, -2, 3 + r}, {1, 0, 0}, 2},
        {"inner equator, axial, offset", Surface::torus({0.5, -2, 3}, {0, 1, 0}, R, r), {0.5 + R - r, 0, 3}, {0, 1, 0}, 1},
    };
    Stats st;
    st.name = "tangent exact";
    for (const Case& c : cases) {
        const TorusReference ref(c.s.origin, c.s.axis, c.s.radius, c.s.minor_radius, c.o, c.d);
        ASSERT_EQ(ref.roots().size(), c.roots) << c.name;
        int touching = 0;
        for (const TorusRoot& x : ref.roots()) touching += x.multiplicity >= 2;
        EXPECT_EQ(touching, c.roots == 0 ? 0 : (c.roots == 3 ? 1 : static_cast<int>(c.roots))) << c.name;
        const Roots got = compare(c.s, c.o, c.d, st, c.name);
        if (c.roots == 0) {
            EXPECT_EQ(got.count, 0) << c.name;
        }
    }
    st.print();
    EXPECT_EQ(st.multiple, 12);

    // Near-tangent rays in every orientation: a random tube point, a random tangent direction
    // (exactly tangent up to the rounding of the construction, so either side of tangency).
    std::mt19937_64 g(3);
    std::uniform_real_distribution<double> U(0, 1);
    for (double ratio : {1.1, 10.0, 1e3, 1e4}) {
        Stats rs;
        rs.name = "tangent random R/r " + std::to_string(ratio).substr(0, 6);
        for (int n = 0; n < 400; ++n) {
            const double RR = 0.5 + 20 * U(g), rr = RR / ratio;
            const Surface s = Surface::torus({10 * U(g) - 5, 10 * U(g) - 5, 10 * U(g) - 5}, random_unit(g), RR, rr);
            const TubePoint q = tube_point(s, 2 * M_PI * U(g), 2 * M_PI * U(g));
            Vec3 t = random_unit(g);
            t = normalize(t - q.n * dot(t, q.n));
            compare(s, q.p - t * (3 * rr), t, rs, s.describe() + " " + ray_text(q.p - t * (3 * rr), t));
        }
        rs.print();
    }
}

TEST(TorusTrace, RaysAlongTheGroove) {
    // Lines along the centre circle's direction inside the tube: at (R + a, 0, b) with a^2 + b^2 < r^2,
    // direction (0, 1, 0): the tube is left where rho = R + sqrt(r^2 - b^2), at
    // y = +-sqrt((R + w)^2 - (R + a)^2): two roots ~2 sqrt(2 R r) apart, far apart for the tube.
    std::mt19937_64 g(5);
    std::uniform_real_distribution<double> U(0, 1);
    Stats st;
    st.name = "along the groove";
    for (double ratio : {1.1, 4.0, 40.0, 1e3, 1e4}) {
        const double R = 5, r = R / ratio;
        const Surface s = Surface::torus({0, 0, 0}, {0, 0, 1}, R, r);
        for (int i = -4; i <= 4; ++i)
            for (int j = -4; j <= 4; ++j) {
                const double a = 0.2 * i * r, b = 0.2 * j * r;
                if (a * a + b * b >= 0.99 * r * r) continue;
                const Vec3 o{R + a, -3 * (R + r), b}, d{0, 1, 0};
                const Roots got = compare(s, o, d, st, s.describe() + " " + ray_text(o, d));
                EXPECT_EQ(got.count, 2) << ray_text(o, d);
            }
        // The same lines rotated to random azimuths, and tilted tori.
        for (int n = 0; n < 100; ++n) {
            const Surface t = n % 2 ? s : Surface::torus({1, 2, 3}, random_unit(g), R, r);
            const double phi = 2 * M_PI * U(g), rho = std::sqrt(U(g)) * 0.95 * r, psi = 2 * M_PI * U(g);
            Vec3 e0, e1;
            orthonormal_basis(t.axis, e0, e1);
            const Vec3 radial = e0 * std::cos(phi) + e1 * std::sin(phi), along = cross(t.axis, radial);
            const Vec3 p = t.origin + radial * (R + rho * std::cos(psi)) + t.axis * (rho * std::sin(psi));
            const Vec3 o = p - along * (3 * (R + r));
            compare(t, o, along, st, t.describe() + " " + ray_text(o, along));
        }
    }
    st.print();
    EXPECT_EQ(st.band, 0);

    // Rays in the equatorial plane (z = 0 exactly, direction (cos, sin, 0)): 0, 2 or 4 roots,
    // the two chords of a 4-root ray 2 (R - r) apart or more.
    Stats eq;
    eq.name = "equatorial plane";
    for (double ratio : {1.1, 4.0, 40.0, 1e3, 1e4}) {
        const double R = 5, r = R / ratio;
        const Surface s = Surface::torus({0, 0, 0}, {0, 0, 1}, R, r);
        int four = 0;
        for (int n = 0; n < 300; ++n) {
            const double phi = 2 * M_PI * U(g);
            const Vec3 d{std::cos(phi), std::sin(phi), 0};
            // Lines at distance b from the centre: b in [0, R + 1.2 r].
            const double b = U(g) * (R + 1.2 * r);
            const Vec3 normal{-d.y, d.x, 0};
            const Vec3 o = normal * b - d * (2 * (R + r) * (0.5 + U(g)));
            four += compare(s, o, d, eq, s.describe() + " " + ray_text(o, d)).count == 4;
        }
        EXPECT_GT(four, 0);
        // Through the centre: roots at +-(R - r) and +-(R + r) from it.
        const Vec3 o{-3 * R, 0, 0};
        const Roots got = compare(s, o, {1, 0, 0}, eq, "diameter");
        ASSERT_EQ(got.count, 4);
    }
    eq.print();
}
