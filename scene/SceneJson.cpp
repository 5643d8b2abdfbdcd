#include "scene/SceneJson.h"

#include "io/Json.h"

namespace ltm {

using io::Json;
using io::json_number;

namespace {

Json vec(const Vec3& v) { return {json_number(v.x), json_number(v.y), json_number(v.z)}; }
Json vec2(double x, double y) { return {json_number(x), json_number(y)}; }

const char* object_type_name(ObjectType t) {
    switch (t) {
        case ObjectType::Lens: return "lens";
        case ObjectType::Window: return "window";
        case ObjectType::Sphere: return "sphere";
    }
    return "?";
}

// The index field's own keys (a graded glass only).
Json index_field_json(const IndexField& f) {
    Json j = {{"type", to_string(f.type)}};
    switch (f.type) {
        case IndexFieldType::RadialN2:
        case IndexFieldType::SphericalN2: j["g"] = json_number(f.g); break;
        case IndexFieldType::QuadraticN2: {
            Json h = Json::array();
            for (int r = 0; r < 3; ++r) h.push_back({json_number(f.hessian(r, 0)), json_number(f.hessian(r, 1)), json_number(f.hessian(r, 2))});
            j["gradient"] = vec(f.gradient);
            j["hessian"] = h;
            break;
        }
        default: j["gradient"] = vec(f.gradient); break;
    }
    return j;
}

Json defect_json(const Defect& d) {
    if (d.type == DefectType::Scratch) {
        Json j = {{"type", "scratch"}, {"surface", d.side == 0 ? "front" : "back"}};
        if (d.arc) {
            j["arc"] = {{"center", vec2(d.arc_center.x, d.arc_center.y)},
                        {"radius", json_number(d.arc_radius)},
                        {"start_angle", json_number(d.start_angle)},
                        {"end_angle", json_number(d.end_angle)}};
        } else {
            j["start"] = vec2(d.start.x, d.start.y);
            j["end"] = vec2(d.end.x, d.end.y);
        }
        j["width"] = json_number(d.width);
        j["depth"] = json_number(d.depth);
        j["profile"] = d.profile == ScratchProfile::V ? "V" : "U";
        return j;
    }
    Json frame = Json::array();
    for (int i = 0; i < 9; ++i) frame.push_back(json_number(d.frame.m[static_cast<size_t>(i)]));
    Json j = {{"type", to_string(d.type)}, {"center", vec(d.center)}, {"semi_axes", vec(d.semi_axes)}, {"frame", frame}};
    if (d.type == DefectType::Bubble && d.surface_breaking) j["surface_breaking"] = true;
    if (d.type == DefectType::Inhomogeneity) {
        j["delta_n"] = json_number(d.delta_n);
        j["profile"] = d.index_profile == IndexProfile::Smooth ? "smooth" : "uniform";
    }
    return j;
}

}  // namespace

Json scene_to_json(const Scene& s) {
    const auto& L = s.object.lens;
    Json object = {{"type", object_type_name(s.object.type)},
                   {"r1", json_number(L.r1)},
                   {"r2", json_number(L.r2)},
                   {"center_thickness", json_number(L.center_thickness)},
                   {"diameter", json_number(L.diameter)},
                   {"ior", json_number(L.ior)},
                   {"rim", s.object.rim == RimFinish::Polished ? "polished" : "absorbing"},
                   {"absorption", json_number(s.object.absorption)}};
    if (s.object.index_field.graded()) object["index_field"] = index_field_json(s.object.index_field);
    Json defects = Json::array();
    for (const Defect& d : s.defects) defects.push_back(defect_json(d));
    Json j = {{"source", s.source},
            {"object", object},
            {"defects", defects},
            {"camera",
             {{"resolution", {s.camera.resolution[0], s.camera.resolution[1]}},
              {"size", vec2(s.camera.size[0], s.camera.size[1])},
              {"numerical_aperture", json_number(s.camera.numerical_aperture)},
              {"samples_per_pixel", s.camera.samples_per_pixel},
              {"focus_z", json_number(s.camera.focus_z)}}},
            {"display",
             {{"resolution", {s.display.resolution[0], s.display.resolution[1]}},
              {"size", vec2(s.display.size[0], s.display.size[1])},
              {"z", json_number(s.display.z)}}},
            {"mesh",
             {{"chord_tolerance", json_number(s.mesh.chord_tolerance)},
              {"defect_relative_tolerance", json_number(s.mesh.defect_relative_tolerance)},
              {"always_boolean", s.mesh.always_boolean},
              {"index_tolerance", json_number(s.mesh.index_tolerance)}}},
            {"tracing", tracing_to_json(s.tracing)},
            {"seed", s.seed}};
    if (s.reference_seed) j["reference_seed"] = *s.reference_seed;
    return j;
}

Json tracing_to_json(const TracingDesc& t) {
    Json j = {{"estimator", to_string(t.estimator)}};
    if (t.estimator == Estimator::Split) j["split_depth"] = t.split_depth;  // Sample has no depth
    return j;
}

}  // namespace ltm
