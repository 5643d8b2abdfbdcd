// The analytic reference solver (validation/AnalyticScene.h) against closed forms of geometrical
// optics, and the validation ray set (validation/ValidationRays.h). Tolerances: tests/Tolerances.h.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <string>

#include "scene/SceneLoader.h"
#include "tests/BuildPaths.h"
#include "tests/Tolerances.h"
#include "validation/AnalyticScene.h"
#include "validation/ValidationRays.h"
#include "validation/ValidationTolerance.h"

using namespace ltm;
using namespace ltm::validation;

namespace {

constexpr double kDeg = kPi / 180.0;

Scene lens_scene(const std::string& r1, const std::string& r2, double t, double D, double n,
                 const std::string& extra = "", const std::string& rim = "polished") {
    const std::string y = "object: {type: lens, r1: " + r1 + ", r2: " + r2 +
                          ", center_thickness: " + std::to_string(t) + ", diameter: " + std::to_string(D) +
                          ", ior: " + std::to_string(n) + ", rim: " + rim + "}\n" + extra;
    return parse_scene(y, "test.yaml");
}

Scene window_scene(double t, double D, double n, const std::string& extra = "", const std::string& rim = "polished") {
    const std::string y = "object: {type: window, thickness: " + std::to_string(t) +
                          ", diameter: " + std::to_string(D) + ", ior: " + std::to_string(n) +
                          ", rim: " + rim + "}\n" + extra;
    return parse_scene(y, "test.yaml");
}

Scene example(const std::string& name) { return load_scene(ltm::test::source_dir() + "/scenes/" + name); }

void expect_vec_near(const Vec3& a, const Vec3& b, double tol, const std::string& what = "") {
    EXPECT_LE(distance(a, b), tol) << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x
                                   << ", " << b.y << ", " << b.z << ")";
}

}  // namespace

// ---- single-interface optics ---------------------------------------------------------------------

// Normal incidence: rs = (n1 - n2) / (n1 + n2), rp = -(rs), so R = ((n - 1) / (n + 1))^2 = 0.04
// for n = 1.5 (Hecht, Optics, 4th ed., Sec. 4.6.3), from either side.
TEST(AnalyticOptics, FresnelNormalIncidence) {
    const Fresnel in = fresnel(1.0, 1.5, 1.0), out = fresnel(1.5, 1.0, 1.0);
    EXPECT_NEAR(in.R, 0.04, tol::optics_identity());
    EXPECT_NEAR(out.R, 0.04, tol::optics_identity());
    EXPECT_NEAR(in.Rs, in.Rp, tol::optics_identity());
    EXPECT_NEAR(in.T, 0.96, tol::optics_identity());
    EXPECT_FALSE(in.tir);
    EXPECT_FALSE(out.tir);
    // The same through interact() with an arbitrary normal orientation.
    const Interaction i2 = interact({0, 0, 1}, {0, 0, 1}, 1.0, 1.5);
    EXPECT_NEAR(i2.R, 0.04, tol::optics_identity());
    EXPECT_EQ(i2.direction.z, 1.0);
}

// Brewster's angle tan(theta_B) = n2 / n1 (Hecht, Sec. 8.6.1): the p-polarised reflectance
// vanishes, from either side (theta_B' = atan(n1 / n2) inside the glass).
TEST(AnalyticOptics, BrewsterAngle) {
    for (double n : {1.5, 1.5168, 1.8}) {
        const Fresnel in = fresnel(1.0, n, std::cos(std::atan(n)));
        const Fresnel out = fresnel(n, 1.0, std::cos(std::atan(1.0 / n)));
        EXPECT_LE(std::sqrt(in.Rp), tol::optics_identity()) << n;
        EXPECT_LE(std::sqrt(out.Rp), tol::optics_identity()) << n;
        EXPECT_GT(in.Rs, 0.01);  // s is still reflected
        EXPECT_FALSE(out.tir);   // Brewster's angle inside is below the critical angle
    }
}

