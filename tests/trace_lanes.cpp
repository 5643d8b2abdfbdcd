// The SIMD twins of trace/Lanes.h give every lane the bits its scalar function gives for that
// lane's inputs: the roots of a sphere and a cylinder, on_patch, patch_hit, segment_near,
// point_rounding_bound, a cap's normal and spawn offset (Tracer::on_surface), fresnel, reflect and
// refract, on random rays through lenses of every cap kind and on edge cases (axial and
// face-parallel rays, rays from a centre, grazing and total internal reflection, NaN and infinite
// inputs). This file is compiled for the baseline (2 lanes); the kernels built from the same twins
// for AVX2 and AVX-512 (trace/LaneKernels.h) must give the baseline kernels' bits on the same
// inputs, which the second test checks on every set this processor runs.
// The expected values are the scalar functions' own results, which the rest of the suite checks
// against closed forms; this test fixes only that the lanes reproduce them exactly, which the
// byte-identical outputs of the lockstep tracer (tests/trace_packets.cpp) rely on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "geometry/Lens.h"
#include "trace/Camera.h"
#include "trace/LaneKernels.h"
#include "trace/Lanes.h"
#include "trace/Optics.h"
#include "trace/Patch.h"
#include "trace/Rng.h"
#include "trace/SinCos.h"

using namespace ltm;
using lanes::kLanes;

namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// One batch of lanes: the inputs, and every twin's outputs.
struct Batch {
    lanes::V3 o, d;         // rays
    lanes::Real t, tmax;    // a parameter along each ray (on_patch), a segment end (segment_near)
    lanes::V3 p;            // points (cap_surface, point_rounding_bound)
    lanes::V3 n;            // unit normals against d (reflect, refract)
    lanes::Real cos_i, eta; // fresnel's arguments
    lanes::Quadratic sphere, cylinder;
    lanes::Real root;       // patch_root
    lanes::Mask on, near;
    lanes::Real rounding, offset;
    lanes::V3 normal;
    lanes::Fresnel fresnel;
    lanes::V3 reflected, refracted;
};

// What a batch is evaluated against: one patch of a lens, the lens's rim (its cylinder), a cap
// surface with its normal sign, and a closed patch (segment_near).
struct Shapes {
    const Patch* patch;
    const Patch* rim;
    const Surface* cap;
    int sign;
    const Patch* closed;
};

void evaluate(const Shapes& s, Batch& b) {
    const Surface& rim = s.rim->surface;
    if (s.cap->kind == SurfaceKind::Sphere) b.sphere = lanes::sphere_roots(s.cap->origin, s.cap->radius, b.o, b.d);
    b.cylinder = lanes::cylinder_roots(rim.origin, rim.axis, rim.radius, b.o, b.d);
    b.root = lanes::patch_root(*s.patch, b.o, b.d);
    b.on = lanes::on_patch(*s.patch, b.o, b.d, b.t);
    b.near = lanes::segment_near(*s.closed, b.o, b.d, b.tmax);
    b.rounding = lanes::point_rounding_bound(*s.cap, b.p);
    lanes::cap_surface(*s.cap, s.sign, b.p, b.normal, b.offset);
    b.fresnel = lanes::fresnel(b.cos_i, b.eta);
    b.reflected = lanes::reflect(b.d, b.n);
    b.refracted = lanes::refract(b.d, b.n, b.eta, b.cos_i, b.fresnel.cos_t);
}

Vec3 lane(const lanes::V3& v, int j) { return {v.x[j], v.y[j], v.z[j]}; }
void set(lanes::V3& v, int j, const Vec3& x) {
    v.x[j] = x.x;
    v.y[j] = x.y;
    v.z[j] = x.z;
}

// Expects the bits of a lane vector and of its scalar counterpart to agree.
#define EXPECT_SAME_BITS(lane_value, scalar_value, what)                                              \
    EXPECT_TRUE(same_bits(lane_value, scalar_value))                                                 \
        << what << ": lane " << (lane_value) << " scalar " << (scalar_value) << " (" << context << ")"
#define EXPECT_SAME_VEC(lane_vec, scalar_vec, what)               \
    do {                                                          \
        const Vec3 lv = lane(lane_vec, j), sv = (scalar_vec);     \
        EXPECT_SAME_BITS(lv.x, sv.x, what << ".x");               \
        EXPECT_SAME_BITS(lv.y, sv.y, what << ".y");               \
        EXPECT_SAME_BITS(lv.z, sv.z, what << ".z");               \
    } while (0)

