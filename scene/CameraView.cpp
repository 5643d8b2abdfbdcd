#include "scene/CameraView.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace ltm {

namespace {

// The area of the unit disc within the rectangle |x| <= u, |y| <= v, as a fraction of the disc's.
// By symmetry it is 4 Q / pi, Q the area of the quarter disc within [0, u] x [0, v]:
//   Q = int_0^min(u, 1) min(v, sqrt(1 - x^2)) dx.
// With G(x) = int_0^x sqrt(1 - t^2) dt = (x sqrt(1 - x^2) + asin x) / 2: for v >= 1 the disc's edge
// is always the lower bound, Q = G(min(u, 1)); else the edge drops below v at x0 = sqrt(1 - v^2),
// Q = v min(u, x0) + (G(min(u, 1)) - G(x0) where u > x0).
double disc_fraction_in_rectangle(double u, double v) {
    auto G = [](double x) { return 0.5 * (x * std::sqrt(std::max(0.0, 1.0 - x * x)) + std::asin(x)); };
    const double um = std::min(u, 1.0);
    double q = 0;
    if (v >= 1.0) {
        q = G(um);
    } else {
        const double x0 = std::sqrt((1.0 - v) * (1.0 + v));
        q = v * std::min(u, x0) + (u > x0 ? std::max(0.0, G(um) - G(x0)) : 0.0);
    }
    return std::clamp(4.0 * q / kPi, 0.0, 1.0);
}

}  // namespace

CameraView camera_view(const ObjectDesc& object, const CameraDesc& camera) {
    CameraView v;
    const double a = 0.5 * object.lens.diameter;  // a sphere's too: ball_spec's diameter is 2 R
    const double W = camera.size[0], H = camera.size[1];
    v.object_diameter = object.lens.diameter;
    v.pixel_width = W / camera.resolution[0];
    v.pixel_height = H / camera.resolution[1];
    // Ratios first, so that no product of lengths over- or underflows for any positive sizes.
    v.object_in_pixels = kPi * (a / v.pixel_width) * (a / v.pixel_height);
    v.seen_fraction = disc_fraction_in_rectangle(0.5 * W / a, 0.5 * H / a);
    return v;
}

std::vector<ViewWarning> view_warnings(const ObjectDesc& object, const CameraDesc& camera, bool camera_size_given) {
    std::vector<ViewWarning> out;
    const CameraView v = camera_view(object, camera);
    const std::string object_key = object.type == ObjectType::Sphere ? "object.radius" : "object.diameter";
    if (v.object_in_pixels < kMinObjectPixels)
        out.push_back({object_key,
                       fmt::format("the object (diameter {:g} mm) is smaller than one camera pixel ({:g} x {:g} mm: "
                                   "camera.size over camera.resolution), {:.3g} of its area; lengths are in mm: were "
                                   "the object's given in metres?",
                                   v.object_diameter, v.pixel_width, v.pixel_height, v.object_in_pixels)});
    if (v.seen_fraction < kMinSeenFraction) {
        const std::string what = fmt::format("the camera's field ({:g} x {:g} mm, centred on the axis) sees {:.3g} of "
                                             "the object's extent (diameter {:g} mm); lengths are in mm: ",
                                             camera.size[0], camera.size[1], v.seen_fraction, v.object_diameter);
        out.push_back(camera_size_given
                          ? ViewWarning{"camera.size", what + "was camera.size given in metres?"}
                          : ViewWarning{object_key, what + "were the object's given in micrometres?"});
    }
    return out;
}

}  // namespace ltm
