#include "study/DatasetSpec.h"

#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <set>

#include "scene/SceneLoader.h"
#include "scene/SceneYaml.h"
#include "scene/StrictYaml.h"

namespace ltm {

namespace {

namespace fs = std::filesystem;
using yaml::Item;
using yaml::KeyRule;
using yaml::Loc;

// What a real parameter may take: any value, a positive one (a length), or a non-negative one.
using Range = Distribution::Range;

class SpecParser {
public:
    explicit SpecParser(std::string file) : r_(file), file_(std::move(file)) {}
    DatasetSpec run(const YAML::Node& root);

private:
    SpecLocation where(Loc at, const std::string& path) const { return {at.line, at.column, path}; }
    Distribution distribution(const YAML::Node& v, Loc at, const std::string& path, Range range) const;
    CountDistribution count(const YAML::Node& v, Loc at, const std::string& path) const;
    Choice choice(const YAML::Node& v, Loc at, const std::string& path, const std::vector<std::string>& options) const;
    DefectKindSpec defect_kind(const YAML::Node& node, const std::string& path) const;
    void object_variation(const Item& it, const Scene& base, ObjectVariation& o) const;
    void splits(const Item& it, std::vector<DatasetSplit>& out) const;
    Scene base_scene(const Item& it, std::string& source) const;