// Beyond the critical angle asin(n2 / n1) from the dense side all light is reflected (Hecht,
// Sec. 4.7): R = 1, and the ray takes the mirror direction. Just below it, it is transmitted.
TEST(AnalyticOptics, TotalInternalReflectionBeyondCriticalAngle) {
    const double n = 1.5;
    const double tc = std::asin(1.0 / n);
    for (double dt : {1e-6, 1e-3, 0.1, 0.5}) {
        const double th = tc + dt;
        const Fresnel f = fresnel(n, 1.0, std::cos(th));
        EXPECT_TRUE(f.tir);
        EXPECT_EQ(f.R, 1.0);
        EXPECT_EQ(f.T, 0.0);
        const Vec3 d{std::sin(th), 0.0, std::cos(th)};
        const Interaction in = interact(d, {0, 0, 1}, n, 1.0);
        EXPECT_TRUE(in.tir);
        EXPECT_EQ(in.R, 1.0);
        expect_vec_near(in.direction, {d.x, d.y, -d.z}, tol::optics_identity(), "mirror");
        const Fresnel below = fresnel(n, 1.0, std::cos(tc - dt));
        EXPECT_FALSE(below.tir);
        EXPECT_LT(below.R, 1.0);
    }
}

// Snell's law as an identity on random directions: n1 sin_i = n2 sin_t with the sines measured as
// |d x N| and |t x N|; t coplanar with d and N, on the far side, unit length.
TEST(AnalyticOptics, SnellIdentityRandomDirections) {
    std::mt19937_64 rng(12345);
    std::normal_distribution<double> g;
    const double ns[3] = {1.0, 1.5, 1.5168};
    int refracted = 0;
    for (int i = 0; i < 2000; ++i) {
        const Vec3 d = normalize(Vec3{g(rng), g(rng), g(rng)});
        const Vec3 N = normalize(Vec3{g(rng), g(rng), g(rng)});
        const double n1 = ns[i % 3], n2 = ns[(i / 3) % 3];
        const Interaction in = interact(d, N, n1, n2);
        EXPECT_LE(dot(in.normal, d), 0.0);
        EXPECT_NEAR(length(in.direction), 1.0, tol::optics_identity());
        // Coplanarity: t . (d x N) = 0.
        EXPECT_NEAR(dot(in.direction, cross(d, in.normal)), 0.0, tol::snell_identity(1.0));
        if (in.tir) {
            EXPECT_GT(n1 * length(cross(d, in.normal)), n2 * (1.0 - tol::snell_identity(1.0)));
            continue;
        }
        ++refracted;
        EXPECT_NEAR(n1 * length(cross(d, in.normal)), n2 * length(cross(in.direction, in.normal)),
                    tol::snell_identity(std::max(n1, n2)));
        EXPECT_LT(dot(in.direction, in.normal), 0.0);  // crosses the interface
        EXPECT_NEAR(in.cos_t, -dot(in.direction, in.normal), tol::snell_identity(1.0));
    }
    EXPECT_GT(refracted, 1000);
}

// Energy: with T computed from the transmission amplitudes (not as 1 - R), Rs + Ts = Rp + Tp = 1
// at every angle below the critical one, from both sides (Hecht, Sec. 4.6.3).
TEST(AnalyticOptics, FresnelEnergyConservation) {
    for (double n : {1.2, 1.5168, 2.0})
        for (int side = 0; side < 2; ++side)
            for (int k = 0; k <= 200; ++k) {
                const double ci = k / 200.0;
                const double n1 = side ? n : 1.0, n2 = side ? 1.0 : n;
                const Fresnel f = fresnel(n1, n2, ci);
                if (f.tir) {
                    EXPECT_EQ(f.R, 1.0);
                    continue;
                }
                EXPECT_NEAR(f.Rs + f.Ts, 1.0, tol::optics_identity()) << n << " " << side << " " << ci;
                EXPECT_NEAR(f.Rp + f.Tp, 1.0, tol::optics_identity()) << n << " " << side << " " << ci;
                EXPECT_NEAR(f.R + f.T, 1.0, tol::optics_identity());
            }
}

// ---- paths ---------------------------------------------------------------------------------------

