// The analytic reference solver (AnalyticScene.h). Every formula is derived here, in the
// comments, from first principles and the cited textbooks; nothing is taken from trace/ or from
// the geometry library's surfaces (independence: see AnalyticScene.h).
#include "validation/AnalyticScene.h"
#include "validation/ReferenceMath.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "validation/ValidationTolerance.h"

namespace ltm::validation {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

// ---- supports -----------------------------------------------------------------------------------

bool supports(const Scene& scene, std::string* why) {
    auto fail = [&](const std::string& m) {
        if (why) *why = m;
        return false;
    };
    const LensSpec& s = scene.object.lens;
    const double a = 0.5 * s.diameter;
    if (!(s.diameter > 0) || !(s.center_thickness > 0) || !(s.ior > 1))
        return fail("object: invalid geometry (diameter, thickness and ior - 1 must be positive)");
    if ((std::isfinite(s.r1) && std::fabs(s.r1) < a) || (std::isfinite(s.r2) && std::fabs(s.r2) < a))
        return fail("object: a face's |R| is smaller than the semi-diameter");
    // A ball (object type sphere: r1 = R, r2 = -R, t = D = 2R) is the one solid whose edge
    // thickness is exactly zero: its caps are the two hemispheres and its rim has no height.
    const double edge = s.center_thickness + sag(s.r2, a) - sag(s.r1, a);
    if (!(edge > 0) && !(s.ball && edge == 0))
        return fail("object: the edge thickness is not positive");
    const auto& D = scene.defects;
    for (size_t k = 0; k < D.size(); ++k) {
        const Defect& d = D[k];
        if (d.type == DefectType::Scratch)
            return fail(defect_key(int(k)) +
                        ": a scratch is not supported by the analytic reference solver (its groove walls "
                        "are cones, planes and tori trimmed against the face; only enclosed bubbles and "
                        "particles are modelled)");
        if (d.type == DefectType::Bubble && d.surface_breaking)
            return fail(defect_key(int(k)) +
                        ": a surface-breaking bubble (open pit) is not supported by the analytic reference "
                        "solver (the face and the bubble are trimmed against each other; only enclosed "
                        "bubbles and particles are modelled)");
        if (!(d.semi_axes.x > 0 && d.semi_axes.y > 0 && d.semi_axes.z > 0))
            return fail(defect_key(int(k)) + ": non-positive size");
    }
    // Disjointness: the media model (glass around each defect, air or absorber inside) needs
    // defects that do not overlap. Two spheres overlap iff |c1 - c2| <= r1 + r2 (exact); for an
    // ellipsoid the test uses its bounding sphere (radius = the largest semi-axis), which is
    // conservative: a pair that cannot be proven disjoint this way is rejected.
    for (size_t i = 0; i < D.size(); ++i)
        for (size_t j = i + 1; j < D.size(); ++j) {
            const double ri = std::max({D[i].semi_axes.x, D[i].semi_axes.y, D[i].semi_axes.z});
            const double rj = std::max({D[j].semi_axes.x, D[j].semi_axes.y, D[j].semi_axes.z});
            if (distance(D[i].center, D[j].center) <= ri + rj)
                return fail(defect_key(int(i)) + " and " + defect_key(int(j)) +
                            (D[i].is_sphere() && D[j].is_sphere()
                                 ? " overlap"
                                 : " may overlap (their bounding spheres intersect)") +
                            ": the analytic reference solver needs disjoint defects");
        }
    if (why) why->clear();
    return true;
}

// ---- interface optics ---------------------------------------------------------------------------

Vec3 reflect(const Vec3& d, const Vec3& n) {
    // The law of reflection (Hecht, Optics, 4th ed., Sec. 4.3): the angle of reflection equals
    // the angle of incidence, in the plane of incidence. Decomposing d = (d.n) n + d_t, the
    // tangential part d_t is kept and the normal part reversed: r = d_t - (d.n) n = d - 2 (d.n) n.
    return d - n * (2.0 * dot(d, n));
}

namespace {

// The Fresnel equations for given cosines (both in [0, 1]). Derivation (Hecht, Optics, 4th ed.,
// Sec. 4.6.2): at a plane interface between non-magnetic media, the tangential components of
// E and H are continuous, and |H| is proportional to n |E|.
//   s (E perpendicular to the plane of incidence): E_i + E_r = E_t (tangential E) and
//     n1 ci (E_i - E_r) = n2 ct E_t (tangential H)  =>
//     rs = E_r / E_i = (n1 ci - n2 ct) / (n1 ci + n2 ct),  ts = 1 + rs = 2 n1 ci / (n1 ci + n2 ct).
//   p (E in the plane of incidence): ci (E_i - E_r) = ct E_t (tangential E) and
//     n1 (E_i + E_r) = n2 E_t (tangential H)  =>
//     rp = (n2 ci - n1 ct) / (n2 ci + n1 ct),  tp = (n1 / n2)(1 + rp) = 2 n1 ci / (n2 ci + n1 ct).
// Power (Sec. 4.6.3): the flux through a unit area of the interface is proportional to
// n cos(theta) |E|^2, so R = r^2 and T = (n2 ct / (n1 ci)) t^2. Expanding t^2 removes the division
// by ci (finite at grazing incidence):
//   Ts = 4 n1 n2 ci ct / (n1 ci + n2 ct)^2,  Tp = 4 n1 n2 ci ct / (n2 ci + n1 ct)^2.
// T is computed from the transmission amplitudes, not as 1 - R, so R + T = 1 is a real check.
// Unpolarised light is an equal incoherent mixture of s and p: R = (Rs + Rp) / 2, T = (Ts + Tp) / 2.
Fresnel fresnel_cosines(double n1, double n2, double ci, double ct) {
    Fresnel f;
    f.tir = false;
    f.cos_t = ct;
    const double s_den = n1 * ci + n2 * ct, p_den = n2 * ci + n1 * ct;
    if (!(s_den > 0) || !(p_den > 0)) {  // ci = ct = 0: grazing on both sides, all reflected
        return f;                       // Rs = Rp = R = 1, T = 0
    }
    const double rs = (n1 * ci - n2 * ct) / s_den;
    const double rp = (n2 * ci - n1 * ct) / p_den;
    f.Rs = rs * rs;
    f.Rp = rp * rp;
    f.R = 0.5 * (f.Rs + f.Rp);
    const double num = 4.0 * n1 * n2 * ci * ct;
    f.Ts = num / (s_den * s_den);
    f.Tp = num / (p_den * p_den);
    f.T = 0.5 * (f.Ts + f.Tp);
    return f;
}

}  // namespace

Fresnel fresnel(double n1, double n2, double cos_i) {
    // Snell's law (Hecht, Sec. 4.4): n1 sin_i = n2 sin_t, so sin_t^2 = (n1/n2)^2 (1 - cos_i^2).
    // 1 - cos_i^2 is evaluated as (1 - ci)(1 + ci) (exact factors near ci = 1). If sin_t^2 >= 1
    // there is no transmitted wave: total internal reflection (Hecht, Sec. 4.7), R = 1.
    const double ci = std::clamp(cos_i, 0.0, 1.0);
    const double eta = n1 / n2;
    const double sin2_t = eta * eta * ((1.0 - ci) * (1.0 + ci));
    if (sin2_t >= 1.0) {
        Fresnel f;
        f.tir = true;
        return f;
    }
    return fresnel_cosines(n1, n2, ci, std::sqrt(1.0 - sin2_t));
}

Interaction interact(const Vec3& d, const Vec3& normal, double n1, double n2) {
    // Vector form of Snell's law. Orient the unit normal N against d (N points back into the
    // incident medium): cos_i = -d.N >= 0. Decompose d = -cos_i N + d_t with the tangential part
    // d_t = d + cos_i N, |d_t| = sin_i (computed directly from d_t: accurate near normal
    // incidence, where 1 - cos_i^2 would cancel).
    // The refracted direction lies in the plane of d and N (Hecht, Sec. 4.4), on the far side of
    // the interface; its tangential part is parallel to d_t with length sin_t = (n1/n2) sin_i
    // (Snell), its normal part is -cos_t N with cos_t = sqrt(1 - sin_t^2). Hence
    //   t = eta d_t - cos_t N = eta d + (eta cos_i - cos_t) N,   eta = n1 / n2,
    // a unit vector since |t|^2 = sin_t^2 + cos_t^2 = 1. If eta sin_i > 1 no such cos_t exists:
    // total internal reflection, and the ray takes the mirror direction r = d + 2 cos_i N.
    // Both are renormalised (once, a few ulps) so rounding does not accumulate along a path.
    Interaction in;
    Vec3 N = normal;
    double c = dot(N, d);
    if (c > 0) {
        N = -N;
        c = -c;
    }
    in.normal = N;
    const double cos_i = std::min(1.0, -c);
    in.cos_i = cos_i;
    const Vec3 dt = d + N * cos_i;
    const double sin2_i = std::min(1.0, dot(dt, dt));
    const double eta = n1 / n2;
    const double sin2_t = eta * eta * sin2_i;
    in.reflected = normalize(d + N * (2.0 * cos_i));
    if (sin2_t >= 1.0) {
        in.tir = true;
        in.cos_t = 0.0;
        in.R = 1.0;
        in.direction = in.reflected;
        return in;
    }
    const double cos_t = std::sqrt(1.0 - sin2_t);
    in.cos_t = cos_t;
    in.direction = normalize(d * eta + N * (eta * cos_i - cos_t));
    in.R = fresnel_cosines(n1, n2, cos_i, cos_t).R;
    return in;
}

// ---- the scene ----------------------------------------------------------------------------------

AnalyticScene::AnalyticScene(const Scene& scene) : scene_(scene) {
    std::string why;
    if (!supports(scene, &why)) throw std::invalid_argument("analytic reference solver: " + why);
    const LensSpec& s = scene.object.lens;
    n_glass_ = s.ior;
    a_ = 0.5 * s.diameter;
    t_ = s.center_thickness;
    r1_ = s.r1;
    r2_ = s.r2;
    absorbing_rim_ = scene.object.rim == RimFinish::Absorbing;
    z_edge_front_ = z_front(a_);
    z_edge_back_ = z_back(a_);
    // The faces' sags are monotonic in rho (d sag / d rho = rho / sqrt(R^2 - rho^2) sgn(R)), so
    // the extremes of the solid along z are at the vertices or at the edges.
    z_min_ = std::min(-0.5 * t_, z_edge_front_);
    z_max_ = std::max(0.5 * t_, z_edge_back_);
    L_ = validation::length_scale(scene);
    // Smallest accepted ray parameter for a surface other than the one the ray starts on: far
    // below any feature of the scene (1e-12 L ~ 1e-10 mm), far above the rounding of a vertex
    // (~u L): it only rejects a zero-length step across an edge seam.
    tmin_ = 1e-12 * L_;

    auto cap = [&](const char* name, double R, double z_vertex) {
        Surf f;
        f.name = name;
        if (std::isfinite(R)) {
            // Sphere of radius |R| centred at (0, 0, z_vertex + R): R > 0 puts the centre at +z of
            // the vertex (docs/conventions.md). The branch through the vertex is the one with
            // sgn(R) (z - zc) <= 0 (see sag()).
            f.kind = Kind::SphereCap;
            f.center = {0.0, 0.0, z_vertex + R};
            f.radius = std::fabs(R);
            f.sign = R > 0 ? 1.0 : -1.0;
        } else {
            f.kind = Kind::PlaneCap;
            f.z0 = z_vertex;
        }
        surfaces_.push_back(f);
    };
    cap("front", r1_, -0.5 * t_);
    cap("back", r2_, 0.5 * t_);
    Surf rim;
    rim.kind = Kind::Rim;
    rim.name = "rim";
    surfaces_.push_back(rim);
    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const Defect& d = scene.defects[k];
        Surf e;
        e.kind = Kind::Ellipsoid;
        e.defect = int(k);
        e.particle = d.type == DefectType::Particle;
        e.name = std::string(e.particle ? "particle " : "bubble ") + std::to_string(k);
        e.center = d.center;
        e.is_sphere = d.is_sphere();
        e.radius = d.semi_axes.x;
        // Ellipsoid with body axes the columns f_i of the frame F and semi-axes s_i:
        //   { p : sum_i ((p - c).f_i / s_i)^2 = 1 } = { p : |M (p - c)| = 1 },  M = S^-1 F^T,
        // i.e. row i of M is f_i / s_i. M maps the ellipsoid onto the unit sphere.
        const double sa[3] = {d.semi_axes.x, d.semi_axes.y, d.semi_axes.z};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) e.M(i, j) = d.frame(j, i) / sa[i];
        surfaces_.push_back(e);
    }
}

