// Mesh export for MeshLab (geometry/MeshExport.h): what each format carries after a round trip
// through OpenMesh's reader, the PLY legend, atomic writing and its failure modes, and (where
// MeshLab is installed) that MeshLab sees the exported solids as closed two-manifolds with the
// role colours.
#include "geometry/MeshExport.h"

#include <gtest/gtest.h>

#include "tests/TestSupport.h"
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "tests/Tolerances.h"

namespace ltm {
namespace {

namespace fs = std::filesystem;

// ---- fixtures ---------------------------------------------------------------------------------

SurfaceInfo entry(const std::string& name, SurfaceRole role, Medium inside, Medium outside, int defect) {
    SurfaceInfo s;
    s.surface = Surface::plane({0, 0, 0}, {0, 0, 1});  // the export never looks at the surface
    s.name = name;
    s.role = role;
    s.defect = defect;
    s.inside = inside;
    s.outside = outside;
    return s;
}

// Five entries with five different roles (so five different colours).
SurfaceTable make_table() {
    SurfaceTable t;
    t.add(entry("front", SurfaceRole::Front, Medium::Glass, Medium::Air, -1));
    t.add(entry("back", SurfaceRole::Back, Medium::Glass, Medium::Air, -1));
    t.add(entry("rim", SurfaceRole::Rim, Medium::Glass, Medium::Air, -1));
    t.add(entry("bubble 0", SurfaceRole::Bubble, Medium::Glass, Medium::Air, 0));
    t.add(entry("particle 1", SurfaceRole::Particle, Medium::Absorber, Medium::Glass, 1));
    return t;
}

// Coordinates that are not floats (thirds, an offset of 10.1 mm) so the float rounding shows.
Vec3 place(const Vec3& p, const Vec3& offset) { return p * (7.0 / 3.0) + offset + Vec3{10.1, -3.3, 0.7}; }

// Closed, outward-wound (counter-clockwise seen from outside) regular octahedron.
TriMesh octahedron(const std::vector<int>& tags, const Vec3& offset = {}) {
    TriMesh m;
    const Vec3 p[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& v : p) m.add_vertex(place(v, offset));
    const std::uint32_t f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                   {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int i = 0; i < 8; ++i) m.add_triangle(f[i][0], f[i][1], f[i][2], tags.at(static_cast<size_t>(i)));
    return m;
}

// Closed, outward-wound tetrahedron.
TriMesh tetrahedron(const std::vector<int>& tags, const Vec3& offset = {}) {
    TriMesh m;
    const Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const auto& v : p) m.add_vertex(place(v, offset));
    const std::uint32_t f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (int i = 0; i < 4; ++i) m.add_triangle(f[i][0], f[i][1], f[i][2], tags.at(static_cast<size_t>(i)));
    return m;
}

// Tags in no particular order, every entry used, so a reordering of faces would show.
const std::vector<int> kOctaTags = {3, 0, 2, 4, 1, 3, 0, 2};
const std::vector<int> kTetraTags = {2, 4, 0, 3};

std::vector<std::array<std::uint8_t, 3>> expected_colours(const TriMesh& m, const SurfaceTable& t) {
    std::vector<std::array<std::uint8_t, 3>> c;
    for (int tag : m.tags) c.push_back(role_colour(t[tag].role));
    return c;
}

std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// Names in a folder, sorted.
std::vector<std::string> listing(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
    return std::find(v.begin(), v.end(), s) != v.end();
}

// Runs f, expecting an exception of type E whose message contains every one of `needles`.
template <class E, class F>
void expect_throw_with(F&& f, const std::vector<std::string>& needles) {
    try {
        f();
        ADD_FAILURE() << "no exception thrown";
    } catch (const E& e) {
        const std::string what = e.what();
        for (const auto& n : needles) EXPECT_NE(what.find(n), std::string::npos) << "'" << n << "' not in: " << what;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
    }
}

// A fresh folder per test under the system's temporary folder, removed afterwards.
class MeshExport : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::random_device rd;
        dir_ = fs::temp_directory_path() /
               fmt::format("ltm_geometry_export_{}_{}_{:08x}", info->name(), ::getpid(), rd());
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    std::string file(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
    SurfaceTable table_ = make_table();
};

// ---- format from the extension --------------------------------------------------------------------

TEST(MeshFormatFor, KnownExtensionsCaseInsensitive) {
    EXPECT_EQ(mesh_format_for("a/b.ply", false), MeshFormat::PlyBinary);
    EXPECT_EQ(mesh_format_for("a/b.ply", true), MeshFormat::PlyAscii);
    EXPECT_EQ(mesh_format_for("b.PLY", false), MeshFormat::PlyBinary);
    EXPECT_EQ(mesh_format_for("b.obj", true), MeshFormat::Obj);
    EXPECT_EQ(mesh_format_for("b.Off", false), MeshFormat::Off);
}

TEST(MeshFormatFor, UnknownExtensionThrowsNamingItAndTheSupportedOnes) {
    expect_throw_with<std::invalid_argument>([] { mesh_format_for("out/lens.stl", false); },
                                             {"'.stl'", "out/lens.stl", ".ply", ".obj", ".off"});
    expect_throw_with<std::invalid_argument>([] { mesh_format_for("out/lens", false); },
                                             {"no extension", ".ply"});
}

// ---- round trips ---------------------------------------------------------------------------------

TEST_F(MeshExport, FixturesAreClosedAndOutward) {
    EXPECT_GT(octahedron(kOctaTags).signed_volume(), 0);
    EXPECT_GT(tetrahedron(kTetraTags).signed_volume(), 0);
}

// Binary and ASCII PLY: every face keeps its position, its tag and its colour (OpenMesh keeps the
// face order: the tags come back in order, not merely as the same multiset), the legend is in the
// header, and the coordinates are the doubles rounded to float.
TEST_F(MeshExport, PlyKeepsFaceOrderTagsColoursAndLegend) {
    for (bool ascii : {false, true}) {
        for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
            SCOPED_TRACE(fmt::format("{} PLY, {} faces", ascii ? "ASCII" : "binary", mesh.num_triangles()));
            const std::string path = file("mesh.ply");
            write_mesh(path, mesh, table_, ascii ? MeshFormat::PlyAscii : MeshFormat::PlyBinary);
            const MeshFileSummary s = read_mesh_summary(path);
            EXPECT_EQ(s.vertices, mesh.num_vertices());
            EXPECT_EQ(s.faces, mesh.num_triangles());
            EXPECT_EQ(s.tags, mesh.tags);
            EXPECT_EQ(s.face_colours, expected_colours(mesh, table_));

            // Legend: one line per table entry, in this exact form, plus units and axes.
            EXPECT_TRUE(contains(s.comments, "tag 0 = front (front, rgb 110 170 230, inside glass / outside air)"));
            EXPECT_TRUE(contains(s.comments, "tag 3 = bubble 0 (bubble, rgb 240 80 60, inside glass / outside air)"));
            EXPECT_TRUE(contains(s.comments,
                                 "tag 4 = particle 1 (particle, rgb 40 40 40, inside absorber / outside glass)"));
            size_t legend_lines = 0;
            for (const auto& c : s.comments) legend_lines += c.rfind("tag ", 0) == 0;
            EXPECT_EQ(legend_lines, table_.size());
            EXPECT_TRUE(std::any_of(s.comments.begin(), s.comments.end(), [](const std::string& c) {
                return c.find("units mm") != std::string::npos && c.find("+z is the optical axis") != std::string::npos &&
                       c.find("camera at -z") != std::string::npos;
            }));

            // Float rounding only (tests/Tolerances.h, float_export).
            const Aabb b = mesh.bounds();
            const double scale = std::max({std::fabs(b.lo.x), std::fabs(b.lo.y), std::fabs(b.lo.z),
                                           std::fabs(b.hi.x), std::fabs(b.hi.y), std::fabs(b.hi.z)});
            for (int k = 0; k < 3; ++k) {
                EXPECT_NEAR(s.bounds.lo[k], b.lo[k], tol::float_export(scale));
                EXPECT_NEAR(s.bounds.hi[k], b.hi[k], tol::float_export(scale));
            }

            // The header is amended in place: "ply", "format ...", then our comments; the binary
            // body after "end_header\n" is exactly vertices x 3 floats plus per face a uchar count,
            // 3 int indices, 3 uchar colours and the int tag.
            const std::string bytes = read_bytes(path);
            const std::string format_line = ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
            EXPECT_EQ(bytes.rfind("ply\n" + format_line + "comment ", 0), 0u);
            const size_t body = bytes.find("end_header\n") + 11;
            if (!ascii) {
                EXPECT_EQ(bytes.size() - body, mesh.num_vertices() * 12 + mesh.num_triangles() * (1 + 12 + 3 + 4));
            }
            EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.ply"});
        }
    }
}

