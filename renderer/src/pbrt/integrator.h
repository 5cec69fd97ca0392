// The "path" integrator (pbrt-v4's PathIntegrator): unidirectional path tracing with
// next-event estimation, multiple importance sampling (power heuristic) between light and
// BSDF sampling, Russian roulette after the second bounce, and a maximum depth.
//
// Depth counts scattering events: maxdepth 0 shows emitters seen directly, 1 adds direct
// lighting, and so on. Other integrator names ("volpath", "bdpt", "mlt", "sppm", ...)
// render with "path" after one warning; "regularize" is not supported.
#pragma once

#include <pbrt/ray.h>
#include <pbrt/util/spectrum.h>

#include <string>
#include <vector>

namespace pbrt {

class ParameterDictionary;
class Sampler;
struct Scene;

struct IntegratorSettings {
    std::string name = "path";
    int maxDepth = 5;

    static IntegratorSettings Create(const std::string &name, const ParameterDictionary &params,
                                     const FileLoc &loc);
};

// Where each light's share of a path's radiance goes (the wavelength-guiding pre-pass,
// guiding.h, design §1.8): every term PathLi adds to its result (next-event estimation and
// emitter hits, both already MIS-weighted) is also added to byGroup[groupOfLight[light]] of the
// light that produced it (groups with index < 0 are not recorded). The terms of one path sum to
// what PathLi returns.
struct LightContributions {
    const std::vector<int> *groupOfLight = nullptr;
    std::vector<SampledSpectrum> byGroup;
    void Add(int light, const SampledSpectrum &c) {
        int g = (*groupOfLight)[size_t(light)];
        if (g >= 0) byGroup[size_t(g)] += c;
    }
};

// Radiance arriving along `ray` at the camera, at the wavelengths lambda. A dispersive
// material on the path terminates lambda's secondary wavelengths (design §1), so the caller
// must weight the result with lambda as it is after the call. `depth`, when given, receives
// the number of surfaces with a material the path reached (the last one, where maxdepth or
// Russian roulette ended it, included). `byLight`, when given, receives each light's terms.
// `uFirstLight`, when given, replaces the sampler's number for the first next-event
// estimation's choice of light (--wavelength-net, samplers.h); the sampler's number is drawn
// anyway, so that the path's other dimensions stay where they were.
SampledSpectrum PathLi(const Scene &scene, Ray ray, SampledWavelengths &lambda,
                       Sampler &sampler, int maxDepth, int *depth = nullptr,
                       LightContributions *byLight = nullptr, const Float *uFirstLight = nullptr);

}  // namespace pbrt
