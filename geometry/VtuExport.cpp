#include "geometry/VtuExport.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "geometry/ExportWriter.h"
#include "io/AtomicFile.h"

namespace ltm {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& path, const std::string& why) {
    throw std::runtime_error(fmt::format("cannot write VTU file '{}': {}", path, why));
}

void validate(const std::string& path, const TetMesh& mesh) {
    const size_t nv = mesh.vertices.size();
    if (mesh.n2.size() != nv) fail(path, fmt::format("the mesh has {} vertices but {} n2 values", nv, mesh.n2.size()));
    for (size_t v = 0; v < nv; ++v) {
        const Vec3& p = mesh.vertices[v];
        if (!is_finite(p)) fail(path, fmt::format("vertex {} has a non-finite coordinate ({}, {}, {})", v, p.x, p.y, p.z));
        if (!std::isfinite(mesh.n2[v]) || mesh.n2[v] < 0)
            fail(path, fmt::format("vertex {} has n2 = {}, which has no real square root n", v, mesh.n2[v]));
    }
    for (size_t t = 0; t < mesh.tets.size(); ++t)
        for (auto i : mesh.tets[t])
            if (i >= nv) fail(path, fmt::format("tetrahedron {} uses vertex {}, but the mesh has {} vertices", t, i, nv));
}

}  // namespace

void write_vtu(const std::string& path, const TetMesh& mesh) {
    if (path.empty()) throw std::runtime_error("cannot write VTU file: the path is empty");
    const fs::path parent = fs::path(path).parent_path();
    const fs::path folder = parent.empty() ? fs::path(".") : parent;
    std::error_code ec;
    if (!fs::exists(folder, ec)) fail(path, fmt::format("the folder '{}' does not exist", folder.string()));
    if (!fs::is_directory(folder, ec)) fail(path, fmt::format("'{}' is not a folder", folder.string()));
    validate(path, mesh);

    io::AtomicFile file(path, "VTU file");
    ExportWriter out(file);
    const size_t nv = mesh.vertices.size(), nt = mesh.tets.size();
    // Version 0.1 is the one every VTK XML reader knows (meshio accepts 0.1 and 1.0; the two differ
    // only in features not used here). byte_order and header_type are irrelevant to ASCII data
    // and stated for readers that expect them.
    out.print("<?xml version=\"1.0\"?>\n"
              "<!-- ltmsim tetrahedral mesh: units mm; n2 = n^2 at the vertices, linear in each tetrahedron -->\n"
              "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
              "  <UnstructuredGrid>\n"
              "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n"
              "      <PointData Scalars=\"n\">\n"
              "        <DataArray type=\"Float64\" Name=\"n\" format=\"ascii\">\n",
              nv, nt);
    for (double v : mesh.n2) out.print("{:.17g}\n", std::sqrt(v));
    out.print("        </DataArray>\n"
              "        <DataArray type=\"Float64\" Name=\"n2\" format=\"ascii\">\n");
    for (double v : mesh.n2) out.print("{:.17g}\n", v);
    out.print("        </DataArray>\n"
              "      </PointData>\n"
              "      <Points>\n"
              "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (const Vec3& p : mesh.vertices) out.print("{:.17g} {:.17g} {:.17g}\n", p.x, p.y, p.z);
    out.print("        </DataArray>\n"
              "      </Points>\n"
              "      <Cells>\n"
              "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for (const auto& t : mesh.tets) out.print("{} {} {} {}\n", t[0], t[1], t[2], t[3]);
    out.print("        </DataArray>\n"
              "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for (size_t t = 0; t < nt; ++t) out.print("{}\n", 4 * (t + 1));
    out.print("        </DataArray>\n"
              "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (size_t t = 0; t < nt; ++t) out.print("10\n");
    out.print("        </DataArray>\n"
              "      </Cells>\n"
              "    </Piece>\n"
              "  </UnstructuredGrid>\n"
              "</VTKFile>\n");
    out.flush();
    file.commit();
}

}  // namespace ltm