    yaml::Reader r_;
    std::string file_;
};

const std::vector<std::string> kDistributions{"uniform", "log_uniform", "normal"};

Distribution SpecParser::distribution(const YAML::Node& v, Loc at, const std::string& path, Range range) const {
    auto check_value = [&](double x, Loc l, const std::string& p) {
        if (range == Range::Positive && !(x > 0)) r_.fail(l, p, fmt::format("must be positive, got {}", x));
        if (range == Range::NonNegative && !(x >= 0)) r_.fail(l, p, fmt::format("must be >= 0, got {}", x));
    };
    if (v.IsScalar()) {
        const double x = r_.number(v, at, path);
        check_value(x, at, path);
        Distribution d = Distribution::constant(x);
        d.range = range;
        return d;
    }
    if (!v.IsMap() || v.size() != 1)
        r_.fail(at, path,
                fmt::format("expected a number or one distribution {{uniform: [a, b]}}, {{log_uniform: [a, b]}} or "
                            "{{normal: [mean, sd]}}, got {}",
                            yaml::describe(v)));
    const Item e = yaml::items_of(v).front();
    const std::string p = yaml::join_path(path, e.key);
    auto known = std::find(kDistributions.begin(), kDistributions.end(), e.key);
    if (known == kDistributions.end()) {
        std::string msg = fmt::format("unknown distribution '{}'", e.key);
        if (auto s = yaml::nearest(e.key, kDistributions)) msg += fmt::format(" (did you mean '{}'?)", *s);
        else msg += "; the distributions are: " + yaml::join_keys(kDistributions);
        r_.fail(e.key_loc(), p, msg);
    }
    const auto xs = r_.number_list(e.value, e.value_loc(), p, {2}, e.key == "normal" ? "numbers [mean, sd]" : "numbers [a, b]",
                                   [&](const YAML::Node& x, Loc l, const std::string& q) { return r_.number(x, l, q); });
    Distribution d;
    d.a = xs[0];
    d.b = xs[1];
    d.range = range;
    if (e.key == "normal") {
        d.kind = Distribution::Kind::Normal;
        if (!(d.b > 0)) r_.fail(e.value_loc(), p + "[1]", fmt::format("the standard deviation must be positive, got {}", d.b));
        return d;
    }
    d.kind = e.key == "uniform" ? Distribution::Kind::Uniform : Distribution::Kind::LogUniform;
    if (!(d.b >= d.a))
        r_.fail(e.value_loc(), p, fmt::format("the range [{}, {}] is empty: its end must not be below its start", d.a, d.b));
    if (d.kind == Distribution::Kind::LogUniform && !(d.a > 0))
        r_.fail(e.value_loc(), p, fmt::format("a log-uniform range must be positive, got [{}, {}]", d.a, d.b));
    if (range == Range::Positive && !(d.a > 0))
        r_.fail(e.value_loc(), p, fmt::format("the range [{}, {}] holds values <= 0; this parameter must be positive", d.a, d.b));
    if (range == Range::NonNegative && !(d.a >= 0))
        r_.fail(e.value_loc(), p, fmt::format("the range [{}, {}] holds negative values; this parameter must be >= 0", d.a, d.b));
    return d;
}

CountDistribution SpecParser::count(const YAML::Node& v, Loc at, const std::string& path) const {
    CountDistribution c;
    const auto cap = static_cast<long long>(kMaxDefectsPerSample);
    if (v.IsScalar()) {
        c.a = c.b = static_cast<int>(r_.integer(v, at, path, 0, cap, "a count from 0 to 64"));
        return c;
    }
    if (!v.IsMap() || v.size() != 1)
        r_.fail(at, path,
                fmt::format("expected an integer, {{poisson: mean}} or {{uniform_int: [a, b]}}, got {}", yaml::describe(v)));
    const Item e = yaml::items_of(v).front();
    const std::string p = yaml::join_path(path, e.key);
    if (e.key == "poisson") {
        c.kind = CountDistribution::Kind::Poisson;
        c.mean = r_.number(e.value, e.value_loc(), p);
        if (!(c.mean > 0 && c.mean <= kMaxPoissonMean))
            r_.fail(e.value_loc(), p, fmt::format("the mean must be in (0, {:g}] (the cap on a Poisson count), got {}",
                                                  kMaxPoissonMean, c.mean));
    } else if (e.key == "uniform_int") {
        c.kind = CountDistribution::Kind::UniformInt;
        const auto xs = r_.number_list(e.value, e.value_loc(), p, {2}, "integers [a, b]",
                                       [&](const YAML::Node& x, Loc l, const std::string& q) {
                                           return static_cast<double>(r_.integer(x, l, q, 0, cap, "a count from 0 to 64"));
                                       });
        c.a = static_cast<int>(xs[0]);
        c.b = static_cast<int>(xs[1]);
        if (c.b < c.a) r_.fail(e.value_loc(), p, fmt::format("the range [{}, {}] is empty: its end must not be below its start", c.a, c.b));
    } else {
        const std::vector<std::string> kinds{"poisson", "uniform_int"};
        std::string msg = fmt::format("unknown count distribution '{}'", e.key);
        if (auto s = yaml::nearest(e.key, kinds)) msg += fmt::format(" (did you mean '{}'?)", *s);
        else msg += "; a count is an integer, {poisson: mean} or {uniform_int: [a, b]}";
        r_.fail(e.key_loc(), p, msg);
    }
    return c;
}

Choice SpecParser::choice(const YAML::Node& v, Loc at, const std::string& path, const std::vector<std::string>& options) const {
    Choice c;
    if (v.IsScalar()) {
        c.options.push_back(options[r_.choice(v, at, path, options)]);
        return c;
    }
    if (!v.IsMap() || v.size() != 1 || yaml::items_of(v).front().key != "choice")
        r_.fail(at, path, fmt::format("expected {} or {{choice: [...]}} of them, got {}", yaml::list_words(options, " or "),
                                      yaml::describe(v)));
    const Item e = yaml::items_of(v).front();
    const std::string p = yaml::join_path(path, "choice");
    if (!e.value.IsSequence() || e.value.size() == 0)
        r_.fail(e.value_loc(), p, fmt::format("expected a non-empty list of {}, got {}", yaml::list_words(options, " or "),
                                              yaml::describe(e.value)));
    for (std::size_t i = 0; i < e.value.size(); ++i) {
        const YAML::Node x = e.value[i];
        const std::string q = fmt::format("{}[{}]", p, i);
        const std::string& word = options[r_.choice(x, yaml::loc_of(x), q, options)];
        if (std::find(c.options.begin(), c.options.end(), word) != c.options.end())
            r_.fail(yaml::loc_of(x), q, fmt::format("'{}' is listed twice", word));
        c.options.push_back(word);
    }
    return c;
}

const std::vector<std::string> kBubbleKeys{"type", "count", "radius", "semi_axes", "surface_breaking", "surface", "center_depth"};
const std::vector<std::string> kParticleKeys{"type", "count", "radius", "semi_axes"};
const std::vector<std::string> kInhomogeneityKeys{"type", "count", "radius", "semi_axes", "delta_n", "profile"};
const std::vector<std::string> kScratchKeys{"type", "count", "surface", "shape", "width", "depth", "length", "arc_radius", "profile"};

DefectKindSpec SpecParser::defect_kind(const YAML::Node& node, const std::string& path) const {
    if (!node.IsMap())
        r_.fail(yaml::loc_of(node), path,
                fmt::format("expected a mapping with a 'type' key (bubble, scratch, particle or inhomogeneity), got {}",
                            yaml::describe(node)));
    const auto items = yaml::items_of(node);
    const Item* type_item = yaml::find_item(items, "type");
    if (!type_item) r_.fail(yaml::loc_of(node), yaml::join_path(path, "type"), "missing required key 'type'");
    DefectKindSpec k;
    k.where = where(yaml::loc_of(node), path);
    const std::size_t t = r_.choice(type_item->value, type_item->value_loc(), yaml::join_path(path, "type"),
                                    {"bubble", "scratch", "particle", "inhomogeneity"});
    const DefectType types[] = {DefectType::Bubble, DefectType::Scratch, DefectType::Particle, DefectType::Inhomogeneity};
    k.type = types[t];
    KeyRule rule;
    rule.keys = t == 0 ? kBubbleKeys : t == 1 ? kScratchKeys : t == 2 ? kParticleKeys : kInhomogeneityKeys;
    rule.context = fmt::format(" for a {} kind", to_string(k.type));
    // Documented defaults (docs/dataset.md, "Defect kinds").
    using Kind = Distribution::Kind;
    if (k.type == DefectType::Inhomogeneity) k.radius = Distribution{Kind::Uniform, 0.5, 2.0, Range::Positive};
    else k.radius = Distribution{Kind::LogUniform, 0.05, 0.5, Range::Positive};
    k.count = CountDistribution{};
    k.count.a = k.count.b = 1;
    k.surface = Choice{{"front", "back"}};
    if (k.type == DefectType::Scratch) {
        k.width = {Kind::LogUniform, 0.01, 0.1, Range::Positive};
        k.depth = {Kind::LogUniform, 0.005, 0.05, Range::Positive};
        k.length = {Kind::Uniform, 1.0, 10.0, Range::Positive};
        k.arc_radius = {Kind::Uniform, 2.0, 10.0, Range::Positive};
        k.scratch_profile = Choice{{"V", "U"}};
    }
    if (k.type == DefectType::Inhomogeneity) k.delta_n = {Kind::Uniform, 0.0005, 0.002};
    yaml::Where seen;
    Loc surface_loc;
    r_.walk(node, path, rule, [&](const Item& e) {
        const std::string p = yaml::join_path(path, e.key);
        const Loc at = e.value_loc();
        seen[e.key] = at;
        k.keys[e.key] = where(at, p);
        if (e.key == "type") return;
        if (e.key == "count") k.count = count(e.value, at, p);
        else if (e.key == "radius") {
            if (seen.count("semi_axes")) r_.fail(e.key_loc(), p, "give either radius (spheres) or semi_axes (ellipsoids), not both");
            k.radius = distribution(e.value, at, p, Range::Positive);
        } else if (e.key == "semi_axes") {
            if (seen.count("radius")) r_.fail(e.key_loc(), p, "give either radius (spheres) or semi_axes (ellipsoids), not both");
            if (!e.value.IsSequence() || e.value.size() != 3)
                r_.fail(at, p, fmt::format("expected a list of 3 numbers or distributions, got {}", yaml::describe(e.value)));
            std::array<Distribution, 3> axes;
            for (std::size_t i = 0; i < 3; ++i) {
                const YAML::Node x = e.value[i];
                axes[i] = distribution(x, x.IsNull() ? at : yaml::loc_of(x), fmt::format("{}[{}]", p, i), Range::Positive);
            }
            k.semi_axes = axes;
            k.radius.reset();
        } else if (e.key == "surface_breaking") k.surface_breaking = r_.boolean(e.value, at, p);
        else if (e.key == "surface") {
            k.surface = choice(e.value, at, p, {"front", "back"});
            surface_loc = e.key_loc();
        } else if (e.key == "center_depth") k.center_depth = distribution(e.value, at, p, Range::Any);
        else if (e.key == "delta_n") k.delta_n = distribution(e.value, at, p, Range::Any);
        else if (e.key == "profile") {
            if (k.type == DefectType::Scratch) k.scratch_profile = choice(e.value, at, p, {"V", "U"});
            else k.index_profile = choice(e.value, at, p, {"smooth", "uniform"});
        } else if (e.key == "shape") k.shape = choice(e.value, at, p, {"straight", "arc"});
        else if (e.key == "width") k.width = distribution(e.value, at, p, Range::Positive);
        else if (e.key == "depth") k.depth = distribution(e.value, at, p, Range::Positive);
        else if (e.key == "length") k.length = distribution(e.value, at, p, Range::Positive);
        else if (e.key == "arc_radius") k.arc_radius = distribution(e.value, at, p, Range::Positive);
    });
    if (k.type == DefectType::Bubble && !k.surface_breaking && (seen.count("surface") || seen.count("center_depth"))) {
        const std::string key = seen.count("surface") ? "surface" : "center_depth";
        r_.fail(seen.at(key), yaml::join_path(path, key),
                fmt::format("{} applies to surface-breaking bubbles (pits) only: add surface_breaking: true", key));
    }
    if (k.type == DefectType::Inhomogeneity && k.delta_n.kind == Distribution::Kind::Constant && k.delta_n.a == 0)
        r_.fail(seen.at("delta_n"), yaml::join_path(path, "delta_n"),
                "must be non-zero: delta_n = 0 leaves the glass unchanged");
    return k;
}

void SpecParser::object_variation(const Item& it, const Scene& base, ObjectVariation& o) const {
    const std::string path = "object";
    r_.require_map(it, path);
    o.where = where(it.value_loc(), path);
    KeyRule rule;
    switch (base.object.type) {
        case ObjectType::Lens: rule.keys = {"r1", "r2", "center_thickness", "diameter", "ior"}; break;
        case ObjectType::Window: rule.keys = {"thickness", "diameter", "ior"}; break;
        case ObjectType::Sphere: rule.keys = {"radius", "ior"}; break;
    }
    rule.context = fmt::format(" for the base scene's {}", base.object.type == ObjectType::Lens     ? "lens"
                                                           : base.object.type == ObjectType::Window ? "window"
                                                                                                    : "sphere");
    r_.walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = yaml::join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "r1") o.r1 = distribution(e.value, at, p, Range::Any);
        else if (e.key == "r2") o.r2 = distribution(e.value, at, p, Range::Any);
        else if (e.key == "center_thickness" || e.key == "thickness") o.center_thickness = distribution(e.value, at, p, Range::Positive);
        else if (e.key == "diameter") o.diameter = distribution(e.value, at, p, Range::Positive);
        else if (e.key == "radius") o.radius = distribution(e.value, at, p, Range::Positive);
        else if (e.key == "ior") o.ior = distribution(e.value, at, p, Range::Positive);
    });
}

