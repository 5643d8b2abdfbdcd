#include "geometry/Tessellate.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace ltm {

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

double face_deviation(const TriMesh& mesh, size_t f, const Surface& s, int n) {
    const auto& t = mesh.triangles[f];
    const Vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    double dev = 0;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j) {
            const double u = double(i) / n, v = double(j) / n;
            dev = std::max(dev, std::fabs(s.signed_distance(a + (b - a) * u + (c - a) * v)));
        }
    if (s.kind == SurfaceKind::Sphere)
        dev = std::max(dev, std::fabs(s.signed_distance(closest_point_on_triangle(s.origin, a, b, c))));
    return dev;
}

namespace {

// Emits the band between ring `in` (m_in vertices, or the single apex when m_in == 1) and ring
// `out` (m_out vertices), both starting at azimuth 0 and sorted by increasing azimuth. Triangles
// are wound so their normal has +z (`up`) or -z orientation.
void stitch_rings(TriMesh& m, const std::vector<std::uint32_t>& in, const std::vector<std::uint32_t>& out,
                  bool up, int tag) {
    auto tri = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        if (up) m.add_triangle(a, b, c, tag); else m.add_triangle(a, c, b, tag);
    };
    const size_t mi = in.size(), mo = out.size();
    if (mi == 1) {
        for (size_t j = 0; j < mo; ++j) tri(in[0], out[j], out[(j + 1) % mo]);
        return;
    }
    size_t a = 0, b = 0;
    // Advance whichever ring's next vertex comes first in azimuth; compare (b+1)/mo <= (a+1)/mi
    // in integers so the choice is exact.
    while (a < mi || b < mo) {
        const bool advance_out = b < mo && (a == mi || (b + 1) * mi <= (a + 1) * mo);
        if (advance_out) {
            tri(in[a % mi], out[b], out[(b + 1) % mo]);
            ++b;
        } else {
            tri(in[a], out[b % mo], in[(a + 1) % mi]);
            ++a;
        }
    }
}

// Radii of rings 0..n of a cap: uniform in arc length on a sphere, uniform in rho on a plane.
std::vector<double> ring_radii(double R, double a, int n) {
    std::vector<double> r(static_cast<size_t>(n) + 1);
    const double theta_max = std::isinf(R) ? 0.0 : std::asin(a / std::fabs(R));
    for (int i = 0; i <= n; ++i) {
        if (std::isinf(R)) r[i] = a * i / n;
        else r[i] = std::fabs(R) * std::sin(theta_max * i / n);
    }
    r[n] = a;
    return r;
}

LensTessellation build_lens(const Lens& lens, int n, int tag_front, int tag_back, int tag_rim) {
    LensTessellation out;
    out.rings = n;
    TriMesh& m = out.mesh;
    const double a = lens.aperture_radius();
    const auto rf = ring_radii(lens.spec().r1, a, n);
    const auto rb = ring_radii(lens.spec().r2, a, n);
    // Rim rows: keep rim quads roughly square (height ~ the outer ring's vertex spacing).
    const double spacing = 2.0 * kPi * a / (6.0 * n);
    const int rows = std::max(1, static_cast<int>(std::ceil(lens.edge_thickness() / spacing)));
    out.rim_rows = rows;

    auto make_ring = [&](double rho, double z, int count) {
        std::vector<std::uint32_t> ring(static_cast<size_t>(count));
        for (int j = 0; j < count; ++j) {
            const double phi = 2.0 * kPi * j / count;
            ring[j] = m.add_vertex({rho * std::cos(phi), rho * std::sin(phi), z});
        }
        return ring;
    };
    std::vector<std::vector<std::uint32_t>> front(n + 1), back(n + 1);
    front[0] = {m.add_vertex({0, 0, lens.z_front(0)})};
    back[0] = {m.add_vertex({0, 0, lens.z_back(0)})};
    for (int i = 1; i <= n; ++i) {
        front[i] = make_ring(rf[i], lens.z_front(rf[i]), 6 * i);
        // A ball's hemispheres meet at the equator: they share its ring, and there is no rim.
        back[i] = lens.spec().ball && i == n ? front[n] : make_ring(rb[i], lens.z_back(rb[i]), 6 * i);
    }
    for (int i = 0; i < n; ++i) {
        stitch_rings(m, front[i], front[i + 1], /*up=*/false, tag_front);
        stitch_rings(m, back[i], back[i + 1], /*up=*/true, tag_back);
    }
    if (lens.spec().ball) {
        out.rim_rows = 0;
        return out;
    }
    // Rim: rows of quads from the front's outer ring (z0) to the back's (z1), outward normal.
    const double z0 = lens.z_front(a), z1 = lens.z_back(a);
    std::vector<std::uint32_t> lower = front[n];
    for (int r = 1; r <= rows; ++r) {
        std::vector<std::uint32_t> upper = r == rows ? back[n] : make_ring(a, z0 + (z1 - z0) * r / rows, 6 * n);
        const size_t cnt = lower.size();
        for (size_t j = 0; j < cnt; ++j) {
            const size_t k = (j + 1) % cnt;
            m.add_triangle(lower[j], lower[k], upper[k], tag_rim);
            m.add_triangle(lower[j], upper[k], upper[j], tag_rim);
        }
        lower = upper;
    }
    return out;
}

}  // namespace

