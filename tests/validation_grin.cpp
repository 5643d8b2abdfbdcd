// The GRIN reference solver (validation/GrinReference.h) against the closed forms of
// validation/GrinClosedForms.h, against the homogeneous reference (validation/AnalyticScene.h) in
// the homogeneous limit, and against first-order and sharp-interface results for inhomogeneities.
// Tolerances: tests/Tolerances.h and validation/ValidationTolerance.h.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "tests/Tolerances.h"
#include "validation/AnalyticScene.h"
#include "validation/GrinClosedForms.h"
#include "validation/GrinReference.h"
#include "validation/ValidationTolerance.h"

using namespace ltm;
using namespace ltm::validation;
namespace cf = ltm::validation::grin_closed_form;

namespace {

IndexField field(IndexFieldType type, double ior, const Vec3& gradient = {}, double g = 0,
                 const Mat3& hessian = Mat3::zero()) {
    IndexField f;
    f.type = type;
    f.ior = ior;
    f.gradient = gradient;
    f.g = g;
    f.hessian = hessian;
    return f;
}

Scene window_scene(double t, double D, double n, const IndexField& f, const std::vector<Defect>& defects = {},
                   RimFinish rim = RimFinish::Polished) {
    Scene s;
    s.source = "test";
    s.object.type = ObjectType::Window;
    s.object.lens.r1 = INFINITY;
    s.object.lens.r2 = INFINITY;
    s.object.lens.center_thickness = t;
    s.object.lens.diameter = D;
    s.object.lens.ior = n;
    s.object.rim = rim;
    s.object.index_field = f;
    s.defects = defects;
    return s;
}

Scene lens_scene(double r1, double r2, double t, double D, double n, const IndexField& f,
                 const std::vector<Defect>& defects = {}) {
    Scene s = window_scene(t, D, n, f, defects);
    s.object.type = ObjectType::Lens;
    s.object.lens.r1 = r1;
    s.object.lens.r2 = r2;
    return s;
}

// A ball: LensSpec{R, -R, 2R, 2R, ball = true} (geometry/Lens.h, ball_spec).
Scene ball_scene(double R, double n, const IndexField& f) {
    Scene s = window_scene(2 * R, 2 * R, n, f);
    s.object.type = ObjectType::Sphere;
    s.object.lens.r1 = R;
    s.object.lens.r2 = -R;
    s.object.lens.ball = true;
    return s;
}

Defect sphere_defect(DefectType type, const Vec3& c, double r) {
    Defect d;
    d.type = type;
    d.center = c;
    d.semi_axes = {r, r, r};
    return d;
}

Defect inhomogeneity(const Vec3& c, double r, double dn, IndexProfile profile) {
    Defect d = sphere_defect(DefectType::Inhomogeneity, c, r);
    d.delta_n = dn;
    d.index_profile = profile;
    return d;
}

// The Luneburg sphere of radius R: ior sqrt 2, spherical_n2 with g = 1 / (R sqrt 2).
Scene luneburg_scene(double R) {
    const double n0 = std::sqrt(2.0);
    return ball_scene(R, n0, field(IndexFieldType::SphericalN2, n0, {}, 1.0 / (R * std::sqrt(2.0))));
}

double display_error(const Path& p, const cf::Exit& e) {
    return std::hypot(p.display_x - e.display_x, p.display_y - e.display_y);
}

double angle(const Vec3& a, const Vec3& b) { return std::atan2(length(cross(a, b)), dot(a, b)); }

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A window path (front, back) of the reference against a closed-form exit; tolerances from
// tol::grin_reference_path with the reference's own step count and sensitivity.
double expect_window_path(const GrinReference& ref, const Vec3& entry, const Vec3& d, const cf::Exit& e, double n_min,
                          const std::string& what) {
    EXPECT_TRUE(e.exits) << what;
    if (!e.exits) return kInfinity;
    const Vec3 origin = entry - d * 2.0;
    const GrinPath g = ref.trace(origin, d);
    const Path& p = g.path;
    EXPECT_EQ(p.surfaces, (std::vector<std::string>{"front", "back"})) << what;
    const RaySensitivity s = ref.sensitivity(origin, d);
    EXPECT_TRUE(s.stable) << what;
    if (p.vertices.size() != 2 || !s.stable) return kInfinity;
    const double p_ratio = std::max(1.0, ref.scene().object.lens.ior) / n_min;
    const double tp = tol::grin_reference_path(g.steps, grin_reference_constant(g, ref.length_scale()), ref.tolerance(),
                                               ref.object_size(), ref.length_scale(), p_ratio, s.kappa);
    const double td =
        tol::grin_reference_direction(g.steps, grin_reference_constant(g, ref.length_scale()), ref.tolerance(),
                                      ref.object_size(), ref.length_scale(), p_ratio, s.kappa_dir);
    EXPECT_LE(distance(p.vertices[0], e.entry), tp) << what;
    EXPECT_LE(distance(p.vertices[1], e.exit), tp) << what;
    EXPECT_LE(angle(p.direction, e.direction), td) << what;
    EXPECT_EQ(p.display_hit, e.display_hit) << what;
    double worst = std::max(distance(p.vertices[0], e.entry), distance(p.vertices[1], e.exit));
    if (e.display_hit && p.display_hit) {
        EXPECT_LE(display_error(p, e), tp) << what;
        worst = std::max(worst, display_error(p, e));
    }
    return worst;
}

}  // namespace

