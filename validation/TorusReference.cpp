// The torus-ray reference (TorusReference.h) in exact dyadic arithmetic with MPFR.
//
// ---- The quartic -----------------------------------------------------------------------------
// Let x = w + t d with w = o - C (the ray relative to the torus centre), and let A = a / |a| be the
// unit axis. A point is at height h = x.A above the equatorial plane and at distance rho from the
// axis, rho^2 = |x|^2 - h^2. The torus (the points at distance r from the centre circle rho = R,
// h = 0) is (rho - R)^2 + h^2 = r^2, i.e. |x|^2 + R^2 - r^2 = 2 R rho. Squaring (both sides are
// >= 0 on the torus) gives the quartic
//     f(x) = (|x|^2 + R^2 - r^2)^2 - 4 R^2 (|x|^2 - (x.A)^2) = 0,
// whose zero set is the torus together with (rho + R)^2 + h^2 = r^2 (the point at distance r from
// the circle point on the far side of the axis), which is empty when R > r: for R > r the real
// roots of f along the ray are exactly the ray's torus points. Factored,
//     f = ((rho - R)^2 + h^2 - r^2) ((rho + R)^2 + h^2 - r^2),
// so f < 0 inside the tube and f > 0 outside (R > r), and a root's multiplicity is the order of
// contact of the line with the surface.
// To avoid the division by |a| (which would round), the reference solves F = |a|^2 f instead:
//     F(t) = aa g(t)^2 - 4 R^2 (aa X(t) - Y(t)^2),
//     X(t) = |x|^2 = dd t^2 + 2 wd t + ww,   Y(t) = x.a = da t + wa,   g(t) = X(t) + R^2 - r^2,
// with aa = a.a, dd = d.d, wd = w.d, ww = w.w, da = d.a, wa = w.a: a polynomial of degree 4 in t
// with leading coefficient aa dd^2 > 0, whose coefficients are sums of products of the inputs.
// F and f have the same roots with the same multiplicities (aa > 0 is a constant).
//
// ---- Exactness (the precision argument) ------------------------------------------------------
// Every double is a dyadic rational m 2^e (|m| < 2^53). Sums, differences and products of dyadic
// numbers are dyadic, and MPFR represents a dyadic number with a p-bit significand exactly at any
// precision >= p. Every operation below sets its result's precision from its operands before
// computing: for a product, the sum of the operands' significand lengths (mpfr_min_prec); for a
// sum, from one bit above the higher operand's leading bit down to the lower operand's last set
// bit. So no result is ever rounded (precisions grow as needed, typically a few hundred bits for
// F's coefficients and a few thousand for the last Sturm polynomial), and each operation checks
// MPFR's ternary value, which is 0 exactly when the result is exact; a non-zero value throws.
// Nothing divides: the Sturm sequence is built from pseudo-remainders (below). The coefficients of
// F, the Sturm sequence and every sign evaluated are therefore exact, and the only roundings are
// the final ones to double (t, lo, hi, and the reported derivatives and values of f).
//
// ---- Root isolation (why nothing is missed) --------------------------------------------------
// Sturm's theorem (e.g. Basu, Pollack and Roy, Algorithms in Real Algebraic Geometry, Ch. 2):
// with p0 = F, p1 = F', p_{k+1} = -rem(p_{k-1}, p_k) (each element may be replaced by a positive
// multiple) until the remainder is 0, and V(x) the number of sign changes in (p0(x), p1(x), ...)
// (zeros skipped), the number of DISTINCT real roots of F in (a, b) is V(a) - V(b) for a < b that
// are not roots of F. This holds for F with multiple roots as well: the last element is then
// gcd(F, F') up to a constant, every element is a multiple of it, and at a non-root x the common
// factor's sign does not change V.
// Pseudo-remainders: with b = lc(B) and s the number of elimination steps, b^s A = Q B + R exactly
// (each step R <- b R - lc(R) x^k B uses only products and differences), so
// -rem(A, B) = -R / b^s, and the positive multiple -R sgn(b)^s is the next element. Each element
// is also divided by the largest power of 2 dividing all its coefficients (exact, positive).
// All roots lie in |t| < 2^e, 2^e above Fujiwara's bound 2 max_k |c_{4-k} / c_4|^{1/k} (the
// k = 4 term with |c_0 / (2 c_4)|), computed with upward rounding (an upper bound). The interval
// (-2^e, 2^e) is bisected, counting roots with Sturm's theorem, until every interval holds
// exactly one distinct root. A split point that is itself a root of F is moved to another dyadic
// point of the interval (lo + (hi - lo) j / 16 for j = 8, 7, 9, 6, ...: F has at most 4 roots, so
// one of the first five is not a root), so the theorem's condition holds at every end point.
// Distinct roots of an exact polynomial are a positive distance apart, so this terminates.
//
// ---- Multiplicity and refinement -------------------------------------------------------------
// Let G0 = F and G_{k+1} = gcd(G_k, G_k') (the last element of G_k's Sturm sequence), as long as
// it has degree >= 1. A root of multiplicity m of F is a root of multiplicity m - k of G_k (and
// G_k has no other roots than F's). So for an interval (lo, hi) isolating one root of F, its
// multiplicity is 1 plus the number of k >= 1 for which G_k has a root in (lo, hi) (Sturm again:
// lo and hi are not roots of F, hence of no G_k). The root is then a simple root of
// q = G_{m-1}, the only root of q in (lo, hi), and q changes sign across it: bisection on the
// exact sign of q brackets it at every step. It stops when both ends round to the same double
// (then the root, between them, rounds to it too: rounding is monotone), when q is exactly 0 at a
// midpoint (the root is that dyadic number), or when the bracket is below 2^-200 of its magnitude
// (or 2^-1200 absolute): the root is then within 2^-200 relative of a tie between two doubles,
// and the midpoint's rounding is reported (an error of at most half an ulp plus 2^-200 relative).
#include "validation/TorusReference.h"

