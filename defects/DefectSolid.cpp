#include "defects/DefectSolid.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

#include "defects/ScratchPath.h"
#include "geometry/Tessellate.h"

namespace ltm {

const char* to_string(DefectType t) {
    switch (t) {
        case DefectType::Bubble: return "bubble";
        case DefectType::Scratch: return "scratch";
        case DefectType::Particle: return "particle";
        case DefectType::Inhomogeneity: return "inhomogeneity";
    }
    return "?";
}

double Defect::max_semi_axis() const { return std::max({semi_axes.x, semi_axes.y, semi_axes.z}); }

double Defect::segment_min_rho2(const Vec3& a, const Vec3& b) const {
    const Mat3 Ft = frame.transposed();
    const Vec3 ya = Ft * (a - center), yd = Ft * (b - a);
    const Vec3 u{ya.x / semi_axes.x, ya.y / semi_axes.y, ya.z / semi_axes.z};
    const Vec3 v{yd.x / semi_axes.x, yd.y / semi_axes.y, yd.z / semi_axes.z};
    const double vv = dot(v, v);
    const double t = vv > 0 ? std::clamp(-dot(u, v) / vv, 0.0, 1.0) : 0.0;
    return length2(u + v * t);
}

double defect_tolerance(const Defect& d, double object_tolerance, double relative) {
    const double size = d.type == DefectType::Scratch ? std::min(d.width, d.depth)
                                                      : std::min({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z});
    return std::min(object_tolerance, relative * size);
}

namespace {

// Largest distance from the z axis over the ellipsoid: its shadow on the xy plane is the ellipse
// c + A (cos, sin) with A's columns the principal semi-axes of A A^T (A = P F diag(e), P the xy
// projection). The maximum of |c + A(theta)| is found by a dense scan followed by golden-section
// refinement of the best bracket (the function is smooth with at most two local maxima).
double max_rho(const Vec3& c, const Mat3& F, const Vec3& e) {
    double s00 = 0, s01 = 0, s11 = 0;
    for (int k = 0; k < 3; ++k) {
        const double ax = F(0, k) * e[k], ay = F(1, k) * e[k];
        s00 += ax * ax;
        s01 += ax * ay;
        s11 += ay * ay;
    }
    const double tr = s00 + s11, det = s00 * s11 - s01 * s01;
    const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
    const double l1 = 0.5 * tr + disc, l2 = std::max(0.0, 0.5 * tr - disc);
    double vx = s01, vy = l1 - s00;
    if (std::hypot(vx, vy) < 1e-300) { vx = 1; vy = 0; if (s11 > s00) { vx = 0; vy = 1; } }
    const double nv = std::hypot(vx, vy);
    vx /= nv; vy /= nv;
    const double a1 = std::sqrt(l1), a2 = std::sqrt(l2);
    auto rho = [&](double th) {
        const double x = c.x + a1 * std::cos(th) * vx - a2 * std::sin(th) * vy;
        const double y = c.y + a1 * std::cos(th) * vy + a2 * std::sin(th) * vx;
        return std::hypot(x, y);
    };
    const int n = 720;
    int best = 0;
    double bv = -1;
    for (int i = 0; i < n; ++i) {
        const double v = rho(2 * kPi * i / n);
        if (v > bv) { bv = v; best = i; }
    }
    double lo = 2 * kPi * (best - 1) / n, hi = 2 * kPi * (best + 1) / n;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
        const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
        if (rho(m1) > rho(m2)) hi = m2; else lo = m1;
    }
    return std::max(bv, rho(0.5 * (lo + hi)));
}

// Gap between the ellipsoid and one spherical or flat face (positive: on the glass side).
double face_gap(const Surface& s, int sign, const Vec3& c, const Mat3& F, const Vec3& e) {
    if (s.kind == SurfaceKind::Plane) {
        const Vec3 n_out = s.axis * double(sign);
        const Vec3 nb = F.transposed() * n_out;  // the support function of the ellipsoid along n_out
        const double support = std::sqrt((e.x * nb.x) * (e.x * nb.x) + (e.y * nb.y) * (e.y * nb.y) +
                                         (e.z * nb.z) * (e.z * nb.z));
        return dot(s.origin - c, n_out) - support;
    }
    const Vec3 y = F.transposed() * (s.origin - c);  // the sphere's centre in the body frame
    if (sign > 0) return s.radius - distance(y, ellipsoid_farthest_point(e, y));
    const double inside = (y.x / e.x) * (y.x / e.x) + (y.y / e.y) * (y.y / e.y) + (y.z / e.z) * (y.z / e.z);
    if (inside <= 1.0) return -s.radius;  // the ellipsoid swallows the centre of curvature
    return distance(y, ellipsoid_closest_point(e, y)) - s.radius;
}

const char* nearest_face(const Lens& lens, const Vec3& p) {
    const double f = lens.distance_to_front(p), b = lens.distance_to_back(p), r = lens.distance_to_rim(p);
    if (f <= b && f <= r) return "front";
    return b <= r ? "back" : "rim";
}

}  // namespace

