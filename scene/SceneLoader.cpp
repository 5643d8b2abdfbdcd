#include "scene/SceneLoader.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "defects/DefectSolid.h"
#include "scene/CameraView.h"
#include "scene/StrictYaml.h"

namespace ltm {

namespace {

using yaml::describe;
using yaml::find_item;
using yaml::Item;
using yaml::items_of;
using yaml::join_keys;
using yaml::join_path;
using yaml::KeyRule;
using yaml::Loc;
using yaml::loc_of;
using yaml::Where;

// The scene's sections on top of the strict engine (scene/StrictYaml.h).
class SceneParser : public yaml::Reader {
public:
    using Reader::Reader;

    // `whole_file`: the root is a file's document (an empty one is "the scene file is empty"),
    // not a mapping inside another document.
    Scene run(const YAML::Node& root, bool whole_file) const;

private:
    // Reader::walk, keeping where each entry's value is (Scene::locations).
    void walk(const YAML::Node& map, const std::string& path, const KeyRule& rule,
              const std::function<void(const Item&)>& visit) const {
        Reader::walk(map, path, rule, [&](const Item& e) {
            const Loc at = e.value_loc();
            locations_[join_path(path, e.key)] = {at.line, at.column};
            visit(e);
        });
    }
    // "FILE:LINE:COLUMN: warning: KEY: message" at the key's value (Scene::warnings).
    std::string warning(const std::string& key, const std::string& message) const;
    mutable std::map<std::string, SourceLocation> locations_;

    // [x, y] or [x, y, z] (a point of a face; `has_z` says whether z was given).
    Vec3 point23(const Item& it, const std::string& path, bool& has_z) const;

