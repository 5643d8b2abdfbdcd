#include "geometry/TriMesh.h"

#include <array>

#include "geometry/SurfaceTable.h"

namespace ltm {

std::string to_string(Medium m) {
    if (m == Medium::Air) return "air";
    if (m == Medium::Glass) return "glass";
    if (m == Medium::Absorber) return "absorber";
    return "inhomogeneity " + std::to_string(m.defect());
}

const char* to_string(SurfaceRole r) {
    switch (r) {
        case SurfaceRole::Front: return "front";
        case SurfaceRole::Back: return "back";
        case SurfaceRole::Rim: return "rim";
        case SurfaceRole::Bubble: return "bubble";
        case SurfaceRole::Pit: return "pit";
        case SurfaceRole::Scratch: return "scratch";
        case SurfaceRole::Particle: return "particle";
        case SurfaceRole::Inhomogeneity: return "inhomogeneity";
    }
    return "?";
}

std::array<std::uint8_t, 3> role_colour(SurfaceRole r) {
    switch (r) {
        case SurfaceRole::Front: return {110, 170, 230};
        case SurfaceRole::Back: return {120, 210, 140};
        case SurfaceRole::Rim: return {190, 190, 190};
        case SurfaceRole::Bubble: return {240, 80, 60};
        case SurfaceRole::Pit: return {250, 160, 40};
        case SurfaceRole::Scratch: return {200, 60, 200};
        case SurfaceRole::Particle: return {40, 40, 40};
        case SurfaceRole::Inhomogeneity: return {90, 220, 220};
    }
    return {255, 255, 255};
}

void TriMesh::append(const TriMesh& other, bool flip) {
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
    for (size_t f = 0; f < other.triangles.size(); ++f) {
        auto t = other.triangles[f];
        if (flip) std::swap(t[1], t[2]);
        triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
        tags.push_back(other.tags[f]);
    }
}

Aabb TriMesh::bounds() const {
    Aabb b;
    for (const auto& v : vertices) b.extend(v);
    return b;
}

double TriMesh::signed_volume() const {
    const Aabb b = bounds();
    const Vec3 c = b.empty() ? Vec3{} : (b.lo + b.hi) * 0.5;
    double v = 0;
    for (const auto& t : triangles) {
        const Vec3 a = vertices[t[0]] - c, p = vertices[t[1]] - c, q = vertices[t[2]] - c;
        v += dot(a, cross(p, q));
    }
    return v / 6.0;
}

double TriMesh::area() const {
    double a = 0;
    for (size_t f = 0; f < triangles.size(); ++f) a += face_area(f);
    return a;
}

Vec3 TriMesh::face_normal(size_t f) const {
    const auto& t = triangles[f];
    return normalize(cross(vertices[t[1]] - vertices[t[0]], vertices[t[2]] - vertices[t[0]]));
}

double TriMesh::face_area(size_t f) const {
    const auto& t = triangles[f];
    return 0.5 * length(cross(vertices[t[1]] - vertices[t[0]], vertices[t[2]] - vertices[t[0]]));
}

}  // namespace ltm
