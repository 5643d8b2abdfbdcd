#include "geometry/Lens.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace ltm {

double sphere_sag(double R, double rho) {
    if (std::isinf(R)) return 0.0;
    const double u = rho / R;
    return rho * rho / (R * (1.0 + std::sqrt((1.0 - u) * (1.0 + u))));
}

double sag_volume(double R, double a) {
    if (std::isinf(R)) return 0.0;
    const double h = std::fabs(sphere_sag(R, a));
    const double v = kPi * a * a * h - kPi * h * h * (3.0 * std::fabs(R) - h) / 3.0;
    return std::copysign(v, R);
}

double cap_area(double R, double a) {
    if (std::isinf(R)) return kPi * a * a;
    return 2.0 * kPi * std::fabs(R) * std::fabs(sphere_sag(R, a));
}

LensSpec ball_spec(double radius, double ior) {
    LensSpec s;
    s.r1 = radius;
    s.r2 = -radius;
    s.center_thickness = 2.0 * radius;
    s.diameter = 2.0 * radius;
    s.ior = ior;
    s.ball = true;
    return s;
}

std::vector<Lens::Problem> Lens::problems(const LensSpec& s) {
    std::vector<Problem> out;
    if (s.ball) {
        // A ball is given by its radius alone (ball_spec); the lens keys are derived from it.
        if (!(s.r1 > 0) || !std::isfinite(s.r1))
            out.push_back({"radius", fmt::format("must be a positive finite length (got {})", s.r1)});
        else if (s.r2 != -s.r1 || s.center_thickness != 2.0 * s.r1 || s.diameter != 2.0 * s.r1)
            out.push_back({"radius", "a ball's radii, thickness and diameter must be those of ball_spec"});
        if (!(s.ior > 1.0) || !std::isfinite(s.ior))
            out.push_back({"ior", fmt::format("the glass's refractive index must be > 1 (got {})", s.ior)});
        return out;
    }
    const double a = 0.5 * s.diameter;
    auto bad_radius = [&](const char* key, double R) {
        if (std::isnan(R) || R == 0.0)
            out.push_back({key, fmt::format("radius must be non-zero or inf (got {})", R)});
        else if (!std::isinf(R) && std::fabs(R) < a)
            out.push_back({key, fmt::format("|{}| = {} mm is smaller than the semi-diameter {} mm: "
                                            "the spherical surface cannot span the aperture",
                                            key, std::fabs(R), a)});
    };
    if (!(s.diameter > 0) || !std::isfinite(s.diameter))
        out.push_back({"diameter", fmt::format("must be a positive finite length (got {})", s.diameter)});
    if (!(s.center_thickness > 0) || !std::isfinite(s.center_thickness))
        out.push_back({"center_thickness",
                       fmt::format("must be a positive finite length (got {})", s.center_thickness)});
    if (!(s.ior > 1.0) || !std::isfinite(s.ior))
        out.push_back({"ior", fmt::format("the glass's refractive index must be > 1 (got {})", s.ior)});
    if (s.diameter > 0) {
        bad_radius("r1", s.r1);
        bad_radius("r2", s.r2);
    }
    if (out.empty()) {
        const double te = s.center_thickness + sphere_sag(s.r2, a) - sphere_sag(s.r1, a);
        if (!(te > 0))
            out.push_back({"center_thickness",
                           fmt::format("edge thickness t + sag(r2) - sag(r1) = {:.6g} mm is not positive: "
                                       "the faces cross before the rim (increase center_thickness or "
                                       "reduce diameter)",
                                       te)});
    }
    return out;
}

Lens::Lens(const LensSpec& spec) : spec_(spec) {
    const auto p = problems(spec);
    if (!p.empty()) throw std::invalid_argument(p.front().key + ": " + p.front().message);
}

double Lens::z_front(double rho) const { return -0.5 * spec_.center_thickness + sphere_sag(spec_.r1, rho); }
double Lens::z_back(double rho) const { return 0.5 * spec_.center_thickness + sphere_sag(spec_.r2, rho); }
double Lens::edge_thickness() const {
    const double a = aperture_radius();
    return z_back(a) - z_front(a);
}

bool Lens::is_convex() const {
    return (std::isinf(spec_.r1) || spec_.r1 > 0) && (std::isinf(spec_.r2) || spec_.r2 < 0);
}

Surface Lens::front_surface() const {
    const double zv = -0.5 * spec_.center_thickness;
    if (std::isinf(spec_.r1)) return Surface::plane({0, 0, zv}, {0, 0, -1});
    return Surface::sphere({0, 0, zv + spec_.r1}, std::fabs(spec_.r1));
}
Surface Lens::back_surface() const {
    const double zv = 0.5 * spec_.center_thickness;
    if (std::isinf(spec_.r2)) return Surface::plane({0, 0, zv}, {0, 0, 1});
    return Surface::sphere({0, 0, zv + spec_.r2}, std::fabs(spec_.r2));
}
Surface Lens::rim_surface() const { return Surface::cylinder({0, 0, 0}, {0, 0, 1}, aperture_radius()); }

// Front: the glass lies inside the sphere when r1 > 0 (its centre is on the glass side), so the
// sphere's outward normal points out of the glass there. The plane's normal is -z = outward.
int Lens::front_normal_sign() const { return (std::isinf(spec_.r1) || spec_.r1 > 0) ? +1 : -1; }
int Lens::back_normal_sign() const { return (std::isinf(spec_.r2) || spec_.r2 < 0) ? +1 : -1; }

