// The flat triangle test (flat_triangles.h) and the Accelerator's use of it for small scenes:
// analytic hits, agreement with a double-precision reference and with Embree, watertight
// shared edges, and degenerate rays.
#include <pbrt/accel.h>
#include <pbrt/flat_triangles.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

using namespace pbrt;

namespace {

// Möller and Trumbore's test in double precision: t of the hit (or -1) and the margin, the
// smallest barycentric, which says how close the ray passes to an edge.
double ReferenceHit(const Point3f &o, const Vector3f &d, const Point3f &p0, const Point3f &p1,
                    const Point3f &p2, double *margin) {
    double e1[3] = {double(p1.x) - p0.x, double(p1.y) - p0.y, double(p1.z) - p0.z};
    double e2[3] = {double(p2.x) - p0.x, double(p2.y) - p0.y, double(p2.z) - p0.z};
    double dd[3] = {d.x, d.y, d.z};
    double s[3] = {double(o.x) - p0.x, double(o.y) - p0.y, double(o.z) - p0.z};
    auto cross = [](const double *a, const double *b, double *c) {
        c[0] = a[1] * b[2] - a[2] * b[1];
        c[1] = a[2] * b[0] - a[0] * b[2];
        c[2] = a[0] * b[1] - a[1] * b[0];
    };
    auto dot = [](const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    double p[3], q[3];
    cross(dd, e2, p);
    double det = dot(e1, p);
    *margin = -1;
    if (det == 0) return -1;
    double u = dot(s, p) / det;
    cross(s, e1, q);
    double v = dot(dd, q) / det, t = dot(e2, q) / det;
    *margin = std::min({u, v, 1 - u - v});
    return *margin >= 0 ? t : -1;
}

Point3f RandomPoint(std::mt19937 &rng, float lo, float hi) {
    std::uniform_real_distribution<float> u(lo, hi);
    float x = u(rng), y = u(rng), z = u(rng);
    return {x, y, z};
}

Vector3f RandomDirection(std::mt19937 &rng) {
    std::uniform_real_distribution<float> u(0, 1);
    float z = 1 - 2 * u(rng), r = std::sqrt(std::max(0.f, 1 - z * z)), phi = 2 * Pi * u(rng);
    return {r * std::cos(phi), r * std::sin(phi), z};
}

}  // namespace

TEST(FlatTriangles, AnalyticHitDistanceAndBarycentrics) {
    for (bool flip : {false, true}) {  // either winding
        FlatTriangles ft;
        Point3f a(0, 0, 1), b(1, 0, 1), c(0, 1, 1);
        if (flip) ft.Add(a, c, b); else ft.Add(a, b, c);
        FlatTriangles::Hit h;
        ASSERT_TRUE(ft.Closest({0.2f, 0.3f, 0}, {0, 0, 2}, Infinity, &h));
        EXPECT_EQ(h.index, 0);
        EXPECT_FLOAT_EQ(h.t, 0.5f);  // t in units of |d|
        EXPECT_NEAR(h.b1, flip ? 0.3f : 0.2f, 1e-6f);
        EXPECT_NEAR(h.b2, flip ? 0.2f : 0.3f, 1e-6f);
        // From the other side, and not behind the origin or beyond tMax.
        ASSERT_TRUE(ft.Closest({0.2f, 0.3f, 3}, {0, 0, -1}, Infinity, &h));
        EXPECT_FLOAT_EQ(h.t, 2);
        EXPECT_FALSE(ft.Closest({0.2f, 0.3f, 3}, {0, 0, 1}, Infinity, &h));
        EXPECT_FALSE(ft.Closest({0.2f, 0.3f, 0}, {0, 0, 2}, 0.5f, &h));
        EXPECT_TRUE(ft.Closest({0.2f, 0.3f, 0}, {0, 0, 2}, 0.5001f, &h));
        EXPECT_FALSE(ft.Any({0.2f, 0.3f, 0}, {0, 0, 2}, 0.5f));
        EXPECT_TRUE(ft.Any({0.2f, 0.3f, 0}, {0, 0, 2}, 0.5001f));
        // Outside the hypotenuse.
        EXPECT_FALSE(ft.Closest({0.6f, 0.6f, 0}, {0, 0, 1}, Infinity, &h));
        EXPECT_FALSE(ft.Any({0.6f, 0.6f, 0}, {0, 0, 1}, Infinity));
    }
}

TEST(FlatTriangles, ClosestAndAnyAgreeWithADoublePrecisionReference) {
    // 53 triangles: three full blocks of sixteen and one partly used.
    std::mt19937 rng(7);
    std::vector<std::array<Point3f, 3>> tris;
    FlatTriangles ft;
    for (int i = 0; i < 53; ++i) {
        Point3f c = RandomPoint(rng, -1, 1);
        std::array<Point3f, 3> t = {c + Vector3f(RandomPoint(rng, -0.5f, 0.5f)),
                                    c + Vector3f(RandomPoint(rng, -0.5f, 0.5f)),
                                    c + Vector3f(RandomPoint(rng, -0.5f, 0.5f))};
        tris.push_back(t);
        ft.Add(t[0], t[1], t[2]);
    }
    ASSERT_EQ(ft.Size(), 53);
    int hits = 0, compared = 0;
    for (int r = 0; r < 20000; ++r) {
        Point3f o = RandomPoint(rng, -2, 2);
        Vector3f d = RandomDirection(rng) * 1.7f;
        float tMax = r % 3 == 0 ? Infinity : std::uniform_real_distribution<float>(0.1f, 3)(rng);
        // The reference's closest hit, and whether the case is clear-cut: no triangle passed
        // within 1e-4 of an edge, nor two hits (or the hit and tMax) within 1e-4 in t.
        double best = -1, second = -1;
        int which = -1;
        bool clear = true;
        for (int i = 0; i < int(tris.size()); ++i) {
            double margin, t = ReferenceHit(o, d, tris[i][0], tris[i][1], tris[i][2], &margin);
            if (std::abs(margin) < 1e-4 && margin != -1) clear = false;
            if (t > 0 && std::abs(t - tMax) < 1e-4) clear = false;
            if (t > 0 && t < tMax) {
                if (best < 0 || t < best) {
                    second = best;
                    best = t;
                    which = i;
                } else if (second < 0 || t < second) {
                    second = t;
                }
            }
        }
        if (best > 0 && best < 1e-4) clear = false;
        if (second > 0 && second - best < 1e-4) clear = false;
        if (!clear) continue;
        ++compared;
        FlatTriangles::Hit h;
        bool found = ft.Closest(o, d, tMax, &h);
        ASSERT_EQ(found, which >= 0) << "ray " << r;
        ASSERT_EQ(ft.Any(o, d, tMax), which >= 0) << "ray " << r;
        if (!found) continue;
        ++hits;
        EXPECT_EQ(h.index, which) << "ray " << r;
        EXPECT_NEAR(h.t, best, 1e-5 * std::max(1.0, best)) << "ray " << r;
        // The barycentrics give back the point at t.
        const auto &t = tris[which];
        Point3f p = t[0] * (1 - h.b1 - h.b2) + Vector3f(t[1]) * h.b1 + Vector3f(t[2]) * h.b2;
        Point3f q = o + d * h.t;
        EXPECT_LT(Length(p - q), 1e-4f) << "ray " << r;
    }
    EXPECT_GT(compared, 19000);
    EXPECT_GT(hits, 1000);
}

TEST(FlatTriangles, SharedEdgesAndVerticesAreWatertight) {
    // A 6 x 6 grid of quads split into triangles (every interior edge and vertex shared),
    // tilted out of the axis planes; rays aimed exactly at its edges and vertices (computed
    // in float) must all hit it: no ray slips between two triangles.
    const int n = 6;
    auto vertex = [&](int i, int j) {
        float x = i / float(n), y = j / float(n);
        return Point3f(0.3f + x + 0.2f * y, 0.1f + 0.7f * y, 2 + 0.4f * x - 0.3f * y);
    };
    FlatTriangles ft;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            // Alternate the diagonal so that vertices are shared by 4 or 8 triangles.
            Point3f a = vertex(i, j), b = vertex(i + 1, j), c = vertex(i + 1, j + 1), d = vertex(i, j + 1);
            if ((i + j) % 2) {
                ft.Add(a, b, c);
                ft.Add(a, c, d);
            } else {
                ft.Add(a, b, d);
                ft.Add(b, c, d);
            }
        }
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, 1);
    std::uniform_int_distribution<int> inner(1, n - 1), any(0, n - 1);
    int misses = 0, rays = 0;
    for (int r = 0; r < 60000; ++r) {
        // A point on an interior edge (horizontal, vertical or diagonal) or an interior vertex.
        int i = inner(rng), j = inner(rng), kind = r % 4;
        Point3f a = vertex(i, j), b;
        float s = u(rng);
        if (kind == 0) b = vertex(i + 1, j);
        else if (kind == 1) b = vertex(i, j + 1);
        else if (kind == 2) b = ((i + j) % 2) ? vertex(i + 1, j + 1) : vertex(i + 1, j - 1);
        else b = a, s = 0;
        if (kind == 0 && (j == 0 || j == n)) continue;
        (void)any;
        Point3f target = a + (b - a) * s;
        Point3f o = RandomPoint(rng, -3, 3);
        o.z = -2 + u(rng);  // in front of the grid (z ~ 1.5-2.5)
        Vector3f d = target - o;
        ++rays;
        FlatTriangles::Hit h;
        bool hit = ft.Closest(o, d, Infinity, &h) && ft.Any(o, d, Infinity);
        misses += !hit;
    }
    EXPECT_GT(rays, 50000);
    EXPECT_EQ(misses, 0) << "of " << rays << " rays through shared edges and vertices";
}