// The optical axis ray meets every face at normal incidence: undeviated, display hit (0, 0)
// exactly (every x and y along the way is 0 times something), for every lens kind; the
// default scene's centred bubble is crossed along its diameter.
TEST(AnalyticPaths, AxialRayUndeviated) {
    std::vector<Scene> scenes{lens_scene("50", "-50", 6, 25, 1.5168), lens_scene("-40", "60", 3, 20, 1.6),
                              lens_scene("30", "45", 4, 20, 1.5), lens_scene("45", "30", 6, 20, 1.5),
                              lens_scene("inf", "-30", 5, 20, 1.5), lens_scene("inf", "25", 5, 20, 1.7),
                              window_scene(5, 30, 1.5), example("default.yaml")};
    for (const Scene& s : scenes) {
        const AnalyticScene as(s);
        const Path p = as.principal_path({0, 0, as.z_min() - 1}, {0, 0, 1});
        ASSERT_FALSE(p.absorbed);
        ASSERT_GE(p.vertices.size(), 2u);
        EXPECT_EQ(p.surfaces.front(), "front");
        EXPECT_EQ(p.surfaces.back(), "back");
        for (const Vec3& v : p.vertices) {
            EXPECT_EQ(v.x, 0.0);
            EXPECT_EQ(v.y, 0.0);
        }
        const double tz = tol::closed_form_path(int(p.vertices.size()), as.length_scale(), 1.0);
        EXPECT_NEAR(p.vertices.front().z, -0.5 * s.object.lens.center_thickness, tz);
        EXPECT_NEAR(p.vertices.back().z, 0.5 * s.object.lens.center_thickness, tz);
        EXPECT_EQ(p.direction.x, 0.0);
        EXPECT_EQ(p.direction.y, 0.0);
        EXPECT_EQ(p.direction.z, 1.0);
        ASSERT_TRUE(p.display_hit);
        EXPECT_TRUE(p.on_display);
        EXPECT_EQ(p.display_x, 0.0);
        EXPECT_EQ(p.display_y, 0.0);
        EXPECT_EQ(p.display_q, s.display.resolution[0] / 2);
        EXPECT_EQ(p.display_p, s.display.resolution[1] / 2);
        EXPECT_EQ(p.tir_count, 0);
        // Transmission: (1 - R0)^k with R0 = ((n - 1) / (n + 1))^2 for the k glass-air crossings.
        const double n = s.object.lens.ior, R0 = std::pow((n - 1) / (n + 1), 2);
        EXPECT_NEAR(p.transmission, std::pow(1 - R0, double(p.vertices.size())),
                    tol::optics_identity() * p.vertices.size());
    }
    const Path p = AnalyticScene(example("default.yaml")).principal_path({0, 0, -4}, {0, 0, 1});
    EXPECT_EQ(p.surfaces, (std::vector<std::string>{"front", "bubble 0", "bubble 0", "back"}));
}

// A paraxial ray through a thick double-convex lens crosses the axis at the back focal point:
// 1/f = (n - 1)(1/r1 - 1/r2 + (n - 1) t / (n r1 r2)) (lensmaker's equation for a thick lens), f
// measured from the second principal plane, which lies h2 = -f (n - 1) t / (n r1) from the back
// vertex (Hecht, Optics, 4th ed., Sec. 6.2.1). A real ray at height h crosses short of it by the
// spherical aberration, O(h^2) relative.
TEST(AnalyticPaths, ParaxialFocusLensmaker) {
    struct Case { double r1, r2, t, D, n; };
    for (const Case c : {Case{50, -50, 6, 25, 1.5168}, Case{100, -100, 4, 30, 1.5}, Case{40, -80, 5, 25, 1.7}}) {
        const Scene s = lens_scene(std::to_string(c.r1), std::to_string(c.r2), c.t, c.D, c.n,
                                   "display: {z: 300, size: [400, 400]}\n");
        const AnalyticScene as(s);
        const double n = c.n;
        const double f = 1.0 / ((n - 1) * (1 / c.r1 - 1 / c.r2 + (n - 1) * c.t / (n * c.r1 * c.r2)));
        const double h2 = -f * (n - 1) * c.t / (n * c.r1);
        const double z_H2 = 0.5 * c.t + h2;
        // Third-order coefficient (Tolerances.h): shape factor q = (r2 + r1) / (r2 - r1), position
        // factor p = -1 (object at infinity; p^2 and p q enter).
        const double q = (c.r2 + c.r1) / (c.r2 - c.r1), pp = -1;
        const double c3 = ((n + 2) / (n - 1) * q * q + 4 * (n + 1) * pp * q + (3 * n + 2) * (n - 1) * pp * pp +
                           n * n * n / (n - 1)) /
                          (8 * n * (n - 1));
        const double h = 0.01;
        const Path p = as.principal_path({h, 0, as.z_min() - 1}, {0, 0, 1});
        ASSERT_EQ(p.surfaces, (std::vector<std::string>{"front", "back"}));
        const Vec3 v = p.vertices.back(), d = p.direction;
        ASSERT_LT(d.x, 0.0);
        const double z_cross = v.z - v.x * d.z / d.x;
        const double f_meas = z_cross - z_H2;
        EXPECT_LE(std::fabs(f_meas - f) / f, tol::paraxial_focus_relative(c3, h, f))
            << "f = " << f << ", measured " << f_meas << ", third-order estimate of the shortfall "
            << c3 * h * h / f;
        EXPECT_LT(f_meas, f);  // positive lens, undercorrected: the real ray crosses short
        // O(h^2): at height 2h the shortfall is 4 times as large.
        const Path p2 = as.principal_path({2 * h, 0, as.z_min() - 1}, {0, 0, 1});
        const Vec3 v2 = p2.vertices.back(), d2 = p2.direction;
        const double f_meas2 = v2.z - v2.x * d2.z / d2.x - z_H2;
        EXPECT_NEAR((f - f_meas2) / (f - f_meas), 4.0, 4.0 * tol::paraxial_scaling());
    }
}

