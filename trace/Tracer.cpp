#include "trace/Tracer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <stdexcept>

#include "trace/Intersect.h"
#include "trace/LaneKernels.h"
#include "trace/Optics.h"
#include "trace/TraceTolerance.h"
#include "trace/TracerState.h"

namespace ltm {

namespace {
using trace_tol::kFloatUlp;

// The same analytic surface (a ball's front and back hemispheres lie on one sphere).
bool same_surface(const Surface& a, const Surface& b) {
    return a.kind == b.kind && a.origin == b.origin && a.axis == b.axis && a.radius == b.radius &&
           a.minor_radius == b.minor_radius && a.angle == b.angle && a.semi_axes == b.semi_axes &&
           a.frame == b.frame;
}
}

const char* to_string(Representation r) {
    switch (r) {
        case Representation::Refined: return "refined";
        case Representation::Analytic: return "analytic";
        case Representation::MeshOnly: return "mesh-only";
    }
    return "?";
}

Tracer::Tracer(const Scene& scene, const Solid& solid, TracerOptions options)
    : scene_(scene),
      solid_(solid),
      options_(options),
      lens_(scene.object.lens),
      display_(scene.display),
      camera_(scene.camera, std::min(lens_.z_front(0), lens_.z_front(lens_.aperture_radius())) - 1.0) {
    // The scene loader admits [0, kMaxSplitDepth] only; a scene built in code is held to it too
    // (the split stack's capacity), rather than clamped silently.
    if (scene.tracing.split_depth < 0 || scene.tracing.split_depth > kMaxSplitDepth)
        throw std::invalid_argument(fmt::format("Tracer: tracing.split_depth must be in [0, {}], got {}", kMaxSplitDepth,
                                                scene.tracing.split_depth));
    const double a = lens_.aperture_radius();
    scale_ = std::max({a, lens_.spec().center_thickness, std::fabs(scene.display.z)});
    convex_ = lens_.is_convex();
    // The caps' heights are monotone in rho (sagitta), so their extremes are at the vertex or the edge.
    object_bounds_ = {{-a, -a, std::min(lens_.z_front(0), lens_.z_front(a))},
                      {a, a, std::max(lens_.z_back(0), lens_.z_back(a))}};
    object_patches_ = object_patches(lens_);
    for (size_t k = 0; k < scene.defects.size(); ++k)
        if (k < solid.corefined.size() && solid.corefined[k]) {
            Cutter c{ToolShape(lens_, scene.defects[k]), {}};
            for (size_t t = 0; t < solid.surfaces.size(); ++t)
                if (solid.surfaces[static_cast<int>(t)].defect == static_cast<int>(k)) c.tags.push_back(static_cast<int>(t));
            cutters_.push_back(std::move(c));
        }
    tag_cutter_.assign(solid.surfaces.size(), -1);
    for (size_t i = 0; i < cutters_.size(); ++i)
        for (int t : cutters_[i].tags) tag_cutter_[static_cast<size_t>(t)] = static_cast<int>(i);

    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const Defect& d = scene.defects[k];
        if (d.type == DefectType::Inhomogeneity && d.index_profile == IndexProfile::Smooth &&
            lens_.signed_distance(d.center) < d.max_semi_axis())  // it may reach a face
            face_inclusions_.push_back(static_cast<int>(k));
    }

