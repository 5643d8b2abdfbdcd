#include "geometry/IndexField.h"

#include <Eigen/Dense>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

namespace ltm {

const char* to_string(IndexFieldType t) {
    switch (t) {
        case IndexFieldType::Uniform: return "uniform";
        case IndexFieldType::LinearN2: return "linear_n2";
        case IndexFieldType::RadialN2: return "radial_n2";
        case IndexFieldType::SphericalN2: return "spherical_n2";
        case IndexFieldType::QuadraticN2: return "quadratic_n2";
        case IndexFieldType::LinearN: return "linear_n";
    }
    return "unknown";
}

QuadraticForm IndexField::n2_form() const {
    QuadraticForm f;
    f.c = ior * ior;
    switch (type) {
        case IndexFieldType::Uniform: break;
        case IndexFieldType::LinearN2: f.b = gradient; break;
        case IndexFieldType::RadialN2: {
            const double k = -2.0 * ior * ior * g * g;
            f.H = Mat3{{k, 0, 0, 0, k, 0, 0, 0, 0}};
            break;
        }
        case IndexFieldType::SphericalN2: f.H = Mat3::identity() * (-2.0 * ior * ior * g * g); break;
        case IndexFieldType::QuadraticN2:
            f.b = gradient;
            f.H = hessian;
            break;
        case IndexFieldType::LinearN:
            throw std::logic_error("IndexField::n2_form: linear_n has no closed-form quadratic n^2");
    }
    return f;
}

// linear_n defines n itself, n = ior + gradient . x, so n2 is its square and grad n^2 = 2 n gradient.
// For the closed-form kinds n = sqrt(n^2), taken as 0 where n^2 <= 0: such a field is not a glass
// (index_field_problems rejects it) and the tracer never evaluates one.
double IndexField::n2(const Vec3& x) const {
    if (type == IndexFieldType::LinearN) {
        const double v = ior + dot(gradient, x);
        return v * v;
    }
    return n2_form()(x);
}

double IndexField::n(const Vec3& x) const {
    if (type == IndexFieldType::LinearN) return ior + dot(gradient, x);
    return std::sqrt(std::fmax(n2(x), 0.0));
}

Vec3 IndexField::grad_n2(const Vec3& x) const {
    if (type == IndexFieldType::LinearN) return gradient * (2.0 * n(x));
    return n2_form().gradient(x);
}

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

template <int N>
using VecN = Eigen::Matrix<double, N, 1>;
template <int N>
using MatN = Eigen::Matrix<double, N, N>;

// The running minimum and maximum of q over candidate points, each a point of the solid (up to the
// rounding of its coordinates), valued by q itself.
struct Extremes {
    const QuadraticForm& q;
    QuadraticRange r;
    bool empty = true;
    void add(const Vec3& x) {
        const double v = q(x);
        if (empty || v < r.min) r.min = v, r.argmin = x;
        if (empty || v > r.max) r.max = v, r.argmax = x;
        empty = false;
    }
};

// ---- Stationary points of F(u) = u^T A u + beta . u on the unit sphere |u| = 1 of R^N, N = 2, 3 ----
//
// Lagrange: 2 A u + beta = 2 mu u, i.e. (mu I - A) u = beta / 2. In A's eigenbasis (eigenvalues
// alpha_i, beta_i the components of beta) every mu that is not an eigenvalue gives
//   u_i(mu) = beta_i / (2 (mu - alpha_i)),   on the sphere iff
//   f(mu) = |u(mu)|^2 - 1 = sum_i beta_i^2 / (4 (mu - alpha_i)^2) - 1 = 0   (the secular equation).
// Its poles are the distinct eigenvalues whose eigenspace beta does not annihilate (weight
// W_p = sum over the eigenspace of beta_i^2 > 0). f is strictly convex between poles and tends to
// +inf at each, so an interval between consecutive poles holds 0, 1 (tangent) or 2 roots, on
// either side of f's minimum; outside the outermost poles f is monotone between +inf and -1, so
// each outer interval holds exactly one root. That makes at most 2 N roots, every one bracketed.
//
// The hard case mu = alpha_k is possible only when beta has no component in alpha_k's eigenspace
// E_k: then u = w + v with w_i = beta_i / (2 (alpha_k - alpha_i)) outside E_k and any v in E_k with
// |v|^2 = 1 - |w|^2 >= 0. Along that set F = mu + beta . u / 2 = mu + beta . w / 2 is constant (beta
// is orthogonal to v): a pair of points for a simple eigenvalue (both kept: a cap or the rim band
// may hold only one), a circle or a whole sphere for a repeated one. Such a continuum only matters
// if it lies inside the stratum (otherwise it crosses the stratum's boundary, a lower stratum that
// sees the same value), so one point of it suffices: the one closest to `axis` (the cap's
// direction), any when axis has no component in E_k.
//
// Precision: mu is represented as alpha_o + s for an origin pole o, and mu - alpha_i as
// s - (alpha_i - alpha_o), so a root or minimum close to a pole is resolved to full relative
// precision in its distance to that pole (the origin is always the nearer pole), as in LAPACK's
// secular equation solver dlaed4.
template <int N>
class SphereStationary {
public:
    SphereStationary(const MatN<N>& A, const VecN<N>& beta, const VecN<N>& axis) {
        const Eigen::SelfAdjointEigenSolver<MatN<N>> es(A);
        V_ = es.eigenvectors();
        alpha_ = es.eigenvalues();
        beta_ = V_.transpose() * beta;
        axis_ = V_.transpose() * axis;
        // Groups of equal eigenvalues (ascending, so equal ones are adjacent) and their weights.
        for (int i = 0; i < N; ++i) {
            if (i == 0 || alpha_[i] != alpha_[i - 1]) groups_.push_back({i, i, 0.0});
            groups_.back().last = i + 1;
            groups_.back().weight += beta_[i] * beta_[i];
        }
        secular_roots();
        hard_cases();
        for (VecN<N>& u : points_) u = V_ * u.normalized();
    }
    // Unit vectors in the original coordinates.
    const std::vector<VecN<N>>& points() const { return points_; }

private:
    struct Group {
        int first, last;  // eigen-indices [first, last)
        double weight;    // sum of beta_i^2 over the group
    };
    struct Value {
        double f, df, ddf;  // f(mu), f'(mu), f''(mu)
        VecN<N> u;          // u(mu)
    };

