#pragma once
// The table of analytic surfaces an object is bounded by. A mesh face's tag is an index into
// this table, so every face knows the exact surface it lies on and which media it separates.
//
// Orientation convention: mesh faces are wound counter-clockwise seen from the side their normal
// points to, and that normal points from `inside` to `outside`. For the glass body, outside is
// air (camera side of the front face, the void of a bubble); for an absorbing particle, inside is
// the particle and outside the glass.
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/Surface.h"

namespace ltm {

// A medium: an index into the scene's table of media (trace/Media.h says, per medium, its index of
// refraction and how rays propagate through it). Three are always there; an inhomogeneity
// defect k brings its own, Medium::inclusion(k).
struct Medium {
    std::uint16_t id = 0;
    static const Medium Air, Glass, Absorber;
    static constexpr Medium inclusion(int defect) { return Medium{static_cast<std::uint16_t>(3 + defect)}; }
    constexpr bool operator==(Medium o) const { return id == o.id; }
    constexpr bool operator!=(Medium o) const { return id != o.id; }
    // The inhomogeneity defect this medium belongs to, or -1.
    constexpr int defect() const { return id >= 3 ? id - 3 : -1; }
};
inline constexpr Medium Medium::Air{0};
inline constexpr Medium Medium::Glass{1};
inline constexpr Medium Medium::Absorber{2};
std::string to_string(Medium m);  // "air", "glass", "absorber", "inhomogeneity 2"

// What part of the object a surface belongs to; also picks its colour in exported meshes.
enum class SurfaceRole : std::uint8_t { Front, Back, Rim, Bubble, Pit, Scratch, Particle, Inhomogeneity };
const char* to_string(SurfaceRole r);

struct SurfaceInfo {
    Surface surface;
    std::string name;       // e.g. "front", "bubble 2", "scratch 0 wall +"
    SurfaceRole role = SurfaceRole::Front;
    int defect = -1;        // index into the scene's defect list, -1 for the object's own faces
    Medium inside = Medium::Glass;
    Medium outside = Medium::Air;
    // Reference-normal sign: +1 when the mesh's outward normal (inside -> outside) agrees with
    // Surface::normal, -1 when it is opposite (e.g. a bubble wall seen from the glass).
    int normal_sign = +1;
    // false: the boundary of a smooth inhomogeneity, where the index is continuous. Rays cross it
    // without refraction or reflection; only the way they propagate changes.
    bool optical = true;
};

struct SurfaceTable {
    std::vector<SurfaceInfo> entries;
    int add(SurfaceInfo info) {
        entries.push_back(std::move(info));
        return static_cast<int>(entries.size()) - 1;
    }
    const SurfaceInfo& operator[](int tag) const { return entries.at(static_cast<size_t>(tag)); }
    size_t size() const { return entries.size(); }
};

// Fixed RGB colour of a role in exported meshes (the legend is written into PLY headers).
std::array<std::uint8_t, 3> role_colour(SurfaceRole r);

}  // namespace ltm
