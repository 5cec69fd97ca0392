#include <pbrt/test_tempdir.h>
#include <pbrt/util/image.h>

#include <ImfChannelList.h>
#include <ImfChromaticitiesAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfFloatAttribute.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfMatrixAttribute.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>

#include <gtest/gtest.h>

#include <stb_image.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

using namespace pbrt;
namespace fs = std::filesystem;

namespace {

using pbrt::testing_util::TempDir;

Image RandomImage(int w, int h, int c, float lo, float hi, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(lo, hi);
    Image im{w, h, c, std::vector<float>(size_t(w) * h * c)};
    for (float &v : im.pixels) v = u(rng);
    return im;
}

std::string ErrorOf(const std::function<void()> &f) {
    try {
        f();
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

// An uncompressed true-colour TGA (image type 2) written byte by byte from the format's
// description: 18-byte header, then BGR(A) pixels, bottom row first unless topFirst.
std::string MakeTGA(int w, int h, int channels, const std::vector<uint8_t> &rgbTopFirst,
                    bool topFirst) {
    std::string out(18, '\0');
    out[2] = 2;  // uncompressed true colour
    out[12] = char(w & 255);
    out[13] = char(w >> 8);
    out[14] = char(h & 255);
    out[15] = char(h >> 8);
    out[16] = char(8 * channels);
    out[17] = char((topFirst ? 0x20 : 0) | (channels == 4 ? 8 : 0));
    for (int row = 0; row < h; ++row) {
        int y = topFirst ? row : h - 1 - row;
        for (int x = 0; x < w; ++x) {
            const uint8_t *p = &rgbTopFirst[(size_t(y) * w + x) * channels];
            out += char(p[2]);
            out += char(p[1]);
            out += char(p[0]);
            if (channels == 4) out += char(p[3]);
        }
    }
    return out;
}

}  // namespace

TEST(Image, SRGBCurve) {
    // Reference values of IEC 61966-2-1: linear 0.5 encodes to 0.735357; the segments meet
    // at linear 0.0031308 / encoded 0.04045.
    EXPECT_NEAR(LinearToSRGBCurve(0.5f), 0.735357f, 1e-5f);
    EXPECT_NEAR(SRGBCurveToLinear(0.04045f), 0.0031308f, 1e-6f);
    EXPECT_EQ(LinearToSRGBCurve(0.f), 0.f);
    EXPECT_NEAR(LinearToSRGBCurve(1.f), 1.f, 1e-6f);
    float prev = -1;
    for (int i = 0; i <= 1000; ++i) {
        float x = i / 1000.f;
        float e = LinearToSRGBCurve(x);
        EXPECT_GT(e, prev) << "not increasing at " << x;
        prev = e;
        EXPECT_NEAR(SRGBCurveToLinear(e), x, 1e-5f) << "round trip at " << x;
    }
}

TEST(Image, ExrRoundTripIsExact) {
    TempDir dir;
    for (int c = 1; c <= 4; ++c) {
        // Non-square, with negative, large and tiny values: float EXR keeps all bits.
        Image im = RandomImage(7, 5, c, -2.f, 3.f, 17 + c);
        im.pixels[0] = 1e6f;
        im.pixels[1] = 1e-20f;
        im.pixels[2] = 0.f;
        std::string path = dir.File("rt" + std::to_string(c) + ".exr");
        WriteImage(path, im);
        Image back = ReadImage(path, /*decodeSRGB=*/true);  // ignored for EXR
        EXPECT_EQ(back.width, 7);
        EXPECT_EQ(back.height, 5);
        EXPECT_EQ(back.channels, c);
        EXPECT_EQ(back.pixels, im.pixels) << c << " channels";
    }
    // No temporary files are left behind.
    for (const auto &e : fs::directory_iterator(dir.path))
        EXPECT_EQ(e.path().extension(), ".exr") << e.path();
}

TEST(Image, PngRoundTripWithinOneCode) {
    TempDir dir;
    for (int c = 1; c <= 4; ++c) {
        Image im = RandomImage(9, 4, c, 0.f, 1.f, 5 + c);
        std::string path = dir.File("rt.png");
        WriteImage(path, im);
        Image back = ReadImage(path, /*decodeSRGB=*/true);
        ASSERT_EQ(back.width, 9);
        ASSERT_EQ(back.height, 4);
        ASSERT_EQ(back.channels, c);
        for (size_t i = 0; i < im.pixels.size(); ++i) {
            bool alpha = (c == 2 || c == 4) && int(i % c) == c - 1;
            // 8-bit quantization: half a code in the encoded (sRGB or, for alpha, linear) space.
            float want = alpha ? im.pixels[i] : LinearToSRGBCurve(im.pixels[i]);
            float got = alpha ? back.pixels[i] : LinearToSRGBCurve(back.pixels[i]);
            EXPECT_LE(std::abs(got - want), 0.5f / 255 + 1e-5f)
                << "channel " << i % c << " of " << c << ": " << back.pixels[i] << " vs "
                << im.pixels[i];
        }
    }
}

TEST(Image, PngBytesAreSRGBEncodedAndClamped) {
    TempDir dir;
    // Top-left pixel distinct so a flipped or transposed image is caught.
    Image im{3, 2, 3, {0.5f, 0.f, 1.f,  2.f, -1.f, NAN,  0.f, 0.f, 0.f,
                       0.f, 0.f, 0.f,   0.f, 0.f, 0.f,   0.f, 0.f, 0.2158605f}};
    std::string path = dir.File("bytes.png");
    WriteImage(path, im);
    int w, h, n;
    unsigned char *raw = stbi_load(path.c_str(), &w, &h, &n, 0);
    ASSERT_NE(raw, nullptr);
    ASSERT_EQ(w, 3);
    ASSERT_EQ(h, 2);
    ASSERT_EQ(n, 3);
    std::vector<int> bytes(raw, raw + 18);
    stbi_image_free(raw);
    EXPECT_EQ(bytes[0], 188);  // round(255 * 0.735357)
    EXPECT_EQ(bytes[1], 0);
    EXPECT_EQ(bytes[2], 255);
    EXPECT_EQ(bytes[3], 255);  // 2 clamps to 1
    EXPECT_EQ(bytes[4], 0);    // negative clamps to 0
    EXPECT_EQ(bytes[5], 0);    // NaN written as 0
    EXPECT_EQ(bytes[17], 128); // linear 0.2158605 is sRGB 128/255

    // Without decoding, the values are code / 255.
    Image raw01 = ReadImage(path, /*decodeSRGB=*/false);
    EXPECT_FLOAT_EQ(raw01.pixels[0], 188 / 255.f);
    EXPECT_FLOAT_EQ(raw01.pixels[17], 128 / 255.f);
}

TEST(Image, TgaReadBothRowOrders) {
    TempDir dir;
    // 3x2 pixels, top row first: red, green, blue / white, black, grey.
    std::vector<uint8_t> rgb = {255, 0, 0, 0, 255, 0, 0, 0, 255,
                                255, 255, 255, 0, 0, 0, 128, 128, 128};
    for (bool topFirst : {false, true}) {
        std::string path = dir.File(topFirst ? "top.tga" : "bottom.tga");
        std::ofstream(path, std::ios::binary) << MakeTGA(3, 2, 3, rgb, topFirst);
        Image raw = ReadImage(path, /*decodeSRGB=*/false);
        ASSERT_EQ(raw.width, 3);
        ASSERT_EQ(raw.height, 2);
        ASSERT_EQ(raw.channels, 3);
        for (size_t i = 0; i < rgb.size(); ++i)
            EXPECT_FLOAT_EQ(raw.pixels[i], rgb[i] / 255.f) << path << " value " << i;
        Image lin = ReadImage(path, /*decodeSRGB=*/true);
        EXPECT_NEAR(lin.Get(2, 1, 0), SRGBCurveToLinear(128 / 255.f), 1e-6f);
        EXPECT_NEAR(lin.Get(2, 1, 0), 0.2158605f, 1e-5f);  // sRGB code 128
        EXPECT_EQ(lin.Get(0, 0, 0), 1.f);
    }
    // With alpha: alpha stays linear when colour is decoded.
    std::vector<uint8_t> rgba = {128, 128, 128, 128};
    std::string path = dir.File("alpha.tga");
    std::ofstream(path, std::ios::binary) << MakeTGA(1, 1, 4, rgba, true);
    Image lin = ReadImage(path, true);
    ASSERT_EQ(lin.channels, 4);
    EXPECT_NEAR(lin.pixels[0], 0.2158605f, 1e-5f);
    EXPECT_FLOAT_EQ(lin.pixels[3], 128 / 255.f);
}

TEST(Image, ErrorsNameTheFile) {
    TempDir dir;
    std::string missing = dir.File("missing.png");
    EXPECT_NE(ErrorOf([&] { ReadImage(missing, true); }).find(missing), std::string::npos);

    std::string garbage = dir.File("garbage.png");
    std::ofstream(garbage, std::ios::binary) << "this is not a png";
    std::string msg = ErrorOf([&] { ReadImage(garbage, true); });
    EXPECT_NE(msg.find(garbage), std::string::npos) << msg;

    std::string badExr = dir.File("garbage.exr");
    std::ofstream(badExr, std::ios::binary) << "this is not an exr either";
    msg = ErrorOf([&] { ReadImage(badExr, true); });
    EXPECT_NE(msg.find(badExr), std::string::npos) << msg;

    std::string odd = dir.File("image.xyz");
    std::ofstream(odd) << "x";
    msg = ErrorOf([&] { ReadImage(odd, true); });
    EXPECT_NE(msg.find("unsupported image format"), std::string::npos) << msg;

    // Writing: a bad image, an unknown format, a directory that does not exist. No file is
    // left behind by a failed write.
    Image good = RandomImage(2, 2, 3, 0, 1, 1);
    Image bad{2, 2, 3, std::vector<float>(5)};
    msg = ErrorOf([&] { WriteImage(dir.File("bad.exr"), bad); });
    EXPECT_NE(msg.find("bad.exr"), std::string::npos) << msg;
    msg = ErrorOf([&] { WriteImage(dir.File("out.tiff"), good); });
    EXPECT_NE(msg.find("unsupported output image format"), std::string::npos) << msg;
    for (const char *name : {"no/such/dir/out.exr", "no/such/dir/out.png"}) {
        std::string path = dir.File(name);
        msg = ErrorOf([&] { WriteImage(path, good); });
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
    }
    EXPECT_FALSE(fs::exists(dir.File("bad.exr")));
}

// The staircase's TGA textures (outside the repository) read as images of [0, 1] values.
TEST(Image, EvaluationSceneTextures) {
    fs::path textures = fs::path(PBRT_SHARED_DIR) / "scenes" / "staircase" / "textures";
    if (!fs::is_directory(textures)) GTEST_SKIP() << textures << " is not present";
    int count = 0;
    for (const auto &e : fs::directory_iterator(textures)) {
        if (e.path().extension() != ".tga") continue;
        ++count;
        Image im = ReadImage(e.path().string(), true);
        EXPECT_GT(im.width, 0) << e.path();
        EXPECT_GT(im.height, 0) << e.path();
        EXPECT_GE(im.channels, 1) << e.path();
        EXPECT_EQ(im.pixels.size(), size_t(im.width) * im.height * im.channels) << e.path();
        for (float v : im.pixels) ASSERT_TRUE(v >= 0 && v <= 1) << e.path();
    }
    EXPECT_GT(count, 0);
}

TEST(Image, ExrMetadataRoundTripsThroughOpenEXR) {
    TempDir dir;
    Image im = RandomImage(5, 3, 3, 0, 2, 7);
    ImageMetadata m;
    m.chromaticities = ImageMetadata::Chromaticities{{0.708f, 0.292f}, {0.17f, 0.797f}, {0.131f, 0.046f},
                                                     {0.3127f, 0.329f}};
    m.ints["samples"] = -12;
    m.floats["seconds"] = 1.5f;
    m.float2s["range"] = {380, 780};
    m.strings["note"] = "a b\tc";
    std::string path = dir.File("meta.exr");
    WriteImage(path, im, m);

    Imf::InputFile file(path.c_str());
    const Imf::Header &h = file.header();
    const auto *chr = h.findTypedAttribute<Imf::ChromaticitiesAttribute>("chromaticities");
    ASSERT_TRUE(chr);
    EXPECT_EQ(chr->value().red, Imath::V2f(0.708f, 0.292f));
    EXPECT_EQ(chr->value().green, Imath::V2f(0.17f, 0.797f));
    EXPECT_EQ(chr->value().blue, Imath::V2f(0.131f, 0.046f));
    EXPECT_EQ(chr->value().white, Imath::V2f(0.3127f, 0.329f));
    ASSERT_TRUE(h.findTypedAttribute<Imf::IntAttribute>("samples"));
    EXPECT_EQ(h.findTypedAttribute<Imf::IntAttribute>("samples")->value(), -12);
    ASSERT_TRUE(h.findTypedAttribute<Imf::FloatAttribute>("seconds"));
    EXPECT_EQ(h.findTypedAttribute<Imf::FloatAttribute>("seconds")->value(), 1.5f);
    ASSERT_TRUE(h.findTypedAttribute<Imf::V2fAttribute>("range"));
    EXPECT_EQ(h.findTypedAttribute<Imf::V2fAttribute>("range")->value(), Imath::V2f(380, 780));
    ASSERT_TRUE(h.findTypedAttribute<Imf::StringAttribute>("note"));
    EXPECT_EQ(h.findTypedAttribute<Imf::StringAttribute>("note")->value(), "a b\tc");
    // The pixels are unaffected.
    EXPECT_EQ(ReadImage(path, false).pixels, im.pixels);

    // Without metadata: no chromaticities (readers then assume BT.709), no extra attributes.
    WriteImage(dir.File("plain.exr"), im);
    Imf::InputFile plain(dir.File("plain.exr").c_str());
    EXPECT_EQ(plain.header().find("chromaticities"), plain.header().end());
    EXPECT_EQ(plain.header().find("samples"), plain.header().end());
}

// Matrices are stored row by row as EXR m44f (as pbrt-v4 writes worldToCamera and worldToNDC);
// a crop's image lies at its origin inside the full frame (data window vs display window);
// named channels are written under their names, and a PNG refuses them.
TEST(Image, ExrMatricesWindowsAndNamedChannels) {
    TempDir dir;
    Image im = RandomImage(4, 3, 5, 0, 1, 11);
    im.channelNames = {"R", "G", "B", "S0.400,00nm", "S0.500,00nm"};
    im.originX = 7;
    im.originY = 2;
    ImageMetadata m;
    std::array<float, 16> a;
    for (size_t i = 0; i < 16; ++i) a[i] = float(i) - 3.5f;
    m.matrices["worldToCamera"] = a;
    m.fullResolution = std::array<int, 2>{20, 10};
    const std::string path = dir.File("crop.exr");
    WriteImage(path, im, m);

    Imf::InputFile file(path.c_str());
    const Imf::Header &h = file.header();
    const auto *mat = h.findTypedAttribute<Imf::M44fAttribute>("worldToCamera");
    ASSERT_TRUE(mat);
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_EQ(mat->value()[i][j], a[size_t(4 * i + j)]);
    EXPECT_EQ(h.dataWindow().min, Imath::V2i(7, 2));
    EXPECT_EQ(h.dataWindow().max, Imath::V2i(10, 4));
    EXPECT_EQ(h.displayWindow().min, Imath::V2i(0, 0));
    EXPECT_EQ(h.displayWindow().max, Imath::V2i(19, 9));
    for (const std::string &n : im.channelNames) EXPECT_TRUE(h.channels().findChannel(n)) << n;

    // Each named channel holds its own values (read back with OpenEXR itself).
    for (int c = 0; c < im.channels; ++c) {
        std::vector<float> v(size_t(im.width) * im.height);
        Imf::FrameBuffer fb;
        fb.insert(im.channelNames[size_t(c)],
                  Imf::Slice::Make(Imf::FLOAT, v.data(), h.dataWindow(), sizeof(float), sizeof(float) * im.width));
        file.setFrameBuffer(fb);
        file.readPixels(h.dataWindow().min.y, h.dataWindow().max.y);
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x) EXPECT_EQ(v[size_t(y * im.width + x)], im.Get(x, y, c));
    }
    EXPECT_THROW(WriteImage(dir.File("crop.png"), im), PbrtError);
    EXPECT_FALSE(std::filesystem::exists(dir.File("crop.png")));
}