double ellipsoid_clearance(const Lens& lens, const Vec3& c, const Mat3& F, const Vec3& e) {
    if (e.x == e.y && e.y == e.z) return lens.signed_distance(c) - e.x;
    double gap = lens.signed_distance(c);  // the centre itself must be in the glass
    gap = std::min(gap, face_gap(lens.front_surface(), lens.front_normal_sign(), c, F, e));
    gap = std::min(gap, face_gap(lens.back_surface(), lens.back_normal_sign(), c, F, e));
    gap = std::min(gap, lens.aperture_radius() - max_rho(c, F, e));
    return gap;
}

namespace {

// Whether the ellipsoid certainly reaches into the glass: its centre is in it; for a sphere, the
// centre is nearer to the glass than the radius (exact); for an ellipsoid, one of 1024 points
// spread over its surface (a spherical Fibonacci lattice under its affine map) is in the glass.
// False means "not shown", never "certainly not": an ellipsoid centred outside the glass whose
// part in the glass falls between the points (spaced about 0.1 of its semi-axes: a graze, or a
// thin slab of glass crossing it) is missed, and only the advice that uses this is withheld.
bool reaches_glass(const Lens& lens, const Defect& d, double sdf) {
    if (sdf > 0) return true;
    if (d.is_sphere()) return sdf > -d.semi_axes.x;
    const int n = 1024;
    const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = golden_angle * i;
        const Vec3 body{d.semi_axes.x * r * std::cos(phi), d.semi_axes.y * r * std::sin(phi), d.semi_axes.z * z};
        if (lens.contains(d.center + d.frame * body)) return true;
    }
    return false;
}

