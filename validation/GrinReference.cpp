// The GRIN reference solver (GrinReference.h). Every formula is derived here, in the comments;
// nothing is taken from trace/, from the geometry library's surfaces or lens, or from IndexField's
// functions (independence: see GrinReference.h and AnalyticScene.h).
#include "validation/GrinReference.h"
#include "validation/ReferenceMath.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "validation/ValidationTolerance.h"

namespace ltm::validation {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kU = 0x1p-53;  // unit roundoff of double

// ||A||_inf = the largest absolute row sum. For a symmetric matrix it bounds the spectral norm
// (the spectral radius is below every induced norm, and equals the spectral norm when A = A^T).
double norm_inf(const Mat3& A) {
    double m = 0;
    for (int i = 0; i < 3; ++i) m = std::max(m, std::fabs(A(i, 0)) + std::fabs(A(i, 1)) + std::fabs(A(i, 2)));
    return m;
}

bool all_finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// ---- the glass's index field, from the scene's data ----------------------------------------------
//
// The kinds (docs/conventions.md, x from the origin in mm). Five have n^2 quadratic in x,
//   n^2(x) = n0^2 + b . x + x^T H x / 2,   grad(n^2) / 2 = (b + H x) / 2,
// with (each read off the definition by matching coefficients):
//   uniform        n = n0:                         b = 0, H = 0
//   linear_n2      n^2 = n0^2 + gradient . x:      b = gradient, H = 0
//   radial_n2      n^2 = n0^2 (1 - G^2 (x^2+y^2)): b = 0, H = -2 n0^2 G^2 diag(1, 1, 0)
//   spherical_n2   n^2 = n0^2 (1 - g^2 |x|^2):     b = 0, H = -2 n0^2 g^2 I
//   quadratic_n2   n^2 = n0^2 + b . x + x^T H x/2: b = gradient, H = hessian
// and one has n linear: linear_n, n = n0 + k . x, so grad(n^2) / 2 = n grad n = (n0 + k . x) k.
struct Field {
    IndexFieldType type = IndexFieldType::Uniform;
    double n0 = 1.5;
    Vec3 b;
    Mat3 H = Mat3::zero();
    Vec3 k;  // linear_n
    bool graded = false;
    bool quadric = true;

    static Field from(const IndexField& f, double ior) {
        Field F;
        F.type = f.type;
        F.n0 = ior;
        F.graded = f.type != IndexFieldType::Uniform;
        const double n2 = ior * ior;
        switch (f.type) {
            case IndexFieldType::Uniform:
                break;
            case IndexFieldType::LinearN2:
                F.b = f.gradient;
                break;
            case IndexFieldType::RadialN2:
                F.H(0, 0) = F.H(1, 1) = -2.0 * n2 * f.g * f.g;
                break;
            case IndexFieldType::SphericalN2:
                F.H(0, 0) = F.H(1, 1) = F.H(2, 2) = -2.0 * n2 * f.g * f.g;
                break;
            case IndexFieldType::QuadraticN2:
                F.b = f.gradient;
                F.H = f.hessian;
                break;
            case IndexFieldType::LinearN:
                F.quadric = false;
                F.k = f.gradient;
                break;
        }
        return F;
    }
    double n2(const Vec3& x) const {
        if (!quadric) {
            const double n = n0 + dot(k, x);
            return n * n;
        }
        return n0 * n0 + dot(b, x) + 0.5 * dot(x, H * x);
    }
    double n(const Vec3& x) const {
        if (!graded) return n0;
        if (!quadric) return n0 + dot(k, x);
        return std::sqrt(std::max(0.0, n2(x)));
    }
    // grad(n^2) / 2.
    Vec3 half_grad_n2(const Vec3& x) const {
        if (!quadric) return k * (n0 + dot(k, x));
        return (b + H * x) * 0.5;
    }
    // An upper bound of ||D^2(n^2)|| / 2 (spectral norm): ||H||_inf / 2 for the quadric kinds;
    // for linear_n D^2(n^2) = 2 k k^T, of norm 2 |k|^2.
    double half_hessian_norm() const { return quadric ? 0.5 * norm_inf(H) : dot(k, k); }
    // The range of n^2 over the ball |x - c| <= s: by Taylor's theorem (exact for a quadratic)
    // n^2(x) = n^2(c) + grad(n^2)(c) . (x - c) + (x - c)^T H (x - c) / 2, so
    // |n^2(x) - n^2(c)| <= |grad(n^2)(c)| s + ||H|| s^2 / 2. For linear_n, n itself is within
    // |k| s of n(c).
    void n2_range(const Vec3& c, double s, double& lo, double& hi) const {
        if (!quadric) {
            const double nc = n0 + dot(k, c), dn = length(k) * s;
            const double a = nc - dn, z = nc + dn;
            lo = a > 0 ? a * a : 0.0;
            hi = std::max(a * a, z * z);
            return;
        }
        const double mid = n2(c);
        const double dev = length(b + H * c) * s + 0.5 * norm_inf(H) * s * s;
        lo = mid - dev;
        hi = mid + dev;
    }
    // An upper bound of |grad(n^2) / 2| over the ball |x - c| <= s: |b + H c| / 2 + ||H|| s / 2;
    // for linear_n |n k| <= (|n(c)| + |k| s) |k|.
    double half_grad_bound(const Vec3& c, double s) const {
        if (!quadric) return (std::fabs(n0 + dot(k, c)) + length(k) * s) * length(k);
        return 0.5 * (length(b + H * c) + norm_inf(H) * s);
    }
};

// ---- inhomogeneities ------------------------------------------------------------------------------
//
// An inhomogeneity's ellipsoid has body axes the columns f_i of the frame F and semi-axes s_i.
// With M = S^-1 F^T (row i = f_i / s_i), y = M (x - c) are its unit-sphere body coordinates and
// rho = |y| the body-frame ellipsoidal radius (rho = |x - c| / radius for a sphere).
// Smooth profile: n = n_glass + D, D = dn (1 - rho^2)^2 for rho < 1, else 0. Its gradient:
//   grad rho^2 = 2 M^T M (x - c) = 2 M^T y,  dD / d(rho^2) = -2 dn (1 - rho^2),
//   grad D = -4 dn (1 - rho^2) M^T y,
// continuous at rho = 1 (both D and grad D vanish): the profile is C1, its second derivatives
// jump there (which is why rho = 1 is an integration seam, see "Seams").
// Bound: M^T = F S^-1, so |M^T y| <= |y| / s_min = rho / s_min (F is a rotation), and
// (1 - rho^2) rho on [0, 1] peaks at rho = 1/sqrt 3 with 2 / (3 sqrt 3):
//   |grad D| <= 8 |dn| / (3 sqrt(3) s_min).
struct Inclusion {
    bool smooth = true;
    Vec3 c;
    Mat3 M;
    double dn = 0;
    double s_min = 0, s_max = 0;
    // Filled from the field (bounds): the range of the glass's n over the region the paths
    // inside the inclusion can reach, and a Lipschitz constant of F there (see Bounds).
    double nb_min = 1, nb_max = 1;
    double lip = 0;

