#include "defects/SolidBuilder.h"

#include <algorithm>
#include <optional>
#include <fmt/format.h>
#include <stdexcept>
#include <utility>

#include "defects/DefectSolid.h"
#include "defects/Inclusion.h"
#include "geometry/Boolean.h"
#include "geometry/Refine.h"
#include "geometry/Tessellate.h"

namespace ltm {

namespace {

std::string defect_key_path(int defect, const std::string& key) {
    return fmt::format("defects[{}]{}{}", defect, key.empty() ? "" : ".", key);
}

}  // namespace

DefectError::DefectError(int defect_, std::string key_, std::string message_)
    : std::invalid_argument(defect_key_path(defect_, key_) + ": " + message_),
      defect(defect_),
      key(std::move(key_)),
      message(std::move(message_)) {}

std::string DefectError::key_path() const { return defect_key_path(defect, key); }

SurfaceTable object_surfaces(const Lens& lens) {
    SurfaceTable t;
    SurfaceInfo front{lens.front_surface(), "front", SurfaceRole::Front, -1, Medium::Glass, Medium::Air,
                      lens.front_normal_sign()};
    SurfaceInfo back{lens.back_surface(), "back", SurfaceRole::Back, -1, Medium::Glass, Medium::Air,
                     lens.back_normal_sign()};
    SurfaceInfo rim{lens.rim_surface(), "rim", SurfaceRole::Rim, -1, Medium::Glass, Medium::Air, +1};
    t.add(front);
    t.add(back);
    t.add(rim);
    return t;
}

namespace {

bool smooth_inclusion(const Defect& d) {
    return d.type == DefectType::Inhomogeneity && d.index_profile == IndexProfile::Smooth;
}

// Greedy grouping of tools whose bounding boxes do not overlap: each group is one corefinement
// (CGAL needs the tool to be free of self-intersections, which disjoint components guarantee).
std::vector<std::vector<size_t>> disjoint_groups(const std::vector<Aabb>& boxes, double margin) {
    std::vector<std::vector<size_t>> groups;
    std::vector<Aabb> group_boxes;
    for (size_t i = 0; i < boxes.size(); ++i) {
        bool placed = false;
        for (size_t g = 0; g < groups.size() && !placed; ++g) {
            bool clash = false;
            for (size_t j : groups[g]) clash = clash || boxes[i].overlaps(boxes[j], margin);
            if (!clash) {
                groups[g].push_back(i);
                placed = true;
            }
        }
        if (!placed) groups.push_back({i});
    }
    return groups;
}

}  // namespace

namespace {

// A smooth inclusion's TetGen region and its lattice, in units of its ellipsoid (index_region).
constexpr double kRegionScale = 1.25, kLatticeScale = 1.12;
// The bias-corrected lattice's bound over the plain one's (index_region: 1.027 needed).
constexpr double kCorrectedLatticeFactor = 1.05;

// The mesh whose faces lie outside the surface they approximate: vertices pushed out along their
// (area-weighted) normals by `offset`; twice the chord error makes a facet inscribed within e of a
// convex surface clear it by at least e (a concave one is already outside).
TriMesh circumscribed(TriMesh m, double offset) {
    std::vector<Vec3> normal(m.vertices.size());
    for (size_t f = 0; f < m.num_triangles(); ++f) {
        const auto& t = m.triangles[f];
        const Vec3 n = cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
        for (auto v : t) normal[v] += n;
    }
    for (size_t v = 0; v < m.vertices.size(); ++v) m.vertices[v] += normalize(normal[v]) * offset;
    return m;
}

}  // namespace

TetRegion index_region(const Lens& lens, const Defect* defect, const IndexField& field, const MeshOptions& opt,
                       const std::string& name) {
    TetRegion r;
    r.name = name;
    r.tolerance = opt.index_tolerance;
    // Tetrahedra whose enclosing ball misses the glass are dropped: no path inside the glass
    // reaches them (the tracer meets the exact faces first).
    r.keep = [lens](const Vec3& c, double radius) { return lens.signed_distance(c) > -radius; };
    if (defect) {
        const auto f = std::make_shared<InclusionField>(*defect, lens.spec().ior);
        // The region: the ellipsoid scaled by kRegionScale, tessellated within 1 % of its smallest
        // semi-axis (so the true ellipsoid, where the tracer hands paths over, lies well inside).
        // The lattice (geometry/TetMesh.h) fills it out to rho = kLatticeScale, across the
        // ellipsoid where the field's curvature jumps; beyond, where n is constant and linear
        // interpolation exact, TetGen's unstructured layer along the boundary costs no accuracy.
        // The boundary only has to enclose the lattice (rho <= kLatticeScale): an icosphere with a
        // chord error of 2 % of the unit sphere, under the ellipsoid's affine map, keeps its facets
        // at rho >= 0.98 kRegionScale = 1.225 (the map preserves rho), whatever the ellipsoid's
        // elongation; finer facets would only make TetGen refine along them.
        const double tol = 0.02 * kRegionScale * f->max_semi_axis();
        r.boundary = tessellate_ellipsoid(defect->center, defect->frame, defect->semi_axes * kRegionScale, tol, 0).mesh;
        // What the mesh interpolates. Two things make the lattice's interpolant follow the field
        // more closely than the tolerance alone:
        //  * the profile's polynomial continued beyond the ellipsoid (extended_n2), to s_ext: the
        //    field's curvature jumps at s = 1, and the tetrahedra straddling it would otherwise
        //    interpolate a kink (a layer of biased gradient that grazing paths cross lengthwise).
        //    s_ext = (1 + 2 r / e_min)^2, with r the lattice tetrahedron's enclosing radius,
        //    covers every lattice tetrahedron with part of it inside; beyond, n is the glass's
        //    again (and extended_hessian_bound makes TetGen split any other tetrahedron that would
        //    reach across both). Where that reach exceeds the lattice's own extent
        //    (kLatticeScale: tetrahedra coarse against the inclusion, as for weak striae) the
        //    field is meshed as it is (s_ext = 1);
        //  * the lattice's mean interpolation error taken out of the vertex values. Linear
        //    interpolation of f = x^T H x / 2 over a tetrahedron errs by (1/10) sum_i (v_i - c)^T H
        //    (v_i - c) on average (c its centroid; the simplex's second moment is 1/20 of
        //    sum_i (v_i - c)(v_i - c)^T); BCC's Delaunay tetrahedra, in their cubic orientations,
        //    have sum_i (v_i - c)(v_i - c)^T = (5 a^2 / 12) I on average, so the mean error is
        //    a^2 tr H / 24, a smooth bias field whose gradient bends every path by O(h^2) the
        //    same way. Subtracting it at the vertices leaves the periodic, zero-mean part that
        //    averages out along a path. The criterion accounts for it: with the bias written as
        //    tr(H alpha I) / 2, alpha = a^2 / 12, the corrected error at x is
        //    tr(H (S(x) - alpha I)) / 2 with S(x) = sum_i l_i (v_i - x)(v_i - x)^T >= 0 and
        //    tr S <= r^2 (Waldron), so at most M (r^2 + alpha) / 2: the bound handed to TetGen is
        //    M (1 + alpha / r^2). A lattice tetrahedron (r^2 = 5 a^2 / 16) then needs 1.027 times
        //    the bound the plain lattice does; the lattice is spaced for 1.05 times it, so that it
        //    passes with 2 % to spare (TetGen's optimisation moves some of its tetrahedra).
        const double t = opt.index_tolerance, emin = f->min_semi_axis();
        const double m_inside = f->hessian_bound(defect->center, emin);  // over s in [0, 1]
        const double reach = 2.0 * (lattice_spacing(t, m_inside) * std::sqrt(5.0) / 4.0) / emin;
        const double s_ext = 1.0 + reach <= kLatticeScale ? (1.0 + reach) * (1.0 + reach) : 1.0;
        // The bound over s in [0, s_ext] (the ball of radius sqrt(s_ext) e_min about the centre),
        // which only raises the bound: the spacing shrinks, and the reach with it.
        r.lattice_hessian = kCorrectedLatticeFactor * f->extended_hessian_bound(defect->center, std::sqrt(s_ext) * emin, s_ext);
        const double a = lattice_spacing(t, r.lattice_hessian), alpha = a * a / 12.0;
        r.n2 = [f, s_ext, alpha](const Vec3& x) {
            return f->extended_n2(x, s_ext) - 0.5 * alpha * f->extended_laplacian_n2(x, s_ext);
        };
        r.hessian_bound = [f, s_ext, alpha](const Vec3& c, double radius) {
            const double m = f->extended_hessian_bound(c, radius, s_ext);
            return m > 0 && radius > 0 ? m * (1.0 + alpha / (radius * radius)) : m;
        };
        // The Hessian where paths use the mesh, for the lattice's end correction (LatticePhase.h).
        r.hessian = [f, s_ext](const Vec3& x) { return f->extended_hessian_n2(x, s_ext); };
        // rho is 1/e_min-Lipschitz: (kLatticeScale - rho) e_min is a lower bound of the depth below
        // the ellipsoid rho = kLatticeScale.
        r.depth = [f](const Vec3& x) { return (kLatticeScale - std::sqrt(f->s(x))) * f->min_semi_axis(); };
        return r;
    }
    // linear_n: n^2 = (ior + k . x)^2 has the constant Hessian 2 k k^T, of norm 2 |k|^2. The
    // boundary's facets need not be finer than a quarter of the lattice's spacing (paths meet the
    // exact faces; the facets only enclose them).
    const double m = 2.0 * length2(field.gradient);
    const double a = lattice_spacing(opt.index_tolerance, m);
    // The region reaches 1.5 a beyond the glass and the lattice 0.9 a beyond it, so that TetGen's
    // unstructured layer along the boundary lies outside the glass, where no path goes: inside,
    // every tetrahedron is the lattice's (the exact faces cut through it).
    const LensTessellation t = tessellate_lens(lens, std::max(opt.chord_tolerance, 0.25 * a), 0, 0, 0);
    r.boundary = circumscribed(t.mesh, 2.0 * t.chord_error + 1.5 * a);
    r.n2 = [field](const Vec3& x) { return field.n2(x); };
    r.hessian_bound = [m](const Vec3&, double) { return m; };
    const Vec3 k = field.gradient;
    r.hessian = [k](const Vec3&) {  // 2 k k^T, for the lattice's end correction (LatticePhase.h)
        Mat3 h;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) h(i, j) = 2.0 * k[i] * k[j];
        return h;
    };
    r.depth = [lens, a](const Vec3& x) { return lens.signed_distance(x) + 1.5 * a; };
    return r;
}

