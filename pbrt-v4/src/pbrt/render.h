// Rendering the image: pixels in 16x16 tiles spread over threads with TBB. A pixel's value
// depends only on the scene, the seed and the pixel, never on the number of threads or the
// order in which tiles run (each pixel's samples come from its own sampler state and only
// touch that pixel, thanks to filter importance sampling).
//
// Each path draws, in this order: the film sample (2D), the wavelength sample (1D, through
// the scene's WavelengthSampler: four wavelengths from one u), the lens sample (2D), then
// what the integrator asks for.
#pragma once

#include <pbrt/util/image.h>

#include <cstdint>

namespace pbrt {

struct Scene;

struct RenderStats {
    double wallSeconds = 0, cpuSeconds = 0;
    uint64_t paths = 0;
};

// Renders into scene.film. nThreads 0 uses every core.
RenderStats Render(const Scene &scene, int nThreads, bool quiet);

// The provenance an EXR image of the render records (with the film's "chromaticities" and
// "colorSpace"):
//   samplesPerPixel           int     samples per pixel (pbrt-v4's name)
//   renderTimeSeconds         float   wall-clock seconds of the render (pbrt-v4's name)
//   seed                      string  the sampler's seed, in decimal (EXR has no 64-bit int)
//   wavelengthSampler         string  "visible", "uniform", "table" or "emission"
//   wavelengthRange           v2f     the range it samples, in nm
//   wavelengthTable           string  the table file as named (only with a table)
//   wavelengthTableSHA256     string  SHA-256 of the table file's bytes, as sha256sum prints it
//   wavelengthDefensiveShare  float   the uniform share mixed into the table (--wavelength-pdf-defensive)
//   wavelengthEmissionWeight  string  with emission sampling: its weight, "spd", "luminance" or "xyz"
ImageMetadata RenderMetadata(const Scene &scene, const RenderStats &stats);

// CPU time (user + system) used by this process so far, in seconds.
double ProcessCPUSeconds();

}  // namespace pbrt
