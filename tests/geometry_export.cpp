// Mesh export (geometry/MeshExport.h): each format's layout, its body read as text or bytes
// against the mesh bit for bit, OpenMesh's reader on every file, the PLY legend, atomic writing
// and its failure modes, and (where MeshLab is installed) that MeshLab sees the exported solids as
// closed two-manifolds with the role colours. Every format through meshio and MeshLab, on real
// scenes: tests/app_mesh_command.cpp.
#include "geometry/MeshExport.h"

#include <gtest/gtest.h>

#include "tests/TestSupport.h"
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
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

// PLY is ASCII unless asked for binary (the ASCII file is the one with colours and tags).
TEST(MeshFormatFor, KnownExtensionsCaseInsensitive) {
    EXPECT_EQ(mesh_format_for("a/b.ply", false), MeshFormat::PlyAscii);
    EXPECT_EQ(mesh_format_for("a/b.ply", true), MeshFormat::PlyBinary);
    EXPECT_EQ(mesh_format_for("b.PLY", true), MeshFormat::PlyBinary);
    EXPECT_EQ(mesh_format_for("b.obj", false), MeshFormat::Obj);
    EXPECT_EQ(mesh_format_for("b.Off", false), MeshFormat::Off);
}

TEST(MeshFormatFor, BinaryIsForPlyOnly) {
    expect_throw_with<std::invalid_argument>([] { mesh_format_for("out/lens.obj", true); }, {"out/lens.obj", ".ply only"});
    expect_throw_with<std::invalid_argument>([] { mesh_format_for("out/lens.OFF", true); }, {"out/lens.OFF", ".ply only"});
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

// The body of a text file after its header (the first `header_lines` lines), read as
// whitespace-separated tokens.
std::istringstream body_after(const std::string& bytes, size_t header_lines) {
    std::istringstream in(bytes);
    std::string line;
    for (size_t i = 0; i < header_lines && std::getline(in, line);) ++i;
    return std::istringstream(bytes.substr(static_cast<size_t>(in.tellg())));
}

// Reads three coordinates as doubles (operator>> is strtod, correctly rounded) and expects the
// vertex bit for bit: 17 significant digits print every double exactly.
void expect_exact_vertex(std::istream& in, const Vec3& v, size_t index) {
    double x = NAN, y = NAN, z = NAN;
    ASSERT_TRUE(in >> x >> y >> z) << "vertex " << index;
    EXPECT_EQ(x, v.x) << "vertex " << index;
    EXPECT_EQ(y, v.y) << "vertex " << index;
    EXPECT_EQ(z, v.z) << "vertex " << index;
}

// OpenMesh's reader (a third party's) on `path`: the mesh's counts, and its tags and face colours
// in order when `table` is given (ASCII PLY), none otherwise. Returns what it read.
MeshFileSummary expect_openmesh_reads(const std::string& path, const TriMesh& mesh, const SurfaceTable* table) {
    const MeshFileSummary s = read_mesh_summary(path);
    EXPECT_EQ(s.vertices, mesh.num_vertices());
    EXPECT_EQ(s.faces, mesh.num_triangles());
    EXPECT_EQ(s.tags, table ? mesh.tags : std::vector<int>{});
    using Colours = std::vector<std::array<std::uint8_t, 3>>;
    EXPECT_EQ(s.face_colours, table ? expected_colours(mesh, *table) : Colours{});
    return s;
}

std::array<long, 3> indices_of(const std::array<std::uint32_t, 3>& t, long base = 0) {
    return {static_cast<long>(t[0]) + base, static_cast<long>(t[1]) + base, static_cast<long>(t[2]) + base};
}

// The header of an ASCII PLY as the exporter writes it: the exact property layout, the legend
// (one line per table entry, in this form), units and axes.
TEST_F(MeshExport, AsciiPlyHeaderHasTheLayoutAndTheLegend) {
    const std::string path = file("mesh.ply");
    write_mesh(path, octahedron(kOctaTags), table_, MeshFormat::PlyAscii);
    const std::string bytes = read_bytes(path);
    const size_t end = bytes.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    const std::string header = bytes.substr(0, end + 11);
    EXPECT_EQ(header.rfind("ply\nformat ascii 1.0\ncomment ", 0), 0u) << header;
    EXPECT_NE(header.find("element vertex 6\nproperty double x\nproperty double y\nproperty double z\n"
                          "element face 8\nproperty list uchar int vertex_indices\nproperty uchar red\n"
                          "property uchar green\nproperty uchar blue\nproperty int tag\nend_header\n"),
              std::string::npos)
        << header;
    const MeshFileSummary s = read_mesh_summary(path);
    EXPECT_TRUE(contains(s.comments, "tag 0 = front (front, rgb 110 170 230, inside glass / outside air)"));
    EXPECT_TRUE(contains(s.comments, "tag 3 = bubble 0 (bubble, rgb 240 80 60, inside glass / outside air)"));
    EXPECT_TRUE(contains(s.comments, "tag 4 = particle 1 (particle, rgb 40 40 40, inside absorber / outside glass)"));
    size_t legend_lines = 0;
    for (const auto& c : s.comments) legend_lines += c.rfind("tag ", 0) == 0;
    EXPECT_EQ(legend_lines, table_.size());
    EXPECT_TRUE(std::any_of(s.comments.begin(), s.comments.end(), [](const std::string& c) {
        return c.find("units mm") != std::string::npos && c.find("+z is the optical axis") != std::string::npos &&
               c.find("camera at -z") != std::string::npos;
    }));
    EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.ply"});
}

// The ASCII PLY body read as text, independently of any mesh library: vertex i is the mesh's
// vertex i bit for bit, and face line i is "3 a b c r g b tag" with triangle i's vertex indices in
// the same rotation, its role colour and its tag; nothing follows.
TEST_F(MeshExport, AsciiPlyBodyIsTheMeshExactly) {
    for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
        SCOPED_TRACE(fmt::format("{} faces", mesh.num_triangles()));
        const std::string path = file("mesh.ply");
        write_mesh(path, mesh, table_, MeshFormat::PlyAscii);
        std::istringstream in(read_bytes(path));
        std::string line;
        while (std::getline(in, line) && line != "end_header") {}
        for (size_t v = 0; v < mesh.num_vertices(); ++v) expect_exact_vertex(in, mesh.vertices[v], v);
        for (size_t f = 0; f < mesh.num_triangles(); ++f) {
            long n, a, b, c, r, g, bl, tag;
            ASSERT_TRUE(in >> n >> a >> b >> c >> r >> g >> bl >> tag) << "face " << f;
            EXPECT_EQ(n, 3);
            EXPECT_EQ((std::array<long, 3>{a, b, c}), indices_of(mesh.triangles[f])) << "face " << f;
            const auto rgb = role_colour(table_[mesh.tags[f]].role);
            EXPECT_EQ((std::array<long, 3>{r, g, bl}), (std::array<long, 3>{rgb[0], rgb[1], rgb[2]})) << "face " << f;
            EXPECT_EQ(tag, mesh.tags[f]) << "face " << f;
        }
        std::string rest;
        EXPECT_FALSE(in >> rest) << "unexpected trailing content: " << rest;
        // OpenMesh's reader agrees, face by face (it keeps the file's face order).
        expect_openmesh_reads(path, mesh, &table_);
    }
}