// A flat window displaces an oblique ray laterally by t sin(th - th') / cos(th') with
// sin th = n sin th' (Snell), and the ray leaves parallel to its entry direction.
TEST(AnalyticPaths, WindowLateralDisplacement) {
    const double t = 5.0, n = 1.5168;
    const Scene s = window_scene(t, 40, n, "display: {z: 60, size: [400, 400]}\n");
    const AnalyticScene as(s);
    for (double th_deg : {1.0, 5.0, 20.0, 45.0, 70.0, 85.0})
        for (double phi : {0.0, 0.7, 2.0, 4.0}) {
            const double th = th_deg * kDeg;
            const Vec3 d{std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th)};
            const Vec3 o = Vec3{1.0, -0.5, -0.5 * t} - d * (2.0 / d.z);
            const Path p = as.principal_path(o, d);
            ASSERT_EQ(p.surfaces, (std::vector<std::string>{"front", "back"})) << th_deg;
            const double thp = std::asin(std::sin(th) / n);
            const double shift = t * std::sin(th - thp) / std::cos(thp);
            const double measured = length(cross(p.vertices.back() - o, d));  // distance between the lines
            const RaySensitivity k = as.sensitivity(o, d);
            ASSERT_TRUE(k.stable);
            EXPECT_NEAR(measured, shift, tol::closed_form_path(2, as.length_scale(), k.kappa)) << th_deg;
            expect_vec_near(p.direction, d, tol::closed_form_path(2, 1.0, k.kappa_dir), "exit direction");
            // The glass segment has the refraction angle th'.
            EXPECT_NEAR(p.directions[0].z, std::cos(thp), tol::closed_form_path(1, 1.0, k.kappa_dir));
        }
}

// A ray crossing an enclosed spherical bubble along a diameter meets both of its surfaces at
// normal incidence and is undeviated. Window: the glass segment through the centre is built in
// closed form; lens: the reference solver's "bubble" ray aimed through a bubble's centre.
TEST(AnalyticPaths, BubbleDiameterUndeviated) {
    const double t = 4.0, n = 1.5168, r = 0.5;
    const Vec3 c{2.0, -1.0, 0.3};
    const Scene s = window_scene(t, 20, n, "defects: [{type: bubble, center: [2.0, -1.0, 0.3], radius: 0.5}]\n");
    const AnalyticScene as(s);
    for (double th_deg : {0.0, 10.0, 20.0, 40.0}) {
        const double th = th_deg * kDeg, phi = 0.5;
        const double thp = std::asin(std::sin(th) / n);
        const Vec3 da{std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), std::cos(th)};
        const Vec3 dg{std::sin(thp) * std::cos(phi), std::sin(thp) * std::sin(phi), std::cos(thp)};
        const Vec3 F = c - dg * ((c.z + 0.5 * t) / dg.z);
        const Vec3 o = F - da * 3.0;
        const Path p = as.principal_path(o, da);
        ASSERT_EQ(p.surfaces, (std::vector<std::string>{"front", "bubble 0", "bubble 0", "back"})) << th_deg;
        const RaySensitivity k = as.sensitivity(o, da);
        ASSERT_TRUE(k.stable);
        const double tp = tol::closed_form_path(4, as.length_scale(), k.kappa);
        const double td = tol::closed_form_path(4, 1.0, k.kappa_dir);
        expect_vec_near(p.vertices[1], c - dg * r, tp, "bubble entry");
        expect_vec_near(p.vertices[2], c + dg * r, tp, "bubble exit");
        expect_vec_near(p.directions[0], dg, td, "glass");
        expect_vec_near(p.directions[1], dg, td, "inside the bubble");
        expect_vec_near(p.directions[2], dg, td, "glass after");
        expect_vec_near(p.direction, da, td, "exit");
    }
    // The lens: the first "bubble" ray of each bubble is aimed (by inverse refraction at the
    // front) through its centre along +z in the glass.
    const Scene def = example("default.yaml");
    const AnalyticScene ad(def);
    std::map<std::string, int> seen;
    for (const ValidationRay& vr : validation_rays(def, 1)) {
        if (vr.category != "bubble") continue;
        const Path p = ad.principal_path(vr.origin, vr.direction);
        ASSERT_GE(p.surfaces.size(), 3u);
        if (seen[p.surfaces[1]]++) continue;  // the first ray per bubble: f = 0, glass direction +z
        const RaySensitivity k = ad.sensitivity(vr.origin, vr.direction);
        const double td = tol::closed_form_path(4, 1.0, k.kappa_dir);
        expect_vec_near(p.directions[0], {0, 0, 1}, td, "aimed along +z");
        expect_vec_near(p.directions[1], p.directions[0], td, p.surfaces[1]);
        expect_vec_near(p.directions[2], p.directions[0], td, p.surfaces[1]);
        EXPECT_EQ(p.surfaces[2], p.surfaces[1]);
    }
    EXPECT_EQ(seen.size(), 3u);
}

