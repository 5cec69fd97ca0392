// Image input and output through libraries: stb_image / stb_image_write (Debian libstb-dev;
// the implementations live in libstb, linked through cmake/stb.cmake) and OpenEXR.
#include <pbrt/util/image.h>

#include <pbrt/util/output_path.h>

#include <stb_image.h>
#include <stb_image_write.h>

#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFloatAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfMatrixAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <unistd.h>

namespace pbrt {

// IEC 61966-2-1 (sRGB): the piecewise curve with the linear segment below 0.0031308.
Float LinearToSRGBCurve(Float v) {
    if (v <= 0.0031308f) return 12.92f * v;
    return 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

Float SRGBCurveToLinear(Float v) {
    if (v <= 0.04045f) return v / 12.92f;
    return std::pow((v + 0.055f) / 1.055f, 2.4f);
}

namespace {

std::string LowerExtension(const std::string &path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char &c : ext) c = char(std::tolower((unsigned char)c));
    return ext;
}

PbrtError FileError(const std::string &path, const std::string &why) {
    return PbrtError("\"" + path + "\": " + why);
}

// Whether channel c of an image with n channels holds colour (rather than alpha).
bool IsColorChannel(int c, int n) { return !((n == 2 || n == 4) && c == n - 1); }

Image ReadEXR(const std::string &path) {
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header &header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        const Imf::ChannelList &list = header.channels();
        auto has = [&](const char *name) { return list.findChannel(name) != nullptr; };

        // RGB(A) if the file has colour, else luminance Y(A).
        std::vector<const char *> names;
        if (has("R") && has("G") && has("B")) names = {"R", "G", "B"};
        else if (has("Y")) names = {"Y"};
        else throw FileError(path, "EXR file has neither R, G, B nor Y channels");
        if (has("A")) names.push_back("A");
        for (const char *n : names)
            if (list.findChannel(n)->xSampling != 1 || list.findChannel(n)->ySampling != 1)
                throw FileError(path, "subsampled EXR channels are not supported");

        Image image;
        image.width = dw.max.x - dw.min.x + 1;
        image.height = dw.max.y - dw.min.y + 1;
        image.originX = dw.min.x;
        image.originY = dw.min.y;
        image.channels = int(names.size());
        image.pixels.resize(size_t(image.width) * image.height * image.channels);
        const size_t xStride = sizeof(float) * image.channels;
        const size_t yStride = xStride * image.width;
        Imf::FrameBuffer fb;
        for (int c = 0; c < image.channels; ++c)
            fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, dw,
                                                 xStride, yStride));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return image;
    } catch (const PbrtError &) {
        throw;
    } catch (const std::exception &e) {
        throw FileError(path, std::string("cannot read EXR image: ") + e.what());
    }
}

Image ReadWithStb(const std::string &path, bool decodeSRGB) {
    Image image;
    int w = 0, h = 0, n = 0;
    std::unique_ptr<void, void (*)(void *)> data(nullptr, stbi_image_free);

    if (stbi_is_hdr(path.c_str())) {
        // Radiance HDR: already linear floats.
        data.reset(stbi_loadf(path.c_str(), &w, &h, &n, 0));
        if (!data) throw FileError(path, std::string("cannot read image: ") + stbi_failure_reason());
        const float *f = static_cast<const float *>(data.get());
        image.pixels.assign(f, f + size_t(w) * h * n);
    } else {
        // 8 or 16 bits per channel, scaled to [0, 1].
        bool sixteen = stbi_is_16_bit(path.c_str());
        data.reset(sixteen ? static_cast<void *>(stbi_load_16(path.c_str(), &w, &h, &n, 0))
                           : static_cast<void *>(stbi_load(path.c_str(), &w, &h, &n, 0)));
        if (!data) throw FileError(path, std::string("cannot read image: ") + stbi_failure_reason());
        size_t count = size_t(w) * h * n;
        image.pixels.resize(count);
        if (sixteen) {
            const uint16_t *s = static_cast<const uint16_t *>(data.get());
            for (size_t i = 0; i < count; ++i) image.pixels[i] = s[i] / 65535.f;
        } else {
            const uint8_t *s = static_cast<const uint8_t *>(data.get());
            for (size_t i = 0; i < count; ++i) image.pixels[i] = s[i] / 255.f;
        }
        if (decodeSRGB) {
            // An 8-bit table avoids a pow() per texel; 16-bit values use the curve.
            std::array<float, 256> table;
            for (int i = 0; i < 256; ++i) table[i] = SRGBCurveToLinear(i / 255.f);
            for (size_t i = 0; i < count; ++i) {
                if (!IsColorChannel(int(i % n), n)) continue;
                image.pixels[i] = sixteen ? SRGBCurveToLinear(image.pixels[i])
                                          : table[static_cast<const uint8_t *>(data.get())[i]];
            }
        }
    }
    image.width = w;
    image.height = h;
    image.channels = n;
    return image;
}

void CheckImage(const std::string &path, const Image &image) {
    const bool named = !image.channelNames.empty();
    if (image.width <= 0 || image.height <= 0 || image.channels < 1 ||
        (named ? image.channelNames.size() != size_t(image.channels) : image.channels > 4) ||
        image.pixels.size() != size_t(image.width) * image.height * image.channels)
        throw FileError(path, "cannot write an image of " + std::to_string(image.width) + "x" +
                                  std::to_string(image.height) + "x" +
                                  std::to_string(image.channels) + " with " +
                                  std::to_string(image.pixels.size()) + " values");
}

