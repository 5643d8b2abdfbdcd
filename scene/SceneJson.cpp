#include "scene/SceneJson.h"

#include <cmath>
#include <fmt/format.h>

namespace ltm {

std::string json_number(double v) {
    if (std::isnan(v)) return "\"nan\"";
    if (std::isinf(v)) return v > 0 ? "\"inf\"" : "\"-inf\"";
    return fmt::format("{}", v);  // fmt's default: the shortest representation that round-trips
}

std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') { o += '\\'; o += c; }
        else if (static_cast<unsigned char>(c) < 0x20) o += fmt::format("\\u{:04x}", static_cast<int>(c));
        else o += c;
    }
    return o + "\"";
}

namespace {

std::string vec(const Vec3& v) { return fmt::format("[{}, {}, {}]", json_number(v.x), json_number(v.y), json_number(v.z)); }

const char* object_type_name(ObjectType t) {
    switch (t) {
        case ObjectType::Lens: return "lens";
        case ObjectType::Window: return "window";
        case ObjectType::Sphere: return "sphere";
    }
    return "?";
}

// The index field's own keys, or "" for a homogeneous glass.
std::string index_field_json(const IndexField& f) {
    if (!f.graded()) return "";
    std::string keys;
    switch (f.type) {
        case IndexFieldType::RadialN2:
        case IndexFieldType::SphericalN2: keys = fmt::format(", \"g\": {}", json_number(f.g)); break;
        case IndexFieldType::QuadraticN2: {
            std::string h = "[";
            for (int r = 0; r < 3; ++r)
                h += fmt::format("{}[{}, {}, {}]", r ? ", " : "", json_number(f.hessian(r, 0)), json_number(f.hessian(r, 1)),
                                 json_number(f.hessian(r, 2)));
            keys = fmt::format(", \"gradient\": {}, \"hessian\": {}]", vec(f.gradient), h);
            break;
        }
        default: keys = fmt::format(", \"gradient\": {}", vec(f.gradient)); break;
    }
    return fmt::format(", \"index_field\": {{\"type\": \"{}\"{}}}", to_string(f.type), keys);
}

std::string defect_json(const Defect& d) {
    switch (d.type) {
        case DefectType::Scratch: {
            std::string path = d.arc ? fmt::format("\"arc\": {{\"center\": [{}, {}], \"radius\": {}, \"start_angle\": {}, "
                                                   "\"end_angle\": {}}}",
                                                   json_number(d.arc_center.x), json_number(d.arc_center.y),
                                                   json_number(d.arc_radius), json_number(d.start_angle),
                                                   json_number(d.end_angle))
                                     : fmt::format("\"start\": [{}, {}], \"end\": [{}, {}]", json_number(d.start.x),
                                                   json_number(d.start.y), json_number(d.end.x), json_number(d.end.y));
            return fmt::format("{{\"type\": \"scratch\", \"surface\": \"{}\", {}, \"width\": {}, \"depth\": {}, \"profile\": \"{}\"}}",
                               d.side == 0 ? "front" : "back", path, json_number(d.width), json_number(d.depth),
                               d.profile == ScratchProfile::V ? "V" : "U");
        }
        default: {
            std::string frame = "[";
            for (int i = 0; i < 9; ++i) frame += (i ? ", " : "") + json_number(d.frame.m[static_cast<size_t>(i)]);
            frame += "]";
            std::string extra;
            if (d.type == DefectType::Bubble && d.surface_breaking) extra = ", \"surface_breaking\": true";
            if (d.type == DefectType::Inhomogeneity)
                extra = fmt::format(", \"delta_n\": {}, \"profile\": \"{}\"", json_number(d.delta_n),
                                    d.index_profile == IndexProfile::Smooth ? "smooth" : "uniform");
            return fmt::format("{{\"type\": \"{}\", \"center\": {}, \"semi_axes\": {}, \"frame\": {}{}}}",
                               to_string(d.type), vec(d.center), vec(d.semi_axes), frame, extra);
        }
    }
}

}  // namespace

std::string scene_to_json(const Scene& s, int indent) {
    const std::string pad(static_cast<size_t>(indent), ' ');
    std::string defects = "[";
    for (size_t i = 0; i < s.defects.size(); ++i) defects += (i ? ", " : "") + defect_json(s.defects[i]);
    defects += "]";
    const auto& L = s.object.lens;
    return fmt::format(
        "{{\n{p}  \"source\": {},\n"
        "{p}  \"object\": {{\"type\": \"{}\", \"r1\": {}, \"r2\": {}, \"center_thickness\": {}, \"diameter\": {}, "
        "\"ior\": {}, \"rim\": \"{}\", \"absorption\": {}{}}},\n"
        "{p}  \"defects\": {},\n"
        "{p}  \"camera\": {{\"resolution\": [{}, {}], \"size\": [{}, {}], \"numerical_aperture\": {}, "
        "\"samples_per_pixel\": {}, \"focus_z\": {}}},\n"
        "{p}  \"display\": {{\"resolution\": [{}, {}], \"size\": [{}, {}], \"z\": {}}},\n"
        "{p}  \"mesh\": {{\"chord_tolerance\": {}, \"defect_relative_tolerance\": {}, \"always_boolean\": {}, "
        "\"index_tolerance\": {}}},\n"
        "{p}  \"seed\": {}\n{p}}}",
        json_string(s.source), object_type_name(s.object.type), json_number(L.r1), json_number(L.r2),
        json_number(L.center_thickness), json_number(L.diameter), json_number(L.ior),
        s.object.rim == RimFinish::Polished ? "polished" : "absorbing", json_number(s.object.absorption),
        index_field_json(s.object.index_field), defects,
        s.camera.resolution[0], s.camera.resolution[1], json_number(s.camera.size[0]), json_number(s.camera.size[1]),
        json_number(s.camera.numerical_aperture), s.camera.samples_per_pixel, json_number(s.camera.focus_z),
        s.display.resolution[0], s.display.resolution[1], json_number(s.display.size[0]), json_number(s.display.size[1]),
        json_number(s.display.z), json_number(s.mesh.chord_tolerance), json_number(s.mesh.defect_relative_tolerance),
        s.mesh.always_boolean ? "true" : "false", json_number(s.mesh.index_tolerance), s.seed, fmt::arg("p", pad));
}

}  // namespace ltm
