#include "study/Sampler.h"

#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

#include "defects/DefectSolid.h"
#include "defects/Sampling.h"
#include "geometry/Lens.h"
#include "io/InputError.h"
#include "scene/SceneLoader.h"
#include "scene/SceneYaml.h"
#include "trace/Rng.h"

namespace ltm {

namespace {

[[noreturn]] void infeasible(const DatasetSpec& spec, const SpecLocation& at, const std::string& message) {
    throw InputError(spec.file, at.line, at.column, at.key_path, message);
}

LensSpec draw_object(const DatasetSpec& spec, Rng& rng, std::string& why) {
    LensSpec s = spec.base.object.lens;
    const ObjectVariation& v = spec.object;
    if (spec.base.object.type == ObjectType::Sphere) {
        const double R = v.radius ? v.radius->draw(rng) : 0.5 * s.diameter;
        const double n = v.ior ? v.ior->draw(rng) : s.ior;
        s = ball_spec(R, n);
    } else {
        if (v.r1) s.r1 = v.r1->draw(rng);
        if (v.r2) s.r2 = v.r2->draw(rng);
        if (v.center_thickness) s.center_thickness = v.center_thickness->draw(rng);
        if (v.diameter) s.diameter = v.diameter->draw(rng);
        if (v.ior) s.ior = v.ior->draw(rng);
    }
    if (!(s.ior > 1)) {
        why = fmt::format("ior {} is not above 1", s.ior);
        return s;
    }
    const auto problems = Lens::problems(s);
    why = problems.empty() ? "" : problems.front().key + ": " + problems.front().message;
    return s;
}

// One draw of a defect of kind k (its parameters and position), unchecked.
Defect draw_defect(const DefectKindSpec& k, const Lens& lens, Rng& rng) {
    const Uniform01 u = [&rng] { return rng.uniform(); };
    Defect d;
    d.type = k.type;
    if (k.type == DefectType::Scratch) {
        d.side = k.surface.draw(rng) == "front" ? 0 : 1;
        d.width = k.width.draw(rng);
        d.depth = k.depth.draw(rng);
        d.profile = k.scratch_profile.draw(rng) == "V" ? ScratchProfile::V : ScratchProfile::U;
        const bool arc = k.shape.draw(rng) == "arc";
        const double length = k.length.draw(rng);
        const FacePoint mid = uniform_point_on_face(lens, d.side, u);
        if (!arc) {
            const double phi = 2 * kPi * rng.uniform();
            const double hx = 0.5 * length * std::cos(phi), hy = 0.5 * length * std::sin(phi);
            d.arc = false;
            d.start = {mid.point.x - hx, mid.point.y - hy, 0};
            d.end = {mid.point.x + hx, mid.point.y + hy, 0};
        } else {
            d.arc = true;
            d.arc_center = {mid.point.x, mid.point.y, 0};
            d.arc_radius = k.arc_radius.draw(rng);
            d.start_angle = 360.0 * rng.uniform();
            d.end_angle = d.start_angle + length / d.arc_radius * (180.0 / kPi);  // >= 360: rejected by the caller
        }
        return d;
    }
    if (k.semi_axes) {
        d.semi_axes = {(*k.semi_axes)[0].draw(rng), (*k.semi_axes)[1].draw(rng), (*k.semi_axes)[2].draw(rng)};
    } else {
        const double r = k.radius->draw(rng);
        d.semi_axes = {r, r, r};
    }
    if (k.type == DefectType::Inhomogeneity) {
        d.delta_n = k.delta_n.draw(rng);
        d.index_profile = k.index_profile.draw(rng) == "smooth" ? IndexProfile::Smooth : IndexProfile::Uniform;
    }
    if (k.type == DefectType::Bubble && k.surface_breaking) {
        d.surface_breaking = true;
        const int side = k.surface.draw(rng) == "front" ? 0 : 1;
        const FacePoint f = uniform_point_on_face(lens, side, u);
        d.center = f.point + f.inward * k.center_depth.draw(rng);
    } else {
        d.center = uniform_point_in_glass(lens, u);
    }
    if (k.semi_axes) d.set_rotation_deg(uniform_rotation_euler_deg(u));
    return d;
}

// Why a drawn defect cannot go into the scene, or "".
std::string placement_problem(const Lens& lens, const Scene& scene, const Defect& d) {
    for (double x : {d.semi_axes.x, d.semi_axes.y, d.semi_axes.z, d.width, d.depth, d.delta_n})
        if (!std::isfinite(x)) return "a parameter is not finite";
    if (d.is_ellipsoid() && !(d.semi_axes.x > 0 && d.semi_axes.y > 0 && d.semi_axes.z > 0))
        return fmt::format("semi-axes [{}, {}, {}] are not all positive", d.semi_axes.x, d.semi_axes.y, d.semi_axes.z);
    if (d.type == DefectType::Inhomogeneity && d.delta_n == 0) return "delta_n is 0";
    if (d.type == DefectType::Scratch && d.arc && !(d.end_angle - d.start_angle < 360.0))
        return fmt::format("an arc of {:.4g} degrees (length over arc_radius) closes on itself", d.end_angle - d.start_angle);
    auto problems = defect_problems(lens, d, scene.object.index_field);
    if (!problems.empty()) return problems.front().key + ": " + problems.front().message;
    for (size_t j = 0; j < scene.defects.size(); ++j) {
        const Defect& o = scene.defects[j];
        problems = defect_pair_problems(lens, d, o, static_cast<int>(j));
        if (!problems.empty()) return problems.front().key + ": " + problems.front().message;
        // Enclosed defects keep apart (bounding spheres): no Boolean is needed for them.
        if (d.is_ellipsoid() && o.is_ellipsoid() && distance(d.center, o.center) <= d.max_semi_axis() + o.max_semi_axis())
            return fmt::format("it would touch defect {}", j);
    }
    return "";
}

}  // namespace

std::string sample_name(long index) { return fmt::format("{:06d}", index); }

SampleDraw draw_sample(const DatasetSpec& spec, long index) {
    SampleDraw s;
    s.index = index;
    s.seed = mix_seed(spec.seed, static_cast<std::uint64_t>(index));
    // 1. Defect-free or not, and the split: one stream each, one variate each.
    Rng choose(s.seed, kSamplingStream);
    s.defect_free = choose.uniform() < spec.defect_free_fraction;
    Rng split_rng(s.seed, kSamplingStream + 1);
    const double us = split_rng.uniform();
    double cumulative = 0;
    s.split = spec.splits.back().name;
    for (const auto& sp : spec.splits) {
        cumulative += sp.fraction;
        if (us < cumulative) {
            s.split = sp.name;
            break;
        }
    }

    Scene scene = spec.base;
    scene.defects.clear();
    scene.seed = s.seed;
    // 2. The object.
    if (spec.object.any()) {
        Rng rng(s.seed, kSamplingStream + 2);
        std::string why = "?";
        LensSpec object;
        for (int a = 0; a < spec.max_attempts && !why.empty(); ++a) object = draw_object(spec, rng, why);
        if (!why.empty())
            infeasible(spec, spec.object.where,
                       fmt::format("no valid object after {} draws (sample {}): {}", spec.max_attempts, index, why));
        scene.object.lens = object;
        scene.object.index_field.ior = object.ior;
    }
    const Lens lens(scene.object.lens);
    // 3. The counts.
    Rng rng(s.seed, kSamplingStream + 3);
    std::vector<int> counts(spec.defects.size(), 0);
    if (!s.defect_free) {
        bool ok = false;
        for (int a = 0; a < spec.max_attempts && !ok; ++a) {
            int total = 0;
            for (size_t k = 0; k < spec.defects.size(); ++k) total += counts[k] = spec.defects[k].count.draw(rng);
            ok = total >= 1 && total <= kMaxDefectsPerSample;
        }
        if (!ok)
            infeasible(spec, spec.defects_where,
                       fmt::format("the counts give no sample with 1 to {} defects after {} draws (sample {})",
                                   kMaxDefectsPerSample, spec.max_attempts, index));
    }
    // 4. The defects.
    for (size_t k = 0; k < spec.defects.size(); ++k)
        for (int j = 0; j < counts[k]; ++j) {
            std::string why = "?";
            Defect d;
            for (int a = 0; a < spec.max_attempts && !why.empty(); ++a) {
                d = draw_defect(spec.defects[k], lens, rng);
                why = placement_problem(lens, scene, d);
            }
            if (!why.empty())
                infeasible(spec, spec.defects[k].where,
                           fmt::format("cannot place a {} in the object after {} draws (sample {}; the last draw: {})",
                                       to_string(spec.defects[k].type), spec.max_attempts, index, why));
            scene.defects.push_back(d);
            s.kinds.push_back(static_cast<int>(k));
        }
    // The scene as its file says it, read back by the strict loader.
    const std::string source = "samples/" + sample_name(index) + "/scene.yaml";
    s.scene_yaml = scene_to_yaml(scene);
    try {
        s.scene = parse_scene(s.scene_yaml, source);
    } catch (const InputError& e) {
        throw std::logic_error(fmt::format("sample {}: the written scene does not load back: {}", index, e.what()));
    }
    return s;
}

}  // namespace ltm