double AnalyticScene::z_front(double rho) const { return -0.5 * t_ + sag(r1_, rho); }
double AnalyticScene::z_back(double rho) const { return 0.5 * t_ + sag(r2_, rho); }

Medium AnalyticScene::medium_at(const Vec3& p) const {
    for (const Surf& s : surfaces_) {
        if (s.kind != Kind::Ellipsoid) continue;
        const bool inside = s.is_sphere ? length(p - s.center) < s.radius : length(s.M * (p - s.center)) < 1.0;
        if (inside) return {s.particle ? MediumKind::Particle : MediumKind::Bubble, s.defect};
    }
    const double rho = std::hypot(p.x, p.y);
    if (rho < a_ && p.z > z_front(rho) && p.z < z_back(rho)) return {MediumKind::Glass, -1};
    return {MediumKind::Air, -1};
}

Medium AnalyticScene::across(int id, const Medium& from) const {
    const Surf& s = surfaces_.at(id);
    if (s.kind == Kind::Ellipsoid) {
        if (from.kind == MediumKind::Glass) return {s.particle ? MediumKind::Particle : MediumKind::Bubble, s.defect};
        return {MediumKind::Glass, -1};
    }
    return from.kind == MediumKind::Air ? Medium{MediumKind::Glass, -1} : Medium{MediumKind::Air, -1};
}