// The ASCII body read as text, independently of OpenMesh's reader: vertex i is float(vertex i)
// exactly (9 significant digits), and face line i is "3 a b c r g b tag" with triangle i's vertex
// indices in the same rotation, its role colour and its tag.
TEST_F(MeshExport, AsciiPlyBodyIsTheMeshInOrder) {
    const TriMesh mesh = octahedron(kOctaTags);
    const std::string path = file("mesh.ply");
    write_mesh(path, mesh, table_, MeshFormat::PlyAscii);
    std::istringstream in(read_bytes(path));
    std::string line;
    while (std::getline(in, line) && line != "end_header") {}
    for (size_t v = 0; v < mesh.num_vertices(); ++v) {
        float x, y, z;
        ASSERT_TRUE(in >> x >> y >> z);
        EXPECT_EQ(x, static_cast<float>(mesh.vertices[v].x)) << "vertex " << v;
        EXPECT_EQ(y, static_cast<float>(mesh.vertices[v].y)) << "vertex " << v;
        EXPECT_EQ(z, static_cast<float>(mesh.vertices[v].z)) << "vertex " << v;
    }
    for (size_t f = 0; f < mesh.num_triangles(); ++f) {
        int n, a, b, c, r, g, bl, tag;
        ASSERT_TRUE(in >> n >> a >> b >> c >> r >> g >> bl >> tag);
        EXPECT_EQ(n, 3);
        EXPECT_EQ((std::array<int, 3>{a, b, c}),
                  (std::array<int, 3>{static_cast<int>(mesh.triangles[f][0]), static_cast<int>(mesh.triangles[f][1]),
                                      static_cast<int>(mesh.triangles[f][2])}))
            << "face " << f;
        const auto rgb = role_colour(table_[mesh.tags[f]].role);
        EXPECT_EQ((std::array<int, 3>{r, g, bl}), (std::array<int, 3>{rgb[0], rgb[1], rgb[2]})) << "face " << f;
        EXPECT_EQ(tag, mesh.tags[f]) << "face " << f;
    }
    std::string rest;
    EXPECT_FALSE(in >> rest) << "unexpected trailing content: " << rest;
}

