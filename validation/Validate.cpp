#include "validation/Validate.h"

#include <cmath>
#include <fmt/format.h>

#include "validation/AnalyticScene.h"
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

ValidationReport validate(const Scene& scene, const Solid& solid, Representation representation, int density) {
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
        std::vector<std::string> names;
        for (int tag : got.tags) names.push_back(solid.surfaces[tag].name);
        auto fail = [&](const std::string& why) {
            if (report.failures.size() < 20)
                report.failures.push_back(fmt::format("{} ray o=({:.17g}, {:.17g}, {:.17g}) d=({:.17g}, {:.17g}, {:.17g}): {}",
                                                      ray.category, ray.origin.x, ray.origin.y, ray.origin.z,
                                                      ray.direction.x, ray.direction.y, ray.direction.z, why));
        };
        if (!tol.stable) {
            ++c.ill_conditioned;
            continue;
        }
        if (names != ref.surfaces || got.display_hit != ref.on_display) {
            ++c.sequence_mismatches;
            fail(fmt::format("surfaces [{}] but the reference has [{}]", seq(names), seq(ref.surfaces)));
            continue;
        }
        ++c.compared;
        double hit_err = 0;
        for (size_t i = 0; i < ref.vertices.size(); ++i) hit_err = std::max(hit_err, distance(got.vertices[i], ref.vertices[i]));
        if (ref.on_display) hit_err = std::max(hit_err, std::hypot(got.x - ref.display_x, got.y - ref.display_y));
        const double dir_err = angle_between(got.direction, ref.direction);
        c.max_hit_error = std::max(c.max_hit_error, hit_err);
        c.max_dir_error = std::max(c.max_dir_error, dir_err);
        const double ratio = std::max(hit_err / tol.position, dir_err / tol.direction);
        c.max_ratio = std::max(c.max_ratio, ratio);
        if (ratio > 1.0) {
            ++c.over_tolerance;
            fail(fmt::format("position error {:.3g} mm (tolerance {:.3g}), direction error {:.3g} rad (tolerance {:.3g})",
                             hit_err, tol.position, dir_err, tol.direction));
        }
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