void check_ellipsoid(const Lens& lens, const Defect& d, std::vector<DefectProblem>& out) {
    const char* size_key = d.is_sphere() ? "radius" : "semi_axes";
    const char* what = d.type == DefectType::Particle ? "particle" : "bubble";
    if (!is_finite(d.center)) {
        out.push_back({"center", "must be three finite numbers"});
        return;
    }
    if (!(d.semi_axes.x > 0 && d.semi_axes.y > 0 && d.semi_axes.z > 0) || !is_finite(d.semi_axes)) {
        out.push_back({size_key, fmt::format("must be positive and finite (got {})",
                                             d.is_sphere() ? fmt::format("{}", d.semi_axes.x)
                                                           : fmt::format("[{}, {}, {}]", d.semi_axes.x,
                                                                         d.semi_axes.y, d.semi_axes.z))});
        return;
    }
    const double gap = ellipsoid_clearance(lens, d.center, d.frame, d.semi_axes);
    const double sdf = lens.signed_distance(d.center);
    const std::string where = fmt::format("({:g}, {:g}, {:g})", d.center.x, d.center.y, d.center.z);
    // The ball of radius e_min about the centre lies in the ellipsoid, which lies in the ball of
    // radius e_max: with the object's farthest point from the centre (exact), a void certainly
    // holds the whole object (it would leave no glass) when that point is within e_min, and
    // certainly does not when it is beyond e_max. For a sphere the two agree: the test is exact.
    const double farthest = lens.farthest_distance(d.center);
    const double e_min = std::min({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z}), e_max = d.max_semi_axis();
    if (farthest <= e_min) {
        const std::string size = d.is_sphere() ? fmt::format("radius {:g} mm", d.semi_axes.x)
                                               : fmt::format("semi-axes [{:g}, {:g}, {:g}] mm", d.semi_axes.x,
                                                             d.semi_axes.y, d.semi_axes.z);
        out.push_back({size_key, fmt::format("the {} at {} ({}) holds the whole object, whose every point lies within "
                                             "{:.6g} mm of its centre: it would leave no glass (lengths are in mm)",
                                             what, where, size, farthest)});
        return;
    }
    // For a sphere the test is exact; for an ellipsoid, a centre farther outside than its largest
    // semi-axis certainly misses the glass.
    const bool misses = d.is_sphere() ? sdf <= -d.semi_axes.x : sdf <= -e_max;
    if (d.type == DefectType::Bubble && d.surface_breaking) {
        if (gap > 0)
            out.push_back({"surface_breaking",
                           fmt::format("the bubble at {} is declared surface-breaking but lies entirely inside "
                                       "the glass ({:.6g} mm from the {} face); remove surface_breaking",
                                       where, gap, nearest_face(lens, d.center))});
        else if (misses)
            out.push_back({"center", fmt::format("the surface-breaking bubble at {} lies entirely outside the "
                                                 "glass and would cut nothing",
                                                 where)});
        return;
    }
    if (gap <= 0) {
        std::string msg =
            misses ? fmt::format("the {} at {} lies entirely outside the glass", what, where)
                   : fmt::format("the {} at {} is not inside the glass: it reaches {:.6g} mm beyond the {} face",
                                 what, where, -gap, nearest_face(lens, d.center));
        // As a pit it would be right only where it certainly crosses the boundary (it reaches into
        // the glass, and not wholly: gap <= 0) and certainly leaves glass.
        if (d.type == DefectType::Particle)
            msg += "; an absorbing particle must lie strictly inside the glass";
        else if (misses)
            msg += "; an enclosed bubble must lie strictly inside it";
        else if (farthest > e_max && reaches_glass(lens, d, sdf))
            msg += "; declare surface_breaking: true for an open pit";
        out.push_back({"center", msg});
    }
}

// An inhomogeneity must meet the glass; a uniform one (a sharp interface on its ellipsoid) must
// lie strictly inside it, a smooth one may reach beyond a face (its region is clipped to the
// glass). Its index must stay real and >= 1 (n_glass + delta_n at its centre is the extreme).
void check_inhomogeneity(const Lens& lens, const Defect& d, std::vector<DefectProblem>& out) {
    const char* size_key = d.is_sphere() ? "radius" : "semi_axes";
    if (!is_finite(d.center)) {
        out.push_back({"center", "must be three finite numbers"});
        return;
    }
    if (!(d.semi_axes.x > 0 && d.semi_axes.y > 0 && d.semi_axes.z > 0) || !is_finite(d.semi_axes)) {
        out.push_back({size_key, "must be positive and finite"});
        return;
    }
    if (!std::isfinite(d.delta_n) || d.delta_n == 0) {
        out.push_back({"delta_n", fmt::format("must be a finite, non-zero change of the index (got {})", d.delta_n)});
        return;
    }
    const double n_peak = lens.spec().ior + d.delta_n;
    if (n_peak < 1.0 - kIndexBelowOneSlack) {
        out.push_back({"delta_n", fmt::format("makes n = {:g} + ({:g}) = {:g} < 1 at the inhomogeneity's centre",
                                              lens.spec().ior, d.delta_n, n_peak)});
        return;
    }
    const std::string where = fmt::format("({:g}, {:g}, {:g})", d.center.x, d.center.y, d.center.z);
    const double sdf = lens.signed_distance(d.center);
    if (d.index_profile == IndexProfile::Uniform) {
        const double gap = ellipsoid_clearance(lens, d.center, d.frame, d.semi_axes);
        if (gap <= 0)
            out.push_back({"center", fmt::format("the uniform inhomogeneity at {} is not strictly inside the glass (it "
                                                 "reaches {:.6g} mm beyond the {} face): a sharp inclusion must be "
                                                 "enclosed; use profile: smooth to clip it to the glass",
                                                 where, -gap, nearest_face(lens, d.center))});
        return;
    }
    // A sphere meets the solid iff its centre is within one radius of it (exact); an ellipsoid is
    // only accepted with its centre in the glass, which certainly meets it.
    const bool meets = sdf > 0 || (d.is_sphere() && sdf > -d.semi_axes.x);
    if (!meets)
        out.push_back({"center", d.is_sphere() ? fmt::format("the inhomogeneity at {} does not meet the glass (its "
                                                             "centre is {:.6g} mm outside, beyond its radius)",
                                                             where, -sdf)
                                               : fmt::format("the ellipsoidal inhomogeneity's centre {} must lie in "
                                                             "the glass (it is {:.6g} mm outside)",
                                                             where, -sdf)});
}