// ---- the closed forms against themselves ------------------------------------------------------------

// Each closed form satisfies the invariant |p| = n along its path (the ray equation's Hamiltonian
// |p|^2 - n^2 = 0), and its path function reproduces its exit values: independent checks of the
// derivations in GrinClosedForms.cpp, to rounding (tol::closed_form_identity).
TEST(GrinClosedForms, InvariantsAndExits) {
    const double R = 10;
    const cf::LuneburgPath L{R, {0, -6, -8}, normalize(Vec3{0.1, 0.3, 1.0})};
    for (double tau : {0.0, 1.0, 5.0, 9.0, L.exit_tau()}) {
        const Vec3 r = L.position(tau), p = L.momentum(tau);
        EXPECT_NEAR(dot(p, p), 2.0 - dot(r, r) / (R * R), tol::closed_form_identity(2.0)) << tau;
    }
    const cf::Exit le = cf::luneburg(R, L.r0, L.d0, 60);
    EXPECT_LE(distance(L.position(L.exit_tau()), le.exit), tol::closed_form_identity(R));
    EXPECT_LE(distance(L.momentum(L.exit_tau()), le.exit_momentum), tol::closed_form_identity(1.0));
    EXPECT_NEAR(length(le.exit), R, tol::closed_form_identity(R));

    // The rod: p_x^2 + w^2 x^2 per axis is constant, so |p|^2 + w^2 rho^2 = n0^2.
    const double n0 = 1.6, G = 0.1, t = 40;
    const cf::Exit re = cf::grin_rod(n0, G, t, 1.0, -0.5, normalize(Vec3{0.2, 0.1, 1.0}), 60);
    const double w = n0 * G;
    EXPECT_NEAR(dot(re.exit_momentum, re.exit_momentum) + w * w * (re.exit.x * re.exit.x + re.exit.y * re.exit.y),
                n0 * n0, tol::closed_form_identity(n0 * n0));

    // The catenary against the same path written in tau: n(tau) = n_e cosh(k tau) + p_x0 sinh(k tau)
    // solves n'' = k^2 n (x'' = n k with n = n0 + k x), an independent closed form; x = (n - n0) / k
    // divides by k, hence the magnitude n0 / |k|.
    const double k = 0.02, n1 = 1.5, t1 = 10, x0 = 3.0;
    const Vec3 d = normalize(Vec3{0.3, 0.2, 1.0});
    const cf::Exit ce = cf::catenary_window(n1, k, t1, x0, 0.0, d, 60);
    const double ne = n1 + k * x0;
    const double n_exit = ne * std::cosh(k * ce.tau) + ce.entry_momentum.x * std::sinh(k * ce.tau);
    EXPECT_NEAR(ce.exit.x, (n_exit - n1) / k, tol::closed_form_identity(n1 / k));
    EXPECT_NEAR(length(ce.exit_momentum), n1 + k * ce.exit.x, tol::closed_form_identity(n1 + k * ce.exit.x));

    // The parabola's stable plane crossing against the textbook root (-B + sqrt(B^2 + 4 A dz)) / (2 A),
    // which cancels to ~u B / |A| here (B = 1.4, A = b_z / 4).
    const cf::ParabolaPath P{{0, 0, -4}, {0.1, 0, 1.4}, {0, 0, 0.05}};
    const double tau = P.tau_to_plane(4.0), A = 0.0125, B = 1.4;
    EXPECT_NEAR(P.position(tau).z, 4.0, tol::closed_form_identity(4.0));
    EXPECT_NEAR(tau, (-B + std::sqrt(B * B + 4 * A * 8)) / (2 * A), tol::closed_form_identity(B / A));
}

// ---- (a) the Luneburg sphere ------------------------------------------------------------------------

