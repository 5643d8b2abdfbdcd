// Ground truth by tracing (study/GroundTruth.h) against the geometric footprint where that
// footprint is exact: a window at normal incidence, seen through a vanishing aperture.
//
// Expected fractions. A camera path starts at a uniformly jittered point of its pixel's footprint
// (stratified) and runs parallel to the axis (NA = 1e-6: a tilt of 1e-6 rad, a lateral drift of
// < 1e-5 mm over the window, far below the pixel). At normal incidence nothing bends it:
//  - an enclosed defect (bubble, particle, uniform inclusion) of radius r at the focus plane is
//    met by exactly the paths whose start lies within its outline, the disk of radius r, and that
//    the front face transmits (probability 1 - R0, R0 = ((n - 1)/(n + 1))^2; the reflected ones
//    return to the camera; paths reflected at the back face return along their own line and
//    cannot meet a defect they missed). So p_k = (1 - R0) A_k / A_pixel.
//  - a scratch in the front face is met by every path whose start lies within the groove's
//    opening (a rectangle of the scratch's length and width): they hit a groove wall before
//    anything else. So p_k = A_k / A_pixel.
// A_k, the area of pixel k within the outline, is computed exactly (piecewise closed-form
// integrals of the disk's chord). The count of pixel k is a sum of independent Bernoulli trials
// (one per stratum) with mean p_k; such a sum is more concentrated than the binomial of the same
// mean (Hoeffding 1956), so the exact two-sided binomial test at alpha / pixels (Bonferroni) is a
// valid, conservative test of the counts and of the mask's threshold decisions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "study/GroundTruth.h"
#include "study/SceneRun.h"
#include "tests/SceneFixture.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

// The integral of sqrt(r^2 - x^2): (x sqrt(r^2 - x^2) + r^2 asin(x / r)) / 2.
double chord_primitive(double x, double r) {
    const double xc = std::clamp(x, -r, r);
    return 0.5 * (xc * std::sqrt(std::max(0.0, r * r - xc * xc)) + r * r * std::asin(xc / r));
}

// The area of the disk x^2 + y^2 < r^2 within [x0, x1] x [y0, y1], exactly: the integrand
// clamp(y1, -h, h) - clamp(y0, -h, h), h(x) = sqrt(r^2 - x^2), takes one closed form between the
// breakpoints where h = |y0| or h = |y1|.
double disk_rectangle_area(double r, double x0, double x1, double y0, double y1) {
    x0 = std::max(x0, -r);
    x1 = std::min(x1, r);
    if (x1 <= x0) return 0;
    std::vector<double> xs{x0, x1};
    for (double y : {y0, y1})
        if (std::fabs(y) < r) {
            const double b = std::sqrt(r * r - y * y);
            for (double x : {-b, b})
                if (x > x0 && x < x1) xs.push_back(x);
        }
    std::sort(xs.begin(), xs.end());
    double area = 0;
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
        const double a = xs[i], b = xs[i + 1], m = 0.5 * (a + b), h = std::sqrt(r * r - m * m);
        // Each clamp is a constant y, +h or -h on the whole piece; its integral in closed form.
        auto integral = [&](double y) {
            if (y >= h) return (chord_primitive(b, r) - chord_primitive(a, r));
            if (y <= -h) return -(chord_primitive(b, r) - chord_primitive(a, r));
            return y * (b - a);
        };
        area += integral(y1) - integral(y0);
    }
    return area;
}

// log of the binomial probability mass C(n, c) p^c (1 - p)^(n - c).
double log_pmf(int n, int c, double p) {
    if (p <= 0) return c == 0 ? 0.0 : -INFINITY;
    if (p >= 1) return c == n ? 0.0 : -INFINITY;
    return std::lgamma(n + 1.0) - std::lgamma(c + 1.0) - std::lgamma(n - c + 1.0) + c * std::log(p) +
           (n - c) * std::log1p(-p);
}

