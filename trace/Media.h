#pragma once
// The table of media a scene's rays travel through (geometry/SurfaceTable.h names them by
// Medium ids), each with its index of refraction and its own step "propagate to the next
// interface" (Tracer::propagate dispatches on it):
//   Straight   a constant index: straight segments (air, homogeneous glass, a uniform inclusion);
//   Grin       a quadratic n^2 over the whole glass: closed-form curved paths (GrinPath.h);
//   TetWalk    a TetGen-meshed field (a smooth inclusion, a linear-n glass): exact parabolas
//              through tetrahedra (TetWalk.h);
//   Absorbing  a particle: paths end on entering it.
#include <memory>
#include <string>
#include <vector>

#include "defects/SolidBuilder.h"
#include "geometry/SurfaceTable.h"
#include "scene/Scene.h"
#include "trace/GrinPath.h"
#include "trace/Patch.h"
#include "trace/TetWalk.h"

namespace ltm {

enum class Propagation : std::uint8_t { Straight, Grin, TetWalk, Absorbing };

struct MediumInfo {
    std::string name;                         // "air", "glass", "inhomogeneity 2"
    Propagation propagation = Propagation::Straight;
    double index = 1;                         // Straight: the constant index
    bool attenuates = false;                  // glass-like: Beer-Lambert with object.absorption
    const GrinField* grin = nullptr;          // Grin
    const TetWalk* walk = nullptr;            // TetWalk
};

class MediaTable {
public:
    // `object_patches`: the object's front, back and rim (Patch.h); `ellipsoids`: the enclosed
    // ellipsoid defects' exact patches (tagged), which the walks of whole-object regions can meet.
    MediaTable(const Scene& scene, const Solid& solid, const std::vector<Patch>& object_patches,
               const std::vector<Patch>& ellipsoids);
    ~MediaTable();
    const MediumInfo& operator[](Medium m) const { return media_.at(m.id); }
    bool graded() const { return graded_; }  // some medium is not Straight / Absorbing
    size_t size() const { return media_.size(); }

private:
    std::vector<MediumInfo> media_;
    std::unique_ptr<GrinField> grin_;
    std::vector<std::unique_ptr<TetWalk>> walks_;
    bool graded_ = false;
};

}  // namespace ltm