void WriteEXR(const std::string &path, const std::string &target, const Image &image,
              const ImageMetadata &metadata) {
    static const char *const defaultNames[4][4] = {
        {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    std::vector<std::string> names = image.channelNames;
    if (names.empty())
        for (int c = 0; c < image.channels; ++c) names.push_back(defaultNames[image.channels - 1][c]);
    try {
        // Data window: the image where it lies in the full frame; display window: the frame.
        const Imath::Box2i dataWindow(Imath::V2i(image.originX, image.originY),
                                      Imath::V2i(image.originX + image.width - 1, image.originY + image.height - 1));
        Imath::Box2i displayWindow = dataWindow;
        if (metadata.fullResolution)
            displayWindow = Imath::Box2i(Imath::V2i(0, 0), Imath::V2i((*metadata.fullResolution)[0] - 1,
                                                                      (*metadata.fullResolution)[1] - 1));
        Imf::Header header(displayWindow, dataWindow);
        header.compression() = Imf::ZIP_COMPRESSION;
        if (const auto &c = metadata.chromaticities) {
            auto v = [](const std::array<float, 2> &xy) { return Imath::V2f(xy[0], xy[1]); };
            Imf::addChromaticities(header, Imf::Chromaticities(v(c->red), v(c->green), v(c->blue), v(c->white)));
        }
        for (const auto &[name, value] : metadata.ints) header.insert(name, Imf::IntAttribute(value));
        for (const auto &[name, value] : metadata.floats) header.insert(name, Imf::FloatAttribute(value));
        for (const auto &[name, value] : metadata.float2s)
            header.insert(name, Imf::V2fAttribute(Imath::V2f(value[0], value[1])));
        for (const auto &[name, value] : metadata.strings) header.insert(name, Imf::StringAttribute(value));
        for (const auto &[name, v] : metadata.matrices)
            header.insert(name, Imf::M44fAttribute(Imath::M44f(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8],
                                                               v[9], v[10], v[11], v[12], v[13], v[14], v[15])));
        for (int c = 0; c < image.channels; ++c)
            header.channels().insert(names[size_t(c)], Imf::Channel(Imf::FLOAT));
        const size_t xStride = sizeof(float) * image.channels;
        const size_t yStride = xStride * image.width;
        Imf::FrameBuffer fb;
        for (int c = 0; c < image.channels; ++c)
            fb.insert(names[size_t(c)],
                      Imf::Slice::Make(Imf::FLOAT, const_cast<float *>(image.pixels.data() + c), dataWindow,
                                       xStride, yStride));
        // Extra channels share the data window; a name the image already uses would make
        // OpenEXR silently keep one of the two, so it is an error.
        for (const auto &[name, values] : metadata.channels) {
            if (values.size() != size_t(image.width) * size_t(image.height))
                throw FileError(target, "channel \"" + name + "\" has " + std::to_string(values.size()) +
                                            " values for " + std::to_string(image.width) + "x" +
                                            std::to_string(image.height) + " pixels");
            if (std::find(names.begin(), names.end(), name) != names.end())
                throw FileError(target, "channel \"" + name + "\" is one of the image's own channels");
            header.channels().insert(name, Imf::Channel(Imf::FLOAT));
            fb.insert(name, Imf::Slice::Make(Imf::FLOAT, const_cast<float *>(values.data()), dataWindow,
                                             sizeof(float), sizeof(float) * size_t(image.width)));
        }
        Imf::OutputFile file(path.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(image.height);
    } catch (const PbrtError &) {
        throw;
    } catch (const std::exception &e) {
        throw FileError(target, std::string("cannot write EXR image: ") + e.what());
    }
}

void WritePNG(const std::string &path, const std::string &target, const Image &image) {
    std::vector<uint8_t> bytes(image.pixels.size());
    for (size_t i = 0; i < bytes.size(); ++i) {
        float v = image.pixels[i];
        if (!(v > 0)) v = 0;  // also NaN
        v = std::min(v, 1.f);
        if (IsColorChannel(int(i % image.channels), image.channels)) v = LinearToSRGBCurve(v);
        bytes[i] = uint8_t(std::lround(v * 255.f));
    }
    if (!stbi_write_png(path.c_str(), image.width, image.height, image.channels, bytes.data(),
                        image.width * image.channels))
        throw FileError(target, "cannot write PNG image");
}

}  // namespace

Image ReadImage(const std::string &path, bool decodeSRGB) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw FileError(path, "no such image file");
    std::string ext = LowerExtension(path);
    if (ext == ".exr") return ReadEXR(path);
    if (ext == ".png" || ext == ".tga" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" ||
        ext == ".hdr" || ext == ".ppm" || ext == ".pgm")
        return ReadWithStb(path, decodeSRGB);
    throw FileError(path, "unsupported image format \"" + ext + "\" (supported: exr, png, tga, "
                          "jpg, bmp, hdr, ppm, pgm)");
}

void WriteImage(const std::string &path, const Image &image, const ImageMetadata &metadata) {
    CheckImage(path, image);
    std::string ext = LowerExtension(path);
    if (ext != ".exr" && ext != ".png")
        throw FileError(path, "unsupported output image format \"" + ext + "\" (use .exr or .png)");
    if (ext == ".png" && !image.channelNames.empty())
        throw FileError(path, "an image with channels " + image.channelNames.front() + ", ... can only be "
                              "written as EXR");

    // Write beside the target, then rename: a failed write, or a SIGTERM while writing,
    // leaves no partial file (util/output_path.h).
    TemporaryOutput tmp(path);
    if (ext == ".exr") WriteEXR(tmp.Path(), path, image, metadata);
    else WritePNG(tmp.Path(), path, image);
    if (!tmp.Commit()) throw FileError(path, "cannot write image file");
}

}  // namespace pbrt