// The triangle mesh and surface table (everything but the TetGen regions).
static Solid build_surface_solid(const Lens& lens, const std::vector<Defect>& defects, const MeshOptions& opt,
                                 StageReport* report);

// The surface table alone, when no defect cuts the glass (build_solid, surfaces_only); nullopt
// when one does. A defect cuts nothing when it is an ellipsoid strictly inside the glass
// (ellipsoid_clearance > 0, exact) whose box overlaps no other defect's (conservative).
static std::optional<Solid> surfaces_without_mesh(const Lens& lens, const std::vector<Defect>& defects,
                                                  StageReport* report) {
    StageTimer t(report, "surfaces");
    std::vector<Aabb> boxes;
    for (const Defect& d : defects) {
        if (!d.is_ellipsoid() || d.surface_breaking) return std::nullopt;
        if (!(ellipsoid_clearance(lens, d.center, d.frame, d.semi_axes) > 0)) return std::nullopt;
        boxes.push_back(defect_bounds(lens, d));
    }
    for (size_t i = 0; i < boxes.size(); ++i)
        for (size_t j = i + 1; j < boxes.size(); ++j)
            if (boxes[i].overlaps(boxes[j])) return std::nullopt;
    Solid s;
    s.meshed = false;
    s.surfaces = object_surfaces(lens);
    for (size_t k = 0; k < defects.size(); ++k) add_defect_surfaces(defects[k], static_cast<int>(k), s.surfaces);
    s.corefined.assign(defects.size(), false);
    s.tag_chord_error.assign(s.surfaces.size(), 0.0);
    t.done(fmt::format("{} analytic surfaces, no mesh (closed forms only)", s.surfaces.size()));
    return s;
}