// Every lane of an evaluated batch against the scalar functions.
void expect_scalar(const Shapes& s, const Batch& b, const std::string& where) {
    const Surface& rim = s.rim->surface;
    for (int j = 0; j < kLanes; ++j) {
        const std::string context = where + ", lane " + std::to_string(j);
        const Vec3 o = lane(b.o, j), d = lane(b.d, j), p = lane(b.p, j), n = lane(b.n, j);
        if (s.cap->kind == SurfaceKind::Sphere) {
            const Roots r = intersect_sphere(s.cap->origin, s.cap->radius, o, d);
            EXPECT_EQ(b.sphere.real[j] != 0, r.count == 2) << context;
            if (r.count == 2 && b.sphere.real[j]) {
                EXPECT_SAME_BITS(b.sphere.lo[j], r.t[0], "sphere lo");
                EXPECT_SAME_BITS(b.sphere.hi[j], r.t[1], "sphere hi");
            }
        }
        const Roots c = intersect_cylinder(rim.origin, rim.axis, rim.radius, o, d);
        EXPECT_EQ(b.cylinder.real[j] != 0, c.count == 2) << context;
        if (c.count == 2 && b.cylinder.real[j]) {
            EXPECT_SAME_BITS(b.cylinder.lo[j], c.t[0], "cylinder lo");
            EXPECT_SAME_BITS(b.cylinder.hi[j], c.t[1], "cylinder hi");
        }
        EXPECT_SAME_BITS(b.root[j], patch_hit(*s.patch, o, d, 0.0, INFINITY), "patch_hit");
        EXPECT_EQ(b.on[j] != 0, on_patch(*s.patch, o + d * b.t[j])) << context;
        EXPECT_EQ(b.near[j] != 0, segment_near(*s.closed, o, d, b.tmax[j])) << context;
        EXPECT_SAME_BITS(b.rounding[j], point_rounding_bound(*s.cap, p), "point_rounding_bound");
        // Tracer::on_surface: Surface::normal signed, kSpawnOffsetBounds point_error_bound.
        EXPECT_SAME_VEC(b.normal, s.cap->normal(p) * static_cast<double>(s.sign), "normal");
        EXPECT_SAME_BITS(b.offset[j], trace_tol::kSpawnOffsetBounds * point_error_bound(*s.cap, p), "offset");
        const FresnelResult f = fresnel(b.cos_i[j], b.eta[j]);
        EXPECT_EQ(b.fresnel.tir[j] != 0, f.total_internal_reflection) << context;
        EXPECT_SAME_BITS(b.fresnel.reflectance[j], f.reflectance, "reflectance");
        EXPECT_SAME_BITS(b.fresnel.cos_t[j], f.cos_t, "cos_t");
        EXPECT_SAME_VEC(b.reflected, reflect(d, n), "reflect");
        EXPECT_SAME_VEC(b.refracted, refract(d, n, b.eta[j], b.cos_i[j], f.cos_t), "refract");
    }
}

Vec3 random_unit(std::mt19937_64& g) {
    std::normal_distribution<double> n;
    for (;;) {
        const Vec3 v{n(g), n(g), n(g)};
        if (length(v) > 1e-3) return normalize(v);
    }
}

// Lens specs with every cap kind the twins cover: convex and concave spheres, planes, a ball.
std::vector<LensSpec> lenses() {
    std::vector<LensSpec> out;
    auto add = [&](double r1, double r2, double t, double diameter) {
        LensSpec s;
        s.r1 = r1;
        s.r2 = r2;
        s.center_thickness = t;
        s.diameter = diameter;
        s.ior = 1.5;
        out.push_back(s);
    };
    add(50.0, -50.0, 8.0, 25.4);       // double convex (the paper's)
    add(40.0, INFINITY, 7.0, 24.0);    // plano-convex
    add(-30.0, 30.0, 3.0, 20.0);       // biconcave
    add(30.0, 60.0, 4.0, 20.0);        // meniscus
    add(INFINITY, INFINITY, 5.0, 20.0);  // window
    out.push_back(ball_spec(5.0, 1.5));
    return out;
}

}  // namespace

