// A ray's hit on a surface, in world space, and how new rays leave it.
#pragma once

#include <cstdint>
#include <cstring>

#include <pbrt/pbrt.h>
#include <pbrt/ray.h>
#include <pbrt/util/vecmath.h>

namespace pbrt {

struct SurfaceInteraction {
    Point3f p;
    Vector3f pError;    // conservative per-axis bound on the error of p
    Normal3f n;         // geometric normal, oriented by pbrt's rules (ReverseOrientation,
                        // handedness, and toward the shading normal when the mesh has N)
    Normal3f ns;        // shading normal (same side as n)
    Vector3f dpdu;      // surface tangent along u (the shading frame's x before
                        // orthogonalization); may be zero
    Vector3f dpdv;      // surface tangent along v (bump mapping); may be zero
    Point2f uv;
    Vector3f wo;        // direction back along the incoming ray (normalized)
    Float tHit = 0;
    int material = -1;  // index into Scene::materials; -1: "interface" (no surface)
    int areaLight = -1; // index into Scene::lights of the emitter on this surface, or -1
    int faceIndex = 0;
    const FileLoc *shapeLoc = nullptr;  // the Shape statement of the surface hit (for messages)

    // The ray origin offset off the surface, to the side of w, so a new ray does not hit the
    // surface it starts on.
    // std::nextafter(v, +-Infinity) without the library call (a hot path): the same result
    // for every non-NaN float, by stepping the bit pattern.
    static Float NextFloatUp(Float v) {
        if (v == Infinity) return v;
        if (v == 0) v = 0.f;  // -0 steps up to the smallest positive float as well
        uint32_t bits;
        std::memcpy(&bits, &v, sizeof(bits));
        bits = v >= 0 ? bits + 1 : bits - 1;
        std::memcpy(&v, &bits, sizeof(bits));
        return v;
    }
    static Float NextFloatDown(Float v) {
        if (v == -Infinity) return v;
        if (v == 0) v = -0.f;
        uint32_t bits;
        std::memcpy(&bits, &v, sizeof(bits));
        bits = v > 0 ? bits - 1 : bits + 1;
        std::memcpy(&v, &bits, sizeof(bits));
        return v;
    }

    Point3f OffsetRayOrigin(const Vector3f &w) const {
        Float d = Dot(Abs(n), pError);
        Vector3f offset = n * d;
        if (Dot(w, n) < 0) offset = -offset;
        Point3f po = p + offset;
        // Round away from p so the offset is not lost to rounding.
        for (int i = 0; i < 3; ++i) {
            if (offset[i] > 0) po[i] = NextFloatUp(po[i]);
            else if (offset[i] < 0) po[i] = NextFloatDown(po[i]);
        }
        return po;
    }
    Ray SpawnRay(const Vector3f &d) const { return Ray(OffsetRayOrigin(d), d); }
    // A ray toward p2 that stops just short of it (for shadow rays); p2Error is the error of
    // p2 and n2 its normal (zero for points not on a surface).
    Ray SpawnRayTo(const Point3f &p2, const Normal3f &n2 = Normal3f(),
                   const Vector3f &p2Error = Vector3f()) const;
};

inline Ray SurfaceInteraction::SpawnRayTo(const Point3f &p2, const Normal3f &n2,
                                          const Vector3f &p2Error) const {
    Point3f o = OffsetRayOrigin(p2 - p);
    Point3f target = p2;
    if (n2 != Normal3f()) {
        // Pull the target off its surface toward the origin, likewise.
        Float d = Dot(Abs(n2), p2Error);
        Vector3f off = n2 * d;
        if (Dot(o - p2, n2) < 0) off = -off;
        target = p2 + off;
    }
    constexpr Float ShadowEpsilon = 0.0001f;
    return Ray(o, target - o, 1 - ShadowEpsilon);
}

}  // namespace pbrt
