#include "trace/EmbreeScene.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>

namespace ltm {

namespace {

// An intersect context extended with the double-precision ray and the skip list; Embree passes
// the context pointer through to our callbacks (the pattern of Embree's own tutorials).
struct QueryContext {
    RTCIntersectContext ctx;
    Vec3 o, d;
    double tmin = 0, best_t = INFINITY;
    std::uint32_t best_prim = 0;
    const std::uint32_t* skip = nullptr;
    int skip_count = 0;
    double skip_until = 0;
};

void skip_filter(const RTCFilterFunctionNArguments* args) {
    const auto* q = reinterpret_cast<const QueryContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (!args->valid[i]) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        const float t = RTCRayN_tfar(args->ray, args->N, i);
        for (int k = 0; k < q->skip_count; ++k)
            if (prim == q->skip[k] && t < q->skip_until) args->valid[i] = 0;
    }
}

// The packet's context: each ray's skip (EmbreeScene::PacketSkip), found by the ray's id, for
// the n rays the caller filled. A padding lane (id >= n, valid 0 in the call) still reaches the
// filter under Embree's 8- and 4-wide kernels (seen with max_isa=avx2, avx and sse4.2, where
// UndefinedBehaviorSanitizer caught it reading the caller's unwritten `on`); its answer is
// dropped, so it skips nothing and reads nothing of the caller's.
struct PacketContext {
    RTCIntersectContext ctx;
    const EmbreeScene::PacketSkip* skip = nullptr;
    unsigned n = 0;
};

void packet_skip_filter(const RTCFilterFunctionNArguments* args) {
    const auto* q = reinterpret_cast<const PacketContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (!args->valid[i]) continue;
        const unsigned id = RTCRayN_id(args->ray, args->N, i);
        if (id >= q->n || !q->skip->on[id]) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        const float t = RTCRayN_tfar(args->ray, args->N, i);
        if (prim == q->skip->prim[id] && t < q->skip->until[id]) args->valid[i] = 0;
    }
}

void patch_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* patches = static_cast<const std::vector<Patch>*>(args->geometryUserPtr);
    const Aabb& b = (*patches)[args->primID].bounds;
    // Rounded outward to float so the box still contains the double surface.
    args->bounds_o->lower_x = std::nextafter(static_cast<float>(b.lo.x), -INFINITY);
    args->bounds_o->lower_y = std::nextafter(static_cast<float>(b.lo.y), -INFINITY);
    args->bounds_o->lower_z = std::nextafter(static_cast<float>(b.lo.z), -INFINITY);
    args->bounds_o->upper_x = std::nextafter(static_cast<float>(b.hi.x), INFINITY);
    args->bounds_o->upper_y = std::nextafter(static_cast<float>(b.hi.y), INFINITY);
    args->bounds_o->upper_z = std::nextafter(static_cast<float>(b.hi.z), INFINITY);
}

void patch_intersect(const RTCIntersectFunctionNArguments* args) {
    if (!args->valid[0]) return;
    auto* q = reinterpret_cast<QueryContext*>(args->context);
    const auto* patches = static_cast<const std::vector<Patch>*>(args->geometryUserPtr);
    auto* rh = reinterpret_cast<RTCRayHit*>(args->rayhit);  // N == 1 under rtcIntersect1
    // A triangle found first has shortened tfar; a root must beat it as well as our own best.
    const double t = patch_hit((*patches)[args->primID], q->o, q->d, q->tmin,
                               std::min(q->best_t, static_cast<double>(rh->ray.tfar)));
    if (!(t < q->best_t)) return;
    q->best_t = t;
    q->best_prim = args->primID;
    // tfar culls farther primitives: round up so a primitive with a slightly nearer double root
    // is never culled.
    rh->ray.tfar = std::nextafter(static_cast<float>(t), INFINITY);
    rh->hit.geomID = args->geomID;
    rh->hit.primID = args->primID;
    rh->hit.u = rh->hit.v = 0;
    rh->hit.Ng_x = rh->hit.Ng_y = 0;
    rh->hit.Ng_z = 1;
}