    // Enclosed ellipsoid defects (bubbles and particles that cut nothing) as exact primitives.
    std::vector<Patch> ellipsoids;
    std::vector<bool> is_ellipsoid_tag(solid.surfaces.size(), false);
    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const Defect& d = scene.defects[k];
        if (d.type == DefectType::Scratch || (k < solid.corefined.size() && solid.corefined[k])) continue;
        Patch p;
        p.kind = Patch::Kind::Closed;
        for (size_t t = 0; t < solid.surfaces.size(); ++t)
            if (solid.surfaces[static_cast<int>(t)].defect == static_cast<int>(k)) {
                p.tag = static_cast<int>(t);
                is_ellipsoid_tag[t] = true;
                break;
            }
        p.surface = solid.surfaces[p.tag].surface;
        // Axis-aligned box of the ellipsoid: the half-extent along world axis i is
        // sqrt(sum_j (F_ij e_j)^2).
        Vec3 h;
        for (int i = 0; i < 3; ++i)
            h[i] = std::sqrt(std::pow(d.frame(i, 0) * d.semi_axes.x, 2) + std::pow(d.frame(i, 1) * d.semi_axes.y, 2) +
                             std::pow(d.frame(i, 2) * d.semi_axes.z, 2));
        p.bounds = {d.center - h, d.center + h};
        p.finalize();
        ellipsoids.push_back(p);
    }
    ellipsoids_ = ellipsoids;
    media_ = std::make_unique<MediaTable>(scene, solid, object_patches_, ellipsoids_);
    if (media_->graded()) {
        if (options_.representation == Representation::MeshOnly)
            throw std::invalid_argument(
                "the mesh-only representation traces straight segments against facets; a graded-index glass or a "
                "smooth inhomogeneity needs the exact surfaces (use refined or analytic)");
        if (const GrinField* field = (*media_)[Medium::Glass].grin) {
            auto add = [&](const Patch& p) {
                for (CurvedSurface& c : curved_surfaces_)
                    if (same_surface(c.patches.front().surface, p.surface)) {
                        c.patches.push_back(p);
                        return;
                    }
                curved_surfaces_.push_back({CurvedQuadric(*field, Quadric::from(p.surface)), {p}});
            };
            for (const Patch& p : object_patches_) add(p);
            for (const Patch& p : ellipsoids_) add(p);
            for (const CurvedSurface& c : curved_surfaces_)
                general_surfaces_ = general_surfaces_ || c.quadric.form() == CurvedQuadric::Form::General;
            horizon_ = std::make_unique<CurvedQuadric>(*field, Quadric::from(Surface::sphere({0, 0, 0}, field->radius() * 1.001)));
        }
    }
    switch (options_.representation) {
        case Representation::Analytic: {
            std::string why;
            if (!analytic_supported(solid, &why)) throw std::invalid_argument("the analytic representation " + why);
            // The object's three patches are solved inline on every segment (every ray's box meets
            // them, so a BVH only adds callback overhead); Embree holds the ellipsoid defects.
            user_patches_ = ellipsoids;
            embree_ = std::make_unique<EmbreeScene>(nullptr, &user_patches_, options_.robust);
            break;
        }
        case Representation::Refined:
            // Triangles for the object's faces and the walls Booleans cut; the enclosed
            // ellipsoids' shells are replaced by their exact surfaces.
            tri_mesh_ = solid.mesh.filtered([&](int tag) { return !is_ellipsoid_tag[static_cast<size_t>(tag)]; });
            user_patches_ = ellipsoids;
            embree_ = std::make_unique<EmbreeScene>(&tri_mesh_, &user_patches_, options_.robust);
            break;
        case Representation::MeshOnly: {
            tri_mesh_ = solid.mesh;
            embree_ = std::make_unique<EmbreeScene>(&tri_mesh_, nullptr, options_.robust);
            TriMesh as_embree = tri_mesh_;  // EmbreeScene's RTC_FORMAT_FLOAT3 vertices
            for (Vec3& v : as_embree.vertices)
                v = {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
            clear_planes_ = supporting_planes(as_embree);
            break;
        }
    }
    packets_ = options_.representation != Representation::Analytic && user_patches_.size() <= kLinearScanLimit &&
               embree_->packets_supported();
    analytic_lanes_ = options_.representation == Representation::Analytic &&
                      user_patches_.size() <= kLinearScanLimit &&
                      std::all_of(object_patches_.begin(), object_patches_.end(), lanes::lane_patch);
    lockstep_ = (packets_ || analytic_lanes_) &&
                (scene.tracing.estimator == Estimator::Sample || scene.tracing.split_depth == 0) &&
                !media_->graded() && !(scene.object.absorption > 0);
    refined_lanes_ = lockstep_ && options_.representation == Representation::Refined && cutters_.empty() &&
                     std::all_of(object_patches_.begin(), object_patches_.end(), lanes::lane_patch);
    face_normals_.resize(tri_mesh_.num_triangles());
    for (size_t f = 0; f < tri_mesh_.num_triangles(); ++f) face_normals_[f] = tri_mesh_.face_normal(f);
    // interact's rules per surface and side, for lanes_interact (and interact's escape rule).
    lane_faces_.resize(2 * solid_.surfaces.size());
    for (size_t tag = 0; tag < solid_.surfaces.size(); ++tag) {
        const SurfaceInfo& sf = solid_.surfaces[static_cast<int>(tag)];
        for (int entering = 0; entering < 2; ++entering) {
            LaneFace& f = lane_faces_[2 * tag + static_cast<size_t>(entering)];
            const Medium from = entering ? sf.outside : sf.inside;
            f.to = entering ? sf.inside : sf.outside;
            f.defect = sf.defect;
            f.inclusions = f.to == Medium::Glass && sf.defect < 0 && !face_inclusions_.empty();
            const MediumInfo& into = (*media_)[f.to];
            f.n_to = into.index;
            f.simple = sf.optical && f.to != Medium::Absorber &&
                       !(sf.role == SurfaceRole::Rim && scene_.object.rim == RimFinish::Absorbing) &&
                       into.propagation == Propagation::Straight;
            // Leaving a convex object through its own face into the air: nothing of it can be met
            // again (State::escaped; interact reads this too). Not for the mesh, whose
            // tessellation is not exactly convex: its rule is per face (mesh_clear_ahead).
            f.escapes = convex_ && options_.representation != Representation::MeshOnly && sf.defect < 0 &&
                        from == Medium::Glass && f.to == Medium::Air;
        }
    }
}

Tracer::~Tracer() = default;

bool Tracer::analytic_supported(const Solid& solid, std::string* why) {
    for (size_t k = 0; k < solid.corefined.size(); ++k)
        if (solid.corefined[k]) {
            if (why) *why = fmt::format("needs defects that neither touch a face nor each other; defect {} does", k);
            return false;
        }
    return true;
}

double Tracer::index_at(Medium m, const Vec3& x) const {
    const MediumInfo& info = (*media_)[m];
    switch (info.propagation) {
        case Propagation::Straight: return info.index;
        case Propagation::Grin: return std::sqrt(std::max(info.grin->n2(x), 0.0));
        case Propagation::TetWalk: {
            const int t = info.walk->locate(x);
            return t < 0 ? NAN : std::sqrt(std::max(info.walk->n2(t, x), 0.0));
        }
        case Propagation::Absorbing: return 1.0;
    }
    return NAN;
}

Medium Tracer::medium_at(const Vec3& p) const {
    if (!lens_.contains(p)) return Medium::Air;
    for (const auto& c : cutters_)
        if (c.shape.contains(p)) return Medium::Air;
    for (size_t k = 0; k < scene_.defects.size(); ++k) {
        const Defect& d = scene_.defects[k];
        if (d.type == DefectType::Scratch) continue;
        const Vec3 y = d.frame.transposed() * (p - d.center);
        const Vec3& e = d.semi_axes;
        if ((y.x / e.x) * (y.x / e.x) + (y.y / e.y) * (y.y / e.y) + (y.z / e.z) * (y.z / e.z) < 1.0) {
            if (d.type == DefectType::Inhomogeneity) return Medium::inclusion(static_cast<int>(k));
            return d.type == DefectType::Particle ? Medium::Absorber : Medium::Air;
        }
    }
    return Medium::Glass;
}

double Tracer::bounds_exit(const Vec3& o, const Vec3& d) const {
    double t0 = 0, t1 = INFINITY;
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0) {
            if (o[i] < object_bounds_.lo[i] || o[i] > object_bounds_.hi[i]) return 0;
            continue;
        }
        double a = (object_bounds_.lo[i] - o[i]) / d[i], c = (object_bounds_.hi[i] - o[i]) / d[i];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
    }
    return t0 <= t1 && std::isfinite(t1) ? t1 : 0;
}