    // Sections
    void parse_object(const Item& it, ObjectDesc& object, Where& where) const;
    void parse_index_field(const Item& it, IndexField& field, Where& where) const;
    void check_object(const ObjectDesc& object, const Where& where, Loc object_loc) const;
    Defect parse_defect(const YAML::Node& node, const std::string& path, Where& where) const;
    void parse_ellipsoid_keys(const YAML::Node& map, const std::string& path, DefectType type, Defect& d,
                              Where& where) const;
    void parse_scratch_keys(const YAML::Node& map, const std::string& path, Defect& d, Where& where) const;
    void parse_arc(const Item& it, const std::string& path, Defect& d, Where& where) const;
    void check_defect(const ObjectDesc& object, const std::vector<Defect>& defects, std::size_t index,
                      const Where& where, Loc defect_loc) const;
    // [columns, rows] of positive integers; [width, height] of positive lengths (mm).
    std::array<int, 2> resolution(const YAML::Node& v, Loc at, const std::string& p) const {
        const auto xs = number_list(v, at, p, {2}, "positive integers [columns, rows]",
                                    [&](const YAML::Node& x, Loc l, const std::string& q) {
                                        return static_cast<double>(positive_int(x, l, q));
                                    });
        return {static_cast<int>(xs[0]), static_cast<int>(xs[1])};
    }
    std::array<double, 2> size2(const YAML::Node& v, Loc at, const std::string& p) const {
        const auto xs = number_list(v, at, p, {2}, "positive lengths [width, height]",
                                    [&](const YAML::Node& x, Loc l, const std::string& q) { return positive_length(x, l, q); });
        return {xs[0], xs[1]};
    }
    void parse_camera(const Item& it, CameraDesc& camera) const;
    void parse_display(const Item& it, DisplayDesc& display, Loc& z_loc, bool& z_given) const;
    void parse_mesh(const Item& it, MeshOptions& mesh) const;
    void parse_tracing(const Item& it, TracingDesc& tracing) const;
    void check_display(const ObjectDesc& object, const DisplayDesc& display, Loc z_loc, bool z_given) const;
};

Vec3 SceneParser::point23(const Item& it, const std::string& path, bool& has_z) const {
    const auto xs = number_list(it.value, it.value_loc(), path, {2, 3}, "numbers [x, y] or [x, y, z]",
                                [&](const YAML::Node& e, Loc at, const std::string& p) { return number(e, at, p); });
    has_z = xs.size() == 3;
    return {xs[0], xs[1], has_z ? xs[2] : 0.0};
}

// ---------------------------------------------------------------------------------------------
// The object

const std::vector<std::string> kLensKeys{"type", "r1", "r2", "center_thickness", "diameter", "ior", "rim", "absorption",
                                         "index_field"};
const std::vector<std::string> kWindowKeys{"type", "thickness", "diameter", "ior", "rim", "absorption", "index_field"};
const std::vector<std::string> kSphereKeys{"type", "radius", "ior", "absorption", "index_field"};

void SceneParser::parse_object(const Item& it, ObjectDesc& object, Where& where) const {
    const std::string path = "object";
    require_map(it, path);
    const auto items = items_of(it.value);
    const Item* type_item = find_item(items, "type");
    if (!type_item) fail(loc_of(it.value), "object.type", "missing required key 'type'");
    const std::size_t kind = choice(type_item->value, type_item->value_loc(), "object.type", {"lens", "window", "sphere"});
    const bool window = kind == 1, sphere = kind == 2;
    object.type = sphere ? ObjectType::Sphere : (window ? ObjectType::Window : ObjectType::Lens);
    object.lens = LensSpec{};

    KeyRule rule;
    rule.keys = sphere ? kSphereKeys : (window ? kWindowKeys : kLensKeys);
    rule.context = sphere ? " for a sphere" : (window ? " for a window" : " for a lens");
    rule.hint = [window, sphere, keys = rule.keys](const std::string& k) -> std::optional<std::string> {
        if (window && (k == "r1" || k == "r2"))
            return std::string(": windows have flat faces (use type: lens for curved faces); valid keys are: ") +
                   join_keys(keys);
        if (sphere && (k == "r1" || k == "r2" || k == "diameter" || k == "center_thickness" || k == "thickness"))
            return std::string(": a sphere is given by its radius alone; valid keys are: ") + join_keys(keys);
        if (sphere && k == "rim") return std::string(": a sphere has no rim; valid keys are: ") + join_keys(keys);
        return std::nullopt;
    };

    double radius = 0;
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        where[e.key] = at;
        if (e.key == "type") return;
        if (e.key == "r1" || e.key == "r2") {
            double r = number(e.value, at, p, /*allow_inf=*/true);
            if (std::isinf(r)) r = std::numeric_limits<double>::infinity();  // a plane has no sign
            (e.key == "r1" ? object.lens.r1 : object.lens.r2) = r;
        } else if (e.key == "center_thickness" || e.key == "thickness") {
            object.lens.center_thickness = number(e.value, at, p);
        } else if (e.key == "diameter") {
            object.lens.diameter = number(e.value, at, p);
        } else if (e.key == "radius") {
            radius = number(e.value, at, p);
        } else if (e.key == "ior") {
            object.lens.ior = number(e.value, at, p);
        } else if (e.key == "rim") {
            object.rim = choice(e.value, at, p, {"polished", "absorbing"}) == 0 ? RimFinish::Polished
                                                                                : RimFinish::Absorbing;
        } else if (e.key == "absorption") {
            const double a = number(e.value, at, p);
            if (!(a >= 0)) fail(at, p, fmt::format("must be >= 0 (1/mm), got {}", e.value.Scalar()));
            object.absorption = a;
        } else if (e.key == "index_field") {
            parse_index_field(e, object.index_field, where);
        }
    });
    if (sphere) {
        require_keys(it.value, path, where, {"radius", "ior"});
        object.lens = ball_spec(radius, object.lens.ior);
    } else if (window) {
        require_keys(it.value, path, where, {"thickness", "diameter", "ior"});
        object.lens.r1 = object.lens.r2 = std::numeric_limits<double>::infinity();
    } else {
        require_keys(it.value, path, where, {"r1", "r2", "center_thickness", "diameter", "ior"});
    }
    object.index_field.ior = object.lens.ior;
}

