// Cameras: the matrices recorded in the image (pbrt-v4's worldToCamera and worldToNDC) agree
// with the rays the camera generates.
#include <pbrt/cameras.h>

#include <pbrt/util/paramdict.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace pbrt;

namespace {

// m applied to the homogeneous point (p, 1), divided by w.
Point3f Project(const SquareMatrix4 &m, Point3f p) {
    double v[4];
    for (int i = 0; i < 4; ++i) v[i] = m.m[i][0] * double(p.x) + m.m[i][1] * double(p.y) + m.m[i][2] * double(p.z) + m.m[i][3];
    return Point3f(Float(v[0] / v[3]), Float(v[1] / v[3]), Float(v[2] / v[3]));
}

ParsedParameter FloatParam(const std::string &name, std::vector<double> v) {
    ParsedParameter p;
    p.type = "float";
    p.name = name;
    p.floats = std::move(v);
    return p;
}

}  // namespace

TEST(Camera, MatricesProjectRayPointsToTheirRasterPositions) {
    const Transform cameraFromWorld = LookAt(Point3f(1, 2, -4), Point3f(0, 0.5f, 0), Vector3f(0, 1, 0));
    const Point2i res{40, 20};
    for (const char *type : {"perspective", "orthographic"})
        for (bool window : {false, true}) {
            ParsedParameterVector params = {FloatParam("fov", {30})};
            if (std::string(type) == "orthographic") params.clear();
            if (window) params.push_back(FloatParam("screenwindow", {-1.5, 2.5, -0.5, 1.5}));
            ParameterDictionary dict(params);
            Camera cam = Camera::Create(type, dict, cameraFromWorld, res, FileLoc{});
            Float sw[4] = {-2, 2, -1, 1};  // the default for a 2:1 frame
            if (window) {
                sw[0] = -1.5f;
                sw[1] = 2.5f;
                sw[2] = -0.5f;
                sw[3] = 1.5f;
            }
            // worldToCamera is the CTM at the Camera statement.
            const SquareMatrix4 c = cam.CameraFromWorld();
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) EXPECT_NEAR(c.m[i][j], cameraFromWorld.Matrix().m[i][j], 1e-6);
            // A point along the ray through raster (x, y) projects back to (x, y).
            const SquareMatrix4 ndc = cam.NDCFromWorld();
            for (Point2f film : {Point2f(0.5f, 0.5f), Point2f(20, 10), Point2f(3.25f, 17.5f), Point2f(39.9f, 0.1f)})
                for (Float t : {0.5f, 3.f, 40.f}) {
                    Ray r = cam.GenerateRay(film, Point2f(0.5f, 0.5f));
                    Point3f q = Project(ndc, r(t));
                    Float sx = 2 * q.x - 1, sy = 2 * q.y - 1;
                    Float rx = (sx - sw[0]) / (sw[1] - sw[0]) * res.x, ry = (sw[3] - sy) / (sw[3] - sw[2]) * res.y;
                    EXPECT_NEAR(rx, film.x, 2e-3) << type << " t " << t;
                    EXPECT_NEAR(ry, film.y, 2e-3) << type << " t " << t;
                    // NDC z: half the screen z plus a half; screen z is the perspective depth
                    // between the planes 0.01 and 1000, or the orthographic camera-space z.
                    Point3f pc = cameraFromWorld.ApplyPoint(r(t));
                    Float z = std::string(type) == "perspective" ? Float(1000 * (pc.z - 0.01) / (999.99 * pc.z)) : pc.z;
                    EXPECT_NEAR(q.z, 0.5f * z + 0.5f, 1e-4 * std::max<Float>(1, std::abs(z)));
                }
        }
}
