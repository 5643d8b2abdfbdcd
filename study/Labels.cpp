#include "study/Labels.h"

#include <cmath>
#include <filesystem>
#include <fmt/format.h>

#include "io/Image.h"
#include "features/Plot.h"
#include "study/Coco.h"

namespace ltm {

namespace fs = std::filesystem;
using json = io::Json;

int coco_category(DefectType kind) {
    switch (kind) {
        case DefectType::Bubble: return 1;
        case DefectType::Scratch: return 2;
        case DefectType::Particle: return 3;
        case DefectType::Inhomogeneity: return 4;
    }
    return 0;
}

namespace {

json vec(const Vec3& v) { return json::array({v.x, v.y, v.z}); }
json vec2(const Vec3& v) { return json::array({v.x, v.y}); }

}  // namespace

json defect_parameters(const Lens& lens, const Defect& d) {
    json p;
    if (d.type == DefectType::Scratch) {
        p["surface"] = d.side == 0 ? "front" : "back";
        p["shape"] = d.arc ? "arc" : "straight";
        if (d.arc) {
            p["arc"] = {{"center", vec2(d.arc_center)}, {"radius", d.arc_radius}, {"start_angle", d.start_angle},
                        {"end_angle", d.end_angle}};
            p["length"] = d.arc_radius * (d.end_angle - d.start_angle) * kPi / 180.0;
        } else {
            p["start"] = vec2(d.start);
            p["end"] = vec2(d.end);
            p["length"] = std::hypot(d.end.x - d.start.x, d.end.y - d.start.y);  // in the xy-projection
        }
        p["width"] = d.width;
        p["depth"] = d.depth;
        p["profile"] = d.profile == ScratchProfile::V ? "V" : "U";
        p["size"] = d.width;
        return p;
    }
    p["center"] = vec(d.center);
    if (d.is_sphere() && !d.rotation_given) p["radius"] = d.semi_axes.x;
    else p["semi_axes"] = vec(d.semi_axes);
    if (d.rotation_given) p["rotation"] = vec(d.rotation_deg);
    if (d.type == DefectType::Bubble) p["surface_breaking"] = d.surface_breaking;
    if (d.type == DefectType::Inhomogeneity) {
        p["delta_n"] = d.delta_n;
        p["profile"] = d.index_profile == IndexProfile::Smooth ? "smooth" : "uniform";
    }
    p["size"] = d.max_semi_axis();
    p["depth_below_front"] = d.center.z - lens.z_front(std::hypot(d.center.x, d.center.y));
    return p;
}

std::string sample_labels_json(const DatasetSpec& spec, const SampleDraw& s, const SceneRun& run, const GroundTruth& g) {
    const Scene& scene = s.scene;
    const Lens lens(scene.object.lens);
    json j;
    j["sample"] = s.index;
    j["seed"] = s.seed;
    j["split"] = s.split;
    j["defect_free"] = scene.defects.empty();
    j["image"] = {{"width", g.width}, {"height", g.height}};
    j["ground_truth"] = {{"min_fraction", g.min_fraction},
                         {"samples_per_pixel", scene.camera.samples_per_pixel},
                         {"rule", "camera pixel k belongs to defect j when at least min_fraction of its paths meet j "
                                  "before any other defect; contested pixels go to the defect most paths meet"}};
    const auto& L = scene.object.lens;
    j["object"] = {{"r1", std::isinf(L.r1) ? json("inf") : json(L.r1)},
                   {"r2", std::isinf(L.r2) ? json("inf") : json(L.r2)},
                   {"center_thickness", L.center_thickness},
                   {"diameter", L.diameter},
                   {"ior", L.ior}};
    if (!s.object_sampled.empty()) j["object_sampled"] = s.object_sampled;
    j["representation"] = to_string(run.representation);
    json defects = json::array();
    for (size_t k = 0; k < scene.defects.size(); ++k) {
        const DefectLabel& l = g.defects[k];
        json d;
        d["id"] = l.id;
        d["kind"] = to_string(l.kind);
        d["spec_entry"] = s.kinds[k];
        d["parameters"] = defect_parameters(lens, scene.defects[k]);
        d["sampled"] = s.sampled[k];
        d["bbox"] = json::array({l.bbox[0], l.bbox[1], l.bbox[2], l.bbox[3]});
        d["pixel_area"] = l.pixel_area;
        d["visibility"] = l.visibility;
        d["footprint"] = l.footprint;
        d["path_pixels"] = l.path_pixels;
        d["max_fraction"] = l.max_fraction;
        d["segmentation"] = {{"size", json::array({g.height, g.width})},
                             {"counts", coco_rle_string(coco_rle_counts(g.mask, g.width, g.height,
                                                                        static_cast<std::uint16_t>(l.id)))}};
        defects.push_back(std::move(d));
    }
    j["defects"] = std::move(defects);
    (void)spec;
    return j.dump(2) + "\n";
}

json coco_annotations(const std::vector<json>& labels) {
    json out;
    out["info"] = {{"description", "ltmsim defect dataset (features of light transport matrices)"},
                   {"version", "1"},
                   {"contributor", "ltmsim"}};
    out["licenses"] = json::array();
    json images = json::array(), annotations = json::array();
    long next_id = 1;
    for (const json& L : labels) {
        const long i = L["sample"].get<long>();
        const std::string folder = "samples/" + fmt::format("{:06d}", i);
        images.push_back({{"id", i},
                          {"file_name", folder + "/features.exr"},
                          {"width", L["image"]["width"]},
                          {"height", L["image"]["height"]},
                          {"mask_file", folder + "/mask.png"},
                          {"arrays_file", folder + "/features.npz"},
                          {"split", L["split"]},
                          {"seed", L["seed"]}});
        for (const json& d : L["defects"]) {
            if (d["pixel_area"].get<long>() == 0) continue;  // not visible at this resolution
            const auto& b = d["bbox"];
            json a;
            a["id"] = next_id++;
            a["image_id"] = i;
            const std::string kind = d["kind"].get<std::string>();
            a["category_id"] = kind == "bubble" ? 1 : kind == "scratch" ? 2 : kind == "particle" ? 3 : 4;
            a["segmentation"] = d["segmentation"];
            a["area"] = d["pixel_area"];
            a["bbox"] = json::array({b[0].get<double>(), b[1].get<double>(), b[2].get<double>(), b[3].get<double>()});
            a["iscrowd"] = 0;
            a["attributes"] = {{"defect_id", d["id"]},
                               {"visibility", d["visibility"]},
                               {"split", L["split"]},
                               {"parameters", d["parameters"]}};
            annotations.push_back(std::move(a));
        }
    }
    out["images"] = std::move(images);
    out["annotations"] = std::move(annotations);
    json cats = json::array();
    for (DefectType t : {DefectType::Bubble, DefectType::Scratch, DefectType::Particle, DefectType::Inhomogeneity})
        cats.push_back({{"id", coco_category(t)}, {"name", to_string(t)}, {"supercategory", "defect"}});
    out["categories"] = std::move(cats);
    return out;
}

void write_previews(const std::string& dir, const FeatureImages& f, const GroundTruth& g, const ImageExtent& camera) {
    fs::create_directories(dir);
    const int scale = std::max(1, 400 / std::max(1, f.width));
    for (const auto& [name, values] : f.channels)
        write_pseudo_colour_png((fs::path(dir) / (name + ".png")).string(), values, f.width, f.height,
                                feature_title(name), NAN, NAN, scale, camera);
    std::vector<float> m(g.mask.begin(), g.mask.end());
    write_pseudo_colour_png((fs::path(dir) / "mask.png").string(), m, g.width, g.height,
                            "instance mask (0: background, k: defect k)", 0.0,
                            std::max<double>(1.0, static_cast<double>(g.defects.size())), scale, camera);
}

}  // namespace ltm
