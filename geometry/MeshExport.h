#pragma once
// Export of tagged triangle meshes for MeshLab, meshio and other readers (and reading them back
// for tests).
//
// Every format holds the TriMesh exactly: its vertices in order, as the doubles the program holds
// (binary: float64; text: 17 significant digits, which print every double so that a correctly
// rounding reader gets it back bit for bit), and its triangles in order, each with its vertices
// in the TriMesh's order, so face i of the file is triangle i of the mesh. Nothing is merged or
// split: a non-manifold mesh is written as it is (MeshLab then reports its non-manifold edges).
//
// What each format carries, chosen so that Debian's meshio (5.0) reads every file and Debian's
// MeshLab (2020.09) every PLY and OFF file (tests/app_mesh_command.cpp checks both on real
// scenes, tests/geometry_export.cpp each layout):
//   ASCII PLY (the default for .ply)  vertices (double x, y, z); faces with their vertex_indices
//       (uchar count, int indices), one RGB colour (uchar red, green, blue: the colour of the role
//       of the face's surface, role_colour()) and an int "tag" (the index into the SurfaceTable);
//       header comments: units and axes, the colour legend (one line per table entry). MeshLab
//       shows the face colours; meshio returns red, green, blue and tag as cell data.
//   binary PLY (little-endian)  vertices (double x, y, z) and faces (vertex_indices only); header
//       comments: units and axes. No colours or tags: meshio 5.0's binary PLY reader reads a face
//       element's properties as if each were stored for all faces in turn (all the index lists,
//       then one value of each further property), not face by face as PLY stores them, so it
//       misreads (or fails on) any face element with a property besides vertex_indices.
//   OFF (ASCII, "OFF")  vertices and faces only. meshio's OFF reader accepts the header "OFF" only
//       (not "COFF") and exactly four integers per face, so no colours, and no comment lines.
//   OBJ  vertices and faces (1-based "f" lines), plus '#' comment lines with the units and axes.
//       No colours: OBJ has colours only through a material library, a second file, which defeats
//       the atomic single-file write. (Debian's MeshLab 2020.09 aborts on every OBJ file, its own
//       included: Debian bug #1054006, MeshLab issue #1270. meshio reads them.)
//
// The writers are ltmsim's own, not OpenMesh's: OpenMesh 9 writes coordinates as 32-bit floats
// even from a double mesh, labels face-coloured OFF "COFF", and splits non-manifold faces off
// with copies of their vertices. OpenMesh reads the files back (read_mesh_summary), as a third
// independent reader for the tests.
//
// Thread safety: calls of read_mesh_summary are serialised by a mutex, because OpenMesh's message
// streams (omerr, omlog, omout) are process-wide and are redirected during a call (their messages
// go into the exception text on failure, not onto std::cerr).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/SurfaceTable.h"
#include "geometry/TriMesh.h"

namespace ltm {

enum class MeshFormat { PlyAscii, PlyBinary, Obj, Off };

const char* to_string(MeshFormat f);

// The format for a path by its extension, case-insensitively: ".ply" (ASCII unless
// `binary_ply`), ".obj", ".off". Throws std::invalid_argument naming the extension (or its
// absence) and the supported ones for anything else, and for `binary_ply` with an extension
// other than ".ply" (OBJ and OFF are text only).
MeshFormat mesh_format_for(const std::string& path, bool binary_ply);

// Writes `mesh` to `path` in format `fmt` (the extension of `path` is not consulted), with what
// the format carries (see above).
//
// Atomic (io/AtomicFile.h): the file is written to a temporary file in the same folder and
// renamed onto `path`, so `path` holds either its previous content or the complete new file,
// never a partial one. Throws std::runtime_error naming `path` (and leaves no temporary behind
// and `path` untouched) when: the folder does not exist (it is never created) or is not a
// folder; `path` is a folder; the mesh is inconsistent (tags and triangles differ in number, a
// tag is outside `table`, a vertex index is out of range, more vertices than a PLY int index
// holds, a coordinate is not finite) -- checked before any file is touched; or any file
// operation fails.
void write_mesh(const std::string& path, const TriMesh& mesh, const SurfaceTable& table, MeshFormat fmt);

// What a mesh file holds, as OpenMesh's reader sees it (the format is taken from the extension
// as in mesh_format_for; PLY may be binary or ASCII).
struct MeshFileSummary {
    size_t vertices = 0;
    size_t faces = 0;
    std::vector<int> tags;                                 // per face; PLY with a "tag" property only, else empty
    std::vector<std::array<std::uint8_t, 3>> face_colours; // per face when the file has face colours, else empty
    std::vector<std::string> comments;  // PLY: header "comment" lines; OBJ / OFF: '#' lines; prefix stripped
    Aabb bounds;                        // of the vertices as OpenMesh read them
};

// Reads `path` with OpenMesh, requesting face colours and the custom "tag" face property.
// OpenMesh's halfedge mesh cannot hold a non-manifold face; it gives such a face its own copies
// of its vertices, so for a non-manifold file `vertices` exceeds the file's count.
// Throws std::runtime_error naming the path when the file is missing or unreadable, and
// std::invalid_argument for an unsupported extension.
MeshFileSummary read_mesh_summary(const std::string& path);

}  // namespace ltm