// A rotated ellipsoidal bubble crossed along one of its body axes through its centre: hits at
// c -+ s_i f_i, normal incidence, undeviated (a ray built inside the glass).
TEST(AnalyticPaths, EllipsoidAxisUndeviated) {
    const Scene s = example("examples/ellipsoid-bubble.yaml");
    const AnalyticScene as(s);
    const Defect& b = s.defects[0];
    const double sa[3] = {b.semi_axes.x, b.semi_axes.y, b.semi_axes.z};
    for (int i = 0; i < 3; ++i) {
        const Vec3 f = b.frame.column(i);
        const Vec3 o = b.center - f * 0.5;
        ASSERT_EQ(as.medium_at(o).kind, MediumKind::Glass);
        const Path p = as.principal_path(o, f, validation::Medium{MediumKind::Glass, -1});
        ASSERT_GE(p.surfaces.size(), 3u);
        EXPECT_EQ(p.surfaces[0], "bubble 0");
        EXPECT_EQ(p.surfaces[1], "bubble 0");
        const double tp = tol::closed_form_path(2, as.length_scale(), 1.0);
        expect_vec_near(p.vertices[0], b.center - f * sa[i], tp, "entry");
        expect_vec_near(p.vertices[1], b.center + f * sa[i], tp, "exit");
        expect_vec_near(p.directions[0], f, tol::closed_form_path(1, 1.0, 1.0), "inside");
        expect_vec_near(p.directions[1], f, tol::closed_form_path(2, 1.0, 1.0), "after");
    }
}

// Total internal reflection in a window: a ray entering through the polished rim travels inside
// at less than the critical angle from the horizontal and meets the faces beyond it (n > sqrt 2):
// reflected as by a mirror (z flipped: the faces' normal is z), with no loss. And one built
// inside the glass, meeting the back face at 60 degrees (> asin(1/n) = 41.3 degrees).
TEST(AnalyticPaths, WindowTotalInternalReflection) {
    const double t = 3.0, n = 1.5168;
    const Scene s = window_scene(t, 20, n);
    const AnalyticScene as(s);
    const double a = 10.0;
    const double be = 40 * kDeg;
    const Vec3 target{a, 0.0, 0.2};
    const Vec3 d{-std::cos(be), 0.0, std::sin(be)};
    const Path p = as.principal_path(target - d * 3.0, d);
    ASSERT_GE(p.vertices.size(), 3u);
    EXPECT_EQ(p.surfaces[0], "rim");
    EXPECT_GE(p.tir_count, 1);
    int checked = 0;
    for (size_t k = 1; k < p.vertices.size(); ++k) {
        if (p.events[k] != Event::TotalInternalReflection) continue;
        const Vec3 in = p.directions[k - 1], out = p.directions[k];
        expect_vec_near(out, {in.x, in.y, -in.z}, tol::optics_identity(), "mirror");
        EXPECT_TRUE(p.surfaces[k] == "front" || p.surfaces[k] == "back");
        EXPECT_NEAR(std::fabs(p.vertices[k].z), 0.5 * t, tol::closed_form_path(int(k), as.length_scale(), 0));
        ++checked;
    }
    EXPECT_EQ(checked, p.tir_count);
    // TIR costs nothing: the transmission is the product over the two rim crossings only.
    double prod = 1;
    for (size_t k = 0; k < p.vertices.size(); ++k)
        if (p.events[k] == Event::Transmitted) {
            const Vec3 in = k ? p.directions[k - 1] : d;
            const Vec3 N = normalize(Vec3{p.vertices[k].x, p.vertices[k].y, 0});
            const bool entering = k == 0;
            prod *= 1 - fresnel(entering ? 1.0 : n, entering ? n : 1.0, std::fabs(dot(in, N))).R;
        }
    EXPECT_NEAR(p.transmission, prod, tol::optics_identity());

    // Built inside: from (0, 0, 0) at 60 degrees from +z toward +x.
    const Vec3 d2{std::sin(60 * kDeg), 0.0, std::cos(60 * kDeg)};
    const Path q = as.principal_path({0, 0, 0}, d2, validation::Medium{MediumKind::Glass, -1});
    ASSERT_GE(q.vertices.size(), 2u);
    EXPECT_EQ(q.surfaces[0], "back");
    EXPECT_EQ(q.events[0], Event::TotalInternalReflection);
    expect_vec_near(q.directions[0], {d2.x, d2.y, -d2.z}, tol::optics_identity(), "mirror");
}

