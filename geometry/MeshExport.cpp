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
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "io/AtomicFile.h"

namespace ltm {
namespace {

namespace fs = std::filesystem;

// Double points so that the only rounding is the writer's own conversion to float; unsigned
// char RGB face colours (PLY "uchar red/green/blue", OFF integer colours).
struct ExportTraits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
    using Color = OpenMesh::Vec3uc;
    FaceAttributes(OpenMesh::Attributes::Color);
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<ExportTraits>;

constexpr const char* kTagProperty = "tag";
// float has 24 significand bits: 9 significant decimal digits print every float exactly
// (max_digits10), so ASCII files hold the same float values as binary ones. OpenMesh's default
// (6) would add up to 5e-7 relative on top of the float rounding.
constexpr std::streamsize kAsciiPrecision = 9;

// OpenMesh reports problems on its own process-wide streams (omerr for errors, omlog for chatter
// like "[OBJWriter] : write file"), by default onto std::cerr / std::clog. During one of our
// calls they are redirected into a string, which goes into the exception text on failure and is
// dropped on success. The mutex serialises our calls, as the streams are global.
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

const char* extension_of(MeshFormat f) {
    switch (f) {
        case MeshFormat::PlyBinary:
        case MeshFormat::PlyAscii: return ".ply";
        case MeshFormat::Obj: return ".obj";
        case MeshFormat::Off: return ".off";
    }
    return "";
}

// The folder a path lives in ("." for a bare file name).
fs::path folder_of(const std::string& path) {
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? fs::path(".") : parent;
}

// Everything that could make the export wrong or crash OpenMesh, checked before any file exists.
void validate(const std::string& path, const TriMesh& mesh, const SurfaceTable& table) {
    auto fail = [&](const std::string& why) {
        throw std::runtime_error(fmt::format("cannot write mesh '{}': {}", path, why));
    };
    if (mesh.tags.size() != mesh.triangles.size())
        fail(fmt::format("the mesh has {} triangles but {} tags", mesh.triangles.size(), mesh.tags.size()));
    const size_t nv = mesh.vertices.size();
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

struct BuiltMesh {
    OmMesh om;
    OpenMesh::FPropHandleT<int> tag;
    size_t faces_with_own_vertices = 0;
};

// Copies the TriMesh into OpenMesh, face by face in order (OpenMesh keeps insertion order for
// vertices and faces, and starts each face's vertex circulation at its first vertex).
void build(const TriMesh& mesh, const SurfaceTable& table, BuiltMesh& out) {
    OmMesh& om = out.om;
    om.reserve(mesh.vertices.size(), 3 * mesh.triangles.size() / 2, mesh.triangles.size());
    std::vector<OmMesh::VertexHandle> vh;
    vh.reserve(mesh.vertices.size());
    for (const Vec3& p : mesh.vertices) vh.push_back(om.add_vertex(OmMesh::Point(p.x, p.y, p.z)));

    om.add_property(out.tag, kTagProperty);
    om.property(out.tag).set_persistent(true);  // persistent custom properties go into PLY files

    for (size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto& t = mesh.triangles[f];
        OmMesh::FaceHandle fh = om.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
        if (!fh.is_valid()) {
            // Non-manifold (complex vertex / edge) or degenerate face: OpenMesh leaves the mesh
            // unchanged and returns an invalid handle. Keep the face with its own vertices.
            OmMesh::VertexHandle own[3];
            // A copy of the point, not om.point()'s reference: add_vertex may grow the point
            // array and read the reference after it moved (AddressSanitizer: heap-use-after-free).
            for (int k = 0; k < 3; ++k) {
                const OmMesh::Point p = om.point(vh[t[k]]);
                own[k] = om.add_vertex(p);
            }
            fh = om.add_face(own[0], own[1], own[2]);
            if (!fh.is_valid())
                throw std::logic_error(fmt::format("OpenMesh rejected isolated triangle {}", f));
            ++out.faces_with_own_vertices;
        }
        const auto rgb = role_colour(table[mesh.tags[f]].role);
        om.set_color(fh, OmMesh::Color(rgb[0], rgb[1], rgb[2]));
        om.property(out.tag, fh) = mesh.tags[f];
    }
}

std::vector<std::string> ply_comments(const SurfaceTable& table, size_t faces_with_own_vertices) {
    std::vector<std::string> c;
    c.push_back("ltmsim mesh export");
    c.push_back("units mm; axes right-handed, +z is the optical axis, camera at -z, display at +z");
    c.push_back("coordinates are float32: a picture for viewing, not geometry to re-read");
    c.push_back("face colour = role of the face's surface; face property tag = index into the legend below");
    for (size_t i = 0; i < table.size(); ++i) {
        const SurfaceInfo& s = table.entries[i];
        const auto rgb = role_colour(s.role);
        c.push_back(one_line(fmt::format("tag {} = {} ({}, rgb {} {} {}, inside {} / outside {})", i, s.name,
                                         to_string(s.role), rgb[0], rgb[1], rgb[2], to_string(s.inside),
                                         to_string(s.outside))));
    }
    if (faces_with_own_vertices > 0)
        c.push_back(fmt::format("warning: {} faces did not fit a manifold surface and were written with their "
                                "own copies of their vertices",
                                faces_with_own_vertices));
    return c;
}

// OpenMesh's PLY writer has no header comments. The header is ASCII lines up to and including
// "end_header\n" (also in binary PLY); comments go right after the "format ..." line, which the
// PLY grammar requires second (after "ply"). The body is kept byte for byte.
std::string insert_ply_comments(const std::string& ply, const std::vector<std::string>& comments) {
    const std::string end_marker = "end_header\n";
    const size_t header_end = ply.find(end_marker);
    if (ply.compare(0, 4, "ply\n") != 0 || header_end == std::string::npos)
        throw std::logic_error("OpenMesh's PLY output has no 'ply' line or no 'end_header' line");
    const size_t format_at = ply.find("\nformat ");
    if (format_at == std::string::npos || format_at > header_end)
        throw std::logic_error("OpenMesh's PLY output has no 'format' line");
    const size_t after_format = ply.find('\n', format_at + 1) + 1;
    std::string block;
    for (const auto& c : comments) block += "comment " + c + "\n";
    std::string out;
    out.reserve(ply.size() + block.size());
    out.append(ply, 0, after_format);
    out += block;
    out.append(ply, after_format, std::string::npos);
    return out;
}

// OBJ comments are '#' lines anywhere; they go first, before OpenMesh's "# n vertices" line.
std::string prepend_obj_comments(const std::string& obj) {
    return "# ltmsim mesh export\n"
           "# units mm; axes right-handed, +z is the optical axis, camera at -z, display at +z\n"
           "# coordinates are float32: a picture for viewing, not geometry to re-read\n"
           "# geometry only: face colours and surface tags are in the PLY export\n" +
           obj;
}

}  // namespace

const char* to_string(MeshFormat f) {
    switch (f) {
        case MeshFormat::PlyBinary: return "binary PLY";
        case MeshFormat::PlyAscii: return "ASCII PLY";
        case MeshFormat::Obj: return "OBJ";
        case MeshFormat::Off: return "ASCII OFF";
    }
    return "?";
}

MeshFormat mesh_format_for(const std::string& path, bool ascii_ply) {
    const std::string ext = lower(fs::path(path).extension().string());
    if (ext == ".ply") return ascii_ply ? MeshFormat::PlyAscii : MeshFormat::PlyBinary;
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".off") return MeshFormat::Off;
    const std::string what = ext.empty() ? std::string("has no extension")
                                         : fmt::format("has the unsupported extension '{}'",
                                                       fs::path(path).extension().string());
    throw std::invalid_argument(
        fmt::format("mesh file '{}' {}: supported are .ply (colours, tags and legend), .obj, .off", path, what));
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