Solid build_solid(const Lens& lens, const std::vector<Defect>& defects, const MeshOptions& opt, StageReport* report,
                  const IndexField& field, bool surfaces_only) {
    std::optional<Solid> bare;
    if (surfaces_only) bare = surfaces_without_mesh(lens, defects, report);
    Solid s = bare ? std::move(*bare) : build_surface_solid(lens, defects, opt, report);
    for (size_t k = 0; k < defects.size(); ++k) {
        const Defect& d = defects[k];
        if (d.type != DefectType::Inhomogeneity || d.index_profile != IndexProfile::Smooth) continue;
        s.regions.push_back(tetrahedralize(index_region(lens, &d, field, opt, fmt::format("defects[{}]", k)), report));
        s.region_defect.push_back(static_cast<int>(k));
    }
    if (field.type == IndexFieldType::LinearN) {
        s.regions.push_back(tetrahedralize(index_region(lens, nullptr, field, opt, "object"), report));
        s.region_defect.push_back(-1);
    }
    return s;
}

static Solid build_surface_solid(const Lens& lens, const std::vector<Defect>& defects, const MeshOptions& opt,
                                 StageReport* report) {
    Solid s;
    s.surfaces = object_surfaces(lens);

    StageTimer t_tess(report, "tessellate");
    LensTessellation lt = tessellate_lens(lens, opt.chord_tolerance, kTagFront, kTagBack, kTagRim);
    s.object_chord_error = lt.chord_error;
    t_tess.done(fmt::format("{} triangles, {} rings, chord error {:.3g} mm", lt.mesh.num_triangles(), lt.rings,
                            lt.chord_error));
    if (defects.empty()) {
        s.mesh = std::move(lt.mesh);
        s.tag_chord_error.assign(s.surfaces.size(), s.object_chord_error);
        return s;
    }

    StageTimer t_tools(report, "defect-tools");
    const double eps_obj = s.object_chord_error;
    std::vector<DefectSolid> tools;
    std::vector<double> host_tol(defects.size(), eps_obj);  // object chord error near each defect
    size_t tool_triangles = 0;
    for (size_t k = 0; k < defects.size(); ++k) {
        const Defect& d = defects[k];
        double tol = defect_tolerance(d, opt.chord_tolerance, opt.defect_relative_tolerance);
        if (d.type != DefectType::Scratch && !d.surface_breaking && !smooth_inclusion(d)) {
            // An enclosed defect close to the boundary: both its tool and the object mesh near it
            // must be finer than a quarter of its clearance, so that the two inscribed meshes stay
            // at least half the clearance apart (each moves by at most its chord error).
            const double clearance = ellipsoid_clearance(lens, d.center, d.frame, d.semi_axes);
            if (clearance > 0 && clearance <= 2.0 * (eps_obj + tol)) {
                tol = std::min(tol, 0.25 * clearance);
                host_tol[k] = 0.25 * clearance;
            }
        }
        tools.push_back(make_defect_solid(lens, d, static_cast<int>(k), tol, s.surfaces));
        s.max_defect_chord_error = std::max(s.max_defect_chord_error, tools.back().chord_error);
        tool_triangles += tools.back().tool.num_triangles();
    }
    t_tools.done(fmt::format("{} defects, {} tool triangles", defects.size(), tool_triangles));
    s.tag_chord_error.assign(s.surfaces.size(), s.object_chord_error);
    for (const auto& t : tools)
        for (int tag : t.tags) s.tag_chord_error[static_cast<size_t>(tag)] = t.chord_error;
    s.corefined.assign(defects.size(), false);

    // A defect is enclosed when it stays clear of the glass boundary and of every other defect by
    // more than both tessellations' chord errors: its inscribed tool mesh then cannot touch the
    // object mesh, and appending the reversed tool is exactly what the Boolean would produce.
    std::vector<bool> touches_other(defects.size(), false);
    for (size_t i = 0; i < tools.size(); ++i)
        for (size_t j = i + 1; j < tools.size(); ++j) {
            const double margin = tools[i].chord_error + tools[j].chord_error;
            if (tools[i].bounds.overlaps(tools[j].bounds, margin)) touches_other[i] = touches_other[j] = true;
        }
    std::vector<size_t> cutters;
    std::vector<RefineRegion> regions;
    TriMesh appended;
    for (size_t k = 0; k < defects.size(); ++k) {
        const bool clear = tools[k].clearance > host_tol[k] + tools[k].chord_error && !touches_other[k];
        Aabb near = tools[k].bounds;
        const double reach = std::max(0.0, tools[k].clearance) + 2.0 * eps_obj;
        near.lo -= Vec3{reach, reach, reach};
        near.hi += Vec3{reach, reach, reach};
        if (smooth_inclusion(defects[k])) {
            continue;  // no faces: the region is TetGen's (build_solid)
        } else if (defects[k].type == DefectType::Particle || defects[k].type == DefectType::Inhomogeneity) {
            if (!clear)
                throw DefectError(static_cast<int>(k), "center",
                                  fmt::format("the {} touches another defect or lies within the tessellation's chord "
                                              "error of the glass boundary (clearance {:.3g} mm); it must be separate "
                                              "from everything",
                                              to_string(defects[k].type), tools[k].clearance));
            appended.append(tools[k].tool, /*flip=*/false);
        } else if (clear && !opt.always_boolean) {
            appended.append(tools[k].tool, /*flip=*/true);
            ++s.enclosed_defects;
        } else {
            cutters.push_back(k);
            s.corefined[k] = true;
            host_tol[k] = std::min(host_tol[k], tools[k].chord_error);
        }
        if (host_tol[k] < eps_obj) regions.push_back({near, host_tol[k]});
    }
    if (!regions.empty()) {
        StageTimer t_ref(report, "refine");
        const size_t before = lt.mesh.num_triangles();
        const size_t splits = refine_near(lt.mesh, s.surfaces, regions);
        t_ref.done(fmt::format("{} region(s), {} bisections, {} -> {} triangles", regions.size(), splits, before,
                               lt.mesh.num_triangles()));
    }

    TriMesh body = std::move(lt.mesh);
    if (!cutters.empty()) {
        StageTimer t_bool(report, "boolean");
        std::vector<Aabb> boxes;
        for (size_t k : cutters) boxes.push_back(tools[k].bounds);
        const auto groups = disjoint_groups(boxes, s.max_defect_chord_error);
        std::vector<TriMesh> group_meshes;
        for (const auto& g : groups) {
            TriMesh merged;
            for (size_t i : g) merged.append(tools[cutters[i]].tool);
            group_meshes.push_back(std::move(merged));
        }
        const size_t before = body.num_triangles();
        body = subtract(body, group_meshes);
        s.boolean_operations = static_cast<int>(groups.size());
        t_bool.done(fmt::format("{} defects in {} corefinement(s), {} -> {} triangles", cutters.size(), groups.size(),
                                before, body.num_triangles()));
        // Glass that is left has a boundary, and not only of cavity walls (those face into the
        // voids, so some face of the object bounds it): no triangle left means no glass.
        if (body.num_triangles() == 0) {
            auto kind = [&](size_t k) {
                return defects[k].surface_breaking ? "pit" : to_string(defects[k].type);
            };
            std::string names;
            for (size_t i = 0; i < cutters.size(); ++i)
                names += fmt::format("{}defects[{}] ({})", i == 0 ? "" : (i + 1 == cutters.size() ? " and " : ", "),
                                     cutters[i], kind(cutters[i]));
            throw DefectError(static_cast<int>(cutters.front()), "",
                              cutters.size() == 1
                                  ? fmt::format("the Boolean with this {} leaves no glass: it removes the whole object "
                                                "(lengths are in mm)",
                                                kind(cutters.front()))
                                  : fmt::format("the Booleans with {} leave no glass: together they remove the whole "
                                                "object (lengths are in mm)",
                                                names));
        }
    }
    body.append(appended);
    s.mesh = std::move(body);
    if (report)
        report->add("assemble", 0.0,
                    fmt::format("{} triangles, {} enclosed defect(s) appended without a Boolean", s.mesh.num_triangles(),
                                s.enclosed_defects));
    return s;
}

}  // namespace ltm