LensTessellation tessellate_lens(const Lens& lens, double tol, int tag_front, int tag_back, int tag_rim) {
    if (!(tol > 0)) throw std::invalid_argument("chord tolerance must be positive");
    const double a = lens.aperture_radius();
    // The rim polygon's chords: a (1 - cos(pi / 6n)) <= tol.
    int n = static_cast<int>(std::ceil(kPi / (6.0 * std::acos(std::max(-1.0, 1.0 - tol / a)))));
    // Caps: a face of circumradius rc inscribed in a sphere of radius R deviates by about
    // rc^2 / (2R); ring spacing ~ R dtheta gives rc ~ spacing, so start from that estimate and
    // grow until the exact per-face check passes.
    for (double R : {lens.spec().r1, lens.spec().r2}) {
        if (std::isinf(R)) continue;
        const double theta = std::asin(a / std::fabs(R));
        const double h = std::sqrt(2.0 * std::fabs(R) * tol);
        n = std::max(n, static_cast<int>(std::ceil(theta * std::fabs(R) / h)));
    }
    n = std::max(n, 4);
    const Surface sf = lens.front_surface(), sb = lens.back_surface(), sr = lens.rim_surface();
    for (int attempt = 0; attempt < 40; ++attempt) {
        LensTessellation t = build_lens(lens, n, tag_front, tag_back, tag_rim);
        double err = 0;
        for (size_t f = 0; f < t.mesh.num_triangles(); ++f) {
            const int tag = t.mesh.tags[f];
            const Surface& s = tag == tag_front ? sf : (tag == tag_back ? sb : sr);
            if (s.kind == SurfaceKind::Plane) continue;  // vertices on a plane: the face is on it
            if (s.kind == SurfaceKind::Cylinder) {
                // A rim face spans one azimuth step between two axis-parallel lines: its chord
                // error is exactly that of the polygon edge, a (1 - cos(pi / 6n)).
                continue;
            }
            err = std::max(err, face_deviation(t.mesh, f, s, 0));
        }
        err = std::max(err, a * (1.0 - std::cos(kPi / (6.0 * n))));
        if (err <= tol) {
            t.chord_error = err;
            return t;
        }
        n = static_cast<int>(std::ceil(n * 1.1));
    }
    throw std::runtime_error("lens tessellation did not reach the chord tolerance");
}

namespace {

struct Icosphere {
    std::vector<Vec3> v;
    std::vector<std::array<std::uint32_t, 3>> f;
    double deviation = 0;  // unit-sphere chord error, exact
};

Icosphere subdivide(const Icosphere& s) {
    Icosphere next;
    next.v = s.v;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
        const auto key = std::minmax(a, b);
        auto it = mid.find(key);
        if (it != mid.end()) return it->second;
        next.v.push_back(normalize(s.v[a] + s.v[b]));
        const auto id = static_cast<std::uint32_t>(next.v.size() - 1);
        mid.emplace(key, id);
        return id;
    };
    for (const auto& t : s.f) {
        const auto ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
        next.f.push_back({t[0], ab, ca});
        next.f.push_back({t[1], bc, ab});
        next.f.push_back({t[2], ca, bc});
        next.f.push_back({ab, bc, ca});
    }
    return next;
}