void check_scratch(const Lens& lens, const Defect& d, std::vector<DefectProblem>& out) {
    const char* face = d.side == 0 ? "front" : "back";
    if (!(d.width > 0) || !std::isfinite(d.width))
        out.push_back({"width", fmt::format("must be positive and finite (got {})", d.width)});
    if (!(d.depth > 0) || !std::isfinite(d.depth))
        out.push_back({"depth", fmt::format("must be positive and finite (got {})", d.depth)});
    if (!out.empty()) return;
    const double a = lens.aperture_radius();
    const double R = d.side == 0 ? lens.spec().r1 : lens.spec().r2;
    // Given points must be on the face (within 1 % of the groove depth) and within the aperture.
    auto check_point = [&](const char* key, const Vec3& p, bool has_z) {
        if (!is_finite(p)) {
            out.push_back({key, "must be finite numbers"});
            return false;
        }
        if (std::hypot(p.x, p.y) > a) {
            out.push_back({key, fmt::format("({:g}, {:g}) is outside the {} face's aperture (semi-diameter {:g} mm)",
                                            p.x, p.y, face, a)});
            return false;
        }
        if (has_z) {
            const Vec3 s = lens.surface_point(d.side, p.x, p.y);
            if (std::fabs(p.z - s.z) > 0.01 * d.depth) {
                out.push_back({key, fmt::format("({:g}, {:g}, {:g}) is {:.6g} mm off the {} face (its z there is "
                                                "{:.9g}); give [x, y] or a point on the face",
                                                p.x, p.y, p.z, std::fabs(p.z - s.z), face, s.z)});
                return false;
            }
        }
        return true;
    };
    if (!d.arc) {
        if (!check_point("start", d.start, d.start_has_z) || !check_point("end", d.end, d.end_has_z)) return;
        const Vec3 a3 = lens.surface_point(d.side, d.start.x, d.start.y);
        const Vec3 b3 = lens.surface_point(d.side, d.end.x, d.end.y);
        if (distance(a3, b3) < 1e-9 * std::max(1.0, a)) {
            out.push_back({"end", "coincides with start: a straight scratch needs two distinct points"});
            return;
        }
    } else {
        if (!check_point("arc", d.arc_center, d.arc_center_has_z)) return;
        if (!(d.arc_radius > 0) || !std::isfinite(d.arc_radius)) {
            out.push_back({"arc", fmt::format("radius must be positive and finite (got {})", d.arc_radius)});
            return;
        }
        if (!std::isinf(R) && d.arc_radius >= 2.0 * std::fabs(R)) {
            out.push_back({"arc", fmt::format("radius {:g} mm exceeds the {} sphere's diameter", d.arc_radius, face)});
            return;
        }
        if (!(d.end_angle > d.start_angle) || d.end_angle - d.start_angle >= 360.0) {
            out.push_back({"arc", "needs start_angle < end_angle < start_angle + 360"});
            return;
        }
    }
    // Walk the path: the groove's footprint must stay on the face and its bottom in the glass.
    const ScratchPath path = scratch_path(lens, d);
    const int n = 256;
    for (int i = 0; i <= n; ++i) {
        const double f = double(i) / n;
        for (double s : {-0.5 * d.width, 0.5 * d.width}) {
            const Vec3 edge = path.place(f, {s, 0.0});
            if (std::hypot(edge.x, edge.y) > a) {
                out.push_back({d.arc ? "arc" : "end",
                               fmt::format("the scratch runs off the {} face: its edge reaches rho = {:.6g} mm, beyond "
                                           "the semi-diameter {:g} mm",
                                           face, std::hypot(edge.x, edge.y), a)});
                return;
            }
        }
        const Vec3 bottom = path.place(f, {0.0, d.depth});
        if (lens.signed_distance(bottom) <= 0) {
            out.push_back({"depth", fmt::format("a {:g} mm deep groove cuts through the glass at ({:.6g}, {:.6g}, {:.6g})",
                                                d.depth, bottom.x, bottom.y, bottom.z)});
            return;
        }
    }
}