    double rho2(const Vec3& x) const { return length2(M * (x - c)); }
    // D and grad D at x (both 0 outside).
    void profile(const Vec3& x, double& D, Vec3& gD) const {
        const Vec3 y = M * (x - c);
        const double r2 = dot(y, y);
        if (!(r2 < 1.0)) {
            D = 0;
            gD = {};
            return;
        }
        const double w = 1.0 - r2;
        D = dn * w * w;
        gD = M.transposed() * y * (-4.0 * dn * w);
    }
};

// The media of a path. A smooth inhomogeneity is not a medium (it has no interface): it is a
// region of the glass, `smooth` = its defect index while the ray is inside it.
enum class Med { Air, Glass, Bubble, Particle, Inclusion };
struct Region {
    Med med = Med::Air;
    int defect = -1;  // Bubble, Particle, Inclusion (a uniform inhomogeneity's interior)
    int smooth = -1;  // Glass: the smooth inhomogeneity containing the ray, -1 if none
};

enum class Role { Front, Back, Rim, Bubble, Particle, Uniform, Seam };

// A surface: the plane z = z0, or the quadric |M (x - c)| = radius (spheres: M = I, radius R; the
// rim cylinder: M = diag(1, 1, 0), radius a; an ellipsoid: M = S^-1 F^T, radius 1).
struct Surf {
    std::string name;
    Role role = Role::Front;
    int defect = -1;
    bool plane = false;
    double z0 = 0;
    Vec3 c;
    Mat3 M;
    double radius = 1;
    double m_norm = 1;  // ||M||_2: 1 for spheres and the rim, 1 / s_min for an ellipsoid
    double scale = 1;   // the magnitude of f's operands (rounding of f, see locate_root)
    double sign = 1;    // sphere cap: the branch sgn(R) (z - c.z) <= 0
};

// The numbers every bound below needs (see "Event location"). Computed by grin_supports too, to
// reject a field the bounds cannot cover.
struct Bounds {
    double Rx = 0;         // every point of the solid has |x| <= Rx
    double n_max = 1;      // |p| = n <= n_max on the ball |x| <= 2 Rx (steps keep paths in it)
    double F_max = 0;      // |dp/dtau| = |grad(n^2)| / 2 <= F_max there
    double lip_glass = 0;  // a Lipschitz constant of F = grad(n^2) / 2 of the glass there
};

struct Model {
    LensSpec spec;
    bool ball = false;
    double a = 1, t = 1;
    Field field;
    std::vector<int> incl_of;  // per defect: index into incl, or -1
    std::vector<Inclusion> incl;
    Bounds bounds;
};

// The solid's bounding radius: for a ball R; for a lens its points have rho <= a and z between
// the extremes of the faces (at the vertices or the edges, the sags being monotonic), so
// |x| <= sqrt(a^2 + max(|z_min|, |z_max|)^2).
//
// Bounds on the ball B = {|x| <= 2 Rx} (a curved step starting in the solid, |r0| <= Rx, moves at
// most n_max h <= Rx, see hmax, so it stays in B):
//   n^2 <= n0^2 + |b| 2Rx + ||H|| (2Rx)^2 / 2 (Taylor at the origin; linear_n: n <= n0 + |k| 2Rx),
//   and an inhomogeneity adds at most |dn| to n;
//   |grad(n^2)| / 2 <= half_grad_bound(0, 2Rx) for the glass;
//   inside a smooth inhomogeneity, n grad n = (n_b + D)(grad n_b + grad D) with
//   grad n_b = grad(n_b^2) / (2 n_b): |.| <= (nb_max + |dn|)(|grad n_b^2| / 2 / nb_min + |grad D|),
//   with nb_min, nb_max over the inhomogeneity's bounding ball (|x - c| <= s_max);
//   inside a uniform inhomogeneity's interior (a medium), n = n_b + dn and
//   n grad n = (1 + dn / n_b) grad(n_b^2) / 2, bounded with nb_min over |x - c| <= 2 s_max (a
//   step there moves at most n_max h <= s_max from a point inside, see hmax).
// nb_min must be positive for these to be finite: grin_supports requires nb_min^2 >= 1/4 (any
// field valid in the solid, n >= 1 - 1e-9 there, passes unless it drops by half within an
// inclusion's size).
//
// Lipschitz constants of F (|F(x) - F(x')| <= lip |x - x'|, lip >= ||DF|| on the region):
//   glass: DF = H / 2 for the quadric kinds, D(n k) = k k^T for linear_n: half_hessian_norm();
//   F = n grad n in general has DF = grad n grad n^T + n D^2 n, so lip <= |grad n|^2 + n_max ||D^2 n||;
//   with n_b = sqrt(n_b^2): grad n_b = grad(n_b^2) / (2 n_b), |.| <= g_b / nb_min (g_b the bound
//   of |grad(n_b^2)| / 2), and D^2 n_b = D^2(n_b^2) / (2 n_b) - grad(n_b^2) grad(n_b^2)^T / (4 n_b^3),
//   ||.|| <= ||H|| / (2 nb_min) + g_b^2 / nb_min^3 (0 for linear_n, whose n is linear);
//   the smooth profile: D^2 D = -4 dn (1 - rho^2) M^T M + 8 dn (M^T y)(M^T y)^T, and
//   ||M^T M|| = 1 / s_min^2, |M^T y|^2 <= 1 / s_min^2 inside, so ||D^2 D|| <= 12 |dn| / s_min^2;
//   inside a smooth inhomogeneity n = n_b + D (outside it the glass's lip applies: the larger of the
//   two holds across the seam, F being continuous there); inside a uniform one n = n_b + dn.
bool build_model(const Scene& scene, Model& m, std::string* why) {
    auto fail = [&](const std::string& s) {
        if (why) *why = s;
        return false;
    };
    m.spec = scene.object.lens;
    m.ball = scene.object.type == ObjectType::Sphere || m.spec.ball;
    m.a = 0.5 * m.spec.diameter;
    m.t = m.spec.center_thickness;
    if (m.ball) {
        m.bounds.Rx = m.a;
    } else {
        const double zf = -0.5 * m.t + sag(m.spec.r1, m.a), zb = 0.5 * m.t + sag(m.spec.r2, m.a);
        const double z_min = std::min(-0.5 * m.t, zf), z_max = std::max(0.5 * m.t, zb);
        const double zz = std::max(std::fabs(z_min), std::fabs(z_max));
        m.bounds.Rx = std::sqrt(m.a * m.a + zz * zz);
    }
    m.field = Field::from(scene.object.index_field, m.spec.ior);
    const Field& F = m.field;
    const double Rb = 2.0 * m.bounds.Rx;
    double n2hi = 0, n2lo = 0;
    F.n2_range({}, Rb, n2lo, n2hi);
    double dn_max = 0;
    double F_max = F.graded ? F.half_grad_bound({}, Rb) : 0.0;
    m.bounds.lip_glass = F.graded ? F.half_hessian_norm() : 0.0;
    m.incl_of.assign(scene.defects.size(), -1);
    m.incl.clear();
    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const Defect& d = scene.defects[k];
        if (d.type != DefectType::Inhomogeneity) continue;
        Inclusion in;
        in.smooth = d.index_profile == IndexProfile::Smooth;
        in.c = d.center;
        in.dn = d.delta_n;
        const double sa[3] = {d.semi_axes.x, d.semi_axes.y, d.semi_axes.z};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) in.M(i, j) = d.frame(j, i) / sa[i];
        in.s_min = std::min({sa[0], sa[1], sa[2]});
        in.s_max = std::max({sa[0], sa[1], sa[2]});
        const double reach = in.smooth ? in.s_max : 2.0 * in.s_max;
        double lo = 1, hi = 1;
        F.n2_range(in.c, reach, lo, hi);
        if (F.graded && !(lo >= 0.25))
            return fail(
                defect_key(int(k)) +
                ": the glass's index field falls below 1/2 near this inhomogeneity (n^2 >= " + std::to_string(lo) +
                " is all that can be proven), so the GRIN reference cannot "
                "bound its paths there");
        in.nb_min = F.graded ? std::sqrt(lo) : F.n0;
        in.nb_max = F.graded ? std::sqrt(std::max(hi, 0.0)) : F.n0;
        if (!(in.nb_min - std::fabs(in.dn) >= 0.5))
            return fail(defect_key(int(k)) +
                        ": delta_n brings the index below 1/2 (the GRIN reference "
                        "cannot bound its paths there)");
        const double gb = F.graded ? F.half_grad_bound(in.c, reach) : 0.0;
        const double Fk = in.smooth ? (in.nb_max + std::fabs(in.dn)) *
                                          (gb / in.nb_min + 8.0 * std::fabs(in.dn) / (3.0 * std::sqrt(3.0) * in.s_min))
                                    : gb * (1.0 + std::fabs(in.dn) / in.nb_min);
        F_max = std::max(F_max, Fk);
        const double gnb = F.graded ? gb / in.nb_min : 0.0;
        const double d2nb = F.graded && F.quadric
                                ? 0.5 * norm_inf(F.H) / in.nb_min + gb * gb / (in.nb_min * in.nb_min * in.nb_min)
                                : 0.0;
        const double nmax_k = in.nb_max + std::fabs(in.dn);
        if (in.smooth) {
            const double gD = 8.0 * std::fabs(in.dn) / (3.0 * std::sqrt(3.0) * in.s_min);
            const double d2D = 12.0 * std::fabs(in.dn) / (in.s_min * in.s_min);
            in.lip = std::max(m.bounds.lip_glass, (gnb + gD) * (gnb + gD) + nmax_k * (d2nb + d2D));
        } else {
            in.lip = gnb * gnb + nmax_k * d2nb;
        }
        dn_max = std::max(dn_max, std::fabs(in.dn));
        m.incl_of[k] = int(m.incl.size());
        m.incl.push_back(in);
    }
    m.bounds.n_max = std::sqrt(std::max(n2hi, F.n0 * F.n0)) + dn_max;
    m.bounds.F_max = F_max;
    if (!std::isfinite(m.bounds.n_max) || !std::isfinite(m.bounds.F_max))
        return fail("object.index_field: the field's bounds are not finite");
    return true;
}

}  // namespace

