// Small-vector geometry: 2D/3D vectors, points and normals, bounding boxes and orthonormal
// frames. Points, vectors and normals share one 3-component type (they differ only in how a
// Transform applies to them, see transform.h), which keeps the hot paths free of conversions.
#pragma once

#include <pbrt/pbrt.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

namespace pbrt {

// ---------------------------------------------------------------------------------------
// Scalar helpers
template <typename T>
inline T Sqr(T v) { return v * v; }
template <typename T, typename U, typename V,
          typename = std::enable_if_t<std::is_arithmetic_v<T>>>
inline T Clamp(T v, U lo, V hi) { return v < lo ? T(lo) : (v > hi ? T(hi) : v); }
inline Float Lerp(Float t, Float a, Float b) { return (1 - t) * a + t * b; }
inline Float SafeSqrt(Float x) { return std::sqrt(std::max<Float>(0, x)); }
inline Float SafeASin(Float x) { return std::asin(Clamp(x, -1, 1)); }
inline Float SafeACos(Float x) { return std::acos(Clamp(x, -1, 1)); }
inline Float Radians(Float deg) { return (Pi / 180) * deg; }
inline Float Degrees(Float rad) { return (180 / Pi) * rad; }
// The largest float below one: keeps samples in [0, 1).
constexpr Float OneMinusEpsilon = 0x1.fffffep-1f;

// ---------------------------------------------------------------------------------------
// 2D
struct Vector2f {
    Float x = 0, y = 0;
    Vector2f() = default;
    constexpr Vector2f(Float x, Float y) : x(x), y(y) {}
    Float operator[](int i) const { return i == 0 ? x : y; }
    Float &operator[](int i) { return i == 0 ? x : y; }
    Vector2f operator+(Vector2f o) const { return {x + o.x, y + o.y}; }
    Vector2f operator-(Vector2f o) const { return {x - o.x, y - o.y}; }
    Vector2f operator*(Float s) const { return {x * s, y * s}; }
    Vector2f operator/(Float s) const { return {x / s, y / s}; }
    Vector2f operator-() const { return {-x, -y}; }
    bool operator==(Vector2f o) const { return x == o.x && y == o.y; }
};
using Point2f = Vector2f;
inline Vector2f operator*(Float s, Vector2f v) { return v * s; }

struct Point2i {
    int x = 0, y = 0;
    int operator[](int i) const { return i == 0 ? x : y; }
    bool operator==(Point2i o) const { return x == o.x && y == o.y; }
};

// Integer pixel bounds [pMin, pMax).
struct Bounds2i {
    Point2i pMin, pMax;
    int Width() const { return pMax.x - pMin.x; }
    int Height() const { return pMax.y - pMin.y; }
    long long Area() const { return (long long)Width() * Height(); }
    bool Empty() const { return pMax.x <= pMin.x || pMax.y <= pMin.y; }
};

// ---------------------------------------------------------------------------------------
// 3D: one type for vectors, points and normals.
struct Vector3f {
    Float x = 0, y = 0, z = 0;
    Vector3f() = default;
    constexpr Vector3f(Float x, Float y, Float z) : x(x), y(y), z(z) {}
    Float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    Float &operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    Vector3f operator+(const Vector3f &o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vector3f operator-(const Vector3f &o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vector3f operator*(Float s) const { return {x * s, y * s, z * s}; }
    Vector3f operator/(Float s) const {
        Float inv = 1 / s;
        return {x * inv, y * inv, z * inv};
    }
    Vector3f operator-() const { return {-x, -y, -z}; }
    Vector3f &operator+=(const Vector3f &o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vector3f &operator-=(const Vector3f &o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vector3f &operator*=(Float s) { x *= s; y *= s; z *= s; return *this; }
    bool operator==(const Vector3f &o) const { return x == o.x && y == o.y && z == o.z; }
    bool operator!=(const Vector3f &o) const { return !(*this == o); }
    bool HasNaN() const { return std::isnan(x) || std::isnan(y) || std::isnan(z); }
};
using Point3f = Vector3f;
using Normal3f = Vector3f;

inline Vector3f operator*(Float s, const Vector3f &v) { return v * s; }
inline Float Dot(const Vector3f &a, const Vector3f &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Float AbsDot(const Vector3f &a, const Vector3f &b) { return std::abs(Dot(a, b)); }
inline Vector3f Cross(const Vector3f &a, const Vector3f &b) {
    // Products in double avoid catastrophic cancellation for nearly parallel vectors.
    double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
    return {Float(ay * bz - az * by), Float(az * bx - ax * bz), Float(ax * by - ay * bx)};
}
inline Float LengthSquared(const Vector3f &v) { return Dot(v, v); }
inline Float Length(const Vector3f &v) { return std::sqrt(LengthSquared(v)); }
inline Vector3f Normalize(const Vector3f &v) { return v / Length(v); }
inline Float Distance(const Point3f &a, const Point3f &b) { return Length(a - b); }
inline Float DistanceSquared(const Point3f &a, const Point3f &b) { return LengthSquared(a - b); }
inline Vector3f Abs(const Vector3f &v) { return {std::abs(v.x), std::abs(v.y), std::abs(v.z)}; }
inline Vector3f Min(const Vector3f &a, const Vector3f &b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vector3f Max(const Vector3f &a, const Vector3f &b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline Float MaxComponent(const Vector3f &v) { return std::max({v.x, v.y, v.z}); }
// Flips n to lie in the hemisphere of v.
inline Vector3f FaceForward(const Vector3f &n, const Vector3f &v) { return Dot(n, v) < 0 ? -n : n; }

// Angle between two unit vectors, accurate for nearly (anti)parallel ones.
inline Float AngleBetween(const Vector3f &a, const Vector3f &b) {
    if (Dot(a, b) < 0) return Pi - 2 * SafeASin(Length(a + b) / 2);
    return 2 * SafeASin(Length(b - a) / 2);
}

// Spherical coordinates with +z as the pole.
inline Vector3f SphericalDirection(Float sinTheta, Float cosTheta, Float phi) {
    return {Clamp(sinTheta, -1, 1) * std::cos(phi), Clamp(sinTheta, -1, 1) * std::sin(phi),
            Clamp(cosTheta, -1, 1)};
}

// An orthonormal basis around a unit vector (Duff et al. 2017, "Building an Orthonormal
// Basis, Revisited", JCGT 6(1)): branchless and continuous except at v.z = -1 exactly.
inline void CoordinateSystem(const Vector3f &v, Vector3f *a, Vector3f *b) {
    Float sign = std::copysign(Float(1), v.z);
    Float p = -1 / (sign + v.z);
    Float q = v.x * v.y * p;
    *a = Vector3f(1 + sign * v.x * v.x * p, sign * q, -sign * v.x);
    *b = Vector3f(q, sign + v.y * v.y * p, -v.y);
}

// ---------------------------------------------------------------------------------------
// An orthonormal frame: rows x, y, z. Local coordinates have z as the frame's normal.
struct Frame {
    Vector3f x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
    static Frame FromZ(const Vector3f &z) {
        Frame f;
        f.z = z;
        CoordinateSystem(z, &f.x, &f.y);
        return f;
    }
    static Frame FromXZ(const Vector3f &x, const Vector3f &z) {
        Frame f;
        f.x = x;
        f.z = z;
        f.y = Cross(z, x);
        return f;
    }
    Vector3f ToLocal(const Vector3f &v) const { return {Dot(v, x), Dot(v, y), Dot(v, z)}; }
    Vector3f FromLocal(const Vector3f &v) const { return x * v.x + y * v.y + z * v.z; }
};

// ---------------------------------------------------------------------------------------
// Axis-aligned box; default constructed empty.
struct Bounds3f {
    Point3f pMin{Infinity, Infinity, Infinity}, pMax{-Infinity, -Infinity, -Infinity};
    Bounds3f() = default;
    explicit Bounds3f(const Point3f &p) : pMin(p), pMax(p) {}
    Bounds3f(const Point3f &a, const Point3f &b) : pMin(Min(a, b)), pMax(Max(a, b)) {}
    bool IsEmpty() const { return pMin.x > pMax.x || pMin.y > pMax.y || pMin.z > pMax.z; }
    Vector3f Diagonal() const { return pMax - pMin; }
    Point3f Center() const { return (pMin + pMax) * Float(0.5); }
    // Corner c = 0..7: bit 0 picks x from pMax, bit 1 y, bit 2 z (as pbrt-v4 numbers them).
    Point3f Corner(int c) const {
        return Point3f((c & 1) ? pMax.x : pMin.x, (c & 2) ? pMax.y : pMin.y,
                       (c & 4) ? pMax.z : pMin.z);
    }
    // The bounding sphere (centre and radius); radius 0 for an empty box.
    void BoundingSphere(Point3f *center, Float *radius) const {
        *center = IsEmpty() ? Point3f() : Center();
        *radius = IsEmpty() ? 0 : Distance(*center, pMax);
    }
};
inline Bounds3f Union(const Bounds3f &b, const Point3f &p) {
    Bounds3f r;
    r.pMin = Min(b.pMin, p);
    r.pMax = Max(b.pMax, p);
    return r;
}
inline Bounds3f Union(const Bounds3f &a, const Bounds3f &b) {
    if (a.IsEmpty()) return b;
    if (b.IsEmpty()) return a;
    Bounds3f r;
    r.pMin = Min(a.pMin, b.pMin);
    r.pMax = Max(a.pMax, b.pMax);
    return r;
}

inline std::string ToString(const Vector3f &v) {
    return "[" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + "]";
}

}  // namespace pbrt
