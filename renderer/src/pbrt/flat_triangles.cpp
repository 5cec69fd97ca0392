#include <pbrt/flat_triangles.h>

#include <cmath>
#include <limits>

#ifdef __AVX512F__
#include <immintrin.h>
#endif

namespace pbrt {

static_assert(FlatTriangles::kLanes == 16, "the reductions below are written for 16 lanes");

namespace {
template <typename V>
inline V Min(V a, V b) {
    return a < b ? a : b;
}
// The first lane of a mask (all bits set or clear per lane) that is set; it has one.
inline int FirstLane(FlatTriangles::VInt mask) {
#ifdef __AVX512F__
    static_assert(sizeof(mask) == sizeof(__m512i));
    return __builtin_ctz(_mm512_cmpneq_epi32_mask(__m512i(mask), _mm512_setzero_si512()));
#else
    int i = 0;
    while (!mask[i]) ++i;
    return i;
#endif
}

}  // namespace

void FlatTriangles::Add(const Point3f &p0, const Point3f &p1, const Point3f &p2) {
    int lane = count % kLanes;
    if (lane == 0) {
        // Unused lanes hold NaN vertices: every comparison with them is false (no hit).
        blocks.emplace_back();
        for (auto &vertex : blocks.back().v)
            for (VFloat &axis : vertex) axis = VFloat{} + std::numeric_limits<float>::quiet_NaN();
    }
    Block &b = blocks.back();
    const Point3f *p[3] = {&p0, &p1, &p2};
    for (int v = 0; v < 3; ++v)
        for (int a = 0; a < 3; ++a) b.v[v][a][lane] = (*p[v])[a];
    ++count;
}

// The ray's frame: axes permuted so that z is the direction's largest component, then
// sheared so that the direction becomes (0, 0, 1): a vertex p maps to
// (p[kx] - o[kx] - sx (p[kz] - o[kz]), p[ky] - o[ky] - sy (p[kz] - o[kz]), sz (p[kz] - o[kz])).
struct FlatTriangles::Frame {
    int kx, ky, kz;
    Float ox, oy, oz, sx, sy, sz;
};

inline FlatTriangles::Frame FlatTriangles::MakeFrame(const Point3f &o, const Vector3f &d) {
    Frame f;
    Float ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
    f.kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    f.kx = (f.kz + 1) % 3;
    f.ky = (f.kx + 1) % 3;
    f.ox = o[f.kx];
    f.oy = o[f.ky];
    f.oz = o[f.kz];
    f.sz = 1 / d[f.kz];
    f.sx = d[f.kx] * f.sz;
    f.sy = d[f.ky] * f.sz;
    return f;
}

inline __attribute__((always_inline)) FlatTriangles::VInt FlatTriangles::Test(
    const Block &b, const Frame &f, VFloat *tDet, VFloat *absDet, VFloat *e1Out, VFloat *e2Out) {
    // Named variables, not arrays: arrays of vectors would live in memory.
    VFloat z0 = b.v[0][f.kz] - f.oz, z1 = b.v[1][f.kz] - f.oz, z2 = b.v[2][f.kz] - f.oz;
    VFloat x0 = (b.v[0][f.kx] - f.ox) - f.sx * z0, y0 = (b.v[0][f.ky] - f.oy) - f.sy * z0;
    VFloat x1 = (b.v[1][f.kx] - f.ox) - f.sx * z1, y1 = (b.v[1][f.ky] - f.oy) - f.sy * z1;
    VFloat x2 = (b.v[2][f.kx] - f.ox) - f.sx * z2, y2 = (b.v[2][f.ky] - f.oy) - f.sy * z2;
    // Edge functions: e0 faces p0 (the edge p1 p2), and so on; their sum is the determinant.
    VFloat e0 = x2 * y1 - y2 * x1;
    VFloat e1 = x0 * y2 - y0 * x2;
    VFloat e2 = x1 * y0 - y1 * x0;
    VFloat det = e0 + e1 + e2;
    VInt neg = (e0 < 0) | (e1 < 0) | (e2 < 0), pos = (e0 > 0) | (e1 > 0) | (e2 > 0);
    VFloat tScaled = (e0 * z0 + e1 * z1 + e2 * z2) * f.sz;  // t det
    // t = tDet / |det| without a division: both flipped by det's sign.
    VInt sign = (VInt)det & INT32_MIN;
    *tDet = (VFloat)((VInt)tScaled ^ sign);
    *absDet = (VFloat)((VInt)det ^ sign);
    if (e1Out) {
        *e1Out = (VFloat)((VInt)e1 ^ sign);
        *e2Out = (VFloat)((VInt)e2 ^ sign);
    }
    // Written so that NaN (a zero direction, overflow) compares false: no hit. det = 0 fails
    // t > 0 (all three edge functions are then 0, or their signs differ).
    return ~(neg & pos) & (*tDet > 0);
}

// Not inlined (nor Any): inlined by link-time optimization into a caller compiled with
// fused multiply-adds, the edge functions would be contracted too (flat_triangles.h).
__attribute__((noinline)) bool FlatTriangles::Closest(const Point3f &o, const Vector3f &d, Float tMax,
                                                      Hit *hit) const {
    if (blocks.empty()) return false;
    Frame f = MakeFrame(o, d);
    // Each lane's closest t so far, with the block it is in and its edge functions of p1 and
    // p2 and determinant (for the barycentrics). (Comparing t det / det by cross-multiplying
    // instead of dividing would overflow: they grow as the cube and the square of the
    // scene's size.)
    VFloat best = VFloat{} + tMax, bestE1 = {}, bestE2 = {}, bestDet = {};
    VInt block = {};
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
        VFloat tDet, absDet, e1, e2;
        VInt h = Test(blocks[bi], f, &tDet, &absDet, &e1, &e2);
        VFloat t = tDet / absDet;
        h &= t < best;
        best = h ? t : best;
        bestE1 = h ? e1 : bestE1;
        bestE2 = h ? e2 : bestE2;
        bestDet = h ? absDet : bestDet;
        block = h ? VInt{} + int32_t(bi) : block;
    }
    // The smallest t over the lanes (a lane never hit kept tMax), then the first triangle
    // with it: halving reductions.
    VFloat m = best;
    m = Min(m, __builtin_shufflevector(m, m, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7));
    m = Min(m, __builtin_shufflevector(m, m, 4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11));
    m = Min(m, __builtin_shufflevector(m, m, 2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13));
    m = Min(m, __builtin_shufflevector(m, m, 1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14));
    Float tk = m[0];
    if (!(tk < tMax)) return false;
    int l = FirstLane(best == m);
    hit->index = block[l] * kLanes + l;
    hit->t = tk;
    hit->b1 = bestE1[l] / bestDet[l];
    hit->b2 = bestE2[l] / bestDet[l];
    return true;
}

__attribute__((noinline)) bool FlatTriangles::Any(const Point3f &o, const Vector3f &d, Float tMax) const {
    if (blocks.empty()) return false;
    Frame f = MakeFrame(o, d);
    VFloat tm = VFloat{} + tMax;
    VInt any = VInt{};
    for (const Block &b : blocks) {
        VFloat tDet, absDet;
        any |= Test(b, f, &tDet, &absDet, nullptr, nullptr) & (tDet < tm * absDet);
    }
    any |= __builtin_shufflevector(any, any, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7);
    any |= __builtin_shufflevector(any, any, 4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11);
    any |= __builtin_shufflevector(any, any, 2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13);
    any |= __builtin_shufflevector(any, any, 1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14);
    return any[0] != 0;
}

}  // namespace pbrt
