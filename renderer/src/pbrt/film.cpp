#include <pbrt/film.h>

#include <pbrt/util/paramdict.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <unistd.h>

namespace pbrt {

namespace {

// Bytes a film pixel costs while rendering and writing: the accumulator (four doubles) and
// the output image's three floats.
constexpr int kFilmBytesPerPixel = 4 * sizeof(double) + 3 * sizeof(float);

double PhysicalMemoryBytes() {
    long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && pageSize > 0 ? double(pages) * double(pageSize) : 0;
}

std::string FormatGB(double bytes) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.3g GB", bytes / 1e9);
    return buf;
}

std::string FormatCount(double v) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.4g", v);
    return buf;
}

}  // namespace

FilmSettings FilmSettings::Create(const std::string &type, const ParameterDictionary &params,
                                  const RGBColorSpace *colorSpace, const RenderOptions &opts,
                                  const FileLoc &loc) {
    if (type == "gbuffer")
        throw PbrtError(loc, "Film \"gbuffer\" is not supported (its geometry channels are not "
                             "written by this renderer); use \"rgb\" or \"spectral\"");
    if (type != "rgb" && type != "spectral")
        throw PbrtError(loc, "Film \"" + type + "\" is not supported (supported: rgb, spectral)");
    const Point2i resOverride = opts.resolution;
    const Float resScale = opts.resolutionScale;
    FilmSettings s;
    s.colorSpace = colorSpace;
    Point2i fileRes{params.GetOneInt("xresolution", 1280), params.GetOneInt("yresolution", 720)};
    if (fileRes.x <= 0 || fileRes.y <= 0) throw PbrtError(loc, "film resolution must be positive");
    s.fullResolution = fileRes;
    if (resOverride.x > 0) s.fullResolution = resOverride;
    if (opts.quick) {
        // pbrt-v4's --quick: a quarter of the resolution each way.
        s.fullResolution.x = std::max(1, s.fullResolution.x / 4);
        s.fullResolution.y = std::max(1, s.fullResolution.y / 4);
    }
    if (resScale != 1) {
        // In double: a scale of 1e9 must be refused, not wrapped around to a 1x1 image.
        double w = std::round(double(s.fullResolution.x) * resScale);
        double h = std::round(double(s.fullResolution.y) * resScale);
        if (!(w <= kMaxFilmSide && h <= kMaxFilmSide))
            throw PbrtError(loc, "the resolution " + std::to_string(s.fullResolution.x) + "x" +
                                     std::to_string(s.fullResolution.y) + " scaled by " +
                                     std::to_string(resScale) + " is " + FormatCount(w) + "x" +
                                     FormatCount(h) + " pixels, more than " +
                                     std::to_string(kMaxFilmSide) + " per side");
        if (w < 1 || h < 1)
            Warning(loc, "the resolution scale " + std::to_string(resScale) +
                             " makes the film smaller than one pixel; rendering one pixel");
        s.fullResolution.x = std::max(1, int(w));
        s.fullResolution.y = std::max(1, int(h));
    }

    s.filename = params.GetOneString("filename", "pbrt.exr");

    // Pixel bounds from "cropwindow" (fractions) or "pixelbounds" (pixels of the file's
    // resolution, rescaled with it).
    std::vector<Float> crop = params.GetFloatArray("cropwindow");
    std::vector<int> pb = params.GetIntArray("pixelbounds");
    if (!crop.empty() && !pb.empty())
        throw PbrtError(loc, "both \"cropwindow\" and \"pixelbounds\" were given");
    s.pixelBounds = Bounds2i{{0, 0}, s.fullResolution};
    // The command line's crop replaces the film's (pbrt-v4), with the same rules.
    if (opts.cropWindow) crop.assign(opts.cropWindow->begin(), opts.cropWindow->end()), pb.clear();
    if (opts.pixelBounds) pb.assign(opts.pixelBounds->begin(), opts.pixelBounds->end()), crop.clear();
    const FileLoc cropLoc = opts.cropWindow ? FileLoc{} : params.Loc("cropwindow");
    const FileLoc boundsLoc = opts.pixelBounds ? FileLoc{} : params.Loc("pixelbounds");
    if (!crop.empty()) {
        if (crop.size() != 4) throw PbrtError(cropLoc, "\"cropwindow\" needs 4 values");
        for (Float c : crop)
            if (!(c >= 0 && c <= 1))
                Warning(cropLoc, "the crop window's values lie in [0, 1] (fractions of the image; "
                                 "\"pixelbounds\" takes pixels): clamped to it");
        Float x0 = Clamp(std::min(crop[0], crop[1]), 0, 1), x1 = Clamp(std::max(crop[0], crop[1]), 0, 1);
        Float y0 = Clamp(std::min(crop[2], crop[3]), 0, 1), y1 = Clamp(std::max(crop[2], crop[3]), 0, 1);
        s.pixelBounds = Bounds2i{{int(std::ceil(s.fullResolution.x * x0)), int(std::ceil(s.fullResolution.y * y0))},
                                 {int(std::ceil(s.fullResolution.x * x1)), int(std::ceil(s.fullResolution.y * y1))}};
    } else if (!pb.empty()) {
        if (pb.size() != 4) throw PbrtError(boundsLoc, "\"pixelbounds\" needs 4 values");
        // The film's own bounds are pixels of its file's resolution, rescaled with it; the
        // command line's are pixels of the image rendered.
        double sx = opts.pixelBounds ? 1 : double(s.fullResolution.x) / fileRes.x;
        double sy = opts.pixelBounds ? 1 : double(s.fullResolution.y) / fileRes.y;
        Bounds2i b{{int(std::lround(pb[0] * sx)), int(std::lround(pb[2] * sy))},
                   {int(std::lround(pb[1] * sx)), int(std::lround(pb[3] * sy))}};
        if (b.pMin.x < 0 || b.pMin.y < 0 || b.pMax.x > s.fullResolution.x || b.pMax.y > s.fullResolution.y)
            Warning(boundsLoc, "the pixel bounds reach beyond the " + std::to_string(s.fullResolution.x) + "x" +
                                   std::to_string(s.fullResolution.y) + " image; clamped to it");
        s.pixelBounds.pMin.x = Clamp(b.pMin.x, 0, s.fullResolution.x);
        s.pixelBounds.pMax.x = Clamp(b.pMax.x, 0, s.fullResolution.x);
        s.pixelBounds.pMin.y = Clamp(b.pMin.y, 0, s.fullResolution.y);
        s.pixelBounds.pMax.y = Clamp(b.pMax.y, 0, s.fullResolution.y);
    }
    if (s.pixelBounds.Empty()) throw PbrtError(loc, "the film's crop window / pixel bounds are empty");

    if (type == "spectral") {
        s.nBuckets = params.GetOneInt("nbuckets", 16);
        s.lambdaMin = params.GetOneFloat("lambdamin", 360);
        s.lambdaMax = params.GetOneFloat("lambdamax", 830);
        if (s.nBuckets < 1 || s.nBuckets > 4096)
            throw PbrtError(params.Loc("nbuckets"), "\"nbuckets\" must lie in [1, 4096], got " +
                                                        std::to_string(s.nBuckets));
        if (!(s.lambdaMin >= 0 && s.lambdaMin < s.lambdaMax && std::isfinite(s.lambdaMax)))
            throw PbrtError(params.Find("lambdamax") ? params.Loc("lambdamax") : params.Loc("lambdamin"),
                            "the spectral film needs 0 <= \"lambdamin\" < \"lambdamax\"");
        params.GetOneBool("writefp16", true);  // output precision only: EXR is 32-bit float
    }

    // Refuse a film that cannot fit in memory before allocating it, with the size it needs.
    const double bytesPerPixel = kFilmBytesPerPixel + double(s.nBuckets) * (sizeof(double) + sizeof(float));
    double bytes = double(s.pixelBounds.Area()) * bytesPerPixel;
    double available = PhysicalMemoryBytes();
    if (available > 0 && bytes > available)
        throw PbrtError(loc, "a " + std::to_string(s.pixelBounds.Width()) + "x" +
                                 std::to_string(s.pixelBounds.Height()) + " film needs " +
                                 FormatGB(bytes) + " of memory (" +
                                 FormatCount(bytesPerPixel) +
                                 " bytes per pixel), more than this machine's " +
                                 FormatGB(available));

    // Sensor: only pbrt-v4's default "cie1931" without white balancing.
    std::string sensor = params.GetOneString("sensor", "cie1931");
    if (sensor != "cie1931")
        throw PbrtError(params.Loc("sensor"), "film sensor \"" + sensor + "\" is not supported (only cie1931)");
    if (params.GetOneFloat("whitebalance", 0) != 0)
        throw PbrtError(params.Loc("whitebalance"), "film \"whitebalance\" is not supported");
    s.iso = params.GetOneFloat("iso", 100);
    if (!(s.iso > 0)) throw PbrtError(params.Loc("iso"), "\"iso\" must be positive");
    s.maxComponentValue = params.GetOneFloat("maxcomponentvalue", std::numeric_limits<Float>::infinity());
    params.GetOneBool("savefp16", true);  // output precision only
    params.GetOneFloat("diagonal", 35);   // only used by realistic cameras
    return s;
}

