// Ray queries against a handful of triangles without a hierarchy: every triangle is tested,
// sixteen at a time.
//
// Written here because no library does it: Embree's queries carry a fixed cost (context and
// ray set-up, the dispatch into its kernels, the robust traversal) of about 100 ns per ray
// on this project's machines, which on a scene of a few dozen triangles (a Cornell box,
// Veach's MIS scene) is most of a query; testing all of them costs a fifth of that
// (docs/performance.md, change 24). The Accelerator uses this for small scenes only
// (kMaxTriangles) and Embree for everything else.
//
// The test is the watertight one of Woop, Benthin and Wald (2013, "Watertight Ray/Triangle
// Intersection"): in a frame sheared so that the ray runs along +z, a ray hits a triangle
// when the three 2D edge functions of its vertices have one sign; a ray through a shared
// edge or vertex sees the same edge function from both triangles, so it cannot pass
// between them. Zeros count as inside (such a ray may hit both neighbours; never neither).
// That needs an edge's function from one triangle to be exactly the negative of the same
// edge's from the other, i.e. products rounded one by one: CMakeLists.txt compiles this
// file without fused multiply-adds.
#pragma once

#include <pbrt/util/vecmath.h>

#include <cstdint>
#include <vector>

namespace pbrt {

class FlatTriangles {
  public:
    // The most triangles the Accelerator tests one by one. Measured against Embree's robust
    // single-ray query (rays from inside a room of small random triangles): 39 ns against
    // 65 with 32 triangles, 102 against 148 with 128, even at 256 (docs/performance.md,
    // change 24); scenes whose triangles are spread out favour Embree sooner.
    static constexpr int kMaxTriangles = 128;
    static constexpr int kLanes = 16;

    void Add(const Point3f &p0, const Point3f &p1, const Point3f &p2);
    int Size() const { return count; }

    struct Hit {
        int index = -1;   // in the order of Add
        Float t = 0;      // along the ray (parametric, in units of |d|)
        Float b1 = 0, b2 = 0;  // barycentrics of p1 and p2 (p0's is 1 - b1 - b2)
    };
    // The closest triangle with t in (0, tMax), if any.
    bool Closest(const Point3f &o, const Vector3f &d, Float tMax, Hit *hit) const;
    // Whether any triangle has t in (0, tMax).
    bool Any(const Point3f &o, const Vector3f &d, Float tMax) const;

    // Sixteen lanes: one AVX-512 register; GCC and Clang split it on narrower targets.
    typedef float VFloat __attribute__((vector_size(kLanes * sizeof(float))));
    typedef int32_t VInt __attribute__((vector_size(kLanes * sizeof(int32_t))));
    // Sixteen triangles, structure of arrays: v[vertex][axis][lane].

  private:
    struct Block {
        VFloat v[3][3];
    };
    struct Frame;  // a ray in the sheared frame
    static Frame MakeFrame(const Point3f &o, const Vector3f &d);
    // The lanes of block b whose triangle the ray hits with t > 0 (all bits set), and each
    // lane's t as the fraction tDet / absDet; when e1 is not null, the edge functions of p1
    // and p2, whose ratios to absDet are the barycentrics of p1 and p2.
    static VInt Test(const Block &b, const Frame &f, VFloat *tDet, VFloat *absDet, VFloat *e1, VFloat *e2);

    std::vector<Block> blocks;
    int count = 0;
};

}  // namespace pbrt