    // f and its derivatives at mu = alpha_o + s, with t_i = u_i = beta_i / (2 d_i), d_i = mu - alpha_i:
    //   f = sum t_i^2 - 1,   f' = -2 sum t_i^2 / d_i,   f'' = 6 sum t_i^2 / d_i^2.
    // Eigen-directions with beta_i = 0 contribute nothing (u_i = 0 off the hard case).
    Value at(int o, double s) const {
        Value v{0, 0, 0, VecN<N>::Zero()};
        for (int i = 0; i < N; ++i) {
            if (beta_[i] == 0) continue;
            const double d = s - (alpha_[i] - alpha_[o]);
            const double t = beta_[i] / (2.0 * d);
            v.u[i] = t;
            v.f += t * t;
            v.df -= 2.0 * t * t / d;
            v.ddf += 6.0 * t * t / (d * d);
        }
        v.f -= 1.0;
        return v;
    }

    // Newton's correction for a root of f, taken on phi = 1 - 1 / |u| (nearly linear in mu near a
    // pole, where |u| ~ 1 / |mu - alpha|): phi / phi' with phi' = f' / (2 |u|^3), and
    // 1 - 1 / |u| = f / (|u| (|u| + 1)) to avoid the cancellation.
    static double root_step(const Value& v) {
        const double norm2 = v.f + 1.0, norm = std::sqrt(norm2);
        return 2.0 * norm2 * v.f / ((norm + 1.0) * v.df);
    }
    // Newton's correction for the minimum of f (a root of f', f'' > 0).
    static double min_step(const Value& v) { return v.df / v.ddf; }
    // Left of a root where f decreases, f > 0; left of one where it increases, f < 0; left of the
    // minimum, f' < 0.
    static bool left_of_falling_root(const Value& v) { return v.f > 0; }
    static bool left_of_rising_root(const Value& v) { return v.f < 0; }
    static bool left_of_minimum(const Value& v) { return v.df < 0; }

