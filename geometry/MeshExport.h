#pragma once
// Export of tagged triangle meshes for viewing in MeshLab (and reading them back for tests).
//
// Exported files are PICTURES of the geometry, never a way to store it: OpenMesh writes vertex
// coordinates as 32-bit floats even from a double mesh (relative rounding up to 2^-24, about
// 6e-7 mm at 10 mm), so nothing in ltmsim ever re-reads an exported file for geometry; the
// geometry is always regenerated from the scene.
//
// What each format carries (OpenMesh 9 writers, checked by tests/geometry_export.cpp):
//   PLY (binary little-endian or ASCII)  geometry, one RGB colour per face (the colour of the
//       role of the face's surface, role_colour()), an int face property "tag" (the index into
//       the SurfaceTable), and header comments: units and axes, the colour legend (one line per
//       table entry), and a note when faces had to be given their own vertices (see below).
//       This is the format to use: MeshLab shows the face colours, and the tag is in the file.
//   OFF (ASCII)  geometry and per-face RGB colours, no tags, no comments. OpenMesh labels the
//       file "COFF" although the colours follow the faces, not the vertices; MeshLab 2020.09 and
//       OpenMesh both read it back with the face colours. Binary OFF is never written: OpenMesh
//       corrupts face colours of binary OFF on re-read (stack notes; on an 8-face file its
//       reader even failed an assertion).
//   OBJ  geometry only, plus '#' comment lines with the units and axes. OBJ has no per-face
//       colour; OpenMesh would write a material library (a second file, named after the file
//       being written) for face colours, which defeats atomic writing and the single-file
//       contract, so the OBJ is plain and .mtl-free.
// In every format the vertices and faces appear in the TriMesh's order (faces with their
// vertices in the TriMesh's order too), so face i of the file is triangle i of the mesh.
//
// Non-manifold input: OpenMesh's halfedge mesh rejects a face that would make a vertex or edge
// non-manifold (e.g. two solids touching at a vertex, or a duplicated face). Such a face is
// still exported, with its own copies of its three vertices (appended after the mesh's
// vertices), so the file has every face and the picture shows the defect (MeshLab then reports
// boundary edges and holes around the split-off faces); the PLY header says how many faces this
// happened to, and the file has more vertices than the mesh.
//
// Thread safety: calls of write_mesh / read_mesh_summary are serialised by a mutex, because
// OpenMesh's message streams (omerr, omlog, omout) are process-wide and are redirected during
// a call (their messages go into the exception text on failure, not onto std::cerr).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/SurfaceTable.h"
#include "geometry/TriMesh.h"

namespace ltm {

enum class MeshFormat { PlyBinary, PlyAscii, Obj, Off };

const char* to_string(MeshFormat f);

// The format for a path by its extension, case-insensitively: ".ply" (binary unless
// `ascii_ply`), ".obj", ".off". Throws std::invalid_argument naming the extension (or its
// absence) and the supported ones for anything else.
MeshFormat mesh_format_for(const std::string& path, bool ascii_ply);

// Writes `mesh` to `path` in format `fmt` (the extension of `path` is not consulted), with face
// colours by role and, for PLY, the "tag" face property and header comments (see above).
//
// Atomic (io/AtomicFile.h): the file is written to a temporary file in the same folder and
// renamed onto `path`, so `path` holds either its previous content or the complete new file,
// never a partial one. Throws std::runtime_error naming `path` (and leaves no temporary behind
// and `path` untouched) when: the folder does not exist (it is never created) or is not a
// folder; `path` is a folder; the mesh is
// inconsistent (tags and triangles differ in number, a tag is outside `table`, a vertex index
// is out of range, a coordinate is not finite) -- checked before any file is touched; OpenMesh
// fails; or any file operation fails.
void write_mesh(const std::string& path, const TriMesh& mesh, const SurfaceTable& table, MeshFormat fmt);

// What a mesh file holds, as OpenMesh's reader sees it (the format is taken from the extension
// as in mesh_format_for; PLY may be binary or ASCII).
struct MeshFileSummary {
    size_t vertices = 0;
    size_t faces = 0;
    std::vector<int> tags;                                 // per face; PLY with a "tag" property only, else empty
    std::vector<std::array<std::uint8_t, 3>> face_colours; // per face when the file has face colours, else empty
    std::vector<std::string> comments;  // PLY: header "comment" lines; OBJ / OFF: '#' lines; prefix stripped
    Aabb bounds;                        // of the vertices as read (float-rounded coordinates)
};

// Reads `path` with OpenMesh, requesting face colours and the custom "tag" face property.
// Throws std::runtime_error naming the path when the file is missing or unreadable, and
// std::invalid_argument for an unsupported extension.
MeshFileSummary read_mesh_summary(const std::string& path);

}  // namespace ltm
