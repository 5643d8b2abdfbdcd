#include "trace/GrinPath.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "trace/Polynomial.h"
#include "trace/TraceTolerance.h"

namespace ltm {

namespace {

double spectral_norm(const Mat3& A) {
    Eigen::Matrix3d m;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m(i, j) = A(i, j);
    return Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues()(0);
}

// C, S, U of one eigen-direction (see GrinPath.h), from the half angle alone: with
// s = sin(w tau / 2) and c = cos(w tau / 2) (one sincos),
//   S = 2 s c / w,  U = 2 s^2 / w^2,  C = 1 - w^2 U = 1 - 2 s^2,
// each within a few ulps (no cancellation: C's absolute error is that of s^2, as a correctly
// rounded cos would have near 1, and an ulp of 1 where C is near 0, below y0's own rounding).
// Likewise with s = sinh(k tau / 2) and c = sqrt(1 + s^2) = cosh(k tau / 2):
//   S = 2 s c / k,  U = 2 s^2 / k^2,  C = 1 + 2 s^2.
// One transcendental call instead of three: these are most of a general-form step's cost.
struct Csu {
    double C, S, U;
};
Csu csu(double lambda, double tau) {
    if (lambda == 0) return {1.0, tau, 0.5 * tau * tau};
    if (lambda < 0) {
        const double w = std::sqrt(-lambda), half = 0.5 * w * tau;
        const double s = std::sin(half), c = std::cos(half);
        const double u = 2.0 * s * s;
        return {1.0 - u, 2.0 * s * c / w, u / (w * w)};
    }
    const double k = std::sqrt(lambda);
    const double s = std::sinh(0.5 * k * tau), c = std::sqrt(1.0 + s * s);
    const double u = 2.0 * s * s;
    return {1.0 + u, 2.0 * s * c / k, u / (k * k)};
}

}  // namespace

GrinField::GrinField(const QuadraticForm& q, double n2_max, double radius) : q_(q), n2_max_(n2_max), radius_(radius) {
    parabolic_ = q.H == Mat3::zero();
    if (parabolic_) {
        Q_ = Mat3::identity();
        lambda_ = {0, 0, 0};
        beta_ = q.b * 0.5;
    } else {
        Eigen::Matrix3d h;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) h(i, j) = q.H(i, j);
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(h);
        for (int i = 0; i < 3; ++i) {
            lambda_[i] = 0.5 * es.eigenvalues()(i);
            for (int j = 0; j < 3; ++j) Q_(j, i) = es.eigenvectors()(j, i);
        }
        beta_ = Q_.transposed() * q.b * 0.5;
    }
    accel_max_ = 0.5 * (length(q.b) + (parabolic_ ? 0.0 : spectral_norm(q.H) * radius));
}

GrinPath::GrinPath(const GrinField& field, const Vec3& r0, const Vec3& p0) : f_(&field), r0_(r0), p0_(p0) {
    if (field.parabolic()) {
        y0_ = r0;
        v0_ = p0;
    } else {
        const Mat3 qt = field.basis().transposed();
        y0_ = qt * r0;
        v0_ = qt * p0;
    }
}

void GrinPath::state(double tau, Vec3& r, Vec3& p) const {
    if (f_->parabolic()) {
        // r = r0 + p0 tau + b tau^2 / 4,  p = p0 + b tau / 2  (beta = b / 2).
        const Vec3& beta = f_->beta();
        r = r0_ + p0_ * tau + beta * (0.5 * tau * tau);
        p = p0_ + beta * tau;
        return;
    }
    if (tau == 0) {  // the start, exactly (every surface's search begins there)
        r = r0_;
        p = p0_;
        return;
    }
    Vec3 y, v;
    for (int i = 0; i < 3; ++i) {
        const double l = f_->lambda()[i], b = f_->beta()[i];
        const Csu k = csu(l, tau);
        y[i] = y0_[i] * k.C + v0_[i] * k.S + b * k.U;
        v[i] = y0_[i] * l * k.S + v0_[i] * k.C + b * k.S;
    }
    r = f_->basis() * y;
    p = f_->basis() * v;
}

