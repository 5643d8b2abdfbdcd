#pragma once
// Interface optics in double precision: vector Snell's law, unpolarised Fresnel reflectance and
// total internal reflection.
//
// Conventions (as in Mitsuba's render/fresnel.h): `d` is the unit incident direction, `n` a unit
// normal on the incident side (dot(d, n) < 0), eta = n_incident / n_transmitted. Going from air
// into glass of index 1.5, eta = 1 / 1.5.
#include <cmath>

#include "geometry/Vec3.h"

namespace ltm {

struct FresnelResult {
    double reflectance = 1.0;  // unpolarised: (Rs + Rp) / 2; 1 under total internal reflection
    double cos_t = 0.0;        // cosine of the transmission angle (0 under TIR)
    bool total_internal_reflection = false;
};

// cos_i = -dot(d, n) > 0. Fresnel equations (Hecht, Optics, 4.4):
//   rs = (eta cos_i - cos_t) / (eta cos_i + cos_t), rp = (cos_i - eta cos_t) / (cos_i + eta cos_t)
// with cos_t = sqrt(1 - eta^2 (1 - cos_i^2)); TIR when the radicand is negative.
// Inline: it is called once per interaction of every path.
inline FresnelResult fresnel(double cos_i, double eta) {
    FresnelResult r;
    // min(1, |cos_i|), and 1 for a NaN (as std::fmin gives it, without its library call).
    const double c = std::fabs(cos_i);
    cos_i = c <= 1.0 ? c : 1.0;
    // 1 - cos^2 written as (1 - c)(1 + c) keeps its relative precision near normal incidence.
    const double sin2_t = eta * eta * (1.0 - cos_i) * (1.0 + cos_i);
    if (sin2_t >= 1.0) {
        r.total_internal_reflection = true;
        return r;
    }
    const double cos_t = std::sqrt((1.0 - sin2_t));
    const double rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const double rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    r.reflectance = 0.5 * (rs * rs + rp * rp);
    r.cos_t = cos_t;
    return r;
}

// Mirror reflection of d about n.
inline Vec3 reflect(const Vec3& d, const Vec3& n) { return d - n * (2.0 * dot(d, n)); }

// Refraction by the vector form of Snell's law: t = eta d + (eta cos_i - cos_t) n, given cos_t
// from `fresnel` (it is a unit vector when d and n are).
inline Vec3 refract(const Vec3& d, const Vec3& n, double eta, double cos_i, double cos_t) {
    return d * eta + n * (eta * cos_i - cos_t);
}

}  // namespace ltm