// ---- grin_supports ---------------------------------------------------------------------------------

bool grin_supports(const Scene& scene, std::string* why) {
    auto fail = [&](const std::string& m) {
        if (why) *why = m;
        return false;
    };
    const LensSpec& s = scene.object.lens;
    const bool ball = scene.object.type == ObjectType::Sphere || s.ball;
    if (ball) {
        if (!(s.r1 > 0) || !std::isfinite(s.r1) || s.r2 != -s.r1 || s.center_thickness != 2.0 * s.r1 ||
            s.diameter != 2.0 * s.r1)
            return fail("object: a ball must be LensSpec{R, -R, 2R, 2R} with R > 0");
        if (!(s.ior > 1) || !std::isfinite(s.ior)) return fail("object: ior must be > 1");
    } else {
        const double a = 0.5 * s.diameter;
        if (!(s.diameter > 0) || !(s.center_thickness > 0) || !(s.ior > 1) || !std::isfinite(s.ior))
            return fail("object: invalid geometry (diameter, thickness and ior - 1 must be positive)");
        if ((std::isfinite(s.r1) && std::fabs(s.r1) < a) || (std::isfinite(s.r2) && std::fabs(s.r2) < a))
            return fail("object: a face's |R| is smaller than the semi-diameter");
        if (!(s.center_thickness + sag(s.r2, a) - sag(s.r1, a) > 0))
            return fail("object: the edge thickness is not positive");
    }
    const IndexField& f = scene.object.index_field;
    if (f.type != IndexFieldType::Uniform) {
        if (!std::isfinite(f.ior) || f.ior != s.ior)
            return fail("object.index_field: its ior (n at the origin) differs from the object's ior");
        if (!all_finite(f.gradient) || !std::isfinite(f.g)) return fail("object.index_field: non-finite parameter");
        for (double v : f.hessian.m)
            if (!std::isfinite(v)) return fail("object.index_field.hessian: non-finite entry");
        if (f.type == IndexFieldType::QuadraticN2)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < i; ++j)
                    if (f.hessian(i, j) != f.hessian(j, i)) return fail("object.index_field.hessian: not symmetric");
    }
    const auto& D = scene.defects;
    for (size_t k = 0; k < D.size(); ++k) {
        const Defect& d = D[k];
        if (d.type == DefectType::Scratch)
            return fail(defect_key(int(k)) +
                        ": scratches are not supported by the GRIN reference solver (their surfaces are "
                        "cones, planes and tori trimmed against the face; only enclosed bubbles, particles "
                        "and inhomogeneities are modelled)");
        if (d.type == DefectType::Bubble && d.surface_breaking)
            return fail(defect_key(int(k)) +
                        ": a surface-breaking bubble (open pit) is not supported by the GRIN reference "
                        "solver (the face and the bubble are trimmed against each other; only enclosed "
                        "bubbles, particles and inhomogeneities are modelled)");
        if (!(d.semi_axes.x > 0 && d.semi_axes.y > 0 && d.semi_axes.z > 0) || !all_finite(d.semi_axes) ||
            !all_finite(d.center))
            return fail(defect_key(int(k)) + ": non-positive or non-finite size");
        if (d.type == DefectType::Inhomogeneity && !std::isfinite(d.delta_n))
            return fail(defect_key(int(k)) + ": non-finite delta_n");
    }
    // Disjointness, as AnalyticScene: the bounding spheres (radius = largest semi-axis) of two
    // defects must not meet (exact for spheres, conservative for ellipsoids).
    for (size_t i = 0; i < D.size(); ++i)
        for (size_t j = i + 1; j < D.size(); ++j)
            if (distance(D[i].center, D[j].center) <= D[i].max_semi_axis() + D[j].max_semi_axis())
                return fail(defect_key(int(i)) + " and " + defect_key(int(j)) +
                            (D[i].is_sphere() && D[j].is_sphere() ? " overlap"
                                                                  : " may overlap (their bounding spheres intersect)") +
                            ": the GRIN reference solver needs disjoint defects");
    Model m;
    if (!build_model(scene, m, why)) return false;
    if (why) why->clear();
    return true;
}

// ---- the solver ------------------------------------------------------------------------------------

struct State {
    Vec3 r, p;
};

struct GrinReference::Impl {
    Scene scene;
    double tol = 1e-12;
    Model m;
    double size = 1;  // object_size()
    double L = 1;     // length_scale
    double tmin = 0;
    double p_scale = 1;  // the momentum scale of the error norm: max(1, n0)
    double omega = 0;    // phase_rate()
    double z_edge_front = 0, z_edge_back = 0;
    bool absorbing_rim = false;
    std::vector<Surf> surfs;
    std::vector<int> air_ids, glass_ids;
    std::vector<std::vector<int>> own_ids;  // per defect: {3 + K}

    Impl(const Scene& s, const GrinOptions& o);

    // Geometry.
    double z_front(double rho) const { return -0.5 * m.t + sag(m.spec.r1, rho); }
    double z_back(double rho) const { return 0.5 * m.t + sag(m.spec.r2, rho); }
    bool inside_solid(const Vec3& x) const;
    bool on_patch(const Surf& s, const Vec3& x) const;
    Vec3 normal_at(const Surf& s, const Vec3& x) const;
    double sfun(const Surf& s, const Vec3& x) const;
    Vec3 sgrad(const Surf& s, const Vec3& x) const;

    // Media.
    bool curved(const Region& g) const;
    double index(const Region& g, const Vec3& x) const;
    Vec3 force(const Region& g, const Vec3& x) const;
    int smooth_at(const Vec3& x) const;
    Region across(int id, const Region& from, const Vec3& x) const;
    const std::vector<int>& candidates(const Region& g) const;

    // Straight motion.
    bool straight_hit(const Surf& s, const Vec3& o, const Vec3& d, bool starts_on, double& t) const;
    // Curved motion.
    State gbs(const State& y0, const Vec3& F0, double H, const Region& g, double tol_step, double* err) const;
    enum class Cls { Free, Monotone, Unknown };
    double lipschitz(const Region& g) const;
    Cls classify(const Surf& s, const State& y, double h, double F0, double lip) const;
    State locate_root(const State& y0, const Vec3& F0, double h, const Region& g, const Surf& s, double f0, double f1,
                      double tol_step, double& s_out, long& steps) const;