// object.index_field: {type: linear_n2 | radial_n2 | spherical_n2 | quadratic_n2 | linear_n, ...}
// (geometry/IndexField.h). Positions of its keys go into `where` as "index_field.<key>".
void SceneParser::parse_index_field(const Item& it, IndexField& f, Where& where) const {
    const std::string path = "object.index_field";
    require_map(it, path);
    const auto items = items_of(it.value);
    const Item* type_item = find_item(items, "type");
    if (!type_item) fail(loc_of(it.value), path + ".type", "missing required key 'type'");
    const std::vector<std::string> kinds{"linear_n2", "radial_n2", "spherical_n2", "quadratic_n2", "linear_n"};
    const std::size_t kind = choice(type_item->value, type_item->value_loc(), path + ".type", kinds);
    const IndexFieldType types[] = {IndexFieldType::LinearN2, IndexFieldType::RadialN2, IndexFieldType::SphericalN2,
                                    IndexFieldType::QuadraticN2, IndexFieldType::LinearN};
    f = IndexField{};
    f.type = types[kind];
    KeyRule rule;
    switch (f.type) {
        case IndexFieldType::RadialN2:
        case IndexFieldType::SphericalN2: rule.keys = {"type", "g"}; break;
        case IndexFieldType::QuadraticN2: rule.keys = {"type", "gradient", "hessian"}; break;
        default: rule.keys = {"type", "gradient"}; break;
    }
    rule.context = " for an index field of type " + kinds[kind];
    Where local;
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        local[e.key] = at;
        where["index_field." + e.key] = at;
        if (e.key == "g") {
            f.g = number(e.value, at, p);
        } else if (e.key == "gradient") {
            f.gradient = vec3(e, p, "numbers [gx, gy, gz]");
        } else if (e.key == "hessian") {
            const bool rows_ok = e.value.IsSequence() && e.value.size() == 3;
            if (!rows_ok)
                fail(at, p, fmt::format("expected a list of 3 rows of 3 numbers [[..], [..], [..]], got {}",
                                        describe(e.value)));
            for (std::size_t r = 0; r < 3; ++r) {
                const YAML::Node row = e.value[r];
                const std::string rp = fmt::format("{}[{}]", p, r);
                const auto xs = number_list(row, row.IsNull() ? at : loc_of(row), rp, {3}, "numbers (a row of the hessian)",
                                            [&](const YAML::Node& x, Loc l, const std::string& q) { return number(x, l, q); });
                for (std::size_t c = 0; c < 3; ++c) f.hessian(static_cast<int>(r), static_cast<int>(c)) = xs[c];
            }
        }
    });
    if (f.type == IndexFieldType::QuadraticN2) require_keys(it.value, path, local, {"hessian"});
    else if (f.type == IndexFieldType::RadialN2 || f.type == IndexFieldType::SphericalN2)
        require_keys(it.value, path, local, {"g"});
    else
        require_keys(it.value, path, local, {"gradient"});
    where["index_field"] = it.value_loc();
}

void SceneParser::check_object(const ObjectDesc& object, const Where& where, Loc object_loc) const {
    auto located = [&](const std::string& key) { return yaml::located(where, key, object_loc); };
    const auto problems = Lens::problems(object.lens);
    if (!problems.empty()) {
        std::string key = problems.front().key;
        if (object.type == ObjectType::Window && key == "center_thickness") key = "thickness";
        fail(located(key), join_path("object", key), problems.front().message);
    }
    if (!object.index_field.graded()) return;
    const auto field_problems = index_field_problems(Lens(object.lens), object.index_field);
    if (field_problems.empty()) return;
    const std::string key = field_problems.front().key.empty() ? "index_field" : "index_field." + field_problems.front().key;
    fail(located(key), join_path("object", key), field_problems.front().message);
}

// ---------------------------------------------------------------------------------------------
// Defects

const std::vector<std::string> kBubbleKeys{"type", "center", "radius", "semi_axes", "rotation", "surface_breaking"};
const std::vector<std::string> kParticleKeys{"type", "center", "radius", "semi_axes", "rotation"};
const std::vector<std::string> kInhomogeneityKeys{"type", "center", "radius", "semi_axes", "rotation", "delta_n", "profile"};
const std::vector<std::string> kScratchKeys{"type", "surface", "width", "depth", "profile", "start", "end", "arc"};
const std::vector<std::string> kArcKeys{"center", "radius", "start_angle", "end_angle"};

