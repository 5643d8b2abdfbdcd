#pragma once
// What the camera sees of the object, from their exact lateral extents (docs/scene-format.md,
// "Warnings"). The telecentric camera's pixel footprints tile its field, the rectangle
// |x| <= W/2, |y| <= H/2 (camera.size = [W, H], centred on the axis), N x M of them
// (camera.resolution); the object's lateral extent, its shadow along the axis, is the disc
// rho <= a (a lens's or window's rim, a sphere's equator). Both are centred on the axis, so the
// field always sees the object's centre; what can go wrong is scale: an object smaller than one
// pixel, or a field that sees only a sliver of the object (a length in the wrong unit, typically).
#include <string>
#include <vector>

#include "scene/Scene.h"

namespace ltm {

struct CameraView {
    double object_diameter = 0;               // 2 a, mm
    double pixel_width = 0, pixel_height = 0;  // one footprint: W / N, H / M, mm
    double object_in_pixels = 0;              // the disc's area in footprints: pi a^2 / (W H / (N M))
    double seen_fraction = 0;                 // area(field and disc) / area(disc), in [0, 1]
};

CameraView camera_view(const ObjectDesc& object, const CameraDesc& camera);

// An object whose disc covers less than one footprint's area gives at most a pixel's worth of
// image (the issue this catches: the default lens written in metres, 0.008 of a 0.25 mm pixel).
constexpr double kMinObjectPixels = 1.0;
// A field that sees less than this fraction of the disc sees a sliver: a square field a hundredth
// of the object's diameter across sees 1.3e-4 of it; one written in metres for a 25 mm lens,
// 1.3e-6. A line-scan field across the whole object (25 x 0.025 mm) sees 1.3e-3 and passes.
constexpr double kMinSeenFraction = 1e-4;

// One warning about the view: the key it is about (a key path from the scene's root) and the
// message, naming the sizes and the likely unit slip.
struct ViewWarning {
    std::string key, message;
};
// The object smaller than one pixel (kMinObjectPixels), reported at the object's size key
// (object.diameter; object.radius for a sphere); the field seeing a sliver (kMinSeenFraction), at
// camera.size when the file gives it (`camera_size_given`), else at the object's size key.
std::vector<ViewWarning> view_warnings(const ObjectDesc& object, const CameraDesc& camera, bool camera_size_given);

}  // namespace ltm