// An Embree ray from the double ray, over [tnear, tfar] (floats), with no hit yet.
RTCRayHit make_rayhit(const Vec3& o, const Vec3& d, float tnear, float tfar) {
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(o.x);
    rh.ray.org_y = static_cast<float>(o.y);
    rh.ray.org_z = static_cast<float>(o.z);
    rh.ray.dir_x = static_cast<float>(d.x);
    rh.ray.dir_y = static_cast<float>(d.y);
    rh.ray.dir_z = static_cast<float>(d.z);
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

void throw_on_error(RTCDevice device, const char* what) {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("Embree error during ") + what + ": " + std::to_string(e));
}

}  // namespace

// Geometry masks: single-ray queries (mask ~0) see both; packets see the triangles only.
constexpr unsigned kTriangleMask = 1u, kPatchMask = 2u;

struct EmbreeScene::Impl {
    bool masks = false;  // the build honours ray masks
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    unsigned tri_geom = RTC_INVALID_GEOMETRY_ID, patch_geom = RTC_INVALID_GEOMETRY_ID;
    const TriMesh* triangles = nullptr;
    const std::vector<Patch>* patches = nullptr;
};

EmbreeScene::EmbreeScene(const TriMesh* triangles, const std::vector<Patch>* patches, bool robust)
    : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.triangles = triangles;
    m.patches = patches;
    // LTM_EMBREE_CONFIG, when set, is added to Embree's device configuration: the tests run the
    // packet paths again with max_isa=avx2 (tests/CMakeLists.txt), the 8-wide kernels that a
    // machine without AVX-512 takes, whose 16-ray packets reach the filter in other ways.
    std::string config = "verbose=0";
    if (const char* extra = std::getenv("LTM_EMBREE_CONFIG"); extra && *extra) config += std::string(",") + extra;
    m.device = rtcNewDevice(config.c_str());
    if (!m.device) throw std::runtime_error("Embree: cannot create a device with the configuration '" + config + "'");
    m.masks = rtcGetDeviceProperty(m.device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
    m.scene = rtcNewScene(m.device);
    rtcSetSceneFlags(m.scene, static_cast<RTCSceneFlags>((robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE) |
                                                         RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));
    rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_HIGH);
    if (triangles && triangles->num_triangles() > 0) {
        RTCGeometry g = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), triangles->num_vertices()));
        for (size_t i = 0; i < triangles->num_vertices(); ++i) {
            v[3 * i] = static_cast<float>(triangles->vertices[i].x);
            v[3 * i + 1] = static_cast<float>(triangles->vertices[i].y);
            v[3 * i + 2] = static_cast<float>(triangles->vertices[i].z);
        }
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), triangles->num_triangles()));
        for (size_t f = 0; f < triangles->num_triangles(); ++f)
            for (int k = 0; k < 3; ++k) idx[3 * f + k] = triangles->triangles[f][k];
        rtcSetGeometryMask(g, kTriangleMask);
        rtcCommitGeometry(g);
        m.tri_geom = rtcAttachGeometry(m.scene, g);
        rtcReleaseGeometry(g);
    }
    if (patches && !patches->empty()) {
        RTCGeometry g = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(patches->size()));
        rtcSetGeometryUserData(g, const_cast<std::vector<Patch>*>(patches));
        rtcSetGeometryBoundsFunction(g, patch_bounds, nullptr);
        rtcSetGeometryIntersectFunction(g, patch_intersect);
        rtcSetGeometryMask(g, kPatchMask);
        rtcCommitGeometry(g);
        m.patch_geom = rtcAttachGeometry(m.scene, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(m.scene);
    throw_on_error(m.device, "scene build");
}

EmbreeScene::~EmbreeScene() {
    if (impl_->scene) rtcReleaseScene(impl_->scene);
    if (impl_->device) rtcReleaseDevice(impl_->device);
}