    // The point in (lo, hi) where `left_of` switches from true to false, by Newton steps
    // (x -= step) safeguarded by bisection: each evaluation moves one end of the bracket, and a
    // step leaving the bracket is replaced by its midpoint. Stops when a step changes x by at most
    // 2 ulps; bisection alone reaches any double's full precision within the iteration cap (2098
    // binades of exponent plus 53 bits).
    double bracketed(int o, double lo, double hi, bool (*left_of)(const Value&), double (*step)(const Value&)) const {
        double x = 0.5 * (lo + hi);
        for (int it = 0; it < 2200; ++it) {
            const Value v = at(o, x);
            if (left_of(v)) lo = x; else hi = x;
            double next = x - step(v);
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
            if (next == lo || next == hi) return x;
            if (std::fabs(next - x) <= 2.0 * kEps * std::fabs(x)) return next;
            x = next;
        }
        return x;
    }

    // f's minimum between the consecutive poles alpha_o1 < alpha_o2 (f' < 0 left of it): the sign
    // of f' at the midpoint picks the half, whose pole becomes the origin.
    std::pair<int, double> gap_minimum(int o1, int o2) const {
        const double half = 0.5 * (alpha_[o2] - alpha_[o1]);
        if (left_of_minimum(at(o1, half))) return {o2, bracketed(o2, -half, 0.0, left_of_minimum, min_step)};
        return {o1, bracketed(o1, 0.0, half, left_of_minimum, min_step)};
    }

    // The roots of f on either side of that minimum (om, sm), where f < 0, each bracketed alone:
    // by the minimum on one side and by a pole or the midpoint on the other (the midpoint's f
    // says which half the root is in when the minimum is in the other half). f decreases towards
    // the left root and increases from the right one.
    std::pair<int, double> gap_root(int o1, int o2, int om, double sm, bool left) const {
        const double half = 0.5 * (alpha_[o2] - alpha_[o1]);
        const auto falling = left_of_falling_root, rising = left_of_rising_root;
        if (left) {
            if (om == o1) return {o1, bracketed(o1, 0.0, sm, falling, root_step)};
            if (at(o1, half).f > 0) return {o2, bracketed(o2, -half, sm, falling, root_step)};
            return {o1, bracketed(o1, 0.0, half, falling, root_step)};
        }
        if (om == o2) return {o2, bracketed(o2, sm, 0.0, rising, root_step)};
        if (at(o1, half).f > 0) return {o1, bracketed(o1, sm, half, rising, root_step)};
        return {o2, bracketed(o2, -half, 0.0, rising, root_step)};
    }

    void add(int o, double s) { points_.push_back(at(o, s).u); }

    void secular_roots() {
        std::vector<const Group*> poles;
        double W = 0;
        for (const Group& g : groups_)
            if (g.weight > 0) poles.push_back(&g), W += g.weight;
        if (poles.empty()) return;
        // Outer roots: with the outermost pole p as origin every |mu - alpha_i| >= |s|, so
        // W_p / (4 s^2) - 1 <= f <= W / (4 s^2) - 1: the root has sqrt(W_p) / 2 <= |s| <= sqrt(W) / 2.
        const int first = poles.front()->first, last = poles.back()->first;
        add(first, bracketed(first, -0.5 * std::sqrt(W), -0.5 * std::sqrt(poles.front()->weight),
                             left_of_rising_root, root_step));
        add(last, bracketed(last, 0.5 * std::sqrt(poles.back()->weight), 0.5 * std::sqrt(W),
                            left_of_falling_root, root_step));
        // Between consecutive poles: f's minimum, then a root on each side of it if the minimum is
        // negative. The minimiser itself is kept too: at a tangential (double) root the computed
        // minimum may round just above 0, and after normalisation the minimiser is a point of the
        // sphere like any other candidate.
        for (size_t k = 0; k + 1 < poles.size(); ++k) {
            const int o1 = poles[k]->first, o2 = poles[k + 1]->first;
            const auto [om, sm] = gap_minimum(o1, o2);
            add(om, sm);
            if (!(at(om, sm).f < 0)) continue;
            for (const bool left : {true, false}) {
                const auto [o, s] = gap_root(o1, o2, om, sm, left);
                add(o, s);
            }
        }
    }

