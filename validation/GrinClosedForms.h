#pragma once
// Closed-form light paths through graded-index glass: test targets for the GRIN reference solver
// (validation/GrinReference.h) and, through it, for the tracer. Each is derived from the ray
// equation in GrinClosedForms.cpp and shares no code with either solver.
//
// Notation: tau with d tau = ds / n, p = n dr/ds (|p| = n); the ray equation is
//   dr/dtau = p,   dp/dtau = grad(n^2) / 2.
// The windows are flat plates with the front face z = -t/2 and the back face z = +t/2 (wide
// enough that the paths below never reach the rim); the display is the plane z = display_z, as in
// the scenes (docs/conventions.md).
#include "geometry/Vec3.h"

namespace ltm::validation::grin_closed_form {

// Where a closed-form path enters and leaves the glass, and where it lands.
struct Exit {
    bool exits = false;        // reached the exit surface and was refracted out (false: total
                               // internal reflection there, or the path turns back before it)
    Vec3 entry, exit;          // the entry and exit vertices
    Vec3 entry_momentum;       // p just inside the entry
    Vec3 exit_momentum;        // p just inside the exit
    double tau = 0;            // tau from the entry to the exit
    Vec3 direction;            // unit direction in air after the exit (exits only)
    bool display_hit = false;  // the exit direction heads to +z and meets z = display_z beyond the exit
    double display_x = 0, display_y = 0;
};

// (a) The Luneburg sphere: a ball of radius R with n^2 = 2 - |x|^2 / R^2 (ior = sqrt 2, spherical_n2
// with g = 1 / (R sqrt 2)). The path entering at r0 (|r0| = R) with unit direction d0
// (r0 . d0 < 0):
//   r(tau) = r0 cos(tau / R) + R d0 sin(tau / R),   p(tau) = d0 cos(tau / R) - (r0 / R) sin(tau / R),
// leaving at tau = pi R / 2 through the point R d0 with the direction -r0 / R.
struct LuneburgPath {
    double R = 1;
    Vec3 r0, d0;
    Vec3 position(double tau) const;
    Vec3 momentum(double tau) const;
    double exit_tau() const;
};
Exit luneburg(double R, const Vec3& entry, const Vec3& d0, double display_z);

// (b) The GRIN rod: a window of thickness t with n^2 = n0^2 (1 - G^2 (x^2 + y^2)) (radial_n2). The
// ray from air with unit direction d (d.z > 0) enters at (x0, y0, -t/2); with omega = n0 G,
//   x(tau) = x0 cos(omega tau) + (p_x0 / omega) sin(omega tau)   (y likewise),
//   z(tau) = -t/2 + p_z tau,
// so x(z) is sinusoidal with period 2 pi p_z / omega; it leaves at tau = t / p_z.
struct RodPath {
    double omega = 0;
    Vec3 r0, p0;
    Vec3 position(double tau) const;
    Vec3 momentum(double tau) const;
};
Exit grin_rod(double n0, double G, double t, double x0, double y0, const Vec3& d, double display_z);

// (c) The linear gradient: a window with n^2 = n0^2 + b . x (linear_n2). The path is the parabola
//   r(tau) = r0 + p0 tau + b tau^2 / 4,   p(tau) = p0 + b tau / 2.
struct ParabolaPath {
    Vec3 r0, p0, b;
    Vec3 position(double tau) const;
    Vec3 momentum(double tau) const;
    // The first tau > 0 at which z(tau) = z1, or -1 if there is none (the path turns back first).
    double tau_to_plane(double z1) const;
};
Exit linear_n2_window(double n0, const Vec3& b, double t, double x0, double y0, const Vec3& d, double display_z);

// (d) The catenary: a window with n = n0 + k x (linear_n with the gradient (k, 0, 0), transverse to
// the optical axis). p_y and p_z are conserved; with beta = hypot(p_y, p_z) and sigma the distance
// travelled in the (y, z) plane, n cos(theta) = beta (theta: the ray's angle to that plane) and
//   x(sigma) = (beta / k) cosh(k (sigma - sigma0) / beta) - n0 / k.
Exit catenary_window(double n0, double k, double t, double x0, double y0, const Vec3& d, double display_z);

}  // namespace ltm::validation::grin_closed_form