// A fixed, index-dependent rotation for sphere tessellations, so that no two spheres share
// vertex directions: touching spheres then never meet vertex-to-vertex.
Mat3 sphere_frame(int index) {
    const double k = index + 1;
    return rotation_from_euler_deg({std::fmod(k * 137.50776, 360.0), std::fmod(k * 59.2, 360.0),
                                    std::fmod(k * 23.9, 360.0)});
}

// The sign relating a surface's reference normal to the glass's outward normal on the faces of
// a tool that become cavity walls (their outward normal is minus the tool's).
int cavity_normal_sign(const TriMesh& tool, int tag, const Surface& s) {
    for (size_t f = 0; f < tool.num_triangles(); ++f) {
        if (tool.tags[f] != tag) continue;
        const auto& t = tool.triangles[f];
        const Vec3 c = (tool.vertices[t[0]] + tool.vertices[t[1]] + tool.vertices[t[2]]) / 3.0;
        return dot(s.normal(c), tool.face_normal(f)) > 0 ? -1 : +1;
    }
    return -1;
}

SurfaceInfo ellipsoid_surface(const Defect& d, int index) {
    const bool particle = d.type == DefectType::Particle, inclusion = d.type == DefectType::Inhomogeneity;
    SurfaceInfo info;
    info.surface = d.is_sphere() ? Surface::sphere(d.center, d.semi_axes.x) : Surface::ellipsoid(d.center, d.frame, d.semi_axes);
    info.defect = index;
    if (inclusion) {
        // Glass of another index inside, the glass outside; an outward shell like a particle's.
        // The smooth profile's boundary is not an optical interface (n is continuous there).
        info.name = fmt::format("inhomogeneity {}", index);
        info.role = SurfaceRole::Inhomogeneity;
        info.inside = Medium::inclusion(index);
        info.outside = Medium::Glass;
        info.normal_sign = +1;
        info.optical = d.index_profile == IndexProfile::Uniform;
    } else {
        info.name = fmt::format("{} {}", particle ? "particle" : (d.surface_breaking ? "pit" : "bubble"), index);
        info.role = particle ? SurfaceRole::Particle : (d.surface_breaking ? SurfaceRole::Pit : SurfaceRole::Bubble);
        info.inside = particle ? Medium::Absorber : Medium::Glass;
        info.outside = particle ? Medium::Glass : Medium::Air;
        info.normal_sign = particle ? +1 : -1;  // a particle keeps its outward shell; a void is a reversed one
    }
    return info;
}

DefectSolid make_ellipsoid(const Defect& d, int index, double tol, SurfaceTable& table, const Lens& lens) {
    DefectSolid out;
    const Mat3 frame = d.is_sphere() ? sphere_frame(index) : d.frame;
    const int tag = table.add(ellipsoid_surface(d, index));
    EllipsoidTessellation t = tessellate_ellipsoid(d.center, frame, d.semi_axes, tol, tag);
    out.tool = std::move(t.mesh);
    out.chord_error = t.chord_error_bound;
    out.clearance = ellipsoid_clearance(lens, d.center, d.frame, d.semi_axes);
    out.tags = {tag};
    return out;
}