Vec3 GrinPath::position(double tau) const {
    Vec3 r, p;
    state(tau, r, p);
    return r;
}

Vec3 GrinPath::momentum(double tau) const {
    Vec3 r, p;
    state(tau, r, p);
    return p;
}

double GrinPath::arc_length(double tau) const {
    // Gauss-Legendre with 8 nodes on each piece, compared with the two halves; pieces are split
    // until the two agree to 1e-12 relative (|p| = n is smooth and varies by a few percent).
    static const double x8[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double w8[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    auto gl = [&](double a, double b) {
        const double m = 0.5 * (a + b), h = 0.5 * (b - a);
        double s = 0;
        for (int i = 0; i < 4; ++i) s += w8[i] * (length(momentum(m - h * x8[i])) + length(momentum(m + h * x8[i])));
        return s * h;
    };
    double total = 0;
    struct Piece {
        double a, b, v;
        int depth;
    };
    std::vector<Piece> stack{{0.0, tau, gl(0.0, tau), 0}};
    while (!stack.empty()) {
        const Piece pc = stack.back();
        stack.pop_back();
        const double m = 0.5 * (pc.a + pc.b);
        const double l = gl(pc.a, m), r = gl(m, pc.b);
        if (pc.depth >= 20 || std::fabs(l + r - pc.v) <= 1e-12 * std::fabs(l + r)) {
            total += l + r;
        } else {
            stack.push_back({pc.a, m, l, pc.depth + 1});
            stack.push_back({m, pc.b, r, pc.depth + 1});
        }
    }
    return total;
}

Quadric Quadric::from(const Surface& s) {
    Quadric q;
    switch (s.kind) {
        case SurfaceKind::Plane:
            q.plane = true;
            q.n = s.axis;
            q.o = s.origin;
            return q;
        case SurfaceKind::Sphere:
            q.L = Mat3::identity();
            q.c = s.origin;
            q.R2 = s.radius * s.radius;
            q.norm_L = 1;
            return q;
        case SurfaceKind::Cylinder: {
            const Vec3& u = s.axis;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) q.L(i, j) = (i == j ? 1.0 : 0.0) - u[i] * u[j];
            q.c = s.origin;
            q.R2 = s.radius * s.radius;
            q.norm_L = 1;
            return q;
        }
        case SurfaceKind::Ellipsoid: {
            // |S^-1 F^T (x - c)| = 1: row i of L is f_i / e_i.
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) q.L(i, j) = s.frame(j, i) / s.semi_axes[i];
            q.c = s.origin;
            q.R2 = 1;
            q.norm_L = 1.0 / std::min({s.semi_axes.x, s.semi_axes.y, s.semi_axes.z});
            return q;
        }
        default: break;
    }
    throw std::invalid_argument("graded-index paths meet planes, spheres, cylinders and ellipsoids only");
}

double Quadric::value(const Vec3& x) const {
    if (plane) return dot(n, x - o);
    const Vec3 u = L * (x - c);
    return length2(u) - R2;
}

double Quadric::slope(const Vec3& x, const Vec3& p) const {
    if (plane) return dot(n, p);
    return 2.0 * dot(L * (x - c), L * p);
}

namespace {

// The root in [a, b] of f = q(path) with sign(f(a)) = -sign(f(b)), f monotone there:
// safeguarded Newton (Polynomial.h) from the bracket's near end, which the guaranteed step put
// close to the root.
double polish(const GrinPath& path, const Quadric& q, double a, double b, long* evals) {
    auto eval = [&](double tau, double& f, double& df) {
        Vec3 r, p;
        path.state(tau, r, p);
        if (evals) ++*evals;
        f = q.value(r);
        df = q.slope(r, p);
    };
    double fa, dfa;
    eval(a, fa, dfa);
    return safeguarded_newton(eval, a, b, fa, a, fa, dfa);
}

}  // namespace

