#include <pbrt/cameras.h>

#include <pbrt/util/paramdict.h>
#include <pbrt/shapes.h>
#include <pbrt/util/sampling.h>

#include <cmath>

namespace pbrt {

Camera::Camera(Type type, const Transform &worldFromCamera, Point2i fullResolution,
               const Float screenWindow[4], Float fovDegrees, Float lensRadius,
               Float focalDistance, Float shutterOpen, Float shutterClose)
    : type(type), worldFromCamera(worldFromCamera), resolution(fullResolution), fov(fovDegrees),
      lensRadius(lensRadius), focalDistance(focalDistance), shutterOpen(shutterOpen),
      shutterClose(shutterClose) {
    for (int i = 0; i < 4; ++i) screen[i] = screenWindow[i];
    tanHalfFov = std::tan(Radians(fovDegrees) / 2);
}

void Camera::DefaultScreenWindow(Float frame, Float s[4]) {
    if (frame > 1) {
        s[0] = -frame; s[1] = frame; s[2] = -1; s[3] = 1;
    } else {
        s[0] = -1; s[1] = 1; s[2] = -1 / frame; s[3] = 1 / frame;
    }
}

Camera Camera::Create(const std::string &name, const ParameterDictionary &params,
                      const Transform &cameraFromWorld, Point2i res, const FileLoc &loc) {
    Type type;
    if (name == "perspective") type = Type::Perspective;
    else if (name == "orthographic") type = Type::Orthographic;
    else
        throw PbrtError(loc, "Camera \"" + name +
                                 "\" is not supported (supported: perspective, orthographic)");

    Float shutterOpen = params.GetOneFloat("shutteropen", 0);
    Float shutterClose = params.GetOneFloat("shutterclose", 1);
    if (shutterClose < shutterOpen)
        throw PbrtError(loc, "Camera: shutterclose is before shutteropen");
    Float lensRadius = params.GetOneFloat("lensradius", 0);
    Float focalDistance = params.GetOneFloat("focaldistance", 1e6f);
    if (lensRadius < 0 || !(focalDistance > 0))
        throw PbrtError(loc, "Camera: lensradius must be >= 0 and focaldistance > 0");

    // Screen window: explicit, or from the frame aspect ratio (default x / y resolution).
    Float frame = params.GetOneFloat("frameaspectratio", Float(res.x) / Float(res.y));
    if (!(frame > 0)) throw PbrtError(params.Loc("frameaspectratio"), "frameaspectratio must be positive");
    Float screen[4];
    DefaultScreenWindow(frame, screen);
    std::vector<Float> sw = params.GetFloatArray("screenwindow");
    if (!sw.empty()) {
        if (sw.size() != 4 || !(sw[0] < sw[1]) || !(sw[2] < sw[3]))
            throw PbrtError(params.Loc("screenwindow"),
                            "\"screenwindow\" needs four values xmin xmax ymin ymax with min < max");
        for (int i = 0; i < 4; ++i) screen[i] = sw[i];
        if (!std::isfinite(screen[1] - screen[0]) || !std::isfinite(screen[3] - screen[2]))
            throw PbrtError(params.Loc("screenwindow"),
                            "\"screenwindow\" is too large (its width or height overflows)");
    }

    Float fov = 90;
    if (type == Type::Perspective) {
        fov = params.GetOneFloat("fov", 90);
        if (!(fov > 0 && fov < 180)) throw PbrtError(params.Loc("fov"), "fov must be in (0, 180) degrees");
    }
    return Camera(type, Inverse(cameraFromWorld), res, screen, fov, lensRadius, focalDistance,
                  shutterOpen, shutterClose);
}

Ray Camera::GenerateRay(Point2f pFilm, Point2f uLens) const {
    // Raster -> screen: x left to right, y flipped (raster down, screen up).
    Float sx = screen[0] + pFilm.x / resolution.x * (screen[1] - screen[0]);
    Float sy = screen[3] - pFilm.y / resolution.y * (screen[3] - screen[2]);
    Ray r;
    if (type == Type::Perspective) {
        r = Ray(Point3f(0, 0, 0), Normalize(Vector3f(sx * tanHalfFov, sy * tanHalfFov, 1)));
    } else {
        r = Ray(Point3f(sx, sy, 0), Vector3f(0, 0, 1));
    }
    if (lensRadius > 0) {
        // Thin lens: aim the ray from a point on the lens through the in-focus point.
        Point2f pl = SampleUniformDiskConcentric(uLens) * lensRadius;
        Float ft = focalDistance / r.d.z;
        Point3f pFocus = r(ft);
        r.o = Point3f(r.o.x + pl.x, r.o.y + pl.y, 0);
        if (type == Type::Perspective) r.o = Point3f(pl.x, pl.y, 0);
        r.d = Normalize(pFocus - r.o);
    }
    Ray w = worldFromCamera.ApplyRay(r);
    w.d = Normalize(w.d);
    w.tMax = Infinity;
    return w;
}

void Camera::CheckRays(Vector2f filterRadius, const FileLoc &loc) const {
    const SquareMatrix4 &m = worldFromCamera.Matrix();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (!std::isfinite(m.m[i][j]))
                throw PbrtError(loc, "the camera transformation is not finite (its inverse "
                                     "overflows: is the CTM at the Camera statement singular "
                                     "or huge?)");
    // Rays are affine in the film position (before normalization), so the extremes of the
    // film and the lens bound every ray's magnitude.
    const Float xs[] = {-filterRadius.x, Float(resolution.x) / 2, resolution.x + filterRadius.x};
    const Float ys[] = {-filterRadius.y, Float(resolution.y) / 2, resolution.y + filterRadius.y};
    const Point2f lens[] = {{0.5f, 0.5f}, {0, 0}, {1, 1}, {0, 1}, {1, 0}};
    for (Float x : xs)
        for (Float y : ys)
            for (const Point2f &u : lens) {
                Ray r = GenerateRay(Point2f(x, y), u);
                bool ok = std::isfinite(r.d.x) && std::isfinite(r.d.y) && std::isfinite(r.d.z) &&
                          LengthSquared(r.d) > 0 && WithinRenderRange(r.o);
                if (!ok)
                    throw PbrtError(loc, "camera rays at film position (" + std::to_string(x) +
                                             ", " + std::to_string(y) +
                                             ") are not finite or start beyond +-1e12: the "
                                             "camera transformation, screen window, lens or "
                                             "pixel filter radius is too large");
            }
}

SquareMatrix4 Camera::NDCFromWorld() const {
    SquareMatrix4 screenFromCamera;  // identity
    if (type == Type::Perspective) {
        // pbrt-v4's Perspective(fov, n = 0.01, f = 1000): x/z and y/z over tan(fov / 2), and
        // z' = f (z - n) / ((f - n) z) after the divide by w = z.
        const double n = 1e-2, f = 1000, inv = 1 / std::tan(Radians(fov) / 2);
        const Float m[16] = {Float(inv), 0, 0, 0,
                             0, Float(inv), 0, 0,
                             0, 0, Float(f / (f - n)), Float(-f * n / (f - n)),
                             0, 0, 1, 0};
        screenFromCamera = SquareMatrix4::FromRowMajor(m);
    }
    // (Orthographic(0, 1) is the identity.)
    const Float half[16] = {0.5f, 0, 0, 0.5f, 0, 0.5f, 0, 0.5f, 0, 0, 0.5f, 0.5f, 0, 0, 0, 1};
    return SquareMatrix4::FromRowMajor(half) * screenFromCamera * CameraFromWorld();
}

std::string Camera::Description() const {
    std::string s = type == Type::Perspective ? "perspective fov " + std::to_string(fov) : "orthographic";
    if (lensRadius > 0) s += " lens radius " + std::to_string(lensRadius);
    return s;
}

}  // namespace pbrt