DefectSolid make_scratch(const Lens& lens, const Defect& d, int index, double tol, SurfaceTable& table) {
    DefectSolid out;
    const ScratchPath path = scratch_path(lens, d);
    const double w = d.width, dep = d.depth;
    const double m = std::max(w, dep);  // how far the tool reaches out of the glass
    std::vector<Point2> prof;
    std::vector<int> edge_tags;
    auto add_surface = [&](const std::string& part, const Surface& s) {
        SurfaceInfo info;
        info.surface = s;
        info.name = fmt::format("scratch {} {}", index, part);
        info.role = SurfaceRole::Scratch;
        info.defect = index;
        const int tag = table.add(info);
        out.tags.push_back(tag);
        return tag;
    };
    if (d.profile == ScratchProfile::V) {
        // Apex at depth d; the walls continue straight out of the glass to t = -m.
        const double W = 0.5 * w * (1.0 + m / dep);
        const Point2 apex{0, dep}, right{W, -m}, left{-W, -m};
        prof = {apex, right, left};
        edge_tags = {add_surface("wall+", path.line_surface(apex, right)),
                     add_surface("top", path.line_surface(right, left)),
                     add_surface("wall-", path.line_surface(left, apex))};
    } else {
        // Circular bottom: radius rb, centre on the groove's midline at depth dep - rb.
        const double rb = dep <= 0.5 * w ? (0.25 * w * w + dep * dep) / (2.0 * dep) : 0.5 * w;
        const Point2 centre{0, dep - rb};
        const double theta_m = dep <= 0.5 * w ? std::asin(std::min(1.0, 0.5 * w / rb)) : 0.5 * kPi;
        const int bottom = add_surface("bottom", path.circle_surface(centre, rb));
        // Segments with chord error rb (1 - cos(dtheta / 2)) <= tol / 2: the bottom's faces also
        // carry the azimuthal chord error (<= tol / 2 below), and the two add.
        const double dtheta = 2.0 * std::acos(std::max(-1.0, 1.0 - 0.5 * tol / rb));
        const int nseg = std::max(2, static_cast<int>(std::ceil(2.0 * theta_m / dtheta)));
        const Point2 top_right{0.5 * w, -m}, top_left{-0.5 * w, -m};
        const Point2 arc_start{0.5 * w, centre.t + rb * std::cos(theta_m)};
        const Point2 arc_end{-0.5 * w, centre.t + rb * std::cos(theta_m)};
        const int side_p = add_surface("side+", path.line_surface(top_right, arc_start));
        const int side_m = add_surface("side-", path.line_surface(arc_end, top_left));
        const int top = add_surface("top", path.line_surface(top_left, top_right));
        prof.push_back(top_right);
        edge_tags.push_back(side_p);
        for (int i = 0; i < nseg; ++i) {
            const double th = theta_m - 2.0 * theta_m * i / nseg;
            prof.push_back(i == 0 ? arc_start : Point2{rb * std::sin(th), centre.t + rb * std::cos(th)});
            edge_tags.push_back(bottom);
        }
        prof.push_back(arc_end);
        edge_tags.push_back(side_m);
        prof.push_back(top_left);
        edge_tags.push_back(top);
    }
    const int end0 = add_surface("end0", path.end_surface(0));
    const int end1 = add_surface("end1", path.end_surface(1));
    // Stations: azimuthal chords within tol / 2 at the largest distance from the axis.
    int stations = 2;
    if (path.revolve) {
        double qmax = 0;
        for (const auto& p : prof) qmax = std::max(qmax, std::fabs(path.q0 + p.s * path.sq + p.t * path.tq));
        const double dphi = 2.0 * std::acos(std::max(-1.0, 1.0 - 0.5 * tol / qmax));
        stations = std::max(2, static_cast<int>(std::ceil(std::fabs(path.phi1 - path.phi0) / dphi)) + 1);
    } else {
        // A flat extrusion is exact with two stations; a few more keep the faces' aspect ratio sane.
        stations = std::clamp(static_cast<int>(std::ceil(path.length / (2.0 * std::max(w, m)))) + 1, 2, 256);
    }
    out.tool = sweep_profile(prof, stations, [&](int s, const Point2& p) { return path.place(double(s) / (stations - 1), p); },
                             edge_tags, end0, end1);
    out.chord_error = tol;
    out.clearance = -1;
    for (int tag : out.tags) table.entries[tag].normal_sign = cavity_normal_sign(out.tool, tag, table[tag].surface);
    return out;
}

}  // namespace

