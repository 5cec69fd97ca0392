// Rendering the image: pixels in 16x16 tiles spread over threads with TBB. A pixel's value
// depends only on the scene, the seed and the pixel, never on the number of threads or the
// order in which tiles run (each pixel's samples come from its own sampler state and only
// touch that pixel, thanks to filter importance sampling).
//
// Each path draws, in this order: the film sample (2D), the wavelength sample (1D, through
// the scene's WavelengthSampler: four wavelengths from one u), the lens sample (2D), then
// what the integrator asks for.
#pragma once

#include <cstdint>

namespace pbrt {

struct Scene;

struct RenderStats {
    double wallSeconds = 0, cpuSeconds = 0;
    uint64_t paths = 0;
};

// Renders into scene.film. nThreads 0 uses every core.
RenderStats Render(const Scene &scene, int nThreads, bool quiet);

// CPU time (user + system) used by this process so far, in seconds.
double ProcessCPUSeconds();

}  // namespace pbrt