RGBFilm::RGBFilm(const FilmSettings &s, Float exposureTime)
    : settings(s), sensor(s.colorSpace, exposureTime * s.iso / 100),
      pixels(size_t(s.pixelBounds.Area())), buckets(size_t(s.pixelBounds.Area()) * size_t(s.nBuckets)),
      luminance(s.nBuckets > 0 ? size_t(s.pixelBounds.Area()) : 0) {}

void RGBFilm::AddSpectralSample(Point2i pPixel, const SampledSpectrum &L, const SampledWavelengths &lambda,
                                Float weight) {
    const Float y = L.y(lambda);
    if (std::isfinite(y)) {
        std::array<double, 2> &lum = luminance[Offset(pPixel)];
        lum[0] += double(weight) * y;
        if (lambda.SecondaryTerminated()) lum[1] += double(weight) * y;
    }
    double *b = buckets.data() + Offset(pPixel) * size_t(settings.nBuckets);
    const double width = double(settings.lambdaMax - settings.lambdaMin) / settings.nBuckets;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        const double pdf = lambda.PDF()[i], l = lambda[i];
        if (!(pdf > 0) || !std::isfinite(L[i]) || l < settings.lambdaMin || l >= settings.lambdaMax) continue;
        const int k = std::min(settings.nBuckets - 1, int((l - settings.lambdaMin) / width));
        // CIE_Y_integral undoes the photometric normalization of the lights' spectra, as
        // pbrt-v4's spectral film does, so that the values are radiance in W m^-2 sr^-1 nm^-1.
        b[k] += double(weight) * L[i] / pdf / NSpectrumSamples / width * CIE_Y_integral;
    }
}