int add_defect_surfaces(const Defect& d, int index, SurfaceTable& table) {
    return table.add(ellipsoid_surface(d, index));
}

std::vector<DefectProblem> defect_problems(const Lens& lens, const Defect& d, const IndexField& field) {
    std::vector<DefectProblem> out;
    if (field.graded()) {
        if (d.type == DefectType::Inhomogeneity) {
            out.push_back({"type", fmt::format("an inhomogeneity needs a homogeneous glass around it, but the object has "
                                               "an index field ({}); give the glass a constant ior",
                                               to_string(field.type))});
            return out;
        }
        if (d.type == DefectType::Scratch || d.surface_breaking) {
            out.push_back({"type", fmt::format("a {} cuts a face, which a graded-index object ({}) cannot have: its "
                                               "curved paths are traced against the object's own faces and enclosed "
                                               "defects only",
                                               d.type == DefectType::Scratch ? "scratch" : "surface-breaking bubble",
                                               to_string(field.type))});
            return out;
        }
    }
    if (d.type == DefectType::Scratch) check_scratch(lens, d, out);
    else if (d.type == DefectType::Inhomogeneity) check_inhomogeneity(lens, d, out);
    else check_ellipsoid(lens, d, out);
    return out;
}

Aabb defect_bounds(const Lens& lens, const Defect& d) {
    Aabb box;
    if (d.is_ellipsoid()) {
        Vec3 h;
        for (int i = 0; i < 3; ++i)
            h[i] = std::sqrt(std::pow(d.frame(i, 0) * d.semi_axes.x, 2) + std::pow(d.frame(i, 1) * d.semi_axes.y, 2) +
                             std::pow(d.frame(i, 2) * d.semi_axes.z, 2));
        box.extend(d.center - h);
        box.extend(d.center + h);
        return box;
    }
    // The groove's cross-section reaches at most max(width, depth) from the path point on the
    // face; consecutive samples of a path of curvature radius rc at most L apart leave a sag below
    // L^2 / (8 rc) <= L (taken as is: the box only needs to contain the groove).
    const ScratchPath path = scratch_path(lens, d);
    const int n = 256;
    const double step = path.path_length() / n;
    const double reach = std::max(d.width, d.depth) + step;
    for (int i = 0; i <= n; ++i) {
        const Vec3 p = path.place(double(i) / n, {0.0, 0.0});
        box.extend(p - Vec3{reach, reach, reach});
        box.extend(p + Vec3{reach, reach, reach});
    }
    return box;
}

std::vector<DefectProblem> defect_pair_problems(const Lens& lens, const Defect& d, const Defect& other,
                                                int other_index) {
    if (d.type != DefectType::Inhomogeneity && other.type != DefectType::Inhomogeneity) return {};
    if (!defect_bounds(lens, d).overlaps(defect_bounds(lens, other))) return {};
    return {{"center", fmt::format("this {} overlaps defects[{}] (a {}): their bounding boxes intersect, and an "
                                   "inhomogeneity may overlap no other defect",
                                   to_string(d.type), other_index, to_string(other.type))}};
}

DefectSolid make_defect_solid(const Lens& lens, const Defect& d, int index, double tol, SurfaceTable& table) {
    DefectSolid s = d.type == DefectType::Scratch ? make_scratch(lens, d, index, tol, table)
                                                  : make_ellipsoid(d, index, tol, table, lens);
    s.bounds = s.tool.bounds();
    return s;
}

}  // namespace ltm
