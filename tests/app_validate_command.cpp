// The `ltmsim validate` command's contract (docs: docs/conventions.md, "Command line"):
// traced paths against analytic Snell's-law solutions, non-zero exit above tolerance. Every
// shipped scene the analytic reference models passes (exit 0, "PASSED"), as do the paper's lens
// scaled by 1e-3 and 1e3 (the tolerances scale with the scene's length scale,
// validation/ValidationTolerance.h); the output carries the mesh-only comparison; a scene the
// reference does not model (a pit, a scratch) exits 2 with "no analytic reference".
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::Outcome;

class ValidateCommand : public ltm::test::TempDirTest {
protected:
    // `ltmsim validate SCENE`, capturing stdout and stderr.
    Outcome validate(const std::string& scene) { return ltm::test::ltmsim("validate '" + scene + "'", dir); }
    void expect_passes(const std::string& scene) {
        SCOPED_TRACE(scene);
        const Outcome r = validate(scene);
        EXPECT_EQ(r.status, 0) << r.out << r.err;
        // The verdict (on the chosen, refined representation) comes first, then the mesh-only
        // comparison section, which has no verdict of its own.
        const size_t mesh = r.out.find("without refinement");
        ASSERT_NE(mesh, std::string::npos) << r.out;
        const std::string verdict = r.out.substr(0, mesh);
        EXPECT_NE(verdict.find("PASSED"), std::string::npos) << r.out;
        EXPECT_EQ(verdict.find("FAILED"), std::string::npos) << r.out;
        EXPECT_NE(r.out.find("mesh-only", mesh), std::string::npos) << r.out;
    }
    static std::string source(const std::string& rel) { return ltm::test::source_dir() + "/scenes/" + rel; }
};

// The default scene (the paper's lens with three bubbles) scaled by s: every length (radii,
// thicknesses, diameter, defect centres and radii, camera field, display size and distance, and
// the mesh's absolute chord tolerance) times s; dimensionless values (ior, NA, resolutions,
// relative tolerances) unchanged.
std::string scaled_paper_lens(double s) {
    std::ostringstream y;
    y.precision(17);
    y << "object: {type: lens, r1: " << 50 * s << ", r2: " << -50 * s << ", center_thickness: " << 6 * s
      << ", diameter: " << 25 * s << ", ior: 1.5168}\n"
      << "defects:\n";
    for (double x : {0.0, 4.0, 8.0})
        y << "  - {type: bubble, center: [" << x * s << ", 0.0, 0.0], radius: " << 0.1 * s << "}\n";
    y << "camera: {resolution: [100, 100], size: [" << 25 * s << ", " << 25 * s
      << "], numerical_aperture: 0.01, samples_per_pixel: 64}\n"
      << "display: {resolution: [500, 500], size: [" << 100 * s << ", " << 100 * s << "], z: " << 60 * s << "}\n"
      << "mesh: {chord_tolerance: " << 0.001 * s << "}\n"
      << "seed: 1\n";
    return y.str();
}

}  // namespace

TEST_F(ValidateCommand, DefaultScenePasses) { expect_passes(source("default.yaml")); }

TEST_F(ValidateCommand, EveryModelledExamplePasses) {
    for (const char* name : {"plano-convex", "positive-meniscus", "negative-meniscus", "plano-concave", "biconcave",
                             "window", "ellipsoid-bubble", "particle"})
        expect_passes(source(std::string("examples/") + name + ".yaml"));
}

TEST_F(ValidateCommand, ScaledLensesPass) {
    for (double s : {1e-3, 1e3}) {
        SCOPED_TRACE("scale " + std::to_string(s));
        const fs::path scene = dir / "scaled.yaml";
        std::ofstream(scene) << scaled_paper_lens(s);
        expect_passes(scene.string());
    }
}

TEST_F(ValidateCommand, ScenesWithoutAnAnalyticReferenceExitTwo) {
    for (const char* name : {"pit", "scratch-v-front", "scratch-u-arc-back", "overlapping-defects"}) {
        SCOPED_TRACE(name);
        const std::string scene = source(std::string("examples/") + name + ".yaml");
        const Outcome r = validate(scene);
        EXPECT_EQ(r.status, 2) << r.out << r.err;
        EXPECT_NE(r.err.find(scene), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("no analytic reference"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("defects["), std::string::npos) << "the reason names the defect: " << r.err;
        EXPECT_EQ(r.out.find("PASSED"), std::string::npos) << r.out;
    }
}

TEST_F(ValidateCommand, BadSceneExitsTwo) {
    const fs::path bad = dir / "bad.yaml";
    std::ofstream(bad) << "object: {type: lens, r1: 50, r2: -50, center_thickness: 1, diameter: 25, ior: 1.5}\n";
    const Outcome r = validate(bad.string());
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("object.center_thickness"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(validate((dir / "nope.yaml").string()).status, 2);
}
