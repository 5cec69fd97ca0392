// Transforms: pbrt's conventions (column-major file matrices, LookAt's camera frame) and
// inverses.
#include <pbrt/util/transform.h>

#include <pbrt/cameras.h>
#include <pbrt/util/rng.h>

#include <gtest/gtest.h>

using namespace pbrt;

namespace {
void ExpectNear(const Vector3f &a, const Vector3f &b, Float tol, const char *what) {
    EXPECT_NEAR(a.x, b.x, tol) << what << ": " << ToString(a) << " vs " << ToString(b);
    EXPECT_NEAR(a.y, b.y, tol) << what << ": " << ToString(a) << " vs " << ToString(b);
    EXPECT_NEAR(a.z, b.z, tol) << what << ": " << ToString(a) << " vs " << ToString(b);
}
}  // namespace

TEST(Transform, ColumnMajorFileMatrix) {
    // The Cornell box's camera transform: the translation is in elements 12..14.
    Float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, -1, 6.8f, 1};
    Transform t = TransformFromColumnMajor(m);
    ExpectNear(t.ApplyPoint({0, 0, 0}), {0, -1, 6.8f}, 1e-6f, "origin");
    ExpectNear(t.ApplyVector({0, 0, 1}), {0, 0, -1}, 1e-6f, "z axis");
    EXPECT_TRUE(t.SwapsHandedness());
}

TEST(Transform, InverseRoundTrip) {
    RNG rng(2);
    Transform t = Translate({1, -2, 3}) * Rotate(37, {1, 2, 3}) * Scale(2, 0.5f, 3);
    Transform inv = Inverse(t);
    for (int i = 0; i < 100; ++i) {
        Point3f p(rng.UniformFloat() * 10 - 5, rng.UniformFloat() * 10 - 5, rng.UniformFloat() * 10 - 5);
        ExpectNear(inv.ApplyPoint(t.ApplyPoint(p)), p, 1e-4f, "point");
        ExpectNear(inv.ApplyVector(t.ApplyVector(p)), p, 1e-4f, "vector");
    }
    // Normals stay perpendicular to transformed tangents.
    Vector3f tangent(1, 1, 0), normal(1, -1, 0.5f);
    ASSERT_NEAR(Dot(tangent, normal), 0, 1e-6);
    EXPECT_NEAR(Dot(t.ApplyVector(tangent), t.ApplyNormal(normal)), 0, 1e-4);
    EXPECT_THROW(Scale(0, 1, 1), PbrtError);
}

TEST(Transform, RotateFollowsRightHandRule) {
    ExpectNear(Rotate(90, {0, 0, 1}).ApplyVector({1, 0, 0}), {0, 1, 0}, 1e-6f, "z rotation");
    ExpectNear(Rotate(90, {1, 0, 0}).ApplyVector({0, 1, 0}), {0, 0, 1}, 1e-6f, "x rotation");
}

TEST(Transform, LookAtConventions) {
    // Camera space: +z toward the look-at point, +y up, +x = Cross(up, forward).
    Point3f eye(1, 2, 3), look(1, 2, -7);
    Transform cameraFromWorld = LookAt(eye, look, {0, 1, 0});
    ExpectNear(cameraFromWorld.ApplyPoint(eye), {0, 0, 0}, 1e-5f, "eye at the origin");
    ExpectNear(cameraFromWorld.ApplyPoint(look), {0, 0, 10}, 1e-5f, "look point on +z");
    Transform worldFromCamera = Inverse(cameraFromWorld);
    ExpectNear(worldFromCamera.ApplyVector({0, 1, 0}), {0, 1, 0}, 1e-6f, "camera up is world up");
    // Looking down -z with y up, pbrt's camera +x is world -x (left-handed camera space).
    ExpectNear(worldFromCamera.ApplyVector({1, 0, 0}), {-1, 0, 0}, 1e-6f, "camera x");
    EXPECT_THROW(LookAt({0, 0, 0}, {0, 1, 0}, {0, 1, 0}), PbrtError);
}

TEST(Camera, RayDirectionsForKnownFov) {
    // 200 x 100 image, fov 60 applies to the shorter (vertical) axis.
    Float screen[4];
    Camera::DefaultScreenWindow(2.f, screen);
    EXPECT_FLOAT_EQ(screen[0], -2.f);
    EXPECT_FLOAT_EQ(screen[3], 1.f);
    Transform worldFromCamera;  // identity: camera at origin looking down +z
    Camera cam(Camera::Type::Perspective, worldFromCamera, {200, 100}, screen, 60);
    Ray c = cam.GenerateRay({100, 50}, {0.5f, 0.5f});
    ExpectNear(c.d, {0, 0, 1}, 1e-6f, "centre ray");
    // Top edge centre: 30 degrees above the axis, +y (raster y = 0 is the top row).
    Ray top = cam.GenerateRay({100, 0}, {0.5f, 0.5f});
    EXPECT_NEAR(Degrees(std::atan2(top.d.y, top.d.z)), 30, 1e-3);
    // Right edge centre: tan(angle) = 2 tan(30 deg), toward +x.
    Ray right = cam.GenerateRay({200, 50}, {0.5f, 0.5f});
    EXPECT_NEAR(right.d.x / right.d.z, 2 * std::tan(Radians(30)), 1e-5);
    EXPECT_GT(right.d.x, 0);
    // A square image: fov on both axes.
    Float sq[4];
    Camera::DefaultScreenWindow(1.f, sq);
    Camera cam2(Camera::Type::Perspective, Translate({0, 0, -5}), {64, 64}, sq, 90);
    Ray corner = cam2.GenerateRay({0, 64}, {0.5f, 0.5f});
    ExpectNear(corner.o, {0, 0, -5}, 1e-6f, "origin follows worldFromCamera");
    ExpectNear(corner.d, Normalize(Vector3f(-1, -1, 1)), 1e-5f, "bottom-left corner");
}

TEST(Camera, OrthographicAndThinLens) {
    Float screen[4] = {-2, 2, -1, 1};
    Camera ortho(Camera::Type::Orthographic, Transform(), {100, 50}, screen, 0);
    Ray r = ortho.GenerateRay({75, 25}, {0.5f, 0.5f});
    ExpectNear(r.o, {1, 0, 0}, 1e-5f, "orthographic origin");
    ExpectNear(r.d, {0, 0, 1}, 1e-6f, "orthographic direction");
    // Thin lens: every lens sample's ray passes through the in-focus point.
    Camera lens(Camera::Type::Perspective, Transform(), {100, 50}, screen, 40, 0.2f, 3);
    Ray pin = Camera(Camera::Type::Perspective, Transform(), {100, 50}, screen, 40).GenerateRay({30, 10}, {0.5f, 0.5f});
    Point3f focus = pin(3 / pin.d.z);
    RNG rng(4);
    for (int i = 0; i < 20; ++i) {
        Ray l = lens.GenerateRay({30, 10}, {rng.UniformFloat(), rng.UniformFloat()});
        Float t = (focus.z - l.o.z) / l.d.z;
        ExpectNear(l(t), focus, 1e-4f, "focus point");
    }
}