Tracer::Hit Tracer::exact_guard(const Vec3& o, const Vec3& d, double tmax, int solved_patch) const {
    Hit best;
    // The object's own patches, where no cutting defect removed them. The first root on the glass
    // boundary, not just the first root: a ray leaving a groove through its opening crosses the
    // face's surface inside the void before it meets the face again where it re-enters the glass.
    const Vec3 inv = reciprocals(d);
    for (const Patch& p : object_patches_) {
        if (p.tag == solved_patch || !may_hit(p, o, d, inv, best.t < tmax ? best.t : tmax)) continue;
        double t = patch_hit(p, o, d, 0.0, best.t < tmax ? best.t : tmax);
        while (t < INFINITY && !on_glass_boundary(p.tag, o, d, t)) t = patch_hit(p, o, d, t, best.t < tmax ? best.t : tmax);
        if (t < INFINITY) {
            best.t = t;
            best.tag = p.tag;
        }
    }
    // The cutters' walls: a root of one of a cutter's surfaces on the glass boundary.
    for (const auto& c : cutters_) {
        const double limit = best.t < tmax ? best.t : tmax;
        if (!segment_meets_box(o, d, limit, c.shape.bounds())) continue;
        for (int tag : c.tags) {
            const Roots r = intersect(solid_.surfaces[tag].surface, o, d);
            for (int i = 0; i < r.count; ++i) {
                const double t = r.t[i];
                if (!(t > 0 && t < (best.t < tmax ? best.t : tmax))) continue;
                if (!on_glass_boundary(tag, o, d, t)) continue;
                best.t = t;
                best.tag = tag;
            }
        }
    }
    if (best.tag >= 0) best.found = true;
    return best;
}

// How far outside the lens a root of a cutter's wall may lie and still count as a crossing of the
// glass boundary: the rounding of the root and of the lens's distance (twice the point error bound),
// so a ray through the seam where the wall meets a face is caught by one of the two. A wider slack,
// such as the classification step 1e-9 (|t| + L), would let a ray within that step above a face
// take a pit's or a groove's wall there, in the air, for a way into the glass (tests/
// trace_stress.cpp shoots such rays).
double Tracer::lens_slack(int tag, const Vec3& x) const {
    return trace_tol::kSpawnOffsetBounds * point_error_bound(solid_.surfaces[tag].surface, x);
}

// The step either side of a root of a cutter's wall at which membership of the cutter is tested:
// beyond the root's own error along the ray (its point error bound over the cosine of incidence,
// kGuardStepBounds times), at least a few ulps of the scene, and at most kGuardStepMax (|t| + L),
// the wide step. So near another wall of the same tool (a U's side line continuing past its corner
// with the bottom arc, a V's wall past the apex) the test still sees the wall the root is on,
// while a grazing root, whose error along the ray grows as 1 / cos, keeps the wide step. (With the
// wide step for every root, rays within 1e-9 L of such corners would refract at a wall's
// continuation inside the glass; tests/trace_stress.cpp shoots such rays.)
double Tracer::guard_step(int tag, const Vec3& x, const Vec3& d, double t) const {
    const Surface& S = solid_.surfaces[tag].surface;
    const double wide = trace_tol::kGuardStepMax * (std::fabs(t) + scale_);
    const double cosi = std::fabs(dot(d, S.normal(x)));
    const double err = trace_tol::kGuardStepBounds * trace_tol::kSpawnOffsetBounds * point_error_bound(S, x);
    if (!(err < wide * cosi)) return wide;  // grazing (or a NaN normal)
    return std::max(err / cosi, trace_tol::kPointErrorUlps * trace_tol::kU * (std::fabs(t) + scale_));
}

bool Tracer::on_glass_boundary(int tag, const Vec3& o, const Vec3& d, double t) const {
    if (cutters_.empty()) return true;
    const int own = tag < static_cast<int>(tag_cutter_.size()) ? tag_cutter_[static_cast<size_t>(tag)] : -1;
    const bool object_patch = tag < static_cast<int>(object_patches_.size());
    if (!object_patch && own < 0) return true;
    const Vec3 x = o + d * t;
    double delta = 0;
    // The surface's own test: an object patch outside every cutter; a cutter's wall where
    // membership of that cutter changes, within the lens (up to the root's rounding) and outside
    // the other cutters.
    bool on = true;
    for (size_t i = 0; i < cutters_.size() && on; ++i)
        if (static_cast<int>(i) != own && cutters_[i].shape.contains(x)) on = false;
    if (on && own >= 0) {
        const ToolShape& shape = cutters_[static_cast<size_t>(own)].shape;
        delta = guard_step(tag, x, d, t);
        on = shape.contains(o + d * (t - delta)) != shape.contains(o + d * (t + delta)) &&
             (lens_.contains(x) || lens_.signed_distance(x) >= -lens_slack(tag, x));
    }
    if (on) return true;
    // The edge rule. On a seam (where a cutter's wall meets a face, or two cutters meet) every
    // surface's own test is undecided within rounding, and each may reject its root for the other:
    // a ray through the seam then crosses the boundary unseen (tests/trace_stress.cpp,
    // SeamExactRays: 4.5 % of rays within 1e-9 of a seam leaked). Wherever the exact solid's
    // membership changes across the root, one step either side along the ray, the root is a
    // crossing whichever surface's test rejected it.
    if (delta == 0) delta = guard_step(tag, x, d, t);
    return in_glass(o + d * (t - delta)) != in_glass(o + d * (t + delta));
}

// Membership of the exact Boolean solid: in the lens and in no cutter (the glass, with every
// enclosed defect counted as glass: they are crossed at their own surfaces).
bool Tracer::in_glass(const Vec3& p) const {
    if (!lens_.contains(p)) return false;
    for (const auto& c : cutters_)
        if (c.shape.contains(p)) return false;
    return true;
}

void Tracer::on_surface(Hit& h) const {
    const SurfaceInfo& s = solid_.surfaces[h.tag];
    if (s.surface.kind == SurfaceKind::Sphere) {
        // Surface::normal and point_error_bound of a sphere, sharing their one distance |p - c|
        // (the same arithmetic as theirs: the caps of most lenses are spheres).
        const Vec3 v = h.p - s.surface.origin;
        const double r = length(v);
        h.n_out = (v / r) * static_cast<double>(s.normal_sign);
        h.offset = trace_tol::kSpawnOffsetBounds * (std::fabs(r - s.surface.radius) + point_rounding_bound(s.surface, h.p));
    } else {
        h.n_out = s.surface.normal(h.p) * static_cast<double>(s.normal_sign);
        h.offset = trace_tol::kSpawnOffsetBounds * point_error_bound(s.surface, h.p);
    }
    h.found = true;
}

Tracer::Hit Tracer::propagate(const State& st, PathStats& stats, const Candidate* first) const {
    // Every branch returns a prvalue, so the hit record is built in the caller's slot (a named
    // record returned beside prvalues would be copied: measured, 7 % of an analytic render).
    const MediumInfo& m = (*media_)[st.medium];
    switch (m.propagation) {
        case Propagation::Grin: return grin_hit(st, m, stats);
        case Propagation::TetWalk: return walk_hit(st, m, stats);
        default: return straight_step(st, m, stats, first);
    }
}