    void hard_cases() {
        for (const Group& k : groups_) {
            if (k.weight != 0) continue;
            VecN<N> u = VecN<N>::Zero();
            for (int i = 0; i < N; ++i)
                if ((i < k.first || i >= k.last) && beta_[i] != 0)
                    u[i] = beta_[i] / (2.0 * (alpha_[k.first] - alpha_[i]));
            const double r2 = 1.0 - u.squaredNorm();
            if (r2 < 0) continue;
            const double r = std::sqrt(r2);
            if (k.last - k.first == 1) {
                // Two points; F is the same at both but the stratum may hold only one.
                VecN<N> v = u;
                u[k.first] = r;
                v[k.first] = -r;
                points_.push_back(u);
                points_.push_back(v);
                continue;
            }
            VecN<N> dir = VecN<N>::Zero();
            for (int i = k.first; i < k.last; ++i) dir[i] = axis_[i];
            const double len = dir.norm();
            if (len > 0) dir /= len; else dir[k.first] = 1.0;
            points_.push_back(u + r * dir);
        }
    }

    MatN<N> V_;
    VecN<N> alpha_, beta_, axis_;
    std::vector<Group> groups_;
    std::vector<VecN<N>> points_;
};

// x^T H x sees only the symmetric part of H, (H + H^T) / 2 (H itself when symmetric).
Eigen::Matrix3d symmetric_part(const Mat3& H) {
    Eigen::Matrix3d m;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m(i, j) = 0.5 * (H(i, j) + H(j, i));
    return m;
}

// The solution of M y = -g when M is non-singular (every eigenvalue non-zero). A singular M has
// an affine line or plane of stationary points or none: an unbounded set, which leaves the
// stratum through its boundary if it meets the stratum at all, where the lower strata see its
// (constant) value.
template <int N>
bool stationary_point(const MatN<N>& M, const VecN<N>& g, VecN<N>& y) {
    const Eigen::SelfAdjointEigenSolver<MatN<N>> es(M);
    const VecN<N>& lambda = es.eigenvalues();
    for (int i = 0; i < N; ++i)
        if (lambda[i] == 0) return false;
    y = -es.eigenvectors() * ((es.eigenvectors().transpose() * g).array() / lambda.array()).matrix();
    return true;
}

// (1) The interior: grad q = b + H x = 0. Only a definite H makes it an extreme; the saddle of an
// indefinite one is a point of the solid like any other candidate and changes nothing.
void interior(const Lens& lens, const Eigen::Matrix3d& H, const Vec3& b, Extremes& e) {
    Eigen::Vector3d x;
    if (!stationary_point<3>(H, Eigen::Vector3d(b.x, b.y, b.z), x)) return;
    const Vec3 p{x[0], x[1], x[2]};
    if (lens.contains(p)) e.add(p);
}

// (2a) A spherical cap: the sphere |x - C| = R restricted to rho <= a on the branch through the
// vertex, i.e. where (x - C) points along `toward_vertex` (+-z). With x = C + R u:
//   q = q(C) + R (b + H C) . u + u^T (R^2 H / 2) u,
// a quadratic on the unit sphere (SphereStationary).
void sphere_cap(const Lens& lens, const Eigen::Matrix3d& H, const Vec3& b, double zc, double R,
                double toward_vertex, Extremes& e) {
    const double a = lens.aperture_radius();
    const Eigen::Vector3d C(0, 0, zc);
    const Eigen::Vector3d beta = R * (Eigen::Vector3d(b.x, b.y, b.z) + H * C);
    const SphereStationary<3> s(0.5 * R * R * H, beta, Eigen::Vector3d(0, 0, toward_vertex));
    for (const Eigen::Vector3d& u : s.points()) {
        const Vec3 x{R * u[0], R * u[1], zc + R * u[2]};
        if (u[2] * toward_vertex >= 0 && std::hypot(x.x, x.y) <= a) e.add(x);
    }
}

// (2b) A flat face z = z0, rho <= a: q(y, z0) = const + (b_xy + z0 h) . y + y^T H_xy y / 2 with
// h = (H_xz, H_yz): stationary where H_xy y = -(b_xy + z0 h).
void flat_face(const Lens& lens, const Eigen::Matrix3d& H, const Vec3& b, double z0, Extremes& e) {
    const Eigen::Matrix2d Hxy = H.topLeftCorner<2, 2>();
    const Eigen::Vector2d g = Eigen::Vector2d(b.x, b.y) + z0 * H.block<2, 1>(0, 2);
    Eigen::Vector2d y;
    if (stationary_point<2>(Hxy, g, y) && std::hypot(y[0], y[1]) <= lens.aperture_radius())
        e.add({y[0], y[1], z0});
}

// (3) The rim band rho = a, z0 <= z <= z1, as x = (a w, z) with w = (cos phi, sin phi):
//   q = c + a b_xy . w + (a^2 / 2) w^T H_xy w + (b_z + a h . w) z + H_zz z^2 / 2,   h = (H_xz, H_yz).
// H_zz != 0: dq/dz = 0 gives z*(w) = -(b_z + a h . w) / H_zz, and along that curve
//   q(w, z*(w)) = c - b_z^2 / (2 H_zz) + a (b_xy - (b_z / H_zz) h) . w
//                 + w^T (a^2 / 2) (H_xy - h h^T / H_zz) w,
// a quadratic on the unit circle whose stationary points are those of q on the cylinder (d/dphi
// of the reduced q is dq/dphi, as dq/dz = 0 there).
// H_zz = 0: q = F(phi) + G(phi) z is linear along each generator. At a stationary point
// (G = 0, F' + G' z = 0) its Hessian in (phi, z) is [[q_phiphi, G'], [G', 0]], of determinant
// -G'^2: a saddle when G' != 0, never an extreme; when G' = 0 too, F' = 0 and the whole generator
// is stationary with the constant value F, an unbounded line that reaches the edge circles. Either
// way the band holds no candidate of its own.
void rim(const Lens& lens, const Eigen::Matrix3d& H, const Vec3& b, Extremes& e) {
    const double a = lens.aperture_radius();
    const double z0 = lens.z_front(a), z1 = lens.z_back(a);
    const Eigen::Matrix2d Hxy = H.topLeftCorner<2, 2>();
    const Eigen::Vector2d h = H.block<2, 1>(0, 2), bxy(b.x, b.y);
    const double Hzz = H(2, 2);
    if (Hzz == 0) return;
    const Eigen::Matrix2d A = 0.5 * a * a * (Hxy - h * h.transpose() / Hzz);
    const Eigen::Vector2d beta = a * (bxy - (b.z / Hzz) * h);
    const SphereStationary<2> s(A, beta, Eigen::Vector2d::Zero());
    for (const Eigen::Vector2d& w : s.points()) {
        const double z = -(b.z + a * h.dot(w)) / Hzz;
        if (z >= z0 && z <= z1) e.add({a * w[0], a * w[1], z});
    }
}

// (4) An edge circle rho = a at height z: x = (a w, z),
//   q = const + a (b_xy + z h) . w + w^T (a^2 / 2) H_xy w,
// a quadratic on the unit circle; the whole circle belongs to the solid.
void edge_circle(const Lens& lens, const Eigen::Matrix3d& H, const Vec3& b, double z, Extremes& e) {
    const double a = lens.aperture_radius();
    const Eigen::Matrix2d A = 0.5 * a * a * H.topLeftCorner<2, 2>();
    const Eigen::Vector2d beta = a * (Eigen::Vector2d(b.x, b.y) + z * H.block<2, 1>(0, 2));
    const SphereStationary<2> s(A, beta, Eigen::Vector2d::Zero());
    for (const Eigen::Vector2d& w : s.points()) e.add({a * w[0], a * w[1], z});
}

// A face: the sphere of signed radius R with vertex at z_vertex (centre z_vertex + R; the vertex
// lies at -sgn(R) z from the centre), or the plane z = z_vertex when R = inf.
void face(const Lens& lens, const Eigen::Matrix3d& H, const Vec3& b, double R, double z_vertex, Extremes& e) {
    if (std::isinf(R)) flat_face(lens, H, b, z_vertex, e);
    else sphere_cap(lens, H, b, z_vertex + R, std::fabs(R), R > 0 ? -1.0 : 1.0, e);
}

// linear_n's n = ior + gradient . x as a (linear) quadratic form.
QuadraticForm linear_n_form(const IndexField& field) {
    QuadraticForm f;
    f.c = field.ior;
    f.b = field.gradient;
    return f;
}

std::string format_point(const Vec3& p) {
    // + 0.0 prints a negative zero as 0.
    return fmt::format("({:g}, {:g}, {:g})", p.x + 0.0, p.y + 0.0, p.z + 0.0);
}

}  // namespace

