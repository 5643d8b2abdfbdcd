#pragma once
// The telecentric camera and the programmable display (docs/conventions.md).
//
// Camera: orthographic, looking along +z. Pixel (m, n) (row m from the +y edge down, column n
// from -x; k = m N + n) sees the rectangle of the focus plane z = focus_z
//   x in [-W/2 + n W/N, -W/2 + (n+1) W/N],  y in [H/2 - (m+1) H/M, H/2 - m H/M],
// through directions within the acceptance cone of half-angle asin(NA) about +z, sampled uniformly
// over the aperture (i.e. over the disc of direction sines of radius NA: the projected solid
// angle a telecentric stop passes). Rays start in air at z = start_z, before the object.
// Display: the plane z = Z; pixel (p, q) covers x in [-W/2 + q W/Q, ...], y in
// [H/2 - (p+1) H/P, H/2 - p H/P]; l = p Q + q.
#include <cmath>
#include <vector>

#include "geometry/Vec3.h"
#include "scene/Scene.h"
#include "trace/Rng.h"
#include "trace/SinCos.h"

namespace ltm {

struct Display {
    double z = 60, width = 100, height = 100;
    int Q = 500, P = 500;
    explicit Display(const DisplayDesc& d)
        : z(d.z), width(d.size[0]), height(d.size[1]), Q(d.resolution[0]), P(d.resolution[1]) {}
    // The pixel index l hit at (x, y), or -1 off the display. Points on the far edges belong to
    // the last row / column.
    long pixel(double x, double y, int* p_out = nullptr, int* q_out = nullptr) const {
        const double fx = (x + 0.5 * width) / width * Q, fy = (0.5 * height - y) / height * P;
        if (!(fx >= 0 && fx <= Q && fy >= 0 && fy <= P)) return -1;
        const int q = std::min(Q - 1, static_cast<int>(fx)), p = std::min(P - 1, static_cast<int>(fy));
        if (p_out) *p_out = p;
        if (q_out) *q_out = q;
        return static_cast<long>(p) * Q + q;
    }
    long pixels() const { return static_cast<long>(P) * Q; }
};

class TelecentricCamera {
public:
    TelecentricCamera(const CameraDesc& c, double start_z)
        : width_(c.size[0]), height_(c.size[1]), N_(c.resolution[0]), M_(c.resolution[1]), na_(c.numerical_aperture),
          focus_z_(c.focus_z), start_z_(start_z), spp_(c.samples_per_pixel) {
        grid_ = static_cast<int>(std::lround(std::sqrt(static_cast<double>(spp_))));
        if (grid_ * grid_ != spp_) grid_ = 0;
    }
    long pixels() const { return static_cast<long>(M_) * N_; }
    int samples_per_pixel() const { return spp_; }
    // The centre of pixel k's footprint on the focus plane.
    Vec3 pixel_centre(long k) const {
        const long m = k / N_, n = k % N_;
        return {-0.5 * width_ + (n + 0.5) * width_ / N_, 0.5 * height_ - (m + 0.5) * height_ / M_, focus_z_};
    }

    // Sample s of pixel k. Positions are stratified over the footprint: a jittered grid when spp
    // is a square, otherwise Latin-hypercube strata (x stratum s, y stratum from a per-pixel
    // permutation `perm`). `rng` supplies the jitter and the direction: four draws, in order.
    void sample(long k, int s, const std::vector<int>& perm, Rng& rng, Vec3& origin, Vec3& dir) const {
        double u[4];
        for (double& x : u) x = rng.uniform();
        sample_from(k, s, perm, u, origin, dir);
    }
    // Samples s0, ..., s0 + n - 1 of pixel k (n <= 16) with their streams: rng[i] is
    // Rng(seed, k, s0 + i) after sample() took its draws, origin[i] and dir[i] what sample() gives,
    // bit for bit. Computed in SIMD lanes (trace/Camera.cpp).
    void sample_packet(long k, int s0, int n, const std::vector<int>& perm, std::uint64_t seed, Rng* rng,
                       Vec3* origin, Vec3* dir) const;
    // Sample s from its four draws u (sample's arithmetic).
    void sample_from(long k, int s, const std::vector<int>& perm, const double u[4], Vec3& origin, Vec3& dir) const {
        const long m = k / N_, n = k % N_;
        double fx, fy;
        if (grid_ > 0) {
            fx = ((s % grid_) + u[0]) / grid_;
            fy = ((s / grid_) + u[1]) / grid_;
        } else {
            fx = (s + u[0]) / spp_;
            fy = (perm[static_cast<size_t>(s)] + u[1]) / spp_;
        }
        const double x = -0.5 * width_ + (n + fx) * width_ / N_;
        const double y = 0.5 * height_ - (m + fy) * height_ / M_;
        // The azimuth 2 pi u[3]'s cosine and sine by the function a SIMD lane repeats bit for bit.
        const double r = na_ * std::sqrt(u[2]);
        const CosSin phi = cos_sin_turns(u[3]);
        dir = {r * phi.cos, r * phi.sin, std::sqrt((1.0 - r) * (1.0 + r))};
        const Vec3 focus{x, y, focus_z_};
        origin = focus - dir * ((focus_z_ - start_z_) / dir.z);
    }
    // The per-pixel stratum permutation for Latin-hypercube sampling (empty for a square spp).
    std::vector<int> permutation(long k, std::uint64_t seed) const {
        if (grid_ > 0) return {};
        std::vector<int> p(static_cast<size_t>(spp_));
        for (int i = 0; i < spp_; ++i) p[static_cast<size_t>(i)] = i;
        Rng rng(seed, static_cast<std::uint64_t>(k), 0xfeedull << 32);
        for (int i = spp_ - 1; i > 0; --i) {
            const int j = static_cast<int>(rng.uniform() * (i + 1));
            std::swap(p[static_cast<size_t>(i)], p[static_cast<size_t>(j)]);
        }
        return p;
    }

private:
    double width_, height_;
    int N_, M_;
    double na_, focus_z_, start_z_;
    int spp_, grid_ = 0;
};

}  // namespace ltm
