#include "geometry/MeshExport.h"

// OpenMesh's VectorT default constructor leaves its elements uninitialised on purpose (speed), and
// GCC 12 warns about that wherever a property vector grows: noise, silenced for its headers only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#pragma GCC diagnostic pop
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "geometry/ExportWriter.h"
#include "io/AtomicFile.h"

namespace ltm {
namespace {

namespace fs = std::filesystem;

// What OpenMesh reads into (read_mesh_summary): double points, unsigned char RGB face colours.
struct ReadTraits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
    using Color = OpenMesh::Vec3uc;
    FaceAttributes(OpenMesh::Attributes::Color);
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<ReadTraits>;

constexpr const char* kTagProperty = "tag";

// OpenMesh reports problems on its own process-wide streams (omerr for errors, omlog for its
// readers' chatter), by default onto std::cerr / std::clog. During one of our calls they are
// redirected into a string, which goes into the exception text on failure and is dropped on
// success. The mutex serialises our calls, as the streams are global.
std::mutex g_openmesh_io_mutex;

class OpenMeshMessages {
public:
    OpenMeshMessages() : lock_(g_openmesh_io_mutex) {
        omerr().flush();
        omlog().flush();
        omout().flush();
        err_had_cerr_ = omerr().disconnect(std::cerr);
        log_had_clog_ = omlog().disconnect(std::clog);
        out_had_cout_ = omout().disconnect(std::cout);
        omerr().connect(text_);
        omlog().connect(text_);
        omout().connect(text_);
    }
    ~OpenMeshMessages() {
        omerr().flush();
        omlog().flush();
        omout().flush();
        omerr().disconnect(text_);
        omlog().disconnect(text_);
        omout().disconnect(text_);
        if (err_had_cerr_) omerr().connect(std::cerr);
        if (log_had_clog_) omlog().connect(std::clog);
        if (out_had_cout_) omout().connect(std::cout);
    }
    OpenMeshMessages(const OpenMeshMessages&) = delete;
    OpenMeshMessages& operator=(const OpenMeshMessages&) = delete;

    // The messages so far, on one line, or "" when there were none.
    std::string text() {
        omerr().flush();
        omlog().flush();
        std::string s = text_.str();
        std::replace(s.begin(), s.end(), '\n', ' ');
        while (!s.empty() && s.back() == ' ') s.pop_back();
        return s.empty() ? s : " (OpenMesh said: " + s + ")";
    }

private:
    std::lock_guard<std::mutex> lock_;
    std::ostringstream text_;
    bool err_had_cerr_ = false, log_had_clog_ = false, out_had_cout_ = false;
};

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// A comment must stay on its line (PLY header lines end at '\n'; OBJ comments likewise).
std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r' || c == '\0') c = ' ';
    return s;
}

// The folder a path lives in ("." for a bare file name).
fs::path folder_of(const std::string& path) {
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? fs::path(".") : parent;
}

// Everything that could make the export wrong, checked before any file exists.
void validate(const std::string& path, const TriMesh& mesh, const SurfaceTable& table) {
    auto fail = [&](const std::string& why) {
        throw std::runtime_error(fmt::format("cannot write mesh '{}': {}", path, why));
    };
    if (mesh.tags.size() != mesh.triangles.size())
        fail(fmt::format("the mesh has {} triangles but {} tags", mesh.triangles.size(), mesh.tags.size()));
    const size_t nv = mesh.vertices.size();
    // PLY's vertex_indices are "int" (the type every PLY reader knows), so vertex numbers stop at 2^31 - 1.
    if (nv > static_cast<size_t>(std::numeric_limits<std::int32_t>::max()) + 1)
        fail(fmt::format("the mesh has {} vertices, but PLY's int vertex indices reach 2^31 - 1", nv));
    for (size_t v = 0; v < nv; ++v)
        if (!is_finite(mesh.vertices[v]))
            fail(fmt::format("vertex {} has a non-finite coordinate ({}, {}, {})", v, mesh.vertices[v].x,
                             mesh.vertices[v].y, mesh.vertices[v].z));
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto& t = mesh.triangles[f];
        for (auto i : t)
            if (i >= nv)
                fail(fmt::format("triangle {} uses vertex {}, but the mesh has {} vertices", f, i, nv));
        const int tag = mesh.tags[f];
        if (tag < 0 || static_cast<size_t>(tag) >= table.size())
            fail(fmt::format("triangle {} has tag {}, outside the surface table ({} entries)", f, tag,
                             table.size()));
    }
}

