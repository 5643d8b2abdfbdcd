#include "defects/Sampling.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <random>
#include <stdexcept>

namespace ltm {

namespace {
// A double uniform in [0, 1) from the top 53 bits.
double uniform01(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }
}  // namespace

std::vector<Defect> sample_bubbles(const Lens& lens, const BubblePopulation& p) {
    std::mt19937_64 g(p.seed);
    const double a = lens.aperture_radius();
    const double zlo = std::fmin(lens.z_front(0), lens.z_front(a)), zhi = std::fmax(lens.z_back(0), lens.z_back(a));
    std::vector<Defect> out;
    out.reserve(static_cast<size_t>(p.count));
    for (int i = 0; i < p.count; ++i) {
        // The radius is drawn once: redrawing it with a rejected position would favour the sizes
        // that fit more easily.
        const double r = p.min_radius + (p.max_radius - p.min_radius) * uniform01(g);
        bool placed = false;
        for (int attempt = 0; attempt < 1000 && !placed; ++attempt) {
            const double x = a * (2 * uniform01(g) - 1), y = a * (2 * uniform01(g) - 1);
            const double z = zlo + (zhi - zlo) * uniform01(g);
            const Vec3 c{x, y, z};
            if (lens.signed_distance(c) - r <= p.min_clearance) continue;
            bool clash = false;
            for (const auto& o : out)
                clash = clash || distance(o.center, c) <= o.semi_axes.x + r + p.min_clearance;
            if (clash) continue;
            Defect d;
            d.type = DefectType::Bubble;
            d.center = c;
            d.semi_axes = {r, r, r};
            out.push_back(d);
            placed = true;
        }
        if (!placed)
            throw std::runtime_error(
                fmt::format("could not place bubble {} of {} (radius {}) after 1000 positions", i + 1, p.count, r));
    }
    return out;
}

Vec3 uniform_point_in_glass(const Lens& lens, const Uniform01& u, int max_tries) {
    const double a = lens.aperture_radius();
    const double zlo = std::fmin(lens.z_front(0), lens.z_front(a)), zhi = std::fmax(lens.z_back(0), lens.z_back(a));
    for (int i = 0; i < max_tries; ++i) {
        const double x = a * (2 * u() - 1), y = a * (2 * u() - 1), z = zlo + (zhi - zlo) * u();
        const Vec3 c{x, y, z};
        if (lens.signed_distance(c) > 0) return c;
    }
    throw std::runtime_error(fmt::format("no point inside the glass after {} tries", max_tries));
}

FacePoint uniform_point_on_face(const Lens& lens, int side, const Uniform01& u) {
    const double a = lens.aperture_radius();
    const double R = side == 0 ? lens.spec().r1 : lens.spec().r2;
    const double w = u(), phi = 2 * kPi * u();
    double rho;
    if (std::isinf(R)) {
        rho = a * std::sqrt(w);
    } else {
        const double h = std::fabs(sphere_sag(R, a)), r = std::fabs(R);
        const double height = w * h;
        rho = std::min(a, std::sqrt(std::max(0.0, height * (2 * r - height))));
    }
    const double x = rho * std::cos(phi), y = rho * std::sin(phi);
    const double z = side == 0 ? lens.z_front(rho) : lens.z_back(rho);
    FacePoint fp;
    fp.point = {x, y, z};
    // A flat face's inward normal is +z (front) or -z (back). A spherical face's centre of
    // curvature c lies at vertex + R on the axis; the inward normal is sgn(R) (c - p) / |R| on the
    // front face (toward c for a convex face, away for a concave one) and -sgn(R) (c - p) / |R| on
    // the back face.
    const double side_sign = side == 0 ? 1.0 : -1.0;
    if (std::isinf(R)) {
        fp.inward = {0, 0, side_sign};
    } else {
        const Vec3 centre{0, 0, (side == 0 ? lens.z_front(0) : lens.z_back(0)) + R};
        fp.inward = normalize(centre - fp.point) * (side_sign * (R > 0 ? 1.0 : -1.0));
    }
    return fp;
}

Vec3 euler_deg_from_rotation(const Mat3& R) {
    auto at = [&](int r, int c) { return R.m[static_cast<size_t>(3 * r + c)]; };
    const double s = std::clamp(-at(2, 0), -1.0, 1.0);
    const double b = std::asin(s);
    double a, c;
    if (std::fabs(s) < 1.0 - 1e-12) {
        a = std::atan2(at(2, 1), at(2, 2));
        c = std::atan2(at(1, 0), at(0, 0));
    } else {  // gimbal lock: only a - c (b = +90) or a + c (b = -90) is defined
        a = 0;
        c = std::atan2(-at(0, 1), at(1, 1));
    }
    const double d = 180.0 / kPi;
    return {a * d, b * d, c * d};
}

Vec3 uniform_rotation_euler_deg(const Uniform01& u) {
    const double u1 = u(), u2 = u(), u3 = u();
    const double s1 = std::sqrt(1 - u1), s2 = std::sqrt(u1);
    const double t1 = 2 * kPi * u2, t2 = 2 * kPi * u3;
    const double x = s1 * std::sin(t1), y = s1 * std::cos(t1), z = s2 * std::sin(t2), w = s2 * std::cos(t2);
    Mat3 R;
    R.m = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
           2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
           2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
    return euler_deg_from_rotation(R);
}

}  // namespace ltm
