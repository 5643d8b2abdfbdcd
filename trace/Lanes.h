#pragma once
// SIMD over the rays of a packet: one lane per ray (trace/LaneKernels.cpp, the kernels of the
// lockstep tracer, Tracer::lockstep).
//
// A lane value is a GCC/Clang vector as wide as the instruction set the including file is compiled
// for: 8 doubles with AVX-512, 4 with AVX2, 2 otherwise (trace/LaneKernels.cpp is compiled for
// each, CMakeLists.txt). The lane functions live in a namespace of that set (LTM_LANE_ISA), so
// files compiled for different sets never share one. A vector wider than the compiled set would
// be split by the compiler into pieces, element by element where a comparison is involved, and
// the compilers reject or warn of it as an ABI change: hence one width per set, not one per
// program with target attributes.
//
// Bit for bit. Every lane function below is the twin of a scalar function of the tracer (named in
// its comment) and performs the same IEEE operations on the same operands in the same order:
// + - * / and sqrt are correctly rounded whatever the instruction set, there is no contraction
// into fused multiply-adds (-ffp-contract=off, CMakeLists.txt), and a branch of the scalar code
// becomes a select of both sides. So each lane's result is the scalar function's result for that
// lane's inputs, bit for bit, on every machine (tests/trace_lanes.cpp checks every twin against
// its scalar function on random and edge-case inputs, and the kernels of every set against each
// other; tests/trace_packets.cpp whole paths).
// Where a twin cannot reproduce its scalar function (a root the twin does not solve, a NaN), the
// caller takes that lane back to the scalar code; the twins only ever cover common cases exactly.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "geometry/Vec3.h"
#include "trace/Optics.h"
#include "trace/Patch.h"
#include "trace/Rng.h"
#include "trace/SinCos.h"
#include "trace/TraceTolerance.h"

#if defined(__AVX512F__)
#define LTM_LANE_ISA isa_x86_64_v4
#define LTM_LANE_WIDTH 8
#elif defined(__AVX__)
#define LTM_LANE_ISA isa_x86_64_v3
#define LTM_LANE_WIDTH 4
#else
#define LTM_LANE_ISA isa_baseline
#define LTM_LANE_WIDTH 2
#endif