Defect SceneParser::parse_defect(const YAML::Node& node, const std::string& path, Where& where) const {
    if (!node.IsMap())
        fail(loc_of(node), path,
             fmt::format("expected a mapping with a 'type' key (bubble, scratch, particle or inhomogeneity), got {}",
                         describe(node)));
    const auto items = items_of(node);
    const Item* type_item = find_item(items, "type");
    if (!type_item) fail(loc_of(node), join_path(path, "type"), "missing required key 'type'");
    Defect d;
    switch (choice(type_item->value, type_item->value_loc(), join_path(path, "type"),
                   {"bubble", "scratch", "particle", "inhomogeneity"})) {
        case 0: parse_ellipsoid_keys(node, path, DefectType::Bubble, d, where); break;
        case 1: parse_scratch_keys(node, path, d, where); break;
        case 2: parse_ellipsoid_keys(node, path, DefectType::Particle, d, where); break;
        default: parse_ellipsoid_keys(node, path, DefectType::Inhomogeneity, d, where); break;
    }
    return d;
}

void SceneParser::parse_ellipsoid_keys(const YAML::Node& map, const std::string& path, DefectType type, Defect& d,
                                       Where& where) const {
    const bool bubble = type == DefectType::Bubble, inclusion = type == DefectType::Inhomogeneity;
    d.type = type;
    KeyRule rule;
    rule.keys = bubble ? kBubbleKeys : (inclusion ? kInhomogeneityKeys : kParticleKeys);
    rule.context = bubble ? " for a bubble" : (inclusion ? " for an inhomogeneity" : " for a particle");
    rule.hint = [bubble, inclusion, keys = rule.keys](const std::string& k) -> std::optional<std::string> {
        if (!bubble && !inclusion && k == "surface_breaking")
            return std::string(": particles always lie strictly inside the glass (a surface-breaking void is a "
                               "bubble); valid keys are: ") +
                   join_keys(keys);
        if (inclusion && k == "surface_breaking")
            return std::string(": an inhomogeneity is clipped to the glass where it reaches a face; valid keys are: ") +
                   join_keys(keys);
        if (k == "index_field")
            return std::string(": index_field is a key of the object (the glass's index as a field); a defect "
                               "changes the index locally as type inhomogeneity with delta_n; valid keys are: ") +
                   join_keys(keys);
        if (!inclusion && (k == "delta_n"))
            return fmt::format(" ({} is a key of inhomogeneities); valid keys are: {}", k, join_keys(keys));
        if (std::find(kScratchKeys.begin(), kScratchKeys.end(), k) != kScratchKeys.end())
            return fmt::format(" ({} is a key of scratches); valid keys are: {}", k, join_keys(keys));
        return std::nullopt;
    };

    Loc rotation_key;
    Vec3 rotation;
    double radius = 0;
    walk(map, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        where[e.key] = at;
        if (e.key == "center") {
            d.center = vec3(e, p, "numbers [x, y, z]");
        } else if (e.key == "radius") {
            if (where.count("semi_axes"))
                fail(e.key_loc(), p, "give either radius (a sphere) or semi_axes (an ellipsoid), not both");
            radius = positive_length(e.value, at, p);
        } else if (e.key == "semi_axes") {
            if (where.count("radius"))
                fail(e.key_loc(), p, "give either radius (a sphere) or semi_axes (an ellipsoid), not both");
            d.semi_axes = positive_vec3(e, p, "positive lengths [a, b, c]");
        } else if (e.key == "rotation") {
            rotation_key = e.key_loc();
            rotation = vec3(e, p, "angles in degrees [rx, ry, rz]");
        } else if (e.key == "surface_breaking") {
            d.surface_breaking = boolean(e.value, at, p);
        } else if (e.key == "delta_n") {
            d.delta_n = number(e.value, at, p);
            if (d.delta_n == 0)
                fail(at, p, "must be non-zero: delta_n = 0 leaves the glass unchanged (remove the defect instead)");
        } else if (e.key == "profile") {
            d.index_profile = choice(e.value, at, p, {"smooth", "uniform"}) == 0 ? IndexProfile::Smooth
                                                                                  : IndexProfile::Uniform;
        }
    });
    require_keys(map, path, where, inclusion ? std::vector<std::string>{"center", "delta_n"}
                                             : std::vector<std::string>{"center"});
    if (!where.count("radius") && !where.count("semi_axes"))
        fail(loc_of(map), path, "missing required key 'radius' (a sphere) or 'semi_axes' (an ellipsoid)");
    if (where.count("rotation") && where.count("radius"))
        fail(rotation_key, join_path(path, "rotation"),
             "rotation applies only to an ellipsoid given by semi_axes: a sphere (radius) has no orientation");
    if (where.count("radius")) d.semi_axes = {radius, radius, radius};
    if (where.count("rotation"))
        d.set_rotation_deg(rotation);
    else
        d.frame = Mat3::identity();
}