namespace {
double index_of(const Medium& m, double n_glass) { return m.kind == MediumKind::Glass ? n_glass : 1.0; }
}  // namespace

bool AnalyticScene::on_patch(const Surf& s, const Vec3& p) const {
    // The part of each surface that bounds the solid. A relative slack of 1e-12 on the bounds
    // (rounding of a vertex is ~1e-16 relative) closes the edge seams between caps and rim, so no
    // ray can slip through the edge circle between two patches because of rounding; where two
    // patches both accept, the nearer hit wins, which is the same point to within the slack.
    const double rho2 = p.x * p.x + p.y * p.y;
    switch (s.kind) {
        case Kind::SphereCap:
            return rho2 <= a_ * a_ * (1.0 + 1e-12) && s.sign * (p.z - s.center.z) <= 1e-12 * s.radius;
        case Kind::PlaneCap:
            return rho2 <= a_ * a_ * (1.0 + 1e-12);
        case Kind::Rim:
            return p.z >= z_edge_front_ - 1e-12 * L_ && p.z <= z_edge_back_ + 1e-12 * L_;
        case Kind::Ellipsoid:
            return true;
    }
    return false;
}

Vec3 AnalyticScene::normal_at(const Surf& s, const Vec3& p) const {
    switch (s.kind) {
        case Kind::SphereCap:
            return normalize(p - s.center);  // the radius vector
        case Kind::PlaneCap:
            return {0.0, 0.0, 1.0};
        case Kind::Rim:
            return normalize(Vec3{p.x, p.y, 0.0});  // radial, horizontal
        case Kind::Ellipsoid:
            if (s.is_sphere) return normalize(p - s.center);
            // The gradient of f(p) = |M (p - c)|^2 is 2 M^T M (p - c): normal to the level set.
            return normalize(s.M.transposed() * (s.M * (p - s.center)));
    }
    return {};
}

