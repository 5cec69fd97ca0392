// The "rgb" film: accumulates filter-weighted RGB (from the cie1931 FilmSensor, in the output
// colour space) per pixel and writes linear RGB, EXR 32-bit float or PNG by file extension.
//
// Parameters (pbrt-v4): xresolution (1280), yresolution (720), filename ("pbrt.exr"),
// cropwindow [x0 x1 y0 y1] in [0,1], pixelbounds [x0 x1 y0 y1], iso (100), whitebalance
// (0 only), sensor ("cie1931" only), maxcomponentvalue (infinite; applied to the output
// RGB), savefp16 (ignored: EXR is always 32-bit float), diagonal (only for realistic cameras).
// The colour space is the one in effect at the Film directive (ColorSpace directive).
// The "spectral" film (nbuckets 16, lambdamin 360, lambdamax 830) writes the same RGB plus the
// spectral radiance in nbuckets equal bands as EXR channels "S0.<centre>nm" (OpenEXR's
// spectral layout, pbrt-v4's names and units); "gbuffer" is refused at its line.
#pragma once

#include <pbrt/options.h>
#include <pbrt/sensor.h>
#include <pbrt/util/color.h>
#include <pbrt/util/image.h>
#include <pbrt/util/vecmath.h>

#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace pbrt {

class ParameterDictionary;

// The largest film side in pixels: pixel coordinates are ints. (Films far smaller are
// refused too when they cannot fit in memory.)
constexpr int kMaxFilmSide = std::numeric_limits<int>::max();

struct FilmSettings {
    Point2i fullResolution{1280, 720};
    Bounds2i pixelBounds{{0, 0}, {1280, 720}};
    std::string filename = "pbrt.exr";
    Float iso = 100;
    Float maxComponentValue = std::numeric_limits<Float>::infinity();
    const RGBColorSpace *colorSpace = nullptr;
    // "spectral" films: buckets of spectral radiance over [lambdaMin, lambdaMax] (0: "rgb").
    int nBuckets = 0;
    Float lambdaMin = 360, lambdaMax = 830;

    // From a Film directive and the command line: opts.resolution (if x > 0) replaces the
    // resolution, opts.resolutionScale scales it (the crop window stays the same fraction of
    // the image), opts.quick divides it by 4, and opts.cropWindow / opts.pixelBounds replace
    // the film's crop.
    static FilmSettings Create(const std::string &type, const ParameterDictionary &params,
                               const RGBColorSpace *colorSpace, const RenderOptions &opts,
                               const FileLoc &loc);
};

class RGBFilm {
  public:
    RGBFilm(const FilmSettings &settings, Float exposureTime);

    const FilmSettings &Settings() const { return settings; }
    Bounds2i PixelBounds() const { return settings.pixelBounds; }
    Point2i FullResolution() const { return settings.fullResolution; }
    const FilmSensor &Sensor() const { return sensor; }

    // The RGB of one path's radiance (clamped per maxcomponentvalue; non-finite values
    // become 0 and are counted).
    RGB ToRGB(const SampledSpectrum &L, const SampledWavelengths &lambda) const;

    // Adds a weighted RGB sample to a pixel; pixels are independent (filter importance
    // sampling), so threads that own different pixels never touch the same entry.
    void AddSample(Point2i pPixel, const RGB &rgb, Float weight) {
        Pixel &px = pixels[Offset(pPixel)];
        px.rgb[0] += double(weight) * rgb.r;
        px.rgb[1] += double(weight) * rgb.g;
        px.rgb[2] += double(weight) * rgb.b;
        px.weight += weight;
    }
    bool IsSpectral() const { return settings.nBuckets > 0; }
    // Spectral films: adds weight times one path's spectral radiance, per bucket the unbiased
    // estimate of its mean over the bucket, (1/n) sum_i [lambda_i in bucket] L_i / pdf_i /
    // width, for any wavelength sampler (pbrt-v4 averages L in buckets, which holds for its
    // uniform sampling only). The weights are the ones AddSample gets. The path's luminance
    // is summed too, apart for paths that kept one wavelength (a dispersive surface,
    // SampledWavelengths::TerminateSecondary): their share of the pixel's luminance is the
    // channel "wavelengths.terminated" (design §6.8).
    void AddSpectralSample(Point2i pPixel, const SampledSpectrum &L, const SampledWavelengths &lambda,
                           Float weight);
    // The final image (width x height of the pixel bounds, 3 channels; spectral films add
    // their buckets as named channels).
    Image GetImage() const;
    // Writes the image with the metadata plus the colour space's "chromaticities" and its
    // name ("colorSpace") in an EXR file.
    void WriteImage(const std::string &filename, ImageMetadata metadata = {}) const;

  private:
    size_t Offset(Point2i p) const {
        return size_t(p.y - settings.pixelBounds.pMin.y) * settings.pixelBounds.Width() +
               size_t(p.x - settings.pixelBounds.pMin.x);
    }
    struct Pixel {
        double rgb[3] = {0, 0, 0};
        double weight = 0;
    };
    FilmSettings settings;
    FilmSensor sensor;
    std::vector<Pixel> pixels;
    std::vector<double> buckets;  // spectral films: nBuckets per pixel, weighted sums
    // Spectral films: per pixel, the weighted luminance of all paths and of those that kept
    // one wavelength.
    std::vector<std::array<double, 2>> luminance;
};

}  // namespace pbrt