// Absorbers end the path: a particle, and an absorbing rim.
TEST(AnalyticPaths, AbsorbersEndThePath) {
    const Scene s = example("examples/particle.yaml");
    const AnalyticScene as(s);
    int found = 0;
    for (const ValidationRay& r : validation_rays(s, 1)) {
        if (r.category != "particle") continue;
        const Path p = as.principal_path(r.origin, r.direction);
        EXPECT_TRUE(p.absorbed);
        EXPECT_FALSE(p.display_hit);
        EXPECT_EQ(p.surfaces.back().rfind("particle ", 0), 0u);
        // With probability `transmission` the path is the principal one and ends absorbed.
        EXPECT_LE(as.expected_display_throughput(r.origin, r.direction), 1.0 - p.transmission + tol::throughput_series());
        ++found;
    }
    EXPECT_GT(found, 0);
    const Scene w = window_scene(3, 20, 1.5, "", "absorbing");
    const AnalyticScene aw(w);
    const Path p = aw.principal_path({9.0, 0, -3}, {std::sin(30 * kDeg), 0, std::cos(30 * kDeg)});
    EXPECT_TRUE(p.absorbed);
    EXPECT_EQ(p.surfaces, (std::vector<std::string>{"front", "rim"}));
}

// Reversibility (Helmholtz): tracing the final ray backwards retraces the same vertices in
// reverse order and leaves along the reversed initial direction, for every stable validation ray
// that reaches the display plane. (Beyond the original origin the reversed ray may meet the object
// again, e.g. in the dish of a concave face: only the first n vertices are compared.) The bound is
// the validation tolerance itself: two independent computations of the same exact path.
TEST(AnalyticPaths, ReversedPathRetracesVertices) {
    for (const char* name : {"default.yaml", "examples/biconcave.yaml", "examples/negative-meniscus.yaml",
                             "examples/ellipsoid-bubble.yaml", "examples/plano-convex.yaml"}) {
        const Scene s = example(name);
        const AnalyticScene as(s);
        int checked = 0;
        for (const ValidationRay& r : validation_rays(s, 1)) {
            const Path p = as.principal_path(r.origin, r.direction);
            if (!p.display_hit || p.vertices.empty()) continue;
            const RaySensitivity k = as.sensitivity(r.origin, r.direction);
            if (!k.stable) continue;
            const Vec3 start = p.vertices.back() + p.direction * 5.0;
            const Path q = as.principal_path(start, -p.direction);
            const RaySensitivity kq = as.sensitivity(start, -p.direction);
            const size_t n = p.vertices.size();
            ASSERT_GE(q.vertices.size(), n) << name << " " << r.category;
            const double tol =
                position_tolerance(int(n), as.length_scale(), std::max(k.kappa, kq.kappa));
            for (size_t i = 0; i < n; ++i) {
                EXPECT_EQ(q.surfaces[i], p.surfaces[n - 1 - i]);
                expect_vec_near(q.vertices[i], p.vertices[n - 1 - i], tol, r.category);
            }
            expect_vec_near(q.directions[n - 1], -r.direction,
                            direction_tolerance(int(n), std::max(k.kappa_dir, kq.kappa_dir)), r.category);
            ++checked;
        }
        EXPECT_GT(checked, 100) << name;
    }
}

// ---- expected throughput ------------------------------------------------------------------------

