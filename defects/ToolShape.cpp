#include "defects/ToolShape.h"

#include <algorithm>
#include <cmath>

namespace ltm {

ToolShape::ToolShape(const Lens& lens, const Defect& d) : d_(d) {
    if (d.type == DefectType::Scratch) {
        path_ = scratch_path(lens, d);
        m_ = std::max(d.width, d.depth);
        // Bounds from the profile's extreme points swept along the path (sampled densely, then
        // padded by the largest profile extent, which covers the chord bulge between samples).
        const double W = 0.5 * d.width * (1.0 + m_ / d.depth) + d.width;
        for (int i = 0; i <= 64; ++i)
            for (double s : {-W, W})
                for (double t : {-m_, d.depth}) box_.extend(path_.place(i / 64.0, {s, t}));
        const double pad = W + m_ + d.depth + path_.path_length() / 64.0;
        box_.lo -= Vec3{pad, pad, pad};
        box_.hi += Vec3{pad, pad, pad};
    } else {
        inv_frame_ = d.frame.transposed();
        const double r = d.max_semi_axis();
        box_ = {d.center - Vec3{r, r, r}, d.center + Vec3{r, r, r}};
    }
}

bool ToolShape::contains(const Vec3& p) const {
    if (p.x < box_.lo.x || p.y < box_.lo.y || p.z < box_.lo.z || p.x > box_.hi.x || p.y > box_.hi.y || p.z > box_.hi.z)
        return false;
    if (d_.type != DefectType::Scratch) {
        const Vec3 y = inv_frame_ * (p - d_.center);
        const Vec3& e = d_.semi_axes;
        return (y.x / e.x) * (y.x / e.x) + (y.y / e.y) * (y.y / e.y) + (y.z / e.z) * (y.z / e.z) < 1.0;
    }
    // Profile coordinates (s, t) and the fraction f along the path.
    double s, t, f;
    const ScratchPath& P = path_;
    if (!P.revolve) {
        const Vec3 v = p - P.p0;
        f = dot(v, P.dir) / P.length;
        s = dot(v, P.s_axis);
        t = dot(v, P.t_axis);
    } else {
        const Vec3 v = p - P.o;
        const double h = dot(v, P.u);
        const Vec3 r = v - P.u * h;
        const double q = length(r);
        double phi = std::atan2(dot(r, P.e1), dot(r, P.e0));
        // Bring phi into the sweep's range (phi1 may be below phi0 for mirrored arcs).
        const double lo = std::min(P.phi0, P.phi1);
        while (phi < lo - kPi) phi += 2 * kPi;
        while (phi > lo + kPi) phi -= 2 * kPi;
        if (phi < lo) phi += 2 * kPi;
        f = (phi - P.phi0) / (P.phi1 - P.phi0);
        // Solve (q - q0, h - h0) = s (sq, sh) + t (tq, th).
        const double dq = q - P.q0, dh = h - P.h0;
        const double det = P.sq * P.th - P.sh * P.tq;
        s = (dq * P.th - dh * P.tq) / det;
        t = (P.sq * dh - P.sh * dq) / det;
    }
    if (!(f > 0 && f < 1) || !(t > -m_)) return false;
    const double w = d_.width, dep = d_.depth;
    if (d_.profile == ScratchProfile::V) return t < dep * (1.0 - 2.0 * std::fabs(s) / w);
    if (std::fabs(s) >= 0.5 * w) return false;
    const double rb = dep <= 0.5 * w ? (0.25 * w * w + dep * dep) / (2.0 * dep) : 0.5 * w;
    const double tc = dep - rb;
    return t < tc || s * s + (t - tc) * (t - tc) < rb * rb;
}

}  // namespace ltm