// Every ray entering the Luneburg sphere leaves through R d0 with the direction -r0 / R. 64 rays
// with random directions (all over the sphere) and random entry points on the lit hemisphere
// (fixed seed), each against the closed form to the integration-derived tolerance.
TEST(GrinReference, LuneburgSphereRandomRays) {
    const double R = 10;
    const Scene scene = luneburg_scene(R);
    const GrinReference ref(scene);
    std::mt19937_64 rng(20240611);
    std::normal_distribution<double> gauss;
    double worst = 0, worst_ratio = 0;
    int display_hits = 0;
    for (int i = 0; i < 64; ++i) {
        const Vec3 d0 = normalize(Vec3{gauss(rng), gauss(rng), gauss(rng)});
        Vec3 u = normalize(Vec3{gauss(rng), gauss(rng), gauss(rng)});
        if (dot(u, d0) > 0) u = -u;
        if (dot(u, d0) > -0.05) u = normalize(u - d0 * 0.2);  // not grazing (ill-conditioned)
        const Vec3 r0 = u * R;
        const Vec3 origin = r0 - d0 * (3 * R);
        const cf::Exit e = cf::luneburg(R, r0, d0, scene.display.z);
        const GrinPath g = ref.trace(origin, d0);
        const Path& p = g.path;
        ASSERT_EQ(p.vertices.size(), 2u) << i;
        EXPECT_EQ(p.surfaces[0], r0.z < 0 ? "front" : "back") << i;
        if (std::fabs(e.exit.z) > 1e-6) {
            EXPECT_EQ(p.surfaces[1], e.exit.z < 0 ? "front" : "back") << i;
        }
        const RaySensitivity s = ref.sensitivity(origin, d0);
        ASSERT_TRUE(s.stable) << i;
        // n >= 1 in the sphere, p_scale = sqrt 2.
        const double tp =
            tol::grin_reference_path(g.steps, grin_reference_constant(g, ref.length_scale()), ref.tolerance(),
                                     ref.object_size(), ref.length_scale(), std::sqrt(2.0), s.kappa);
        const double td =
            tol::grin_reference_direction(g.steps, grin_reference_constant(g, ref.length_scale()), ref.tolerance(),
                                          ref.object_size(), ref.length_scale(), std::sqrt(2.0), s.kappa_dir);
        const double err = std::max(distance(p.vertices[0], r0), distance(p.vertices[1], e.exit));
        EXPECT_LE(err, tp) << i;
        EXPECT_LE(angle(p.direction, e.direction), td) << i;
        ASSERT_EQ(p.display_hit, e.display_hit) << i;
        double derr = 0;
        if (e.display_hit) {
            ++display_hits;
            derr = display_error(p, e);
            EXPECT_LE(derr, tp) << i;
        }
        worst = std::max({worst, err, derr});
        worst_ratio = std::max(worst_ratio, std::max(err, derr) / tp);
        EXPECT_EQ(p.tir_count, 0);
    }
    EXPECT_GT(display_hits, 10);
    std::cout << "[ Luneburg ] worst position error " << worst << " mm, worst error / tolerance " << worst_ratio
              << "\n";
}

// ---- (b) the GRIN rod ---------------------------------------------------------------------------------

TEST(GrinReference, GrinRodSinusoidalPaths) {
    const double n0 = 1.6, G = 0.1, t = 40, D = 10;
    const GrinReference ref(window_scene(t, D, n0, field(IndexFieldType::RadialN2, n0, {}, G)));
    // n >= n0 sqrt(1 - G^2 a^2) = 1.386 over the rod (a = 5).
    const double n_min = n0 * std::sqrt(1 - G * G * 25);
    double worst = 0;
    struct Ray {
        double x0, y0;
        Vec3 d;
    };
    for (const Ray& r : {Ray{0, 0, {0, 0, 1}}, Ray{1.0, 0, {0, 0, 1}}, Ray{0.5, -1.2, {0, 0, 1}},
                         Ray{0, 0, normalize(Vec3{0.2, 0, 1})}, Ray{-2, 1, normalize(Vec3{0.15, -0.25, 1})},
                         Ray{1.5, 1.5, normalize(Vec3{-0.3, 0.1, 1})}}) {
        const cf::Exit e = cf::grin_rod(n0, G, t, r.x0, r.y0, r.d, 60);
        worst = std::max(worst,
                         expect_window_path(ref, {r.x0, r.y0, -0.5 * t}, r.d, e, n_min,
                                            "rod ray at (" + std::to_string(r.x0) + ", " + std::to_string(r.y0) + ")"));
    }
    // The period 2 pi p_z / w: an axial ray at height x0 has p_z = n(x0), so with t equal to half a
    // period it leaves at -x0 (x = x0 cos(pi)).
    const double x0 = 1.0;
    const double pz = n0 * std::sqrt(1 - G * G * x0 * x0);
    const double half_period = kPi * pz / (n0 * G);
    const GrinReference half(window_scene(half_period, D, n0, field(IndexFieldType::RadialN2, n0, {}, G)));
    const cf::Exit e = cf::grin_rod(n0, G, half_period, x0, 0, {0, 0, 1}, 60);
    // The phase w tau = pi carries ~u pi relative: the amplitude x0 times (1 + pi).
    EXPECT_NEAR(e.exit.x, -x0, tol::closed_form_identity(x0 * (1 + kPi)));
    worst = std::max(worst, expect_window_path(half, {x0, 0, -0.5 * half_period}, {0, 0, 1}, e, n_min, "half period"));
    std::cout << "[ rod ] worst position error " << worst << " mm\n";
}