TEST(FlatTriangles, DegenerateRaysAndTrianglesNeverHit) {
    FlatTriangles empty;
    FlatTriangles::Hit h;
    EXPECT_FALSE(empty.Closest({0, 0, 0}, {0, 0, 1}, Infinity, &h));
    EXPECT_FALSE(empty.Any({0, 0, 0}, {0, 0, 1}, Infinity));

    FlatTriangles ft;
    ft.Add({-1, -1, 1}, {1, -1, 1}, {0, 1, 1});
    ft.Add({-1, 0, 2}, {0, 0, 2}, {1, 0, 2});  // zero area (collinear)
    ft.Add({5, 5, 5}, {5, 5, 5}, {5, 5, 5});   // a point
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (Vector3f d : {Vector3f(0, 0, 0), Vector3f(nan, 0, 1), Vector3f(0, nan, nan)}) {
        EXPECT_FALSE(ft.Closest({0, 0, 0}, d, Infinity, &h));
        EXPECT_FALSE(ft.Any({0, 0, 0}, d, Infinity));
    }
    EXPECT_FALSE(ft.Closest({nan, 0, 0}, {0, 0, 1}, Infinity, &h));
    EXPECT_FALSE(ft.Any({0, 0, 0}, {0, 0, 1}, nan));
    // The zero-area triangle is never the hit: rays along and across its line.
    for (float x : {-0.5f, 0.f, 0.25f}) {
        ASSERT_TRUE(ft.Closest({x, 0, 3}, {0, 0, -1}, Infinity, &h));
        EXPECT_EQ(h.index, 0);
        EXPECT_FLOAT_EQ(h.t, 2);
    }
    EXPECT_FALSE(ft.Closest({-2, 0, 2}, {1, 0, 0}, Infinity, &h));
    EXPECT_FALSE(ft.Closest({5, 5, 0}, {0, 0, 1}, Infinity, &h));
}