Candidate EmbreeScene::intersect(const Vec3& o, const Vec3& d, double tmin, double tmax, const std::uint32_t* skip,
                                 int skip_count, double skip_until) const {
    QueryContext q;
    rtcInitIntersectContext(&q.ctx);
    if (skip_count > 0) q.ctx.filter = skip_filter;
    q.o = o;
    q.d = d;
    q.tmin = tmin;
    q.best_t = tmax;
    q.skip = skip;
    q.skip_count = skip_count;
    q.skip_until = skip_until;
    // Float bounds rounded outward: the double interval is what counts for user geometry.
    RTCRayHit rh = make_rayhit(o, d, tmin > 0 ? std::nextafter(static_cast<float>(tmin), 0.0f) : 0.0f,
                               std::isinf(tmax) ? std::numeric_limits<float>::infinity()
                                                : std::nextafter(static_cast<float>(tmax), INFINITY));
    rtcIntersect1(impl_->scene, &q.ctx, &rh);
    Candidate c;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return c;
    c.hit = true;
    if (rh.hit.geomID == impl_->patch_geom) {
        c.analytic = true;
        c.t = q.best_t;
        c.prim = q.best_prim;
        c.tag = (*impl_->patches)[c.prim].tag;
    } else {
        c.t = rh.ray.tfar;
        c.prim = rh.hit.primID;
        c.tag = impl_->triangles->tags[c.prim];
    }
    return c;
}

bool EmbreeScene::packets_supported() const { return impl_->masks && impl_->tri_geom != RTC_INVALID_GEOMETRY_ID; }

namespace {
// A ray's origin and direction as floats, rounded as make_rayhit rounds them.
void float_ray(const Vec3& o, const Vec3& d, float* r) {
    r[0] = static_cast<float>(o.x);
    r[1] = static_cast<float>(o.y);
    r[2] = static_cast<float>(o.z);
    r[3] = static_cast<float>(d.x);
    r[4] = static_cast<float>(d.y);
    r[5] = static_cast<float>(d.z);
}
}  // namespace

template <class Rays>
void EmbreeScene::packet_query(int n, Candidate* out, const PacketSkip* skip, const Rays& ray) const {
    if (n < 0 || n > kPacket) throw std::invalid_argument("EmbreeScene::intersect_packet: more rays than a packet holds");
    if (!packets_supported()) throw std::logic_error("EmbreeScene::intersect_packet: this scene cannot take packets");
    if (n == 0) return;
    PacketContext pc;
    RTCIntersectContext& ctx = pc.ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    const bool filter_first = skip && !skip->rare;
    if (skip) {
        pc.skip = skip;
        pc.n = static_cast<unsigned>(n);
        if (filter_first) ctx.filter = packet_skip_filter;
    }
    alignas(64) int valid[kPacket];
    alignas(64) RTCRayHit16 rh;
    // Each lane exactly as make_rayhit rounds a single ray; the unused lanes (invalid) repeat
    // the first. Fixed-count loops, which the compiler turns into whole-vector stores.
    for (int i = 0; i < n; ++i) {
        float r[6];
        ray(i, r);
        rh.ray.org_x[i] = r[0];
        rh.ray.org_y[i] = r[1];
        rh.ray.org_z[i] = r[2];
        rh.ray.dir_x[i] = r[3];
        rh.ray.dir_y[i] = r[4];
        rh.ray.dir_z[i] = r[5];
    }
    for (int i = n; i < kPacket; ++i) {
        rh.ray.org_x[i] = rh.ray.org_x[0];
        rh.ray.org_y[i] = rh.ray.org_y[0];
        rh.ray.org_z[i] = rh.ray.org_z[0];
        rh.ray.dir_x[i] = rh.ray.dir_x[0];
        rh.ray.dir_y[i] = rh.ray.dir_y[0];
        rh.ray.dir_z[i] = rh.ray.dir_z[0];
    }
    for (int i = 0; i < kPacket; ++i) {
        valid[i] = i < n ? -1 : 0;
        rh.ray.tnear[i] = 0.0f;
        rh.ray.tfar[i] = std::numeric_limits<float>::infinity();
        rh.ray.mask[i] = kTriangleMask;
        rh.ray.flags[i] = 0;
        rh.ray.time[i] = 0;
        rh.ray.id[i] = static_cast<unsigned>(i);
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, impl_->scene, &ctx, &rh);
    // A rare skip list, without a filter on every hit of every ray: a ray whose answer is not its
    // skipped facet within the band has the filtered query's answer already (the filter rejects
    // that facet alone, and the facet lies no nearer than the answer); the rays that did meet it
    // are traced again with the filter, in one packet of their own.
    if (skip && !filter_first) {
        bool again = false;
        for (int i = 0; i < n; ++i) {  // the lanes past n are invalid already
            const bool self = skip->on[i] && rh.hit.geomID[i] == impl_->tri_geom && rh.hit.primID[i] == skip->prim[i] &&
                              rh.ray.tfar[i] < skip->until[i];
            valid[i] = self ? -1 : 0;
            again |= self;
            if (self) {
                rh.ray.tfar[i] = std::numeric_limits<float>::infinity();
                rh.hit.geomID[i] = rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
            }
        }
        if (again) {
            ctx.filter = packet_skip_filter;
            rtcIntersect16(valid, impl_->scene, &ctx, &rh);
        }
    }
    for (int i = 0; i < n; ++i) {
        Candidate c;
        if (rh.hit.geomID[i] == impl_->tri_geom) {
            c.hit = true;
            c.t = rh.ray.tfar[i];
            c.prim = rh.hit.primID[i];
            c.tag = impl_->triangles->tags[c.prim];
        }
        out[i] = c;
    }
}