void SceneParser::parse_scratch_keys(const YAML::Node& map, const std::string& path, Defect& d, Where& where) const {
    d.type = DefectType::Scratch;
    KeyRule rule;
    rule.keys = kScratchKeys;
    rule.context = " for a scratch";
    rule.hint = [](const std::string& k) -> std::optional<std::string> {
        if (k == "center" || k == "radius" || k == "start_angle" || k == "end_angle")
            return fmt::format(": an arc scratch takes {} inside arc: {{center, radius, start_angle, end_angle}}", k);
        if (k == "semi_axes" || k == "rotation" || k == "surface_breaking")
            return fmt::format(" ({} is a key of bubbles and particles); valid keys are: {}", k, join_keys(kScratchKeys));
        return std::nullopt;
    };
    const char* both = "give either start and end (a straight scratch) or arc (a circular one), not both";
    walk(map, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        where[e.key] = at;
        if (e.key == "surface") {
            d.side = static_cast<int>(choice(e.value, at, p, {"front", "back"}));
        } else if (e.key == "width") {
            d.width = positive_length(e.value, at, p);
        } else if (e.key == "depth") {
            d.depth = positive_length(e.value, at, p);
        } else if (e.key == "profile") {
            d.profile = choice(e.value, at, p, {"V", "U"}) == 0 ? ScratchProfile::V : ScratchProfile::U;
        } else if (e.key == "start" || e.key == "end") {
            if (where.count("arc")) fail(e.key_loc(), p, both);
            if (e.key == "start")
                d.start = point23(e, p, d.start_has_z);
            else
                d.end = point23(e, p, d.end_has_z);
        } else if (e.key == "arc") {
            if (where.count("start") || where.count("end")) fail(e.key_loc(), p, both);
            parse_arc(e, p, d, where);
        }
    });
    require_keys(map, path, where, {"surface", "width", "depth"});
    if (where.count("arc")) {
        d.arc = true;
        return;
    }
    const bool s = where.count("start") > 0, e = where.count("end") > 0;
    if (s != e) {
        const char* missing = s ? "end" : "start";
        fail(loc_of(map), join_path(path, missing),
             fmt::format("missing required key '{}' (a straight scratch needs start and end)", missing));
    }
    if (!s)
        fail(loc_of(map), path, "missing required key 'start' and 'end' (a straight scratch) or 'arc' (a circular one)");
    d.arc = false;  // distinct end points, on the face: defect_problems
}