bool AnalyticScene::hit_surface(const Surf& s, int id, const Vec3& o, const Vec3& d, bool starts_on,
                                double tmin, SurfaceHit& out) const {
    // Each surface is a quadric (or a plane) written as A t^2 + 2 b t + C = 0 along o + t d. The
    // reduced discriminant b^2 - A C is evaluated in its geometric, cancellation-free form
    //   b^2 - A C = A (r^2 - |w|^2) = A (r - |w|)(r + |w|),
    // where w is the foot of the perpendicular from the quadric's centre (axis) onto the line
    // (so |w| is the distance of the centre from the line) and r the radius:
    //   |o - c + t d|^2 = r^2 with w = (o - c) - (b / A) d, b = (o - c).d, A = d.d;
    //   Pythagoras: |o - c|^2 = |w|^2 + b^2 / A, so b^2 - A C = b^2 - A (|o - c|^2 - r^2)
    //   = A (r^2 - |w|^2). The naive b^2 - A C subtracts two numbers of size |o - c|^2 ~ R^2
    //   and loses digits when R >> r - |w|; |w| is computed to ~u |o - c| instead.
    // C = |o - c|^2 - r^2 = (|o - c| - r)(|o - c| + r) likewise.
    // When the ray starts ON this surface (starts_on), one root is 0 exactly in exact arithmetic;
    // rounding would make it +-tiny. Vieta (t1 + t2 = -2 b / A) gives the other root exactly
    // from b without the tiny one, and only that root is considered.
    double lo = 0, hi = 0;
    bool has = false;
    if (s.kind == Kind::PlaneCap) {
        // z = z0: t = (z0 - o.z) / d.z; a plane is never met twice in a row.
        if (starts_on || d.z == 0.0) return false;
        const double t = (s.z0 - o.z) / d.z;
        lo = hi = t;
        has = true;
    } else if (s.kind == Kind::Rim) {
        // Cylinder x^2 + y^2 = a^2: the same in the xy projection (A = dx^2 + dy^2).
        const double A = d.x * d.x + d.y * d.y;
        if (!(A > 0.0)) return false;  // parallel to the axis: never meets the cylinder
        const double b = o.x * d.x + o.y * d.y;
        if (starts_on) {
            lo = hi = -2.0 * b / A;
            has = true;
        } else {
            const double k = b / A;
            const double wl = std::hypot(o.x - k * d.x, o.y - k * d.y);
            const double ol = std::hypot(o.x, o.y);
            const double disc = A * ((a_ - wl) * (a_ + wl));
            const double C = (ol - a_) * (ol + a_);
            has = stable_roots(A, b, C, disc, lo, hi);
        }
    } else {
        // Sphere (cap or spherical defect): unit-free form with oc = o - c, radius r.
        // Ellipsoid: the same for the unit sphere in body coordinates o' = M (o - c), d' = M d
        // (M is linear, so the ray parameter t is the same in both frames).
        Vec3 oc, dd;
        double r;
        if (s.kind == Kind::SphereCap || s.is_sphere) {
            oc = o - s.center;
            dd = d;
            r = s.radius;
        } else {
            oc = s.M * (o - s.center);
            dd = s.M * d;
            r = 1.0;
        }
        const double A = dot(dd, dd);
        const double b = dot(oc, dd);
        if (starts_on) {
            lo = hi = -2.0 * b / A;
            has = true;
        } else {
            const double wl = length(oc - dd * (b / A));
            const double ol = length(oc);
            const double disc = A * ((r - wl) * (r + wl));
            const double C = (ol - r) * (ol + r);
            has = stable_roots(A, b, C, disc, lo, hi);
        }
    }
    if (!has) return false;
    // The smallest root above tmin whose point lies on the surface's patch.
    for (double t : {lo, hi}) {
        if (!(t > tmin)) continue;
        const Vec3 p = o + d * t;
        if (!on_patch(s, p)) continue;
        out.hit = true;
        out.t = t;
        out.point = p;
        out.normal = normal_at(s, p);
        out.surface = id;
        return true;
    }
    return false;
}

