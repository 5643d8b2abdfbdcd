#pragma once
// Defects drawn from distributions, for datasets and stress tests. Deterministic for a seed on
// every platform: the generator is std::mt19937_64 (fully specified by the standard) and the
// uniform variates are built from its bits here, not by std::uniform_real_distribution (whose
// algorithm is implementation-defined).
#include <cstdint>
#include <functional>
#include <vector>

#include "defects/Defect.h"
#include "geometry/Lens.h"

namespace ltm {

struct BubblePopulation {
    int count = 100;
    double min_radius = 0.02, max_radius = 0.1;  // mm, radius uniform in [min, max]
    double min_clearance = 0.0;                  // mm, from the glass boundary and between bubbles
    std::uint64_t seed = 1;
};

// Spherical bubbles, each with its radius drawn once (uniform in [min, max]) and its centre then
// uniform over where it fits (rejection sampling in the bounding cylinder): strictly inside the
// glass and clear of the others by min_clearance. The radii are uniform whatever the room; throws
// std::runtime_error if a bubble finds no place in 1000 positions.
std::vector<Defect> sample_bubbles(const Lens& lens, const BubblePopulation& p);

// ---- Geometric draws for sampled datasets (study/Sampler.h) ----
// Each takes a source of uniform variates in [0, 1) and consumes a documented number of them, so a
// seeded generator gives the same draws everywhere.
using Uniform01 = std::function<double()>;

// A point uniform over the glass volume: uniform in the bounding cylinder (3 variates per try),
// kept when strictly inside the glass (Lens::signed_distance > 0). Throws std::runtime_error
// after `max_tries` tries (only a degenerate lens gets there).
Vec3 uniform_point_in_glass(const Lens& lens, const Uniform01& u, int max_tries = 100000);

// A point uniform over the area of a face (side 0: front, 1: back), 2 variates. A spherical cap's
// area above height w from its vertex grows linearly in w (Archimedes: area = 2 pi |R| w), so w
// uniform in [0, h] (h the cap's height over rho <= a) and rho = sqrt(w (2|R| - w)) is exact, for
// a ball's hemispheres too; a flat face has rho = a sqrt(u). The azimuth is uniform.
struct FacePoint {
    Vec3 point;    // on the face
    Vec3 inward;   // the unit normal into the glass
};
FacePoint uniform_point_on_face(const Lens& lens, int side, const Uniform01& u);

// A rotation uniform over SO(3) (Shoemake 1992: a uniform unit quaternion from 3 variates), as
// the Euler angles in degrees that rotation_from_euler_deg (geometry/Vec3.h) turns back into it:
// R = Rz(c) Ry(b) Rx(a), b in [-90, 90], a, c in (-180, 180].
Vec3 uniform_rotation_euler_deg(const Uniform01& u);

// The Euler angles (degrees) of a rotation matrix, the inverse of rotation_from_euler_deg
// (b = asin(-R20), a = atan2(R21, R22), c = atan2(R10, R00); at the gimbal lock |R20| = 1 the
// angle a is 0 and c takes the rest).
Vec3 euler_deg_from_rotation(const Mat3& R);

}  // namespace ltm