void SceneParser::parse_arc(const Item& it, const std::string& path, Defect& d, Where& where) const {
    require_map(it, path);
    KeyRule rule;
    rule.keys = kArcKeys;
    Where arc_where;
    double start = 0, end = 0;
    std::string start_text, end_text;
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        arc_where[e.key] = at;
        where["arc." + e.key] = at;
        if (e.key == "center") {
            d.arc_center = point23(e, p, d.arc_center_has_z);
        } else if (e.key == "radius") {
            d.arc_radius = positive_length(e.value, at, p);
        } else if (e.key == "start_angle") {
            start = number(e.value, at, p);
            start_text = e.value.Scalar();
        } else if (e.key == "end_angle") {
            end = number(e.value, at, p);
            end_text = e.value.Scalar();
        }
    });
    require_keys(it.value, path, arc_where, kArcKeys);
    const Loc end_loc = arc_where.at("end_angle");
    if (!(end > start))
        fail(end_loc, join_path(path, "end_angle"),
             fmt::format("must be greater than start_angle ({}), got {}", start_text, end_text));
    if (!(end - start < 360.0))
        fail(end_loc, join_path(path, "end_angle"),
             fmt::format("the arc spans {:g} degrees from start_angle {}: it must span less than 360", end - start,
                         start_text));
    d.start_angle = start;
    d.end_angle = end;
}

void SceneParser::check_defect(const ObjectDesc& object, const std::vector<Defect>& defects, std::size_t index,
                               const Where& where, Loc defect_loc) const {
    const Lens lens(object.lens);
    const Defect& d = defects[index];
    const std::string path = fmt::format("defects[{}]", index);
    auto problems = defect_problems(lens, d, object.index_field);
    for (std::size_t j = 0; j < index && problems.empty(); ++j)
        problems = defect_pair_problems(lens, d, defects[j], static_cast<int>(j));
    if (problems.empty()) return;
    std::string key = problems.front().key;
    // An arc scratch's centre and radius live in its `arc` mapping.
    if (d.type == DefectType::Scratch && d.arc && !where.count(key) &&
        std::find(kArcKeys.begin(), kArcKeys.end(), key) != kArcKeys.end())
        key = "arc." + key;
    // The value of the named key, or of its nearest enclosing key in the file ("center[2]" ->
    // "center"), else the defect's own mapping.
    fail(yaml::located(where, key, defect_loc), join_path(path, key), problems.front().message);
}

// ---------------------------------------------------------------------------------------------
// Camera, display, mesh

void SceneParser::parse_camera(const Item& it, CameraDesc& camera) const {
    const std::string path = "camera";
    require_map(it, path);
    KeyRule rule;
    rule.keys = {"resolution", "size", "numerical_aperture", "samples_per_pixel", "focus_z"};
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "resolution") {
            camera.resolution = resolution(e.value, at, p);
        } else if (e.key == "size") {
            camera.size = size2(e.value, at, p);
        } else if (e.key == "numerical_aperture") {
            const double na = number(e.value, at, p);
            if (!(na > 0 && na < 1)) fail(at, p, fmt::format("must be in (0, 1), got {}", e.value.Scalar()));
            camera.numerical_aperture = na;
        } else if (e.key == "samples_per_pixel") {
            camera.samples_per_pixel = positive_int(e.value, at, p);
        } else if (e.key == "focus_z") {
            camera.focus_z = number(e.value, at, p);
        }
    });
}

void SceneParser::parse_display(const Item& it, DisplayDesc& display, Loc& z_loc, bool& z_given) const {
    const std::string path = "display";
    require_map(it, path);
    z_loc = loc_of(it.value);
    z_given = false;
    KeyRule rule;
    rule.keys = {"resolution", "size", "z"};
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "resolution") {
            display.resolution = resolution(e.value, at, p);
        } else if (e.key == "size") {
            display.size = size2(e.value, at, p);
        } else if (e.key == "z") {
            display.z = number(e.value, at, p);
            z_loc = at;
            z_given = true;
        }
    });
}

void SceneParser::check_display(const ObjectDesc& object, const DisplayDesc& display, Loc z_loc, bool z_given) const {
    // The back face's farthest point: its vertex, or its rim when the back face bulges toward +z
    // (a spherical cap is monotonic in rho, so rho in {0, a} covers it).
    const Lens lens(object.lens);
    const double back = std::max(lens.z_back(0.0), lens.z_back(lens.aperture_radius()));
    if (display.z > back) return;
    fail(z_loc, "display.z",
         fmt::format("the display must lie behind the object: z must be greater than {:g} mm (the object's back "
                     "extent), got {:g}{}",
                     back, display.z, z_given ? "" : " (the default)"));
}