    GrinPath trace(const Vec3& origin, const Vec3& direction, double tol_step, double step_scale) const;
    void finish_display(Path& path, const Vec3& o) const;
};

GrinReference::Impl::Impl(const Scene& s, const GrinOptions& o) : scene(s), tol(o.tolerance) {
    std::string why;
    if (!grin_supports(s, &why)) throw std::invalid_argument("GRIN reference solver: " + why);
    if (!(tol > 0 && tol < 1)) throw std::invalid_argument("GRIN reference solver: the tolerance must be in (0, 1)");
    build_model(s, m, &why);
    size = std::max(m.spec.diameter, m.spec.center_thickness);
    L = validation::length_scale(s);
    // As AnalyticScene: the smallest accepted ray parameter for a surface other than the one the
    // ray starts on, far below any feature (1e-12 L) and far above a vertex's rounding (~u L).
    tmin = 1e-12 * L;
    p_scale = std::max(1.0, m.field.n0);
    omega = m.field.graded ? std::sqrt(m.field.half_hessian_norm()) : 0.0;
    absorbing_rim = s.object.rim == RimFinish::Absorbing;
    z_edge_front = m.ball ? 0.0 : z_front(m.a);
    z_edge_back = m.ball ? 0.0 : z_back(m.a);

    auto cap = [&](const char* name, Role role, double R, double z_vertex) {
        Surf f;
        f.name = name;
        f.role = role;
        if (std::isfinite(R)) {
            // Sphere of radius |R| centred at (0, 0, z_vertex + R) (R > 0: centre at +z of the
            // vertex); the face is its branch through the vertex, sgn(R) (z - zc) <= 0 (see sag).
            f.c = {0.0, 0.0, z_vertex + R};
            f.M = Mat3::identity();
            f.radius = std::fabs(R);
            f.sign = R > 0 ? 1.0 : -1.0;
            f.scale = f.radius + std::fabs(f.c.z) + size;
        } else {
            f.plane = true;
            f.z0 = z_vertex;
            f.scale = std::fabs(z_vertex) + size;
        }
        surfs.push_back(f);
    };
    cap("front", Role::Front, m.spec.r1, -0.5 * m.t);
    cap("back", Role::Back, m.spec.r2, 0.5 * m.t);
    Surf rim;
    rim.name = "rim";
    rim.role = Role::Rim;
    rim.M = Mat3::identity();
    rim.M(2, 2) = 0.0;
    rim.radius = m.a;
    rim.scale = m.a + size;
    surfs.push_back(rim);
    for (size_t k = 0; k < s.defects.size(); ++k) {
        const Defect& d = s.defects[k];
        Surf e;
        e.defect = int(k);
        if (d.type == DefectType::Particle) {
            e.role = Role::Particle;
            e.name = "particle " + std::to_string(k);
        } else if (d.type == DefectType::Bubble) {
            e.role = Role::Bubble;
            e.name = "bubble " + std::to_string(k);
        } else {
            e.role = d.index_profile == IndexProfile::Uniform ? Role::Uniform : Role::Seam;
            e.name = "inhomogeneity " + std::to_string(k);
        }
        e.c = d.center;
        if (d.is_sphere()) {
            e.M = Mat3::identity();
            e.radius = d.semi_axes.x;
            e.m_norm = 1.0;
        } else {
            // { x : |M (x - c)| = 1 }, M = S^-1 F^T (row i = f_i / s_i), ||M||_2 = 1 / s_min.
            const double sa[3] = {d.semi_axes.x, d.semi_axes.y, d.semi_axes.z};
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) e.M(i, j) = d.frame(j, i) / sa[i];
            e.radius = 1.0;
            e.m_norm = 1.0 / std::min({sa[0], sa[1], sa[2]});
        }
        e.scale = e.radius + e.m_norm * (length(e.c) + size);
        surfs.push_back(e);
    }
    // The surfaces bounding each medium: air sees the object's outer surfaces (the defects lie
    // inside the glass; a ball's rim has no height and is left out), glass sees those and every
    // defect (the smooth inhomogeneities' seams included), a defect's interior only its own.
    air_ids = {0, 1};
    if (!m.ball) air_ids.push_back(2);
    glass_ids = air_ids;
    for (size_t k = 0; k < s.defects.size(); ++k) {
        glass_ids.push_back(3 + int(k));
        own_ids.push_back({3 + int(k)});
    }
}

bool GrinReference::Impl::inside_solid(const Vec3& x) const {
    if (m.ball) return length(x) < m.a;
    const double rho = std::hypot(x.x, x.y);
    return rho < m.a && x.z > z_front(rho) && x.z < z_back(rho);
}

bool GrinReference::Impl::on_patch(const Surf& s, const Vec3& x) const {
    // AnalyticScene's patches, with its relative slack of 1e-12 that closes the edge seams: a cap
    // within rho <= a on its branch, the rim between the edge heights, every defect whole.
    const double rho2 = x.x * x.x + x.y * x.y;
    switch (s.role) {
        case Role::Front:
        case Role::Back:
            if (s.plane) return rho2 <= m.a * m.a * (1.0 + 1e-12);
            return rho2 <= m.a * m.a * (1.0 + 1e-12) && s.sign * (x.z - s.c.z) <= 1e-12 * s.radius;
        case Role::Rim:
            return !m.ball && x.z >= z_edge_front - 1e-12 * L && x.z <= z_edge_back + 1e-12 * L;
        default:
            return true;
    }
}

Vec3 GrinReference::Impl::normal_at(const Surf& s, const Vec3& x) const {
    // The gradient of |M (x - c)|^2 is 2 M^T M (x - c): normal to the level set (the radius vector
    // of a sphere, the horizontal radial direction of the rim); a plane's normal is +z.
    if (s.plane) return {0.0, 0.0, 1.0};
    return normalize(s.M.transposed() * (s.M * (x - s.c)));
}

// The surface function f (negative on the side of the plane's -z, inside the quadric) and its
// gradient, for event location: f = z - z0, or f = |M (x - c)| - radius (a distance in mm for
// spheres and the rim; for an ellipsoid in body units). Written as a norm minus the radius
// rather than |.|^2 - radius^2 so that its rounding, ~u (radius + |M (x - c)|), does not grow with
// the square of the magnitudes. grad f = M^T M (x - c) / |M (x - c)|.
double GrinReference::Impl::sfun(const Surf& s, const Vec3& x) const {
    if (s.plane) return x.z - s.z0;
    return length(s.M * (x - s.c)) - s.radius;
}
Vec3 GrinReference::Impl::sgrad(const Surf& s, const Vec3& x) const {
    if (s.plane) return {0.0, 0.0, 1.0};
    const Vec3 y = s.M * (x - s.c);
    const double l = length(y);
    return l > 0 ? s.M.transposed() * y / l : Vec3{};
}

bool GrinReference::Impl::curved(const Region& g) const {
    if (g.med == Med::Glass) return m.field.graded || g.smooth >= 0;
    if (g.med == Med::Inclusion) return m.field.graded;
    return false;
}

double GrinReference::Impl::index(const Region& g, const Vec3& x) const {
    switch (g.med) {
        case Med::Glass: {
            double n = m.field.n(x);
            if (g.smooth >= 0) {
                double D;
                Vec3 gD;
                m.incl[m.incl_of[g.smooth]].profile(x, D, gD);
                n += D;
            }
            return n;
        }
        case Med::Inclusion:
            return m.field.n(x) + m.incl[m.incl_of[g.defect]].dn;
        default:
            return 1.0;
    }
}