// Event location near a tangency: in the rod, a ray entering on the axis with p_x0 = w A swings
// out to x = A (x(tau) = A sin(w tau), the turning point at tau = pi / (2 w), well inside the rod
// here). With A = a (1 - eta) it comes within a eta of the rim and must NOT cross it; with
// A = a (1 + eta) it crosses the rim twice within 2 sqrt(2 eta) / w in tau and must be stopped at
// the first crossing, for eta down to 1e-10 (a 5e-10 mm miss or dip).
TEST(GrinReference, NearTangencyToTheRimIsResolved) {
    const double n0 = 1.6, G = 0.1, t = 40, D = 10, a = 5;
    const double w = n0 * G;
    const GrinReference ref(window_scene(t, D, n0, field(IndexFieldType::RadialN2, n0, {}, G)));
    for (double eta : {1e-4, 1e-7, 1e-10}) {
        for (int side : {-1, 1}) {
            const double A = a * (1 + side * eta);
            const Vec3 d{w * A, 0, std::sqrt(1 - w * A * w * A)};
            const GrinPath g = ref.trace(Vec3{0, 0, -0.5 * t} - d * 2.0, d);
            ASSERT_GE(g.path.surfaces.size(), 2u);
            if (side < 0) {
                EXPECT_EQ(g.path.surfaces, (std::vector<std::string>{"front", "back"})) << eta;
            } else {
                EXPECT_EQ(g.path.surfaces[1], "rim") << eta;
                // The first crossing: x = a before the turning point, sin(w tau) = 1 / (1 + eta).
                const double tau1 = std::asin(1 / (1 + eta)) / w;
                const double pz = std::sqrt(n0 * n0 - d.x * d.x);
                EXPECT_LT(g.path.vertices[1].z, -0.5 * t + pz * 0.5 * kPi / w) << eta;
                EXPECT_GT(g.path.vertices[1].z, -0.5 * t + pz * tau1 - 2 * pz * std::sqrt(2 * eta) / w) << eta;
            }
            std::cout << "[ tangency ] eta " << eta << (side < 0 ? " inside" : " outside") << ": " << g.steps
                      << " steps\n";
        }
    }
}

// ---- (c) the linear gradient ------------------------------------------------------------------------

TEST(GrinReference, LinearGradientParabolas) {
    const double n0 = 1.5, t = 8, D = 40;
    double worst = 0;
    for (const Vec3& b : {Vec3{0, 0, 0.05}, Vec3{0.03, 0, 0}, Vec3{0.02, -0.01, 0.04}, Vec3{0, 0, -0.05}}) {
        const GrinReference ref(window_scene(t, D, n0, field(IndexFieldType::LinearN2, n0, b)));
        // n^2 >= n0^2 - |b| max |x| over the window (|x| <= hypot(20, 4)).
        const double n_min = std::sqrt(n0 * n0 - length(b) * std::hypot(20.0, 4.0));
        for (const Vec3& d : {Vec3{0, 0, 1}, normalize(Vec3{0.3, 0, 1}), normalize(Vec3{-0.2, 0.4, 1})})
            for (const Vec3& xy : {Vec3{0, 0, 0}, Vec3{3, -2, 0}}) {
                const cf::Exit e = cf::linear_n2_window(n0, b, t, xy.x, xy.y, d, 60);
                worst = std::max(worst, expect_window_path(ref, {xy.x, xy.y, -0.5 * t}, d, e, n_min, "linear_n2"));
            }
    }
    std::cout << "[ linear_n2 ] worst position error " << worst << " mm\n";
}

// ---- (d) the catenary ----------------------------------------------------------------------------------

TEST(GrinReference, LinearIndexCatenaries) {
    const double n0 = 1.5, t = 10, D = 40;
    double worst = 0;
    for (double k : {0.02, -0.015}) {
        const GrinReference ref(window_scene(t, D, n0, field(IndexFieldType::LinearN, n0, {k, 0, 0})));
        const double n_min = n0 - std::fabs(k) * 20;
        for (const Vec3& d :
             {Vec3{0, 0, 1}, normalize(Vec3{0.3, 0, 1}), normalize(Vec3{-0.4, 0, 1}), normalize(Vec3{0.2, 0.3, 1})})
            for (double x0 : {0.0, 4.0, -6.0}) {
                const cf::Exit e = cf::catenary_window(n0, k, t, x0, 1.0, d, 60);
                worst = std::max(worst, expect_window_path(ref, {x0, 1.0, -0.5 * t}, d, e, n_min,
                                                           "catenary k=" + std::to_string(k)));
            }
    }
    std::cout << "[ catenary ] worst position error " << worst << " mm\n";
}

// ---- the homogeneous limit ---------------------------------------------------------------------------