void SceneParser::parse_mesh(const Item& it, MeshOptions& mesh) const {
    const std::string path = "mesh";
    require_map(it, path);
    KeyRule rule;
    rule.keys = {"chord_tolerance", "defect_relative_tolerance", "always_boolean", "index_tolerance"};
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "chord_tolerance") {
            mesh.chord_tolerance = positive_length(e.value, at, p);
        } else if (e.key == "defect_relative_tolerance") {
            const double r = number(e.value, at, p);
            if (!(r > 0 && r <= 0.5)) fail(at, p, fmt::format("must be in (0, 0.5], got {}", e.value.Scalar()));
            mesh.defect_relative_tolerance = r;
        } else if (e.key == "always_boolean") {
            mesh.always_boolean = boolean(e.value, at, p);
        } else if (e.key == "index_tolerance") {
            const double t = number(e.value, at, p);
            if (!(t > 0 && t <= 0.1)) fail(at, p, fmt::format("must be in (0, 0.1] (a tolerance on n^2), got {}", e.value.Scalar()));
            mesh.index_tolerance = t;
        }
    });
}

// tracing: {estimator: sample | split, split_depth: 0..kMaxSplitDepth}. split_depth belongs to the
// split estimator: given with sample (or without estimator, which is sample) it would be ignored,
// so it is an error at the key.
void SceneParser::parse_tracing(const Item& it, TracingDesc& tracing) const {
    const std::string path = "tracing";
    require_map(it, path);
    KeyRule rule;
    rule.keys = {"estimator", "split_depth"};
    std::optional<Loc> depth_key;
    const std::string depth_expected = fmt::format("an integer in [0, {}] (Fresnel interactions split)", kMaxSplitDepth);
    walk(it.value, path, rule, [&](const Item& e) {
        const std::string p = join_path(path, e.key);
        const Loc at = e.value_loc();
        if (e.key == "estimator") {
            tracing.estimator = choice(e.value, at, p, {"sample", "split"}) == 0 ? Estimator::Sample : Estimator::Split;
        } else if (e.key == "split_depth") {
            tracing.split_depth = static_cast<int>(integer(e.value, at, p, 0, kMaxSplitDepth, depth_expected.c_str()));
            depth_key = e.key_loc();
        }
    });
    if (depth_key && tracing.estimator != Estimator::Split)
        fail(*depth_key, join_path(path, "split_depth"),
             "applies only to 'estimator: split' (the estimator here is sample); remove it or add 'estimator: split'");
}

std::string SceneParser::warning(const std::string& key, const std::string& message) const {
    const std::string k = yaml::enclosing_key(key, [&](const std::string& x) { return locations_.count(x) > 0; });
    const std::string where =
        k.empty() ? file() : fmt::format("{}:{}:{}", file(), locations_.at(k).line, locations_.at(k).column);
    return fmt::format("{}: warning: {}: {}", where, join_path(prefix(), key), message);
}

// ---------------------------------------------------------------------------------------------
// The document