Tracer::Hit Tracer::straight_step(const State& st, const MediumInfo& m, PathStats& stats, const Candidate* first) const {
    Hit h = straight_hit(st, stats, first);
    h.d_in = st.d;
    h.length = h.t;
    h.n_from = h.repaired && h.found ? index_at(h.medium, h.p) : m.index;
    return h;
}

Tracer::Hit Tracer::straight_hit(const State& st, PathStats& stats, const Candidate* first) const {
    if (st.escaped) return {};
    switch (options_.representation) {
        case Representation::Analytic: return analytic_hit(st, stats);
        case Representation::MeshOnly: return mesh_only_hit(st, stats, first);
        case Representation::Refined: break;
    }
    return refined_hit(st, stats, first);
}

Tracer::Hit Tracer::analytic_hit(const State& st, PathStats& stats) const {
    const Vec3& o = st.o;
    const Vec3& d = st.d;
    // The nearest root and its surface; the hit record is made once, for the root that wins.
    double best = INFINITY;
    int tag = -1;
    const Vec3 inv = reciprocals(d);
    for (const Patch& p : object_patches_) {
        if (!may_hit(p, o, d, inv, best)) continue;
        const double t = patch_hit(p, o, d, 0.0, best);
        if (t < best) {
            best = t;
            tag = p.tag;
        }
    }
    if (user_patches_.size() <= kLinearScanLimit) {
        // A handful of defects: a box test each beats the cost of a BVH query.
        for (const Patch& p : user_patches_) {
            if (!segment_near(p, o, d, best)) continue;
            const double t = patch_hit(p, o, d, 0.0, best);
            if (t < best) {
                best = t;
                tag = p.tag;
            }
        }
    } else {
        const Candidate c = embree_->intersect(o, d, 0.0, best);
        if (c.hit && c.t < best) {
            best = c.t;
            tag = c.tag;
        }
    }
    // One named record on every return, built in the caller's slot (see propagate).
    Hit h;
    if (tag < 0) {
        // Nothing ahead: genuine in air; from inside a closed medium the geometry decides (a ray
        // spawned across the rim at a cap edge escapes), as in refined_hit.
        if (st.medium != Medium::Air) h = repair_medium(st, {}, stats);
        return h;
    }
    h.t = best;
    h.tag = tag;
    h.p = o + d * best;
    on_surface(h);
    return h;
}

Tracer::Hit Tracer::mesh_only_hit(const State& st, PathStats& stats, const Candidate* first) const {
    const Vec3& o = st.o;
    const Vec3& d = st.d;
    const std::uint32_t skip[1] = {st.skip_prim};
    // A packet's candidate is the query's own answer: this scene has triangles only.
    const Candidate c = first ? *first : embree_->intersect(o, d, 0.0, INFINITY, skip, st.skip ? 1 : 0, st.skip_until);
    if (first) ++stats.packet_segments;
    Hit h;  // one named record on every return (see propagate)
    if (c.hit) mesh_only_record(o, d, c, h);
    return h;
}

bool Tracer::packet_answers(const Candidate& c, const Vec3& o, const Vec3& d) const {
    // The full query takes a patch's root only before the nearest triangle (Embree's tfar): a
    // patch whose bounding sphere the segment up to the candidate (widened by far more than the
    // float rounding of its distance) does not meet cannot be that answer.
    const double reach = c.hit ? c.t * (1.0 + 1e-6) : INFINITY;
    for (const Patch& p : user_patches_)
        if (segment_near(p, o, d, reach)) return false;
    return true;
}