// A graded field that is constant (quadratic_n2 with zero gradient and hessian: integrated, F = 0)
// and the uniform field (straight, exact) give AnalyticScene's paths, within validate's GRIN
// tolerance (ValidationTolerance.h, grin_position_tolerance: the tracer's floor, here standing for
// AnalyticScene's, the reference's rounding and twice its error estimate).
TEST(GrinReference, HomogeneousLimitEqualsAnalyticScene) {
    const double n = 1.5168;
    const std::vector<Defect> defects{sphere_defect(DefectType::Bubble, {0.5, 0, 0.5}, 0.4),
                                      sphere_defect(DefectType::Particle, {-2, 1.5, -0.5}, 0.3)};
    double worst = 0;
    for (IndexFieldType type : {IndexFieldType::QuadraticN2, IndexFieldType::Uniform}) {
        for (const Scene& scene :
             {lens_scene(50, -50, 6, 25, n, field(type, n), defects), lens_scene(-40, 60, 3, 20, n, field(type, n)),
              window_scene(5, 30, n, field(type, n), defects, RimFinish::Polished)}) {
            const GrinReference ref(scene);
            const AnalyticScene as(scene);
            int compared = 0;
            for (int i = -4; i <= 4; ++i)
                for (double tilt : {0.0, 0.12, -0.3}) {
                    const Vec3 o{0.5 + 1.9 * i, 0.7 - 0.3 * i, -20};
                    const Vec3 d = normalize(Vec3{tilt, 0.5 * tilt, 1});
                    const Path a = as.principal_path(o, d);
                    const GrinPath g = ref.trace(o, d);
                    ASSERT_EQ(g.path.surfaces, a.surfaces) << i << " " << tilt;
                    ASSERT_EQ(g.path.events, a.events);
                    const RaySensitivity s = ref.sensitivity(o, d);
                    if (!s.stable) continue;
                    ++compared;
                    const PathError est = ref.estimate_error(o, d);
                    ASSERT_TRUE(est.comparable);
                    const int nv = int(a.vertices.size());
                    const double tp = grin_position_tolerance(g, ref.length_scale(), s.kappa, est.position);
                    const double td = grin_direction_tolerance(g, ref.length_scale(), s.kappa_dir, est.direction);
                    for (int v = 0; v < nv; ++v) EXPECT_LE(distance(g.path.vertices[v], a.vertices[v]), tp) << v;
                    EXPECT_LE(angle(g.path.direction, a.direction), td);
                    ASSERT_EQ(g.path.display_hit, a.display_hit);
                    if (a.display_hit) {
                        const double e = std::hypot(g.path.display_x - a.display_x, g.path.display_y - a.display_y);
                        EXPECT_LE(e, tp);
                        worst = std::max(worst, e);
                    }
                    for (int v = 0; v < nv; ++v) worst = std::max(worst, distance(g.path.vertices[v], a.vertices[v]));
                    EXPECT_EQ(g.path.display_p, a.display_p);
                    EXPECT_EQ(g.path.display_q, a.display_q);
                    EXPECT_NEAR(g.path.transmission, a.transmission, tol::optics_identity() * (nv + 1));
                    if (type == IndexFieldType::Uniform) {
                        EXPECT_EQ(g.curved_segments, 0);
                    }
                }
            EXPECT_GT(compared, 20);
        }
    }
    std::cout << "[ homogeneous ] worst difference to AnalyticScene " << worst << " mm\n";
}

// ---- inhomogeneities -----------------------------------------------------------------------------------

// A uniform spherical inclusion (n_i = n_g + dn inside, a sharp interface) centred in a uniform
// window. A ray parallel to the axis at height b meets it at E = (b, 0, -sqrt(a^2 - b^2)) with
// incidence sin i = b / a and refracts to sin t = (n_g / n_i) sin i; its direction turns by i - t
// toward the axis, d_in = (-sin(i - t), 0, cos(i - t)), and it crosses the sphere along the chord
// 2 a cos t (the refracted ray makes the angle t with the inward normal at both ends), leaving at
// X = E + 2 a cos(t) d_in, turned by i - t again (the symmetric refraction): d_out =
// (-sin 2(i - t), 0, cos 2(i - t)). The back face conserves the tangential momentum:
// d_air = (n_g d_out.x, 0, sqrt(1 - (n_g d_out.x)^2)). The axial ray (b = 0) is undeviated.
TEST(GrinReference, UniformInclusionIsASharpInterface) {
    const double ng = 1.5, dn = 0.1, a = 2, t = 8;
    const Scene scene = window_scene(t, 20, ng, field(IndexFieldType::Uniform, ng),
                                     {inhomogeneity({0, 0, 0}, a, dn, IndexProfile::Uniform)});
    const GrinReference ref(scene);
    const Path axial = ref.principal_path({0, 0, -10}, {0, 0, 1});
    ASSERT_EQ(axial.surfaces, (std::vector<std::string>{"front", "inhomogeneity 0", "inhomogeneity 0", "back"}));
    const double tz = tol::closed_form_path(4, ref.length_scale(), 1.0);
    const double zs[4] = {-4, -2, 2, 4};
    for (int v = 0; v < 4; ++v) {
        EXPECT_EQ(axial.vertices[v].x, 0.0);
        EXPECT_EQ(axial.vertices[v].y, 0.0);
        EXPECT_NEAR(axial.vertices[v].z, zs[v], tz);
    }
    EXPECT_EQ(axial.direction.x, 0.0);
    EXPECT_EQ(axial.direction.y, 0.0);
    EXPECT_NEAR(axial.direction.z, 1.0, tol::optics_identity());
    const double ni = ng + dn;
    for (double b : {0.3, 0.9, 1.5, 1.9}) {
        const Vec3 o{b, 0, -10}, d{0, 0, 1};
        const Path p = ref.principal_path(o, d);
        ASSERT_EQ(p.surfaces, axial.surfaces) << b;
        const double i = std::asin(b / a), tr = std::asin(ng / ni * b / a);
        const Vec3 E{b, 0, -std::sqrt(a * a - b * b)};
        const Vec3 din{-std::sin(i - tr), 0, std::cos(i - tr)};
        const Vec3 X = E + din * (2 * a * std::cos(tr));
        const Vec3 dout{-std::sin(2 * (i - tr)), 0, std::cos(2 * (i - tr))};
        const Vec3 B = X + dout * ((0.5 * t - X.z) / dout.z);
        const double sx = ng * dout.x;
        const Vec3 dair{sx, 0, std::sqrt(1 - sx * sx)};
        const RaySensitivity s = ref.sensitivity(o, d);
        ASSERT_TRUE(s.stable);
        const double tp = tol::closed_form_path(4, ref.length_scale(), s.kappa);
        const double td = tol::closed_form_path(4, 1.0, s.kappa_dir);
        EXPECT_LE(distance(p.vertices[0], Vec3{b, 0, -4}), tp) << b;
        EXPECT_LE(distance(p.vertices[1], E), tp) << b;
        EXPECT_LE(distance(p.vertices[2], X), tp) << b;
        EXPECT_LE(distance(p.vertices[3], B), tp) << b;
        EXPECT_LE(angle(p.direction, dair), td) << b;
        // Snell at the inclusion's surface, as an identity on the path: n_g sin i = n_i sin t.
        const Vec3 N = normalize(p.vertices[1]);
        EXPECT_NEAR(ng * length(cross(d, N)), ni * length(cross(p.directions[1], N)), tol::snell_identity(ni));
    }
}

