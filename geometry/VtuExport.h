#pragma once
// Export of tetrahedral meshes (geometry/TetMesh.h) as VTK XML UnstructuredGrid files (.vtu), for
// viewing in ParaView or reading with meshio.
//
// The file holds the vertices as Points (Float64, 3 components), the tetrahedra as Cells
// (connectivity and offsets Int64, types UInt8, all 10 = VTK_TETRA, with the TetMesh's vertex
// order, so cell i is tetrahedron i), and two Float64 PointData arrays: "n2" (the mesh's n^2 per
// vertex) and "n" (its square root, the active scalars). Format "ascii" with 17 significant
// digits, which print every double exactly: the file holds the mesh's values bit for bit, and is
// plain text that needs no base64 or byte-order handling by any reader. It is about 100 bytes
// per tetrahedron (a million-tetrahedron mesh makes ~100 MB); the text is streamed to the file in
// 1 MiB blocks, so memory stays small whatever the mesh.
#include <string>

#include "geometry/TetMesh.h"

namespace ltm {

// Writes `mesh` to `path`. Atomic (io/AtomicFile.h): the text goes to a temporary file in the
// same folder, which is renamed onto `path` once complete, so `path` holds either its previous
// content or the whole new file. Throws std::runtime_error naming `path` (leaving no temporary behind and `path`
// untouched) when the folder does not exist (it is never created) or is not a folder, when the
// mesh is inconsistent (n2 and vertices differ in number, a vertex index is out of range, a
// coordinate or n2 is not finite, n2 < 0) -- checked before any file is touched -- or when a file
// operation fails.
void write_vtu(const std::string& path, const TetMesh& mesh);

}  // namespace ltm