Tracer::Hit Tracer::refined_hit(const State& st, PathStats& stats, const Candidate* first) const {
    const Vec3& o = st.o;
    const Vec3& d = st.d;
    const SurfaceTable& table = solid_.surfaces;
    const double omag = std::max({std::fabs(o.x), std::fabs(o.y), std::fabs(o.z), trace_tol::kOriginFloor * scale_});
    Hit last_inconsistent;
    for (int attempt = 0; attempt < trace_tol::kLeakRetries; ++attempt) {
        // A jittered candidate ray, a few float ulps off the true one, steps past a vertex or
        // edge the true ray slipped through; the hit is still solved for the true ray. The first
        // attempt is the true ray itself (no basis, no sincos: most segments need no retry).
        Vec3 oq = o;
        if (attempt > 0) {
            ++stats.leak_retries;
            Vec3 b1, b2;
            orthonormal_basis(d, b1, b2);
            const double jitter = trace_tol::kJitterUlps * attempt * kFloatUlp * omag;
            const double ang = trace_tol::kGoldenAngle * attempt;  // a new direction each time
            oq = o + (b1 * std::cos(ang) + b2 * std::sin(ang)) * jitter;
        }
        Hit best;
        double tmin = 0;
        for (int s = 0; s < 16; ++s) {
            const std::uint32_t skip[1] = {st.skip_prim};
            bool packed = false;
            if (first && attempt == 0 && s == 0) {
                packed = packet_answers(*first, o, d);
                ++(packed ? stats.packet_segments : stats.packet_fallbacks);
            }
            const Candidate c =
                packed ? *first : embree_->intersect(oq, d, tmin, INFINITY, skip, st.skip ? 1 : 0, st.skip_until);
            if (!c.hit) break;
            const double step_past = trace_tol::kCandidateStepUlps * kFloatUlp * (omag + c.t);
            if (c.analytic) {
                // An enclosed ellipsoid, solved exactly for the jittered ray: re-solve for the true one.
                const double tt = patch_hit(user_patches_[c.prim], o, d, 0.0, INFINITY);
                if (std::isinf(tt)) {
                    tmin = c.t + step_past;
                    continue;
                }
                best.t = tt;
                best.tag = c.tag;
                break;
            }
            // Refine: the root of the tagged surface nearest the facet's distance. Facet and
            // surface are at most the chord error e apart, i.e. e / |cos| along the ray, plus the
            // float rounding of Embree's origin and distance.
            const Surface& S = table[c.tag].surface;
            const Roots roots = c.tag < static_cast<int>(object_patches_.size()) ? Roots{} : intersect(S, o, d);
            const double cosf = std::fabs(dot(d, face_normals_[c.prim]));
            const double window = 2.0 * solid_.tag_chord_error[static_cast<size_t>(c.tag)] /
                                      std::max(cosf, trace_tol::kCandidateMinCos) +
                                  trace_tol::kCandidateFloatUlps * kFloatUlp * (omag + c.t);
            double te = INFINITY;
            if (c.tag < static_cast<int>(object_patches_.size())) {
                // The object's own faces: a root counts only on the patch (within the aperture, on
                // the rim between the caps' edges), not on the rest of the sphere or cylinder. The
                // solve covers (0, t + window], so the guard need not solve this patch again: a
                // root before the window is a crossing the mesh missed, and it is taken.
                // A root where a cutting defect removed the face is no crossing (the ray is in the
                // defect's void on both sides): the next root counts. (Found by
                // tests/trace_stress.cpp: a ray from the air near a pit's rim hit the back face
                // inside the pit and believed itself in the glass.)
                const Patch& P = object_patches_[static_cast<size_t>(c.tag)];
                te = patch_hit(P, o, d, 0.0, c.t + window);
                while (te < INFINITY && !on_glass_boundary(c.tag, o, d, te)) te = patch_hit(P, o, d, te, c.t + window);
                if (te < c.t - window) {
                    ++stats.guard_hits;
                    best.t = te;
                    best.tag = c.tag;
                    best.solved_patch = c.tag;
                    break;
                }
                if (te <= c.t + window) best.solved_patch = c.tag;
            } else {
                // Only roots on the part of the surface that bounds the glass: a cutter's wall
                // continues beyond its piece of the Boolean result (out of the lens above the face,
                // past a V's apex, past another cutter), and a facet near such an edge has the
                // continuation within its window. (Found by tests/trace_stress.cpp: a ray from the
                // air met a scratch wall's cone above the face, a TIR path in a ball the extension
                // of a V wall past the apex, both inside a single medium.)
                for (int i = 0; i < roots.count; ++i)
                    if (roots.t[i] > 0 && std::fabs(roots.t[i] - c.t) < std::fabs(te - c.t) &&
                        on_glass_boundary(c.tag, o, d, roots.t[i]))
                        te = roots.t[i];
            }
            if (std::fabs(te - c.t) <= window) {
                best.t = te;
                best.tag = c.tag;
                best.prim = c.prim;
                best.triangle = true;
                break;
            }
            // A facet the true surface does not reach here: step past it.
            ++stats.spurious_candidates;
            tmin = c.t + step_past;
        }
        // The exact guard: the glass boundary solved analytically along the segment. A nearer
        // crossing than the mesh's candidate means the mesh leaked or strayed from the surface.
        const Hit g = exact_guard(o, d, best.t, best.solved_patch);
        if (g.t < best.t) {
            if (!best.triangle || best.tag != g.tag) ++stats.guard_hits;
            best = g;
        }
        if (std::isinf(best.t)) {
            // Nothing ahead. Genuine in air; inside a closed medium it is a leak.
            if (st.medium == Medium::Air) return {};
            continue;
        }
        best.p = o + d * best.t;
        Hit& h = best;
        on_surface(h);
        const SurfaceInfo& s = table[h.tag];
        const Medium from = dot(d, h.n_out) < 0 ? s.outside : s.inside;
        if (from == st.medium) return h;
        last_inconsistent = h;  // approached from the wrong medium: an earlier surface leaked
    }
    return repair_medium(st, last_inconsistent, stats);
}

// No jitter found a crossing approached from the medium the path believes it is in: the ray
// passed within rounding of an edge of the glass (a seam where a scratch or pit wall meets a face,
// a cap edge where a face meets the rim), where it took the surface on the wrong side of the edge,
// spawned across the other surface within its offset, or slipped through the edge unseen. The
// geometry decides instead of the belief. The segment from o to the next crossing meets no
// boundary, so its medium is the medium of its midpoint, classified by exact containment on the
// analytic solid (medium_at):
//  - the medium the next surface is approached from: the belief was wrong and the segment is in
//    that medium (`repaired`; PathStats::seam_repairs);
//  - the believed medium: the belief is right and the hit ends a chord through the edge too short
//    to resolve (its first crossing is the edge itself): it is crossed from the other side as
//    found (PathStats::edge_chords);
//  - with nothing ahead, a ray whose start and whose way out of the object's bounds are both in
//    the air escapes (repaired to air).
// What is lost in either case is the refraction at the edge itself: a direction error on rays
// within rounding of an edge, where two surfaces with different normals meet (tests/
// trace_stress.cpp, SeamExactRays, counts them). Anything else is an unresolved leak: a found hit
// is taken as found, and with nothing ahead the path is lost (counted, its weight reported as
// lost) instead of escaping from inside the glass as if it had left it (tests/trace_stress.cpp
// shoots rays along the rim, where a path could otherwise end in the glass).
Tracer::Hit Tracer::repair_medium(const State& st, Hit h, PathStats& stats) const {
    if (h.found) {
        const SurfaceInfo& s = solid_.surfaces[h.tag];
        const Medium from = dot(st.d, h.n_out) < 0 ? s.outside : s.inside;
        const Medium mid = medium_at(st.o + st.d * (0.5 * h.t));
        if (mid == from) {
            ++stats.seam_repairs;
            h.repaired = true;
            h.medium = from;
            return h;
        }
        if (mid == st.medium) {
            ++stats.edge_chords;
            return h;
        }
    } else {
        const double far = bounds_exit(st.o, st.d);
        if (medium_at(st.o) == Medium::Air && (far == 0 || medium_at(st.o + st.d * (0.5 * far)) == Medium::Air)) {
            ++stats.seam_repairs;
            Hit none;
            none.repaired = true;
            none.medium = Medium::Air;
            return none;
        }
        h.lost = true;
    }
    ++stats.leaks_unresolved;
    return h;
}

// A closed-form graded-index segment (GrinPath.h): the first crossing of every exact surface the
// glass is bounded by, each on its patch, along the path from the spawned point with |p| = n there.
Tracer::Hit Tracer::grin_hit(const State& st, const MediumInfo& m, PathStats& stats) const {
    ++stats.grin_segments;
    const GrinField& field = *m.grin;
    const double n0 = std::sqrt(std::max(field.n2(st.o), 0.0));
    const GrinPath path(field, st.o, st.d * n0);
    Hit h;
    long evals = 0;
    if (general_surfaces_) h.t = horizon_->first_crossing(path, 0.0, INFINITY, nullptr, 0, nullptr, &evals);
    for (const CurvedSurface& s : curved_surfaces_) {
        int which = 0;
        const double t = s.quadric.first_crossing(path, 0.0, h.t, s.patches.data(), static_cast<int>(s.patches.size()),
                                                  &which, &evals);
        if (t < h.t) {
            h.t = t;
            h.tag = s.patches[static_cast<size_t>(which)].tag;
        }
    }
    stats.grin_evaluations += static_cast<std::uint64_t>(evals);
    if (h.tag < 0) {
        h.lost = true;
        return h;
    }
    Vec3 r, p;
    path.state(h.t, r, p);
    const double n2 = field.n2(r);
    if (std::fabs(length2(p) - n2) > trace_tol::kHamiltonianRelative * field.n2_max()) ++stats.hamiltonian_violations;
    h.p = r;
    h.d_in = normalize(p);
    h.n_from = std::sqrt(std::max(n2, 0.0));
    if (scene_.object.absorption > 0) h.length = path.arc_length(h.t);
    on_surface(h);
    return h;
}