// dp/dtau = grad(n^2) / 2 = n grad n in the region:
//   glass:                  grad(n_b^2) / 2;
//   in a smooth inclusion:  n = n_b + D, n grad n = (n_b + D)(grad n_b + grad D),
//                           grad n_b = grad(n_b^2) / (2 n_b) (0 for uniform glass);
//   a uniform inclusion:    n = n_b + dn, n grad n = (n_b + dn) grad n_b
//                           = (1 + dn / n_b) grad(n_b^2) / 2.
Vec3 GrinReference::Impl::force(const Region& g, const Vec3& x) const {
    const Field& F = m.field;
    if (g.med == Med::Glass) {
        if (g.smooth < 0) return F.half_grad_n2(x);
        const Inclusion& in = m.incl[m.incl_of[g.smooth]];
        double D;
        Vec3 gD;
        in.profile(x, D, gD);
        if (!F.graded) return gD * (F.n0 + D);
        const double nb = F.n(x);
        const Vec3 gnb = F.half_grad_n2(x) / nb;
        return (gnb + gD) * (nb + D);
    }
    if (g.med == Med::Inclusion) {
        const Inclusion& in = m.incl[m.incl_of[g.defect]];
        return F.half_grad_n2(x) * (1.0 + in.dn / F.n(x));
    }
    return {};
}

int GrinReference::Impl::smooth_at(const Vec3& x) const {
    for (size_t k = 0; k < m.incl_of.size(); ++k) {
        const int i = m.incl_of[k];
        if (i >= 0 && m.incl[i].smooth && m.incl[i].rho2(x) < 1.0) return int(k);
    }
    return -1;
}

Region GrinReference::Impl::across(int id, const Region& from, const Vec3& x) const {
    const Surf& s = surfs[id];
    Region to;
    switch (s.role) {
        case Role::Front:
        case Role::Back:
        case Role::Rim:
            if (from.med == Med::Air) {
                to.med = Med::Glass;
                to.smooth = smooth_at(x);
            }
            return to;
        case Role::Seam:
            to = from;
            to.smooth = from.smooth == s.defect ? -1 : s.defect;
            return to;
        default:
            if (from.med == Med::Glass) {
                to.med = s.role == Role::Bubble     ? Med::Bubble
                         : s.role == Role::Particle ? Med::Particle
                                                    : Med::Inclusion;
                to.defect = s.defect;
            } else {
                to.med = Med::Glass;
                to.smooth = smooth_at(x);
            }
            return to;
    }
}

const std::vector<int>& GrinReference::Impl::candidates(const Region& g) const {
    // A defect's interior is bounded by its own surface only (defects are disjoint).
    if (g.med == Med::Air) return air_ids;
    if (g.med == Med::Glass) return glass_ids;
    return own_ids[g.defect];
}

// ---- straight motion: exact ray-quadric intersection ---------------------------------------------
//
// Along o + t d, the quadric |M (x - c)| = r reads |O + t D|^2 = r^2 with O = M (o - c), D = M d
// (M linear, so t is the same parameter in both frames): A t^2 + 2 b t + C = 0 with A = D.D,
// b = O.D, C = |O|^2 - r^2. Its reduced discriminant in the cancellation-free geometric form
// (Pythagoras: |O|^2 = |w|^2 + b^2 / A for the foot w = O - (b / A) D of the perpendicular from
// the centre onto the line): b^2 - A C = A (r^2 - |w|^2) = A (r - |w|)(r + |w|), and
// C = (|O| - r)(|O| + r). A ray starting ON the surface has the root 0 exactly; Vieta
// (t1 + t2 = -2 b / A) gives the other root without the tiny rounded one. A plane z = z0:
// t = (z0 - o.z) / d.z, never met twice in a row.
bool GrinReference::Impl::straight_hit(const Surf& s, const Vec3& o, const Vec3& d, bool starts_on,
                                       double& t_out) const {
    double lo = 0, hi = 0;
    if (s.plane) {
        if (starts_on || d.z == 0.0) return false;
        lo = hi = (s.z0 - o.z) / d.z;
    } else {
        const Vec3 O = s.M * (o - s.c), D = s.M * d;
        const double A = dot(D, D);
        if (!(A > 0.0)) return false;
        const double b = dot(O, D);
        if (starts_on) {
            lo = hi = -2.0 * b / A;
        } else {
            const double wl = length(O - D * (b / A));
            const double ol = length(O);
            const double disc = A * ((s.radius - wl) * (s.radius + wl));
            const double C = (ol - s.radius) * (ol + s.radius);
            if (!stable_roots(A, b, C, disc, lo, hi)) return false;
        }
    }
    for (double t : {lo, hi}) {
        if (!(t > tmin)) continue;
        if (!on_patch(s, o + d * t)) continue;
        t_out = t;
        return true;
    }
    return false;
}

// ---- curved motion: Gragg-Bulirsch-Stoer ----------------------------------------------------------
//
// The system y' = f(y), y = (r, p), f = (p, F(r)), F = grad(n^2) / 2, is smooth (analytic for the
// quadric fields) within a region: the seams of the smooth inhomogeneities, where F is only
// continuous, end every step (see "Seams"). Gragg's modified midpoint rule with n (even) substeps
// of h = H / n,
//   z_0 = y0,  z_1 = z_0 + h f(z_0),  z_{m+1} = z_{m-1} + 2 h f(z_m)  (m = 1 .. n - 1),
//   S(h) = (z_{n-1} + z_n + h f(z_n)) / 2      (Gragg's smoothing),
// has an asymptotic error expansion in even powers of h (W. B. Gragg, SIAM J. Numer. Anal. 2, 1965;
// Hairer, Norsett, Wanner, Solving ODEs I, 2nd ed., Sec. II.9), so Richardson extrapolation to
// h = 0 by the Aitken-Neville scheme in h^2 (ibid., Sec. II.9),
//   T_{j,1} = S(H / n_j),  T_{j,i+1} = T_{j,i} + (T_{j,i} - T_{j-1,i}) / ((n_j / n_{j-i})^2 - 1),
// gives T_{j,j} of order 2j. With the sequence n_j = 2j (Deuflhard's), j = 1 .. 8, a step costs
// 1 + sum n_j = 73 evaluations of F and T_{8,8} has order 16; |T_{8,8} - T_{8,7}| estimates the
// local error of T_{8,7} (order 14), which bounds that of the more accurate T_{8,8} that is kept
// (local extrapolation, ibid. Sec. II.4 and II.9).
//
// Rounding: the scheme runs on the increments z_m - y0 (never on y0 + small), so their rounding
// is relative to the increment |z_m - y0| <= |p| H, not to |y0|; the error estimate's rounding
// noise therefore shrinks with the step, and a tolerance near the unit roundoff is reached by
// smaller steps instead of stalling.
//
// Step-size control (ibid. Sec. II.4): err = max(|e_r|_inf / (tol size), |e_p|_inf / (tol p_scale))
// with e the estimate above; a step is accepted when err <= 1, and the next step is
// H 0.9 err^(-1/15) (the estimate is O(H^15)), its growth limited to 4x per step and its
// reduction after a rejection to 0.2x.
State GrinReference::Impl::gbs(const State& y0, const Vec3& F0, double H, const Region& g, double tol_step,
                               double* err) const {
    constexpr int K = 8;
    using V6 = std::array<double, 6>;
    V6 T[K][K];
    for (int j = 0; j < K; ++j) {
        const int n = 2 * (j + 1);
        const double h = H / n;
        Vec3 dr0, dp0;                      // z_{m-1} - y0
        Vec3 dr1 = y0.p * h, dp1 = F0 * h;  // z_m - y0, m = 1
        for (int s = 1; s < n; ++s) {
            const Vec3 pm = y0.p + dp1;
            const Vec3 Fm = force(g, y0.r + dr1);
            const Vec3 dr2 = dr0 + pm * (2.0 * h), dp2 = dp0 + Fm * (2.0 * h);
            dr0 = dr1;
            dp0 = dp1;
            dr1 = dr2;
            dp1 = dp2;
        }
        const Vec3 pn = y0.p + dp1;
        const Vec3 Fn = force(g, y0.r + dr1);
        const Vec3 Sr = (dr0 + dr1 + pn * h) * 0.5, Sp = (dp0 + dp1 + Fn * h) * 0.5;
        T[j][0] = {Sr.x, Sr.y, Sr.z, Sp.x, Sp.y, Sp.z};
        for (int i = 1; i <= j; ++i) {
            const double ratio = double(n) / double(2 * (j - i + 1));
            const double den = ratio * ratio - 1.0;
            for (int c = 0; c < 6; ++c) T[j][i][c] = T[j][i - 1][c] + (T[j][i - 1][c] - T[j - 1][i - 1][c]) / den;
        }
    }
    const V6& best = T[K - 1][K - 1];
    if (err) {
        const V6& prev = T[K - 1][K - 2];
        double er = 0, ep = 0;
        for (int c = 0; c < 3; ++c) er = std::max(er, std::fabs(best[c] - prev[c]));
        for (int c = 3; c < 6; ++c) ep = std::max(ep, std::fabs(best[c] - prev[c]));
        *err = std::max(er / (tol_step * size), ep / (tol_step * p_scale));
    }
    return {y0.r + Vec3{best[0], best[1], best[2]}, y0.p + Vec3{best[3], best[4], best[5]}};
}

