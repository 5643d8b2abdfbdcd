#include "scene/SceneYaml.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace ltm {

namespace {

[[noreturn]] void unwritable(const std::string& what) {
    throw std::invalid_argument("scene_to_yaml: " + what + ": no scene file can express it exactly");
}

// Bit equality: -0 and 0 differ, as they would after a round trip.
bool same_bits(double a, double b) {
    std::uint64_t x = 0, y = 0;
    std::memcpy(&x, &a, sizeof x);
    std::memcpy(&y, &b, sizeof y);
    return x == y;
}

bool same_bits(const Mat3& a, const Mat3& b) {
    for (std::size_t i = 0; i < 9; ++i)
        if (!same_bits(a.m[i], b.m[i])) return false;
    return true;
}

bool same_bits(const LensSpec& a, const LensSpec& b) {
    return same_bits(a.r1, b.r1) && same_bits(a.r2, b.r2) && same_bits(a.center_thickness, b.center_thickness) &&
           same_bits(a.diameter, b.diameter) && same_bits(a.ior, b.ior) && a.ball == b.ball;
}

// A double that the loader reads back to the same bits: fmt's shortest round-trip form ("0.1",
// "1e-05", "-0", "5e-324") is a YAML 1.2 float the loader parses with from_chars, which rounds
// correctly. Infinity is written `inf`.
std::string num(double v, const std::string& path) {
    if (std::isnan(v)) unwritable(path + " is NaN");
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return fmt::format("{}", v);
}

std::string vec3(const Vec3& v, const std::string& path) {
    return fmt::format("[{}, {}, {}]", num(v.x, path), num(v.y, path), num(v.z, path));
}

// A face point: [x, y, z] if the scene gave z, else [x, y] (the loader takes the face's z).
std::string point(const Vec3& v, bool has_z, const std::string& path) {
    if (has_z) return vec3(v, path);
    return fmt::format("[{}, {}]", num(v.x, path), num(v.y, path));
}

const char* boolean(bool b) { return b ? "true" : "false"; }

// Lines of a block mapping; `indent` spaces before each key.
class Out {
public:
    void put(int indent, const std::string& key, const std::string& value) {
        text_ += std::string(static_cast<std::size_t>(indent), ' ') + key + ": " + value + "\n";
    }
    void open(int indent, const std::string& key) {
        text_ += std::string(static_cast<std::size_t>(indent), ' ') + key + ":\n";
    }
    void raw(const std::string& s) { text_ += s; }
    std::size_t size() const { return text_.size(); }
    // Turns the two spaces before column `at + 2` into "- ": the first key of a list item.
    void dash(std::size_t at) { text_.replace(at + 2, 2, "- "); }
    const std::string& text() const { return text_; }

private:
    std::string text_;
};

void write_index_field(Out& out, const IndexField& f) {
    if (!f.graded()) return;
    const std::string p = "object.index_field";
    out.open(2, "index_field");
    out.put(4, "type", to_string(f.type));
    switch (f.type) {
        case IndexFieldType::RadialN2:
        case IndexFieldType::SphericalN2: out.put(4, "g", num(f.g, p + ".g")); break;
        case IndexFieldType::QuadraticN2: {
            out.put(4, "gradient", vec3(f.gradient, p + ".gradient"));
            std::string rows;
            for (int r = 0; r < 3; ++r)
                rows += (r ? ", " : "") + vec3({f.hessian(r, 0), f.hessian(r, 1), f.hessian(r, 2)}, p + ".hessian");
            out.put(4, "hessian", "[" + rows + "]");
            break;
        }
        default: out.put(4, "gradient", vec3(f.gradient, p + ".gradient")); break;
    }
}

void write_object(Out& out, const ObjectDesc& o) {
    const LensSpec& L = o.lens;
    if (!same_bits(o.index_field.ior, L.ior))
        unwritable(fmt::format("object.index_field.ior {} differs from object.ior {}", o.index_field.ior, L.ior));
    out.open(0, "object");
    switch (o.type) {
        case ObjectType::Lens:
            if (L.ball) unwritable("a lens with LensSpec::ball set (a ball is object type sphere)");
            out.put(2, "type", "lens");
            out.put(2, "r1", num(L.r1, "object.r1"));
            out.put(2, "r2", num(L.r2, "object.r2"));
            out.put(2, "center_thickness", num(L.center_thickness, "object.center_thickness"));
            out.put(2, "diameter", num(L.diameter, "object.diameter"));
            break;
        case ObjectType::Window:
            if (L.ball || !(std::isinf(L.r1) && L.r1 > 0 && std::isinf(L.r2) && L.r2 > 0))
                unwritable("a window whose faces are not flat (r1 = r2 = inf)");
            out.put(2, "type", "window");
            out.put(2, "thickness", num(L.center_thickness, "object.thickness"));
            out.put(2, "diameter", num(L.diameter, "object.diameter"));
            break;
        case ObjectType::Sphere:
            if (!same_bits(L, ball_spec(L.r1, L.ior))) unwritable("a sphere whose lens is not ball_spec(radius, ior)");
            if (o.rim != RimFinish::Polished) unwritable("a sphere with an absorbing rim (a sphere has no rim)");
            out.put(2, "type", "sphere");
            out.put(2, "radius", num(L.r1, "object.radius"));
            break;
    }
    out.put(2, "ior", num(L.ior, "object.ior"));
    if (o.type != ObjectType::Sphere) out.put(2, "rim", o.rim == RimFinish::Polished ? "polished" : "absorbing");
    out.put(2, "absorption", num(o.absorption, "object.absorption"));
    write_index_field(out, o.index_field);
}

void write_ellipsoid(Out& out, const Defect& d, const std::string& p) {
    const Mat3 frame = d.rotation_given ? rotation_from_euler_deg(d.rotation_deg) : Mat3::identity();
    if (!same_bits(d.frame, frame))
        unwritable(p + ".frame is not the rotation of its Euler angles (orient a defect by Defect::set_rotation_deg)");
    out.put(4, "center", vec3(d.center, p + ".center"));
    if (d.is_sphere() && !d.rotation_given) {
        out.put(4, "radius", num(d.semi_axes.x, p + ".radius"));
    } else {
        out.put(4, "semi_axes", vec3(d.semi_axes, p + ".semi_axes"));
        if (d.rotation_given) out.put(4, "rotation", vec3(d.rotation_deg, p + ".rotation"));
    }
    switch (d.type) {
        case DefectType::Bubble: out.put(4, "surface_breaking", boolean(d.surface_breaking)); break;
        case DefectType::Inhomogeneity:
            out.put(4, "delta_n", num(d.delta_n, p + ".delta_n"));
            out.put(4, "profile", d.index_profile == IndexProfile::Smooth ? "smooth" : "uniform");
            break;
        default: break;
    }
}

void write_scratch(Out& out, const Defect& d, const std::string& p) {
    out.put(4, "surface", d.side == 0 ? "front" : "back");
    out.put(4, "width", num(d.width, p + ".width"));
    out.put(4, "depth", num(d.depth, p + ".depth"));
    out.put(4, "profile", d.profile == ScratchProfile::V ? "V" : "U");
    if (!d.arc) {
        out.put(4, "start", point(d.start, d.start_has_z, p + ".start"));
        out.put(4, "end", point(d.end, d.end_has_z, p + ".end"));
        return;
    }
    out.open(4, "arc");
    out.put(6, "center", point(d.arc_center, d.arc_center_has_z, p + ".arc.center"));
    out.put(6, "radius", num(d.arc_radius, p + ".arc.radius"));
    out.put(6, "start_angle", num(d.start_angle, p + ".arc.start_angle"));
    out.put(6, "end_angle", num(d.end_angle, p + ".arc.end_angle"));
}

void write_defects(Out& out, const std::vector<Defect>& defects) {
    if (defects.empty()) {
        out.put(0, "defects", "[]");
        return;
    }
    out.open(0, "defects");
    for (std::size_t i = 0; i < defects.size(); ++i) {
        const Defect& d = defects[i];
        const std::string p = fmt::format("defects[{}]", i);
        const std::size_t first = out.size();
        out.put(4, "type", to_string(d.type));
        out.dash(first);
        if (d.is_ellipsoid())
            write_ellipsoid(out, d, p);
        else
            write_scratch(out, d, p);
    }
}

}  // namespace