// The strata of the closed solid: the interior, the two faces, the rim band and the two edge
// circles rho = a at z_front(a) and z_back(a). A ball has no rim (zero edge thickness) and one
// edge circle, the equator where its hemispheres meet.
// Why the candidates suffice: let m be the minimum of q over the solid and p a point where it is
// attained, taken in the lowest-dimensional stratum that holds one. p is a local minimum of q on
// its stratum, hence a stationary point of q on the stratum's whole surface (space, sphere, plane,
// cylinder, circle). If p is isolated, or its connected set of stationary points (on which q is
// constant) lies inside the stratum, the stratum's routine returns p or a point of that set. The
// set cannot leave the stratum: it would then meet the stratum's boundary, a union of lower strata,
// at a point where q = m, against the choice of p. Every candidate is a point of the solid (up to
// rounding), so the smallest candidate value is m. Likewise for the maximum.
QuadraticRange quadratic_range(const Lens& lens, const QuadraticForm& q) {
    const LensSpec& s = lens.spec();
    const Eigen::Matrix3d H = symmetric_part(q.H);
    const double a = lens.aperture_radius();
    Extremes e{q, {}};
    interior(lens, H, q.b, e);
    face(lens, H, q.b, s.r1, -0.5 * s.center_thickness, e);
    face(lens, H, q.b, s.r2, 0.5 * s.center_thickness, e);
    const double z0 = lens.z_front(a), z1 = lens.z_back(a);
    edge_circle(lens, H, q.b, z0, e);
    if (z1 > z0) {
        rim(lens, H, q.b, e);
        edge_circle(lens, H, q.b, z1, e);
    }
    return e.r;
}