// A segment through a TetGen region (TetWalk.h), from the tetrahedron holding the spawned point.
Tracer::Hit Tracer::walk_hit(const State& st, const MediumInfo& m, PathStats& stats) const {
    const TetWalk& w = *m.walk;
    Hit h;
    const int tet = w.locate(st.o);
    if (tet < 0) {
        h.lost = true;
        return h;
    }
    const double n0 = std::sqrt(std::max(w.n2(tet, st.o), 0.0));
    const TetWalk::Exit ex = w.walk(st.o, w.entering(st.o, st.d * n0), tet, scene_.object.absorption > 0);
    stats.tet_crossings += static_cast<std::uint64_t>(ex.crossings);
    if (ex.kind == TetWalk::Exit::Kind::Stuck) {
        h.lost = true;
        return h;
    }
    if (ex.kind == TetWalk::Exit::Kind::Boundary) {
        // Out of the region without meeting its exact ellipsoid (rounding at the handover): an
        // inclusion's path continues in the glass around it; a whole-object region has no way out
        // but its exact faces.
        ++stats.walk_boundary_exits;
        const int handover = st.medium.defect();
        if (handover < 0) {
            h.lost = true;
            return h;
        }
        for (const Patch& p : w.surfaces())
            if (solid_.surfaces[p.tag].defect == handover) h.tag = p.tag;
    } else {
        h.tag = w.surfaces()[static_cast<size_t>(ex.surface)].tag;
    }
    const double n2 = w.n2(ex.tet, ex.r);
    if (std::fabs(length2(ex.p) - n2) > trace_tol::kHamiltonianRelative * std::max(n2, 1.0)) ++stats.hamiltonian_violations;
    h.t = ex.tau;
    h.p = ex.r;
    h.d_in = normalize(w.leaving(ex.r, ex.p));
    h.n_from = std::sqrt(std::max(n2, 0.0));
    h.length = ex.arc;
    on_surface(h);
    return h;
}

template <bool Principal>
void Tracer::run(State& st, Rng* rng, PathStats& stats, PrincipalPath* rec, SplitStack* split, const Hit* first) const {
    for (;; ++st.depth) {
        if (!begin_segment(st, stats, rec)) return;
        const Hit h = first ? *first : propagate(st, stats);
        first = nullptr;
        if (!interact<Principal>(st, h, rng, stats, rec, split)) return;
    }
}

