#include <pbrt/film.h>

#include <pbrt/util/paramdict.h>

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
                                  const RGBColorSpace *colorSpace, Point2i resOverride,
                                  Float resScale, const FileLoc &loc) {
    if (type == "gbuffer" || type == "spectral") {
        Warning(loc, "Film \"" + type + "\" is not supported; writing an \"rgb\" film instead");
        for (const char *p : {"coordinatesystem", "nbuckets", "lambdamin", "lambdamax", "writefp16"})
            if (const ParsedParameter *pp = params.Find(p)) pp->lookedUp = true;
    } else if (type != "rgb") {
        throw PbrtError(loc, "Film \"" + type + "\" is not supported (supported: rgb)");
    }
    FilmSettings s;
    s.colorSpace = colorSpace;
    Point2i fileRes{params.GetOneInt("xresolution", 1280), params.GetOneInt("yresolution", 720)};
    if (fileRes.x <= 0 || fileRes.y <= 0) throw PbrtError(loc, "film resolution must be positive");
    s.fullResolution = fileRes;
    if (resOverride.x > 0) s.fullResolution = resOverride;
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
    if (!crop.empty()) {
        if (crop.size() != 4) throw PbrtError(params.Loc("cropwindow"), "\"cropwindow\" needs 4 values");
        Float x0 = Clamp(std::min(crop[0], crop[1]), 0, 1), x1 = Clamp(std::max(crop[0], crop[1]), 0, 1);
        Float y0 = Clamp(std::min(crop[2], crop[3]), 0, 1), y1 = Clamp(std::max(crop[2], crop[3]), 0, 1);
        s.pixelBounds = Bounds2i{{int(std::ceil(s.fullResolution.x * x0)), int(std::ceil(s.fullResolution.y * y0))},
                                 {int(std::ceil(s.fullResolution.x * x1)), int(std::ceil(s.fullResolution.y * y1))}};
    } else if (!pb.empty()) {
        if (pb.size() != 4) throw PbrtError(params.Loc("pixelbounds"), "\"pixelbounds\" needs 4 values");
        double sx = double(s.fullResolution.x) / fileRes.x, sy = double(s.fullResolution.y) / fileRes.y;
        s.pixelBounds = Bounds2i{{int(std::lround(pb[0] * sx)), int(std::lround(pb[2] * sy))},
                                 {int(std::lround(pb[1] * sx)), int(std::lround(pb[3] * sy))}};
        s.pixelBounds.pMin.x = Clamp(s.pixelBounds.pMin.x, 0, s.fullResolution.x);
        s.pixelBounds.pMax.x = Clamp(s.pixelBounds.pMax.x, 0, s.fullResolution.x);
        s.pixelBounds.pMin.y = Clamp(s.pixelBounds.pMin.y, 0, s.fullResolution.y);
        s.pixelBounds.pMax.y = Clamp(s.pixelBounds.pMax.y, 0, s.fullResolution.y);
    }
    if (s.pixelBounds.Empty()) throw PbrtError(loc, "the film's crop window / pixel bounds are empty");

    // Refuse a film that cannot fit in memory before allocating it, with the size it needs.
    double bytes = double(s.pixelBounds.Area()) * kFilmBytesPerPixel;
    double available = PhysicalMemoryBytes();
    if (available > 0 && bytes > available)
        throw PbrtError(loc, "a " + std::to_string(s.pixelBounds.Width()) + "x" +
                                 std::to_string(s.pixelBounds.Height()) + " film needs " +
                                 FormatGB(bytes) + " of memory (" +
                                 std::to_string(kFilmBytesPerPixel) +
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
      pixels(size_t(s.pixelBounds.Area())) {}

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
    return img;
}

void RGBFilm::WriteImage(const std::string &filename, ImageMetadata metadata) const {
    if (const RGBColorSpace *cs = settings.colorSpace) {
        auto xy = [](const Chromaticity &c) { return std::array<float, 2>{float(c.x), float(c.y)}; };
        metadata.chromaticities = ImageMetadata::Chromaticities{xy(cs->r), xy(cs->g), xy(cs->b), xy(cs->w)};
        metadata.strings["colorSpace"] = cs->Name();
    }
    metadata.fullResolution = std::array<int, 2>{settings.fullResolution.x, settings.fullResolution.y};
    pbrt::WriteImage(filename, GetImage(), metadata);
}

}  // namespace pbrt