namespace {

// Newton's method on f(tau) = q(r(tau)) from a root found through a closed form, to the last bit
// the evaluation allows: steps while they shrink, at most 4.
double newton_polish(const GrinPath& path, const Quadric& q, double tau, long* evals) {
    double last = INFINITY;
    for (int it = 0; it < 4; ++it) {
        Vec3 r, p;
        path.state(tau, r, p);
        if (evals) ++*evals;
        const double f = q.value(r), d = q.slope(r, p);
        if (f == 0 || d == 0) break;
        const double step = f / d;
        if (!(std::fabs(step) < 0.5 * last)) break;
        tau -= step;
        last = std::fabs(step);
    }
    return tau;
}

// The roots in [lo, hi] of a polynomial of degree <= 4, with [lo, hi] clipped to the Cauchy bound
// 1 + max |c_i / c_n| that holds them all.
PolyRoots bounded_roots(const double* c, int degree, double lo, double hi) {
    int d = degree;
    while (d > 0 && c[d] == 0) --d;
    if (d == 0) return {};
    double bound = 0;
    for (int i = 0; i < d; ++i) bound = std::max(bound, std::fabs(c[i] / c[d]));
    return real_roots(c, d, std::max(lo, -1.0 - bound), std::min(hi, 1.0 + bound));
}

bool exactly_zero(const Vec3& v) { return v.x == 0 && v.y == 0 && v.z == 0; }

// Whether x lies on one of the patches (any point when there are none); *which: the first such.
bool on_some(const Patch* patches, int count, const Vec3& x, int* which) {
    if (count == 0) return true;
    for (int i = 0; i < count; ++i)
        if (on_patch(patches[i], x)) {
            if (which) *which = i;
            return true;
        }
    return false;
}

}  // namespace

CurvedQuadric::CurvedQuadric(const GrinField& field, const Quadric& q) : f_(&field), q_(q) {
    const Mat3& Q = field.basis();
    if (q.plane) {
        ne_ = Q.transposed() * q.n;
        no_ = dot(q.n, q.o);
        for (int i = 0; i < 3; ++i) seen_[i] = ne_[i] != 0;
    } else {
        G_ = q.L * Q;
        gc_ = q.L * q.c;
        for (int i = 0; i < 3; ++i) seen_[i] = !exactly_zero(G_.column(i));
    }
    // One lambda for every direction the surface depends on: a closed form in one variable.
    bool first = true, common = true;
    for (int i = 0; i < 3; ++i) {
        if (!seen_[i]) continue;
        if (first) lambda_ = field.lambda()[i];
        common = common && field.lambda()[i] == lambda_;
        first = false;
    }
    if (!common) form_ = Form::General;
    else if (lambda_ == 0) form_ = Form::Polynomial;
    else form_ = lambda_ < 0 ? Form::Trigonometric : Form::Hyperbolic;
}