#include <mpfr.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ltm::validation {

namespace {

void exact(int ternary) {
    if (ternary != 0) throw std::logic_error("TorusReference: an exact MPFR operation rounded");
}

// An exact dyadic number (an mpfr_t whose precision always fits its value).
class Dyadic {
public:
    Dyadic() {
        mpfr_init2(v_, MPFR_PREC_MIN);
        mpfr_set_zero(v_, 1);
    }
    explicit Dyadic(double x) {
        mpfr_init2(v_, 53);
        exact(mpfr_set_d(v_, x, MPFR_RNDN));
    }
    Dyadic(const Dyadic& o) {
        mpfr_init2(v_, mpfr_get_prec(o.v_));
        exact(mpfr_set(v_, o.v_, MPFR_RNDN));
    }
    Dyadic(Dyadic&& o) noexcept {
        mpfr_init2(v_, MPFR_PREC_MIN);
        mpfr_swap(v_, o.v_);
    }
    Dyadic& operator=(Dyadic o) noexcept {
        mpfr_swap(v_, o.v_);
        return *this;
    }
    ~Dyadic() { mpfr_clear(v_); }

    bool zero() const { return mpfr_zero_p(v_) != 0; }
    int sign() const { return mpfr_sgn(v_); }
    // The bit positions the value occupies: |x| < 2^high, and x is a multiple of 2^low.
    long high() const { return static_cast<long>(mpfr_get_exp(v_)); }
    long low() const { return static_cast<long>(mpfr_get_exp(v_)) - static_cast<long>(mpfr_min_prec(v_)); }
    double to_double(mpfr_rnd_t rnd = MPFR_RNDN) const { return mpfr_get_d(v_, rnd); }
    const __mpfr_struct* get() const { return v_; }
    __mpfr_struct* get() { return v_; }

