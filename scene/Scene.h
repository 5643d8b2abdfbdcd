#pragma once
// The whole scene as parsed from a YAML file (docs/scene-format.md): the object, its defects,
// the telecentric camera, the programmable display, meshing options and the seed.
#include <array>
#include <cstdint>
#include <map>
#include <optional>
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

// How each camera sample's paths are generated (the `tracing` section; docs/estimators.md).
//  - Sample: one path per camera sample; at every Fresnel interface it reflects with probability R
//    and transmits with probability T = 1 - R, its weight unchanged; Russian roulette from
//    TracerOptions::rr_depth.
//  - Split: the first split_depth Fresnel interactions of a path (total internal reflection is no
//    choice and does not count) follow both branches, the reflected one with its weight times R,
//    the transmitted one times T; beyond them each branch continues as Sample does.
enum class Estimator { Sample, Split };
inline const char* to_string(Estimator e) { return e == Estimator::Split ? "split" : "sample"; }
// The deepest split the tracer supports: a sample has at most 2^depth branches, and the tracer's
// fixed stack of pending branches holds depth states (trace/Tracer.cpp, sample_paths).
constexpr int kMaxSplitDepth = 16;
// With estimator: split and no split_depth: the direct image and the first ghost of a window or
// lens (front, back, front, back: four interactions) are followed exactly.
constexpr int kDefaultSplitDepth = 4;

struct TracingDesc {
    Estimator estimator = Estimator::Sample;
    int split_depth = kDefaultSplitDepth;  // used by Split only
};

// Where a value sits in a scene's file: 1-based line and column, as an editor shows them.
struct SourceLocation {
    int line = 0, column = 0;
};

struct Scene {
    std::string source;                        // the file it was read from
    ObjectDesc object;
    std::vector<Defect> defects;
    CameraDesc camera;
    DisplayDesc display;
    MeshOptions mesh;
    TracingDesc tracing;
    std::uint64_t seed = 1;
    // The seed of the deflection map's golden reference (study/SceneRun.h): when given, every scene
    // of the same object with the same reference_seed is measured against the same reference,
    // whatever its own seed (a dataset's samples); when not, one derived from `seed`.
    std::optional<std::uint64_t> reference_seed;

    // Where the file gave each value, by key path from the scene's root ("object.diameter",
    // "camera.size", "defects[2]" for a defect's mapping, "defects[2].radius"), and the scene's
    // own key path in its document ("scene" for a dataset spec's inline scene, else ""): problems
    // found after loading are located as the loader's own (scene_error, scene/SceneLoader.h).
    // Empty for a scene made in memory.
    std::map<std::string, SourceLocation> locations;
    std::string key_prefix;
    // What the loader found odd but possible (docs/scene-format.md, "Warnings"): one line each,
    // "FILE:LINE:COLUMN: warning: KEY: message". The commands print them to stderr.
    std::vector<std::string> warnings;
};

}  // namespace ltm
