// A scene ready to render, and how it is built from pbrt-v4 scene files.
//
// The builder (scene.cpp) implements the parser's ParserTarget: the graphics state stack
// (CTM, ReverseOrientation, material, area light, colour space, Attribute defaults), named
// coordinate systems, materials, textures and object instances, and the scene-wide
// directives. What it does not support and would change the picture (a material type,
// shape, light, parameter, participating media, motion blur) is a PbrtError naming it and
// its file:line; what cannot change the picture is at most a warning.
#pragma once

#include <pbrt/accel.h>
#include <pbrt/cameras.h>
#include <pbrt/film.h>
#include <pbrt/filters.h>
#include <pbrt/integrator.h>
#include <pbrt/lights.h>
#include <pbrt/materials.h>
#include <pbrt/options.h>
#include <pbrt/samplers.h>
#include <pbrt/wavelengths.h>

#include <memory>
#include <string>
#include <vector>

namespace pbrt {

struct Scene {
    std::unique_ptr<Accelerator> accel;
    std::vector<Material> materials;
    // Per material: where it was defined ("FILE:LINE:COL", or the default material) and
    // whether any shape uses it (for --material-reflectances, design §5.6).
    std::vector<std::string> materialWhere;
    std::vector<char> materialUsed;
    std::vector<Light> lights;
    std::vector<int> infiniteLights;   // indices of lights seen by escaping rays
    LightSampler lightSampler;
    bool hasInterfaces = false;        // any "interface" surfaces (shadow rays pass them)

    std::unique_ptr<Camera> camera;
    std::unique_ptr<RGBFilm> film;
    Filter filter = Filter::Gaussian({1.5f, 1.5f}, 0.5f);
    Sampler sampler;
    IntegratorSettings integrator;
    WavelengthSampler wavelengths = WavelengthSampler::Visible();
    bool disablePixelJitter = false, disableWavelengthJitter = false;
    // --wavelength-net: each sample's film position, wavelength number and first light choice
    // from one net per pixel (samplers.h, WavelengthNet) instead of the sampler's dimensions.
    bool wavelengthNet = false;
    // --wavelength-seed S: each sample's wavelength number from a hash of (pixel, sample, S)
    // in place of the sampler's or the net's (render.h).
    std::optional<uint64_t> wavelengthSeed;

    // Whether nothing opaque lies on the segment of a shadow ray.
    // skipSphere: a sphere's id (Sphere::id) the segment is known not to cross, or 0.
    bool Unoccluded(const Ray &ray, uint32_t skipSphere = 0) const;
};

// Parses the files (standard input if none) and builds the scene, applying the options.
std::unique_ptr<Scene> LoadScene(const std::vector<std::string> &files, const RenderOptions &opts);
// The same for scene text in memory (`name` names it in error messages).
std::unique_ptr<Scene> LoadSceneFromString(const std::string &text, const RenderOptions &opts,
                                           const std::string &name = "<string>");

}  // namespace pbrt
