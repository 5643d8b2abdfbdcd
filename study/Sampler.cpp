#include "study/Sampler.h"

#include <algorithm>
#include <cmath>
#include <optional>
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

LensSpec draw_object(const DatasetSpec& spec, Rng& rng, std::string& why, io::Json& sampled) {
    LensSpec s = spec.base.object.lens;
    sampled = io::Json::object();
    for (const auto& [key, law] : varied_object_keys(spec)) sampled[key] = law->draw(rng);
    const auto value = [&](const char* key, double base) { return sampled.contains(key) ? sampled[key].get<double>() : base; };
    if (spec.base.object.type == ObjectType::Sphere) {
        s = ball_spec(value("radius", 0.5 * s.diameter), value("ior", s.ior));
    } else {
        s.r1 = value("r1", s.r1);
        s.r2 = value("r2", s.r2);
        s.center_thickness = value(spec.base.object.type == ObjectType::Window ? "thickness" : "center_thickness",
                                   s.center_thickness);
        s.diameter = value("diameter", s.diameter);
        s.ior = value("ior", s.ior);
    }
    if (!(s.ior > 1)) {
        why = fmt::format("ior {} is not above 1", s.ior);
        return s;
    }
    const auto problems = Lens::problems(s);
    why = problems.empty() ? "" : problems.front().key + ": " + problems.front().message;
    return s;
}

// A defect's parameters as drawn (step 4), before it has a place.
struct DrawnDefect {
    Defect defect;        // sizes, face, profile, ...; no position yet
    double length = 0;    // a scratch's (straight: in the xy-projection; arc: along the arc)
    double center_depth = 0;  // a pit's centre below its face, along the inward normal
    int entry = 0;        // in spec.defects
    io::Json sampled = io::Json::object();
};

// One value of `key` from `dist`, truncated to the key's range; InputError at the key when
// max_attempts draws give none in it.
double draw_value(const DatasetSpec& spec, const DefectKindSpec& k, const std::string& key, const Distribution& dist,
                  Rng& rng, long index) {
    for (int a = 0; a < spec.max_attempts; ++a) {
        const double x = dist.draw(rng);
        if (dist.admits(x)) return x;
    }
    infeasible(spec, k.location_of(key),
               fmt::format("{} gave no {} value in {} draws (sample {}): a normal is truncated to its key's range, "
                           "not moved; put its mean in the range",
                           dist.to_string(), dist.range == Distribution::Range::Positive ? "positive" : "non-negative",
                           spec.max_attempts, index));
}

const std::string& draw_word(const std::string& key, const Choice& c, Rng& rng, io::Json& sampled) {
    const std::string& w = c.draw(rng);
    sampled[key] = w;
    return w;
}