TEST(FlatTriangles, LargeCoordinatesStillHit) {
    // A scene 1e9 units across seen from 1e11 away: t det and det stay finite.
    for (float scale : {1e3f, 1e6f, 1e9f}) {
        FlatTriangles ft;
        ft.Add({-scale, -scale, 0}, {scale, -scale, 0}, {0, scale, 0});
        FlatTriangles::Hit h;
        Point3f o(0.1f * scale, 0, 100 * scale);
        ASSERT_TRUE(ft.Closest(o, {0, 0, -1}, Infinity, &h)) << scale;
        EXPECT_NEAR(h.t, 100 * scale, 1e-5 * 100 * scale);
        EXPECT_TRUE(ft.Any(o, {0, 0, -1}, Infinity));
        EXPECT_FALSE(ft.Any(o, {0, 0, -1}, 99 * scale));
    }
}

namespace {

// The same small scene in two accelerators: one that tests every shape, one through Embree.
struct TwoAccelerators {
    Accelerator flat, embree{0};
    std::vector<Sphere> spheres;

    TwoAccelerators() {
        auto mesh = std::make_shared<TriangleMesh>();
        // A box room (12 triangles) and a slanted quad, as Cornell boxes are built.
        Point3f c[8];
        for (int k = 0; k < 8; ++k) c[k] = Point3f(k & 1 ? 2 : -2, k & 2 ? 2 : -2, k & 4 ? 2 : -2);
        int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
        for (auto &f : faces) {
            uint32_t base = mesh->p.size();
            for (int k : f) mesh->p.push_back(c[k]);
            for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mesh->indices.push_back(base + k);
        }
        auto quad = std::make_shared<TriangleMesh>();
        quad->p = {{-1, -1, 0}, {1, -1, 0.5f}, {1, 1, 0.3f}, {-1, 1, -0.2f}};
        quad->indices = {0, 1, 2, 0, 2, 3};
        // Two spheres (one partial), one of them an emitter.
        spheres.emplace_back(Translate({0.5f, 0.7f, -1}), false, 0.4f, -0.4f, 0.4f, 360);
        spheres.emplace_back(Translate({-1, 0.5f, 1}) * Scale(1, 2, 1), false, 0.5f, -0.2f, 0.5f, 270);
        for (Accelerator *a : {&flat, &embree}) {
            a->AddMesh(0, std::make_shared<TriangleMesh>(*mesh), 0, -1);
            a->AddMesh(0, std::make_shared<TriangleMesh>(*quad), 1, 10);
            a->AddSphere(0, spheres[0], 2, 20);
            a->AddSphere(0, spheres[1], 3, -1);
            a->Commit();
        }
    }
};

}  // namespace

