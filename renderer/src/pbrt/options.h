// Command-line options that override or complement the scene file (one struct; cmd/pbrt.cpp
// fills it from kebab-case flags).
#pragma once

#include <pbrt/guiding.h>
#include <pbrt/util/vecmath.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace pbrt {

struct RenderOptions {
    std::optional<int> spp;               // --spp: samples per pixel (overrides "pixelsamples")
    std::string outfile;                  // --outfile: image to write (overrides the film's)
    int nThreads = 0;                     // --nthreads: 0 = all cores
    std::optional<uint64_t> seed;         // --seed: overrides the scene's seeds
    bool quiet = false;                   // --quiet: no progress bar or summary
    // --quick: a quarter of the film's resolution each way and one sample per pixel (pbrt-v4).
    bool quick = false;
    // --cropwindow x0,x1,y0,y1 (fractions of the image) or --pixelbounds x0,x1,y0,y1 (pixels;
    // --pixel x,y is one pixel): render that part only, replacing the film's own crop
    // (pbrt-v4's meaning; the EXR's data window says where it lies in the frame).
    std::optional<std::array<Float, 4>> cropWindow;
    std::optional<std::array<int, 4>> pixelBounds;
    bool stats = false;                   // --stats: print the render's statistics at the end
    // --mse-reference-image FILE: print the mean squared error of the image against FILE (same
    // size); --mse-reference-out FILE: write "spp MSE" lines, one per pass of samples.
    std::string mseReference, mseReferenceOut;
    // --write-partial-images: write the image after every pass of samples (passes of 1, 1, 2,
    // 4, ..., 64 samples per pixel, as pbrt-v4 renders).
    bool writePartialImages = false;
    // --log-level verbose|error|fatal: verbose adds what was loaded and how, fatal drops
    // warnings; --log-file FILE: messages go there (and the level becomes verbose).
    std::string logLevel = "error", logFile;
    // --disable-pixel-jitter, --disable-wavelength-jitter: as the scene's Option statements of
    // those names (pixel centres; the same wavelengths for every path).
    bool disablePixelJitter = false, disableWavelengthJitter = false;
    // --wavelength-net: film position, wavelength number and first light choice from one net
    // per pixel (design §5.2).
    bool wavelengthNet = false;
    // Wavelength sampling (design §5): "visible" (pbrt-v4's default), "uniform" over
    // [lambdaMin, lambdaMax] (stratified), or "emission" (a table built from the scene's
    // emitted power times emissionWeight, design §1.7; emission.h).
    std::string wavelengthSampling = "visible";
    std::string emissionWeight = "spd";   // --emission-weight: spd, luminance or xyz
    Float lambdaMin = 360, lambdaMax = 830;
    std::string wavelengthTable;          // --wavelength-pdf FILE: sample from a table (design §1, §2)
    Float defensiveShare = 0;             // --wavelength-pdf-defensive S: uniform share in [0, 1]
    Point2i resolution{0, 0};             // --resolution WxH (0: the film's)
    Float resolutionScale = 1;            // --resolution-scale S: multiplies the resolution
    std::optional<int> maxDepth;          // --maxdepth: overrides the integrator's
    // --wavelength-repeats K: trace every camera sample K times with the same random numbers
    // except the wavelength number, shifted by k/K, and average them (design §5.2): the
    // benchmark's floor, an image whose wavelength noise is averaged away.
    int wavelengthRepeats = 1;
    // --wavelength-seed S: each sample's wavelength number u drawn from a hash of the pixel,
    // the sample index and S alone (design §5.2), so that renders with one --seed and two S
    // trace the same paths at independent wavelengths (the spread's renders, design §6.8).
    std::optional<uint64_t> wavelengthSeed;
    // --emission-spectrum FILE: write the scene's total emitted spectral power (design §5.6)
    // instead of rendering (the film's output path is then not checked).
    std::string emissionSpectrum;
    // --material-reflectances FILE: write the diffuse reflectances of the scene's materials
    // (design §5.6) instead of rendering.
    std::string materialReflectances;
    // --emission-table FILE: write the table --wavelength-sampling emission would sample from
    // (design §2 layout) instead of rendering.
    std::string emissionTable;
    // --wavelength-guiding (design §1.8, §5.2): a pre-pass chooses each pixel's table among at
    // most guidingTables tables of the light mixtures it finds (guiding.h). The scene's emission
    // table (with emissionWeight) is built as for "emission"; the pre-pass samples with it.
    bool wavelengthGuiding = false;
    double guidingPrepassShare = kDefaultGuidingPrepassShare;  // --guiding-prepass-share F in (0, 1]
    int guidingTables = kDefaultGuidingTables;                 // --guiding-tables K in [1, 16]
    double guidingDefensive = kDefaultGuidingDefensive;        // --guiding-defensive S in (0, 1]
    int guidingTile = kDefaultGuidingTile;                     // --guiding-tile N in [1, 256]
    std::string guidingTablesDir;         // --wavelength-guiding-tables DIR: optimized tables
    // --wavelength-guiding-spectra DIR: write the tables' mixture spectra (the pre-pass's
    // result) instead of rendering.
    std::string guidingSpectraDir;
};

}  // namespace pbrt