// Step 4: the parameters of a defect of entry k. For a scratch: surface, width, depth, profile,
// shape, length and, for an arc, arc_radius; for a bubble, particle or inhomogeneity: radius or
// the three semi_axes, then an inhomogeneity's delta_n and profile, a pit's surface and
// center_depth. The one check on the sizes alone: a scratch arc whose length reaches 2 pi
// arc_radius would close its circle, and exists nowhere.
DrawnDefect draw_parameters(const DatasetSpec& spec, int entry, Rng& rng, long index) {
    const DefectKindSpec& k = spec.defects[static_cast<size_t>(entry)];
    DrawnDefect out;
    out.entry = entry;
    io::Json& sampled = out.sampled;
    const auto value = [&](const char* key, const Distribution& dist) {
        const double x = draw_value(spec, k, key, dist, rng, index);
        sampled[key] = x;
        return x;
    };
    Defect& d = out.defect;
    d.type = k.type;
    if (k.type == DefectType::Scratch) {
        d.side = draw_word("surface", k.surface, rng, sampled) == "front" ? 0 : 1;
        d.width = value("width", k.width);
        d.depth = value("depth", k.depth);
        d.profile = draw_word("profile", k.scratch_profile, rng, sampled) == "V" ? ScratchProfile::V : ScratchProfile::U;
        d.arc = draw_word("shape", k.shape, rng, sampled) == "arc";
        out.length = value("length", k.length);
        if (d.arc) {
            d.arc_radius = value("arc_radius", k.arc_radius);
            const double degrees = out.length / d.arc_radius * (180.0 / kPi);
            if (!(degrees < 360.0))
                infeasible(spec, k.location_of("length"),
                           fmt::format("a scratch arc of length {:.6g} on arc_radius {:.6g} (sample {}) would turn "
                                       "{:.4g} degrees and close on itself: keep length below 2 pi arc_radius",
                                       out.length, d.arc_radius, index, degrees));
        }
        return out;
    }
    if (k.semi_axes) {
        const auto& axes = *k.semi_axes;
        d.semi_axes.x = draw_value(spec, k, "semi_axes", axes[0], rng, index);
        d.semi_axes.y = draw_value(spec, k, "semi_axes", axes[1], rng, index);
        d.semi_axes.z = draw_value(spec, k, "semi_axes", axes[2], rng, index);
        sampled["semi_axes"] = io::Json::array({d.semi_axes.x, d.semi_axes.y, d.semi_axes.z});
    } else {
        const double r = value("radius", *k.radius);
        d.semi_axes = {r, r, r};
    }
    if (k.type == DefectType::Inhomogeneity) {
        d.delta_n = value("delta_n", k.delta_n);
        d.index_profile = draw_word("profile", k.index_profile, rng, sampled) == "smooth" ? IndexProfile::Smooth
                                                                                           : IndexProfile::Uniform;
    }
    if (k.type == DefectType::Bubble && k.surface_breaking) {
        d.surface_breaking = true;
        d.side = draw_word("surface", k.surface, rng, sampled) == "front" ? 0 : 1;
        out.center_depth = value("center_depth", k.center_depth);
    }
    return out;
}

// Step 5, one try: a position (and orientation) for the drawn defect, its parameters untouched.
Defect place(const DrawnDefect& drawn, const DefectKindSpec& k, const Lens& lens, Rng& rng) {
    const Uniform01 u = [&rng] { return rng.uniform(); };
    Defect d = drawn.defect;
    if (k.type == DefectType::Scratch) {
        const FacePoint mid = uniform_point_on_face(lens, d.side, u);
        if (!d.arc) {
            const double phi = 2 * kPi * rng.uniform();
            const double hx = 0.5 * drawn.length * std::cos(phi), hy = 0.5 * drawn.length * std::sin(phi);
            d.start = {mid.point.x - hx, mid.point.y - hy, 0};
            d.end = {mid.point.x + hx, mid.point.y + hy, 0};
        } else {
            d.arc_center = {mid.point.x, mid.point.y, 0};
            d.start_angle = 360.0 * rng.uniform();
            d.end_angle = d.start_angle + drawn.length / d.arc_radius * (180.0 / kPi);
        }
        return d;
    }
    if (d.surface_breaking) {
        const FacePoint f = uniform_point_on_face(lens, d.side, u);
        d.center = f.point + f.inward * drawn.center_depth;
    } else {
        d.center = uniform_point_in_glass(lens, u);
    }
    if (k.semi_axes) d.set_rotation_deg(uniform_rotation_euler_deg(u));
    return d;
}

// Why a placed defect cannot go into the scene (its key and message), or nothing.
std::optional<DefectProblem> placement_problem(const Lens& lens, const Scene& scene, const Defect& d) {
    auto problems = defect_problems(lens, d, scene.object.index_field);
    if (!problems.empty()) return problems.front();
    for (size_t j = 0; j < scene.defects.size(); ++j) {
        const Defect& o = scene.defects[j];
        problems = defect_pair_problems(lens, d, o, static_cast<int>(j));
        if (!problems.empty()) return problems.front();
        // Enclosed defects keep apart (bounding spheres): no Boolean is needed for them.
        if (d.is_ellipsoid() && o.is_ellipsoid() && distance(d.center, o.center) <= d.max_semi_axis() + o.max_semi_axis())
            return DefectProblem{"center", fmt::format("it would touch defect {}", j)};
    }
    return std::nullopt;
}