namespace ltm::lanes {
inline namespace LTM_LANE_ISA {

inline constexpr int kLanes = LTM_LANE_WIDTH;
using Real = double __attribute__((vector_size(8 * kLanes)));
// Comparisons give all bits set (true) or none (false) per lane; also the integer lanes.
using Mask = std::int64_t __attribute__((vector_size(8 * kLanes)));
// Unsigned 64-bit lanes: the random-number streams (wrapping arithmetic, logical shifts).
using Bits = std::uint64_t __attribute__((vector_size(8 * kLanes)));

#define LTM_LANE inline __attribute__((always_inline))

LTM_LANE Real splat(double x) {
    Real r;
    for (int i = 0; i < kLanes; ++i) r[i] = x;
    return r;
}
LTM_LANE Mask splat_mask(bool b) {
    Mask r;
    for (int i = 0; i < kLanes; ++i) r[i] = b ? -1 : 0;
    return r;
}
LTM_LANE Mask as_bits(const Real& x) { return (Mask)x; }
LTM_LANE Real as_real(const Mask& m) { return (Real)m; }
// m ? a : b per lane (the bits of a where m is set).
LTM_LANE Real select(const Mask& m, const Real& a, const Real& b) {
    return as_real((as_bits(a) & m) | (as_bits(b) & ~m));
}
LTM_LANE Mask select(const Mask& m, const Mask& a, const Mask& b) { return (a & m) | (b & ~m); }
LTM_LANE bool any(const Mask& m) {
    std::int64_t r = 0;
    for (int i = 0; i < kLanes; ++i) r |= m[i];
    return r != 0;
}
// std::sqrt per lane (correctly rounded: the same bits as the scalar call).
LTM_LANE Real sqrt(const Real& x) {
    Real r;
    for (int i = 0; i < kLanes; ++i) r[i] = __builtin_sqrt(x[i]);
    return r;
}
inline constexpr std::int64_t kSignBit = INT64_MIN;
// std::fabs and std::copysign: the sign bit cleared, or taken from b.
LTM_LANE Real abs(const Real& x) { return as_real(as_bits(x) & ~kSignBit); }
LTM_LANE Real copysign(const Real& mag, const Real& sign) {
    return as_real((as_bits(mag) & ~kSignBit) | (as_bits(sign) & kSignBit));
}
// std::min and std::max of two: (b < a) ? b : a and (a < b) ? b : a.
LTM_LANE Real min(const Real& a, const Real& b) { return select(b < a, b, a); }
LTM_LANE Real max(const Real& a, const Real& b) { return select(a < b, b, a); }
// std::isfinite per lane.
LTM_LANE Mask finite(const Real& x) { return abs(x) < splat(INFINITY); }  // false for NaN too

// Three lane values: a Vec3 per lane. The operators are Vec3's, component by component.
struct V3 {
    Real x, y, z;
};
LTM_LANE V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
LTM_LANE V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
LTM_LANE V3 operator*(const V3& a, const Real& s) { return {a.x * s, a.y * s, a.z * s}; }
LTM_LANE V3 operator/(const V3& a, const Real& s) { return {a.x / s, a.y / s, a.z / s}; }
LTM_LANE V3 operator-(const V3& a) { return {-a.x, -a.y, -a.z}; }
LTM_LANE V3 splat(const Vec3& v) { return {splat(v.x), splat(v.y), splat(v.z)}; }
LTM_LANE Real dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
LTM_LANE Real length(const V3& v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
LTM_LANE V3 normalize(const V3& v) { return v / length(v); }
LTM_LANE V3 select(const Mask& m, const V3& a, const V3& b) {
    return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}
LTM_LANE Mask finite(const V3& v) { return finite(v.x) & finite(v.y) & finite(v.z); }

// ---- Roots (trace/Intersect.h) --------------------------------------------------------------------
// The two roots of solve_quadratic ascending (lo <= hi), where `real` is set; elsewhere none.
struct Quadratic {
    Real lo, hi;
    Mask real;
};
// solve_quadratic(a, b, c, disc) where a != 0 in every lane (the sphere's a = 1; the cylinder's
// callers take a == 0 lanes apart): q = -(b + copysign(sqrt(disc), b)) / 2, t0 = q / a,
// t1 = c / q (t0 where q = 0), ascending by std::min and std::max.
LTM_LANE Quadratic solve_quadratic(const Real& a, const Real& b, const Real& c, const Real& disc) {
    const Real q = splat(-0.5) * (b + copysign(sqrt(disc), b));
    const Real t0 = q / a;
    const Real t1 = select(q != splat(0.0), c / q, t0);
    return {min(t0, t1), max(t0, t1), disc >= splat(0.0)};
}
// intersect_sphere(c, r, o, d): the discriminant from the line's distance to the centre.
LTM_LANE Quadratic sphere_roots(const Vec3& centre, double radius, const V3& o, const V3& d) {
    const V3 oc = o - splat(centre);
    const Real b = dot(oc, d);
    const V3 perp = oc - d * b;
    const Real lp = length(perp), lo = length(oc);
    const Real r = splat(radius);
    // a = 1: q / 1 is q, which solve_quadratic's division gives too.
    return solve_quadratic(splat(1.0), splat(2.0) * b, (lo - r) * (lo + r), splat(4.0) * (r - lp) * (r + lp));
}
// intersect_cylinder(c, u, r, o, d) (no roots where the ray is parallel to the axis, a = 0).
LTM_LANE Quadratic cylinder_roots(const Vec3& centre, const Vec3& axis, double radius, const V3& o, const V3& d) {
    const V3 u = splat(axis);
    const V3 oc = o - splat(centre);
    const V3 ocp = oc - u * dot(oc, u), dp = d - u * dot(d, u);
    const Real a = dot(dp, dp);
    const Mask axial = a == splat(0.0);
    const Real a_safe = select(axial, splat(1.0), a);  // the lanes with a = 0 have no roots anyway
    const Real b = dot(ocp, dp);
    const V3 perp = ocp - dp * (b / a_safe);
    const Real lp = length(perp), lo = length(ocp);
    const Real r = splat(radius);
    Quadratic q = solve_quadratic(a_safe, splat(2.0) * b, (lo - r) * (lo + r), splat(4.0) * a_safe * (r - lp) * (r + lp));
    q.real &= ~axial;
    return q;
}

// on_patch(p, o + d t) for a cap or the rim (Patch.h); closed patches are not lane patches.
LTM_LANE Mask on_patch(const Patch& p, const V3& o, const V3& d, const Real& t) {
    const V3 x = o + d * t;
    if (p.kind == Patch::Kind::Rim) return (x.z >= splat(p.z_min)) & (x.z <= splat(p.z_max));
    Mask on = ~(x.x * x.x + x.y * x.y > splat(p.rho2_max));
    if (p.surface.kind == SurfaceKind::Sphere) {
        const double zc = p.surface.origin.z;
        on &= ~((x.z - splat(zc)) * splat(p.z_vertex - zc) <= splat(0.0));
    }
    return on;
}
// patch_hit(p, o, d, 0, inf) for a lane patch: the first root in (0, inf) on the patch, or +inf.
// (patch_hit(p, o, d, 0, tmax) is this where it is below tmax and +inf elsewhere: the roots come
// ascending, so the first on the patch below tmax is the first on the patch.)
LTM_LANE Real patch_root(const Patch& p, const V3& o, const V3& d) {
    const Surface& s = p.surface;
    const Real inf = splat(INFINITY), zero = splat(0.0);
    if (s.kind == SurfaceKind::Plane) {
        // intersect(): one root dot(origin - o, axis) / dot(d, axis) unless the ray is parallel.
        const V3 n = splat(s.axis);
        const Real dn = dot(d, n);
        const Real t = dot(splat(s.origin) - o, n) / dn;
        const Mask ok = (dn != zero) & (t > zero) & (t < inf) & on_patch(p, o, d, t);
        return select(ok, t, inf);
    }
    const Quadratic q = s.kind == SurfaceKind::Sphere ? sphere_roots(s.origin, s.radius, o, d)
                                                      : cylinder_roots(s.origin, s.axis, s.radius, o, d);
    const Mask ok_lo = q.real & (q.lo > zero) & (q.lo < inf) & on_patch(p, o, d, q.lo);
    const Mask ok_hi = q.real & (q.hi > zero) & (q.hi < inf) & on_patch(p, o, d, q.hi);
    return select(ok_lo, q.lo, select(ok_hi, q.hi, inf));
}
// segment_near(p, o, d, tmax) (Patch.h): the segment comes within the patch's bounding sphere.
LTM_LANE Mask segment_near(const Patch& p, const V3& o, const V3& d, const Real& tmax) {
    const V3 v = splat(p.centre) - o;
    const Real vd = dot(v, d);
    const Real lo = select(vd > splat(0.0), vd, splat(0.0));
    const Real tc = select(tmax < lo, tmax, lo);
    const V3 w = v - d * tc;
    return dot(w, w) <= splat(p.bounding_radius * p.bounding_radius);
}

// ---- Surfaces (Tracer::on_surface, Intersect.h) -----------------------------------------------------
// point_rounding_bound(s, p): kPointErrorUlps u of (max |p_i| + max |origin_i| + radius +
// minor_radius + max semi-axis), summed in that order.
LTM_LANE Real point_rounding_bound(const Surface& s, const V3& p) {
    constexpr double u = std::numeric_limits<double>::epsilon() * 0.5;
    const Real px = abs(p.x), py = abs(p.y), pz = abs(p.z);
    // std::max({a, b, c}): the first largest, by <.
    const Real pmax = max(max(px, py), pz);
    const double omax = std::max({std::fabs(s.origin.x), std::fabs(s.origin.y), std::fabs(s.origin.z)});
    const double smax = std::max({s.semi_axes.x, s.semi_axes.y, s.semi_axes.z});
    const Real mag = pmax + splat(omax) + splat(s.radius) + splat(s.minor_radius) + splat(smax);
    return splat(trace_tol::kPointErrorUlps * u) * mag;
}
// The unit normal (inside -> outside, by normal_sign) and spawn offset of a hit at p on a sphere
// or a plane, as Tracer::on_surface computes them (the sphere's one distance |p - c| for both).
LTM_LANE void cap_surface(const Surface& s, int normal_sign, const V3& p, V3& n_out, Real& offset) {
    const Real sign = splat(static_cast<double>(normal_sign));
    const Real bounds = splat(trace_tol::kSpawnOffsetBounds);
    if (s.kind == SurfaceKind::Sphere) {
        const V3 v = p - splat(s.origin);
        const Real r = length(v);
        n_out = (v / r) * sign;
        offset = bounds * (abs(r - splat(s.radius)) + point_rounding_bound(s, p));
    } else {  // a plane: Surface::normal is its axis, signed_distance dot(p - origin, axis)
        n_out = splat(s.axis) * sign;
        offset = bounds * (abs(dot(p - splat(s.origin), splat(s.axis))) + point_rounding_bound(s, p));
    }
}

// ---- Optics (trace/Optics.h) ----------------------------------------------------------------------
// fresnel(cos_i, eta): where `tir` is set the reflectance is 1 and cos_t 0, as the scalar returns.
struct Fresnel {
    Real reflectance, cos_t;
    Mask tir;
};
LTM_LANE Fresnel fresnel(const Real& cos_i_in, const Real& eta) {
    const Real one = splat(1.0);
    const Real c = abs(cos_i_in);
    const Real cos_i = select(c <= one, c, one);  // 1 for a NaN, as the scalar
    const Real sin2_t = eta * eta * (one - cos_i) * (one + cos_i);
    const Mask tir = sin2_t >= one;
    const Real cos_t = sqrt((one - sin2_t));
    const Real rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const Real rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const Real r = splat(0.5) * (rs * rs + rp * rp);
    return {select(tir, one, r), select(tir, splat(0.0), cos_t), tir};
}
// reflect(d, n) and refract(d, n, eta, cos_i, cos_t).
LTM_LANE V3 reflect(const V3& d, const V3& n) { return d - n * (splat(2.0) * dot(d, n)); }
LTM_LANE V3 refract(const V3& d, const V3& n, const Real& eta, const Real& cos_i, const Real& cos_t) {
    return d * eta + n * (eta * cos_i - cos_t);
}

// ---- The camera's azimuth (trace/SinCos.h) --------------------------------------------------------
// cos_sin_turns(u): the same operations, the quarter turn's swap and signs as selects.
struct CosSin {
    Real cos, sin;
};
LTM_LANE CosSin cos_sin_turns(const Real& u) {
    using namespace ltm::sincos_detail;
    const Real q = splat(4.0) * u;
    const Real shifted = q + splat(kRoundInteger);
    const Real k = shifted - splat(kRoundInteger);
    const Real x = (q - k) * splat(kHalfPi);
    const Real z = x * x;
    const Real sr = splat(S2) + z * (splat(S3) + z * (splat(S4) + z * (splat(S5) + z * splat(S6))));
    const Real s = x + z * x * (splat(S1) + z * sr);
    const Real cr = z * (splat(C1) + z * (splat(C2) + z * (splat(C3) + z * (splat(C4) + z * (splat(C5) + z * splat(C6))))));
    const Real hz = splat(0.5) * z, w = splat(1.0) - hz;
    const Real c = w + (((splat(1.0) - w) - hz) + z * cr);
    const Mask quarter = as_bits(shifted) & 3;  // k mod 4, as the scalar reads it
    const Mask odd = (quarter & 1) != 0, neg_cos = ((quarter + 1) & 2) != 0, neg_sin = (quarter & 2) != 0;
    const Real a = select(odd, s, c), b = select(odd, c, s);
    return {select(neg_cos, -a, a), select(neg_sin, -b, b)};
}

// ---- Random numbers (trace/Rng.h) -------------------------------------------------------------------
// Integer twins: wrapping multiplication, shifts and xor give the scalar code's bits on any set.
LTM_LANE Bits splat_bits(std::uint64_t x) {
    Bits r;
    for (int i = 0; i < kLanes; ++i) r[i] = x;
    return r;
}
// splitmix64 per lane.
LTM_LANE Bits splitmix64(Bits x) {
    x += splat_bits(0x9e3779b97f4a7c15ull);
    x = (x ^ (x >> 30)) * splat_bits(0xbf58476d1ce4e5b9ull);
    x = (x ^ (x >> 27)) * splat_bits(0x94d049bb133111ebull);
    return x ^ (x >> 31);
}
// PCG32 streams, one per lane: Rng's state and increment.
struct Streams {
    Bits state, inc;
};
// Rng(seed, a, b) per lane, given key = splitmix64(seed) ^ splitmix64(a + Rng::kStreamA) (the same
// in every lane; xor is associative and commutative, so the hash of the three is unchanged).
LTM_LANE Streams seed_streams(std::uint64_t key, const Bits& b) {
    const Bits h = splitmix64(splat_bits(key) ^ splitmix64(b + splat_bits(Rng::kStreamB)));
    const Bits inc = (splitmix64(h) << 1) | splat_bits(1);
    // The constructor's two steps from state 0: 0 * M + inc, plus h, then one more step.
    const Bits state = (inc + h) * splat_bits(Rng::kMultiplier) + inc;
    return {state, inc};
}
// PCG32's output of a state (Rng::next_u32's result from the state before its step), per lane:
// the 32-bit result in the low half of each lane.
LTM_LANE Bits pcg_output(const Bits& old) {
    const Bits low = splat_bits(0xffffffffull);
    const Bits xorshifted = (((old >> 18) ^ old) >> 27) & low;
    const Bits rot = old >> 59;
    return ((xorshifted >> rot) | (xorshifted << ((splat_bits(32) - rot) & splat_bits(31)))) & low;
}
// Rng::next_u32 per lane.
LTM_LANE Bits next_u32(Streams& r) {
    const Bits old = r.state;
    r.state = old * splat_bits(Rng::kMultiplier) + r.inc;
    return pcg_output(old);
}
// Rng::uniform's 53 bits from two outputs, converted exactly (below 2^53) and scaled by 2^-53.
LTM_LANE Real uniform_of(const Bits& hi, const Bits& lo) {
    const Mask bits = (Mask)(((hi << 32) | lo) >> 11);
    return __builtin_convertvector(bits, Real) * splat(0x1.0p-53);
}
// Rng::uniform per lane.
LTM_LANE Real uniform(Streams& r) {
    const Bits hi = next_u32(r), lo = next_u32(r);
    return uniform_of(hi, lo);
}
// The LCG's j-th state from x, x_j = M^j x + (M^(j-1) + ... + M + 1) inc (mod 2^64): the jump's
// two factors, for the state and for the increment.
struct Jump {
    std::uint64_t state, inc;
};
constexpr Jump lcg_jump(int j) {
    Jump a{1, 0};
    for (int i = 0; i < j; ++i) a = {a.state * Rng::kMultiplier, a.inc * Rng::kMultiplier + 1};
    return a;
}
// Four Rng::uniform draws per lane, and the streams after them: the eight states they read each
// from the first by its jump (wrapping arithmetic: the very states the eight steps reach), so the
// eight multiplications do not wait on one another as the steps' chain does (perf: as a chain,
// its latency would be the camera kernel's time).
LTM_LANE void uniform4(Streams& r, Real (&u)[4]) {
    const Bits x = r.state, inc = r.inc;
    const auto state = [&](int j) {
        const Jump a = lcg_jump(j);
        return splat_bits(a.state) * x + splat_bits(a.inc) * inc;
    };
    u[0] = uniform_of(pcg_output(x), pcg_output(state(1)));
    u[1] = uniform_of(pcg_output(state(2)), pcg_output(state(3)));
    u[2] = uniform_of(pcg_output(state(4)), pcg_output(state(5)));
    u[3] = uniform_of(pcg_output(state(6)), pcg_output(state(7)));
    r.state = state(8);
}

}  // namespace LTM_LANE_ISA
}  // namespace ltm::lanes
