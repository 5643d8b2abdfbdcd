#include "validation/Validate.h"

#include <cmath>
#include <fmt/format.h>

#include "validation/AnalyticScene.h"
#include "validation/GrinReference.h"
#include "validation/ValidationRays.h"
#include "validation/ValidationTolerance.h"

namespace ltm::validation {

namespace {

double angle_between(const Vec3& a, const Vec3& b) {
    // atan2(|a x b|, a.b): accurate for tiny angles, unlike acos.
    return std::atan2(length(cross(a, b)), dot(a, b));
}

void fold(CategoryResult& into, const CategoryResult& c) {
    into.rays += c.rays;
    into.compared += c.compared;
    into.ill_conditioned += c.ill_conditioned;
    into.sequence_mismatches += c.sequence_mismatches;
    into.over_tolerance += c.over_tolerance;
    into.max_hit_error = std::max(into.max_hit_error, c.max_hit_error);
    into.max_dir_error = std::max(into.max_dir_error, c.max_dir_error);
    into.max_ratio = std::max(into.max_ratio, c.max_ratio);
}

std::string seq(const std::vector<std::string>& s) {
    std::string o;
    for (const auto& x : s) o += (o.empty() ? "" : " ") + x;
    return o.empty() ? "(none)" : o;
}

}  // namespace

namespace {

// Compares one traced path with its reference path under the given tolerances: the surface
// sequence and the display first, then the vertices, the display hit and the final direction.
// Updates the ray's category and records a failure (the first 20) with the ray and the reason.
void compare(const ValidationRay& ray, const PrincipalPath& got, const Solid& solid, const Path& ref, double pos_tol,
             double dir_tol, CategoryResult& c, ValidationReport& report) {
    auto fail = [&](const std::string& why) {
        if (report.failures.size() < 20)
            report.failures.push_back(fmt::format("{} ray o=({:.17g}, {:.17g}, {:.17g}) d=({:.17g}, {:.17g}, {:.17g}): {}",
                                                  ray.category, ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x,
                                                  ray.direction.y, ray.direction.z, why));
    };
    std::vector<std::string> names;
    for (int tag : got.tags) names.push_back(solid.surfaces[tag].name);
    if (names != ref.surfaces || got.display_hit != ref.on_display) {
        ++c.sequence_mismatches;
        fail(fmt::format("surfaces [{}] but the reference has [{}]", seq(names), seq(ref.surfaces)));
        return;
    }
    ++c.compared;
    double hit_err = 0;
    for (size_t i = 0; i < ref.vertices.size(); ++i) hit_err = std::max(hit_err, distance(got.vertices[i], ref.vertices[i]));
    if (ref.on_display) hit_err = std::max(hit_err, std::hypot(got.x - ref.display_x, got.y - ref.display_y));
    const double dir_err = angle_between(got.direction, ref.direction);
    c.max_hit_error = std::max(c.max_hit_error, hit_err);
    c.max_dir_error = std::max(c.max_dir_error, dir_err);
    const double ratio = std::max(hit_err / pos_tol, dir_err / dir_tol);
    c.max_ratio = std::max(c.max_ratio, ratio);
    if (ratio > 1.0) {
        ++c.over_tolerance;
        fail(fmt::format("position error {:.3g} mm (tolerance {:.3g}), direction error {:.3g} rad (tolerance {:.3g})",
                         hit_err, pos_tol, dir_err, dir_tol));
    }
}

bool graded(const Scene& scene) {
    if (scene.object.index_field.graded()) return true;
    for (const Defect& d : scene.defects)
        if (d.type == DefectType::Inhomogeneity) return true;
    return false;
}

// The scene's geometry without its index field and inhomogeneities: where the validation rays of
// a graded scene come from (their origins and directions only need the solid's shape).
Scene geometry_only(Scene s) {
    s.object.index_field = IndexField{};
    std::vector<Defect> kept;
    for (const Defect& d : s.defects)
        if (d.type != DefectType::Inhomogeneity) kept.push_back(d);
    s.defects = kept;
    return s;
}

// The bound on |grad n^2| over the meshed glass that meshed_position_tolerance needs, derived here
// from the field's data (independently of geometry/ and defects/): for a smooth inclusion
// n = n0 + dn q, q = (1 - s)^2, |grad q| = 4 (1 - s) sqrt(s) |S^1/2 ...| <= 4 (1 - s) sqrt(s) / e_min
// <= (8 / (3 sqrt 3)) / e_min (the maximum of (1 - s) sqrt(s) is 2 / (3 sqrt 3) at s = 1/3), so
// |grad n^2| = 2 n |dn| |grad q| <= 2 (n0 + |dn|) |dn| 1.54 / e_min; for linear_n,
// |grad n^2| = 2 n |k| <= 2 n_max |k|.
double max_grad_n2(const Scene& scene, double n_max) {
    double g = 0;
    if (scene.object.index_field.type == IndexFieldType::LinearN)
        g = std::max(g, 2.0 * n_max * length(scene.object.index_field.gradient));
    for (const Defect& d : scene.defects) {
        if (d.type != DefectType::Inhomogeneity || d.index_profile != IndexProfile::Smooth) continue;
        const double emin = std::min({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z});
        const double n0 = scene.object.lens.ior, dn = std::fabs(d.delta_n);
        g = std::max(g, 2.0 * (n0 + dn) * dn * (8.0 / (3.0 * std::sqrt(3.0))) / emin);
    }
    return g;
}

ValidationReport validate_graded(const Scene& scene, const Solid& solid, Representation representation, int density) {
    ValidationReport report;
    report.representation = representation;
    const GrinReference reference(scene);
    TracerOptions opt;
    opt.representation = representation;
    const Tracer tracer(scene, solid, opt);
    const double L = reference.length_scale();
    // A TetGen-meshed field: the tracer follows n^2 interpolated within index_tolerance; the
    // tolerance needs the worst tetrahedron's sum of inverse heights (ValidationTolerance.h).
    const bool meshed = !solid.regions.empty();
    double q = 0;
    long tets = 0;
    for (const TetMesh& m : solid.regions) {
        tets += static_cast<long>(m.num_tets());
        for (const auto& t : m.tets)
            q = std::max(q, tet_inverse_heights(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]], m.vertices[t[3]]));
    }
    for (const ValidationRay& ray : validation_rays(geometry_only(scene), density)) {
        CategoryResult& c = report.categories[ray.category];
        ++c.rays;
        const GrinPath ref = reference.trace(ray.origin, ray.direction);
        const RaySensitivity sens = reference.sensitivity(ray.origin, ray.direction);
        const PrincipalPath got = tracer.principal_path(ray.origin, ray.direction);
        if (!sens.stable || ref.path.lost || ref.path.truncated) {
            ++c.ill_conditioned;
            continue;
        }
        const PathError e = reference.estimate_error(ray.origin, ray.direction);
        double pos_tol, dir_tol;
        if (meshed) {
            // The path's length in the glass: its vertices' chords (the arc is longer by O(turn^2)).
            double s = 0;
            for (size_t i = 0; i + 1 < ref.path.vertices.size(); ++i) s += distance(ref.path.vertices[i], ref.path.vertices[i + 1]);
            const double n_min = std::max(1.0, ref.min_index), n_max = reference.glass_index({0, 0, 0}) + 0.1;
            const double G = p1_gradient_error(scene.mesh.index_tolerance, q);
            pos_tol = meshed_position_tolerance(ref, static_cast<int>(std::min<long>(tets, 1 << 30)), L, sens.kappa,
                                                scene.mesh.index_tolerance, G, s, max_grad_n2(scene, n_max), n_min,
                                                ref.min_cos_incidence, e.position);
            dir_tol = pos_tol / L;
            // The tracer follows the interpolated field, which moves a path by up to pos_tol: a ray
            // whose surface sequence changes when its start moves by that much (a path guided by
            // total internal reflection over many bounces) is ill-conditioned at this tolerance,
            // as a ray near a seam is at the rounding level.
            Vec3 e1, e2;
            orthonormal_basis(normalize(ray.direction), e1, e2);
            const double step = std::min(pos_tol, 1e-3 * L);
            bool stable = true;
            // Moved by `step` sideways, and turned by step / L (the tolerance's direction).
            const Vec3 d = normalize(ray.direction);
            for (const Vec3& e : {e1, -e1, e2, -e2})
                for (int turn = 0; turn < 2; ++turn) {
                    try {
                        const Path q = turn ? reference.principal_path(ray.origin, normalize(d + e * (step / L)))
                                            : reference.principal_path(ray.origin + e * step, d);
                        stable = stable && q.surfaces == ref.path.surfaces && q.on_display == ref.path.on_display;
                    } catch (const std::invalid_argument&) {
                        stable = false;  // the moved origin is no longer in air: the ray starts at a face
                    }
                }
            if (!stable) {
                ++c.ill_conditioned;
                continue;
            }
        } else {
            pos_tol = grin_position_tolerance(ref, L, sens.kappa, e.position);
            dir_tol = grin_direction_tolerance(ref, L, sens.kappa_dir, e.direction);
        }
        compare(ray, got, solid, ref.path, pos_tol, dir_tol, c, report);
    }
    for (const auto& [name, c] : report.categories) fold(report.total, c);
    return report;
}

}  // namespace

