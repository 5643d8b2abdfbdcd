#include "trace/Media.h"

#include <cmath>
#include <fmt/format.h>

namespace ltm {

MediaTable::~MediaTable() = default;

MediaTable::MediaTable(const Scene& scene, const Solid& solid, const std::vector<Patch>& object_patches,
                       const std::vector<Patch>& ellipsoids) {
    const Lens lens(scene.object.lens);
    const IndexField& field = scene.object.index_field;
    media_.resize(3 + scene.defects.size());
    media_[Medium::Air.id] = {"air", Propagation::Straight, 1.0, false, nullptr, nullptr};
    media_[Medium::Absorber.id] = {"absorber", Propagation::Absorbing, 1.0, false, nullptr, nullptr};
    MediumInfo& glass = media_[Medium::Glass.id];
    glass = {"glass", Propagation::Straight, lens.spec().ior, true, nullptr, nullptr};
    // The object's bounding sphere about the origin (its farthest point is a vertex or an edge).
    const double a = lens.aperture_radius();
    const double zmax = std::max({std::fabs(lens.z_front(0)), std::fabs(lens.z_back(0)), std::fabs(lens.z_front(a)),
                                  std::fabs(lens.z_back(a))});
    const double radius = std::hypot(a, zmax);

    auto region_walk = [&](int defect, std::vector<Patch> surfaces) -> const TetWalk* {
        for (size_t i = 0; i < solid.regions.size(); ++i)
            if (solid.region_defect[i] == defect) {
                walks_.push_back(std::make_unique<TetWalk>(solid.regions[i], std::move(surfaces)));
                return walks_.back().get();
            }
        throw std::logic_error(fmt::format("no tetrahedral region was built for {}",
                                           defect < 0 ? std::string("the object") : fmt::format("defects[{}]", defect)));
    };
    if (field.graded()) {
        graded_ = true;
        if (field.closed_form()) {
            grin_ = std::make_unique<GrinField>(field.n2_form(), index_range(lens, field).n2_max, radius);
            glass.propagation = Propagation::Grin;
            glass.grin = grin_.get();
        } else {
            std::vector<Patch> surfaces = object_patches;
            surfaces.insert(surfaces.end(), ellipsoids.begin(), ellipsoids.end());
            glass.propagation = Propagation::TetWalk;
            glass.walk = region_walk(-1, std::move(surfaces));
        }
    }
    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const Defect& d = scene.defects[k];
        MediumInfo& m = media_[Medium::inclusion(static_cast<int>(k)).id];
        if (d.type != DefectType::Inhomogeneity) {
            m.name = "(unused)";
            continue;
        }
        m.name = fmt::format("inhomogeneity {}", k);
        m.attenuates = true;
        if (d.index_profile == IndexProfile::Uniform) {
            m.propagation = Propagation::Straight;
            m.index = lens.spec().ior + d.delta_n;
            continue;
        }
        // The region's own ellipsoid (where paths hand over to the glass) and the object's faces
        // (where the region is clipped by the glass).
        std::vector<Patch> surfaces = object_patches;
        for (const Patch& e : ellipsoids)
            if (solid.surfaces[e.tag].defect == static_cast<int>(k)) surfaces.push_back(e);
        m.propagation = Propagation::TetWalk;
        m.walk = region_walk(static_cast<int>(k), std::move(surfaces));
        graded_ = true;
    }
}

}  // namespace ltm