TEST(Lanes, EveryTwinGivesItsScalarFunctionsBits) {
    std::mt19937_64 g(20261203);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const double specials[] = {0.0, -0.0, 1.0, -1.0, 1e-300, INFINITY, -INFINITY, NAN};
    const double etas[] = {1.0 / 1.5, 1.5, 1.0 / 1.72, 1.72, 1.0, 1.0 / 2.4};
    Patch closed;  // an ellipsoid's bounding sphere, re-drawn for every batch
    closed.kind = Patch::Kind::Closed;
    {
        for (const LensSpec& spec : lenses()) {
            const Lens lens(spec);
            const std::vector<Patch> patches = object_patches(lens);
            const double a = lens.aperture_radius();
            for (size_t k = 0; k < patches.size(); ++k) {
                ASSERT_TRUE(lanes::lane_patch(patches[k])) << k;
                const Patch& cap = patches[k < 2 ? k : 0];
                const Shapes shapes{&patches[k], &patches[2], &cap.surface, k == 1 ? -1 : 1, &closed};
                for (int batch = 0; batch < 400; ++batch) {
                    Batch b{};
                    closed.centre = {u(g) * a, u(g) * a, u(g) * a};
                    closed.bounding_radius = 0.1 + std::fabs(u(g)) * a / 4;
                    for (int j = 0; j < kLanes; ++j) {
                        // Rays from around the lens: random directions, near-axial ones (the
                        // telecentric camera's), exactly axial and exactly face-parallel ones,
                        // rays from the cap's centre, and now and then a non-finite coordinate.
                        Vec3 o{u(g) * 2 * a, u(g) * 2 * a, u(g) * 3 * a};
                        Vec3 d = random_unit(g);
                        switch ((batch + j) % 8) {
                            case 0: d = normalize(Vec3{u(g) * 0.05, u(g) * 0.05, 1.0}); break;
                            case 1: d = {0.0, 0.0, u(g) < 0 ? -1.0 : 1.0}; break;
                            case 2: d = normalize(Vec3{u(g), u(g), 0.0}); break;
                            case 3: o = cap.surface.origin; break;
                            case 4: o.x = specials[static_cast<size_t>(batch) % 8]; break;
                            default: break;
                        }
                        set(b.o, j, o);
                        set(b.d, j, d);
                        // A root of the patch where it has one (on its boundary tests' edge more
                        // often than a random t), else a random parameter.
                        const double root = patch_hit(patches[k], o, d, 0.0, INFINITY);
                        b.t[j] = (j % 2 == 0 && root < INFINITY) ? root : u(g) * 4 * a;
                        b.tmax[j] = j % 5 == 0 ? INFINITY : std::fabs(u(g)) * 4 * a;
                        // Points on the cap (its hits) and off it.
                        const double hit = patch_hit(cap, o, d, 0.0, INFINITY);
                        set(b.p, j, j % 3 != 0 && hit < INFINITY ? o + d * hit : Vec3{u(g) * a, u(g) * a, u(g) * a});
                        set(b.n, j, random_unit(g));
                        b.cos_i[j] = j == 7 ? specials[static_cast<size_t>(batch) % 8] : 1.1 * u(g);
                        b.eta[j] = etas[static_cast<size_t>(batch + j) % 6];
                    }
                    evaluate(shapes, b);
                    expect_scalar(shapes, b,
                                  "lens r1 " + std::to_string(spec.r1) + ", patch " +
                                      std::to_string(k) + ", batch " + std::to_string(batch));
                    if (::testing::Test::HasFailure()) return;  // one report, not thousands
                }
            }
        }
    }
}

// Lane helpers with the scalar library's semantics where the twins rely on them: std::min and
// std::max keep the first argument on ties and NaNs, copysign and abs act on the sign bit alone.
TEST(Lanes, HelpersFollowTheStandardLibrary) {
    const double v[] = {0.0, -0.0, 1.5, -2.25, INFINITY, -INFINITY, NAN, 1e-310};
    for (double x : v)
        for (double y : v) {
            const lanes::Real a = lanes::splat(x), b = lanes::splat(y);
            EXPECT_TRUE(same_bits(lanes::min(a, b)[kLanes - 1], std::min(x, y))) << x << " " << y;
            EXPECT_TRUE(same_bits(lanes::max(a, b)[kLanes - 1], std::max(x, y))) << x << " " << y;
            EXPECT_TRUE(same_bits(lanes::copysign(a, b)[kLanes - 1], std::copysign(x, y))) << x << " " << y;
        }
    for (double x : v) {
        const lanes::Real a = lanes::splat(x);
        EXPECT_TRUE(same_bits(lanes::abs(a)[0], std::fabs(x))) << x;
        EXPECT_EQ(lanes::finite(a)[kLanes - 1] != 0, std::isfinite(x)) << x;
        EXPECT_TRUE(same_bits(lanes::sqrt(a)[kLanes - 1], std::sqrt(x)) || (std::isnan(x) || x < 0)) << x;
    }
}