SurfaceHit AnalyticScene::first_hit(const Vec3& o, const Vec3& d, const Medium& in, int last) const {
    // The candidates are the surfaces bounding the current medium: air sees only the object's
    // outer surfaces (the defects are strictly inside the glass), glass sees everything, a bubble
    // (or a particle) only its own surface (defects are disjoint, see supports()).
    SurfaceHit best;
    best.t = kInf;
    const double tmin = tmin_ / length(d);  // tmin_ is a length; t is in units of |d|
    auto consider = [&](int id) {
        SurfaceHit h;
        if (hit_surface(surfaces_[id], id, o, d, id == last, tmin, h) && h.t < best.t) best = h;
    };
    if (in.kind == MediumKind::Bubble || in.kind == MediumKind::Particle) {
        consider(3 + in.defect);
    } else {
        for (int id = 0; id < 3; ++id) consider(id);
        if (in.kind == MediumKind::Glass)
            for (int id = 3; id < surface_count(); ++id) consider(id);
    }
    if (!best.hit) best = SurfaceHit{};
    return best;
}

SurfaceHit AnalyticScene::hit_one(int id, const Vec3& o, const Vec3& d, bool starts_on) const {
    SurfaceHit h;
    hit_surface(surfaces_.at(id), id, o, d, starts_on, tmin_ / length(d), h);
    return h;
}