// OFF (ASCII): geometry and face colours in order; no tags, no comments.
TEST_F(MeshExport, OffKeepsGeometryAndFaceColours) {
    for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
        const std::string path = file("mesh.off");
        write_mesh(path, mesh, table_, MeshFormat::Off);
        const MeshFileSummary s = read_mesh_summary(path);
        EXPECT_EQ(s.vertices, mesh.num_vertices());
        EXPECT_EQ(s.faces, mesh.num_triangles());
        EXPECT_TRUE(s.tags.empty());
        EXPECT_EQ(s.face_colours, expected_colours(mesh, table_));
        EXPECT_TRUE(s.comments.empty());
        // ASCII: OpenMesh labels face-coloured OFF "COFF"; a binary OFF would say "BINARY".
        const std::string bytes = read_bytes(path);
        EXPECT_EQ(bytes.find("BINARY"), std::string::npos);
        EXPECT_EQ(bytes.rfind("COFF\n", 0), 0u);
        EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.off"});
    }
}

// OBJ: geometry only (no colours, no tags, no material file), with the units comment.
TEST_F(MeshExport, ObjKeepsGeometryOnlyAndWritesNoMaterialFile) {
    for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
        const std::string path = file("mesh.obj");
        write_mesh(path, mesh, table_, MeshFormat::Obj);
        const MeshFileSummary s = read_mesh_summary(path);
        EXPECT_EQ(s.vertices, mesh.num_vertices());
        EXPECT_EQ(s.faces, mesh.num_triangles());
        EXPECT_TRUE(s.tags.empty());
        EXPECT_TRUE(s.face_colours.empty());
        EXPECT_TRUE(std::any_of(s.comments.begin(), s.comments.end(),
                                [](const std::string& c) { return c.find("units mm") != std::string::npos; }));
        const std::string bytes = read_bytes(path);
        EXPECT_EQ(bytes.find("mtllib"), std::string::npos);
        EXPECT_EQ(bytes.find("usemtl"), std::string::npos);
        EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.obj"});
    }
}

