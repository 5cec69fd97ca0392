// A ray: origin, direction (not necessarily normalized) and the largest parametric distance.
#pragma once

#include <pbrt/util/vecmath.h>

namespace pbrt {

struct Ray {
    Point3f o;
    Vector3f d;
    Float tMax = Infinity;
    Ray() = default;
    Ray(const Point3f &o, const Vector3f &d, Float tMax = Infinity) : o(o), d(d), tMax(tMax) {}
    Point3f operator()(Float t) const { return o + d * t; }
};

}  // namespace pbrt