    OpenMeshMessages messages;
    BuiltMesh built;
    build(mesh, table, built);

    OpenMesh::IO::Options opt = OpenMesh::IO::Options::Default;
    if (format != MeshFormat::Obj) opt += OpenMesh::IO::Options::FaceColor;  // OBJ: would need a .mtl file
    if (format == MeshFormat::PlyBinary) opt += OpenMesh::IO::Options::Binary;
    // Written to memory first: OpenMesh never touches the file system, and the PLY header can be
    // amended before anything reaches the disk.
    std::ostringstream os(std::ios::out | std::ios::binary);
    if (!OpenMesh::IO::write_mesh(built.om, os, extension_of(format), opt, kAsciiPrecision) || !os)
        throw std::runtime_error(fmt::format("cannot write mesh '{}': OpenMesh's {} writer failed{}", path,
                                             to_string(format), messages.text()));
    std::string bytes = os.str();
    switch (format) {
        case MeshFormat::PlyBinary:
        case MeshFormat::PlyAscii:
            bytes = insert_ply_comments(bytes, ply_comments(table, built.faces_with_own_vertices));
            break;
        case MeshFormat::Obj: bytes = prepend_obj_comments(bytes); break;
        // OFF: '#' comments are a Geomview extension that not every OFF reader skips.
        case MeshFormat::Off: break;
    }
    io::write_file(path, bytes, "mesh");
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