// A weak smooth spherical inclusion n = n0 + dn (1 - r^2/a^2)^2 (r < a) deflects a ray at impact
// parameter b by, to first order in dn, theta1 = (1 / n0) int grad_perp n ds along the straight
// line (the transverse momentum n sin(theta) gained, d/ds (n dx/ds) = dn/dx). On x = b, y = 0:
//   dn/dx = dn d/dx (1 - r^2/a^2)^2 = -4 dn x (1 - r^2/a^2) / a^2,  r^2 = b^2 + z^2,
//   int_{-c}^{c} (1 - (b^2 + z^2) / a^2) dz = (1 / a^2) int_{-c}^{c} (c^2 - z^2) dz = 4 c^3 / (3 a^2),
//   c = sqrt(a^2 - b^2), so
//   theta1(b) = -(dn / n0) 16 b (a^2 - b^2)^(3/2) / (3 a^4)   (toward the axis for dn > 0).
// The ray enters the window at normal incidence, so in the glass it runs along z until the
// inclusion; afterwards n = n0 and the back face conserves p_x: d_air.x = n0 sin(theta). The
// difference sin(theta) - theta1 is second order in eps = dn / n0 (tol::weak_lens_second_order);
// the reference's own direction error (tol::grin_reference_direction) is added.
TEST(GrinReference, SmoothInclusionFirstOrderDeflection) {
    const double n0 = 1.5, a = 2.5, t = 8;
    for (double dn : {1e-5, 2e-5, 0.02}) {
        const Scene scene = window_scene(t, 20, n0, field(IndexFieldType::Uniform, n0),
                                         {inhomogeneity({0, 0, 0}, a, dn, IndexProfile::Smooth)});
        const GrinReference ref(scene);
        const double eps = dn / n0;
        double worst_coef = 0;
        const Path axial = ref.principal_path({0, 0, -10}, {0, 0, 1});
        EXPECT_EQ(axial.direction.x, 0.0);
        EXPECT_EQ(axial.direction.y, 0.0);
        for (double b : {0.3, 0.8, 1.25, 1.8, 2.2}) {
            const Vec3 o{b, 0, -10}, d{0, 0, 1};
            const GrinPath g = ref.trace(o, d);
            ASSERT_EQ(g.path.surfaces, (std::vector<std::string>{"front", "back"})) << b;
            EXPECT_EQ(g.curved_segments, 1);
            const double c = std::sqrt(a * a - b * b);
            const double theta1 = -eps * 16 * b * c * c * c / (3 * a * a * a * a);
            const double sin_theta = g.path.direction.x / n0;
            const RaySensitivity s = ref.sensitivity(o, d);
            ASSERT_TRUE(s.stable);
            const double tnum =
                tol::grin_reference_direction(g.steps, grin_reference_constant(g, ref.length_scale()), ref.tolerance(),
                                              ref.object_size(), ref.length_scale(), 1.0, s.kappa_dir);
            EXPECT_LE(std::fabs(sin_theta - theta1), tol::weak_lens_second_order(eps) + tnum)
                << "dn " << dn << " b " << b << ": " << sin_theta << " vs " << theta1;
            EXPECT_NEAR(g.path.direction.y, 0.0, tnum);
            worst_coef = std::max(worst_coef, std::fabs(sin_theta - theta1) / (eps * eps));
        }
        std::cout << "[ smooth inclusion ] dn " << dn << ": largest |sin(theta) - theta1| / eps^2 = " << worst_coef
                  << " (bound 64)\n";
    }
}

// ---- the error estimate ---------------------------------------------------------------------------------