// Two tetrahedra sharing one vertex: OpenMesh cannot hold that vertex (non-manifold), so the
// faces that hit it get their own vertices; every face is still written, in order, and the header
// says how many were split off.
TEST_F(MeshExport, NonManifoldFacesAreKeptWithTheirOwnVertices) {
    TriMesh mesh = tetrahedron(kTetraTags);
    // The second one is the first reflected through its vertex 0; a point reflection reverses
    // orientation, so its faces are wound the other way round to stay outward.
    const Vec3 c = mesh.vertices[0];
    const std::uint32_t v[4] = {0, mesh.add_vertex(2.0 * c - mesh.vertices[1]),
                                mesh.add_vertex(2.0 * c - mesh.vertices[2]), mesh.add_vertex(2.0 * c - mesh.vertices[3])};
    const std::uint32_t f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    const int tags[4] = {1, 1, 3, 3};
    for (int i = 0; i < 4; ++i) mesh.add_triangle(v[f[i][0]], v[f[i][2]], v[f[i][1]], tags[i]);
    ASSERT_EQ(mesh.num_vertices(), 7u);
    ASSERT_NEAR(mesh.signed_volume(), 2 * tetrahedron(kTetraTags).signed_volume(),
                tol::mesh_signed_volume(12, 16.0 / 6.0));  // 8 + 4 faces of |det| / 6 <= 1/3

    const std::string path = file("touching.ply");
    write_mesh(path, mesh, table_, MeshFormat::PlyBinary);
    const MeshFileSummary s = read_mesh_summary(path);
    EXPECT_EQ(s.faces, 8u);
    EXPECT_EQ(s.tags, mesh.tags);
    EXPECT_EQ(s.face_colours, expected_colours(mesh, table_));
    size_t split = 0;
    for (const auto& c : s.comments) {
        std::smatch m;
        if (std::regex_search(c, m, std::regex(R"(^warning: (\d+) faces did not fit a manifold surface)")))
            split = std::stoul(m[1]);
    }
    EXPECT_GE(split, 1u);
    EXPECT_EQ(s.vertices, 7u + 3u * split);
}

// ---- failures --------------------------------------------------------------------------------------

TEST_F(MeshExport, MissingFolderThrowsNamingItAndCreatesNothing) {
    const fs::path missing = dir_ / "no_such_folder";
    const std::string path = (missing / "mesh.ply").string();
    expect_throw_with<std::runtime_error>(
        [&] { write_mesh(path, octahedron(kOctaTags), table_, MeshFormat::PlyBinary); },
        {path, missing.string(), "does not exist"});
    EXPECT_FALSE(fs::exists(missing));
    EXPECT_TRUE(listing(dir_).empty());
}

