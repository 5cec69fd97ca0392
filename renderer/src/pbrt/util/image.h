// Reading and writing images: textures (PNG, TGA, ... through stb_image; EXR through
// OpenEXR) and the rendered film (EXR as 32-bit float, or PNG).
#pragma once

#include <pbrt/pbrt.h>

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace pbrt {

// Pixels stored row by row, top row first, channels interleaved; linear values.
// Channels: 1 (Y), 2 (Y, A), 3 (R, G, B) or 4 (R, G, B, A), or any number with their names
// in channelNames (EXR only: pbrt-v4's "gbuffer" and "spectral" films).
struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels;
    std::vector<std::string> channelNames;  // empty: named by the channel count, as above
    // Where pixel (0, 0) lies in the full frame: the EXR data window's corner (a crop window's
    // image starts at its pixel bounds' corner, as pbrt-v4 writes it).
    int originX = 0, originY = 0;

    size_t Index(int x, int y, int c) const {
        return (size_t(y) * size_t(width) + size_t(x)) * size_t(channels) + size_t(c);
    }
    float Get(int x, int y, int c) const { return pixels[Index(x, y, c)]; }
};

// Reads an image; the format comes from the file name's extension (case-insensitive):
//   .exr                         OpenEXR: R, G, B (and A) or Y (and A), as linear float
//   .png .tga .jpg .jpeg .bmp    stb_image, 8 or 16 bits per channel, scaled to [0, 1];
//   .ppm .pgm                    with decodeSRGB the colour channels (not alpha) are
//                                decoded from the sRGB curve to linear values
//   .hdr                         stb_image, Radiance RGBE, linear float
// Throws PbrtError naming the file if it is missing, unreadable or of another format.
Image ReadImage(const std::string &path, bool decodeSRGB);

// What an EXR file records besides the pixels, as header attributes (PNG files get none).
struct ImageMetadata {
    // CIE 1931 xy of the red, green and blue primaries and of the white of the RGB values:
    // the standard attribute "chromaticities" (readers assume ITU-R BT.709 without it).
    struct Chromaticities {
        std::array<float, 2> red, green, blue, white;
    };
    std::optional<Chromaticities> chromaticities;
    // Further attributes by name and type (EXR int, float, v2f and string).
    std::map<std::string, int> ints;
    std::map<std::string, float> floats;
    std::map<std::string, std::array<float, 2>> float2s;
    std::map<std::string, std::string> strings;
    // EXR only: further 32-bit float channels by name (such as "wavelengthTable.index"), each
    // width x height values, row by row, top row first.
    std::map<std::string, std::vector<float>> channels;
    // 4 x 4 matrices (EXR m44f), m[4 i + j] row i, column j, as pbrt-v4 stores its
    // transformations ("worldToCamera", "worldToNDC").
    std::map<std::string, std::array<float, 16>> matrices;
    // The full frame's width and height: the EXR display window (default: the image itself).
    std::optional<std::array<int, 2>> fullResolution;
};

// Writes an image; the format comes from the extension:
//   .exr  32-bit float channels R, G, B (A) or Y (A) (or the image's channelNames), ZIP
//         compression, the metadata's attributes, the data window at the image's origin
//   .png  8 bits per channel: colour sRGB-encoded, alpha linear, both clamped to [0, 1]
// The file is written under a temporary name and renamed when complete, so a failed write
// leaves no partial image. Throws PbrtError naming the file on failure.
void WriteImage(const std::string &path, const Image &image, const ImageMetadata &metadata = {});

// The sRGB transfer curve (IEC 61966-2-1), on values in [0, 1].
Float LinearToSRGBCurve(Float linear);
Float SRGBCurveToLinear(Float encoded);

}  // namespace pbrt