template <bool Principal>
bool Tracer::interact(State& st, const Hit& h, Rng* rng, PathStats& stats, PrincipalPath* rec, SplitStack* split) const {
    const SurfaceTable& table = solid_.surfaces;
    const double alpha = scene_.object.absorption;
    // Spawns the ray leaving the interface h along nd (unit; nf the normal on the incident side)
    // into `s`: false (and counted) if the direction is not finite.
    const auto spawn = [&](State& s, const Vec3& nd, const Vec3& nf) {
        if (!is_finite(nd)) {
            ++stats.nan_events;
            return false;
        }
        // Spawn clear of the surface on the side the new direction goes to. Stepping along the new
        // direction by offset / cos clears it by `offset` in normal distance without moving the
        // ray sideways (an offset along the normal would shift the whole continuing path by up
        // to the offset); near-tangent directions fall back to the normal offset.
        const double cos_new = std::fabs(dot(nd, nf));
        const Vec3 side = dot(nd, nf) > 0 ? nf : -nf;
        s.o = cos_new > trace_tol::kSpawnMinCos ? h.p + nd * (h.offset / cos_new) : h.p + side * h.offset;
        s.d = nd;
        s.skip = h.triangle;
        s.skip_prim = h.prim;
        // The band in which the facet just left may still lie ahead of the ray: the chord error
        // over the cosine, plus float rounding.
        if (h.triangle) {
            const double e = options_.representation == Representation::MeshOnly
                                 ? 0.0
                                 : solid_.tag_chord_error[static_cast<size_t>(h.tag)];
            s.skip_until = (trace_tol::kSkipChords * e + trace_tol::kSkipFloatUlps * kFloatUlp * scale_) /
                           std::max(std::fabs(dot(nd, nf)), trace_tol::kCandidateMinCos);
        }
        if (!clear_planes_.empty()) s.escaped = mesh_clear_ahead(s);  // mesh-only's escape rule
        return true;
    };
    const int depth = st.depth;
    ++stats.segments;
    if (h.repaired) st.medium = h.medium;  // the geometry's medium for this segment
    if (h.lost) {
        ++stats.lost;
        stats.lost_weight += st.weight;
        if (rec) rec->lost = true;
        st.weight = 0;
        return false;
    }
    if (!h.found) return false;  // escaped: the caller looks for the display
    if (!is_finite(h.p) || !is_finite(h.n_out) || !is_finite(h.d_in) || !std::isfinite(h.n_from)) {
        ++stats.nan_events;
        if (rec) rec->nan = true;
        st.weight = 0;
        return false;
    }
    if (alpha > 0 && (*media_)[st.medium].attenuates) {
        const double keep = std::exp(-alpha * h.length);  // Beer-Lambert over the (curved) segment
        stats.absorbed_weight += st.weight * (1 - keep);
        st.weight *= keep;
    }
    const SurfaceInfo& s = table[h.tag];
    if (st.defect < 0) {  // the segment through a smooth inclusion comes before the surface ending it
        const int k = st.medium.defect();
        if (k >= 0 && scene_.defects[static_cast<size_t>(k)].segment_min_rho2(st.o, h.p) < 1.0) st.defect = k;
        else if (s.optical && s.defect >= 0) st.defect = s.defect;
    }
    const Vec3& d_in = h.d_in;
    const bool entering = dot(d_in, h.n_out) < 0;  // crossing from `outside` into `inside`
    const Medium from = entering ? s.outside : s.inside;
    Medium to = entering ? s.inside : s.outside;
    // A smooth inhomogeneity clipped by a face: a ray entering the glass through the face
    // where the inhomogeneity reaches it enters the inhomogeneity's medium (the index there
    // is its field's, continuous with the glass's at rho = 1).
    if (to == Medium::Glass && s.defect < 0)
        for (int k : face_inclusions_)
            if (scene_.defects[static_cast<size_t>(k)].segment_min_rho2(h.p, h.p) < 1.0) to = Medium::inclusion(k);
    const Vec3 nf = entering ? h.n_out : -h.n_out;  // normal on the incident side
    Vec3 nd;
    bool split_here = false;
    if (!s.optical) {
        // A smooth inhomogeneity's boundary: the index is continuous, so the ray keeps its
        // direction and only changes how it propagates. The part of the boundary outside the
        // glass (a face clips the inhomogeneity) is met by rays in the air: nothing changes.
        nd = d_in;
        if (st.medium == from) st.medium = to;
    } else {
        if (rec) {
            rec->vertices.push_back(h.p);
            rec->tags.push_back(h.tag);
            rec->media.push_back(st.medium);
        }
        if (to == Medium::Absorber) {
            ++stats.absorbed_particle;
            stats.absorbed_weight += st.weight;
            if (rec) rec->absorbed = true;
            st.weight = 0;
            return false;
        }
        if (s.role == SurfaceRole::Rim && scene_.object.rim == RimFinish::Absorbing) {
            ++stats.absorbed_rim;
            stats.absorbed_weight += st.weight;
            if (rec) rec->absorbed = true;
            st.weight = 0;
            return false;
        }
        // The local indices on both sides of the interface.
        const double eta = h.n_from / index_at(to, h.p);
        const double cos_i = -dot(d_in, nf);
        const FresnelResult F = fresnel(cos_i, eta);
        bool reflect_it;
        if (F.total_internal_reflection) {
            reflect_it = true;
            ++stats.tir;
            if (rec) ++rec->tir;
        } else if (Principal) {
            reflect_it = false;
        } else if (split && st.splits_left > 0) {
            // Splitting. The sampled choice contributes w f_R (reflect, probability R) or w f_T
            // (transmit, probability T), where f_R and f_T are what the rest of the path
            // delivers after each branch; its expectation is R w E[f_R] + T w E[f_T]. Following
            // both, with weights w R and w T, delivers that expectation itself: unbiased, and
            // the Fresnel choice's variance is gone. The reflected branch waits on the stack
            // with the splits this one has left; the transmitted one goes on here.
            --st.splits_left;
            ++stats.splits;
            split_here = true;
            const double w_reflected = st.weight * F.reflectance;
            if (w_reflected > 0) {
                if (split->size >= kMaxSplitDepth)  // impossible by the capacity argument (SplitStack)
                    throw std::logic_error("Tracer: split stack overflow");
                State& r = split->items[static_cast<size_t>(split->size)];
                r = st;
                r.weight = w_reflected;
                r.depth = depth + 1;  // it resumes at the next interaction
                if (spawn(r, normalize(reflect(d_in, nf)), nf)) ++split->size;
            }
            st.weight *= 1.0 - F.reflectance;
            reflect_it = false;
        } else {
            reflect_it = rng->uniform() < F.reflectance;
            ++st.random_choices;
        }
        if (reflect_it) {
            nd = reflect(d_in, nf);
            if (!F.total_internal_reflection) ++stats.reflections;
        } else {
            nd = refract(d_in, nf, eta, cos_i, F.cos_t);
            st.medium = to;
            st.escaped = lane_faces_[2 * static_cast<size_t>(h.tag) + entering].escapes;  // the constructor's rule
            if (!split_here) ++stats.transmissions;  // a split counts as one split
            if (rec) rec->transmission *= 1.0 - F.reflectance;
        }
        nd = normalize(nd);
    }
    if (!spawn(st, nd, nf)) {
        if (rec) rec->nan = true;
        st.weight = 0;
        return false;
    }
    // Russian roulette: survive with probability q, weight / q, so the expected weight is
    // unchanged (q (w / q) + (1 - q) 0 = w). A split interaction is exempt: its branches stay
    // deterministic, which is what makes the low orders exact. Past the split depth a branch
    // is an ordinary sampled path and meets roulette at the same interactions as one.
    if (!Principal && !split_here && depth + 1 >= options_.rr_depth) {
        ++st.random_choices;
        if (rng->uniform() >= options_.rr_survival) {
            ++stats.roulette_kills;
            if (rec) rec->roulette = true;
            st.weight = 0;
            return false;
        }
        st.weight /= options_.rr_survival;
    }
    return true;
}

Tracer::FirstHit Tracer::first_hit(const Vec3& origin, const Vec3& direction, Medium medium, PathStats& stats) const {
    SegmentStart s;
    s.o = origin;
    s.d = normalize_any(direction);
    s.medium = medium;
    return first_hit(s, stats);
}

Tracer::FirstHit Tracer::first_hit(const SegmentStart& start, PathStats& stats) const {
    State st;
    st.o = start.o;
    st.d = start.d;
    st.medium = start.medium;
    st.skip = start.skip;
    st.skip_prim = start.skip_prim;
    st.skip_until = start.skip_until;
    st.escaped = start.escaped;
    const Hit h = propagate(st, stats);
    FirstHit f;
    f.found = h.found;
    f.t = h.t;
    f.tag = h.tag;
    return f;
}

PrincipalPath Tracer::principal_path(const Vec3& origin, const Vec3& direction) const {
    PrincipalPath rec;
    PathStats stats;
    State st;
    st.o = origin;
    st.d = normalize_any(direction);
    st.medium = medium_at(origin);
    if (st.medium == Medium::Absorber) {
        rec.absorbed = true;
        rec.media.push_back(st.medium);
        rec.direction = st.d;
        return rec;
    }
    run<true>(st, nullptr, stats, &rec, nullptr);
    rec.media.push_back(st.medium);
    rec.direction = st.d;
    if (!rec.absorbed && !rec.truncated && !rec.nan && !rec.lost && st.medium == Medium::Air && st.d.z > 0) {
        const double t = (display_.z - st.o.z) / st.d.z;
        if (t > 0) {
            rec.x = st.o.x + t * st.d.x;
            rec.y = st.o.y + t * st.d.y;
            rec.display_hit = display_.pixel(rec.x, rec.y, &rec.p, &rec.q) >= 0;
        }
    }
    return rec;
}