void SpecParser::splits(const Item& it, std::vector<DatasetSplit>& out) const {
    const std::string path = "splits";
    r_.require_map(it, path);
    out.clear();
    std::set<std::string> names;
    double total = 0;
    for (const Item& e : yaml::items_of(it.value)) {
        const std::string p = yaml::join_path(path, e.key);
        const bool ok_name = !e.key.empty() && std::all_of(e.key.begin(), e.key.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
        });
        if (!e.key_node.IsScalar() || !ok_name)
            r_.fail(e.key_loc(), path, fmt::format("a split's name is letters, digits, '_' and '-', got {}", yaml::describe(e.key_node)));
        if (!names.insert(e.key).second) r_.fail(e.key_loc(), p, fmt::format("duplicate split '{}'", e.key));
        const double f = r_.number(e.value, e.value_loc(), p);
        if (!(f > 0 && f <= 1)) r_.fail(e.value_loc(), p, fmt::format("a split's share must be in (0, 1], got {}", f));
        out.push_back({e.key, f});
        total += f;
    }
    if (out.empty()) r_.fail(it.value_loc(), path, "expected at least one split, e.g. {train: 0.8, val: 0.1, test: 0.1}");
    if (std::fabs(total - 1.0) > 1e-9)
        r_.fail(it.value_loc(), path, fmt::format("the shares add up to {}, not 1", total));
}