void AnalyticScene::finish_display(Path& path, const Vec3& o) const {
    // The display is the plane z = Z. A path reaches it iff it ends in air heading to +z
    // (dz > 0), not absorbed: t = (Z - o.z) / dz, and the hit (x, y) = (o + t d).xy. Pixel
    // (docs/conventions.md): column q = floor((x + W/2) / (W/Q)) from -x, row p =
    // floor((H/2 - y) / (H/P)) from +y down, clamped to the last index on the far edges.
    const Vec3& d = path.direction;
    if (path.absorbed || path.truncated || path.lost || !(d.z > 0.0)) return;
    const DisplayDesc& disp = scene_.display;
    const double t = (disp.z - o.z) / d.z;
    if (!(t >= 0.0)) return;  // the origin is beyond the display
    path.display_hit = true;
    path.display_x = o.x + t * d.x;
    path.display_y = o.y + t * d.y;
    const double W = disp.size[0], H = disp.size[1];
    const int Q = disp.resolution[0], P = disp.resolution[1];
    if (std::fabs(path.display_x) <= 0.5 * W && std::fabs(path.display_y) <= 0.5 * H) {
        path.on_display = true;
        path.display_q = std::min(Q - 1, static_cast<int>(std::floor((path.display_x + 0.5 * W) / (W / Q))));
        path.display_p = std::min(P - 1, static_cast<int>(std::floor((0.5 * H - path.display_y) / (H / P))));
        path.display_q = std::max(0, path.display_q);
        path.display_p = std::max(0, path.display_p);
    }
}

Path AnalyticScene::principal_path(const Vec3& origin, const Vec3& direction) const {
    if (medium_at(origin).kind != MediumKind::Air)
        throw std::invalid_argument("principal_path: the origin is not in air");
    return principal_path(origin, direction, Medium{}, -1);
}

Path AnalyticScene::principal_path(const Vec3& origin, const Vec3& direction, const Medium& start,
                                   int start_surface) const {
    Path path;
    Vec3 o = origin;
    Vec3 d = normalize(direction);
    Medium m = start;
    int last = start_surface;
    if (m.kind == MediumKind::Particle) {  // starts inside an absorber
        path.absorbed = true;
        path.direction = d;
        return path;
    }
    int interactions = 0;
    for (;;) {
        const SurfaceHit h = first_hit(o, d, m, last);
        if (!h.hit) {
            if (m.kind != MediumKind::Air) path.lost = true;  // a closed medium must have an exit
            break;
        }
        if (interactions == kMaxInteractions) {
            path.truncated = true;
            break;
        }
        ++interactions;
        const Surf& s = surfaces_[h.surface];
        path.vertices.push_back(h.point);
        path.surfaces.push_back(s.name);
        path.surface_ids.push_back(h.surface);
        if (s.particle || (s.kind == Kind::Rim && absorbing_rim_)) {
            path.absorbed = true;
            path.events.push_back(Event::Absorbed);
            path.directions.push_back(d);
            break;
        }
        const Medium other = across(h.surface, m);
        const Interaction in = interact(d, h.normal, index_of(m, n_glass_), index_of(other, n_glass_));
        d = in.direction;
        if (in.tir) {
            ++path.tir_count;
            path.events.push_back(Event::TotalInternalReflection);
        } else {
            path.transmission *= 1.0 - in.R;
            path.events.push_back(Event::Transmitted);
            m = other;
        }
        path.directions.push_back(d);
        o = h.point;
        last = h.surface;
    }
    path.direction = d;
    finish_display(path, o);
    return path;
}