// Binary PLY: the header declares double coordinates and a face element with vertex_indices only
// (MeshExport.h: the one layout meshio 5.0 reads), and the body is exactly the mesh's doubles
// (8 little-endian bytes each, x86's order, so the host's bytes) followed by, per face, the count
// 3 and three little-endian int32 indices.
TEST_F(MeshExport, BinaryPlyIsTheMeshBitForBit) {
    for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
        SCOPED_TRACE(fmt::format("{} faces", mesh.num_triangles()));
        const std::string path = file("mesh.ply");
        write_mesh(path, mesh, table_, MeshFormat::PlyBinary);
        const std::string bytes = read_bytes(path);
        const size_t end = bytes.find("end_header\n");
        ASSERT_NE(end, std::string::npos);
        const std::string header = bytes.substr(0, end + 11);
        EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\ncomment ", 0), 0u) << header;
        EXPECT_NE(header.find(fmt::format("element vertex {}\nproperty double x\nproperty double y\nproperty double z\n"
                                          "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                                          mesh.num_vertices(), mesh.num_triangles())),
                  std::string::npos)
            << header;
        EXPECT_EQ(header.find("tag "), std::string::npos) << "a legend for tags the file does not hold:\n" << header;
        const std::string body = bytes.substr(end + 11);
        ASSERT_EQ(body.size(), mesh.num_vertices() * 24 + mesh.num_triangles() * 13);
        auto le = [&](size_t at, size_t n) {  // n bytes at `at`, little-endian, as an unsigned integer
            std::uint64_t v = 0;
            for (size_t i = n; i-- > 0;) v = (v << 8) | static_cast<unsigned char>(body[at + i]);
            return v;
        };
        for (size_t v = 0; v < mesh.num_vertices(); ++v)
            for (int k = 0; k < 3; ++k) {
                const double coordinate = mesh.vertices[v][k];
                std::uint64_t want = 0;
                std::memcpy(&want, &coordinate, 8);
                EXPECT_EQ(le(24 * v + 8 * static_cast<size_t>(k), 8), want) << "vertex " << v << " coordinate " << k;
            }
        for (size_t f = 0; f < mesh.num_triangles(); ++f) {
            const size_t at = 24 * mesh.num_vertices() + 13 * f;
            EXPECT_EQ(le(at, 1), 3u) << "face " << f;
            for (size_t k = 0; k < 3; ++k)
                EXPECT_EQ(le(at + 1 + 4 * k, 4), mesh.triangles[f][k]) << "face " << f;
        }
        expect_openmesh_reads(path, mesh, nullptr);
        EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.ply"});
    }
}

// OFF: the header "OFF" (never "COFF": meshio accepts "OFF" only), "vertices faces 0", the exact
// vertices and "3 a b c" per face in order; no colours, no comments, nothing after.
TEST_F(MeshExport, OffIsPlainOffWithTheMeshExactly) {
    for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
        SCOPED_TRACE(fmt::format("{} faces", mesh.num_triangles()));
        const std::string path = file("mesh.off");
        write_mesh(path, mesh, table_, MeshFormat::Off);
        const std::string bytes = read_bytes(path);
        EXPECT_EQ(bytes.rfind(fmt::format("OFF\n{} {} 0\n", mesh.num_vertices(), mesh.num_triangles()), 0), 0u);
        std::istringstream in = body_after(bytes, 2);
        for (size_t v = 0; v < mesh.num_vertices(); ++v) expect_exact_vertex(in, mesh.vertices[v], v);
        for (size_t f = 0; f < mesh.num_triangles(); ++f) {
            long n, a, b, c;
            ASSERT_TRUE(in >> n >> a >> b >> c) << "face " << f;
            EXPECT_EQ(n, 3);
            EXPECT_EQ((std::array<long, 3>{a, b, c}), indices_of(mesh.triangles[f])) << "face " << f;
        }
        std::string rest;
        EXPECT_FALSE(in >> rest) << "unexpected trailing content: " << rest;
        EXPECT_TRUE(expect_openmesh_reads(path, mesh, nullptr).comments.empty());
        EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.off"});
    }
}