// The camera azimuth's twin (lanes::cos_sin_turns) against the scalar cos_sin_turns, bit for bit:
// every quarter turn's swap and signs, the reduction's ties (odd multiples of 1/8), the largest
// remainders beside them, tiny and negative u, non-finite u, and random draws.
TEST(Lanes, CosSinTurnsIsTheScalars) {
    std::vector<double> us = {0.0, -0.0, 0.25, 0.5, 0.75, 1.0, -0.25, 1e-300, -1e-300, 3.5, INFINITY, NAN};
    for (int k = 0; k <= 16; ++k) {
        us.push_back(k / 16.0);
        us.push_back(std::nextafter(k / 16.0, 0.0));
        us.push_back(std::nextafter(k / 16.0, 1.0));
    }
    std::mt19937_64 g(5);
    for (int i = 0; i < 4096; ++i) us.push_back(static_cast<double>(g() >> 11) * 0x1.0p-53);
    for (size_t at = 0; at < us.size(); at += kLanes) {
        lanes::Real u = lanes::splat(0.5);
        for (int j = 0; j < kLanes && at + static_cast<size_t>(j) < us.size(); ++j) u[j] = us[at + static_cast<size_t>(j)];
        const lanes::CosSin got = lanes::cos_sin_turns(u);
        for (int j = 0; j < kLanes; ++j) {
            const CosSin want = cos_sin_turns(u[j]);
            ASSERT_TRUE(same_bits(got.cos[j], want.cos)) << "u = " << u[j];
            ASSERT_TRUE(same_bits(got.sin[j], want.sin)) << "u = " << u[j];
        }
    }
}