// ---- Event location ---------------------------------------------------------------------------------
//
// A crossing of a surface within a step [0, h] is a root of g(tau) = f(r(tau)). Before a step is
// taken, each surface bounding the medium is classified from the start state (r0, p0) and h
// alone, by bounds that hold for the exact path of the field:
//   |dp/dtau| = |F(r(tau))| <= f(tau) := min(F_max, |F(r0)| + lip n_max tau)
//     (|r(tau) - r0| <= n_max tau since |dr/dtau| = |p| = n <= n_max; lip: see Bounds), so
//   |p(tau) - p0| <= int_0^tau f <= min(F_max tau, |F(r0)| tau + lip n_max tau^2 / 2) =: eps(tau),
//   r(tau) - r0 - p0 tau = int_0^tau (p(s) - p0) ds  =>
//   |r(tau) - (r0 + p0 tau)| <= int_0^tau eps
//                            <= min(F_max tau^2 / 2, |F(r0)| tau^2 / 2 + lip n_max tau^3 / 6) =: delta(tau),
// both increasing in tau, so over the step the path lies in the tube of radius delta = delta(h)
// around the segment S = {r0 + p0 tau, 0 <= tau <= h}, and its momentum within eps = eps(h) of p0.
// (The bounds hold on the ball |x| <= 2 Rx, which the path cannot leave: it moves at most
// n_max h <= Rx; see Bounds.)
//   FREE: the tube does not meet the surface, so g has no root in [0, h]. In body coordinates
//     y = M (x - c) the tube maps into the tube of radius m_norm delta around M (S - c); the
//     quadric |y| = radius is missed iff max_S |y| + m_norm delta < radius or
//     min_S |y| - m_norm delta > radius (min: the foot of the perpendicular from the origin,
//     clamped to S; max: at an end of S, |y| being convex along S). A plane z = z0: the tube's z
//     range misses z0.
//   MONOTONE: g is strictly monotone on [0, h], so it has at most one root there. For the quadric,
//     d(|y|^2)/dtau / 2 = y . (M p) = (q + M e).(P + M e') with q(tau) = M (r0 + p0 tau - c) (the
//     segment), P = M p0, |M e| <= m_norm delta, |M e'| <= m_norm eps:
//       q.P is linear in tau, from v0 = q(0).P to v1 = q(h).P;
//       the rest is at most |q|max m_norm eps + m_norm delta |P| + m_norm^2 delta eps,
//     so the derivative keeps the sign of v0 if v0 and v1 have the same sign and
//     min(|v0|, |v1|) exceeds that bound. A plane: dg/dtau = p_z, monotone if |p0_z| > eps.
//   otherwise UNKNOWN, and the step is halved before it is taken (the tests only get easier as
//     h shrinks: delta = O(h^2), eps = O(h), the segment O(h)).
// After an accepted step, a surface that is not FREE has a root in [0, h] iff g changes sign
// between the step's ends (one root at most), and the root is bracketed. The surface the state
// starts on (g(0) = 0) must be MONOTONE: its only root is then the departure at tau = 0. The roots
// of all surfaces are located, sorted, and the first one on its surface's patch (AnalyticScene's
// patches) ends the segment; a root off the patch (a cap's sphere beyond its edge) is passed, and
// no second root of that surface can follow within the step. So no crossing is missed, up to the
// accuracy of the integration itself (a path within ~tol of a tangency is ill-conditioned anyway,
// see sensitivity()).
// The only exception is a step that reaches the floor h_floor (path length 1e-9 x the object
// size) while still UNKNOWN: the path then runs within ~(n_max h_floor) of a surface it is
// tangent to, and the step is taken with the sign test alone. Any double crossing it could hide
// dips into the surface by at most the relative curvature times (n_max h_floor)^2 / 8, ~1e-19 of
// the object size for the scenes here, far below rounding.
double GrinReference::Impl::lipschitz(const Region& g) const {
    if (g.med == Med::Glass) return g.smooth < 0 ? m.bounds.lip_glass : m.incl[m.incl_of[g.smooth]].lip;
    if (g.med == Med::Inclusion) return m.incl[m.incl_of[g.defect]].lip;
    return 0.0;
}

GrinReference::Impl::Cls GrinReference::Impl::classify(const Surf& s, const State& y, double h, double F0,
                                                       double lip) const {
    const double Fm = m.bounds.F_max, ln = lip * m.bounds.n_max;
    const double eps = std::min(Fm * h, F0 * h + 0.5 * ln * h * h);
    const double delta = std::min(0.5 * Fm * h * h, 0.5 * F0 * h * h + ln * h * h * h / 6.0);
    if (s.plane) {
        const double z1 = y.r.z + y.p.z * h;
        const double zl = std::min(y.r.z, z1), zh = std::max(y.r.z, z1);
        if (zh + delta < s.z0 || zl - delta > s.z0) return Cls::Free;
        if (std::fabs(y.p.z) > eps) return Cls::Monotone;
        return Cls::Unknown;
    }
    const Vec3 q0 = s.M * (y.r - s.c), P = s.M * y.p;
    const Vec3 q1 = q0 + P * h;
    const double l0 = length(q0), l1 = length(q1);
    const double PP = dot(P, P);
    // Closest point of the segment q0 + P tau (0 <= tau <= h) to the origin.
    double tc = PP > 0 ? -dot(q0, P) / PP : 0.0;
    tc = std::clamp(tc, 0.0, h);
    const double lmin = length(q0 + P * tc), lmax = std::max(l0, l1);
    const double mt = s.m_norm * delta;
    if (lmax + mt < s.radius || lmin - mt > s.radius) return Cls::Free;
    const double v0 = dot(q0, P), v1 = dot(q1, P);
    if ((v0 > 0 && v1 > 0) || (v0 < 0 && v1 < 0)) {
        const double pert =
            lmax * s.m_norm * eps + s.m_norm * delta * std::sqrt(PP) + s.m_norm * s.m_norm * delta * eps;
        if (std::min(std::fabs(v0), std::fabs(v1)) > pert) return Cls::Monotone;
    }
    return Cls::Unknown;
}

