// Closed-form GRIN paths (GrinClosedForms.h), each derived below from the ray equation
//   dr/dtau = p,  dp/dtau = grad(n^2) / 2      (d tau = ds / n, p = n dr/ds, |p| = n),
// which is d/ds (n dr/ds) = grad n (Born and Wolf, Principles of Optics, 7th ed., Sec. 3.2.1)
// rewritten with dr/dtau = n dr/ds = p and dp/dtau = n d/ds (n dr/ds) = n grad n = grad(n^2) / 2.
#include "validation/GrinClosedForms.h"

#include <cmath>

namespace ltm::validation::grin_closed_form {

namespace {

// The flat-face refraction in momentum form. The vector form of Snell's law,
// n1 d1 x N = n2 d2 x N, says that the tangential part of p = n d is the same on both sides of an
// interface; the normal part follows from |p| = n on the far side. For a face normal to z:
//   p2 = (p1_x, p1_y, +-sqrt(n2^2 - p1_x^2 - p1_y^2)),
// and there is no transmitted ray (total internal reflection) when p1_x^2 + p1_y^2 >= n2^2.
// Entering a window from air (n1 = 1, p1 = d): p0 = (d_x, d_y, sqrt(n^2 - d_x^2 - d_y^2)).
Vec3 enter_flat(const Vec3& d, double n2_glass) { return {d.x, d.y, std::sqrt(n2_glass - d.x * d.x - d.y * d.y)}; }

// Leaving through the back face z = t/2 into air (n2 = 1): d = (p_x, p_y, sqrt(1 - p_t^2)), with
// 1 - p_t^2 = (1 - p_t)(1 + p_t) (exact factors near grazing). Returns false under TIR.
bool leave_flat(const Vec3& p, Vec3& d) {
    const double pt = std::hypot(p.x, p.y);
    if (!(pt < 1.0)) return false;
    d = {p.x, p.y, std::sqrt((1.0 - pt) * (1.0 + pt))};
    return true;
}

// The straight line from the exit to the display plane z = Z: t = (Z - e.z) / d.z (d.z > 0).
void to_display(Exit& out, double display_z) {
    if (!out.exits || !(out.direction.z > 0.0)) return;
    const double t = (display_z - out.exit.z) / out.direction.z;
    if (!(t >= 0.0)) return;
    out.display_hit = true;
    out.display_x = out.exit.x + t * out.direction.x;
    out.display_y = out.exit.y + t * out.direction.y;
}

// sin(w tau) / w, continuous at w = 0 (the straight line's tau).
double sin_over(double w, double tau) { return w > 0 ? std::sin(w * tau) / w : tau; }

// sinh(x) / x, 1 at x = 0; for |x| < 1e-4 its series 1 + x^2 / 6 is exact to double precision
// (the next term x^4 / 120 < 1e-18).
double sinhc(double x) { return std::fabs(x) < 1e-4 ? 1.0 + x * x / 6.0 : std::sinh(x) / x; }

}  // namespace

// ---- (a) the Luneburg sphere -------------------------------------------------------------------------
//
// n^2 = 2 - |x|^2 / R^2, so grad(n^2) / 2 = -x / R^2 and the ray equation is the isotropic harmonic
// oscillator r'' = -w^2 r with w = 1 / R:
//   r(tau) = r0 cos(w tau) + (p0 / w) sin(w tau),  p(tau) = p0 cos(w tau) - r0 w sin(w tau).
// At the surface n = sqrt(2 - 1) = 1, the index of air: Snell's law with n1 = n2 leaves the ray
// unrefracted, so a ray entering at r0 (|r0| = R) with unit direction d0 has p0 = 1 x d0.
// Then |r(tau)|^2 = R^2 cos^2 + R^2 sin^2 + 2 R (r0 . d0) sin cos = R^2 + R (r0 . d0) sin(2 tau / R):
// for an entering ray (r0 . d0 < 0) it is below R^2 on 0 < tau < pi R / 2 and equals R^2 again at
// tau = pi R / 2, the exit, where r = R d0 and p = -r0 / R (|p| = 1 = n there). The exit point
// R d0 depends on the direction only: a parallel beam is focused onto the surface (Luneburg's
// lens). Leaving, n = 1 on both sides again: the ray goes on along -r0 / R.
Vec3 LuneburgPath::position(double tau) const { return r0 * std::cos(tau / R) + d0 * (R * std::sin(tau / R)); }
Vec3 LuneburgPath::momentum(double tau) const { return d0 * std::cos(tau / R) - r0 * (std::sin(tau / R) / R); }
double LuneburgPath::exit_tau() const { return 0.5 * kPi * R; }

Exit luneburg(double R, const Vec3& entry, const Vec3& d0, double display_z) {
    Exit out;
    out.entry = entry;
    out.entry_momentum = d0;
    out.tau = 0.5 * kPi * R;
    // The exit values in closed form (not cos(pi / 2) and sin(pi / 2) rounded).
    out.exit = d0 * R;
    out.exit_momentum = entry * (-1.0 / R);
    out.exits = true;
    out.direction = normalize(out.exit_momentum);
    to_display(out, display_z);
    return out;
}

// ---- (b) the GRIN rod -----------------------------------------------------------------------------------
//
// n^2 = n0^2 (1 - G^2 (x^2 + y^2)) = n0^2 - w^2 (x^2 + y^2) with w = n0 G, so
// grad(n^2) / 2 = -w^2 (x, y, 0): x'' = -w^2 x, y'' = -w^2 y, z'' = 0 in tau, exactly (no paraxial
// approximation):
//   x(tau) = x0 cos(w tau) + (p_x0 / w) sin(w tau),  p_x(tau) = p_x0 cos(w tau) - w x0 sin(w tau),
// y likewise, z(tau) = -t/2 + p_z tau with p_z constant. Hence x(z) = x0 cos(w (z + t/2) / p_z) + ...,
// sinusoidal with period 2 pi p_z / w. Entry from air through the face z = -t/2 (enter_flat) with
// n^2 at the entry point; exit at z = t/2, tau = t / p_z, into air (leave_flat). (Invariant:
// p_x^2 + w^2 x^2 is constant per axis, so |p|^2 + w^2 rho^2 = n0^2, i.e. |p| = n along the way.)
Vec3 RodPath::position(double tau) const {
    const double c = std::cos(omega * tau), s = sin_over(omega, tau);
    return {r0.x * c + p0.x * s, r0.y * c + p0.y * s, r0.z + p0.z * tau};
}
Vec3 RodPath::momentum(double tau) const {
    const double c = std::cos(omega * tau), s = std::sin(omega * tau);
    return {p0.x * c - omega * r0.x * s, p0.y * c - omega * r0.y * s, p0.z};
}

Exit grin_rod(double n0, double G, double t, double x0, double y0, const Vec3& d, double display_z) {
    Exit out;
    RodPath path;
    path.omega = n0 * std::fabs(G);
    path.r0 = {x0, y0, -0.5 * t};
    const double n2 = n0 * n0 * (1.0 - G * G * (x0 * x0 + y0 * y0));
    path.p0 = enter_flat(d, n2);
    out.entry = path.r0;
    out.entry_momentum = path.p0;
    out.tau = t / path.p0.z;
    out.exit = path.position(out.tau);
    out.exit.z = 0.5 * t;  // exactly on the face (z(tau) = -t/2 + p_z t / p_z up to rounding)
    out.exit_momentum = path.momentum(out.tau);
    out.exits = leave_flat(out.exit_momentum, out.direction);
    to_display(out, display_z);
    return out;
}

// ---- (c) the linear gradient --------------------------------------------------------------------------
//
// n^2 = n0^2 + b . x: grad(n^2) / 2 = b / 2 is constant, so p(tau) = p0 + b tau / 2 and
// r(tau) = r0 + p0 tau + b tau^2 / 4, a parabola. It meets the plane z = z1 where
//   (b_z / 4) tau^2 + p_z0 tau - (z1 - z0) = 0,
// solved in the stable form (Press et al., Numerical Recipes, 3rd ed., Sec. 5.6):
// with A = b_z / 4, B = p_z0, C = -(z1 - z0) and disc = B^2 - 4 A C,
//   q = -(B + sgn(B) sqrt(disc)) / 2,  roots q / A and C / q   (Vieta: product C / A),
// never subtracting numbers of equal sign; the first positive root is the crossing. A = 0 leaves
// the linear equation, tau = (z1 - z0) / B.
Vec3 ParabolaPath::position(double tau) const { return r0 + p0 * tau + b * (0.25 * tau * tau); }
Vec3 ParabolaPath::momentum(double tau) const { return p0 + b * (0.5 * tau); }
double ParabolaPath::tau_to_plane(double z1) const {
    const double A = 0.25 * b.z, B = p0.z, C = -(z1 - r0.z);
    if (A == 0.0) {
        const double tau = -C / B;
        return tau > 0 ? tau : -1.0;
    }
    const double disc = B * B - 4.0 * A * C;
    if (!(disc >= 0.0)) return -1.0;
    const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
    double best = -1.0;
    for (double tau : {q / A, q != 0.0 ? C / q : -1.0})
        if (tau > 0 && (best < 0 || tau < best)) best = tau;
    return best;
}

Exit linear_n2_window(double n0, const Vec3& b, double t, double x0, double y0, const Vec3& d, double display_z) {
    Exit out;
    ParabolaPath path;
    path.r0 = {x0, y0, -0.5 * t};
    path.b = b;
    path.p0 = enter_flat(d, n0 * n0 + dot(b, path.r0));
    out.entry = path.r0;
    out.entry_momentum = path.p0;
    out.tau = path.tau_to_plane(0.5 * t);
    if (!(out.tau > 0)) return out;  // turns back before the back face
    out.exit = path.position(out.tau);
    out.exit.z = 0.5 * t;
    out.exit_momentum = path.momentum(out.tau);
    out.exits = leave_flat(out.exit_momentum, out.direction);
    to_display(out, display_z);
    return out;
}

// ---- (d) the catenary ---------------------------------------------------------------------------------
//
// n = n0 + k x: grad n = (k, 0, 0), so by d/ds (n dr/ds) = grad n the y and z components of
// p = n dr/ds are conserved. With beta = hypot(p_y, p_z) and theta the ray's angle to the (y, z)
// plane, the unit direction's (y, z) part has length cos(theta), so
//   n cos(theta) = beta        (Snell's law of a stratified medium),
// and p_x = n sin(theta), p_x^2 = n^2 - beta^2. Let sigma be the distance travelled in the (y, z)
// plane (d sigma / ds = cos theta, so d sigma / dtau = n cos theta = beta); then
// dx / dsigma = tan(theta) = p_x / beta and d p_x / dsigma = (dp_x / ds)(ds / dsigma) = k / cos theta
// = k n / beta. With u = n = n0 + k x:
//   du / dsigma = k p_x / beta,  d^2 u / dsigma^2 = (k / beta) d p_x / dsigma = (k / beta)^2 u,
// so u = n_e cosh(kappa sigma) + p_x0 sinh(kappa sigma) (kappa = k / beta, u(0) = n_e the entry index,
// u'(0) = kappa p_x0), which is beta cosh(kappa (sigma - sigma0)) because n_e^2 - p_x0^2 = beta^2
// (|p0| = n_e) with sinh(-kappa sigma0) = p_x0 / beta. Hence the catenary
//   x(sigma) = (beta / k) cosh(k (sigma - sigma0) / beta) - n0 / k.
// Evaluated as it stands it cancels (two terms ~n0 / k for a weak gradient); with A_e = asinh(p_x0 /
// beta) = -kappa sigma0 and cosh(u) - cosh(v) = 2 sinh((u + v) / 2) sinh((u - v) / 2):
//   x(sigma) - x0 = (beta / k) (cosh(A_e + kappa sigma) - cosh(A_e))
//                 = (2 / kappa) sinh(A_e + kappa sigma / 2) sinh(kappa sigma / 2)
//                 = sigma sinh(A_e + kappa sigma / 2) sinhc(kappa sigma / 2),   sinhc(x) = sinh(x) / x,
// exact for k -> 0 (x - x0 -> sigma p_x0 / beta, the straight line). The slope is
// dx / dsigma = sinh(A_e + kappa sigma), so p_x = beta sinh(A_e + kappa sigma).
// The back face z = t/2 is reached at sigma_e = t beta / p_z (z = -t/2 + sigma p_z / beta), where
// y = y0 + t p_y / p_z and tau = sigma_e / beta = t / p_z.
Exit catenary_window(double n0, double k, double t, double x0, double y0, const Vec3& d, double display_z) {
    Exit out;
    const double ne = n0 + k * x0;
    const Vec3 p0 = enter_flat(d, ne * ne);
    out.entry = {x0, y0, -0.5 * t};
    out.entry_momentum = p0;
    const double beta = std::hypot(p0.y, p0.z);
    const double kappa = k / beta;
    const double Ae = std::asinh(p0.x / beta);
    const double sigma = t * beta / p0.z;
    const double half = 0.5 * kappa * sigma;
    out.tau = t / p0.z;
    out.exit = {x0 + sigma * std::sinh(Ae + half) * sinhc(half), y0 + t * p0.y / p0.z, 0.5 * t};
    out.exit_momentum = {beta * std::sinh(Ae + kappa * sigma), p0.y, p0.z};
    out.exits = leave_flat(out.exit_momentum, out.direction);
    to_display(out, display_z);
    return out;
}

}  // namespace ltm::validation::grin_closed_form