// The kernels of every instruction set this processor runs (AVX-512, AVX2, the baseline) give the
// same bits on the same packets: the nearest patch roots, hit points, normals and offsets of rays
// through every kind of lens with ellipsoids in it, facet candidates refined on the caps, and
// Fresnel, Snell and the spawn of the next ray. With the baseline's twins equal to the scalar functions (above), every set is the scalar
// tracer, lane by lane; kernels() is the widest.
TEST(Lanes, EveryInstructionSetsKernelsGiveTheSameBits) {
    const std::vector<const lanes::Kernels*> sets = lanes::runnable_kernels();
    ASSERT_FALSE(sets.empty());
    EXPECT_EQ(&lanes::kernels(), sets.front());
    EXPECT_STREQ(sets.back()->isa, "baseline");
    for (const lanes::Kernels* k : sets) EXPECT_EQ(lanes::kRays % k->lanes, 0) << k->isa;
    std::mt19937_64 g(4242);
    long refined_lanes = 0, refined_scalar = 0;  // both outcomes of the refinement occur
    long tir_lanes = 0, drawn_lanes = 0;          // both outcomes of the Fresnel choice occur
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (const LensSpec& spec : lenses()) {
        const Lens lens(spec);
        const std::vector<Patch> patches = object_patches(lens);
        const double a = lens.aperture_radius();
        std::vector<Patch> ellipsoids(2);
        lanes::ObjectLanes obj;
        obj.patches = patches.data();
        obj.count = static_cast<int>(patches.size());
        for (int k = 0; k < obj.count; ++k) {
            obj.surfaces[k] = &patches[static_cast<size_t>(k)].surface;
            obj.normal_sign[k] = k == 1 ? -1 : 1;
        }
        obj.ellipsoids = ellipsoids.data();
        obj.ellipsoid_count = 2;
        for (int batch = 0; batch < 300; ++batch) {
            for (Patch& e : ellipsoids) {
                e.kind = Patch::Kind::Closed;
                e.centre = {u(g) * a, u(g) * a, u(g) * a};
                e.bounding_radius = 0.05 + std::fabs(u(g)) * a / 8;
            }
            lanes::SegmentLanes seg{};
            lanes::InteractLanes in{};
            lanes::RefineLanes ref{};
            for (int j = 0; j < lanes::kRays; ++j) {
                const Vec3 o{u(g) * 1.5 * a, u(g) * 1.5 * a, u(g) * 3 * a};
                const Vec3 d = j % 3 == 0 ? normalize(Vec3{u(g) * 0.05, u(g) * 0.05, 1.0}) : random_unit(g);
                seg.o.set(j, o);
                seg.d.set(j, d);
                const Vec3 n = random_unit(g);
                in.d_in.set(j, d);
                in.n_out.set(j, n);
                in.p.set(j, o);
                in.offset[j] = std::fabs(u(g)) * 1e-12;
                in.n_from[j] = j % 2 ? 1.0 : 1.5168;
                in.n_to[j] = j % 2 ? 1.5168 : 1.0;
                in.entering[j] = dot(d, n) < 0 ? -1 : 0;
                in.skip_chord[j] = std::fabs(u(g)) * 1e-3;
                in.state[j] = g();
                in.inc[j] = g() | 1u;
                // A facet candidate near a cap's root (Embree's float distance, a chord away),
                // now and then far from it (a spurious facet) or at no root at all.
                const int cap = j % 2;
                const double root = patch_hit(patches[static_cast<size_t>(cap)], o, d, 0.0, INFINITY);
                ref.o.set(j, o);
                ref.d.set(j, d);
                ref.face_normal.set(j, normalize(n * 0.01 + Vec3{0.0, 0.0, 1.0}));
                ref.candidate_t[j] = root < INFINITY && j % 5 != 0 ? static_cast<float>(root + u(g) * 1e-4) : std::fabs(u(g)) * a;
                ref.patch[j] = cap;
                ref.chord[j] = 1e-4;
            }
            lanes::SegmentLanes want_seg = seg;
            lanes::InteractLanes want_in = in;
            const lanes::Kernels& base = *sets.back();
            base.analytic_segments(obj, want_seg, lanes::kRays);
            base.fresnel(want_in, lanes::kRays);
            // The Fresnel choice is interact's: reflect under TIR without a draw, else where the
            // path's stream's next uniform is below R, the stream left past that draw.
            for (int j = 0; j < lanes::kRays; ++j) {
                Rng rng = Rng::from_state(in.state[j], in.inc[j]);
                ++(want_in.tir[j] ? tir_lanes : drawn_lanes);
                const bool reflect = want_in.tir[j] ? true : rng.uniform() < want_in.reflectance[j];
                ASSERT_EQ(want_in.reflect[j] != 0, reflect) << "lane " << j << ", batch " << batch;
                ASSERT_EQ(want_in.state[j], rng.state()) << "lane " << j << ", batch " << batch;
                ASSERT_EQ(want_in.inc[j], in.inc[j]);
            }
            base.spawn(want_in, lanes::kRays, 3e-15);
            lanes::RefineLanes want_ref = ref;
            base.refine_segments(obj, want_ref, lanes::kRays, 1e-3 * a);
            for (int j = 0; j < lanes::kRays; ++j) ++(want_ref.scalar[j] ? refined_scalar : refined_lanes);
            for (const lanes::Kernels* k : sets) {
                lanes::SegmentLanes got_seg = seg;
                lanes::InteractLanes got_in = in;
                k->analytic_segments(obj, got_seg, lanes::kRays);
                k->fresnel(got_in, lanes::kRays);
                k->spawn(got_in, lanes::kRays, 3e-15);
                ASSERT_EQ(std::memcmp(&got_seg, &want_seg, sizeof got_seg), 0) << k->isa << ", batch " << batch;
                ASSERT_EQ(std::memcmp(&got_in, &want_in, sizeof got_in), 0) << k->isa << ", batch " << batch;
                lanes::RefineLanes got_ref = ref;
                k->refine_segments(obj, got_ref, lanes::kRays, 1e-3 * a);
                ASSERT_EQ(std::memcmp(&got_ref, &want_ref, sizeof got_ref), 0) << k->isa << ", batch " << batch;
            }
        }
    }
    EXPECT_GT(refined_lanes, 0);
    EXPECT_GT(refined_scalar, 0);
    EXPECT_GT(tir_lanes, 0);
    EXPECT_GT(drawn_lanes, 0);
}