void EmbreeScene::intersect_packet(const Vec3* o, const Vec3* d, int n, Candidate* out, const PacketSkip* skip) const {
    packet_query(n, out, skip, [&](int i, float* r) { float_ray(o[i], d[i], r); });
}

void EmbreeScene::intersect_packet(const RayLanes& rays, const int* lanes, int n, Candidate* out,
                                   const PacketSkip* skip) const {
    packet_query(n, out, skip, [&](int i, float* r) {
        const int k = lanes[i];
        float_ray({rays.ox[k], rays.oy[k], rays.oz[k]}, {rays.dx[k], rays.dy[k], rays.dz[k]}, r);
    });
}

void EmbreeScene::intersect_coherent(const Vec3* o, const Vec3* d, int n, Candidate* out) const {
    // A counting sort of the rays by octant, as Embree forms it from the float direction's signs
    // (any grouping gives the same answers; this one gives full packets).
    int small[256];
    unsigned char small_octant[256];
    std::vector<int> large;
    std::vector<unsigned char> large_octant;
    int* order = small;
    unsigned char* octant = small_octant;
    if (n > 256) {
        large.resize(static_cast<size_t>(n));
        large_octant.resize(static_cast<size_t>(n));
        order = large.data();
        octant = large_octant.data();
    }
    int start[9] = {};
    for (int i = 0; i < n; ++i) {
        octant[i] = static_cast<unsigned char>((static_cast<float>(d[i].x) < 0.0f ? 1 : 0) |
                                               (static_cast<float>(d[i].y) < 0.0f ? 2 : 0) |
                                               (static_cast<float>(d[i].z) < 0.0f ? 4 : 0));
        ++start[octant[i] + 1];
    }
    for (int k = 0; k < 8; ++k) start[k + 1] += start[k];
    int fill[8];
    std::copy(start, start + 8, fill);
    for (int i = 0; i < n; ++i) order[fill[octant[i]]++] = i;
    // Whole packets of one octant first, then the octants' remainders pooled into packets.
    Candidate pc[kPacket];
    int lane_ray[kPacket];
    int m = 0;
    const auto flush = [&] {
        packet_query(m, pc, nullptr, [&](int i, float* r) { float_ray(o[lane_ray[i]], d[lane_ray[i]], r); });
        for (int j = 0; j < m; ++j) out[lane_ray[j]] = pc[j];
        m = 0;
    };
    const auto add = [&](int i) {
        lane_ray[m++] = i;
        if (m == kPacket) flush();
    };
    for (int k = 0; k < 8; ++k)
        for (int j = start[k]; j + kPacket <= start[k + 1]; j += kPacket)
            for (int l = 0; l < kPacket; ++l) add(order[j + l]);
    for (int k = 0; k < 8; ++k)
        for (int j = start[k] + (start[k + 1] - start[k]) / kPacket * kPacket; j < start[k + 1]; ++j)
            add(order[j]);
    if (m > 0) flush();
}

long EmbreeScene::raw_intersect(const Vec3& o, const Vec3& d, float tmin) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = make_rayhit(o, d, tmin, std::numeric_limits<float>::infinity());
    rtcIntersect1(impl_->scene, &ctx, &rh);
    return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : static_cast<long>(rh.hit.primID);
}

}  // namespace ltm
