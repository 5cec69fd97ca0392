// Ray intersection through Embree 3: every triangle mesh is an Embree triangle geometry,
// every sphere an Embree user geometry with our own (double precision) intersection test,
// and each ObjectBegin/ObjectEnd definition an Embree scene instanced by ObjectInstance.
// Small scenes are traced without Embree, by testing every shape (flat_triangles.h).
#pragma once

#include <pbrt/flat_triangles.h>
#include <pbrt/interaction.h>
#include <pbrt/shapes.h>
#include <pbrt/util/transform.h>

#include <memory>
#include <vector>

namespace pbrt {

class Accelerator {
  public:
    // Scenes without instances and with at most flatMaxTriangles triangles are traced by
    // testing every shape (flat_triangles.h); 0 traces every scene through Embree.
    explicit Accelerator(int flatMaxTriangles = FlatTriangles::kMaxTriangles);
    ~Accelerator();
    Accelerator(const Accelerator &) = delete;
    Accelerator &operator=(const Accelerator &) = delete;

    // Object 0 is the top level; NewObject() starts an instance definition.
    int NewObject();
    // material: index into the scene's materials (-1: interface); lightOffset: the index of
    // the area light of the first triangle (triangle i has lightOffset + i) or of the
    // sphere, or -1 when the shape does not emit.
    void AddMesh(int object, std::shared_ptr<TriangleMesh> mesh, int material, int lightOffset);
    void AddSphere(int object, const Sphere &sphere, int material, int lightOffset);
    // Places object `object` (>= 1) in the top level with the transform renderFromInstance.
    void AddInstance(int object, const Transform &renderFromInstance);
    bool ObjectIsEmpty(int object) const;
    // Bounds of object `object` (>= 1) in its own space (builds its BVH if not built yet).
    Bounds3f ObjectBounds(int object);
    // Builds the BVHs; call once after adding everything.
    void Commit();

    // Closest hit with t in (0, ray.tMax); fills si (world space) on a hit.
    bool Intersect(const Ray &ray, SurfaceInteraction *si) const;
    // Whether anything is hit with t in (0, ray.tMax).
    // skipSphere: the id of a sphere (Sphere::id) not to test, one the caller knows the ray
    // does not cross (a light sample's own sphere); 0 tests every shape.
    bool Occluded(const Ray &ray, uint32_t skipSphere = 0) const;
    // Whether queries test every shape (a small scene, flat_triangles.h) instead of Embree's.
    bool TestsEveryShape() const;
    // World-space bounds of everything in the top level.
    Bounds3f Bounds() const { return bounds; }

  private:
    struct Impl;
    std::unique_ptr<Impl> impl;
    Bounds3f bounds;
};

}  // namespace pbrt