// estimate_error is an a-posteriori estimate of the reference's own error: the true error against
// the closed form is within twice the estimate plus the rounding that the estimate need not see
// (the reference's, C_ref u L (1 + kappa), and the closed form's, 128 u L (1 + kappa)), as
// ValidationTolerance.h's tolerance assumes; and the estimate is below the a-priori bound
// tol::grin_reference_path (it is "small"), at the default tolerance and at looser ones.
TEST(GrinReference, ErrorEstimateBoundsTheTrueError) {
    const double R = 10;
    const Scene scene = luneburg_scene(R);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> gauss;
    for (double tol_int : {1e-6, 1e-9, 1e-12}) {
        GrinOptions opt;
        opt.tolerance = tol_int;
        const GrinReference ref(scene, opt);
        const double L = ref.length_scale();
        double worst_est = 0, worst_err = 0;
        for (int i = 0; i < 12; ++i) {
            const Vec3 d0 = normalize(Vec3{gauss(rng), gauss(rng), 2.0 + gauss(rng)});
            Vec3 u = normalize(Vec3{gauss(rng), gauss(rng), gauss(rng)});
            if (dot(u, d0) > -0.1) u = normalize(u - d0 * (dot(u, d0) + 0.5));
            const Vec3 r0 = u * R, origin = r0 - d0 * (3 * R);
            const cf::Exit e = cf::luneburg(R, r0, d0, scene.display.z);
            const GrinPath g = ref.trace(origin, d0);
            const PathError est = ref.estimate_error(origin, d0);
            ASSERT_TRUE(est.comparable);
            const RaySensitivity s = ref.sensitivity(origin, d0);
            ASSERT_TRUE(s.stable);
            double err = std::max(distance(g.path.vertices[0], r0), distance(g.path.vertices[1], e.exit));
            if (e.display_hit) err = std::max(err, display_error(g.path, e));
            const double unseen = (grin_reference_constant(g, L) + 128.0) * kUnitRoundoff * L * (1.0 + s.kappa);
            EXPECT_LE(err, kReferenceSafety * est.position + unseen) << tol_int << " " << i;
            EXPECT_LE(est.position, tol::grin_reference_path(g.steps, grin_reference_constant(g, L), tol_int,
                                                             ref.object_size(), L, std::sqrt(2.0), s.kappa))
                << tol_int << " " << i;
            worst_est = std::max(worst_est, est.position);
            worst_err = std::max(worst_err, err);
        }
        std::cout << "[ estimate ] tol " << tol_int << ": worst true error " << worst_err << " mm, worst estimate "
                  << worst_est << " mm\n";
    }
}

// ---- total internal reflection in a graded medium -----------------------------------------------------

// n^2 = n0^2 + 0.05 x: the transverse momentum p_x = p_x0 + 0.05 tau / 2 grows along the path, so
// a steep ray (sin = 0.9 in air) reaches the back face with |p_t| > 1 = n_air and is totally
// reflected (p_z -> -p_z), then again at the front face, the parabolas of the closed form (c)
// between them. The rim is absorbing, which ends the zigzag.
TEST(GrinReference, TotalInternalReflectionInGradedGlass) {
    const double n0 = 1.5, t = 8, D = 40;
    const Vec3 b{0.05, 0, 0};
    const GrinReference ref(window_scene(t, D, n0, field(IndexFieldType::LinearN2, n0, b), {}, RimFinish::Absorbing));
    const Vec3 d{0.9, 0, std::sqrt(1 - 0.81)};
    const Vec3 entry{-12, 0, -0.5 * t};
    const GrinPath g = ref.trace(entry - d * 2.0, d);
    const Path& p = g.path;
    ASSERT_GE(p.vertices.size(), 4u);
    EXPECT_EQ(p.surfaces[0], "front");
    EXPECT_EQ(p.surfaces[1], "back");
    EXPECT_EQ(p.surfaces[2], "front");
    EXPECT_EQ(p.events[0], Event::Transmitted);
    EXPECT_EQ(p.events[1], Event::TotalInternalReflection);
    EXPECT_EQ(p.events[2], Event::TotalInternalReflection);
    EXPECT_TRUE(p.absorbed);
    EXPECT_EQ(p.surfaces.back(), "rim");
    // The closed form: two parabolas with the mirror reflection p_z -> -p_z between them.
    cf::ParabolaPath leg{entry, {d.x, d.y, std::sqrt(n0 * n0 + dot(b, entry) - d.x * d.x)}, b};
    const double tau1 = leg.tau_to_plane(0.5 * t);
    const Vec3 v1 = leg.position(tau1), p1 = leg.momentum(tau1);
    ASSERT_GT(std::hypot(p1.x, p1.y), 1.0);  // TIR at the back face
    cf::ParabolaPath leg2{v1, {p1.x, p1.y, -p1.z}, b};
    const double tau2 = leg2.tau_to_plane(-0.5 * t);
    const Vec3 v2 = leg2.position(tau2), p2 = leg2.momentum(tau2);
    ASSERT_GT(std::hypot(p2.x, p2.y), 1.0);  // and at the front face
    // The path's own sensitivity is not defined for the whole (absorbed) path's vertices beyond;
    // the first three vertices are compared with the sensitivity of the full path.
    const RaySensitivity s = ref.sensitivity(entry - d * 2.0, d);
    ASSERT_TRUE(s.stable);
    const double n_min = std::sqrt(n0 * n0 - 0.05 * 20);
    const double tp = tol::grin_reference_path(g.steps, grin_reference_constant(g, ref.length_scale()), ref.tolerance(),
                                               ref.object_size(), ref.length_scale(), n0 / n_min, s.kappa);
    EXPECT_LE(distance(p.vertices[0], entry), tp);
    EXPECT_LE(distance(p.vertices[1], v1), tp);
    EXPECT_LE(distance(p.vertices[2], v2), tp);
    EXPECT_EQ(p.tir_count, int(p.vertices.size()) - 2);
}