// Normal incidence through a window: the light reaching the display is the sum over 2k internal
// reflections, T R^2k T, i.e. T^2 / (1 - R^2) with R = ((n - 1)/(n + 1))^2, T = 1 - R (incoherent
// multiple reflections between parallel interfaces; Born & Wolf, Principles of Optics, Sec. 7.6.1,
// with intensities added instead of amplitudes). All the internal reflections stay on the axis.
TEST(AnalyticThroughput, WindowNormalIncidenceSeries) {
    for (double n : {1.5, 1.5168}) {
        const Scene s = window_scene(5, 30, n);
        const AnalyticScene as(s);
        const double R = std::pow((n - 1) / (n + 1), 2), T = 1 - R;
        double dropped = 0;
        const double v = as.expected_display_throughput({0, 0, -4}, {0, 0, 1}, 64, 1e-14, &dropped);
        EXPECT_NEAR(v, T * T / (1 - R * R), tol::throughput_series()) << n;
        EXPECT_LE(dropped, tol::throughput_series());
        // An off-axis normal ray too (all reflections stay on its line).
        const double v2 = as.expected_display_throughput({3, -2, -4}, {0, 0, 1}, 64, 1e-14, &dropped);
        EXPECT_NEAR(v2, T * T / (1 - R * R), tol::throughput_series()) << n;
    }
}

// The default scene's axis ray crosses four interfaces at normal incidence (front, the centred
// bubble twice, back), every reflection staying on the axis. Incoherent stacks compose exactly:
// two symmetric elements (R_a, T_a), (R_b, T_b) in series transmit T_a T_b / (1 - R_a R_b) and
// reflect R_a + T_a^2 R_b / (1 - R_a R_b) (the geometric series of the bounces between them; the
// result is again symmetric when the stack is). Four identical interfaces = (pair)(pair).
TEST(AnalyticThroughput, FourInterfaceStackOnAxis) {
    const Scene s = example("default.yaml");
    const AnalyticScene as(s);
    const double n = s.object.lens.ior, R = std::pow((n - 1) / (n + 1), 2), T = 1 - R;
    const double Tp = T * T / (1 - R * R), Rp = R + T * T * R / (1 - R * R);
    const double T4 = Tp * Tp / (1 - Rp * Rp);
    // With the default cutoff the many light branches dropped here add up to ~2e-11: the exact
    // value must lie in [v, v + dropped]. With a cutoff 1e-18 the sum is within 1e-12.
    double dropped = 1;
    const double v = as.expected_display_throughput({0, 0, -4}, {0, 0, 1}, 64, 1e-14, &dropped);
    EXPECT_LE(v, T4 + tol::throughput_series());
    EXPECT_GE(v + dropped, T4 - tol::throughput_series());
    const double v18 = as.expected_display_throughput({0, 0, -4}, {0, 0, 1}, 64, 1e-18, &dropped);
    EXPECT_NEAR(v18, T4, tol::throughput_series());
    EXPECT_LE(dropped, tol::throughput_series());
    // The principal path is the one with no reflection at all: probability T^4.
    EXPECT_NEAR(as.principal_path({0, 0, -4}, {0, 0, 1}).transmission, T * T * T * T, tol::optics_identity());
}

// Oblique incidence: in the solver's model each interface reflects the unpolarised fraction R
// (Stokes: the same R at theta outside and at theta' inside), so the series is again
// T^2 / (1 - R^2) with R = R(theta); the wide window keeps every internal reflection inside.
TEST(AnalyticThroughput, WindowObliqueSeries) {
    const double n = 1.5168, t = 1.0;
    const Scene s = window_scene(t, 80, n, "display: {z: 60, size: [400, 400]}\n");
    const AnalyticScene as(s);
    for (double th_deg : {10.0, 30.0, 60.0}) {
        const double th = th_deg * kDeg;
        const double R = fresnel(1.0, n, std::cos(th)).R, T = 1 - R;
        const double Rin = fresnel(n, 1.0, std::cos(std::asin(std::sin(th) / n))).R;
        EXPECT_NEAR(R, Rin, tol::optics_identity());
        double dropped = 0;
        const Vec3 d{std::sin(th), 0, std::cos(th)};
        const double v = as.expected_display_throughput(Vec3{0, 0, -0.5 * t} - d * 1.0, d, 64, 1e-14, &dropped);
        EXPECT_NEAR(v, T * T / (1 - R * R), tol::throughput_series()) << th_deg;
        EXPECT_LE(dropped, tol::throughput_series());
    }
}

// ---- validation rays -----------------------------------------------------------------------------