Scene SceneParser::run(const YAML::Node& root, bool whole_file) const {
    Scene scene;
    scene.source = file();
    const char* keys = "a mapping of scene keys (object, defects, camera, display, mesh, tracing, seed, reference_seed)";
    if (!root.IsDefined() || root.IsNull()) {
        if (whole_file) fail({1, 1}, "", "the scene file is empty: expected a mapping with at least the key 'object'");
        // An undefined node (a key the caller looked up that is not there) has no mark.
        fail(root.IsDefined() ? loc_of(root) : Loc{}, "", fmt::format("expected {}, got an empty value", keys));
    }
    if (!root.IsMap())
        fail(loc_of(root), "",
             fmt::format("expected {}{}, got {}", keys, whole_file ? " at the top level" : "", describe(root)));

    // Geometry checks need the object; defects and the display are checked as soon as both they
    // and a valid object are known (at once in the usual key order).
    struct PendingDefect {
        std::size_t index;
        Where where;
        Loc loc;
    };
    bool have_object = false, have_display = false;
    Where object_where;
    Loc object_loc, display_z_loc = loc_of(root);
    bool display_z_given = false;
    std::vector<PendingDefect> pending;
    auto check_pending = [&] {
        for (const auto& p : pending) check_defect(scene.object, scene.defects, p.index, p.where, p.loc);
        pending.clear();
    };

    KeyRule rule;
    rule.keys = {"object", "defects", "camera", "display", "mesh", "tracing", "seed", "reference_seed"};
    walk(root, "", rule, [&](const Item& e) {
        const Loc at = e.value_loc();
        if (e.key == "object") {
            parse_object(e, scene.object, object_where);
            object_loc = loc_of(e.value);
            check_object(scene.object, object_where, object_loc);
            have_object = true;
            check_pending();
            if (have_display) check_display(scene.object, scene.display, display_z_loc, display_z_given);
        } else if (e.key == "defects") {
            if (e.value.IsNull()) return;
            if (!e.value.IsSequence())
                fail(at, "defects", fmt::format("expected a list of defects, got {}", describe(e.value)));
            for (std::size_t i = 0; i < e.value.size(); ++i) {
                const YAML::Node node = e.value[i];
                const std::string path = fmt::format("defects[{}]", i);
                Where where;
                const Loc node_loc = loc_of(node);
                locations_[path] = {node_loc.line, node_loc.column};
                scene.defects.push_back(parse_defect(node, path, where));
                pending.push_back({i, std::move(where), loc_of(node)});
                if (have_object) check_pending();
            }
        } else if (e.key == "camera") {
            parse_camera(e, scene.camera);
        } else if (e.key == "display") {
            parse_display(e, scene.display, display_z_loc, display_z_given);
            have_display = true;
            if (have_object) check_display(scene.object, scene.display, display_z_loc, display_z_given);
        } else if (e.key == "mesh") {
            parse_mesh(e, scene.mesh);
        } else if (e.key == "tracing") {
            parse_tracing(e, scene.tracing);
        } else if (e.key == "seed") {
            scene.seed = seed(e.value, at, "seed");
        } else if (e.key == "reference_seed") {
            scene.reference_seed = seed(e.value, at, "reference_seed");
        }
    });
    if (!have_object) fail(loc_of(root), "object", "missing required key 'object'");
    if (!have_display) check_display(scene.object, scene.display, loc_of(root), false);
    for (const ViewWarning& w : view_warnings(scene.object, scene.camera, locations_.count("camera.size") > 0))
        scene.warnings.push_back(warning(w.key, w.message));
    scene.locations = std::move(locations_);
    scene.key_prefix = prefix();
    return scene;
}

}  // namespace

Scene parse_scene_node(const YAML::Node& root, const std::string& file, const std::string& prefix) {
    return SceneParser(file, prefix).run(root, /*whole_file=*/false);
}

Scene parse_scene(const std::string& yaml_text, const std::string& file_name_for_messages) {
    const YAML::Node root = yaml::parse_document(yaml_text, file_name_for_messages, "scene file");
    return SceneParser(file_name_for_messages).run(root, /*whole_file=*/true);
}

Scene load_scene(const std::string& path) { return parse_scene(yaml::read_file(path, "scene file"), path); }

InputError scene_error(const Scene& scene, const std::string& key, const std::string& message) {
    const std::string path = join_path(scene.key_prefix, key);
    // The value of the key, or of its nearest enclosing key in the file ("defects[2].radius" ->
    // "defects[2]"), as the loader's own errors are located.
    const std::string k =
        yaml::enclosing_key(key, [&](const std::string& x) { return scene.locations.count(x) > 0; });
    if (k.empty()) return InputError(scene.source, 0, 0, path, path.empty() ? message : path + ": " + message);
    const SourceLocation at = scene.locations.at(k);
    return InputError(scene.source, at.line, at.column, path, message);
}

}  // namespace ltm