// ---- bad input ---------------------------------------------------------------------------------------------

TEST(GrinReference, RejectsUnsupportedScenes) {
    const double n = 1.5;
    std::string why;
    Defect scratch;
    scratch.type = DefectType::Scratch;
    const Scene with_scratch = window_scene(5, 20, n, field(IndexFieldType::LinearN2, n, {0, 0, 0.01}),
                                            {sphere_defect(DefectType::Bubble, {0, 0, 0}, 0.2), scratch});
    EXPECT_FALSE(grin_supports(with_scratch, &why));
    EXPECT_NE(why.find("defects[1]"), std::string::npos) << why;
    EXPECT_NE(why.find("scratch"), std::string::npos) << why;
    EXPECT_THROW(GrinReference{with_scratch}, std::invalid_argument);

    Defect pit = sphere_defect(DefectType::Bubble, {0, 0, -2.5}, 0.2);
    pit.surface_breaking = true;
    const Scene with_pit = window_scene(5, 20, n, field(IndexFieldType::Uniform, n), {pit});
    EXPECT_FALSE(grin_supports(with_pit, &why));
    EXPECT_NE(why.find("defects[0]"), std::string::npos) << why;
    EXPECT_NE(why.find("surface-breaking"), std::string::npos) << why;
    try {
        GrinReference r(with_pit);
        ADD_FAILURE() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("defects[0]"), std::string::npos) << e.what();
    }

    const Scene overlapping = window_scene(5, 20, n, field(IndexFieldType::Uniform, n),
                                           {sphere_defect(DefectType::Bubble, {0, 0, 0}, 0.5),
                                            inhomogeneity({0.8, 0, 0}, 0.5, 0.01, IndexProfile::Smooth)});
    EXPECT_FALSE(grin_supports(overlapping, &why));
    EXPECT_NE(why.find("defects[0] and defects[1]"), std::string::npos) << why;

    const Scene ok = window_scene(
        5, 20, n, field(IndexFieldType::SphericalN2, n, {}, 0.01),
        {sphere_defect(DefectType::Bubble, {0, 0, 0}, 0.3), inhomogeneity({3, 0, 0}, 0.5, 0.01, IndexProfile::Smooth),
         inhomogeneity({-3, 0, 0}, 0.5, -0.02, IndexProfile::Uniform),
         sphere_defect(DefectType::Particle, {0, 4, 0}, 0.2)});
    EXPECT_TRUE(grin_supports(ok, &why)) << why;
    EXPECT_TRUE(why.empty());

    GrinOptions bad;
    bad.tolerance = 0;
    EXPECT_THROW((GrinReference{ok, bad}), std::invalid_argument);
}

// ---- speed ---------------------------------------------------------------------------------------------------

// Not a correctness check: the paths per second that `ltmsim validate` can count on (~2000 rays,
// each traced for its sensitivity and error estimate).
TEST(GrinReference, Throughput) {
    struct Case {
        std::string name;
        Scene scene;
    };
    const double n0 = 1.6;
    std::vector<Case> cases{
        {"luneburg", luneburg_scene(10)},
        {"rod", window_scene(40, 10, n0, field(IndexFieldType::RadialN2, n0, {}, 0.1))},
        {"linear_n2", window_scene(8, 40, 1.5, field(IndexFieldType::LinearN2, 1.5, {0.02, -0.01, 0.04}))},
        {"smooth inclusion", window_scene(8, 20, 1.5, field(IndexFieldType::Uniform, 1.5),
                                          {inhomogeneity({0, 0, 0}, 2.5, 0.02, IndexProfile::Smooth)})}};
    for (const Case& c : cases) {
        const GrinReference ref(c.scene);
        const int N = 500;
        long steps = 0;
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < N; ++i) {
            const double x = -3.0 + 6.0 * (i % 25) / 24.0, y = -3.0 + 6.0 * (i / 25) / 19.0;
            const GrinPath g = ref.trace({x, y, -30}, normalize(Vec3{0.01 * (i % 7), -0.01 * (i % 5), 1}));
            steps += g.steps;
        }
        const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::cout << "[ throughput ] " << c.name << ": " << N / sec << " paths/s, " << double(steps) / N
                  << " steps/path\n";
    }
}