PrincipalPath Tracer::recorded_path(const Vec3& origin, const Vec3& direction, Medium medium, Rng* rng,
                                    PathStats& stats) const {
    ++stats.paths;
    PrincipalPath rec;
    State st;
    st.o = origin;
    st.d = normalize_any(direction);
    st.medium = medium;
    if (rng) run<false>(st, rng, stats, &rec, nullptr);
    else run<true>(st, nullptr, stats, &rec, nullptr);
    rec.media.push_back(st.medium);
    rec.direction = st.d;
    return rec;
}

PathResult Tracer::sample_path(const Vec3& origin, const Vec3& direction, Rng& rng, PathStats& stats) const {
    ++stats.paths;
    State st;
    st.o = origin;
    st.d = direction;
    st.medium = Medium::Air;
    run<false>(st, &rng, stats, nullptr, nullptr);
    PathResult r;
    branch_result(st, stats, r);
    return r;
}

void Tracer::sample_paths(const Vec3& origin, const Vec3& direction, Rng& rng, PathStats& stats,
                          std::vector<PathResult>& out) const {
    sample_paths_from(origin, direction, rng, stats, out, nullptr);
}

void Tracer::sample_packet(int n, const Vec3* origins, const Vec3* directions, Rng* rngs, PathStats& stats,
                           std::vector<PathResult>& out, size_t* ends) const {
    if (n < 0 || n > kBatch) throw std::invalid_argument("Tracer::sample_packet: more samples than a batch holds");
    if (!(packets_ || lockstep_) || n < 2) {
        for (int i = 0; i < n; ++i) {
            sample_paths_from(origins[i], directions[i], rngs[i], stats, out, nullptr);
            ends[i] = out.size();
        }
        return;
    }
    // The first segment draws no random number, so finding it ahead of the path changes nothing
    // the path draws. The camera rays of the whole batch are queried together, regrouped by
    // octant (EmbreeScene::intersect_coherent); the paths then go in packets of kPacket, in order.
    const bool mesh = options_.representation != Representation::Analytic;
    Candidate camera[kBatch];
    if (mesh) embree_->intersect_coherent(origins, directions, n, camera);
    for (int a = 0; a < n; a += kPacket) {
        const int m = std::min(kPacket, n - a);
        if (lockstep_ && options_.representation == Representation::MeshOnly) {
            sample_mesh_lockstep(m, origins + a, directions + a, rngs + a, stats, out, ends + a, camera + a);
            continue;
        }
        if (lockstep_) {
            sample_lockstep(m, origins + a, directions + a, rngs + a, stats, out, ends + a, mesh ? camera + a : nullptr);
            continue;
        }
        Hit h[kPacket];
        packet_hits(m, origins + a, directions + a, h, &stats, 0, camera + a);
        for (int i = a; i < a + m; ++i) {
            sample_paths_from(origins[i], directions[i], rngs[i], stats, out, &h[i - a]);
            ends[i] = out.size();
        }
    }
}

void Tracer::packet_hits(int n, const Vec3* origins, const Vec3* directions, Hit* out, PathStats* stats, int stride,
                         const Candidate* found) const {
    // One coherent packet of triangle candidates (or the candidates found already), each finished
    // as its own query would be (refined_hit, mesh_only_hit).
    Candidate queried[kPacket];
    const Candidate* c = found;
    if (!c) {
        embree_->intersect_packet(origins, directions, n, queried);
        c = queried;
    }
    for (int i = 0; i < n; ++i) {
        State st;
        st.o = origins[i];
        st.d = directions[i];
        st.medium = Medium::Air;
        out[i] = propagate(st, stats[i * stride], &c[i]);
    }
}

void Tracer::first_hits(int n, const Vec3* origins, const Vec3* directions, FirstHit* out, PathStats& stats) const {
    if (n < 0 || n > kBatch) throw std::invalid_argument("Tracer::first_hits: more rays than a batch holds");
    Hit h[kBatch];
    if (packets_ && n >= 2) {
        Candidate c[kBatch];
        embree_->intersect_coherent(origins, directions, n, c);
        for (int a = 0; a < n; a += kPacket)
            packet_hits(std::min(kPacket, n - a), origins + a, directions + a, h + a, &stats, 0, c + a);
    } else {
        for (int i = 0; i < n; ++i) {
            State st;
            st.o = origins[i];
            st.d = directions[i];
            st.medium = Medium::Air;
            h[i] = propagate(st, stats);
        }
    }
    for (int i = 0; i < n; ++i) out[i] = {h[i].found, h[i].t, h[i].tag};
}

void Tracer::sample_paths_from(const Vec3& origin, const Vec3& direction, Rng& rng, PathStats& stats,
                               std::vector<PathResult>& out, const Hit* first) const {
    const TracingDesc& tracing = scene_.tracing;
    State st;
    st.o = origin;
    st.d = direction;
    st.medium = Medium::Air;
    ++stats.paths;
    if (tracing.estimator == Estimator::Sample || tracing.split_depth == 0) {
        run<false>(st, &rng, stats, nullptr, nullptr, first);
        branch_result(st, stats, out.emplace_back());
        return;
    }
    st.splits_left = tracing.split_depth;  // <= kMaxSplitDepth (the constructor checks)
    // Depth first, transmitted branch first: the order in which branches draw from `rng` and are
    // appended is fixed by the sample alone. After split_depth splits a branch is an ordinary
    // sampled path (random Fresnel choices, roulette from rr_depth) carrying its weight.
    SplitStack pending;
    for (;;) {
        run<false>(st, &rng, stats, nullptr, &pending, first);
        first = nullptr;
        branch_result(st, stats, out.emplace_back());
        if (pending.size == 0) return;
        st = pending.items[static_cast<size_t>(--pending.size)];
    }
}

// The instances trace/Lockstep.cpp calls, which sees only their declarations: emitted here
// explicitly, since an instance this file inlines everywhere need not otherwise be emitted at all
// (an optimised build without link-time optimization then fails to link).
template void Tracer::run<false>(State&, Rng*, PathStats&, PrincipalPath*, SplitStack*, const Hit*) const;
template bool Tracer::interact<false>(State&, const Hit&, Rng*, PathStats&, PrincipalPath*, SplitStack*) const;

}  // namespace ltm