double CurvedQuadric::first_crossing(const GrinPath& path, double tmin, double tmax, const Patch* patches,
                                     int count, int* which, long* evals) const {
    if (form_ == Form::General) return general(path, tmin, tmax, patches, count, which, evals);
    if (evals) ++*evals;
    const Vec3& y0 = path.y0();
    const Vec3& v0 = path.v0();
    const Vec3& beta = f_->beta();
    // The seen part of the path as y(s) = m + a X(s) + b Y(s) + c Z(s) for the form's variable s,
    // then the quadric as a polynomial in it (coefficients ascending, c[0..4]).
    double c[5] = {0, 0, 0, 0, 0};
    auto norm_poly = [&](const Vec3& u0, const Vec3& u1, const Vec3& u2) {
        // |u0 + u1 s + u2 s^2|^2 - R^2.
        const double l0 = length(u0), R = std::sqrt(q_.R2);
        c[0] = (l0 - R) * (l0 + R);
        c[1] = 2.0 * dot(u0, u1);
        c[2] = length2(u1) + 2.0 * dot(u0, u2);
        c[3] = 2.0 * dot(u1, u2);
        c[4] = length2(u2);
    };
    auto seen = [&](const Vec3& v) { return Vec3{seen_[0] ? v.x : 0.0, seen_[1] ? v.y : 0.0, seen_[2] ? v.z : 0.0}; };
    // The first of the candidate roots (ascending, polished) in (tmin, tmax) on the patch.
    auto first_on_patch = [&](const double* roots, int n, bool polish_them) {
        for (int i = 0; i < n; ++i) {
            const double tau = polish_them ? newton_polish(path, q_, roots[i], evals) : roots[i];
            if (!(tau > tmin && tau < tmax)) continue;
            if (on_some(patches, count, path.position(tau), which)) return tau;
        }
        return static_cast<double>(INFINITY);
    };
    if (form_ == Form::Polynomial) {
        // y = y0 + v0 tau + beta tau^2 / 2 on the seen directions.
        const Vec3 m = seen(y0), a = seen(v0), b = seen(beta) * 0.5;
        if (q_.plane) {
            c[0] = dot(ne_, m) - no_;
            c[1] = dot(ne_, a);
            c[2] = dot(ne_, b);
        } else {
            norm_poly(G_ * m - gc_, G_ * a, G_ * b);
        }
        const PolyRoots r = bounded_roots(c, q_.plane ? 2 : 4, tmin, tmax);
        return first_on_patch(r.x.data(), r.count, false);
    }
    if (form_ == Form::Trigonometric) {
        // y = m + A cos(theta) + B sin(theta), theta = w tau: m = beta / w^2, A = y0 - m, B = v0 / w.
        const double w = std::sqrt(-lambda_);
        const Vec3 m = seen(beta) / (w * w), A = seen(y0) - m, B = seen(v0) / w;
        double c0, c1, s1, c2 = 0, s2 = 0, cs = 0;
        if (q_.plane) {
            c0 = dot(ne_, m) - no_;
            c1 = dot(ne_, A);
            s1 = dot(ne_, B);
        } else {
            const Vec3 u0 = G_ * m - gc_, u1 = G_ * A, u2 = G_ * B;
            const double l0 = length(u0), R = std::sqrt(q_.R2);
            c0 = (l0 - R) * (l0 + R);
            c1 = 2.0 * dot(u0, u1);
            s1 = 2.0 * dot(u0, u2);
            c2 = length2(u1);
            s2 = length2(u2);
            cs = 2.0 * dot(u1, u2);
        }
        // (1 + t^2)^2 f with cos = (1 - t^2) / (1 + t^2), sin = 2 t / (1 + t^2), t = tan(theta / 2).
        c[0] = c0 + c1 + c2;
        c[1] = 2.0 * (s1 + cs);
        c[2] = 2.0 * (c0 - c2) + 4.0 * s2;
        c[3] = 2.0 * (s1 - cs);
        c[4] = c0 - c1 + c2;
        const PolyRoots r = bounded_roots(c, 4, -INFINITY, INFINITY);
        // theta in (0, 2 pi): t >= 0 maps to [0, pi), t < 0 to (pi, 2 pi); t = inf (theta = pi) is
        // a root when the leading coefficient vanishes exactly.
        double theta[5];
        int n = 0;
        for (int i = 0; i < r.count; ++i) {
            const double th = 2.0 * std::atan(r.x[static_cast<size_t>(i)]);
            theta[n++] = th < 0 ? th + 2.0 * kPi : th;
        }
        if (c[4] == 0 && (c[3] != 0 || c[2] != 0)) theta[n++] = kPi;
        std::sort(theta, theta + n);
        // The orbit repeats every 2 pi in theta: the roots of later periods are the same, shifted.
        const double period = 2.0 * kPi / w;
        for (int k = 0; n > 0 && k * period < tmax && k < trace_tol::kGrinMaxPeriods; ++k) {
            double taus[5];
            for (int i = 0; i < n; ++i) taus[i] = k * period + theta[i] / w;
            const double t = first_on_patch(taus, n, true);
            if (t < INFINITY) return t;
        }
        return INFINITY;
    }
    // Hyperbolic: y = m + A cosh(k tau) + B sinh(k tau), m = -beta / k^2, A = y0 - m, B = v0 / k;
    // with z = e^(k tau): cosh = (z + 1/z) / 2, sinh = (z - 1/z) / 2, so u = u0 + P z + N / z.
    const double k = std::sqrt(lambda_);
    const Vec3 m = seen(beta) * (-1.0 / (k * k)), A = seen(y0) - m, B = seen(v0) / k;
    const Vec3 P = (A + B) * 0.5, N = (A - B) * 0.5;
    if (q_.plane) {
        // z f = ne.N + (ne.m - no) z + ne.P z^2.
        c[0] = dot(ne_, N);
        c[1] = dot(ne_, m) - no_;
        c[2] = dot(ne_, P);
    } else {
        // z^2 f = |G N + (G m - gc) z + G P z^2|^2 - R^2 z^2.
        const Vec3 n0 = G_ * N, u0 = G_ * m - gc_, p2 = G_ * P;
        c[0] = length2(n0);
        c[1] = 2.0 * dot(n0, u0);
        c[2] = length2(u0) + 2.0 * dot(n0, p2) - q_.R2;
        c[3] = 2.0 * dot(u0, p2);
        c[4] = length2(p2);
    }
    const double zlo = std::exp(k * tmin), zhi = std::isfinite(tmax) ? std::exp(k * tmax) : INFINITY;
    const PolyRoots r = bounded_roots(c, q_.plane ? 2 : 4, zlo, zhi);
    double taus[4];
    for (int i = 0; i < r.count; ++i) taus[i] = std::log(r.x[static_cast<size_t>(i)]) / k;
    return first_on_patch(taus, r.count, true);
}