Scene SpecParser::base_scene(const Item& it, std::string& source) const {
    if (it.value.IsMap()) {
        source = file_ + " (inline)";
        return parse_scene_node(it.value, file_, "scene");
    }
    if (!it.value.IsScalar() || it.value.Scalar().empty())
        r_.fail(it.value_loc(), "scene", fmt::format("expected the path of a scene file or a scene mapping, got {}",
                                                     yaml::describe(it.value)));
    fs::path p(it.value.Scalar());
    if (p.is_relative()) p = fs::path(file_).parent_path() / p;
    source = p.lexically_normal().string();
    return load_scene(source);  // its own located errors
}

DatasetSpec SpecParser::run(const YAML::Node& root) {
    DatasetSpec spec;
    spec.file = file_;
    if (!root.IsDefined() || root.IsNull())
        r_.fail({1, 1}, "", "the dataset spec is empty: expected a mapping with at least 'scene' and 'samples'");
    if (!root.IsMap()) r_.fail(yaml::loc_of(root), "", fmt::format("expected a mapping of spec keys, got {}", yaml::describe(root)));
    KeyRule rule;
    rule.keys = {"scene", "samples", "seed", "defect_free_fraction", "defects", "object", "ground_truth",
                 "splits", "outputs", "max_attempts"};
    yaml::Where seen;
    std::optional<Item> object_item;  // parsed once the base scene is known (keys in any order)
    r_.walk(root, "", rule, [&](const Item& e) {
        const Loc at = e.value_loc();
        seen[e.key] = at;
        if (e.key == "scene") spec.base = base_scene(e, spec.base_source);
        else if (e.key == "samples") spec.samples = static_cast<long>(r_.integer(e.value, at, "samples", 1, kMaxSamples, "a positive integer"));
        else if (e.key == "seed") spec.seed = r_.seed(e.value, at, "seed");
        else if (e.key == "defect_free_fraction") {
            spec.defect_free_fraction = r_.number(e.value, at, e.key);
            if (!(spec.defect_free_fraction >= 0 && spec.defect_free_fraction <= 1))
                r_.fail(at, e.key, fmt::format("must be in [0, 1], got {}", spec.defect_free_fraction));
        } else if (e.key == "defects") {
            spec.defects_where = where(at, "defects");
            if (e.value.IsNull()) return;
            if (!e.value.IsSequence()) r_.fail(at, "defects", fmt::format("expected a list of defect kinds, got {}", yaml::describe(e.value)));
            for (std::size_t i = 0; i < e.value.size(); ++i)
                spec.defects.push_back(defect_kind(e.value[i], fmt::format("defects[{}]", i)));
        } else if (e.key == "object") {
            object_item = e;
        } else if (e.key == "ground_truth") {
            r_.require_map(e, e.key);
            KeyRule g;
            g.keys = {"min_fraction"};
            r_.walk(e.value, e.key, g, [&](const Item& x) {
                spec.mask_fraction = r_.number(x.value, x.value_loc(), "ground_truth.min_fraction");
                if (!(spec.mask_fraction > 0 && spec.mask_fraction <= 1))
                    r_.fail(x.value_loc(), "ground_truth.min_fraction", fmt::format("must be in (0, 1], got {}", spec.mask_fraction));
            });
        } else if (e.key == "splits") splits(e, spec.splits);
        else if (e.key == "outputs") {
            r_.require_map(e, e.key);
            KeyRule o;
            o.keys = {"ltm", "previews"};
            r_.walk(e.value, e.key, o, [&](const Item& x) {
                const bool b = r_.boolean(x.value, x.value_loc(), "outputs." + x.key);
                (x.key == "ltm" ? spec.keep_ltm : spec.previews) = b;
            });
        } else if (e.key == "max_attempts") {
            spec.max_attempts = static_cast<int>(r_.integer(e.value, at, e.key, 1, 1000000, "a positive integer (at most 1000000)"));
        }
    });
    r_.require_keys(root, "", seen, {"scene", "samples"});
    if (object_item) object_variation(*object_item, spec.base, spec.object);
    if (spec.defects.empty() && spec.defect_free_fraction < 1)
        r_.fail(yaml::loc_of(root), "defects",
                "missing: without defect kinds every sample is defect-free; list defects or set defect_free_fraction: 1");
    spec.base.defects.clear();

    // The canonical text: everything that decides the samples' bytes, defaults written out; the
    // sample count is left out so that a dataset can grow (`samples` raised, then --resume).
    std::string c = "# ltmsim dataset spec, canonical\n";
    // How samples are drawn from the spec (study/Sampler.h) is part of what decides their bytes: a
    // folder made by another sampling scheme is refused rather than continued with other draws.
    c += fmt::format("sampling: {}\n", kSamplingScheme);
    c += fmt::format("seed: {}\ndefect_free_fraction: {}\nmin_fraction: {}\nmax_attempts: {}\nltm: {}\npreviews: {}\n",
                     spec.seed, spec.defect_free_fraction, spec.mask_fraction, spec.max_attempts, spec.keep_ltm,
                     spec.previews);
    c += "splits:";
    for (const auto& s : spec.splits) c += fmt::format(" {}={}", s.name, s.fraction);
    c += "\nobject:";
    const auto opt = [](const char* name, const std::optional<Distribution>& d) {
        return d ? fmt::format(" {}={}", name, d->to_string()) : std::string();
    };
    c += opt("r1", spec.object.r1) + opt("r2", spec.object.r2) + opt("center_thickness", spec.object.center_thickness) +
         opt("diameter", spec.object.diameter) + opt("radius", spec.object.radius) + opt("ior", spec.object.ior) + "\n";
    for (const auto& k : spec.defects) {
        c += fmt::format("defect: {} count={}", to_string(k.type), k.count.to_string());
        if (k.radius) c += " radius=" + k.radius->to_string();
        if (k.semi_axes)
            c += fmt::format(" semi_axes=[{}, {}, {}]", (*k.semi_axes)[0].to_string(), (*k.semi_axes)[1].to_string(),
                             (*k.semi_axes)[2].to_string());
        c += fmt::format(" surface_breaking={} center_depth={} delta_n={} index_profile={} surface={} shape={} width={} "
                         "depth={} length={} arc_radius={} scratch_profile={}\n",
                         k.surface_breaking, k.center_depth.to_string(), k.delta_n.to_string(), k.index_profile.to_string(),
                         k.surface.to_string(), k.shape.to_string(), k.width.to_string(), k.depth.to_string(),
                         k.length.to_string(), k.arc_radius.to_string(), k.scratch_profile.to_string());
    }
    Scene base = spec.base;
    base.seed = 0;  // each sample has its own
    c += "scene:\n" + scene_to_yaml(base);
    spec.canonical = c;
    return spec;
}

}  // namespace

SpecLocation DefectKindSpec::location_of(const std::string& key) const {
    const auto it = keys.find(key);
    if (it != keys.end()) return it->second;
    return {where.line, where.column, where.key_path + "." + key};
}

DatasetSpec parse_dataset_spec(const std::string& text, const std::string& file_name) {
    const YAML::Node root = yaml::parse_document(text, file_name, "dataset spec");
    return SpecParser(file_name).run(root);
}

DatasetSpec load_dataset_spec(const std::string& path) {
    return parse_dataset_spec(yaml::read_file(path, "dataset spec"), path);
}

}  // namespace ltm