// Up to max_attempts tries of a position for `drawn` in `scene`: the first that fits, or the last
// try's problem.
std::optional<DefectProblem> try_positions(const DatasetSpec& spec, const DrawnDefect& drawn, const Lens& lens,
                                           const Scene& scene, Rng& rng, Defect& placed) {
    std::optional<DefectProblem> why;
    for (int a = 0; a < spec.max_attempts; ++a) {
        placed = place(drawn, spec.defects[static_cast<size_t>(drawn.entry)], lens, rng);
        why = placement_problem(lens, scene, placed);
        if (!why) break;
    }
    return why;
}

// "radius 0.2", "semi_axes [0.3, 0.2, 0.1], delta_n 0.001, profile smooth": what a defect drew.
std::string describe(const io::Json& sampled) {
    std::string s;
    for (const auto& [key, v] : sampled.items()) {
        s += s.empty() ? "" : ", ";
        if (v.is_string()) s += key + " " + v.get<std::string>();
        else if (v.is_array())
            s += fmt::format("{} [{:.6g}, {:.6g}, {:.6g}]", key, v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
        else s += fmt::format("{} {:.6g}", key, v.get<double>());
    }
    return s;
}

// The spec key that decides whether a defect fits, for a placement problem's key: delta_n and a
// graded object's refusal (type) are their own; a pit that does not reach its face (the problem
// "surface_breaking") is placed by its center_depth; a scratch's depth and width decide
// themselves, and any other problem of a scratch (it runs off its face) its length; an
// ellipsoid's its size.
std::string deciding_key(const DefectKindSpec& k, const std::string& problem_key) {
    if (problem_key == "type" || problem_key == "delta_n") return problem_key;
    if (problem_key == "surface_breaking") return "center_depth";
    if (k.type == DefectType::Scratch) return problem_key == "depth" || problem_key == "width" ? problem_key : "length";
    return k.semi_axes ? "semi_axes" : "radius";
}

}  // namespace

std::vector<std::pair<std::string, const Distribution*>> varied_object_keys(const DatasetSpec& spec) {
    const ObjectVariation& v = spec.object;
    std::vector<std::pair<std::string, const Distribution*>> out;
    const auto add = [&](const char* key, const std::optional<Distribution>& d) {
        if (d) out.emplace_back(key, &*d);
    };
    if (spec.base.object.type == ObjectType::Sphere) {
        add("radius", v.radius);
    } else {
        add("r1", v.r1);
        add("r2", v.r2);
        add(spec.base.object.type == ObjectType::Window ? "thickness" : "center_thickness", v.center_thickness);
        add("diameter", v.diameter);
    }
    add("ior", v.ior);
    return out;
}