double CurvedQuadric::general(const GrinPath& path, double tmin, double tmax, const Patch* patches, int count,
                              int* which, long* evals) const {
    const GrinField& f = *f_;
    const Quadric& q = q_;
    // Guaranteed steps (GrinPath.h). M bounds |f''| while the path is in the glass.
    const double n2max = f.n2_max();
    const double M = q.plane ? f.accel_max()
                             : 2.0 * q.norm_L * q.norm_L * (n2max + (f.radius() + length(q.c)) * f.accel_max());
    const double floor_step = trace_tol::kGrinMinStep * f.radius() / std::sqrt(n2max);
    double tau = tmin;
    Vec3 r, p;
    path.state(tau, r, p);
    if (evals) ++*evals;
    double fv = q.value(r), fs = q.slope(r, p);
    double sign = (fv > 0 || (fv == 0 && fs > 0)) ? 1.0 : -1.0;
    for (int step = 0; step < trace_tol::kGrinMaxSteps && tau < tmax; ++step) {
        const double g = std::max(0.0, sign * fv), gp = sign * fs;
        if (g == 0 && gp < 0) {  // on the surface and leaving its side: a root here
            if (tau > tmin && on_some(patches, count, r, which)) return tau;
            sign = -sign;
            tau += floor_step;
            path.state(tau, r, p);
            fv = q.value(r);
            fs = q.slope(r, p);
            continue;
        }
        const double h_safe = M > 0 ? 2.0 * g / (std::sqrt(gp * gp + 2.0 * M * g) - gp) : (gp < 0 ? g / -gp : INFINITY);
        double next;
        if (gp < 0 && gp * gp > 2.0 * M * g) {
            const double h_sure = 2.0 * g / (-gp + std::sqrt(gp * gp - 2.0 * M * g));
            if (tau + h_safe >= tmax) break;
            const double root = polish(path, q, tau + h_safe, tau + h_sure, evals);
            if (root >= tmax) break;
            if (on_some(patches, count, path.position(root), which)) return root;
            sign = -sign;  // a crossing of the full surface off its patch: go on past it
            next = root;
        } else {
            next = tau + std::max(h_safe, floor_step);
        }
        tau = next;
        path.state(tau, r, p);
        if (evals) ++*evals;
        fv = q.value(r);
        fs = q.slope(r, p);
    }
    return INFINITY;
}

}  // namespace ltm