// One vertex as text: `prefix` ("" or "v "), then x, y and z with 17 significant digits, which
// print every double exactly (max_digits10), so that a correctly rounding reader gets it back.
void print_vertex(ExportWriter& out, const char* prefix, const Vec3& p) {
    out.print("{}{:.17g} {:.17g} {:.17g}\n", prefix, p.x, p.y, p.z);
}

// The header comments every format that has comments starts with (PLY "comment", OBJ '#').
std::vector<std::string> common_comments() {
    return {"ltmsim mesh export",
            "units mm; axes right-handed, +z is the optical axis, camera at -z, display at +z",
            "vertex coordinates are the mesh's doubles exactly (float64 in binary, 17 significant digits in text)"};
}

// PLY (ASCII or binary little-endian). The header lines in the order the PLY grammar asks for:
// "ply", "format ...", comments, then the elements with their properties. The face element of
// the binary file has vertex_indices only (MeshExport.h says why).
void write_ply(ExportWriter& out, const TriMesh& mesh, const SurfaceTable& table, bool binary) {
    out.print("ply\nformat {} 1.0\n", binary ? "binary_little_endian" : "ascii");
    std::vector<std::string> comments = common_comments();
    if (binary) {
        comments.push_back("geometry only: face colours and surface tags are in the ASCII PLY (ltmsim mesh without --binary)");
    } else {
        comments.push_back("face colour = role of the face's surface; face property tag = index into the legend below");
        for (size_t i = 0; i < table.size(); ++i) {
            const SurfaceInfo& s = table.entries[i];
            const auto rgb = role_colour(s.role);
            comments.push_back(one_line(fmt::format("tag {} = {} ({}, rgb {} {} {}, inside {} / outside {})", i, s.name,
                                                    to_string(s.role), rgb[0], rgb[1], rgb[2], to_string(s.inside),
                                                    to_string(s.outside))));
        }
    }
    for (const std::string& c : comments) out.print("comment {}\n", c);
    out.print("element vertex {}\nproperty double x\nproperty double y\nproperty double z\n"
              "element face {}\nproperty list uchar int vertex_indices\n",
              mesh.vertices.size(), mesh.triangles.size());
    if (!binary) out.print("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int tag\n");
    out.print("end_header\n");

    if (binary) {
        for (const Vec3& p : mesh.vertices) {
            out.little_endian(p.x);
            out.little_endian(p.y);
            out.little_endian(p.z);
        }
        for (const auto& t : mesh.triangles) {
            out.little_endian(std::uint8_t{3});
            for (auto i : t) out.little_endian(static_cast<std::int32_t>(i));
        }
        return;
    }
    for (const Vec3& p : mesh.vertices) print_vertex(out, "", p);
    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto& t = mesh.triangles[f];
        const auto rgb = role_colour(table[mesh.tags[f]].role);
        out.print("3 {} {} {} {} {} {} {}\n", t[0], t[1], t[2], rgb[0], rgb[1], rgb[2], mesh.tags[f]);
    }
}

// OFF: "OFF", then "vertices faces edges" (edges 0: OFF readers ignore the count), vertices, faces.
void write_off(ExportWriter& out, const TriMesh& mesh) {
    out.print("OFF\n{} {} 0\n", mesh.vertices.size(), mesh.triangles.size());
    for (const Vec3& p : mesh.vertices) print_vertex(out, "", p);
    for (const auto& t : mesh.triangles) out.print("3 {} {} {}\n", t[0], t[1], t[2]);
}

// OBJ: '#' comments, "v x y z", then "f a b c" with 1-based vertex numbers.
void write_obj(ExportWriter& out, const TriMesh& mesh) {
    for (const std::string& c : common_comments()) out.print("# {}\n", c);
    out.print("# geometry only: face colours and surface tags are in the ASCII PLY\n");
    for (const Vec3& p : mesh.vertices) print_vertex(out, "v ", p);
    for (const auto& t : mesh.triangles) out.print("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
}

}  // namespace

const char* to_string(MeshFormat f) {
    switch (f) {
        case MeshFormat::PlyAscii: return "ASCII PLY";
        case MeshFormat::PlyBinary: return "binary PLY";
        case MeshFormat::Obj: return "OBJ";
        case MeshFormat::Off: return "OFF";
    }
    return "?";
}