// An inconsistent mesh is refused before any file is touched: the previous file stays byte for
// byte, and no temporary is left behind.
TEST_F(MeshExport, InvalidMeshThrowsAndLeavesTheExistingFileUntouched) {
    const std::string path = file("mesh.ply");
    write_mesh(path, octahedron(kOctaTags), table_, MeshFormat::PlyBinary);
    const std::string before = read_bytes(path);
    const auto mtime = fs::last_write_time(path);

    TriMesh bad_tag = tetrahedron(kTetraTags);
    bad_tag.tags[2] = 99;
    expect_throw_with<std::runtime_error>([&] { write_mesh(path, bad_tag, table_, MeshFormat::PlyBinary); },
                                          {path, "triangle 2 has tag 99", "5 entries"});
    TriMesh negative_tag = tetrahedron(kTetraTags);
    negative_tag.tags[0] = -1;
    expect_throw_with<std::runtime_error>([&] { write_mesh(path, negative_tag, table_, MeshFormat::Obj); },
                                          {path, "tag -1"});
    TriMesh bad_index = tetrahedron(kTetraTags);
    bad_index.triangles[1][2] = 4;
    expect_throw_with<std::runtime_error>([&] { write_mesh(path, bad_index, table_, MeshFormat::Off); },
                                          {path, "triangle 1 uses vertex 4"});
    TriMesh missing_tags = tetrahedron(kTetraTags);
    missing_tags.tags.pop_back();
    expect_throw_with<std::runtime_error>([&] { write_mesh(path, missing_tags, table_, MeshFormat::PlyAscii); },
                                          {path, "4 triangles but 3 tags"});
    TriMesh nan_vertex = tetrahedron(kTetraTags);
    nan_vertex.vertices[1].y = NAN;
    expect_throw_with<std::runtime_error>([&] { write_mesh(path, nan_vertex, table_, MeshFormat::PlyBinary); },
                                          {path, "vertex 1 has a non-finite coordinate"});

    EXPECT_EQ(read_bytes(path), before);
    EXPECT_EQ(fs::last_write_time(path), mtime);
    EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.ply"});
}

// A folder in the way of the target is refused (by io::AtomicFile, before any temporary exists;
// a rename that fails after the temporary was written is tested in tests/io_atomic.cpp). The
// folder is untouched and nothing is left behind.
TEST_F(MeshExport, TargetThatIsAFolderIsRefused) {
    const fs::path target = dir_ / "taken.ply";
    fs::create_directory(target);
    fs::create_directory(target / "inside");
    expect_throw_with<std::runtime_error>(
        [&] { write_mesh(target.string(), octahedron(kOctaTags), table_, MeshFormat::PlyBinary); },
        {target.string(), "it is a folder"});
    EXPECT_TRUE(fs::is_directory(target));
    EXPECT_EQ(listing(target), std::vector<std::string>{"inside"});
    EXPECT_EQ(listing(dir_), std::vector<std::string>{"taken.ply"});
}

// Writing over an existing file replaces it whole.
TEST_F(MeshExport, RewriteReplacesTheFile) {
    const std::string path = file("mesh.ply");
    write_mesh(path, octahedron(kOctaTags), table_, MeshFormat::PlyAscii);
    write_mesh(path, tetrahedron(kTetraTags), table_, MeshFormat::PlyBinary);
    const MeshFileSummary s = read_mesh_summary(path);
    EXPECT_EQ(s.faces, 4u);
    EXPECT_EQ(s.tags, kTetraTags);
    EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.ply"});
}

TEST_F(MeshExport, ReadingAMissingFileThrowsNamingIt) {
    const std::string path = file("absent.ply");
    expect_throw_with<std::runtime_error>([&] { read_mesh_summary(path); }, {path});
}

// ---- MeshLab -----------------------------------------------------------------------------------------

bool on_path(const std::string& exe) {
    const char* path = std::getenv("PATH");
    if (!path) return false;
    std::istringstream dirs(path);
    std::string d;
    while (std::getline(dirs, d, ':')) {
        const fs::path p = fs::path(d.empty() ? "." : d) / exe;
        if (fs::is_regular_file(p) && ::access(p.c_str(), X_OK) == 0) return true;
    }
    return false;
}

