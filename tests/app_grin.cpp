// The command line with graded-index glass and inhomogeneities: closed-form fields run no TetGen
// (and say so), a smooth inclusion runs one TetGen stage and its paths stay whole (no lost paths,
// no broken invariant), `mesh` writes the tetrahedra as VTU and the region into the PLY, results
// do not depend on the thread count, and bad input or a TetGen failure exits 2 naming the key or
// the defect, with nothing written.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "geometry/MeshExport.h"
#include "tests/SceneFixture.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::Capture;
using ltm::test::Outcome;
using ltm::test::slurp;

Outcome ltmsim(const std::string& args, const fs::path& dir) { return ltm::test::ltmsim(args, dir, Capture::StderrOnly); }

const char* const kInclusion = ltm::test::kSmallSmoothInclusion;

// The same inclusion clipped by the front face (its centre 0.5 mm below it): rays from the air
// meet the part of its boundary outside the glass (no medium change there) and enter it through
// the face (into its medium, not the plain glass's).
const char* kClippedInclusion = R"(
object: {type: window, thickness: 4.0, diameter: 12.0, ior: 1.5}
defects:
  - {type: inhomogeneity, center: [0.2, -0.1, -1.5], radius: 1.5, delta_n: 0.02, profile: smooth}
camera: {resolution: [24, 24], size: [6.0, 6.0], numerical_aperture: 0.002, samples_per_pixel: 4}
display: {resolution: [100, 100], size: [50.0, 50.0], z: 40.0}
mesh: {index_tolerance: 2e-3}
)";

const char* kLuneburg = R"(
object:
  type: sphere
  radius: 5.0
  ior: 1.4142135623730951
  index_field: {type: spherical_n2, g: 0.1414213562373095}
camera: {resolution: [24, 24], size: [10.0, 10.0], numerical_aperture: 0.002, samples_per_pixel: 4}
display: {resolution: [100, 100], size: [50.0, 50.0], z: 40.0}
)";

// The integer value of `key` in run.json (its path statistics).
long stat(const std::string& json, const std::string& key) {
    std::smatch m;
    if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([0-9]+)"))) return -1;
    return std::stol(m[1]);
}

class GrinCommands : public ltm::test::TempDirTest {};

}  // namespace

TEST_F(GrinCommands, ClosedFormFieldsRunNoTetGen) {
    write("lun.yaml", kLuneburg);
    const Outcome r = ltmsim("render " + path("lun.yaml") + " -o " + path("out") + " --verbose", dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("(no TetGen ran)"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("(no Boolean ran)"), std::string::npos) << r.err;
    const std::string run = slurp(dir / "out" / "run.json");
    EXPECT_GT(stat(run, "grin_segments"), 0);
    EXPECT_EQ(stat(run, "lost"), 0);
    EXPECT_EQ(stat(run, "hamiltonian_violations"), 0);
    EXPECT_EQ(stat(run, "nan_events"), 0);
}

TEST_F(GrinCommands, SmoothInclusionRunsOneTetGenStageAndLosesNoPath) {
    for (const char* scene : {kInclusion, kClippedInclusion}) {
        SCOPED_TRACE(scene == kInclusion ? "enclosed" : "clipped by the front face");
        fs::remove_all(dir / "out");
        write("incl.yaml", scene);
        const Outcome r = ltmsim("render " + path("incl.yaml") + " -o " + path("out") + " --verbose", dir);
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_TRUE(std::regex_search(r.err, std::regex("tetgen .*defects\\[0\\]: [0-9]+ tetrahedra"))) << r.err;
        EXPECT_EQ(r.err.find("(no TetGen ran)"), std::string::npos) << r.err;
        const std::string run = slurp(dir / "out" / "run.json");
        EXPECT_GT(stat(run, "tet_crossings"), 0);
        EXPECT_EQ(stat(run, "lost"), 0);
        EXPECT_EQ(stat(run, "hamiltonian_violations"), 0);
        EXPECT_EQ(stat(run, "walk_boundary_exits"), 0);
        EXPECT_EQ(stat(run, "nan_events"), 0);
        // And the paths agree with the independent graded-index reference.
        EXPECT_EQ(ltmsim("validate " + path("incl.yaml"), dir).status, 0);
    }
}

TEST_F(GrinCommands, TheMatrixDoesNotDependOnThreads) {
    for (const char* scene : {kInclusion, kLuneburg}) {
        write("s.yaml", scene);
        ASSERT_EQ(ltmsim("render " + path("s.yaml") + " -o " + path("t1") + " --threads 1 --overwrite", dir).status, 0);
        ASSERT_EQ(ltmsim("render " + path("s.yaml") + " -o " + path("t2") + " --threads 2 --overwrite", dir).status, 0);
        EXPECT_EQ(slurp(dir / "t1" / "ltm.npz"), slurp(dir / "t2" / "ltm.npz"));
    }
}

TEST_F(GrinCommands, MeshWritesTheTetrahedraAndTheRegion) {
    write("incl.yaml", kInclusion);
    const Outcome r = ltmsim("mesh " + path("incl.yaml") + " -o " + path("m.ply"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string vtu = slurp(dir / "m.vtu");
    EXPECT_NE(vtu.find("<UnstructuredGrid>"), std::string::npos);
    EXPECT_NE(vtu.find("Name=\"n\""), std::string::npos);
    // The PLY holds the window's faces and the region's boundary, tagged as the inhomogeneity.
    const ltm::MeshFileSummary s = ltm::read_mesh_summary(path("m.ply"));
    bool region = false;
    for (const std::string& c : s.comments) region = region || c.find("inhomogeneity 0") != std::string::npos;
    EXPECT_TRUE(region);
}

TEST_F(GrinCommands, BadFieldsExitTwoAndWriteNothing) {
    write("bad.yaml",
          "object:\n  type: sphere\n  radius: 10\n  ior: 1.4142135623730951\n  index_field: {type: spherical_n2, g: 0.08}\n");
    const Outcome r = ltmsim("render " + path("bad.yaml") + " -o " + path("out"), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("bad.yaml:5:16: object.index_field: n = 0.848528"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST_F(GrinCommands, TetGenFailureNamesTheDefectAndWritesNothing) {
    // A tolerance so fine that the mesh would exceed its size limit: refused before TetGen runs
    // out of memory, reported with the defect, exit 2, no output.
    std::string scene = kInclusion;
    scene.replace(scene.find("2e-3"), 4, "1e-9");
    write("fine.yaml", scene);
    const Outcome r = ltmsim("render " + path("fine.yaml") + " -o " + path("out"), dir);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("defects[0]"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("max_tets"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
}