TEST(FlatTriangles, SmallScenesTraceAsEmbreeDoes) {
    TwoAccelerators s;
    EXPECT_TRUE(s.flat.TestsEveryShape());
    EXPECT_FALSE(s.embree.TestsEveryShape());
    std::mt19937 rng(11);
    int rays = 40000, disagree = 0, hits = 0, spheres = 0, lights = 0;
    for (int r = 0; r < rays; ++r) {
        Ray ray(RandomPoint(rng, -1.9f, 1.9f), RandomDirection(rng) * 0.8f);
        if (r % 2) ray.tMax = std::uniform_real_distribution<float>(0.1f, 6)(rng);
        SurfaceInteraction a, b;
        bool ha = s.flat.Intersect(ray, &a), hb = s.embree.Intersect(ray, &b);
        uint32_t skip = r % 3 == 0 ? s.spheres[r % 2].id : 0;
        bool oa = s.flat.Occluded(ray, skip), ob = s.embree.Occluded(ray, skip);
        // Rays that graze an edge may differ (two float tests); they are rare.
        if (ha != hb || oa != ob || (ha && (a.material != b.material || a.areaLight != b.areaLight ||
                                            std::abs(a.tHit - b.tHit) > 1e-4f * b.tHit))) {
            ++disagree;
            continue;
        }
        if (!ha) continue;
        ++hits;
        spheres += a.material >= 2;
        lights += a.areaLight >= 0;
        EXPECT_LT(Length(a.p - b.p), 1e-4f);
        EXPECT_LT(Length(Vector3f(a.n - b.n)), 1e-4f);
        EXPECT_LT(std::abs(a.uv.x - b.uv.x) + std::abs(a.uv.y - b.uv.y), 1e-3f);
    }
    EXPECT_LE(disagree, rays / 2000) << "rays on which the two disagree";
    EXPECT_GT(hits, rays / 2);
    EXPECT_GT(spheres, rays / 50);
    EXPECT_GT(lights, rays / 50);
}

TEST(FlatTriangles, OnlySmallScenesWithoutInstancesAreFlat) {
    auto grid = [](int triangles) {
        auto m = std::make_shared<TriangleMesh>();
        for (int i = 0; i < triangles; ++i) {
            uint32_t base = m->p.size();
            m->p.insert(m->p.end(), {{float(i), 0, 0}, {i + 1.f, 0, 0}, {float(i), 1, 0}});
            m->indices.insert(m->indices.end(), {base, base + 1, base + 2});
        }
        return m;
    };
    Accelerator small, large;
    small.AddMesh(0, grid(FlatTriangles::kMaxTriangles), 0, -1);
    small.Commit();
    large.AddMesh(0, grid(FlatTriangles::kMaxTriangles + 1), 0, -1);
    large.Commit();
    EXPECT_TRUE(small.TestsEveryShape());
    EXPECT_FALSE(large.TestsEveryShape());

    // A few spheres at most (each is a test of its own).
    Accelerator eight, nine;
    for (int i = 0; i < 9; ++i) {
        Sphere sphere(Translate({3.f * i, 0, 0}), false, 1, -1, 1, 360);
        if (i < 8) eight.AddSphere(0, sphere, 0, -1);
        nine.AddSphere(0, sphere, 0, -1);
    }
    eight.Commit();
    nine.Commit();
    EXPECT_TRUE(eight.TestsEveryShape());
    EXPECT_FALSE(nine.TestsEveryShape());

    Accelerator instanced;
    int obj = instanced.NewObject();
    instanced.AddMesh(obj, grid(2), 0, -1);
    instanced.AddInstance(obj, Translate({0, 0, 1}));
    instanced.Commit();
    EXPECT_FALSE(instanced.TestsEveryShape());
    SurfaceInteraction si;
    EXPECT_TRUE(instanced.Intersect(Ray({0.2f, 0.2f, 3}, {0, 0, -1}), &si));
    EXPECT_FLOAT_EQ(si.p.z, 1);
}