// MeshLab 2020.09's filter "Compute Topological Measures" logs (via -l, one per line):
//   V:     12 E:     24 F:    16
//   Unreferenced Vertices 0
//   Boundary Edges 0
//   Mesh is composed by 2 connected component(s)
//   Mesh is two-manifold
//   Mesh has 0 holes
//   Genus is 0
// (a non-manifold mesh says "Mesh has N non two manifold edges ..." instead of "two-manifold").
TEST_F(MeshExport, MeshLabSeesTwoClosedManifoldComponentsWithRoleColours) {
    for (const char* exe : {"meshlabserver", "xvfb-run", "timeout"})
        if (!on_path(exe)) LTM_INTEROP_SKIP() << exe << " is not on PATH: MeshLab check skipped";

    TriMesh mesh = octahedron(kOctaTags);
    mesh.append(octahedron({4, 4, 1, 1, 0, 2, 3, 3}, {5, 0, 0}));
    write_mesh(file("two.ply"), mesh, table_, MeshFormat::PlyBinary);
    {
        std::ofstream script(dir_ / "topology.mlx");
        script << "<!DOCTYPE FilterScript>\n<FilterScript>\n"
                  " <filter name=\"Compute Topological Measures\"/>\n</FilterScript>\n";
    }
    // -o ... -m fc sa: MeshLab saves what it loaded, with face colours, as ASCII PLY.
    const std::string cmd = fmt::format(
        "cd '{}' && timeout 60 xvfb-run -a meshlabserver -i two.ply -o meshlab.ply -m fc sa -s topology.mlx "
        "-l topology.log > meshlab.out 2>&1",
        dir_.string());
    const int status = std::system(cmd.c_str());
    const std::string out = read_bytes(dir_ / "meshlab.out");
    ASSERT_TRUE(WIFEXITED(status)) << cmd;
    ASSERT_NE(WEXITSTATUS(status), 124) << "meshlabserver timed out after 60 s:\n" << out;
    ASSERT_EQ(WEXITSTATUS(status), 0) << cmd << "\n" << out;
    const std::string log = read_bytes(dir_ / "topology.log");
    ASSERT_FALSE(log.empty()) << "no log from meshlabserver:\n" << out;

    auto number = [&](const std::string& pattern) -> long {
        std::smatch m;
        if (!std::regex_search(log, m, std::regex(pattern))) {
            ADD_FAILURE() << "'" << pattern << "' not in the MeshLab log:\n" << log;
            return -1;
        }
        return std::stol(m[1]);
    };
    EXPECT_EQ(number(R"(V:\s*(\d+))"), 12);
    EXPECT_EQ(number(R"(F:\s*(\d+))"), 16);
    EXPECT_EQ(number(R"(Unreferenced Vertices (\d+))"), 0);
    EXPECT_EQ(number(R"(Boundary Edges (\d+))"), 0);
    EXPECT_EQ(number(R"(Mesh is composed by (\d+) connected component)"), 2);
    EXPECT_EQ(number(R"(Mesh has (\d+) holes)"), 0);
    EXPECT_TRUE(std::regex_search(log, std::regex(R"((^|\n)\s*Mesh is two-manifold)"))) << log;
    EXPECT_EQ(log.find("non two manifold"), std::string::npos) << log;

    // MeshLab's own ASCII PLY: its face colours are ours, face by face.
    std::istringstream in(read_bytes(dir_ / "meshlab.ply"));
    std::string line;
    size_t nv = 0, nf = 0;
    bool alpha = false;
    while (std::getline(in, line) && line != "end_header") {
        std::istringstream l(line);
        std::string w, what;
        size_t n = 0;
        if (l >> w >> what >> n && w == "element") {
            if (what == "vertex") nv = n;
            if (what == "face") nf = n;
        }
        if (line == "property uchar alpha") alpha = true;
    }
    ASSERT_EQ(nv, 12u);
    ASSERT_EQ(nf, 16u);
    for (size_t v = 0; v < nv; ++v) std::getline(in, line);
    const auto colours = expected_colours(mesh, table_);
    for (size_t f = 0; f < nf; ++f) {
        int n, a, b, c, r, g, bl, al = 255;
        ASSERT_TRUE(in >> n >> a >> b >> c >> r >> g >> bl) << "face " << f;
        if (alpha) in >> al;
        EXPECT_EQ((std::array<int, 3>{r, g, bl}), (std::array<int, 3>{colours[f][0], colours[f][1], colours[f][2]}))
            << "face " << f;
    }
}

}  // namespace
}  // namespace ltm