// The bracketed root of phi(s) = f(r(s)) on (0, h), r(s) the integrator's step of length s from y0
// (re-integration: a step shorter than the accepted h is at least as accurate, its error being
// O(s^17)). Safeguarded Newton: phi'(s) = grad f . dr/ds = grad f . p(s); a Newton iterate that
// leaves the bracket is replaced by the bracket's midpoint, and the bracket shrinks every
// iteration. The root is polished to full precision, whatever the tolerance: it stops when the
// correction is below the rounding of f (64 u scale / |phi'|, scale the magnitude of f's operands),
// where a further iteration would only move the root by noise, so the vertex carries the
// integration's error only, not the root finder's. (Newton converges quadratically, so this costs
// one or two re-steps more than a looser stop.)
State GrinReference::Impl::locate_root(const State& y0, const Vec3& F0, double h, const Region& g, const Surf& s,
                                       double f0, double f1, double tol_step, double& s_out, long& steps) const {
    double a = 0, b = h, fa = f0;
    double x = h * f0 / (f0 - f1);  // regula falsi start
    if (!(x > 0 && x < h)) x = 0.5 * h;
    State yx = y0;
    for (int it = 0; it < 60; ++it) {
        yx = gbs(y0, F0, x, g, tol_step, nullptr);
        ++steps;
        const double fx = sfun(s, yx.r);
        if (fx == 0.0) break;
        if ((fx < 0) == (fa < 0)) {
            a = x;
            fa = fx;
        } else {
            b = x;
        }
        const double dfx = dot(sgrad(s, yx.r), yx.p);
        double xn = dfx != 0.0 ? x - fx / dfx : 0.5 * (a + b);
        if (!(xn > a && xn < b)) xn = 0.5 * (a + b);
        const double resolution = 64.0 * kU * s.scale / std::fabs(dfx);
        if (std::fabs(xn - x) <= resolution || (b - a) <= resolution) break;
        x = xn;
    }
    s_out = x;
    return yx;
}