double AnalyticScene::expected_display_throughput(const Vec3& origin, const Vec3& direction, int max_depth,
                                                  double cutoff, double* dropped_weight) const {
    // The Monte Carlo tracer follows, at each interface, the reflected branch with probability R
    // and the transmitted one with 1 - R (TIR: reflected with probability 1); an absorber ends
    // the path. The probability that the path ends on the display is therefore the sum, over all
    // leaves of this binary tree that leave the object toward the display, of the product of the
    // branch probabilities along the way (walk_fresnel_tree).
    if (medium_at(origin).kind != MediumKind::Air)
        throw std::invalid_argument("expected_display_throughput: the origin is not in air");
    double dropped = 0.0;
    const double value = walk_fresnel_tree({origin, normalize(direction), Medium{}, -1, 0, 1.0, 0}, max_depth, cutoff,
                                           dropped, nullptr);
    if (dropped_weight) *dropped_weight = dropped;
    return value;
}

AnalyticScene::SplitMoments AnalyticScene::split_sample_moments(const Vec3& origin, const Vec3& direction,
                                                                int split_depth, int max_depth, double cutoff) const {
    if (medium_at(origin).kind != MediumKind::Air)
        throw std::invalid_argument("split_sample_moments: the origin is not in air");
    SplitMoments out;
    // A root of weight w brings w with probability tau (its own tree, walked from weight 1) and 0
    // otherwise: mean w tau, variance w^2 tau (1 - tau). Its dropped weight scales by w.
    const std::function<void(const Branch&)> root = [&](const Branch& b) {
        double dropped = 0.0;
        Branch unit = b;
        unit.w = 1.0;
        const double tau = walk_fresnel_tree(unit, max_depth, cutoff, dropped, nullptr);
        out.mean += b.w * tau;
        out.variance += b.w * b.w * tau * (1.0 - tau);
        out.dropped += b.w * dropped;
    };
    // Leaves reached before any root are deterministic: they add to the mean, not the variance.
    out.mean += walk_fresnel_tree({origin, normalize(direction), Medium{}, -1, 0, 1.0, split_depth}, max_depth,
                                  cutoff, out.dropped, &root);
    return out;
}

double AnalyticScene::walk_fresnel_tree(const Branch& start, int max_depth, double cutoff, double& dropped,
                                        const std::function<void(const Branch&)>* root) const {
    // Depth first with an explicit stack. A branch whose weight is below `cutoff`, or that would
    // need more than max_depth interactions, is not followed: its weight is added to `dropped`
    // (an upper bound of its contribution), so the exact value lies in [value, value + dropped].
    // Light trapped by total internal reflection (skew rays circling between the faces and a
    // polished rim can be trapped for ever) ends up there too, after max_depth interactions.
    constexpr long kMaxBranches = 20'000'000;  // a hard budget; never reached by the scenes here
    std::vector<Branch> stack{start};
    double value = 0.0;
    long visited = 0;
    const DisplayDesc& disp = scene_.display;
    while (!stack.empty()) {
        const Branch b = stack.back();
        stack.pop_back();
        if (root && b.splits == 0) {
            (*root)(b);
            continue;
        }
        if (++visited > kMaxBranches) {
            dropped += b.w;
            continue;
        }
        const SurfaceHit h = first_hit(b.o, b.d, b.m, b.last);
        if (!h.hit) {
            if (b.m.kind != MediumKind::Air) {  // never expected: count it as unresolved
                dropped += b.w;
            } else if (b.d.z > 0.0) {
                const double t = (disp.z - b.o.z) / b.d.z;
                const double x = b.o.x + t * b.d.x, y = b.o.y + t * b.d.y;
                if (t >= 0.0 && std::fabs(x) <= 0.5 * disp.size[0] && std::fabs(y) <= 0.5 * disp.size[1])
                    value += b.w;
            }
            continue;
        }
        if (b.depth >= max_depth) {
            dropped += b.w;
            continue;
        }
        const Surf& s = surfaces_[h.surface];
        if (s.particle || (s.kind == Kind::Rim && absorbing_rim_)) continue;  // absorbed
        const Medium other = across(h.surface, b.m);
        const Interaction in = interact(b.d, h.normal, index_of(b.m, n_glass_), index_of(other, n_glass_));
        auto push = [&](const Vec3& d, const Medium& m, double w, int splits) {
            if (w < cutoff)
                dropped += w;
            else
                stack.push_back({h.point, d, m, h.surface, b.depth + 1, w, splits});
        };
        if (in.tir) {
            push(in.reflected, b.m, b.w, b.splits);  // no choice, no split
        } else {
            push(in.reflected, b.m, b.w * in.R, b.splits - 1);
            push(in.direction, other, b.w * (1.0 - in.R), b.splits - 1);
        }
    }
    return value;
}