    // Exact operations.
    friend Dyadic operator+(const Dyadic& a, const Dyadic& b) { return add(a, b, false); }
    friend Dyadic operator-(const Dyadic& a, const Dyadic& b) { return add(a, b, true); }
    friend Dyadic operator*(const Dyadic& a, const Dyadic& b) {
        Dyadic r;
        if (a.zero() || b.zero()) return r;
        mpfr_set_prec(r.v_, std::max<mpfr_prec_t>(MPFR_PREC_MIN, mpfr_min_prec(a.v_) + mpfr_min_prec(b.v_)));
        exact(mpfr_mul(r.v_, a.v_, b.v_, MPFR_RNDN));
        return r;
    }
    Dyadic operator-() const {
        Dyadic r(*this);
        mpfr_neg(r.v_, r.v_, MPFR_RNDN);  // exact: same precision
        return r;
    }
    // x 2^e (exact).
    Dyadic scaled(long e) const {
        Dyadic r(*this);
        exact(mpfr_mul_2si(r.v_, r.v_, e, MPFR_RNDN));
        return r;
    }

private:
    static Dyadic add(const Dyadic& a, const Dyadic& b, bool subtract) {
        if (b.zero()) return a;
        if (a.zero()) return subtract ? -b : b;
        Dyadic r;
        const long hi = std::max(a.high(), b.high()) + 1, lo = std::min(a.low(), b.low());
        mpfr_set_prec(r.v_, std::max<mpfr_prec_t>(MPFR_PREC_MIN, static_cast<mpfr_prec_t>(hi - lo)));
        exact(subtract ? mpfr_sub(r.v_, a.v_, b.v_, MPFR_RNDN) : mpfr_add(r.v_, a.v_, b.v_, MPFR_RNDN));
        return r;
    }
    mpfr_t v_;
};

// A polynomial with exact coefficients, ascending; no zero leading coefficient (empty: 0).
struct Poly {
    std::vector<Dyadic> c;
    int degree() const { return static_cast<int>(c.size()) - 1; }
    bool zero() const { return c.empty(); }
    void trim() {
        while (!c.empty() && c.back().zero()) c.pop_back();
    }
};

Dyadic eval(const Poly& p, const Dyadic& x) {
    if (p.zero()) return Dyadic();
    Dyadic v = p.c.back();
    for (int i = p.degree() - 1; i >= 0; --i) v = v * x + p.c[static_cast<size_t>(i)];
    return v;
}

Poly derivative(const Poly& p) {
    Poly d;
    for (int i = 1; i <= p.degree(); ++i) d.c.push_back(p.c[static_cast<size_t>(i)] * Dyadic(static_cast<double>(i)));
    d.trim();
    return d;
}

// Divides all coefficients by the largest power of 2 that divides them all (exact, positive).
void remove_power_of_two(Poly& p) {
    if (p.zero()) return;
    long low = p.c.back().low();
    for (const Dyadic& x : p.c)
        if (!x.zero()) low = std::min(low, x.low());
    for (Dyadic& x : p.c) x = x.scaled(-low);
}

// A positive multiple of -rem(A, B) (deg B >= 0, deg A >= deg B): see "Pseudo-remainders".
Poly negated_remainder(const Poly& A, const Poly& B) {
    Poly R = A;
    const Dyadic& b = B.c.back();
    const int n = B.degree();
    int steps = 0;
    while (!R.zero() && R.degree() >= n) {
        const int k = R.degree() - n;
        const Dyadic lead = R.c.back();
        for (Dyadic& x : R.c) x = b * x;
        for (int j = 0; j <= n; ++j) {
            Dyadic& x = R.c[static_cast<size_t>(j + k)];
            x = x - lead * B.c[static_cast<size_t>(j)];
        }
        if (!R.c.back().zero()) throw std::logic_error("TorusReference: pseudo-division left a leading term");
        R.trim();
        ++steps;
    }
    // b^steps A = Q B + R, so -rem(A, B) = -R / b^steps, a positive multiple of -R sgn(b)^steps.
    const bool keep = b.sign() < 0 && steps % 2 == 1;
    if (!keep)
        for (Dyadic& x : R.c) x = -x;
    remove_power_of_two(R);
    return R;
}

// The Sturm sequence of p (see "Root isolation"), its last element being gcd(p, p') up to a constant.
struct Sturm {
    std::vector<Poly> seq;
    explicit Sturm(const Poly& p) {
        seq.push_back(p);
        if (p.degree() < 1) return;
        seq.push_back(derivative(p));
        remove_power_of_two(seq.back());
        while (seq.back().degree() >= 1) {
            Poly next = negated_remainder(seq[seq.size() - 2], seq.back());
            if (next.zero()) break;
            seq.push_back(std::move(next));
        }
    }
    // Sign changes at x, zeros skipped.
    int variations(const Dyadic& x) const {
        int v = 0, last = 0;
        for (const Poly& p : seq) {
            const int s = eval(p, x).sign();
            if (s == 0) continue;
            if (last != 0 && s != last) ++v;
            last = s;
        }
        return v;
    }
    const Poly& gcd() const { return seq.back(); }
};

Dyadic midpoint(const Dyadic& a, const Dyadic& b) { return (a + b).scaled(-1); }

}  // namespace

struct TorusReference::Impl {
    Dyadic aa;
    std::vector<Poly> F;        // F, F', F'', F''', F''''
    std::vector<Sturm> derivative_chains;  // the Sturm sequences of F, F', F'', F'''
    std::vector<Poly> levels;   // G0 = F, G1 = gcd(F, F'), ... (degree >= 1)
    std::vector<Sturm> chains;  // the Sturm sequence of each level

    // Distinct roots of level k in (lo, hi), lo and hi not roots of F.
    int count(size_t k, const Dyadic& lo, const Dyadic& hi) const {
        return chains[k].variations(lo) - chains[k].variations(hi);
    }
};

