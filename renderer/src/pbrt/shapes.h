// Shapes: triangle meshes ("trianglemesh", "plymesh", "bilinearmesh" split into two
// triangles per patch, "loopsubdiv" is not supported) and (partial) spheres.
//
// Meshes are stored transformed to the space of their Embree scene (world space, or the
// object space of an ObjectBegin definition), as pbrt-v4 does. Orientation follows pbrt-v4:
// the geometric normal of a triangle is Cross(p0 - p2, p1 - p2), flipped when
// ReverseOrientation is set XOR the transform swaps handedness; per-vertex normals N are
// transformed and flipped by ReverseOrientation, and when present they decide the side of
// the geometric normal. Sphere normals point outwards unless ReverseOrientation.
#pragma once

#include <pbrt/interaction.h>
#include <pbrt/util/transform.h>
#include <pbrt/util/vecmath.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace pbrt {

class ParameterDictionary;

// The largest render-space coordinate a shape (or a camera ray's origin) may have. Embree
// intersects in single precision, and its triangle test forms a triple product of
// coordinate differences (the distance along the ray, dot(cross(e1, e2), v0 - o)), so
// differences of 2e12 stay below 4.8e37 < FLT_MAX (3.4e38): beyond that, hits overflow
// and the shape silently disappears. Bigger coordinates are an error, not a lost object.
constexpr Float kMaxRenderCoordinate = 1e12f;

// True when every coordinate of p is finite and within kMaxRenderCoordinate.
bool WithinRenderRange(const Point3f &p);

struct TriangleMesh {
    std::vector<Point3f> p;
    std::vector<Normal3f> n;    // empty or one per vertex
    std::vector<Point2f> uv;    // empty or one per vertex
    std::vector<uint32_t> indices;  // three per triangle
    std::vector<int> faceIndices;   // empty or one per triangle
    bool reverseOrientation = false, transformSwapsHandedness = false;
    FileLoc loc;  // the Shape statement (for messages)

    size_t NumTriangles() const { return indices.size() / 3; }
    std::array<Point3f, 3> Vertices(size_t tri) const {
        return {p[indices[3 * tri]], p[indices[3 * tri + 1]], p[indices[3 * tri + 2]]};
    }
    Float Area(size_t tri) const;
    Bounds3f Bounds() const;
    // The surface at barycentrics (b1, b2) of triangle tri (b0 = 1 - b1 - b2), in the
    // mesh's space; sets p, pError, n, ns, dpdu, uv, faceIndex.
    void Interaction(size_t tri, Float b1, Float b2, SurfaceInteraction *si) const;
    // Only the position, its error bound and the (oriented) normal of Interaction, which is
    // all that sampling a point on an area light needs (the same values, less work).
    void SurfacePoint(size_t tri, Float b1, Float b2, Point3f *p, Vector3f *pError,
                      Normal3f *n) const;
    // The oriented geometric normal of a triangle (see the rules above), unit length.
    Normal3f GeometricNormal(size_t tri) const {
        return tri < faceNormals.size() ? faceNormals[tri] : ComputeGeometricNormal(tri);
    }
    Normal3f ComputeGeometricNormal(size_t tri) const;
    // Stores every triangle's GeometricNormal (the same values) for the renderer's hot path;
    // call again after changing p, indices or the orientation flags.
    void PrecomputeFaceNormals();
    std::vector<Normal3f> faceNormals;  // empty or one per triangle
};

struct Sphere {
    Transform renderFromObject, objectFromRender;
    Float radius = 1, zMin = -1, zMax = 1, thetaZMin = 0, thetaZMax = 0, phiMax = 2 * Pi;
    bool reverseOrientation = false;
    FileLoc loc;  // the Shape statement (for messages)
    // Which sphere this is (copies keep it): a light's copy and the ray tracer's copy of one
    // Shape statement have the same id. 0 for default-constructed spheres.
    uint32_t id = 0;
    // Derived from the above by the constructor (what every light sample would otherwise
    // recompute): the centre in render space, and the radius term of SurfacePoint's error
    // bound, radius |renderFromObject (1, 0, 0)|.
    Point3f center;
    Float errorRadius = 1;

    Sphere() = default;
    Sphere(const Transform &renderFromObject, bool reverseOrientation, Float radius, Float zMin,
           Float zMax, Float phiMaxDegrees);
    bool IsFull() const { return zMin <= -radius && zMax >= radius && phiMax >= 2 * Pi; }
    // Surface area in object space (pbrt-v4's definition).
    Float Area() const { return phiMax * radius * (zMax - zMin); }
    Bounds3f ObjectBounds() const;
    // Nearest hit with t in (0, tMax) of a ray given in object space; in double precision.
    bool IntersectObject(const Point3f &o, const Vector3f &d, Float tMax, Float *tHit) const;
    // The surface at object-space point pObj, in render space.
    void Interaction(const Point3f &pObj, SurfaceInteraction *si) const;
    // Only the position, its error bound and the normal of Interaction (the same values),
    // for light sampling, which needs no (u, v) or derivatives; returns the projected pObj.
    Point3f SurfacePoint(const Point3f &pObj, Point3f *p, Vector3f *pError, Normal3f *n) const;
    // Uniform factor of renderFromObject, or 0 if the transform is not a similarity
    // (rotation, translation, uniform scale).
    Float SimilarityScale() const;
};

// The shapes one Shape directive creates.
struct ShapeSet {
    std::vector<std::shared_ptr<TriangleMesh>> meshes;
    std::vector<Sphere> spheres;
};

// Creates the shapes of a Shape directive, transformed by renderFromObject. Throws
// PbrtError (with the location) for unsupported shapes and malformed parameters.
ShapeSet CreateShapes(const std::string &name, const ParameterDictionary &params,
                      const Transform &renderFromObject, bool reverseOrientation,
                      const FileLoc &loc);

// Builds a mesh from raw arrays (used by CreateShapes and tests); validates indices.
std::shared_ptr<TriangleMesh> MakeTriangleMesh(const Transform &renderFromObject,
                                               bool reverseOrientation,
                                               std::vector<std::array<Float, 3>> P,
                                               std::vector<int> indices,
                                               std::vector<std::array<Float, 3>> N,
                                               std::vector<std::array<Float, 2>> uv,
                                               std::vector<int> faceIndices,
                                               const FileLoc &loc);

}  // namespace pbrt