TEST(ValidationRays, Categories) {
    const Scene s = example("default.yaml");
    const AnalyticScene as(s);
    const auto rays = validation_rays(s, 1);
    std::map<std::string, int> count;
    for (const ValidationRay& r : rays) {
        ++count[r.category];
        EXPECT_NEAR(length(r.direction), 1.0, tol::optics_identity());
        EXPECT_EQ(as.medium_at(r.origin).kind, MediumKind::Air) << r.category;
        if (r.category != "grazing" && r.category != "tir") {
            EXPECT_LT(r.origin.z, as.z_min());
        }
    }
    for (const char* c : {"axial", "tilted", "near-rim", "grazing", "bubble", "tir"})
        EXPECT_GE(count[c], 4) << c;
    EXPECT_EQ(count["particle"], 0);
    EXPECT_GE(rays.size(), 150u);
    EXPECT_LE(rays.size(), 300u);
    const auto plain = validation_rays(lens_scene("50", "-50", 6, 25, 1.5168), 1);  // no bubbles
    EXPECT_GE(plain.size(), 150u);
    EXPECT_LE(plain.size(), 300u);
    // The exact axis ray, and rho = a - 1e-6 a.
    bool axis = false, rim = false;
    for (const ValidationRay& r : rays) {
        if (r.origin.x == 0 && r.origin.y == 0 && r.direction == Vec3{0, 0, 1}) axis = true;
        if (r.category == "near-rim" && r.origin.x == 12.5 - 1e-6 * 12.5) rim = true;
    }
    EXPECT_TRUE(axis);
    EXPECT_TRUE(rim);
    // ~linear in density.
    const auto rays2 = validation_rays(s, 2);
    const double ratio = double(rays2.size()) / rays.size();
    EXPECT_GT(ratio, 1.6);
    EXPECT_LT(ratio, 2.4);
    // Deterministic.
    const auto again = validation_rays(s, 1);
    ASSERT_EQ(again.size(), rays.size());
    for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(again[i].origin, rays[i].origin);
}

// The "tir" rays really undergo total internal reflection, in lens scenes with and without bubbles.
TEST(ValidationRays, TirRaysHaveTir) {
    std::vector<Scene> scenes{example("default.yaml"), lens_scene("50", "-50", 6, 25, 1.5168),
                              lens_scene("inf", "-30", 5, 20, 1.5), lens_scene("-40", "60", 3, 20, 1.6),
                              example("examples/ellipsoid-bubble.yaml"), window_scene(3, 20, 1.5)};
    for (const Scene& s : scenes) {
        const AnalyticScene as(s);
        int n = 0;
        for (const ValidationRay& r : validation_rays(s, 1)) {
            if (r.category != "tir") continue;
            EXPECT_GT(as.principal_path(r.origin, r.direction).tir_count, 0);
            ++n;
        }
        EXPECT_GE(n, 5);
    }
}

// Every category has finite tolerances for most of its rays (unstable rays are the exception).
TEST(ValidationRays, MostRaysAreStable) {
    const Scene s = example("default.yaml");
    const AnalyticScene as(s);
    std::map<std::string, int> total, stable;
    for (const ValidationRay& r : validation_rays(s, 1)) {
        const PathTolerance t = path_tolerance(as, r);
        ++total[r.category];
        if (t.stable) {
            ++stable[r.category];
            EXPECT_GT(t.position, 0.0);
            EXPECT_TRUE(std::isfinite(t.position));
        }
    }
    for (const auto& [c, n] : total) EXPECT_GE(stable[c], n / 2) << c;
}

// ---- supports ------------------------------------------------------------------------------------

TEST(AnalyticSupport, RejectsScratchesAndPits) {
    std::string why;
    EXPECT_FALSE(supports(example("examples/pit.yaml"), &why));
    EXPECT_NE(why.find("defects[0]"), std::string::npos) << why;
    EXPECT_NE(why.find("surface-breaking"), std::string::npos) << why;
    EXPECT_FALSE(supports(example("examples/scratch-v-front.yaml"), &why));
    EXPECT_NE(why.find("scratch"), std::string::npos) << why;
    EXPECT_FALSE(supports(example("examples/overlapping-defects.yaml"), &why));  // has a pit
    EXPECT_FALSE(supports(lens_scene("50", "-50", 6, 25, 1.5,
                                     "defects: [{type: bubble, center: [0, 0, 0], radius: 0.2},\n"
                                     "          {type: bubble, center: [0.25, 0, 0], radius: 0.15}]\n"),
                          &why));
    EXPECT_NE(why.find("defects[0] and defects[1] overlap"), std::string::npos) << why;
    EXPECT_THROW(AnalyticScene{example("examples/pit.yaml")}, std::invalid_argument);
    for (const char* ok : {"default.yaml", "examples/particle.yaml", "examples/ellipsoid-bubble.yaml",
                           "examples/window.yaml", "examples/biconcave.yaml"}) {
        EXPECT_TRUE(supports(example(ok), &why)) << ok << ": " << why;
        EXPECT_TRUE(why.empty());
    }
}