double Lens::volume() const {
    const double a = aperture_radius();
    return kPi * a * a * spec_.center_thickness + sag_volume(spec_.r2, a) - sag_volume(spec_.r1, a);
}
double Lens::front_area() const { return cap_area(spec_.r1, aperture_radius()); }
double Lens::back_area() const { return cap_area(spec_.r2, aperture_radius()); }
double Lens::rim_area() const { return 2.0 * kPi * aperture_radius() * edge_thickness(); }

bool Lens::contains(const Vec3& p) const {
    const double rho = std::hypot(p.x, p.y);
    return rho <= aperture_radius() && p.z >= z_front(rho) && p.z <= z_back(rho);
}

double Lens::distance_to_cap(const Vec3& p, double R, double z_vertex, double z_edge) const {
    const double a = aperture_radius();
    const double rho = std::hypot(p.x, p.y);
    const double to_edge = std::hypot(rho - a, p.z - z_edge);
    if (std::isinf(R)) return rho <= a ? std::fabs(p.z - z_vertex) : to_edge;
    // The closest point of the full sphere lies on the ray from the centre through p; it belongs to
    // the cap iff it is on the vertex's side of the centre and within the aperture.
    const Vec3 c{0, 0, z_vertex + R};
    const Vec3 d = p - c;
    const double l = length(d);
    if (l > 0) {
        const Vec3 q = c + d * (std::fabs(R) / l);
        const bool same_branch = (q.z - c.z) * (z_vertex - c.z) > 0;
        if (same_branch && std::hypot(q.x, q.y) <= a) return std::fabs(l - std::fabs(R));
    }
    return to_edge;
}

double Lens::distance_to_front(const Vec3& p) const {
    return distance_to_cap(p, spec_.r1, -0.5 * spec_.center_thickness, z_front(aperture_radius()));
}
double Lens::distance_to_back(const Vec3& p) const {
    return distance_to_cap(p, spec_.r2, 0.5 * spec_.center_thickness, z_back(aperture_radius()));
}
double Lens::distance_to_rim(const Vec3& p) const {
    const double a = aperture_radius();
    const double rho = std::hypot(p.x, p.y);
    const double z0 = z_front(a), z1 = z_back(a);
    if (p.z >= z0 && p.z <= z1) return std::fabs(rho - a);
    return std::hypot(rho - a, p.z < z0 ? p.z - z0 : p.z - z1);
}

// The farthest point of a cap (with its edge circle) from p. On the sphere |q - p|^2 =
// R^2 + |c - p|^2 + 2 (q - c) . (c - p) is affine in q, so its only local maximum on the sphere is
// the antipode of p's direction, q = c - (p - c) |R| / |p - c|: if that lies on the cap, it is the
// cap's farthest point (|p - c| + |R| away); else the maximum over the cap is on its boundary, the
// edge circle (rho = a, z = z_edge), whose farthest point from p is the one diametrically opposite
// p's azimuth, hypot(rho_p + a, z_p - z_edge) away. A flat cap (a disc) is a convex domain of the
// convex |q - p|^2, which takes its maximum on the boundary: the edge circle again.
double Lens::farthest_on_cap(const Vec3& p, double R, double z_vertex, double z_edge) const {
    const double a = aperture_radius();
    const double to_edge = std::hypot(std::hypot(p.x, p.y) + a, p.z - z_edge);
    if (std::isinf(R)) return to_edge;
    const Vec3 c{0, 0, z_vertex + R};
    const Vec3 d = p - c;
    const double l = length(d);
    if (l > 0) {
        const Vec3 q = c - d * (std::fabs(R) / l);
        const bool same_branch = (q.z - c.z) * (z_vertex - c.z) > 0;
        if (same_branch && std::hypot(q.x, q.y) <= a) return std::max(to_edge, l + std::fabs(R));
    }
    return to_edge;
}

// The solid's boundary is the two caps and the rim; over the rim (rho = a, z between the edge
// circles) the distance's horizontal part is largest opposite p's azimuth whatever z, and its
// vertical part, convex in z, is largest at an end: on an edge circle, which the caps include.
double Lens::farthest_distance(const Vec3& p) const {
    const double a = aperture_radius();
    return std::max(farthest_on_cap(p, spec_.r1, -0.5 * spec_.center_thickness, z_front(a)),
                    farthest_on_cap(p, spec_.r2, 0.5 * spec_.center_thickness, z_back(a)));
}

double Lens::signed_distance(const Vec3& p) const {
    const double d = std::fmin(distance_to_front(p), std::fmin(distance_to_back(p), distance_to_rim(p)));
    return contains(p) ? d : -d;
}

Vec3 Lens::surface_point(int side, double x, double y) const {
    const double rho = std::hypot(x, y);
    return {x, y, side == 0 ? z_front(rho) : z_back(rho)};
}

Vec3 Lens::surface_outward_normal(int side, double x, double y) const {
    const Vec3 p = surface_point(side, x, y);
    const Surface s = side == 0 ? front_surface() : back_surface();
    const int sign = side == 0 ? front_normal_sign() : back_normal_sign();
    return s.normal(p) * static_cast<double>(sign);
}

}  // namespace ltm
