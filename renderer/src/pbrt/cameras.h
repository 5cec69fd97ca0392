// Cameras: "perspective" and "orthographic" with an optional thin lens.
//
// pbrt conventions: camera space looks down +z with +y up and +x to the right of the image;
// the scene's CTM at the Camera directive is camera-from-world. The screen window defaults to
// [-a, a] x [-1, 1] for an aspect ratio a = x/y >= 1 (else [-1, 1] x [-1/a, 1/a]), so "fov"
// is the field of view of the shorter image axis. Raster (0, 0) is the top-left corner of
// the full-resolution image; raster y grows downwards while screen y grows upwards.
#pragma once

#include <pbrt/ray.h>
#include <pbrt/util/transform.h>
#include <pbrt/util/vecmath.h>

#include <string>

namespace pbrt {

class ParameterDictionary;

class Camera {
  public:
    enum class Type { Perspective, Orthographic };

    // screenWindow = {xmin, xmax, ymin, ymax}; fovDegrees is ignored for Orthographic.
    Camera(Type type, const Transform &worldFromCamera, Point2i fullResolution,
           const Float screenWindow[4], Float fovDegrees, Float lensRadius = 0,
           Float focalDistance = 1e6f, Float shutterOpen = 0, Float shutterClose = 1);

    // From a Camera directive. cameraFromWorld is the CTM at the directive; the film's full
    // resolution (after command-line overrides) gives the default aspect ratio.
    static Camera Create(const std::string &name, const ParameterDictionary &params,
                         const Transform &cameraFromWorld, Point2i fullResolution,
                         const FileLoc &loc);

    // The screen window that pbrt-v4 uses by default for a frame aspect ratio.
    static void DefaultScreenWindow(Float frameAspect, Float screen[4]);

    // A world-space ray with a normalized direction through raster point pFilm; uLens
    // samples the lens (unused for a pinhole).
    Ray GenerateRay(Point2f pFilm, Point2f uLens) const;

    const Transform &WorldFromCamera() const { return worldFromCamera; }
    // The matrices pbrt-v4 records in its EXR images: camera from world ("worldToCamera"),
    // and NDC from world ("worldToNDC"): Translate(1/2, 1/2, 1/2) Scale(1/2, 1/2, 1/2)
    // screenFromCamera cameraFromWorld, screenFromCamera being pbrt-v4's projection
    // (perspective: x and y divided by z tan(fov/2), z mapped from [0.01, 1000] to [0, 1];
    // orthographic: z from [0, 1]). A world point p lands on screen point (2 ndc - 1) (x, y),
    // i.e. raster x = (2 ndc.x - 1 - screen x0) / (x1 - x0) * width, and raster y likewise
    // from the top (ndc.y grows upwards).
    SquareMatrix4 CameraFromWorld() const { return worldFromCamera.InverseMatrix(); }
    SquareMatrix4 NDCFromWorld() const;
    Float ExposureTime() const { return shutterClose - shutterOpen; }
    std::string Description() const;
    // Throws PbrtError(loc) unless every camera ray is one the ray tracer can trace: film
    // positions up to filterRadius pixels beyond the film's edges, any lens position, must
    // give a finite, non-zero direction and an origin within kMaxRenderCoordinate (a huge
    // camera transform, screen window or filter radius would overflow).
    void CheckRays(Vector2f filterRadius, const FileLoc &loc) const;

  private:
    Type type;
    Transform worldFromCamera;
    Point2i resolution;
    Float screen[4];
    Float fov, tanHalfFov, lensRadius, focalDistance, shutterOpen, shutterClose;
};

}  // namespace pbrt
