#pragma once
// The test object as an analytic solid: a spherical lens of any sign combination, bounded by a
// cylindrical rim. A flat window is the lens with r1 = r2 = inf.
//
// Conventions (docs/conventions.md): millimetres; the optical axis is +z, camera at -z; the
// front vertex is at z = -t/2 and the back vertex at z = +t/2. Radii follow the optics sign
// convention: R > 0 puts the centre of curvature at +z of the vertex. A double-convex lens has
// r1 > 0, r2 < 0; R = inf is a flat face.
//
// Surface equations, with rho = sqrt(x^2 + y^2) <= a = diameter / 2 and the sag of a sphere
//   sag(R, rho) = rho^2 / (R (1 + sqrt(1 - rho^2 / R^2)))      (the stable form of R - sgn(R) sqrt(R^2 - rho^2))
// front:  z = -t/2 + sag(r1, rho)      back:  z = +t/2 + sag(r2, rho)      rim:  rho = a.
#include <string>
#include <vector>

#include "geometry/Surface.h"

namespace ltm {

struct LensSpec {
    double r1 = INFINITY;
    double r2 = INFINITY;
    double center_thickness = 1.0;
    double diameter = 10.0;
    double ior = 1.5;
    // A ball (object type sphere): r1 = R, r2 = -R, t = D = 2 R. It is the lens whose edge
    // thickness is exactly zero: the caps are the two hemispheres, meeting at the equator z = 0,
    // and the rim has no height. Only a ball may have a zero edge thickness.
    bool ball = false;
};

// The spec of a ball of radius R centred at the origin.
LensSpec ball_spec(double radius, double ior);

// The analytic sag of a sphere of signed radius R at radial distance rho (0 for R = inf).
double sphere_sag(double R, double rho);
// The volume between the vertex tangent plane and the surface over the disc rho <= a:
// integral of sag(R, rho) 2 pi rho d rho = sgn(R) (pi a^2 h - pi h^2 (3|R| - h) / 3),
// h = |sag(R, a)| (the cylinder over the disc minus the spherical cap of height h).
double sag_volume(double R, double a);
// Area of the spherical cap over rho <= a: 2 pi |R| h (Archimedes), h = |sag(R, a)|.
double cap_area(double R, double a);

class Lens {
public:
    // Precondition: the spec is valid (see `problems`); throws std::invalid_argument otherwise.
    explicit Lens(const LensSpec& spec);

    // Every reason the spec is not a valid solid, as (key, message) pairs, in key order.
    struct Problem {
        std::string key, message;
    };
    static std::vector<Problem> problems(const LensSpec& spec);

    const LensSpec& spec() const { return spec_; }
    double aperture_radius() const { return 0.5 * spec_.diameter; }
    double z_front(double rho) const;
    double z_back(double rho) const;
    double edge_thickness() const;
    // Both faces convex or flat (r1 > 0 or inf, r2 < 0 or inf): the solid (two balls or
    // half-spaces and the rim's cylinder, intersected) is a convex body.
    bool is_convex() const;

    // Analytic surfaces. The front sphere/plane's reference normal is flipped where needed so
    // that the table entry's normal_sign can say how it relates to the outward normal.
    Surface front_surface() const;
    Surface back_surface() const;
    Surface rim_surface() const;
    // +1 if the front/back surface's reference normal points out of the glass, else -1.
    int front_normal_sign() const;
    int back_normal_sign() const;

    double volume() const;
    double front_area() const;
    double back_area() const;
    double rim_area() const;

    bool contains(const Vec3& p) const;
    // Signed distance to the glass boundary (exact, by patch): positive inside the glass.
    double signed_distance(const Vec3& p) const;
    // Distance from p to each bounding patch (front, back, rim), exact.
    double distance_to_front(const Vec3& p) const;
    double distance_to_back(const Vec3& p) const;
    double distance_to_rim(const Vec3& p) const;
    // The largest distance from p to any point of the solid, exact: the ball of that radius about
    // p is the smallest one centred there that holds the whole object.
    double farthest_distance(const Vec3& p) const;

    // The point of the front (side = 0) or back (side = 1) surface above (x, y).
    Vec3 surface_point(int side, double x, double y) const;
    // Outward (out of the glass) unit normal of that surface at its point above (x, y).
    Vec3 surface_outward_normal(int side, double x, double y) const;

private:
    double distance_to_cap(const Vec3& p, double R, double z_vertex, double z_edge) const;
    double farthest_on_cap(const Vec3& p, double R, double z_vertex, double z_edge) const;
    LensSpec spec_;
};

}  // namespace ltm