// OBJ: the units comment, then "v x y z" with the exact vertices and "f a b c" (1-based) in order;
// no colours, no tags, no material file.
TEST_F(MeshExport, ObjIsTheMeshExactlyWithoutAMaterialFile) {
    for (const TriMesh& mesh : {octahedron(kOctaTags), tetrahedron(kTetraTags)}) {
        SCOPED_TRACE(fmt::format("{} faces", mesh.num_triangles()));
        const std::string path = file("mesh.obj");
        write_mesh(path, mesh, table_, MeshFormat::Obj);
        std::istringstream in(read_bytes(path));
        std::string line;
        size_t v = 0, f = 0;
        while (std::getline(in, line)) {
            std::istringstream l(line);
            std::string key;
            l >> key;
            if (key == "v") {
                ASSERT_LT(v, mesh.num_vertices());
                expect_exact_vertex(l, mesh.vertices[v], v);
                ++v;
            } else if (key == "f") {
                ASSERT_LT(f, mesh.num_triangles());
                long a, b, c;
                ASSERT_TRUE(l >> a >> b >> c) << line;
                EXPECT_EQ((std::array<long, 3>{a, b, c}), indices_of(mesh.triangles[f], 1)) << "face " << f;
                ++f;
            } else {
                EXPECT_EQ(key, "#") << "unexpected line: " << line;
            }
        }
        EXPECT_EQ(v, mesh.num_vertices());
        EXPECT_EQ(f, mesh.num_triangles());
        const MeshFileSummary s = expect_openmesh_reads(path, mesh, nullptr);
        EXPECT_TRUE(std::any_of(s.comments.begin(), s.comments.end(),
                                [](const std::string& c) { return c.find("units mm") != std::string::npos; }));
        EXPECT_EQ(listing(dir_), std::vector<std::string>{"mesh.obj"});
    }
}

// Two tetrahedra sharing one vertex (non-manifold there): the file holds the mesh as it is, its 7
// vertices and 8 faces in order (no face is split off with copies of its vertices, as OpenMesh's
// writer would split it); OpenMesh's reader, which cannot hold that vertex, splits on reading.
TEST_F(MeshExport, NonManifoldMeshIsWrittenAsItIs) {
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

    const std::string path = file("touching.off");
    write_mesh(path, mesh, table_, MeshFormat::Off);
    const std::string bytes = read_bytes(path);
    EXPECT_EQ(bytes.rfind("OFF\n7 8 0\n", 0), 0u);
    std::istringstream in = body_after(bytes, 2);
    for (size_t k = 0; k < 7; ++k) expect_exact_vertex(in, mesh.vertices[k], k);
    for (size_t k = 0; k < 8; ++k) {
        long n, a, b, cc;
        ASSERT_TRUE(in >> n >> a >> b >> cc);
        EXPECT_EQ((std::array<long, 3>{a, b, cc}), indices_of(mesh.triangles[k])) << "face " << k;
    }
    const MeshFileSummary s = read_mesh_summary(path);
    EXPECT_EQ(s.faces, 8u);
    EXPECT_GT(s.vertices, 7u);
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
    MeshFileSummary s = read_mesh_summary(path);
    EXPECT_EQ(s.faces, 4u);
    EXPECT_TRUE(s.tags.empty());
    write_mesh(path, octahedron(kOctaTags), table_, MeshFormat::PlyAscii);
    s = read_mesh_summary(path);
    EXPECT_EQ(s.faces, 8u);
    EXPECT_EQ(s.tags, kOctaTags);
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
    write_mesh(file("two.ply"), mesh, table_, MeshFormat::PlyAscii);
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