RaySensitivity AnalyticScene::sensitivity(const Vec3& origin, const Vec3& direction) const {
    // Central finite differences of the reference path, as documented in ValidationTolerance.h.
    RaySensitivity out;
    const Vec3 d = normalize(direction);
    const Path p0 = principal_path(origin, d);
    out.interfaces = static_cast<int>(p0.vertices.size());
    Vec3 e1, e2;
    orthonormal_basis(d, e1, e2);
    const double h = kSensitivityRelativeStep * a_;   // origin step, mm
    const double eta = kSensitivityRelativeStep;       // direction step, rad

    auto same_shape = [&](const Path& q) {
        return q.surface_ids == p0.surface_ids && q.events == p0.events && q.absorbed == p0.absorbed &&
               q.truncated == p0.truncated && q.lost == p0.lost && q.display_hit == p0.display_hit;
    };
    // Largest position change and final-direction change between two paths of the same shape.
    auto diffs = [&](const Path& a, const Path& b, double& dpos, double& ddir) {
        dpos = 0;
        for (size_t i = 0; i < a.vertices.size(); ++i)
            dpos = std::max(dpos, distance(a.vertices[i], b.vertices[i]));
        if (a.display_hit)
            dpos = std::max(dpos, std::hypot(a.display_x - b.display_x, a.display_y - b.display_y));
        ddir = distance(a.direction, b.direction);
    };
    for (const Vec3& e : {e1, e2}) {
        // Origin moved perpendicular to the ray.
        {
            const Path pp = principal_path(origin + e * h, d, Medium{}, -1);
            const Path pm = principal_path(origin - e * h, d, Medium{}, -1);
            if (!same_shape(pp) || !same_shape(pm) || medium_at(origin + e * h).kind != MediumKind::Air ||
                medium_at(origin - e * h).kind != MediumKind::Air) {
                out.stable = false;
            } else {
                double dp, dd;
                diffs(pp, pm, dp, dd);
                out.kappa = std::max(out.kappa, dp / (2 * h));
                out.kappa_dir = std::max(out.kappa_dir, dd * L_ / (2 * h));
            }
        }
        // Direction turned by +-eta about the axis perpendicular to d and e (toward e).
        {
            const Path pp = principal_path(origin, normalize(d + e * eta), Medium{}, -1);
            const Path pm = principal_path(origin, normalize(d - e * eta), Medium{}, -1);
            if (!same_shape(pp) || !same_shape(pm)) {
                out.stable = false;
            } else {
                double dp, dd;
                diffs(pp, pm, dp, dd);
                // normalize(d +- eta e) turns d by atan(eta) ~ eta (relative error eta^2 = 1e-14).
                const double angle = 2 * std::atan(eta);
                out.kappa = std::max(out.kappa, dp / (angle * L_));
                out.kappa_dir = std::max(out.kappa_dir, dd / angle);
            }
        }
    }
    if (!out.stable) {
        out.kappa = kInf;
        out.kappa_dir = kInf;
    }
    return out;
}

}  // namespace ltm::validation