// Unit icospheres by level (20 4^level faces), built on first use and kept; the chord error of
// each is measured exactly (1 - the smallest distance of a face from the centre).
const Icosphere& icosphere(int level) {
    static std::mutex mutex;
    static std::vector<std::unique_ptr<Icosphere>> cache;
    std::lock_guard<std::mutex> lock(mutex);
    if (cache.empty()) {
        auto s = std::make_unique<Icosphere>();
        const double p = (1.0 + std::sqrt(5.0)) / 2.0;
        s->v = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
        for (auto& x : s->v) x = normalize(x);
        s->f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
        cache.push_back(std::move(s));
    }
    while (static_cast<int>(cache.size()) <= level) cache.push_back(std::make_unique<Icosphere>(subdivide(*cache.back())));
    Icosphere& s = *cache[static_cast<size_t>(level)];
    if (s.deviation == 0) {
        double dev = 0;
        for (const auto& t : s.f)
            dev = std::max(dev, 1.0 - length(closest_point_on_triangle({0, 0, 0}, s.v[t[0]], s.v[t[1]], s.v[t[2]])));
        s.deviation = dev;
    }
    return s;
}

}  // namespace

EllipsoidTessellation tessellate_ellipsoid(const Vec3& centre, const Mat3& frame, const Vec3& e, double tol,
                                           int tag) {
    const double emax = std::max({e.x, e.y, e.z});
    int level = 0;
    while (level < 8 && icosphere(level).deviation * emax > tol) ++level;
    if (icosphere(level).deviation * emax > tol)
        throw std::invalid_argument("an ellipsoid of semi-axis " + std::to_string(emax) +
                                    " mm needs more than 1.3 million triangles for chord tolerance " +
                                    std::to_string(tol) + " mm: raise mesh.chord_tolerance");
    const Icosphere& s = icosphere(level);
    EllipsoidTessellation out;
    out.level = level;
    out.chord_error_bound = s.deviation * emax;
    for (const auto& v : s.v) out.mesh.add_vertex(centre + frame * Vec3{v.x * e.x, v.y * e.y, v.z * e.z});
    for (const auto& t : s.f) out.mesh.add_triangle(t[0], t[1], t[2], tag);
    return out;
}

TriMesh sweep_profile(const std::vector<Point2>& profile, int stations,
                      const std::function<Vec3(int, const Point2&)>& place, const std::vector<int>& edge_tags,
                      int tag_start, int tag_end) {
    const auto k = static_cast<std::uint32_t>(profile.size());
    if (k < 3 || stations < 2 || edge_tags.size() != profile.size())
        throw std::invalid_argument("sweep_profile: need >= 3 profile vertices, >= 2 stations, a tag per edge");
    TriMesh m;
    for (int s = 0; s < stations; ++s)
        for (const auto& p : profile) m.add_vertex(place(s, p));
    auto id = [&](int s, std::uint32_t i) { return static_cast<std::uint32_t>(s) * k + (i % k); };
    for (int s = 0; s + 1 < stations; ++s)
        for (std::uint32_t i = 0; i < k; ++i) {
            m.add_triangle(id(s, i), id(s + 1, i), id(s + 1, i + 1), edge_tags[i]);
            m.add_triangle(id(s, i), id(s + 1, i + 1), id(s, i + 1), edge_tags[i]);
        }
    // End caps: fans from the profile's centroid (the profile is convex).
    Point2 c{0, 0};
    for (const auto& p : profile) { c.s += p.s / k; c.t += p.t / k; }
    const std::uint32_t c0 = m.add_vertex(place(0, c));
    const std::uint32_t c1 = m.add_vertex(place(stations - 1, c));
    for (std::uint32_t i = 0; i < k; ++i) {
        // Wound against the side faces' use of the same boundary edges.
        m.add_triangle(c0, id(0, i), id(0, i + 1), tag_start);
        m.add_triangle(c1, id(stations - 1, i + 1), id(stations - 1, i), tag_end);
    }
    if (m.signed_volume() < 0)
        for (auto& t : m.triangles) std::swap(t[1], t[2]);
    return m;
}

}  // namespace ltm
