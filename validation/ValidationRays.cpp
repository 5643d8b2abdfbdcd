// The validation ray set (ValidationRays.h).
//
// Every ray is built from the scene's analytic description with the reference solver
// (AnalyticScene): points on the front face and their normals come from exact intersections,
// rays aimed at a defect are found by inverse refraction, and the "tir" rays are selected by
// tracing candidates. The set is deterministic: quasi-random numbers come from the golden-ratio
// sequence and a fixed integer hash (splitmix64), never from <random>, whose distributions differ
// between standard libraries.
#include "validation/ValidationRays.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>

#include "validation/AnalyticScene.h"

namespace ltm::validation {

namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kGolden = 0.6180339887498949;          // (sqrt(5) - 1) / 2
constexpr double kGoldenAngle = 2.399963229728653;      // pi (3 - sqrt(5))

double frac(double x) { return x - std::floor(x); }

// splitmix64 (Steele, Lea, Flood 2014) mapped to [0, 1): a fixed, portable hash.
double hash01(std::uint64_t i) {
    std::uint64_t z = i + 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1p-53;
}

struct Builder {
    const Scene& scene;
    AnalyticScene as;
    double a, z0, L;
    std::vector<ValidationRay> rays;

    explicit Builder(const Scene& s) : scene(s), as(s) {
        a = as.aperture_radius();
        z0 = as.z_min() - 1.0;
        L = as.length_scale();
    }

    void add(const Vec3& o, const Vec3& d, const char* category) { rays.push_back({o, normalize(d), category}); }

    // The front face at (x, y) (rho < a) and its unit normal pointing into the air (toward the
    // camera side), by an exact axial hit of the front patch.
    bool front_point(double x, double y, Vec3& P, Vec3& N_out) const {
        const SurfaceHit h = as.hit_one(0, {x, y, z0}, {0.0, 0.0, 1.0});
        if (!h.hit) return false;
        P = h.point;
        N_out = h.normal.z > 0 ? -h.normal : h.normal;
        return true;
    }

    // A ray from air that meets the object first at the front point P: origin P - s d. Accepted
    // only if the origin is in air and the solver's first hit is the front face at P.
    std::optional<ValidationRay> entering_front(const Vec3& P, const Vec3& d_in, double s, const char* cat) const {
        const Vec3 d = normalize(d_in);
        const Vec3 o = P - d * s;
        if (as.medium_at(o).kind != MediumKind::Air) return std::nullopt;
        const SurfaceHit h = as.first_hit(o, d, Medium{});
        if (!h.hit || h.surface != 0 || distance(h.point, P) > 1e-9 * L) return std::nullopt;
        return ValidationRay{o, d, cat};
    }

    // The air ray whose refracted segment in the glass is the line through T with direction dg
    // (unit). Inverse refraction: Snell's law is reversible (the law is symmetric in the two
    // media), so the air direction is minus the refraction of -dg leaving the glass at the front
    // point F where the line, followed backward, meets the front face. Returns nothing if that
    // backward line does not meet the front patch or the reversed refraction is total.
    std::optional<ValidationRay> through_glass_point(const Vec3& T, const Vec3& dg, const char* cat) const {
        const SurfaceHit F = as.hit_one(0, T, -dg);
        if (!F.hit) return std::nullopt;
        const Interaction back = interact(-dg, F.normal, as.ior(), 1.0);
        if (back.tir) return std::nullopt;
        const Vec3 da = -back.direction;
        if (!(da.z > 1e-3)) return std::nullopt;
        const Vec3 o = F.point - da * ((F.point.z - z0) / da.z);
        if (as.medium_at(o).kind != MediumKind::Air) return std::nullopt;
        return ValidationRay{o, da, cat};
    }

    // The half-width of defect k's silhouette seen along unit direction dg, in the unit direction
    // e perpendicular to dg: the largest lambda such that the line c + lambda e + s dg meets the
    // defect. In body coordinates (M maps the ellipsoid onto the unit sphere) the line is
    // lambda e' + s d' (e' = M e, d' = M dg); its distance from the centre is
    // lambda |e' - (e'.u) u| with u = d' / |d'|, and it touches the unit sphere when that is 1.
    double half_width(const Defect& def, const Vec3& dg, const Vec3& e) const {
        if (def.is_sphere()) return def.semi_axes.x;
        Mat3 M;
        const double sa[3] = {def.semi_axes.x, def.semi_axes.y, def.semi_axes.z};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) M(i, j) = def.frame(j, i) / sa[i];
        const Vec3 ep = M * e, u = normalize(M * dg);
        return 1.0 / length(ep - u * dot(ep, u));
    }