// P(X <= c) and P(X >= c) for X ~ Binomial(n, p).
double cdf_below(int n, int c, double p) {
    double s = 0;
    for (int i = 0; i <= c; ++i) s += std::exp(log_pmf(n, i, p));
    return std::min(1.0, s);
}
double cdf_above(int n, int c, double p) {
    double s = 0;
    for (int i = c; i <= n; ++i) s += std::exp(log_pmf(n, i, p));
    return std::min(1.0, s);
}

struct Footprint {
    // Pixel k's expected fraction of paths meeting the defect.
    std::function<double(long k)> p;
};

// For every pixel and every defect: the count passes the exact binomial test, and where the
// expected fraction is clearly (at the same level) above or below the mask threshold, the mask
// decides accordingly. Returns the number of pixels that had to be in the mask.
long check_against_footprints(const Scene& scene, const RenderResult& r, const GroundTruth& g,
                              const std::vector<Footprint>& expected) {
    const int n = scene.camera.samples_per_pixel;
    const long K = static_cast<long>(scene.camera.resolution[0]) * scene.camera.resolution[1];
    const double alpha = tol::kFamilyAlpha / static_cast<double>(K * static_cast<long>(expected.size()));
    const int threshold = static_cast<int>(std::ceil(g.min_fraction * n));  // count >= threshold: in the mask
    long sure_in = 0;
    const auto counts = dense_defect_paths(r, K, static_cast<int>(expected.size()));
    for (long k = 0; k < K; ++k)
        for (size_t j = 0; j < expected.size(); ++j) {
            const double p = expected[j].p(k);
            const int c = static_cast<int>(counts[static_cast<size_t>(k) * expected.size() + j]);
            const double tail = std::min(cdf_below(n, c, p), cdf_above(n, c, p));
            EXPECT_GT(2 * tail, alpha) << fmt::format("pixel {} defect {}: {} of {} paths met it, expected fraction {}",
                                                      k, j, c, n, p);
            const bool in = g.mask[static_cast<size_t>(k)] == j + 1;
            if (cdf_below(n, threshold - 1, p) < alpha) {  // almost surely >= threshold
                EXPECT_TRUE(in) << fmt::format("pixel {}: expected fraction {} is above {}", k, p, g.min_fraction);
                ++sure_in;
            }
            if (cdf_above(n, threshold, p) < alpha) {
                EXPECT_NE(g.mask[static_cast<size_t>(k)], j + 1)
                    << fmt::format("pixel {}: expected fraction {} is below {}", k, p, g.min_fraction);
            }
        }
    return sure_in;
}

// Pixel k's footprint [x0, x1] x [y0, y1] (mm) for the camera of the scene.
std::array<double, 4> pixel_box(const Scene& s, long k) {
    const int N = s.camera.resolution[0], M = s.camera.resolution[1];
    const double w = s.camera.size[0] / N, h = s.camera.size[1] / M;
    const long m = k / N, nn = k % N;
    const double x0 = -0.5 * s.camera.size[0] + nn * w, y1 = 0.5 * s.camera.size[1] - m * h;
    return {x0, x0 + w, y1 - h, y1};
}

SceneRun run(const test::Built& b) {
    SceneRunOptions o;
    o.representation = auto_representation(b.solid);
    o.threads = 2;
    return run_scene(b.scene, b.solid, o, nullptr);
}

}  // namespace

