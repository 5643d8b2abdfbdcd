#pragma once
// Small double-precision vector and rotation types used by every layer of ltmsim.
// Units are millimetres throughout; the world frame is right-handed with +z the optical axis
// (camera -> display), see docs/conventions.md.
#include <array>
#include <cmath>

namespace ltm {

struct Vec3 {
    double x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
    constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
    Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
    constexpr bool operator==(const Vec3& o) const { return x == o.x && y == o.y && z == o.z; }
};

constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
// sqrt(dot): lengths here are between ~1e-9 and ~1e6 mm, far from where squaring could overflow
// or underflow, so the careful (and several times slower) std::hypot is not needed.
inline double length(const Vec3& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
constexpr double length2(const Vec3& v) { return dot(v, v); }
inline Vec3 normalize(const Vec3& v) { return v / length(v); }
// normalize for a vector of any finite magnitude (user input): rescaled by its largest
// component first, so neither 1e200 nor 1e-170 over- or underflows when squared.
inline Vec3 normalize_any(const Vec3& v) {
    const double big = std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
    return normalize(v / big);
}
inline double distance(const Vec3& a, const Vec3& b) { return length(a - b); }
inline bool is_finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline Vec3 min(const Vec3& a, const Vec3& b) {
    return {std::fmin(a.x, b.x), std::fmin(a.y, b.y), std::fmin(a.z, b.z)};
}
inline Vec3 max(const Vec3& a, const Vec3& b) {
    return {std::fmax(a.x, b.x), std::fmax(a.y, b.y), std::fmax(a.z, b.z)};
}

// A unit vector orthogonal to n (n must be unit length). Duff et al., "Building an
// orthonormal basis, revisited" (JCGT 2017): branch-free and exact for n = +-z.
inline void orthonormal_basis(const Vec3& n, Vec3& b1, Vec3& b2) {
    const double s = std::copysign(1.0, n.z);
    const double a = -1.0 / (s + n.z);
    const double b = n.x * n.y * a;
    b1 = {1.0 + s * n.x * n.x * a, s * b, -s * n.x};
    b2 = {b, s + n.y * n.y * a, -n.y};
}

// 3x3 matrix, row-major. Used for rotations (orthonormal) and ellipsoid shape maps.
struct Mat3 {
    std::array<double, 9> m{1, 0, 0, 0, 1, 0, 0, 0, 1};
    static Mat3 identity() { return {}; }
    static Mat3 zero() { return Mat3{{0, 0, 0, 0, 0, 0, 0, 0, 0}}; }
    double operator()(int r, int c) const { return m[3 * r + c]; }
    double& operator()(int r, int c) { return m[3 * r + c]; }
    Vec3 operator*(const Vec3& v) const {
        return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
                m[6] * v.x + m[7] * v.y + m[8] * v.z};
    }
    Mat3 operator*(const Mat3& o) const {
        Mat3 r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r(i, j) = (*this)(i, 0) * o(0, j) + (*this)(i, 1) * o(1, j) + (*this)(i, 2) * o(2, j);
        return r;
    }
    Mat3 transposed() const {
        Mat3 r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r(i, j) = (*this)(j, i);
        return r;
    }
    Vec3 column(int c) const { return {(*this)(0, c), (*this)(1, c), (*this)(2, c)}; }
    Mat3 operator*(double s) const {
        Mat3 r = *this;
        for (double& x : r.m) x *= s;
        return r;
    }
    Mat3 operator+(const Mat3& o) const {
        Mat3 r = *this;
        for (int i = 0; i < 9; ++i) r.m[i] += o.m[i];
        return r;
    }
    bool operator==(const Mat3& o) const { return m == o.m; }
};

// Rotation from intrinsic-free Euler angles in degrees: R = Rz(c) * Ry(b) * Rx(a), i.e. the body
// is first rotated about world x by a, then about world y by b, then about world z by c.
Mat3 rotation_from_euler_deg(const Vec3& angles_deg);

constexpr double kPi = 3.14159265358979323846;

}  // namespace ltm