    // Rays whose glass segment passes through defect k at offset fraction f of its half-width.
    std::optional<ValidationRay> at_defect(int k, const Vec3& dg_in, double f, double psi, const char* cat) const {
        const Defect& def = scene.defects[k];
        const Vec3 dg = normalize(dg_in);
        Vec3 e1, e2;
        orthonormal_basis(dg, e1, e2);
        const Vec3 e = e1 * std::cos(psi) + e2 * std::sin(psi);
        const Vec3 T = def.center + e * (f * half_width(def, dg, e));
        auto r = through_glass_point(T, dg, cat);
        if (!r) return r;
        // Keep it only if the reference path really goes front -> this defect.
        const Path p = as.principal_path(r->origin, r->direction);
        if (p.surfaces.size() < 2 || p.surfaces[0] != "front" || p.surface_ids[1] != 3 + k) return std::nullopt;
        return r;
    }

    static Vec3 tilted(double theta, double phi) {
        return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
    }
};

}  // namespace

std::vector<ValidationRay> validation_rays(const Scene& scene, int density) {
    if (density < 1) throw std::invalid_argument("validation_rays: density must be >= 1");
    std::string why;
    if (!supports(scene, &why)) throw std::invalid_argument("validation_rays: " + why);
    Builder B(scene);
    const double a = B.a, z0 = B.z0;
    const AnalyticScene& as = B.as;

    // ---- axial: the axis ray itself (rho = 0 exactly), then a square grid of parallel rays over
    // the aperture: spacing a / m, the points with rho <= 0.97 a (about pi (0.97 m)^2 of them,
    // m chosen for ~40 density rays); the grid's centre is the axis ray, not repeated.
    B.add({0.0, 0.0, z0}, {0.0, 0.0, 1.0}, "axial");
    {
        const int m = std::max(2, static_cast<int>(std::lround(std::sqrt(40.0 * density / kPi))));
        const double h = a / m;
        for (int i = -m; i <= m; ++i)
            for (int j = -m; j <= m; ++j) {
                if (i == 0 && j == 0) continue;
                if (double(i * i + j * j) > 0.97 * 0.97 * m * m) continue;
                B.add({i * h, j * h, z0}, {0.0, 0.0, 1.0}, "axial");
            }
    }

    // ---- tilted: angles theta = asin(NA) * {0.2, 0.4, 0.6, 0.8, 1.0} and 2, 5, 10 degrees in
    // turn, azimuths from the golden-ratio sequence, each aimed at a point of the plane z = 0 on a
    // Vogel spiral of radius 0.8 a (origin moved back along the ray to z = z0).
    // Without bubbles the ~60 density rays of the "bubble" category go to these three categories
    // instead (+30, +15, +15), so every scene has ~200 density rays.
    int nbubbles = 0;
    for (const Defect& d : scene.defects) nbubbles += d.type == DefectType::Bubble;
    const int extra = nbubbles == 0 ? density : 0;
    {
        const int n = 40 * density + 30 * extra;
        const double th_na = std::asin(scene.camera.numerical_aperture);
        const double big[3] = {2.0 * kDeg, 5.0 * kDeg, 10.0 * kDeg};
        for (int i = 0; i < n; ++i) {
            const int j = i % 8;
            const double th = j < 5 ? th_na * (j + 1) / 5.0 : big[j - 5];
            const double phi = 2 * kPi * frac(i * kGolden + 0.1);
            const double r = 0.8 * a * std::sqrt((i + 0.5) / n), ang = i * kGoldenAngle;
            const Vec3 T{r * std::cos(ang), r * std::sin(ang), 0.0};
            const Vec3 d = Builder::tilted(th, phi);
            B.add(T - d * ((T.z - z0) / d.z), d, "tilted");
        }
    }

    // ---- near-rim: parallel rays at rho = a (0.98 + 0.02 (i + 1/2) / n) in (0.98 a, a), and four
    // at rho = a - 1e-6 a exactly on the x and y axes.
    {
        const int n = 20 * density + 15 * extra;
        for (int i = 0; i < n; ++i) {
            const double rho = a * (0.98 + 0.02 * (i + 0.5) / n), ang = i * kGoldenAngle;
            B.add({rho * std::cos(ang), rho * std::sin(ang), z0}, {0.0, 0.0, 1.0}, "near-rim");
        }
        const double r = a - 1e-6 * a;
        B.add({r, 0.0, z0}, {0.0, 0.0, 1.0}, "near-rim");
        B.add({-r, 0.0, z0}, {0.0, 0.0, 1.0}, "near-rim");
        B.add({0.0, r, z0}, {0.0, 0.0, 1.0}, "near-rim");
        B.add({0.0, -r, z0}, {0.0, 0.0, 1.0}, "near-rim");
    }

    // ---- grazing: a point P of the front face (Vogel spiral, rho <= 0.85 a) and an incidence
    // angle theta in {75, 80, 85, 88, 89, 89.5} degrees: d = -cos(theta) N + sin(theta) T with N
    // the face's normal into the air and T a unit tangent at P (a mix of the radial and azimuthal
    // tangents). The origin is 2 mm back along the ray, which is air: before its entry point a
    // line is outside the front sphere's ball for a convex face, inside it for a concave one,
    // and below the plane for a flat one, in each case outside the glass (checked anyway).
    {
        const int n = 20 * density + 15 * extra;
        const double inc[6] = {75, 80, 85, 88, 89, 89.5};
        int made = 0;
        for (int i = 0; made < n && i < 8 * n; ++i) {
            const double r = 0.85 * a * std::sqrt((i + 0.5) / (2.0 * n)), ang = i * kGoldenAngle;
            Vec3 P, N;
            if (!B.front_point(r * std::cos(ang), r * std::sin(ang), P, N)) continue;
            const Vec3 ephi{-std::sin(ang), std::cos(ang), 0.0};  // tangent to the face (symmetry)
            const Vec3 erad = normalize(cross(ephi, N));           // the other tangent
            const double psi = 2 * kPi * hash01(1000 + i);
            const Vec3 T = erad * std::cos(psi) + ephi * std::sin(psi);
            const double th = inc[i % 6] * kDeg;
            if (auto ray = B.entering_front(P, -N * std::cos(th) + T * std::sin(th), 2.0, "grazing")) {
                B.rays.push_back(*ray);
                ++made;
            }
        }
    }

    // ---- bubble / particle: for each defect, glass directions dg in {+z, 3 deg at 0 deg azimuth,
    // 3 deg at 120, 6 deg at 240} and offset fractions {0, 0.5, 0.9, 0.99, 0.999} of the
    // silhouette half-width, in turn (4 and 5 are coprime, so 20 rays cover every pair), at
    // quasi-random offset azimuths. The first is the diameter ray along +z through the centre.
    {
        int nb = 0, np = 0;
        for (const Defect& d : scene.defects) (d.type == DefectType::Particle ? np : nb)++;
        const Vec3 dirs[4] = {{0, 0, 1}, Builder::tilted(3 * kDeg, 0), Builder::tilted(3 * kDeg, 120 * kDeg),
                              Builder::tilted(6 * kDeg, 240 * kDeg)};
        const double fb[5] = {0.0, 0.5, 0.9, 0.99, 0.999};
        for (size_t k = 0; k < scene.defects.size(); ++k) {
            const bool particle = scene.defects[k].type == DefectType::Particle;
            const int n = particle ? std::max(3, 10 * density / std::max(1, np))
                                   : std::max(10, 60 * density / std::max(1, nb));
            int made = 0;
            for (int j = 0; made < n && j < 4 * n; ++j) {
                const double f = particle ? fb[j % 3] : fb[j % 5];
                const double psi = j == 0 ? 0.0 : 2 * kPi * frac(j * kGolden);
                if (auto r = B.at_defect(int(k), dirs[j % 4], f, psi, particle ? "particle" : "bubble")) {
                    B.rays.push_back(*r);
                    ++made;
                }
            }
        }
    }

    // ---- tir: candidates from four families, traced with the reference solver; those whose
    // principal path has tir_count > 0 are kept, taken from the families in turn (round robin)
    // until 25 density rays are found or the candidates run out (a window with an absorbing rim
    // and no bubbles has no TIR path from outside at all: its faces are parallel, so a ray
    // refracted in by one face meets the other below the critical angle).
    //   1. (polished rim) rays entering THROUGH THE RIM at elevations -50..70 deg: inside they
    //      travel at < asin(1/n) from the horizontal, so for n > sqrt(2) they meet a flat face
    //      above the critical angle (the light-pipe effect), and nearly so for curved faces;
    //   2. (polished rim) rays entering the front near the edge (rho in 0.9..0.99 a), tilted
    //      outward by 5..30 deg: they meet the rim from inside at ~90 deg minus a small angle,
    //      above the critical angle for any n;
    //   3. (bubbles) glass segments at offsets 0.8..0.99 of a bubble's half-width: the incidence
    //      on a sphere is asin(offset), above the critical angle asin(1/n) when offset > 1/n;
    //   4. (any) steep rays (30..75 deg) entering the front anywhere in 0.3..0.99 a: with curved
    //      faces they may meet the back face above the critical angle.
    {
        const int want = 25 * density;
        const int cand = 8 * want;
        std::vector<std::vector<ValidationRay>> fam(4);
        auto keep = [&](int f, const std::optional<ValidationRay>& r) {
            if (!r) return;
            const Path p = as.principal_path(r->origin, r->direction);
            if (p.tir_count > 0) fam[f].push_back(*r);
        };
        const double ze = as.z_front(a), zb = as.z_back(a);
        if (scene.object.rim == RimFinish::Polished) {
            const double elev[7] = {-50, -30, -15, 15, 30, 50, 70};
            const double dev[3] = {0, 20, -35};
            for (int i = 0; i < cand && int(fam[0].size()) < want; ++i) {
                const double ang = i * kGoldenAngle;
                const Vec3 er{std::cos(ang), std::sin(ang), 0.0}, ephi{-std::sin(ang), std::cos(ang), 0.0};
                const double zr = ze + (0.15 + 0.7 * hash01(2000 + i)) * (zb - ze);
                const Vec3 target = er * a + Vec3{0.0, 0.0, zr};
                const double be = elev[i % 7] * kDeg, ga = dev[i % 3] * kDeg;
                const Vec3 d = (-er * std::cos(ga) + ephi * std::sin(ga)) * std::cos(be) + Vec3{0, 0, std::sin(be)};
                const Vec3 o = target - d * 3.0;
                if (as.medium_at(o).kind != MediumKind::Air) continue;
                const SurfaceHit h = as.first_hit(o, d, Medium{});
                if (!h.hit || h.surface != 2 || distance(h.point, target) > 1e-9 * B.L) continue;
                keep(0, ValidationRay{o, d, "tir"});
            }
            const double tilt[4] = {5, 10, 20, 30};
            for (int i = 0; i < cand && int(fam[1].size()) < want; ++i) {
                const double ang = i * kGoldenAngle, r = a * (0.9 + 0.09 * hash01(3000 + i));
                Vec3 P, N;
                if (!B.front_point(r * std::cos(ang), r * std::sin(ang), P, N)) continue;
                const Vec3 d = Builder::tilted(tilt[i % 4] * kDeg, ang + (hash01(3500 + i) - 0.5) * 0.6);
                keep(1, B.entering_front(P, d, (P.z - z0) / d.z, "tir"));
            }
        }
        {
            const double off[4] = {0.8, 0.9, 0.95, 0.99};
            const Vec3 dirs[3] = {{0, 0, 1}, Builder::tilted(4 * kDeg, 60 * kDeg), Builder::tilted(8 * kDeg, 200 * kDeg)};
            std::vector<int> bubbles;
            for (size_t k = 0; k < scene.defects.size(); ++k)
                if (scene.defects[k].type == DefectType::Bubble) bubbles.push_back(int(k));
            for (int i = 0; !bubbles.empty() && i < cand && int(fam[2].size()) < want; ++i) {
                const int k = bubbles[i % bubbles.size()];
                keep(2, B.at_defect(k, dirs[i % 3], off[i % 4], 2 * kPi * hash01(4000 + i), "tir"));
            }
        }
        {
            const double tilt[4] = {30, 45, 60, 75};
            for (int i = 0; i < cand && int(fam[3].size()) < want; ++i) {
                const double ang = i * kGoldenAngle, r = a * (0.3 + 0.69 * hash01(5000 + i));
                Vec3 P, N;
                if (!B.front_point(r * std::cos(ang), r * std::sin(ang), P, N)) continue;
                const Vec3 d = Builder::tilted(tilt[i % 4] * kDeg, 2 * kPi * hash01(5500 + i));
                keep(3, B.entering_front(P, d, 2.0, "tir"));
            }
        }
        int taken = 0;
        std::vector<size_t> next(4, 0);
        for (bool progress = true; progress && taken < want;) {
            progress = false;
            for (int f = 0; f < 4 && taken < want; ++f)
                if (next[f] < fam[f].size()) {
                    B.rays.push_back(fam[f][next[f]++]);
                    ++taken;
                    progress = true;
                }
        }
    }
    return std::move(B.rays);
}

}  // namespace ltm::validation