TEST(GroundTruth, DiskAreaIsExact) {
    // Whole disk, half disk, a quadrant, a box inside the disk, and one off it.
    EXPECT_NEAR(disk_rectangle_area(1, -2, 2, -2, 2), M_PI, tol::kDiskAreaAbs);
    EXPECT_NEAR(disk_rectangle_area(1, 0, 2, -2, 2), M_PI / 2, tol::kDiskAreaAbs);
    EXPECT_NEAR(disk_rectangle_area(1, 0, 2, 0, 2), M_PI / 4, tol::kDiskAreaAbs);
    EXPECT_NEAR(disk_rectangle_area(1, -0.5, 0.5, -0.5, 0.5), 1.0, tol::kDiskAreaAbs);
    EXPECT_EQ(disk_rectangle_area(1, 1.1, 2, -2, 2), 0.0);
    // The segment x > 1/2: r^2 acos(d / r) - d sqrt(r^2 - d^2).
    EXPECT_NEAR(disk_rectangle_area(1, 0.5, 2, -2, 2), std::acos(0.5) - 0.5 * std::sqrt(0.75), tol::kDiskAreaAbs);
}

TEST(GroundTruth, EnclosedDefectsInAWindowAtNormalIncidenceMatchTheirDisks) {
    const test::Built b = test::build(R"(
object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [-1.37, 0.91, 0.0], radius: 0.6}
  - {type: particle, center: [1.12, 1.03, 0.0], radius: 0.45}
  - {type: inhomogeneity, center: [0.21, -1.33, 0.0], radius: 0.55, delta_n: 0.02, profile: uniform}
camera: {resolution: [24, 24], size: [6.0, 6.0], numerical_aperture: 0.000001, samples_per_pixel: 256}
display: {resolution: [50, 50], size: [100.0, 100.0], z: 60.0}
seed: 3
)");
    const SceneRun s = run(b);
    const GroundTruth g = ground_truth(b.scene, s.render);
    const double n = 1.5168, R0 = (n - 1) * (n - 1) / ((n + 1) * (n + 1));
    std::vector<Footprint> expected;
    for (const Defect& d : b.scene.defects) {
        const double r = d.semi_axes.x;
        expected.push_back({[&, d, r](long k) {
            const auto q = pixel_box(b.scene, k);
            const double area = (q[1] - q[0]) * (q[3] - q[2]);
            return (1 - R0) * disk_rectangle_area(r, q[0] - d.center.x, q[1] - d.center.x, q[2] - d.center.y,
                                                   q[3] - d.center.y) / area;
        }});
    }
    const long sure = check_against_footprints(b.scene, s.render, g, expected);
    EXPECT_GT(sure, 3 * 12);  // each disk holds about (pi r^2 / 0.0625) ~ 10..18 whole pixels
    for (const DefectLabel& L : g.defects) {
        EXPECT_GT(L.pixel_area, 0);
        EXPECT_EQ(L.visibility, 1.0);  // nothing overlaps
        // The summed fractions estimate (1 - R0) pi r^2 / A_pixel; its standard error is below
        // sqrt(perimeter pixels / n) ~ 0.2 pixels, so 1 pixel is > 5 sigma.
        const Defect& d = b.scene.defects[static_cast<size_t>(L.id - 1)];
        EXPECT_NEAR(L.path_pixels, (1 - R0) * M_PI * d.semi_axes.x * d.semi_axes.x / 0.0625, tol::kFootprintPixels);
    }
    // bbox and area agree with the mask.
    for (const DefectLabel& L : g.defects) {
        long area = 0;
        for (long k = 0; k < 24 * 24; ++k)
            if (g.mask[static_cast<size_t>(k)] == L.id) {
                ++area;
                const int x = static_cast<int>(k % 24), y = static_cast<int>(k / 24);
                EXPECT_GE(x, L.bbox[0]);
                EXPECT_LT(x, L.bbox[0] + L.bbox[2]);
                EXPECT_GE(y, L.bbox[1]);
                EXPECT_LT(y, L.bbox[1] + L.bbox[3]);
            }
        EXPECT_EQ(area, L.pixel_area);
    }
}