// linear_n: n is linear, so its range is quadratic_range of the linear form, and n^2 = n^2 of it:
// [n_lo^2, n_hi^2] for n_lo >= 0, [n_hi^2, n_lo^2] for n_hi <= 0, and when n changes sign the
// solid (connected) holds a zero of n, so n2_min = 0, found as the minimiser of the quadratic
// (ior + gradient . x)^2.
IndexRange index_range(const Lens& lens, const IndexField& field) {
    IndexRange out;
    if (field.closed_form()) {
        const QuadraticRange r = quadratic_range(lens, field.n2_form());
        out.n2_min = r.min;
        out.n2_max = r.max;
        out.argmin = r.argmin;
        out.n_min = std::sqrt(std::fmax(r.min, 0.0));
        out.n_max = std::sqrt(std::fmax(r.max, 0.0));
        return out;
    }
    const QuadraticRange n = quadratic_range(lens, linear_n_form(field));
    if (n.min >= 0) {
        out.n_min = n.min, out.n_max = n.max, out.argmin = n.argmin;
    } else if (n.max <= 0) {
        out.n_min = -n.max, out.n_max = -n.min, out.argmin = n.argmax;
    } else {
        QuadraticForm sq;
        sq.c = field.ior * field.ior;
        sq.b = field.gradient * (2.0 * field.ior);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) sq.H(i, j) = 2.0 * field.gradient[i] * field.gradient[j];
        out.n_min = 0, out.n_max = std::fmax(-n.min, n.max), out.argmin = quadratic_range(lens, sq).argmin;
    }
    out.n2_min = out.n_min * out.n_min;
    out.n2_max = out.n_max * out.n_max;
    return out;
}