MeshFormat mesh_format_for(const std::string& path, bool binary_ply) {
    const std::string ext = lower(fs::path(path).extension().string());
    if (ext == ".ply") return binary_ply ? MeshFormat::PlyBinary : MeshFormat::PlyAscii;
    if (ext != ".obj" && ext != ".off") {
        const std::string what = ext.empty() ? std::string("has no extension")
                                             : fmt::format("has the unsupported extension '{}'",
                                                           fs::path(path).extension().string());
        throw std::invalid_argument(fmt::format(
            "mesh file '{}' {}: supported are .ply (colours, tags and legend), .obj, .off", path, what));
    }
    if (binary_ply)
        throw std::invalid_argument(fmt::format(
            "mesh file '{}': binary output applies to .ply only (OBJ and OFF are text formats)", path));
    return ext == ".obj" ? MeshFormat::Obj : MeshFormat::Off;
}

void write_mesh(const std::string& path, const TriMesh& mesh, const SurfaceTable& table, MeshFormat format) {
    if (path.empty()) throw std::runtime_error("cannot write mesh: the path is empty");
    const fs::path folder = folder_of(path);
    std::error_code ec;
    if (!fs::exists(folder, ec))
        throw std::runtime_error(fmt::format("cannot write mesh '{}': the folder '{}' does not exist", path,
                                             folder.string()));
    if (!fs::is_directory(folder, ec))
        throw std::runtime_error(
            fmt::format("cannot write mesh '{}': '{}' is not a folder", path, folder.string()));
    validate(path, mesh, table);

    io::AtomicFile file(path, "mesh");
    ExportWriter out(file);
    switch (format) {
        case MeshFormat::PlyAscii: write_ply(out, mesh, table, false); break;
        case MeshFormat::PlyBinary: write_ply(out, mesh, table, true); break;
        case MeshFormat::Obj: write_obj(out, mesh); break;
        case MeshFormat::Off: write_off(out, mesh); break;
    }
    out.flush();
    file.commit();
}

MeshFileSummary read_mesh_summary(const std::string& path) {
    const MeshFormat format = mesh_format_for(path, false);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
        throw std::runtime_error(fmt::format("cannot read mesh '{}': no such file", path));

    MeshFileSummary s;
    {
        OpenMeshMessages messages;
        OmMesh om;
        om.request_face_colors();
        // Options are in/out: in, what to read (Custom: PLY properties beyond the standard ones,
        // which become properties named as in the file); out, what the file had.
        OpenMesh::IO::Options opt = OpenMesh::IO::Options::FaceColor | OpenMesh::IO::Options::Custom;
        if (!OpenMesh::IO::read_mesh(om, path, opt))
            throw std::runtime_error(fmt::format("cannot read mesh '{}': OpenMesh's reader failed{}", path,
                                                 messages.text()));
        s.vertices = om.n_vertices();
        s.faces = om.n_faces();
        for (auto v : om.vertices()) {
            const auto& p = om.point(v);
            s.bounds.extend(Vec3{p[0], p[1], p[2]});
        }
        if (opt.check(OpenMesh::IO::Options::FaceColor)) {
            s.face_colours.reserve(s.faces);
            for (auto f : om.faces()) {
                const auto& c = om.color(f);
                s.face_colours.push_back({c[0], c[1], c[2]});
            }
        }
        OpenMesh::FPropHandleT<int> tag;
        if (om.get_property_handle(tag, kTagProperty)) {
            s.tags.reserve(s.faces);
            for (auto f : om.faces()) s.tags.push_back(om.property(tag, f));
        }
    }

    // Comments, read as text: PLY header lines up to "end_header" (ASCII in binary files too).
    std::ifstream in(path, std::ios::binary);
    std::string line;
    const bool ply = format == MeshFormat::PlyBinary || format == MeshFormat::PlyAscii;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (ply) {
            if (line == "end_header") break;
            if (line.rfind("comment ", 0) == 0) s.comments.push_back(line.substr(8));
        } else if (!line.empty() && line[0] == '#') {
            size_t from = 1;
            while (from < line.size() && line[from] == ' ') ++from;
            s.comments.push_back(line.substr(from));
        }
    }
    return s;
}

}  // namespace ltm