TEST(GroundTruth, AScratchInAWindowMatchesItsOpening) {
    const test::Built b = test::build(R"(
object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: scratch, surface: front, start: [-2.03, 0.51], end: [1.71, 0.51], width: 0.4, depth: 0.05, profile: V}
camera: {resolution: [24, 24], size: [6.0, 6.0], numerical_aperture: 0.000001, samples_per_pixel: 256}
display: {resolution: [50, 50], size: [100.0, 100.0], z: 60.0}
seed: 4
)");
    ASSERT_EQ(auto_representation(b.solid), Representation::Refined);  // the scratch cuts the face
    const SceneRun s = run(b);
    const GroundTruth g = ground_truth(b.scene, s.render);
    const std::vector<Footprint> expected{{[&](long k) {
        const auto q = pixel_box(b.scene, k);
        const double w = std::max(0.0, std::min(q[1], 1.71) - std::max(q[0], -2.03));
        const double h = std::max(0.0, std::min(q[3], 0.71) - std::max(q[2], 0.31));
        return w * h / ((q[1] - q[0]) * (q[3] - q[2]));
    }}};
    const long sure = check_against_footprints(b.scene, s.render, g, expected);
    // The opening covers rows 9 (y 0.5..0.75) and 10 (0.25..0.5) by 0.84 and 0.76 of a pixel,
    // columns 4..17 wholly and 18 (x 1.5..1.75) by 0.84, column 3 by 0.12: 30 pixels far above
    // the threshold, no other far from below it.
    EXPECT_EQ(sure, 30);
    EXPECT_EQ(g.defects[0].pixel_area, 30);
    EXPECT_EQ(g.defects[0].bbox, (std::array<int, 4>{4, 9, 15, 2}));
}

TEST(GroundTruth, OverlappingImagesGoToTheDefectMostPathsMeet) {
    // Two bubbles whose outlines overlap, the second nearer the camera: a pixel both claim goes to
    // the one more of its paths meet, and the other loses visibility for it.
    const test::Built b = test::build(R"(
object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5168}
defects:
  - {type: bubble, center: [0.0, 0.0, 0.7], radius: 0.6}
  - {type: bubble, center: [0.3, 0.0, -0.7], radius: 0.4}
camera: {resolution: [24, 24], size: [6.0, 6.0], numerical_aperture: 0.000001, samples_per_pixel: 64}
display: {resolution: [50, 50], size: [100.0, 100.0], z: 60.0}
seed: 5
)");
    const SceneRun s = run(b);
    const GroundTruth g = ground_truth(b.scene, s.render);
    const std::uint32_t t = 16;  // 0.25 of 64 paths
    long contested[2] = {0, 0};  // pixels both claim, by the defect that lost them
    const auto counts = dense_defect_paths(s.render, 24 * 24, 2);
    for (long k = 0; k < 24 * 24; ++k) {
        const std::uint32_t c0 = counts[static_cast<size_t>(2 * k)];
        const std::uint32_t c1 = counts[static_cast<size_t>(2 * k + 1)];
        const int v = g.mask[static_cast<size_t>(k)];
        const int expect = (c0 >= t || c1 >= t) ? (c1 > c0 ? 2 : 1) : 0;
        EXPECT_EQ(v, expect) << "pixel " << k << ": counts " << c0 << ", " << c1;
        if (c0 >= t && c1 >= t) ++contested[c1 > c0 ? 0 : 1];
    }
    EXPECT_GT(contested[0] + contested[1], 0);  // the outlines overlap by several pixels
    for (int j = 0; j < 2; ++j) {
        const DefectLabel& L = g.defects[static_cast<size_t>(j)];
        EXPECT_EQ(L.footprint - L.pixel_area, contested[j]);
        EXPECT_EQ(L.visibility, static_cast<double>(L.pixel_area) / static_cast<double>(L.footprint));
    }
    EXPECT_THROW(ground_truth(b.scene, s.render, 0.0), std::invalid_argument);
    EXPECT_THROW(ground_truth(b.scene, RenderResult{}), std::invalid_argument);
}