// The camera's streams in lanes (lanes::seed_streams, lanes::uniform4 in the camera kernel) against
// Rng itself: for every sample, the stream after Rng(seed, k, s)'s first four uniforms, on every
// instruction set, for seeds and pixels at the ends of their ranges (the hash of k + kStreamA
// wraps) and for samples past 2^32; and the camera kernel of every set giving the baseline's bits
// (the rays against TelecentricCamera::sample: the next test).
TEST(Lanes, CameraStreamsAreRngsStreams) {
    const std::uint64_t seeds[] = {0, 1, 42, 0xffffffffffffffffull};
    const std::uint64_t pixels[] = {0, 7, 99999, 0xffffffffffffffffull - 3};
    const std::uint64_t firsts[] = {0, 16, 4096, (1ull << 32) - 5};
    const std::vector<const lanes::Kernels*> sets = lanes::runnable_kernels();
    std::mt19937_64 g(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (std::uint64_t seed : seeds)
        for (std::uint64_t pixel : pixels)
            for (std::uint64_t first : firsts) {
                lanes::CameraLanes in{};
                in.key = splitmix64(seed) ^ splitmix64(pixel + Rng::kStreamA);
                in.strata = 1 + std::floor(u(g) * 40);
                in.column = std::floor(u(g) * 1000);
                in.row = std::floor(u(g) * 1000);
                in.width = 1 + u(g) * 50;
                in.height = 1 + u(g) * 50;
                in.half_width = -0.5 * in.width;
                in.half_height = 0.5 * in.height;
                in.columns = 1000;
                in.rows = 1000;
                in.na = u(g);
                in.focus_z = u(g) * 10 - 5;
                in.depth = u(g) * 20;
                for (int j = 0; j < lanes::kRays; ++j) {
                    in.sample[j] = first + static_cast<std::uint64_t>(j);
                    in.stratum_x[j] = std::floor(u(g) * in.strata);
                    in.stratum_y[j] = std::floor(u(g) * in.strata);
                }
                lanes::CameraLanes want = in;
                sets.back()->camera(want, lanes::kRays);
                for (int j = 0; j < lanes::kRays; ++j) {
                    Rng rng(seed, pixel, first + static_cast<std::uint64_t>(j));
                    for (int i = 0; i < 4; ++i) rng.uniform();
                    Rng got = Rng::from_state(want.state[j], want.inc[j]);
                    for (int i = 0; i < 8; ++i) ASSERT_EQ(got.next_u32(), rng.next_u32()) << "lane " << j;
                }
                for (const lanes::Kernels* k : sets) {
                    lanes::CameraLanes got = in;
                    k->camera(got, lanes::kRays);
                    ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << k->isa;
                }
            }
}

// TelecentricCamera::sample_packet against sample one at a time: the same origins and directions,
// bit for bit, and the same streams after them, for a jittered grid (spp a square) and for Latin
// hypercube strata, for packets of every size from 1 to 16 at any first sample.
TEST(Lanes, CameraPacketsAreSamplesOneAtATime) {
    for (int spp : {64, 20}) {
        CameraDesc desc;
        desc.resolution = {7, 5};
        desc.size = {3.0, 2.0};
        desc.numerical_aperture = 0.3;
        desc.samples_per_pixel = spp;
        const TelecentricCamera cam(desc, -10.0);
        const std::uint64_t seed = 12345;
        for (long k : {0L, 17L, 34L}) {
            const std::vector<int> perm = cam.permutation(k, seed);
            for (int n = 1; n <= 16; ++n)
                for (int s0 = 0; s0 + n <= spp; s0 += 3) {
                    Rng rng[16];
                    Vec3 o[16], d[16];
                    cam.sample_packet(k, s0, n, perm, seed, rng, o, d);
                    for (int i = 0; i < n; ++i) {
                        Rng want(seed, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(s0 + i));
                        Vec3 wo, wd;
                        cam.sample(k, s0 + i, perm, want, wo, wd);
                        for (int c = 0; c < 3; ++c) {
                            ASSERT_TRUE(same_bits(o[i][c], wo[c])) << "spp " << spp << " pixel " << k << " sample " << s0 + i;
                            ASSERT_TRUE(same_bits(d[i][c], wd[c])) << "spp " << spp << " pixel " << k << " sample " << s0 + i;
                        }
                        ASSERT_EQ(rng[i].next_u32(), want.next_u32());
                    }
                }
        }
    }
}
