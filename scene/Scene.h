#pragma once
// The whole scene as parsed from a YAML file (docs/scene-format.md): the object, its defects,
// the telecentric camera, the programmable display, meshing options and the seed.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "defects/Defect.h"
#include "defects/SolidBuilder.h"
#include "geometry/IndexField.h"
#include "geometry/Lens.h"

namespace ltm {

enum class ObjectType { Lens, Window, Sphere };
enum class RimFinish { Polished, Absorbing };

struct ObjectDesc {
    ObjectType type = ObjectType::Lens;
    LensSpec lens;                   // a window is a lens with r1 = r2 = inf; a sphere is ball_spec(R)
    RimFinish rim = RimFinish::Polished;
    double absorption = 0.0;         // Beer-Lambert attenuation coefficient of the glass, 1/mm
    IndexField index_field;          // Uniform (n = lens.ior everywhere) unless the scene gives one
};

struct CameraDesc {
    std::array<int, 2> resolution{100, 100};   // [columns N, rows M]
    std::array<double, 2> size{25.0, 25.0};    // [width, height], mm
    double numerical_aperture = 0.01;
    int samples_per_pixel = 64;
    double focus_z = 0.0;                      // mm, the plane the pixel footprints are defined on
};

struct DisplayDesc {
    std::array<int, 2> resolution{500, 500};   // [columns Q, rows P]
    std::array<double, 2> size{100.0, 100.0};  // [width, height], mm
    double z = 60.0;                           // mm
};

struct Scene {
    std::string source;                        // the file it was read from
    ObjectDesc object;
    std::vector<Defect> defects;
    CameraDesc camera;
    DisplayDesc display;
    MeshOptions mesh;
    std::uint64_t seed = 1;
};

}  // namespace ltm