RGB RGBFilm::ToRGB(const SampledSpectrum &L, const SampledWavelengths &lambda) const {
    RGB rgb = sensor.ToOutputRGB(L, lambda);
    if (!std::isfinite(rgb.r) || !std::isfinite(rgb.g) || !std::isfinite(rgb.b)) {
        Warning("a path returned a non-finite radiance value; it was replaced by 0");
        return RGB(0, 0, 0);
    }
    Float m = std::max({rgb.r, rgb.g, rgb.b});
    if (m > settings.maxComponentValue) rgb *= settings.maxComponentValue / m;
    return rgb;
}

Image RGBFilm::GetImage() const {
    Image img;
    img.width = settings.pixelBounds.Width();
    img.height = settings.pixelBounds.Height();
    img.channels = 3;
    img.originX = settings.pixelBounds.pMin.x;
    img.originY = settings.pixelBounds.pMin.y;
    img.pixels.resize(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < pixels.size(); ++i)
        for (int c = 0; c < 3; ++c)
            img.pixels[3 * i + c] = pixels[i].weight != 0 ? float(pixels[i].rgb[c] / pixels[i].weight) : 0.f;
    if (!IsSpectral()) return img;
    // Spectral: R, G, B then one channel per bucket, named by its centre as OpenEXR's spectral
    // layout has it ("S0.<nm>nm", the decimal point written as a comma: a point separates layers).
    const int n = settings.nBuckets, c = 3 + n + 1;
    img.channels = c;
    img.channelNames = {"R", "G", "B"};
    for (int k = 0; k < n; ++k) {
        char centre[64];
        std::snprintf(centre, sizeof(centre), "%.3f",
                      double(settings.lambdaMin) + (k + 0.5) * double(settings.lambdaMax - settings.lambdaMin) / n);
        std::string nm = centre;
        std::replace(nm.begin(), nm.end(), '.', ',');
        img.channelNames.push_back("S0." + nm + "nm");
    }
    img.channelNames.push_back("wavelengths.terminated");
    std::vector<float> rgb = std::move(img.pixels);
    img.pixels.assign(pixels.size() * size_t(c), 0.f);
    for (size_t i = 0; i < pixels.size(); ++i) {
        for (int k = 0; k < 3; ++k) img.pixels[i * c + k] = rgb[3 * i + k];
        if (pixels[i].weight != 0)
            for (int k = 0; k < n; ++k)
                img.pixels[i * c + 3 + k] = float(buckets[i * size_t(n) + k] / pixels[i].weight);
        const std::array<double, 2> &lum = luminance[i];
        img.pixels[i * c + 3 + n] = lum[0] > 0 ? float(std::min(1.0, std::max(0.0, lum[1] / lum[0]))) : 0.f;
    }
    return img;
}

void RGBFilm::WriteImage(const std::string &filename, ImageMetadata metadata) const {
    if (const RGBColorSpace *cs = settings.colorSpace) {
        auto xy = [](const Chromaticity &c) { return std::array<float, 2>{float(c.x), float(c.y)}; };
        metadata.chromaticities = ImageMetadata::Chromaticities{xy(cs->r), xy(cs->g), xy(cs->b), xy(cs->w)};
        metadata.strings["colorSpace"] = cs->Name();
    }
    metadata.fullResolution = std::array<int, 2>{settings.fullResolution.x, settings.fullResolution.y};
    if (IsSpectral()) {
        // OpenEXR's spectral layout (as pbrt-v4 writes it).
        metadata.strings["spectralLayoutVersion"] = "1.0";
        metadata.strings["emissiveUnits"] = "W.m^-2.sr^-1";
    }
    pbrt::WriteImage(filename, GetImage(), metadata);
}

}  // namespace pbrt