std::vector<SampledKey> sampled_keys(const DefectKindSpec& k) {
    std::vector<SampledKey> out;
    const auto number = [&](const std::string& key, const Distribution& d) { out.push_back({key, &d, nullptr}); };
    const auto word = [&](const std::string& key, const Choice& c) { out.push_back({key, nullptr, &c}); };
    if (k.type == DefectType::Scratch) {
        word("surface", k.surface);
        number("width", k.width);
        number("depth", k.depth);
        word("profile", k.scratch_profile);
        word("shape", k.shape);
        number("length", k.length);
        if (std::find(k.shape.options.begin(), k.shape.options.end(), "arc") != k.shape.options.end())
            number("arc_radius", k.arc_radius);
        return out;
    }
    if (k.semi_axes)
        for (int i = 0; i < 3; ++i) number(fmt::format("semi_axes[{}]", i), (*k.semi_axes)[static_cast<size_t>(i)]);
    else number("radius", *k.radius);
    if (k.type == DefectType::Inhomogeneity) {
        number("delta_n", k.delta_n);
        word("profile", k.index_profile);
    }
    if (k.type == DefectType::Bubble && k.surface_breaking) {
        word("surface", k.surface);
        number("center_depth", k.center_depth);
    }
    return out;
}

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
    // Every sample is measured against the golden reference of the spec's seed (the base scene's
    // reference_seed if it gives one): one reference for all samples of one object.
    if (!scene.reference_seed) scene.reference_seed = spec.seed;
    // 2. The object.
    if (spec.object.any()) {
        Rng rng(s.seed, kSamplingStream + 2);
        std::string why = "?";
        LensSpec object;
        for (int a = 0; a < spec.max_attempts && !why.empty(); ++a) object = draw_object(spec, rng, why, s.object_sampled);
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
    // 4. The parameters of every defect, from a stream of their own.
    Rng parameters(s.seed, kParameterStream);
    std::vector<DrawnDefect> drawn;
    for (size_t k = 0; k < spec.defects.size(); ++k)
        for (int j = 0; j < counts[k]; ++j) drawn.push_back(draw_parameters(spec, static_cast<int>(k), parameters, index));
    // 5. Their positions: defect by defect, all again when one finds no room among the others.
    Rng positions(s.seed, kPlacementStream);
    std::vector<bool> fits_alone(drawn.size(), false);
    for (int round = 0; !drawn.empty(); ++round) {
        scene.defects.clear();
        size_t failed = drawn.size();
        std::optional<DefectProblem> why;
        for (size_t j = 0; j < drawn.size() && failed == drawn.size(); ++j) {
            Defect d;
            why = try_positions(spec, drawn[j], lens, scene, positions, d);
            if (why) failed = j;
            else scene.defects.push_back(d);
        }
        s.placement_rounds = round + 1;
        if (failed == drawn.size()) break;
        const DrawnDefect& f = drawn[failed];
        const DefectKindSpec& k = spec.defects[static_cast<size_t>(f.entry)];
        if (!fits_alone[failed] && failed > 0) {
            Scene empty = scene;
            empty.defects.clear();
            Defect d;
            const auto alone = try_positions(spec, f, lens, empty, positions, d);
            fits_alone[failed] = !alone;
            if (alone) why = alone;
        }
        if (!fits_alone[failed]) {
            const std::string key = deciding_key(k, why->key);
            if (key == "type")
                infeasible(spec, k.location_of(key),
                           fmt::format("cannot place a {} in this object (sample {}): {}", to_string(k.type), index, why->message));
            infeasible(spec, k.location_of(key),
                       fmt::format("a {} with {} (sample {}) fits nowhere in the object: none of {} positions holds "
                                   "it (the last: {}: {}). Sizes are drawn as the spec gives them and never redrawn "
                                   "to fit: narrow the range, or raise max_attempts if such a {} has room in a small "
                                   "part of the object only",
                                   to_string(k.type), describe(f.sampled), index, spec.max_attempts, why->key,
                                   why->message, to_string(k.type)));
        }
        if (round + 1 == kPlacementRounds) {
            std::string all;
            for (const DrawnDefect& x : drawn)
                all += fmt::format("{}{} ({})", all.empty() ? "" : "; ", to_string(x.defect.type), describe(x.sampled));
            infeasible(spec, k.where,
                       fmt::format("sample {}: its {} defects do not fit together: {} rounds of placing all of them, "
                                   "{} positions per defect, found no room for the {} with {} among the ones placed "
                                   "before it (the last: {}: {}). The sizes, kept in every round: {}. Lower the "
                                   "counts or the sizes, or use a larger object",
                                   index, drawn.size(), kPlacementRounds, spec.max_attempts, to_string(k.type),
                                   describe(f.sampled), why->key, why->message, all));
        }
    }
    for (const DrawnDefect& x : drawn) {
        s.kinds.push_back(x.entry);
        s.sampled.push_back(x.sampled);
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