std::vector<IndexFieldProblem> index_field_problems(const Lens& lens, const IndexField& field) {
    using T = IndexFieldType;
    std::vector<IndexFieldProblem> out;
    if (field.type == T::Uniform) return out;
    const bool uses_g = field.type == T::RadialN2 || field.type == T::SphericalN2;
    const bool uses_gradient = !uses_g;
    const bool uses_hessian = field.type == T::QuadraticN2;
    if (uses_g && !std::isfinite(field.g))
        out.push_back({"g", fmt::format("must be finite (got {:g})", field.g)});
    if (uses_gradient && !is_finite(field.gradient))
        out.push_back({"gradient", fmt::format("must be finite (got {})", format_point(field.gradient))});
    if (uses_hessian) {
        for (int k = 0; k < 9 && out.empty(); ++k)
            if (!std::isfinite(field.hessian.m[k]))
                out.push_back({"hessian", fmt::format("must be finite (got hessian[{}][{}] = {:g})", k / 3, k % 3,
                                                      field.hessian.m[k])});
        for (int i = 0; i < 3 && out.empty(); ++i)
            for (int j = i + 1; j < 3 && out.empty(); ++j)
                if (field.hessian(i, j) != field.hessian(j, i))
                    out.push_back({"hessian", fmt::format("hessian[{}][{}] = {:g} but hessian[{}][{}] = {:g}: "
                                                          "a Hessian is symmetric",
                                                          i, j, field.hessian(i, j), j, i, field.hessian(j, i))});
    }
    // The solid checks need a well-formed field.
    if (!out.empty()) return out;

    // The tests are written to fail on NaN too (a non-finite ior).
    const IndexRange r = index_range(lens, field);
    if (!(r.n2_min > 0)) {
        out.push_back({"", fmt::format("n^2 = {:g} at {} mm: the index must be real everywhere in the object",
                                       r.n2_min, format_point(r.argmin))});
        return out;
    }
    // linear_n's n is signed: its minimum is that of the linear form, not of |n| = sqrt(n^2).
    double n_min = r.n_min;
    Vec3 where = r.argmin;
    if (field.type == T::LinearN) {
        const QuadraticRange n = quadratic_range(lens, linear_n_form(field));
        n_min = n.min;
        where = n.argmin;
    }
    if (!(n_min >= 1.0 - kIndexBelowOneSlack)) {
        std::string hint;
        // n^2 = ior^2 (1 - g^2 r^2) >= 1 for every r <= r_max iff g <= sqrt(1 - 1 / ior^2) / r_max,
        // with r = |x| (spherical) or rho (radial, r_max = a).
        if (uses_g && field.ior > 1) {
            double r_max = lens.aperture_radius();
            if (field.type == T::SphericalN2) {
                QuadraticForm x2;
                x2.H = Mat3::identity() * 2.0;
                r_max = std::sqrt(quadratic_range(lens, x2).max);
            }
            const double u = 1.0 / field.ior;
            hint = fmt::format(" ({} keeps n >= 1 in this object for g <= sqrt(1 - 1/ior^2) / {} = {:g} 1/mm)",
                               to_string(field.type), field.type == T::SphericalN2 ? "max |x|" : "a",
                               std::sqrt((1 - u) * (1 + u)) / r_max);
        }
        out.push_back({"", fmt::format("n = {:g} at {} mm is below 1: no glass is optically thinner than vacuum{}",
                                       n_min, format_point(where), hint)});
    }
    return out;
}

}  // namespace ltm