TorusReference::TorusReference(const Vec3& centre, const Vec3& axis, double major, double minor, const Vec3& origin,
                               const Vec3& direction)
    : impl_(std::make_unique<Impl>()) {
    for (const Vec3* v : {&centre, &axis, &origin, &direction})
        if (!std::isfinite(v->x) || !std::isfinite(v->y) || !std::isfinite(v->z))
            throw std::invalid_argument("TorusReference: non-finite input");
    if (!(major > 0) || !(minor > 0) || !std::isfinite(major) || !std::isfinite(minor))
        throw std::invalid_argument("TorusReference: radii must be positive and finite");
    if (direction == Vec3{} || axis == Vec3{}) throw std::invalid_argument("TorusReference: zero direction or axis");

    // ---- F's coefficients, exactly (see "The quartic") ----
    auto vec = [](const Vec3& v) { return std::vector<Dyadic>{Dyadic(v.x), Dyadic(v.y), Dyadic(v.z)}; };
    auto dotp = [](const std::vector<Dyadic>& u, const std::vector<Dyadic>& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
    const std::vector<Dyadic> C = vec(centre), a = vec(axis), o = vec(origin), d = vec(direction);
    const std::vector<Dyadic> w{o[0] - C[0], o[1] - C[1], o[2] - C[2]};
    const Dyadic aa = dotp(a, a), dd = dotp(d, d), wd = dotp(w, d), ww = dotp(w, w), da = dotp(d, a), wa = dotp(w, a);
    const Dyadic R2 = Dyadic(major) * Dyadic(major), r2 = Dyadic(minor) * Dyadic(minor);
    const Dyadic two(2.0), four(4.0);
    // g = g0 + g1 t + g2 t^2, X = ww + 2 wd t + dd t^2, Y = wa + da t.
    const Dyadic g0 = ww + R2 - r2, g1 = two * wd, g2 = dd;
    const Dyadic g[3] = {g0, g1, g2};
    Dyadic gg[5];  // g^2
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) gg[i + j] = gg[i + j] + g[i] * g[j];
    // Q = aa X - Y^2.
    const Dyadic Q[3] = {aa * ww - wa * wa, aa * (two * wd) - two * wa * da, aa * dd - da * da};
    Poly F;
    for (int i = 0; i < 5; ++i) F.c.push_back(aa * gg[i] - (i < 3 ? four * R2 * Q[i] : Dyadic()));
    F.trim();
    if (F.degree() != 4) throw std::logic_error("TorusReference: the quartic lost its leading term");

    impl_->aa = aa;
    impl_->F.push_back(F);
    for (int k = 1; k <= 4; ++k) impl_->F.push_back(derivative(impl_->F.back()));
    for (int k = 0; k <= 3; ++k) impl_->derivative_chains.emplace_back(impl_->F[static_cast<size_t>(k)]);
    impl_->levels.push_back(F);
    impl_->chains.emplace_back(F);
    while (impl_->chains.back().gcd().degree() >= 1) {
        const Poly g = impl_->chains.back().gcd();
        impl_->levels.push_back(g);
        impl_->chains.emplace_back(g);
    }

    // ---- Fujiwara's bound, rounded up: all roots in (-B, B), B = 2^e ----
    mpfr_t bound, term;
    mpfr_init2(bound, 64);
    mpfr_init2(term, 64);
    mpfr_set_zero(bound, 1);
    for (int k = 1; k <= 4; ++k) {
        const Dyadic& ck = F.c[static_cast<size_t>(4 - k)];
        if (ck.zero()) continue;
        mpfr_div(term, ck.get(), F.c[4].get(), MPFR_RNDU);
        mpfr_abs(term, term, MPFR_RNDU);
        if (k == 4) mpfr_div_2ui(term, term, 1, MPFR_RNDU);
        mpfr_rootn_ui(term, term, static_cast<unsigned long>(k), MPFR_RNDU);
        mpfr_max(bound, bound, term, MPFR_RNDU);
    }
    mpfr_mul_2ui(bound, bound, 1, MPFR_RNDU);
    const long e = mpfr_zero_p(bound) ? 0 : std::max<long>(0, static_cast<long>(mpfr_get_exp(bound)));  // bound < 2^e
    mpfr_clear(bound);
    mpfr_clear(term);
    const Dyadic B = Dyadic(1.0).scaled(e);

    // ---- Isolation by bisection with Sturm counts (left to right) ----
    struct Interval {
        Dyadic lo, hi;
        int vlo, vhi;
    };
    const Sturm& S = impl_->chains[0];
    std::vector<Interval> isolated, stack;
    stack.push_back({-B, B, S.variations(-B), S.variations(B)});
    while (!stack.empty()) {
        Interval iv = std::move(stack.back());
        stack.pop_back();
        const int n = iv.vlo - iv.vhi;
        if (n <= 0) continue;
        if (n == 1) {
            isolated.push_back(std::move(iv));
            continue;
        }
        const Dyadic width = iv.hi - iv.lo;
        Dyadic m;
        bool found = false;
        for (int j : {8, 7, 9, 6, 10}) {
            m = iv.lo + (width * Dyadic(static_cast<double>(j))).scaled(-4);
            if (!eval(F, m).zero()) {
                found = true;
                break;
            }
        }
        if (!found) throw std::logic_error("TorusReference: five roots in one interval");
        const int vm = S.variations(m);
        stack.push_back({m, iv.hi, vm, iv.vhi});  // the right half after the left one
        stack.push_back({iv.lo, m, iv.vlo, vm});
    }

    // ---- Multiplicity and refinement of each root ----
    for (Interval& iv : isolated) {
        int m = 1;
        while (static_cast<size_t>(m) < impl_->levels.size() && impl_->count(static_cast<size_t>(m), iv.lo, iv.hi) == 1) ++m;
        const Poly& q = impl_->levels[static_cast<size_t>(m - 1)];
        Dyadic lo = iv.lo, hi = iv.hi;
        const int slo = eval(q, lo).sign(), shi = eval(q, hi).sign();
        if (slo == 0 || shi == 0 || slo == shi) throw std::logic_error("TorusReference: no sign change at a simple root");
        Dyadic root;
        bool on_root = false;
        if (lo.sign() < 0 && hi.sign() > 0 && eval(q, Dyadic()).zero()) on_root = true;  // root 0
        for (int it = 0; !on_root; ++it) {
            if (lo.to_double() == hi.to_double()) break;
            const Dyadic width = hi - lo;
            const long mag = std::max(lo.zero() ? -1200L : lo.high(), hi.zero() ? -1200L : hi.high());
            if (width.high() < std::max(mag - 200, -1200L) || it > 5000) break;
            const Dyadic mid = midpoint(lo, hi);
            const int s = eval(q, mid).sign();
            if (s == 0) {
                root = mid;
                on_root = true;
            } else if (s == slo) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        TorusRoot out;
        out.multiplicity = m;
        const Dyadic at = on_root ? root : midpoint(lo, hi);
        out.t = at.to_double();
        out.lo = (on_root ? at : lo).to_double(MPFR_RNDD);
        out.hi = (on_root ? at : hi).to_double(MPFR_RNDU);
        auto derivative_at = [&](int k) {
            mpfr_t v;
            mpfr_init2(v, 53);
            mpfr_div(v, eval(impl_->F[static_cast<size_t>(k)], at).get(), impl_->aa.get(), MPFR_RNDN);
            const double x = mpfr_get_d(v, MPFR_RNDN);
            mpfr_clear(v);
            return x;
        };
        out.slope = m >= 2 ? 0.0 : derivative_at(1);
        out.curvature = m >= 3 ? 0.0 : derivative_at(2);
        roots_.push_back(out);
    }
}

TorusReference::~TorusReference() = default;

double TorusReference::f(double t, int k) const {
    if (k < 0 || k > 4) throw std::invalid_argument("TorusReference::f: derivative order outside 0..4");
    mpfr_t v;
    mpfr_init2(v, 53);
    mpfr_div(v, eval(impl_->F[static_cast<size_t>(k)], Dyadic(t)).get(), impl_->aa.get(), MPFR_RNDN);
    const double x = mpfr_get_d(v, MPFR_RNDN);
    mpfr_clear(v);
    return x;
}

bool TorusReference::has_root_in(int k, double a, double b) const {
    if (k < 0 || k > 3 || !(a <= b)) throw std::invalid_argument("TorusReference::has_root_in: k outside 0..3 or a > b");
    const Poly& p = impl_->F[static_cast<size_t>(k)];
    const Dyadic da(a), db(b);
    if (eval(p, da).zero() || eval(p, db).zero()) return true;
    // Neither end is a root: Sturm's theorem counts the distinct roots in (a, b).
    const Sturm& S = impl_->derivative_chains[static_cast<size_t>(k)];
    return S.variations(da) - S.variations(db) > 0;
}

}  // namespace ltm::validation
