// The `ltmsim mesh` command's contract (docs/conventions.md, "Command line"): formats, the stage
// report, exit status 2 with a file:line:key message for bad input, and never a partial file.
#include <gtest/gtest.h>

#include <array>
#include <regex>
#include <set>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "geometry/MeshExport.h"
#include "tests/TestSupport.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::Capture;
using ltm::test::Outcome;
using ltm::test::slurp;

// Runs ltmsim with `args`, capturing stderr (stdout goes to /dev/null).
Outcome ltmsim(const std::string& args, const fs::path& dir) { return ltm::test::ltmsim(args, dir, Capture::StderrOnly); }

class MeshCommand : public ltm::test::TempDirTest {
protected:
    std::string scene(const std::string& rel) { return ltm::test::source_dir() + "/scenes/" + rel; }
    // Everything in dir except the files the test made itself.
    std::vector<std::string> outputs() {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(dir)) {
            const auto n = e.path().filename().string();
            if (n != "stderr.txt" && n.find(".yaml") == std::string::npos && n != "keep.ply") names.push_back(n);
        }
        return names;
    }
};

}  // namespace

TEST_F(MeshCommand, WritesEveryFormatAndReportsStages) {
    for (const char* ext : {"ply", "obj", "off"}) {
        const fs::path out = dir / (std::string("pit.") + ext);
        const Outcome r = ltmsim("mesh " + scene("examples/pit.yaml") + " -o " + out.string() + " --verbose", dir);
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_TRUE(fs::exists(out));
        // The pit breaks the surface: it must go through a Boolean, and --verbose says so.
        EXPECT_NE(r.err.find("boolean"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("tessellate"), std::string::npos);
        const ltm::MeshFileSummary s = ltm::read_mesh_summary(out.string());
        EXPECT_GT(s.faces, 20000u);
    }
}

TEST_F(MeshCommand, DefectFreeSceneRunsNoBoolean) {
    const fs::path stats = dir / "stats.json";
    const Outcome r = ltmsim("mesh " + scene("examples/plano-convex.yaml") + " -o " + (dir / "m.ply").string() +
                             " --stats " + stats.string() + " --verbose",
                         dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string json = slurp(stats);
    EXPECT_NE(json.find("\"stage\": \"tessellate\""), std::string::npos) << json;
    EXPECT_EQ(json.find("\"stage\": \"boolean\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"boolean_operations\": 0"), std::string::npos) << json;
    EXPECT_NE(r.err.find("no Boolean ran"), std::string::npos) << r.err;
}

TEST_F(MeshCommand, PlyCarriesTagsAndLegend) {
    const fs::path out = dir / "d.ply";
    ASSERT_EQ(ltmsim("mesh " + scene("default.yaml") + " -o " + out.string(), dir).status, 0);
    const ltm::MeshFileSummary s = ltm::read_mesh_summary(out.string());
    ASSERT_EQ(s.tags.size(), s.faces);
    // Tags 0..2 are the lens faces; the default scene's three bubbles are 3..5.
    std::set<int> tags(s.tags.begin(), s.tags.end());
    EXPECT_EQ(tags, (std::set<int>{0, 1, 2, 3, 4, 5}));
    bool legend = false;
    for (const auto& c : s.comments) legend = legend || c.find("bubble 2") != std::string::npos;
    EXPECT_TRUE(legend);
}

TEST_F(MeshCommand, BadSceneExitsTwoAndWritesNothing) {
    // A typo in a key: file:line:col, the key path and a suggestion; exit 2; no output.
    const fs::path bad = write("bad.yaml",
                               "object:\n  type: lens\n  r1: 50\n  r2: -50\n  center_thickness: 6\n  diamter: 25\n"
                               "  ior: 1.5\n");
    const Outcome r = ltmsim("mesh " + bad.string() + " -o " + (dir / "m.ply").string(), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(bad.string() + ":6:3: object.diamter: unknown key 'diamter' for a lens (did you mean "
                                        "'diameter'?)"),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(outputs().empty());
}

TEST_F(MeshCommand, ImpossibleGeometryExitsTwo) {
    const fs::path bad = write("thin.yaml",
                               "object: {type: lens, r1: 50, r2: -50, center_thickness: 1, diameter: 25, ior: 1.5}\n");
    const Outcome r = ltmsim("mesh " + bad.string() + " -o " + (dir / "m.ply").string(), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("object.center_thickness: edge thickness"), std::string::npos) << r.err;
    EXPECT_TRUE(outputs().empty());
}

// The issue's pit: the default lens with a 200 mm surface-breaking bubble at its centre, which
// holds the whole lens (every point of it lies within 12.58 mm of the centre). Refused at its
// radius before any Boolean runs, exit 2, nothing written.
TEST_F(MeshCommand, PitThatHoldsTheObjectExitsTwoBeforeAnyBoolean) {
    const fs::path pit = write("pit.yaml",
                               "object: {type: lens, r1: 50, r2: -50, center_thickness: 6, diameter: 25, ior: 1.5168}\n"
                               "defects:\n"
                               "  - {type: bubble, center: [0, 0, 0], radius: 200, surface_breaking: true}\n");
    const Outcome r = ltmsim("mesh " + pit.string() + " -o " + (dir / "m.ply").string() + " --verbose", dir);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_EQ(r.err.rfind(pit.string() + ":3:47: defects[0].radius: the bubble at (0, 0, 0) (radius 200 mm) holds the "
                                         "whole object, whose every point lies within 12.5795 mm of its centre: it "
                                         "would leave no glass",
                          0),
              0u)
        << r.err;
    EXPECT_EQ(r.err.find("boolean"), std::string::npos) << r.err;  // refused by the loader
    EXPECT_TRUE(outputs().empty());
}

// The final guard: two pits that each leave glass but together remove the whole object (a 2 mm
// window, |z| <= 0.25, and two pits of radius 2 centred on its front face at x = -+1.5: every
// point of the window is within hypot(1.5, 1, 0.5) = 1.87 mm of one of them, while the far rim is
// hypot(2.5, 0.5) = 2.55 mm from each). The Booleans run and leave no triangle: exit 2, located
// at the first pit's mapping, nothing written.
TEST_F(MeshCommand, BooleansThatLeaveNoGlassExitTwo) {
    const fs::path pits = write("pits.yaml",
                                "object: {type: window, thickness: 0.5, diameter: 2, ior: 1.5168}\n"
                                "defects:\n"
                                "  - {type: bubble, center: [-1.5, 0, -0.25], radius: 2, surface_breaking: true}\n"
                                "  - {type: bubble, center: [1.5, 0, -0.25], radius: 2, surface_breaking: true}\n"
                                "mesh: {chord_tolerance: 0.01}\n");
    const Outcome r = ltmsim("mesh " + pits.string() + " -o " + (dir / "m.ply").string(), dir);
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_EQ(r.err, pits.string() + ":3:5: defects[0]: the Booleans with defects[0] (pit) and defects[1] (pit) leave "
                                     "no glass: together they remove the whole object (lengths are in mm)\n");
    EXPECT_TRUE(outputs().empty());
}

TEST_F(MeshCommand, BadOutputPathsExitTwo) {
    Outcome r = ltmsim("mesh " + scene("default.yaml") + " -o " + (dir / "missing" / "m.ply").string(), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
    r = ltmsim("mesh " + scene("default.yaml") + " -o " + (dir / "m.stl").string(), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(".stl"), std::string::npos) << r.err;
    r = ltmsim("mesh " + (dir / "nope.yaml").string() + " -o " + (dir / "m.ply").string(), dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("cannot read scene file"), std::string::npos) << r.err;
    r = ltmsim("mesh", dir);  // usage error
    EXPECT_EQ(r.status, 2);
    EXPECT_TRUE(outputs().empty());
}

TEST_F(MeshCommand, FailureLeavesAnExistingFileUntouched) {
    const fs::path keep = dir / "keep.ply";
    std::ofstream(keep) << "the user's own file";
    const fs::path bad = write("bad.yaml", "object: {type: lens}\n");
    EXPECT_EQ(ltmsim("mesh " + bad.string() + " -o " + keep.string(), dir).status, 2);
    EXPECT_EQ(slurp(keep), "the user's own file");
}

// MeshLab (Debian's meshlabserver, under xvfb) must see the solids ltmsim exports as closed
// two-manifolds with the expected components: the default scene's lens with three enclosed bubble
// cavities is 4 components; a surface-breaking pit is cut into the lens's one boundary; overlapping
// and crossing defects leave one glass boundary plus their enclosed cavities. The counts of
// vertices and faces must be ours (read back with OpenMesh).
TEST_F(MeshCommand, MeshLabSeesClosedManifoldsWithTheExpectedComponents) {
    for (const char* exe : {"meshlabserver", "xvfb-run", "timeout"})
        if (ltm::test::run_shell(std::string("command -v ") + exe, dir).status != 0)
            LTM_INTEROP_SKIP() << exe << " is not on PATH: MeshLab check skipped";
    std::ofstream(dir / "topology.mlx") << "<!DOCTYPE FilterScript>\n<FilterScript>\n"
                                           " <filter name=\"Compute Topological Measures\"/>\n</FilterScript>\n";
    const std::pair<const char*, long> cases[] = {{"default.yaml", 4}, {"examples/pit.yaml", 1}, {"examples/particle.yaml", 3}};
    for (const auto& [rel, components] : cases) {
        SCOPED_TRACE(rel);
        const fs::path ply = dir / "m.ply";
        fs::remove(ply);
        ASSERT_EQ(ltmsim("mesh " + scene(rel) + " -o " + ply.string(), dir).status, 0);
        const ltm::MeshFileSummary ours = ltm::read_mesh_summary(ply.string());
        fs::remove(dir / "topology.log");
        const ltm::test::Outcome r = ltm::test::run_shell(
            "cd '" + dir.string() + "' && timeout 120 xvfb-run -a meshlabserver -i m.ply -s topology.mlx -l topology.log", dir);
        ASSERT_EQ(r.status, 0) << r.out << r.err;
        const std::string log = slurp(dir / "topology.log");
        auto number = [&](const std::string& pattern) -> long {
            std::smatch m;
            if (!std::regex_search(log, m, std::regex(pattern))) {
                ADD_FAILURE() << "'" << pattern << "' not in the MeshLab log:\n" << log;
                return -1;
            }
            return std::stol(m[1]);
        };
        EXPECT_EQ(number(R"(V:\s*(\d+))"), static_cast<long>(ours.vertices));
        EXPECT_EQ(number(R"(F:\s*(\d+))"), static_cast<long>(ours.faces));
        EXPECT_EQ(number(R"(Boundary Edges (\d+))"), 0);
        EXPECT_EQ(number(R"(Mesh has (\d+) holes)"), 0);
        EXPECT_EQ(number(R"(Mesh is composed by (\d+) connected component)"), components);
        EXPECT_TRUE(std::regex_search(log, std::regex(R"((^|\n)\s*Mesh is two-manifold)"))) << log;
    }
}