void GrinReference::Impl::finish_display(Path& path, const Vec3& o) const {
    // AnalyticScene::finish_display: a path that ends in air heading to +z (not absorbed,
    // truncated or lost) meets the display plane z = Z at t = (Z - o.z) / d.z; pixel column
    // q = floor((x + W/2) / (W/Q)) from -x, row p = floor((H/2 - y) / (H/P)) from +y down,
    // clamped to the last index on the far edges.
    const Vec3& d = path.direction;
    if (path.absorbed || path.truncated || path.lost || !(d.z > 0.0)) return;
    const DisplayDesc& disp = scene.display;
    const double t = (disp.z - o.z) / d.z;
    if (!(t >= 0.0)) return;
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

// ---- the principal path -------------------------------------------------------------------------------
//
// Seams: a smooth inhomogeneity's ellipsoid rho = 1 is an event like a surface, but nothing
// happens there (n and grad n are continuous): the state is kept and the region switches (into or
// out of the inhomogeneity), so that every integration step sees an analytic F (the profile's
// second derivatives jump at rho = 1, which would cost a high-order method its order within a
// step across it). In uniform glass the ray is straight outside the inhomogeneities and integrated
// only inside them.
//
// At an interface, n1 = n of the current region at the hit, n2 = n of the region across it, at
// the same point; the direction is p / |p| and interact() gives the refracted or (TIR) reflected
// unit direction d'; the new momentum is n d' with n of the medium the ray continues in.
GrinPath GrinReference::Impl::trace(const Vec3& origin, const Vec3& direction, double tol_step,
                                    double step_scale) const {
    GrinPath out;
    Path& path = out.path;
    Region reg;
    State y{origin, normalize(direction)};  // in air, p = 1 x the unit direction
    int last = -1;
    int interactions = 0;
    long steps = 0;
    double h_next = 0;  // the controller's proposal, carried across events
    bool seg_curved = false;
    double seg_tau = 0;
    const double hfloor = 1e-9 * size / m.bounds.n_max;
    std::vector<Cls> cls;
    struct Root {
        double s;
        int id;
        State y;
    };
    std::vector<Root> roots;
    for (;;) {
        // ---- one leg: from y to the next event (a surface or seam) in region reg ----
        int hit = -1;
        State yh;
        if (!curved(reg)) {
            const Vec3 d = normalize(y.p);
            double best = kInf;
            for (int id : candidates(reg)) {
                double t;
                if (straight_hit(surfs[id], y.r, d, id == last, t) && t < best) {
                    best = t;
                    hit = id;
                }
            }
            if (hit >= 0) yh = {y.r + d * best, y.p};
        } else {
            seg_curved = true;
            const std::vector<int>& ids = candidates(reg);
            cls.resize(ids.size());
            // A step keeps the path in the ball the bounds hold on (see Bounds): n_max h <= Rx in the
            // glass, <= s_max inside a uniform inclusion. And sqrt(lip) h <= 1/2: the linearised flow
            // (d r)'' = DF d r, ||DF|| <= lip, then amplifies an error made within a step by at most
            // cosh(1/2) + sinh(1/2) / (1/2) < 1.2 (ValidationTolerance.h counts the rounding with it).
            const double reach = reg.med == Med::Inclusion ? m.incl[m.incl_of[reg.defect]].s_max : m.bounds.Rx;
            const double lip = lipschitz(reg);
            const double hmax = std::min(reach / m.bounds.n_max, lip > 0 ? 0.5 / std::sqrt(lip) : kInf);
            double h = h_next > 0 ? std::min(h_next, hmax) : std::min(hmax, 0.25 * size / p_scale);
            int on = last;
            bool lost = false;
            for (;;) {
                if (steps > kMaxSteps) {
                    lost = true;
                    break;
                }
                h = std::min(h, hmax);
                const Vec3 F0 = force(reg, y.r);
                const double F0n = length(F0);
                for (;;) {
                    bool ok = true;
                    for (size_t i = 0; i < ids.size(); ++i) {
                        cls[i] = classify(surfs[ids[i]], y, h, F0n, lip);
                        if (cls[i] == Cls::Unknown || (ids[i] == on && cls[i] != Cls::Monotone)) ok = false;
                    }
                    if (ok || h <= hfloor) break;
                    h = std::max(0.5 * h, hfloor);
                }
                // A shorter step than the classification allows is allowed too (the tests only get
                // easier as h shrinks): estimate_error's second trace uses this.
                h = std::max(h * step_scale, std::min(h, hfloor));
                double err = 0;
                const State y1 = gbs(y, F0, h, reg, tol_step, &err);
                ++steps;
                if (std::isnan(err)) {
                    lost = true;
                    break;
                }
                if (err > 1.0 && h > hfloor) {
                    h = std::max(hfloor, h * std::clamp(0.9 * std::pow(err, -1.0 / 15.0), 0.2, 0.9));
                    continue;
                }
                roots.clear();
                for (size_t i = 0; i < ids.size(); ++i) {
                    const int id = ids[i];
                    if (id == on || cls[i] == Cls::Free) continue;
                    const Surf& s = surfs[id];
                    const double f0 = sfun(s, y.r), f1 = sfun(s, y1.r);
                    if ((f0 < 0) == (f1 < 0)) continue;
                    double sr;
                    const State ys = locate_root(y, F0, h, reg, s, f0, f1, tol_step, sr, steps);
                    // A root at the start (the state lies on this surface too: an edge seam) is the
                    // departure, not a crossing; AnalyticScene's tmin likewise.
                    if (length(y.p) * sr <= tmin) continue;
                    roots.push_back({sr, id, ys});
                }
                std::sort(roots.begin(), roots.end(), [](const Root& u, const Root& v) { return u.s < v.s; });
                for (const Root& r : roots)
                    if (on_patch(surfs[r.id], r.y.r)) {
                        hit = r.id;
                        yh = r.y;
                        seg_tau += r.s;
                        out.integrated_length += distance(yh.r, y.r);
                        out.integrated_turn += distance(yh.p, y.p);
                        out.min_index = std::min(out.min_index, length(yh.p));
                        break;
                    }
                const double grow = err > 0 ? std::clamp(0.9 * std::pow(err, -1.0 / 15.0), 0.2, 4.0) : 4.0;
                h_next = h * grow;
                if (hit >= 0) break;
                out.integrated_length += distance(y1.r, y.r);
                out.integrated_turn += distance(y1.p, y.p);
                out.min_index = std::min({out.min_index, length(y.p), length(y1.p)});
                y = y1;
                seg_tau += h;
                on = -1;
                h = h_next;
            }
            if (lost) {
                path.lost = true;
                break;
            }
        }
        if (hit < 0) {
            if (reg.med != Med::Air) path.lost = true;  // a closed medium must have an exit
            break;
        }
        const Surf& s = surfs[hit];
        if (s.role == Role::Seam) {
            reg = across(hit, reg, yh.r);
            y = yh;
            last = hit;
            continue;
        }
        if (interactions == kMaxInteractions) {
            path.truncated = true;
            break;
        }
        ++interactions;
        y = yh;
        const Vec3 d_in = normalize(y.p);
        const Vec3 N = normal_at(s, y.r);
        path.vertices.push_back(y.r);
        path.surfaces.push_back(s.name);
        path.surface_ids.push_back(hit);
        if (seg_curved) {
            ++out.curved_segments;
            out.max_phase = std::max(out.max_phase, omega * seg_tau);
            out.min_cos_incidence = std::min(out.min_cos_incidence, std::fabs(dot(d_in, N)));
        }
        seg_curved = false;
        seg_tau = 0;
        if (s.role == Role::Particle || (s.role == Role::Rim && absorbing_rim)) {
            path.absorbed = true;
            path.events.push_back(Event::Absorbed);
            path.directions.push_back(d_in);
            break;
        }
        const Region other = across(hit, reg, y.r);
        const double n1 = index(reg, y.r), n2 = index(other, y.r);
        const Interaction in = interact(d_in, N, n1, n2);
        if (in.tir) {
            ++path.tir_count;
            path.events.push_back(Event::TotalInternalReflection);
            y.p = in.direction * n1;
        } else {
            path.transmission *= 1.0 - in.R;
            path.events.push_back(Event::Transmitted);
            reg = other;
            y.p = in.direction * n2;
        }
        path.directions.push_back(in.direction);
        last = hit;
    }
    if (seg_curved) {
        ++out.curved_segments;
        out.max_phase = std::max(out.max_phase, omega * seg_tau);
    }
    out.steps = int(std::min<long>(steps, std::numeric_limits<int>::max()));
    path.direction = normalize(y.p);
    finish_display(path, y.r);
    return out;
}

// ---- the public interface -------------------------------------------------------------------------------

GrinReference::GrinReference(const Scene& scene, const GrinOptions& options)
    : impl_(std::make_shared<const Impl>(scene, options)) {}

const Scene& GrinReference::scene() const { return impl_->scene; }
double GrinReference::tolerance() const { return impl_->tol; }
double GrinReference::object_size() const { return impl_->size; }
double GrinReference::length_scale() const { return impl_->L; }
double GrinReference::phase_rate() const { return impl_->omega; }
int GrinReference::surface_count() const { return int(impl_->surfs.size()); }
const std::string& GrinReference::surface_name(int id) const { return impl_->surfs.at(id).name; }

double GrinReference::glass_index(const Vec3& x) const {
    const Impl& I = *impl_;
    double n = I.m.field.n(x);
    for (const Inclusion& in : I.m.incl) {
        if (in.smooth) {
            double D;
            Vec3 gD;
            in.profile(x, D, gD);
            n += D;
        } else if (in.rho2(x) < 1.0) {
            n += in.dn;
        }
    }
    return n;
}

GrinPath GrinReference::trace(const Vec3& origin, const Vec3& direction) const {
    if (impl_->inside_solid(origin)) throw std::invalid_argument("GrinReference: the origin is not in air");
    return impl_->trace(origin, direction, impl_->tol, 1.0);
}

Path GrinReference::principal_path(const Vec3& origin, const Vec3& direction) const {
    return trace(origin, direction).path;
}

namespace {

bool same_shape(const Path& a, const Path& b) {
    return a.surface_ids == b.surface_ids && a.events == b.events && a.absorbed == b.absorbed &&
           a.truncated == b.truncated && a.lost == b.lost && a.display_hit == b.display_hit;
}

// The largest position change (vertices and display hit) and the final-direction change between
// two paths of the same shape.
void path_diffs(const Path& a, const Path& b, double& dpos, double& ddir) {
    dpos = 0;
    for (size_t i = 0; i < a.vertices.size(); ++i) dpos = std::max(dpos, distance(a.vertices[i], b.vertices[i]));
    if (a.display_hit) dpos = std::max(dpos, std::hypot(a.display_x - b.display_x, a.display_y - b.display_y));
    ddir = std::atan2(length(cross(a.direction, b.direction)), dot(a.direction, b.direction));
}

}  // namespace

PathError GrinReference::estimate_error(const Vec3& origin, const Vec3& direction) const {
    if (impl_->inside_solid(origin)) throw std::invalid_argument("GrinReference: the origin is not in air");
    const Path coarse = impl_->trace(origin, direction, impl_->tol, 1.0).path;
    const Path fine = impl_->trace(origin, direction, impl_->tol / kErrorEstimateRatio, 0.5).path;
    PathError e;
    if (!same_shape(coarse, fine)) {
        e.comparable = false;
        e.position = e.direction = kInf;
        return e;
    }
    path_diffs(coarse, fine, e.position, e.direction);
    return e;
}

RaySensitivity GrinReference::sensitivity(const Vec3& origin, const Vec3& direction) const {
    // AnalyticScene::sensitivity's central finite differences (ValidationTolerance.h): the origin
    // moved by +-h = kSensitivityRelativeStep a along the two unit vectors perpendicular to the
    // ray, the direction turned by +-eta = kSensitivityRelativeStep about the same axes. The
    // integration's own error (~tol size, not smooth in the start) adds ~tol size / h ~ 1e-5 to
    // kappa at the default tolerance: negligible for its meaning as an order of magnitude.
    const Impl& I = *impl_;
    RaySensitivity out;
    const Vec3 d = normalize(direction);
    const Path p0 = principal_path(origin, d);
    out.interfaces = static_cast<int>(p0.vertices.size());
    Vec3 e1, e2;
    orthonormal_basis(d, e1, e2);
    const double h = kSensitivityRelativeStep * I.m.a;
    const double eta = kSensitivityRelativeStep;
    for (const Vec3& e : {e1, e2}) {
        {
            const Vec3 op = origin + e * h, om = origin - e * h;
            if (I.inside_solid(op) || I.inside_solid(om)) {
                out.stable = false;
            } else {
                const Path pp = I.trace(op, d, I.tol, 1.0).path, pm = I.trace(om, d, I.tol, 1.0).path;
                if (!same_shape(pp, p0) || !same_shape(pm, p0)) {
                    out.stable = false;
                } else {
                    double dp, dd;
                    path_diffs(pp, pm, dp, dd);
                    out.kappa = std::max(out.kappa, dp / (2 * h));
                    out.kappa_dir = std::max(out.kappa_dir, dd * I.L / (2 * h));
                }
            }
        }
        {
            const Path pp = I.trace(origin, normalize(d + e * eta), I.tol, 1.0).path;
            const Path pm = I.trace(origin, normalize(d - e * eta), I.tol, 1.0).path;
            if (!same_shape(pp, p0) || !same_shape(pm, p0)) {
                out.stable = false;
            } else {
                double dp, dd;
                path_diffs(pp, pm, dp, dd);
                const double angle = 2 * std::atan(eta);
                out.kappa = std::max(out.kappa, dp / (angle * I.L));
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
