// Image-map textures on images the tests write themselves: sRGB decoding of 8-bit files,
// the three wrap modes, bilinear filtering and its orientation, "scale" and "invert", and a
// clear error for a missing file (directly and from a scene file); plus the bump mapping
// of a "displacement" texture against the analytic normal of a tilted plane.
#include <pbrt/bumpmap.h>
#include <pbrt/test_util.h>
#include <pbrt/textures.h>
#include <pbrt/util/image.h>
#include <pbrt/util/paramdict.h>
#include <pbrt/util/rng.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>

#include <unistd.h>

using namespace pbrt;

namespace {

namespace fs = std::filesystem;

struct TexDir {
    fs::path dir = fs::temp_directory_path() / ("pbrt_textures_test_" + std::to_string(::getpid()));
    TexDir() { fs::create_directories(dir); }
    ~TexDir() { fs::remove_all(dir); }
    std::string File(const std::string &name) const { return (dir / name).string(); }
};

// A one-channel-per-pixel grey image (values given row by row from the top) as 3 channels.
Image GreyImage(int w, int h, const std::vector<float> &v) {
    Image img;
    img.width = w;
    img.height = h;
    img.channels = 3;
    for (float x : v)
        for (int c = 0; c < 3; ++c) img.pixels.push_back(x);
    return img;
}

std::string ErrorOf(const std::function<void()> &f) {
    try {
        f();
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(Textures, EightBitImagesAreDecodedFromSRGB) {
    TexDir d;
    std::string png = d.File("ramp.png");
    // WriteImage stores sRGB-encoded 8-bit codes; "sRGB" decoding must give back the linear
    // values to within one code step, "linear" must give the encoded code / 255.
    std::vector<float> linear = {0.0f, 0.05f, 0.2f, 0.5f, 0.8f, 1.0f};
    WriteImage(png, GreyImage(6, 1, linear));
    auto srgb = LoadTextureImage(png, "sRGB", TextureImage::Wrap::Clamp);
    auto raw = LoadTextureImage(png, "linear", TextureImage::Wrap::Clamp);
    ASSERT_EQ(srgb->width, 6);
    ASSERT_EQ(srgb->channels, 3);
    for (int x = 0; x < 6; ++x) {
        Float code = std::round(LinearToSRGBCurve(linear[x]) * 255) / 255;
        EXPECT_NEAR(raw->Texel(x, 0, 0), code, 1e-6) << "x " << x << ": linear encoding keeps the code";
        EXPECT_NEAR(srgb->Texel(x, 0, 1), SRGBCurveToLinear(code), 1e-5) << "x " << x;
        // One code step of the sRGB curve is at most ~0.009 in linear units near 1.
        EXPECT_NEAR(srgb->Texel(x, 0, 2), linear[x], 0.01) << "x " << x;
    }
    // The sRGB curve lies below the identity: mid-grey codes decode darker.
    EXPECT_LT(srgb->Texel(3, 0, 0), raw->Texel(3, 0, 0) - 0.2);
    // "gamma 2.2": code^2.2.
    auto g = LoadTextureImage(png, "gamma 2.2", TextureImage::Wrap::Clamp);
    EXPECT_NEAR(g->Texel(3, 0, 0), std::pow(raw->Texel(3, 0, 0), 2.2f), 1e-5);
    EXPECT_NE(ErrorOf([&] { LoadTextureImage(png, "gamma -1", TextureImage::Wrap::Clamp); }).find(png),
              std::string::npos);
}

TEST(Textures, BilerpIsTheFormulaOverWrappedTexels) {
    // Bilerp wraps each of its four texels once; the value must be the textbook formula over
    // Texel(), in every wrap mode, inside and far outside the image.
    TexDir d;
    std::string exr = d.File("bilerp.exr");
    WriteImage(exr, GreyImage(5, 3, {0.1f, 0.7f, 0.3f, 0.9f, 0.2f, 0.5f, 0.4f, 1.0f, 0.0f, 0.6f, 0.8f, 0.25f, 0.35f, 0.45f, 0.55f}));
    RNG rng(7);
    for (auto wrap : {TextureImage::Wrap::Repeat, TextureImage::Wrap::Clamp, TextureImage::Wrap::Black}) {
        auto img = LoadTextureImage(exr, "linear", wrap);
        for (int i = 0; i < 2000; ++i) {
            Point2f st(-2 + 5 * rng.UniformFloat(), -2 + 5 * rng.UniformFloat());
            float v[3];
            img->Bilerp(st, v);
            Float x = st.x * img->width - 0.5f, y = (1 - st.y) * img->height - 0.5f;
            int xi = int(std::floor(x)), yi = int(std::floor(y));
            Float dx = x - xi, dy = y - yi;
            Float want = (1 - dx) * (1 - dy) * img->Texel(xi, yi, 0) + dx * (1 - dy) * img->Texel(xi + 1, yi, 0) +
                         (1 - dx) * dy * img->Texel(xi, yi + 1, 0) + dx * dy * img->Texel(xi + 1, yi + 1, 0);
            // Equal up to the compiler's choice of fused multiply-adds, which may differ from
            // channel to channel (the grey image's three are the same texels).
            ASSERT_NEAR(v[0], want, 1e-6f) << "wrap " << int(wrap) << " st " << st.x << "," << st.y;
            ASSERT_FLOAT_EQ(v[1], v[0]);
            ASSERT_FLOAT_EQ(v[2], v[0]);
        }
    }
}

TEST(Textures, WrapModes) {
    TexDir d;
    std::string exr = d.File("wrap.exr");
    // 3 x 2 linear image: rows from the top.
    WriteImage(exr, GreyImage(3, 2, {1, 2, 3, 4, 5, 6}));
    auto repeat = LoadTextureImage(exr, "linear", TextureImage::Wrap::Repeat);
    auto clamp = LoadTextureImage(exr, "linear", TextureImage::Wrap::Clamp);
    auto black = LoadTextureImage(exr, "linear", TextureImage::Wrap::Black);
    for (int y = -3; y < 5; ++y)
        for (int x = -4; x < 7; ++x) {
            int rx = ((x % 3) + 3) % 3, ry = ((y % 2) + 2) % 2;
            EXPECT_EQ(repeat->Texel(x, y, 0), Float(1 + rx + 3 * ry)) << x << "," << y;
            int cx = std::clamp(x, 0, 2), cy = std::clamp(y, 0, 1);
            EXPECT_EQ(clamp->Texel(x, y, 0), Float(1 + cx + 3 * cy)) << x << "," << y;
            bool inside = x >= 0 && x < 3 && y >= 0 && y < 2;
            EXPECT_EQ(black->Texel(x, y, 0), inside ? Float(1 + x + 3 * y) : 0) << x << "," << y;
        }
    // Lookups: repeat is periodic in st, clamp is constant beyond the edge, black fades to 0.
    float a[3], b[3];
    for (Point2f st : {Point2f(0.3f, 0.6f), Point2f(0.05f, 0.9f), Point2f(0.77f, 0.12f)}) {
        repeat->Bilerp(st, a);
        repeat->Bilerp(Point2f(st.x + 2, st.y - 3), b);
        EXPECT_NEAR(a[0], b[0], 1e-4) << "repeat is periodic";
    }
    clamp->Bilerp(Point2f(5, 0.75f), a);   // far right, on the top row's centre (t = 0.75)
    EXPECT_NEAR(a[0], 3, 1e-5);
    black->Bilerp(Point2f(5, 0.75f), a);
    EXPECT_EQ(a[0], 0);
}

TEST(Textures, BilinearFilteringAndOrientation) {
    TexDir d;
    std::string exr = d.File("bilerp.exr");
    WriteImage(exr, GreyImage(2, 2, {0, 1, 2, 4}));  // top row 0 1, bottom row 2 4
    auto img = LoadTextureImage(exr, "linear", TextureImage::Wrap::Clamp);
    float v[3];
    // Texel centres sit at s, t in {0.25, 0.75}; t = 0 is the bottom row.
    img->Bilerp(Point2f(0.25f, 0.75f), v);
    EXPECT_NEAR(v[0], 0, 1e-6) << "top-left texel";
    img->Bilerp(Point2f(0.75f, 0.25f), v);
    EXPECT_NEAR(v[0], 4, 1e-6) << "bottom-right texel";
    // The centre is the mean of the four; a point a quarter of the way is the bilinear blend.
    img->Bilerp(Point2f(0.5f, 0.5f), v);
    EXPECT_NEAR(v[0], (0 + 1 + 2 + 4) / 4.0, 1e-5);
    img->Bilerp(Point2f(0.375f, 0.625f), v);  // 1/4 from the top-left centre in both axes
    double w = 0.25;
    EXPECT_NEAR(v[0], (1 - w) * (1 - w) * 0 + w * (1 - w) * 1 + (1 - w) * w * 2 + w * w * 4, 1e-5);
    // Linear along a row between the two centres.
    for (float s : {0.3f, 0.45f, 0.6f, 0.7f}) {
        img->Bilerp(Point2f(s, 0.25f), v);
        EXPECT_NEAR(v[0], 2 + (s - 0.25f) / 0.5f * 2, 1e-5) << "s " << s;
    }

    // Float and spectrum textures: the uv mapping, "scale" and "invert".
    UVMapping map{2, 1, 0, 0};  // s = 2u
    TextureEvalContext ctx{Point3f(0, 0, 0), Point2f(0.125f, 0.75f)};  // st (0.25, 0.75): 0
    TextureEvalContext ctx2{Point3f(0, 0, 0), Point2f(0.375f, 0.25f)};  // st (0.75, 0.25): 4
    EXPECT_NEAR(MakeImageFloatTexture(map, img, 1, false)->Evaluate(ctx2), 4, 1e-5);
    EXPECT_NEAR(MakeImageFloatTexture(map, img, 0.125f, false)->Evaluate(ctx2), 0.5, 1e-5);
    EXPECT_NEAR(MakeImageFloatTexture(map, img, 0.125f, true)->Evaluate(ctx2), 0.5, 1e-5);
    EXPECT_NEAR(MakeImageFloatTexture(map, img, 1, true)->Evaluate(ctx), 1, 1e-5) << "1 - 0";
    EXPECT_NEAR(MakeImageFloatTexture(map, img, 1, true)->Evaluate(ctx2), 0, 1e-5) << "clamped at 0";
    SampledWavelengths lambda = SampledWavelengths::SampleUniform(0.3f);
    SampledSpectrum s = MakeImageSpectrumTexture(map, img, 0.1f, false, SpectrumType::Unbounded,
                                                 RGBColorSpace::sRGB)->Evaluate(ctx2, lambda);
    for (int i = 0; i < NSpectrumSamples; ++i)
        EXPECT_NEAR(s[i], 0.4, 0.01) << "a grey RGB is a flat spectrum, lambda " << lambda[i];
    s = MakeImageSpectrumTexture(map, img, 1, false, SpectrumType::Albedo, RGBColorSpace::sRGB)
            ->Evaluate(ctx2, lambda);
    for (int i = 0; i < NSpectrumSamples; ++i) EXPECT_LE(s[i], 1) << "albedo textures stay <= 1";
}

TEST(Textures, MissingImageIsAnErrorNamingIt) {
    TexDir d;
    std::string missing = d.File("no-such-texture.tga");
    std::string msg = ErrorOf([&] { LoadTextureImage(missing, "sRGB", TextureImage::Wrap::Repeat); });
    EXPECT_NE(msg.find(missing), std::string::npos) << msg;

    // From a scene file: the error names the scene file, the line and the image.
    std::string scene = "WorldBegin\n"
                        "Texture \"t\" \"spectrum\" \"imagemap\"\n"
                        "    \"string filename\" \"" + missing + "\"\n";
    msg = ErrorOf([&] { LoadSceneFromString(scene, RenderOptions{}, "tex.pbrt"); });
    EXPECT_NE(msg.find("tex.pbrt:3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("no-such-texture.tga"), std::string::npos) << msg;
}

// A constant-slope displacement d = k u on a flat patch with dp/du = x, dp/dv = y tilts the
// normal to (-k, 0, 1) / |.| exactly (forward differences of a linear function are exact).
TEST(Textures, BumpMapOfALinearRampTiltsTheNormal) {
    TexDir d;
    std::string exr = d.File("ramp.exr");
    // 64 texels: a linear ramp in s, sampled at the texel centres; with clamp wrap the
    // bilinear lookup is exactly linear between the first and the last centre.
    std::vector<float> v;
    for (int x = 0; x < 64; ++x) v.push_back((x + 0.5f) / 64);
    WriteImage(exr, GreyImage(64, 1, v));
    auto img = LoadTextureImage(exr, "linear", TextureImage::Wrap::Clamp);
    for (Float k : {0.0f, 0.1f, 0.5f, 2.0f}) {
        FloatTextureHandle disp = MakeImageFloatTexture(UVMapping{}, img, k, false);
        SurfaceInteraction si;
        si.p = Point3f(0.4f, 0.5f, 0);
        si.uv = Point2f(0.4f, 0.5f);
        si.n = si.ns = Normal3f(0, 0, 1);
        si.dpdu = Vector3f(1, 0, 0);
        si.dpdv = Vector3f(0, 1, 0);
        BumpedFrame b = BumpMap(*disp, si);
        Vector3f expect = Normalize(Vector3f(-k, 0, 1));
        EXPECT_NEAR(b.ns.x, expect.x, 2e-3) << "k " << k;
        EXPECT_NEAR(b.ns.y, expect.y, 2e-3) << "k " << k;
        EXPECT_NEAR(b.ns.z, expect.z, 2e-3) << "k " << k;
        // The bumped normal stays on the geometric normal's side even when it is flipped.
        si.n = si.ns = Normal3f(0, 0, -1);
        b = BumpMap(*disp, si);
        EXPECT_LT(b.ns.z, 0) << "k " << k;
    }
}

namespace {
ParsedParameter FloatParam(const std::string &name, double v) {
    ParsedParameter p;
    p.type = "float";
    p.name = name;
    p.floats = {v};
    return p;
}
}  // namespace

TEST(Textures, CreateTextureResolvesParametersAndBothSpectrumFlavours) {
    const FileLoc loc{"scene.pbrt", 12, 1};
    // A resolver that knows three float constants and records the flavour of each spectrum lookup.
    std::vector<SpectrumType> flavours;
    TextureResolver res;
    res.floats = [](const std::string &name, std::optional<Float> def) -> FloatTextureHandle {
        if (name == "tex") return MakeConstantFloatTexture(2);
        if (name == "scale") return MakeConstantFloatTexture(3);
        return def ? MakeConstantFloatTexture(*def) : nullptr;
    };
    res.spectrum = [&](const std::string &, SpectrumHandle def, SpectrumType t) -> SpectrumTextureHandle {
        flavours.push_back(t);
        return MakeConstantSpectrumTexture(def);
    };
    TextureImageCache images;
    TextureEvalContext ctx{{0, 0, 0}, {0.25f, 0.25f}};

    TextureDefinition scale = CreateTexture("s", "float", "scale", ParameterDictionary(), res,
                                            *RGBColorSpace::sRGB, &images, loc);
    ASSERT_TRUE(scale.floatTexture);
    EXPECT_FLOAT_EQ(scale.floatTexture->Evaluate(ctx), 6.f);
    EXPECT_FALSE(scale.albedo || scale.unbounded);

    ParameterDictionary constant({FloatParam("value", 0.75)});
    EXPECT_FLOAT_EQ(CreateTexture("c", "float", "constant", constant, res, *RGBColorSpace::sRGB, &images, loc)
                        .floatTexture->Evaluate(ctx), 0.75f);
    EXPECT_TRUE(constant.Unused().empty()) << "\"value\" is looked up";

    // A spectrum texture is made as reflectance and as unbounded; its parameters are
    // resolved in the flavour being made.
    TextureDefinition mix = CreateTexture("m", "spectrum", "mix", ParameterDictionary(), res,
                                          *RGBColorSpace::sRGB, &images, loc);
    ASSERT_TRUE(mix.albedo && mix.unbounded);
    EXPECT_FALSE(mix.floatTexture);
    EXPECT_EQ(flavours, (std::vector<SpectrumType>{SpectrumType::Albedo, SpectrumType::Albedo,
                                                   SpectrumType::Unbounded, SpectrumType::Unbounded}));
    SampledWavelengths lambda = SampledWavelengths::SampleUniform(0.5f, 360, 830);
    // mix of tex1 = 0 and tex2 = 1 with amount 0.5.
    EXPECT_FLOAT_EQ(mix.albedo->Evaluate(ctx, lambda)[0], 0.5f);

    try {
        CreateTexture("f", "float", "fbm", ParameterDictionary(), res, *RGBColorSpace::sRGB, &images, loc);
        FAIL() << "an unsupported texture class was accepted";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("scene.pbrt:12"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("fbm"), std::string::npos) << e.what();
    }
}
