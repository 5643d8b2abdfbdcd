// The `ltmsim mesh` command's contract (docs/conventions.md, "Command line"): formats, the stage
// report, exit status 2 with a file:line:key message for bad input, never a partial file, no
// existing output replaced without --overwrite, and every format read by meshio and MeshLab as
// the mesh the program holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "geometry/MeshExport.h"
#include "io/Json.h"
#include "scene/SceneLoader.h"
#include "scene/SceneSolid.h"
#include "tests/SceneFixture.h"
#include "tests/TestSupport.h"
#include "tests/Tolerances.h"

namespace fs = std::filesystem;

namespace {

using ltm::test::Capture;
using ltm::test::Outcome;
using ltm::test::slurp;
using ltm::test::spit;

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
    for (const char* ext : {"ply", "binary.ply", "obj", "off"}) {
        const fs::path out = dir / (std::string("pit.") + ext);
        const std::string binary = std::string(ext) == "binary.ply" ? " --binary" : "";
        const Outcome r =
            ltmsim("mesh " + scene("examples/pit.yaml") + " -o " + out.string() + binary + " --verbose", dir);
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
    // The loader's message and nothing else: the solid builder, whose Boolean failure would be a
    // second message, never ran.
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
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

// Even with --overwrite, a run that fails leaves the file it would have replaced as it was.
TEST_F(MeshCommand, FailureLeavesAnExistingFileUntouched) {
    const fs::path keep = dir / "keep.ply";
    std::ofstream(keep) << "the user's own file";
    const fs::path bad = write("bad.yaml", "object: {type: lens}\n");
    EXPECT_EQ(ltmsim("mesh " + bad.string() + " -o " + keep.string() + " --overwrite", dir).status, 2);
    EXPECT_EQ(slurp(keep), "the user's own file");
}

// As every command (render, acquire, experiment): an existing output -- the mesh, the --stats
// file, or FILE.vtu of a scene with meshed index regions -- is not replaced without --overwrite;
// the run exits 2 naming it, before writing anything. With --overwrite all are replaced.
TEST_F(MeshCommand, ExistingOutputsNeedOverwrite) {
    const std::string mine = "the user's own file";
    const std::string mesh = path("m.ply"), stats = path("m.json");
    // The mesh exists.
    spit(mesh, mine);
    Outcome r = ltmsim("mesh " + scene("default.yaml") + " -o " + mesh + " --stats " + stats, dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("ltmsim mesh: " + mesh + " exists; pass --overwrite to replace it"), std::string::npos)
        << r.err;
    EXPECT_TRUE(slurp(mesh) == mine) << "the existing mesh was replaced";
    EXPECT_FALSE(fs::exists(stats));
    // The --stats file exists (and the mesh does not).
    fs::remove(mesh);
    spit(stats, mine);
    r = ltmsim("mesh " + scene("default.yaml") + " -o " + mesh + " --stats " + stats, dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(stats + " exists; pass --overwrite"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(mesh));
    EXPECT_TRUE(slurp(stats) == mine) << "the existing --stats file was replaced";
    // With --overwrite both are written.
    spit(mesh, mine);
    ASSERT_EQ(ltmsim("mesh " + scene("default.yaml") + " -o " + mesh + " --stats " + stats + " --overwrite", dir).status, 0);
    EXPECT_EQ(slurp(mesh).rfind("ply\n", 0), 0u);
    EXPECT_NE(slurp(stats).find("\"triangles\""), std::string::npos);

    // FILE.vtu, written for a scene with a TetGen-meshed inhomogeneity: refused before the mesh is written.
    const fs::path incl = write("incl.yaml", ltm::test::kSmallSmoothInclusion);
    const std::string grin = path("g.off"), vtu = path("g.vtu");
    spit(vtu, mine);
    r = ltmsim("mesh " + incl.string() + " -o " + grin, dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(vtu + " exists; pass --overwrite"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(grin));
    EXPECT_TRUE(slurp(vtu) == mine) << "the existing FILE.vtu was replaced";
    ASSERT_EQ(ltmsim("mesh " + incl.string() + " -o " + grin + " --overwrite", dir).status, 0);
    EXPECT_NE(slurp(vtu).find("<UnstructuredGrid>"), std::string::npos);
    EXPECT_EQ(slurp(grin).rfind("OFF\n", 0), 0u);
}

TEST_F(MeshCommand, BinaryIsForPlyAndExcludesAscii) {
    Outcome r = ltmsim("mesh " + scene("default.yaml") + " -o " + path("m.obj") + " --binary", dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find(".ply only"), std::string::npos) << r.err;
    r = ltmsim("mesh " + scene("default.yaml") + " -o " + path("m.ply") + " --binary --ascii", dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_TRUE(outputs().empty());
}

// ---- every format in meshio and MeshLab --------------------------------------------------------

namespace {

// The formats `ltmsim mesh` writes, with the option that selects each.
struct Format {
    const char* name;
    const char* file;
    const char* option;
};
const Format kFormats[] = {
    {"ASCII PLY", "m.ply", ""}, {"binary PLY", "m.binary.ply", " --binary"}, {"OBJ", "m.obj", ""}, {"OFF", "m.off", ""}};

constexpr const char* kPython = "/usr/bin/python3";  // Debian's, with numpy and meshio (the `python3` on PATH may differ)

// The mesh `ltmsim mesh` writes for a scene without meshed index regions: the solid's mesh, built
// in this process exactly as the command builds it (app/SceneSetup.cpp: load_scene, build_solid).
ltm::TriMesh program_mesh(const std::string& scene_path) { return ltm::build_solid(ltm::load_scene(scene_path)).mesh; }

// The host's bytes of `values` (numpy.fromfile reads them with the native-order dtypes f8, i4, u1).
template <class T>
std::string bytes_of(const std::vector<T>& values) {
    return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// meshio (Debian's python3-meshio 5.0) reads every format `ltmsim mesh` writes as the mesh the
// program holds: the same vertices bit for bit (float64), the same triangles in the same order,
// and the same enclosed volume -- computed from meshio's arrays operation for operation as
// TriMesh::signed_volume does (numpy's element-wise double operations round as C++'s, which is
// built without FMA contraction, and add.accumulate sums in order), so it must equal the program's
// volume and the --stats file's exactly. The ASCII PLY's face colours and tags come through as
// cell data, face by face.
TEST_F(MeshCommand, MeshioReadsEveryFormatAsTheProgramHoldsIt) {
    if (!fs::exists(kPython) || ltm::test::run_shell(std::string(kPython) + " -c 'import meshio, numpy'", dir).status != 0)
        LTM_INTEROP_SKIP() << kPython << " cannot import meshio and numpy (Debian: python3-meshio)";
    const std::string scene_path = scene("default.yaml");
    const ltm::Solid solid = ltm::build_solid(ltm::load_scene(scene_path));
    const ltm::TriMesh& mesh = solid.mesh;
    std::vector<double> xyz;
    for (const ltm::Vec3& v : mesh.vertices) xyz.insert(xyz.end(), {v.x, v.y, v.z});
    std::vector<std::int32_t> triangles;
    for (const auto& t : mesh.triangles)
        for (auto i : t) triangles.push_back(static_cast<std::int32_t>(i));
    std::vector<std::uint8_t> colours;
    for (int tag : mesh.tags) {
        const auto rgb = ltm::role_colour(solid.surfaces[tag].role);
        colours.insert(colours.end(), rgb.begin(), rgb.end());
    }
    spit(dir / "vertices.f8", bytes_of(xyz));
    spit(dir / "triangles.i4", bytes_of(triangles));
    spit(dir / "tags.i4", bytes_of(mesh.tags));
    spit(dir / "colours.u1", bytes_of(colours));

    std::string files;
    for (const Format& f : kFormats) {
        const Outcome r = ltmsim("mesh " + scene_path + " -o " + path(f.file) + f.option + " --stats " +
                                     path(std::string(f.file) + ".json"),
                                 dir);
        ASSERT_EQ(r.status, 0) << f.name << ": " << r.err;
        files += " '" + path(f.file) + "'";
    }
    write("read.py", R"(import json, sys
import numpy as np, meshio
ref = sys.argv[1]
P = np.fromfile(ref + "/vertices.f8", "f8").reshape(-1, 3)
T = np.fromfile(ref + "/triangles.i4", "i4").reshape(-1, 3)
tags = np.fromfile(ref + "/tags.i4", "i4")
rgb = np.fromfile(ref + "/colours.u1", "u1").reshape(-1, 3)

def signed_volume(p, t):  # TriMesh::signed_volume, operation for operation
    c = (p.min(axis=0) + p.max(axis=0)) * 0.5
    a, b, q = p[t[:, 0]] - c, p[t[:, 1]] - c, p[t[:, 2]] - c
    x = b[:, 1] * q[:, 2] - b[:, 2] * q[:, 1]
    y = b[:, 2] * q[:, 0] - b[:, 0] * q[:, 2]
    z = b[:, 0] * q[:, 1] - b[:, 1] * q[:, 0]
    d = a[:, 0] * x + a[:, 1] * y + a[:, 2] * z
    return float(np.add.accumulate(d)[-1] / 6.0)

for f in sys.argv[2:]:
    m = meshio.read(f)
    t = np.concatenate([c.data for c in m.cells])
    out = {"cell_types": sorted({c.type for c in m.cells}), "vertices": len(m.points), "triangles": len(t),
           "float64": bool(m.points.dtype == np.float64), "points_equal": bool(np.array_equal(m.points, P)),
           "triangles_equal": bool(np.array_equal(t, T)), "volume": signed_volume(m.points, t),
           "cell_data": sorted(m.cell_data)}
    if "tag" in m.cell_data:
        out["tags_equal"] = bool(np.array_equal(np.concatenate(m.cell_data["tag"]), tags))
        got = np.column_stack([np.concatenate(m.cell_data[k]) for k in ("red", "green", "blue")])
        out["colours_equal"] = bool(np.array_equal(got, rgb))
    print(json.dumps(out))
)");
    const Outcome py = ltm::test::run_shell(std::string(kPython) + " '" + path("read.py") + "' '" + dir.string() + "'" + files, dir);
    ASSERT_EQ(py.status, 0) << py.err;
    const auto lines = py.lines();
    ASSERT_EQ(lines.size(), std::size(kFormats)) << py.out << py.err;
    const double volume = mesh.signed_volume();
    for (size_t i = 0; i < lines.size(); ++i) {
        const Format& f = kFormats[i];
        SCOPED_TRACE(f.name);
        const ltm::io::Json got = ltm::io::parse_json(lines[i], "meshio's output");
        const ltm::io::Json stats = ltm::io::read_json_file(path(std::string(f.file) + ".json"), "mesh statistics")["file"];
        EXPECT_EQ(stats["format"], f.name);
        EXPECT_EQ(got["cell_types"], ltm::io::Json::array({"triangle"}));
        EXPECT_EQ(got["vertices"], mesh.num_vertices());
        EXPECT_EQ(got["triangles"], mesh.num_triangles());
        EXPECT_EQ(stats["vertices"], mesh.num_vertices());
        EXPECT_EQ(stats["triangles"], mesh.num_triangles());
        EXPECT_TRUE(got["float64"].get<bool>());
        EXPECT_TRUE(got["points_equal"].get<bool>());
        EXPECT_TRUE(got["triangles_equal"].get<bool>());
        EXPECT_EQ(got["volume"].get<double>(), volume);
        EXPECT_EQ(stats["signed_volume_mm3"].get<double>(), volume);
        if (std::string(f.name) == "ASCII PLY") {
            EXPECT_EQ(got["cell_data"], ltm::io::Json::array({"blue", "green", "red", "tag"}));
            EXPECT_TRUE(got["tags_equal"].get<bool>());
            EXPECT_TRUE(got["colours_equal"].get<bool>());
        } else {
            EXPECT_FALSE(got.contains("tags_equal")) << got.dump();
        }
    }
}

// What meshlabserver (Debian's MeshLab 2020.09, under xvfb) logs for the filters "Compute
// Topological Measures" and "Compute Geometric Measures" on `file` in `dir`; `status` is its exit
// status (134 when it aborts). The log holds, one per line:
//   V:  15032 E:  45072 F: 30048
//   Boundary Edges 0
//   Mesh is composed by 4 connected component(s)
//   Mesh is two-manifold
//   Mesh has 0 holes
//   Mesh Volume  is 2169.626709
// (a non-manifold mesh says "Mesh has N non two manifold edges ..." instead of "two-manifold").
struct MeshLabLog {
    int status = -1;
    std::string log, output;
};
MeshLabLog meshlab_measures(const fs::path& dir, const std::string& file) {
    if (!fs::exists(dir / "measures.mlx"))
        spit(dir / "measures.mlx", "<!DOCTYPE FilterScript>\n<FilterScript>\n"
                                   " <filter name=\"Compute Topological Measures\"/>\n"
                                   " <filter name=\"Compute Geometric Measures\"/>\n</FilterScript>\n");
    fs::remove(dir / "measures.log");
    const Outcome r = ltm::test::run_shell(
        "cd '" + dir.string() + "' && timeout 120 xvfb-run -a meshlabserver -i '" + file +
            "' -s measures.mlx -l measures.log",
        dir);
    return {r.status, slurp(dir / "measures.log"), r.out + r.err};
}

// True, with the name in `which`, if a program the MeshLab checks run is not on PATH.
bool meshlab_missing(const fs::path& dir, std::string& which) {
    for (const char* exe : {"meshlabserver", "xvfb-run", "timeout"})
        if (ltm::test::run_shell(std::string("command -v ") + exe, dir).status != 0) {
            which = exe;
            return true;
        }
    return false;
}

// Checks MeshLab's log against the mesh: the same vertex and face counts, closed (no boundary
// edge, no hole), two-manifold, `components` connected components, and the same volume within
// tol::meshlab_volume (MeshLab holds floats).
void expect_meshlab_sees(const MeshLabLog& r, const ltm::TriMesh& mesh, long components) {
    ASSERT_EQ(r.status, 0) << r.output;
    auto number = [&](const std::string& pattern) -> double {
        std::smatch m;
        if (!std::regex_search(r.log, m, std::regex(pattern))) {
            ADD_FAILURE() << "'" << pattern << "' not in the MeshLab log:\n" << r.log;
            return NAN;
        }
        return std::stod(m[1]);
    };
    EXPECT_EQ(number(R"(V:\s*(\d+))"), static_cast<double>(mesh.num_vertices()));
    EXPECT_EQ(number(R"(F:\s*(\d+))"), static_cast<double>(mesh.num_triangles()));
    EXPECT_EQ(number(R"(Boundary Edges (\d+))"), 0);
    EXPECT_EQ(number(R"(Mesh has (\d+) holes)"), 0);
    EXPECT_EQ(number(R"(Mesh is composed by (\d+) connected component)"), components);
    EXPECT_TRUE(std::regex_search(r.log, std::regex(R"((^|\n)\s*Mesh is two-manifold)"))) << r.log;
    double scale = 0, area = 0, face_terms = 0;
    for (const ltm::Vec3& v : mesh.vertices) scale = std::max({scale, std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    for (size_t f = 0; f < mesh.num_triangles(); ++f) {
        const auto& t = mesh.triangles[f];
        const ltm::Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
        const double d = std::max({ltm::distance(a, b), ltm::distance(b, c), ltm::distance(c, a)});
        const double af = mesh.face_area(f);
        area += af;
        face_terms += 1.5 * d * d * d + 2 * af * d;
    }
    const double volume = mesh.signed_volume();
    EXPECT_NEAR(number(R"(Mesh Volume\s+is\s+([-0-9.eE+]+))"), volume,
                ltm::tol::meshlab_volume(volume, scale, area, face_terms));
}

}  // namespace

// MeshLab opens every format `ltmsim mesh` writes, on the default scene, as the mesh the program
// holds (counts, closed two-manifold, four components: the lens with three enclosed bubble
// cavities, volume); and, in the default format, solids with other topology: a surface-breaking pit
// is cut into the lens's one boundary, overlapping and crossing defects leave one glass boundary
// plus their enclosed cavities. OBJ: MeshLabOpensTheObj.
TEST_F(MeshCommand, MeshLabOpensEveryFormatAsTheProgramHoldsIt) {
    std::string missing;
    if (meshlab_missing(dir, missing)) LTM_INTEROP_SKIP() << missing << " is not on PATH: MeshLab check skipped";
    const ltm::TriMesh lens = program_mesh(scene("default.yaml"));
    for (const Format& f : kFormats) {
        if (std::string(f.name) == "OBJ") continue;
        SCOPED_TRACE(f.name);
        ASSERT_EQ(ltmsim("mesh " + scene("default.yaml") + " -o " + path(f.file) + f.option, dir).status, 0);
        expect_meshlab_sees(meshlab_measures(dir, f.file), lens, 4);
    }
    const struct {
        const char *scene, *ply;
        long components;
    } cases[] = {{"examples/pit.yaml", "pit.ply", 1}, {"examples/particle.yaml", "particle.ply", 3}};
    for (const auto& [rel, ply, components] : cases) {
        SCOPED_TRACE(rel);
        ASSERT_EQ(ltmsim("mesh " + scene(rel) + " -o " + path(ply), dir).status, 0);
        expect_meshlab_sees(meshlab_measures(dir, ply), program_mesh(scene(rel)), components);
    }
}

// OBJ in MeshLab. Debian's MeshLab 2020.09 aborts on every OBJ file (an assertion in its OBJ
// importer: Debian bug #1054006, MeshLab issue #1270), so the check first asks it to open a
// four-vertex tetrahedron; where that fails the test is skipped with the reason, and it runs by
// itself with a MeshLab that opens OBJ files.
TEST_F(MeshCommand, MeshLabOpensTheObj) {
    std::string missing;
    if (meshlab_missing(dir, missing)) LTM_INTEROP_SKIP() << missing << " is not on PATH: MeshLab check skipped";
    write("tetrahedron.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    if (meshlab_measures(dir, "tetrahedron.obj").status != 0)
        GTEST_SKIP() << "this MeshLab cannot open OBJ files at all (Debian's 2020.09 aborts on every one: Debian "
                        "bug #1054006, MeshLab issue #1270)";
    ASSERT_EQ(ltmsim("mesh " + scene("default.yaml") + " -o " + path("m.obj"), dir).status, 0);
    expect_meshlab_sees(meshlab_measures(dir, "m.obj"), program_mesh(scene("default.yaml")), 4);
}