std::string scene_to_yaml(const Scene& s) {
    Out out;
    out.raw("# A scene written by ltmsim: every key resolved, defaults included (docs/scene-format.md).\n");
    write_object(out, s.object);
    write_defects(out, s.defects);

    const CameraDesc& c = s.camera;
    out.open(0, "camera");
    out.put(2, "resolution", fmt::format("[{}, {}]", c.resolution[0], c.resolution[1]));
    out.put(2, "size", fmt::format("[{}, {}]", num(c.size[0], "camera.size"), num(c.size[1], "camera.size")));
    out.put(2, "numerical_aperture", num(c.numerical_aperture, "camera.numerical_aperture"));
    out.put(2, "samples_per_pixel", fmt::format("{}", c.samples_per_pixel));
    out.put(2, "focus_z", num(c.focus_z, "camera.focus_z"));

    const DisplayDesc& d = s.display;
    out.open(0, "display");
    out.put(2, "resolution", fmt::format("[{}, {}]", d.resolution[0], d.resolution[1]));
    out.put(2, "size", fmt::format("[{}, {}]", num(d.size[0], "display.size"), num(d.size[1], "display.size")));
    out.put(2, "z", num(d.z, "display.z"));

    const MeshOptions& m = s.mesh;
    out.open(0, "mesh");
    out.put(2, "chord_tolerance", num(m.chord_tolerance, "mesh.chord_tolerance"));
    out.put(2, "defect_relative_tolerance", num(m.defect_relative_tolerance, "mesh.defect_relative_tolerance"));
    out.put(2, "always_boolean", boolean(m.always_boolean));
    out.put(2, "index_tolerance", num(m.index_tolerance, "mesh.index_tolerance"));

    // Only the split estimator has keys to write: the loader rejects split_depth with sample, and
    // a sample scene's split_depth means nothing, so a sample scene is written without the section
    // (the sample estimator is the default).
    if (s.tracing.estimator == Estimator::Split) {
        out.open(0, "tracing");
        out.put(2, "estimator", to_string(s.tracing.estimator));
        out.put(2, "split_depth", fmt::format("{}", s.tracing.split_depth));
    }

    out.put(0, "seed", fmt::format("{}", s.seed));
    if (s.reference_seed) out.put(0, "reference_seed", fmt::format("{}", *s.reference_seed));
    return out.text();
}

}  // namespace ltm
