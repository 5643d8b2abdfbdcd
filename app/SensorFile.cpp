#include "app/SensorFile.h"

#include <fmt/format.h>

#include "scene/StrictYaml.h"

namespace ltm::app {

acquire::SensorModel load_sensor_file(const std::string& path) {
    const YAML::Node root = yaml::load_document(path, "sensor file");
    const yaml::Reader r(path);
    acquire::SensorModel m;
    if (!root.IsMap()) r.fail(yaml::loc_of(root), "", fmt::format("expected a mapping with the key sensor, got {}", yaml::describe(root)));
    auto at_least = [&](const yaml::Item& it, const std::string& p, double min, bool strict) {
        const double v = r.number(it.value, it.value_loc(), p);
        if (strict ? !(v > min) : !(v >= min))
            r.fail(it.value_loc(), p, fmt::format("must be {} {} (got {})", strict ? ">" : ">=", min, v));
        return v;
    };
    yaml::KeyRule top;
    top.keys = {"sensor"};
    yaml::Where seen;
    r.walk(root, "", top, [&](const yaml::Item& s) {
        seen[s.key] = s.value_loc();
        r.require_map(s, "sensor");
        yaml::KeyRule sr;
        sr.keys = {"seed", "camera", "display"};
        r.walk(s.value, "sensor", sr, [&](const yaml::Item& it) {
            const std::string p = yaml::join_path("sensor", it.key);
            if (it.key == "seed") {
                m.seed = r.seed(it.value, it.value_loc(), p);
            } else if (it.key == "camera") {
                r.require_map(it, p);
                yaml::KeyRule cr;
                cr.keys = {"full_well", "exposure", "read_noise", "dark_level", "bits"};
                r.walk(it.value, p, cr, [&](const yaml::Item& c) {
                    const std::string q = yaml::join_path(p, c.key);
                    acquire::CameraModel& cam = m.camera;
                    if (c.key == "full_well") cam.full_well = at_least(c, q, 0, true);
                    else if (c.key == "exposure") cam.exposure = at_least(c, q, 0, true);
                    else if (c.key == "read_noise") cam.read_noise = at_least(c, q, 0, false);
                    else if (c.key == "dark_level") cam.dark_level = at_least(c, q, 0, false);
                    else if (c.key == "bits") {
                        cam.bits = static_cast<int>(r.integer(c.value, c.value_loc(), q, 0, 64, "an integer"));
                        if (cam.bits != 8 && cam.bits != 10 && cam.bits != 12 && cam.bits != 16)
                            r.fail(c.value_loc(), q, fmt::format("the camera quantises to 8, 10, 12 or 16 bits (got {})", cam.bits));
                    }
                });
            } else if (it.key == "display") {
                r.require_map(it, p);
                yaml::KeyRule dr;
                dr.keys = {"contrast_ratio", "black_level", "gamma", "bits"};
                yaml::Where given;
                r.walk(it.value, p, dr, [&](const yaml::Item& d) {
                    const std::string q = yaml::join_path(p, d.key);
                    given[d.key] = d.key_loc();
                    if ((d.key == "contrast_ratio" && given.count("black_level")) ||
                        (d.key == "black_level" && given.count("contrast_ratio")))
                        r.fail(d.key_loc(), q, "give contrast_ratio or black_level (= 1 / contrast_ratio), not both");
                    acquire::DisplayModel& dis = m.display;
                    if (d.key == "contrast_ratio") {
                        const double c = r.number(d.value, d.value_loc(), q, /*allow_inf=*/true);
                        if (!(c >= 1)) r.fail(d.value_loc(), q, fmt::format("must be >= 1 (got {}); inf is a perfect black", c));
                        dis.black_level = 1 / c;
                    } else if (d.key == "black_level") {
                        dis.black_level = at_least(d, q, 0, false);
                        if (!(dis.black_level < 1)) r.fail(d.value_loc(), q, fmt::format("must be < 1, the white level (got {})", dis.black_level));
                    } else if (d.key == "gamma") {
                        dis.gamma = at_least(d, q, 0, true);
                    } else if (d.key == "bits") {
                        dis.bits = static_cast<int>(r.integer(d.value, d.value_loc(), q, 1, 16, "an integer in [1, 16]"));
                    }
                });
            }
        });
    });
    r.require_keys(root, "", seen, {"sensor"});
    return m;
}

}  // namespace ltm::app