bool can_validate(const Scene& scene, std::string* why) {
    if (!graded(scene)) return supports(scene, why);
    if (!grin_supports(scene, why)) return false;
    return supports(geometry_only(scene), why);
}

ValidationReport validate(const Scene& scene, const Solid& solid, Representation representation, int density) {
    if (graded(scene)) return validate_graded(scene, solid, representation, density);
    ValidationReport report;
    report.representation = representation;
    const AnalyticScene reference(scene);
    TracerOptions opt;
    opt.representation = representation;
    const Tracer tracer(scene, solid, opt);
    for (const ValidationRay& ray : validation_rays(scene, density)) {
        CategoryResult& c = report.categories[ray.category];
        ++c.rays;
        const Path ref = reference.principal_path(ray.origin, ray.direction);
        const PrincipalPath got = tracer.principal_path(ray.origin, ray.direction);
        const PathTolerance tol = path_tolerance(reference, ray);
        if (!tol.stable) {
            ++c.ill_conditioned;
            continue;
        }
        compare(ray, got, solid, ref, tol.position, tol.direction, c, report);
    }
    for (const auto& [name, c] : report.categories) fold(report.total, c);
    return report;
}

std::string format_report(const ValidationReport& r, bool verdict) {
    std::string out = fmt::format("representation: {}\n{:<10} {:>6} {:>9} {:>6} {:>9} {:>9} {:>14} {:>14} {:>10}\n",
                                  to_string(r.representation), "category", "rays", "compared", "ill", "sequence",
                                  "over-tol", "hit error mm", "dir error rad", "err/tol");
    auto row = [&](const std::string& name, const CategoryResult& c) {
        out += fmt::format("{:<10} {:>6} {:>9} {:>6} {:>9} {:>9} {:>14.3e} {:>14.3e} {:>10.3g}\n", name, c.rays, c.compared,
                           c.ill_conditioned, c.sequence_mismatches, c.over_tolerance, c.max_hit_error, c.max_dir_error,
                           c.max_ratio);
    };
    for (const auto& [name, c] : r.categories) row(name, c);
    row("all", r.total);
    if (!verdict) return out;
    out += r.passed() ? "PASSED: every well-conditioned ray within its tolerance\n" : "FAILED\n";
    for (const auto& f : r.failures) out += "  " + f + "\n";
    return out;
}

}  // namespace ltm::validation
