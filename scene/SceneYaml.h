#pragma once
// A scene written as a scene file (docs/scene-format.md, "Scene files ltmsim writes"): the exact
// inverse of the loader, so that a file written for a generated scene (a dataset sample's
// scene.yaml) renders that very scene again, bit for bit.
//
// The file is complete and fully resolved: every key of every section, defaults included, in the
// format's own names (a window's `thickness`, a sphere's `radius`). Doubles are written in their
// shortest form that reads back to the same bits ("0.1", "1e-05", "-0"), flat radii as `inf`.
// For every scene `s` the loader accepts,
//   parse_scene(scene_to_yaml(s), s.source) == s   in every field, bit for bit,
//   scene_to_yaml(parse_scene(scene_to_yaml(s), f)) == scene_to_yaml(s),
// (tests/scene_yaml.cpp). Scene::source is not written. The output depends on the scene alone
// (a fixed header comment, fixed key order): it is deterministic.
//
// An ellipsoid defect is written with `radius` when it is a sphere without a rotation, else with
// `semi_axes` (and `rotation`, the Euler angles it was given: Defect::rotation_deg). A scratch's
// points carry z only where the scene gave it (Defect::start_has_z and the like).
#include <string>

#include "scene/Scene.h"

namespace ltm {

// Throws std::invalid_argument for a scene that no scene file can express exactly: an ellipsoid
// whose frame is not the rotation of its recorded Euler angles (set it by Defect::set_rotation_deg),
// an index field whose ior is not the object's, a window with curved faces, a sphere that is not
// ball_spec(radius, ior) or has an absorbing rim, a NaN.
std::string scene_to_yaml(const Scene& scene);

}  // namespace ltm
