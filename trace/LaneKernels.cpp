// The SIMD kernels of the lockstep tracer, compiled once per instruction set (LaneKernels.h):
// this file is built for the x86-64 baseline inside ltm_trace, and again with AVX2 and with
// AVX-512 enabled (CMakeLists.txt); trace/Lanes.h sizes its vectors for the set it is compiled
// for, and its lane functions live in a namespace of that set, so the three builds never share
// an inline function. Each build defines its own entry in the table; the baseline build also
// chooses among them.
#include <cstring>

#include "trace/LaneKernels.h"
#include "trace/Lanes.h"
#include "trace/TraceTolerance.h"

namespace ltm::lanes {
inline namespace LTM_LANE_ISA {


static_assert(kRays % kLanes == 0);

LTM_LANE Real load(const double* p) {
    Real r;
    std::memcpy(&r, p, sizeof r);
    return r;
}
LTM_LANE Mask load(const std::int64_t* p) {
    Mask r;
    std::memcpy(&r, p, sizeof r);
    return r;
}
LTM_LANE void store(double* p, const Real& r) { std::memcpy(p, &r, sizeof r); }
LTM_LANE void store(std::int64_t* p, const Mask& r) { std::memcpy(p, &r, sizeof r); }
LTM_LANE Mask splat_int(std::int64_t k) {
    Mask r;
    for (int i = 0; i < kLanes; ++i) r[i] = k;
    return r;
}

LTM_LANE Bits load(const std::uint64_t* p) {
    Bits r;
    std::memcpy(&r, p, sizeof r);
    return r;
}
LTM_LANE void store(std::uint64_t* p, const Bits& r) { std::memcpy(p, &r, sizeof r); }

LTM_LANE V3 load(const Vec3s& v, int at) { return {load(v.x + at), load(v.y + at), load(v.z + at)}; }
LTM_LANE void store(Vec3s& v, int at, const V3& a) {
    store(v.x + at, a.x);
    store(v.y + at, a.y);
    store(v.z + at, a.z);
}



// Where a lane's segment [0, tmax] may meet the patch: a superset of may_hit's lanes (Patch.h),
// so a patch no lane of a chunk may meet is skipped for the chunk as analytic_hit skips it for
// each ray (its roots would not count: may_hit is conservative). The box test in z alone (the
// camera looks along z) and the rim's test of both ends inside the cylinder, whose margins
// (kCullMargin, kRimInsideMargin) exceed the rounding here by orders of magnitude. A NaN may.
LTM_LANE Mask may_meet(const Patch& p, const V3& o, const V3& d, const Real& tmax) {
    Mask may = splat_mask(true);
    if (!p.cull.empty()) {
        const Real z1 = select(d.z == splat(0.0), o.z, o.z + d.z * tmax);
        const Real lo = min(o.z, z1), hi = max(o.z, z1);
        may = ~((hi < splat(p.cull.lo.z)) | (lo > splat(p.cull.hi.z)));
    }
    if (p.kind == Patch::Kind::Rim) {
        const V3 u = splat(p.surface.axis), c = splat(p.surface.origin);
        const auto rho2 = [&](const V3& x) {
            const V3 v = x - c;
            const Real h = dot(v, u);
            return dot(v, v) - h * h;
        };
        const Real in = splat(p.rho2_inside);
        may &= ~((tmax < splat(INFINITY)) & (rho2(o) < in) & (rho2(o + d * tmax) < in));
    }
    return may;
}

// Tracer::analytic_hit for the lanes [at, at + kLanes), as far as SIMD twins reach: the nearest
// root of the object's patches (patch_root, the first root of each, the nearest in patch order as
// the scalar loop keeps it), the enclosed ellipsoids only culled (a lane whose segment comes near
// one is the scalar's), and on_surface where the winner is a cap (a rim hit is the scalar's).
LTM_LANE void analytic_chunk(const ObjectLanes& obj, SegmentLanes& s, int at) {
    const V3 o = load(s.o, at), d = load(s.d, at);
    Real best = splat(INFINITY);
    Mask which = splat_int(-1);
    for (int k = 0; k < obj.count; ++k) {
        const Patch& P = obj.patches[k];
        if (!any(may_meet(P, o, d, best))) continue;
        const Real t = patch_root(P, o, d);
        const Mask nearer = t < best;
        best = select(nearer, t, best);
        which = select(nearer, splat_int(k), which);
    }
    Mask scalar = splat_mask(false);
    for (int e = 0; e < obj.ellipsoid_count; ++e) scalar |= segment_near(obj.ellipsoids[e], o, d, best);
    const V3 p = o + d * best;
    V3 n = {splat(0.0), splat(0.0), splat(0.0)};
    Real offset = splat(0.0);
    for (int k = 0; k < obj.count; ++k) {
        const Mask won = which == splat_int(k);
        if (!any(won)) continue;
        const Surface& S = *obj.surfaces[k];
        if (obj.patches[k].kind != Patch::Kind::Cap ||
            !(S.kind == SurfaceKind::Sphere || S.kind == SurfaceKind::Plane)) {
            scalar |= won;
            continue;
        }
        V3 nk;
        Real ok;
        cap_surface(S, obj.normal_sign[k], p, nk, ok);
        n = select(won, nk, n);
        offset = select(won, ok, offset);
    }
    scalar |= (which >= splat_int(0)) & ~(finite(p) & finite(n) & finite(offset));
    store(s.t + at, best);
    store(s.which + at, which);
    store(s.p, at, p);
    store(s.n_out, at, n);
    store(s.offset + at, offset);
    store(s.scalar + at, scalar);
}
// The lanes [0, count) chunk by chunk (count a multiple of kLanes).
void analytic_segments(const ObjectLanes& obj, SegmentLanes& s, int count) {
    for (int at = 0; at < count; at += kLanes) analytic_chunk(obj, s, at);
}


// Tracer::refined_hit's first attempt for the lanes [at, at + kLanes) (RefineLanes).
LTM_LANE void refine_chunk(const ObjectLanes& obj, RefineLanes& r, int at, double origin_floor) {
    const V3 o = load(r.o, at), d = load(r.d, at);
    const Real ct = load(r.candidate_t + at);
    const Mask cap = load(r.patch + at);
    // omag = std::max({|o.x|, |o.y|, |o.z|, floor}): the first largest, by <.
    const Real omag = max(max(max(abs(o.x), abs(o.y)), abs(o.z)), splat(origin_floor));
    const Real cosf = abs(dot(d, load(r.face_normal, at)));
    const Real window = splat(2.0) * load(r.chord + at) / max(cosf, splat(trace_tol::kCandidateMinCos)) +
                        splat(trace_tol::kCandidateFloatUlps * trace_tol::kFloatUlp) * (omag + ct);
    // te = patch_hit(cap, o, d, 0, ct + window): the cap's first root, where it is below the bound.
    const Real inf = splat(INFINITY);
    const Real reach = ct + window;
    Real te = inf;
    for (int k = 0; k < obj.count; ++k) {
        const Mask mine = cap == splat_int(k);
        if (!any(mine)) continue;
        const Real root = patch_root(obj.patches[k], o, d);
        te = select(mine & (root < reach), root, te);
    }
    // Taken where the root is within the window (not before it: a guard hit; not beyond: a
    // spurious facet); the cap is then solved over (0, te], exact_guard's solved_patch.
    Mask ok = ~(te < ct - window) & (abs(te - ct) <= window);
    // exact_guard(o, d, te, cap): the other patches' first roots below the nearest so far.
    Real g = inf;
    for (int k = 0; k < obj.count; ++k) {
        const Mask guarded = ok & ~(cap == splat_int(k));
        const Real limit = select(g < te, g, te);
        if (!any(guarded & may_meet(obj.patches[k], o, d, limit))) continue;
        const Real root = patch_root(obj.patches[k], o, d);
        g = select(guarded & (root < limit), root, g);
    }
    ok &= ~(g < te);
    const V3 p = o + d * te;
    V3 n = {splat(0.0), splat(0.0), splat(0.0)};
    Real offset = splat(0.0);
    for (int k = 0; k < obj.count; ++k) {
        const Mask won = ok & (cap == splat_int(k));
        if (!any(won)) continue;
        V3 nk;
        Real offset_k;
        cap_surface(*obj.surfaces[k], obj.normal_sign[k], p, nk, offset_k);
        n = select(won, nk, n);
        offset = select(won, offset_k, offset);
    }
    ok &= finite(p) & finite(n) & finite(offset);
    // Tracer::packet_answers: no ellipsoid (which the packet does not see) near the segment up to
    // the candidate, widened far beyond its float rounding.
    const Real reach_e = ct * splat(1.0 + 1e-6);
    for (int e = 0; e < obj.ellipsoid_count; ++e) ok &= ~segment_near(obj.ellipsoids[e], o, d, reach_e);
    store(r.t + at, te);
    store(r.p, at, p);
    store(r.n_out, at, n);
    store(r.offset + at, offset);
    store(r.scalar + at, ~ok);
}
void refine_segments(const ObjectLanes& obj, RefineLanes& r, int count, double origin_floor) {
    for (int at = 0; at < count; at += kLanes) refine_chunk(obj, r, at, origin_floor);
}

// nf (the normal on the incident side), eta = n_from / n_to (interact's division), cos_i, fresnel,
// reflect and refract.
void fresnel_lanes(InteractLanes& a, int count) {
    for (int at = 0; at < count; at += kLanes) {
        const V3 d = load(a.d_in, at), n_out = load(a.n_out, at);
        const V3 nf = select(load(a.entering + at), n_out, -n_out);
        const Real eta = load(a.n_from + at) / load(a.n_to + at);
        const Real cos_i = -dot(d, nf);
        const Fresnel F = fresnel(cos_i, eta);
        store(a.reflectance + at, F.reflectance);
        store(a.tir + at, F.tir);
        store(a.reflected, at, reflect(d, nf));
        store(a.refracted, at, refract(d, nf, eta, cos_i, F.cos_t));
        // interact's choice: reflect under TIR without a draw, else where uniform() < R.
        Streams r{load(a.state + at), load(a.inc + at)};
        const Bits before = r.state;
        const Real u = uniform(r);
        store(a.reflect + at, F.tir | (u < F.reflectance));
        store(a.state + at, (Bits)select(F.tir, (Mask)before, (Mask)r.state));
    }
}

// The chosen direction normalized, and the spawn (Tracer::interact's spawn): stepped along the
// new direction by offset / cos clear of the surface, along the normal where near-tangent.
void spawn_lanes(InteractLanes& a, int count, double skip_floor) {
    for (int at = 0; at < count; at += kLanes) {
        const V3 n_out = load(a.n_out, at);
        const V3 nf = select(load(a.entering + at), n_out, -n_out);
        const V3 nd = normalize(select(load(a.reflect + at), load(a.reflected, at), load(a.refracted, at)));
        const Real dn = dot(nd, nf);
        const Real cos_new = abs(dn);
        const V3 side = select(dn > splat(0.0), nf, -nf);
        const V3 p = load(a.p, at);
        const Real offset = load(a.offset + at);
        const V3 o = select(cos_new > splat(trace_tol::kSpawnMinCos), p + nd * (offset / cos_new), p + side * offset);
        // (kSkipChords e + kSkipFloatUlps uf L) / max(|cos|, kCandidateMinCos); skip_floor is the
        // second term, the same product the scalar evaluates.
        const Real until = (splat(trace_tol::kSkipChords) * load(a.skip_chord + at) + splat(skip_floor)) /
                           max(abs(dot(nd, nf)), splat(trace_tol::kCandidateMinCos));
        store(a.o, at, o);
        store(a.d, at, nd);
        store(a.skip_until + at, until);
        store(a.finite + at, finite(nd));
    }
}

void camera(CameraLanes& c, int count) {
    for (int at = 0; at < count; at += kLanes) {
        Streams r = seed_streams(c.key, load(c.sample + at));
        Real u[4];
        uniform4(r, u);
        const Real u0 = u[0], u1 = u[1], u2 = u[2], u3 = u[3];
        store(c.state + at, r.state);
        store(c.inc + at, r.inc);
        // TelecentricCamera::sample_from.
        const Real strata = splat(c.strata);
        const Real fx = (load(c.stratum_x + at) + u0) / strata, fy = (load(c.stratum_y + at) + u1) / strata;
        const Real x = splat(c.half_width) + (splat(c.column) + fx) * splat(c.width) / splat(c.columns);
        const Real y = splat(c.half_height) - (splat(c.row) + fy) * splat(c.height) / splat(c.rows);
        const Real rr = splat(c.na) * sqrt(u2);
        const CosSin phi = cos_sin_turns(u3);
        const V3 dir{rr * phi.cos, rr * phi.sin, sqrt((splat(1.0) - rr) * (splat(1.0) + rr))};
        const V3 focus{x, y, splat(c.focus_z)};
        store(c.origin, at, focus - dir * (splat(c.depth) / dir.z));
        store(c.dir, at, dir);
    }
}

}  // namespace LTM_LANE_ISA

#if defined(__AVX512F__)
const Kernels* kernels_x86_64_v4() {
    static const Kernels k{"x86-64-v4", kLanes, analytic_segments, refine_segments, fresnel_lanes, spawn_lanes, camera};
    return &k;
}
#elif defined(__AVX2__)
const Kernels* kernels_x86_64_v3() {
    static const Kernels k{"x86-64-v3", kLanes, analytic_segments, refine_segments, fresnel_lanes, spawn_lanes, camera};
    return &k;
}
#else
#if defined(LTM_LANE_KERNELS_X86)
// Built from this file with AVX-512 and with AVX2 enabled (CMakeLists.txt).
const Kernels* kernels_x86_64_v4();
const Kernels* kernels_x86_64_v3();
#endif

std::vector<const Kernels*> runnable_kernels() {
    static const Kernels baseline{"baseline", kLanes, analytic_segments, refine_segments, fresnel_lanes, spawn_lanes, camera};
    std::vector<const Kernels*> out;
#if defined(LTM_LANE_KERNELS_X86)
    // The features the AVX-512 and AVX2 builds are compiled with (CMakeLists.txt).
    __builtin_cpu_init();
    const bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                    __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    const bool v4 = v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                    __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl") &&
                    __builtin_cpu_supports("avx512cd");
    if (v4) out.push_back(kernels_x86_64_v4());
    if (v3) out.push_back(kernels_x86_64_v3());
#endif
    out.push_back(&baseline);
    return out;
}

const Kernels& kernels() {
    static const Kernels* const best = runnable_kernels().front();
    return *best;
}
#endif

}  // namespace ltm::lanes
