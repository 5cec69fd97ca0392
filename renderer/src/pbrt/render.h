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
#include <functional>

namespace pbrt {

struct Scene;
class WavelengthGuide;

struct RenderStats {
    double wallSeconds = 0, cpuSeconds = 0;
    uint64_t paths = 0;        // camera paths traced (pixels x spp x wavelength repeats)
    uint64_t scatterings = 0;  // surface hits of all those paths (PathLi's depth)
    int wavelengthRepeats = 1;
};

// Renders into scene.film. nThreads 0 uses every core. wavelengthRepeats K > 1 traces each
// camera sample K times, with the sampler's numbers replayed except the wavelength number u,
// which becomes (u + k/K) mod 1, and adds their mean (--wavelength-repeats, design §5.2).
// With scene.wavelengthSeed, u is a hash of the pixel, the sample index and that seed
// (--wavelength-seed), before the repeats' shifts.
//
// afterPass, when given, makes the render go in passes over the whole image, of 1, 1, 2, 4,
// ..., 64 samples per pixel (pbrt-v4's waves), and is called after each with the samples per
// pixel done so far (--write-partial-images, --mse-reference-out). A pixel's value is the same
// either way: its samples are added in the same order.
//
// With a guide (wavelength guiding, guiding.h), each pixel draws its wavelengths from the
// guide's table for that pixel instead of scene.wavelengths.
RenderStats Render(const Scene &scene, int nThreads, bool quiet, int wavelengthRepeats = 1,
                   const std::function<void(int sppDone)> &afterPass = {},
                   const WavelengthGuide *guide = nullptr);

// The provenance an EXR image of the render records (with the film's "chromaticities" and
// "colorSpace"):
//   samplesPerPixel           int     samples per pixel (pbrt-v4's name)
//   renderTimeSeconds         float   wall-clock seconds of the render (pbrt-v4's name)
//   seed                      string  the sampler's seed, in decimal (EXR has no 64-bit int)
//   wavelengthSampler         string  "visible", "uniform", "table", "emission" or "guided"
//   wavelengthRange           v2f     the range it samples, in nm
//   wavelengthTable           string  the table file as named (only with a table)
//   wavelengthTableSHA256     string  SHA-256 of the table file's bytes, as sha256sum prints it
//   wavelengthDefensiveShare  float   the uniform share mixed into the table (--wavelength-pdf-defensive)
//   renderCPUSeconds          float   CPU seconds (user + system, all threads) of the render
//   meanPathDepth             float   surfaces a camera path reached (at most maxdepth + 1), averaged
//   wavelengthRepeats         int     K of --wavelength-repeats (only when K > 1)
//   wavelengthNet             int     1 with --wavelength-net (absent otherwise)
//   wavelengthSeed            string  S of --wavelength-seed, in decimal (absent otherwise)
//   wavelengthEmissionWeight  string  with emission sampling (and guiding): its weight, "spd", "luminance" or "xyz"
// With wavelength guiding (guiding.h, AddGuidingMetadata; renderCPUSeconds then includes the
// pre-pass and the tables):
//   wavelengthGuidingTables               int     K, the number of tables
//   wavelengthGuidingKinds                int     kinds of light (distinct spectra up to scale)
//   wavelengthGuidingTile                 int     pixels per side of a pre-pass tile
//   wavelengthGuidingPrepassPathsPerTile  int     pre-pass paths per tile (0: no pre-pass, one kind)
//   wavelengthGuidingBytes                int     memory of the tables and the index map
//   wavelengthGuidingPrepassShare         float   --guiding-prepass-share
//   wavelengthGuidingDefensive            float   --guiding-defensive S
//   wavelengthGuidingCPUSeconds           float   CPU seconds of the pre-pass and the tables
//   wavelengthGuidingTablesDir            string  --wavelength-guiding-tables (optimized tables)
//   channel wavelengthTable.index         float   per pixel: the index of its table
ImageMetadata RenderMetadata(const Scene &scene, const RenderStats &stats);

// CPU time (user + system) used by this process so far, in seconds.
double ProcessCPUSeconds();

}  // namespace pbrt
