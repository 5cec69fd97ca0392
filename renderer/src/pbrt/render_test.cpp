// End-to-end checks of the renderer on small scenes with known answers: a white furnace,
// the irradiance under a small area light, unbiased wavelength sampling, determinism,
// meshes from PLY files, error reporting and the Cornell box of ../shared.
// Tolerances come from the noise measured in each render (standard errors), and each test
// also bounds the error absolutely so that it can fail.
#include <pbrt/test_tempdir.h>
#include <pbrt/test_util.h>
#include <pbrt/util/hash.h>

#include <ImfChromaticitiesAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

// Configuration factor from a differential area to a parallel a x b rectangle with one
// corner above it at height c (Howell's catalogue, B-3).
double CornerRectangleFormFactor(double a, double b, double c) {
    double A = a / c, B = b / c;
    return (A / std::sqrt(1 + A * A) * std::atan(B / std::sqrt(1 + A * A)) +
            B / std::sqrt(1 + B * B) * std::atan(A / std::sqrt(1 + B * B))) /
           (2 * M_PI);
}

const char *kFurnace = R"(
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [20]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16]
Sampler "independent" "integer pixelsamples" [256]
Integrator "path" "integer maxdepth" [100]
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1] "float scale" [2]
Material "diffuse" "spectrum reflectance" [300 1 900 1]
Shape "sphere" "float radius" [1]
)";

}  // namespace

TEST(Render, WhiteFurnace) {
    // Every pixel sees the unit-albedo sphere, which reflects exactly the constant sky; the
    // sky's equal-energy spectrum is normalized to 1 nit and scaled by 2, so Y = 2.
    Image img = RenderString(kFurnace);
    XYZ e = SpectrumToXYZ(ConstantSpectrum(1));
    double k = 2 / e.Y;
    for (int c = 0; c < 3; ++c) {
        Stat st = XYZStat(img, c);
        double expect = k * e[c];
        EXPECT_LT(std::abs(st.mean - expect), 0.005 * expect) << "XYZ channel " << c << ": " << st.mean << " vs " << expect;
        EXPECT_LT(std::abs(st.mean - expect), 5 * st.stderror + 1e-4 * expect) << "channel " << c << " beyond the noise";
    }
}

TEST(Render, IrradianceUnderSmallSpectralAreaLight) {
    // A 0.2 x 0.2 light facing down at height 1 above a diffuse floor of albedo 0.5; an
    // orthographic camera sees a 0.002-wide patch straight below the light's centre.
    // Outgoing radiance = albedo / pi * E and E = pi L F (F: form factor), so
    // Y_out = albedo * F * scale for an emitter of luminance "scale".
    const double a = 0.1, h = 1, albedo = 0.5, scale = 3;
    std::string scene = R"(
LookAt 0 0 0.5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-0.001 0.001 -0.001 0.001]
Film "rgb" "integer xresolution" [4] "integer yresolution" [4]
Sampler "independent" "integer pixelsamples" [1024]
Integrator "path" "integer maxdepth" [1]
WorldBegin
AttributeBegin
  ReverseOrientation
  AreaLightSource "diffuse" "spectrum L" [400 0 450 1 600 1 650 0] "float scale" [3]
  Material "diffuse" "spectrum reflectance" [300 0 900 0]
  Shape "trianglemesh" "point3 P" [-0.1 -0.1 1  0.1 -0.1 1  0.1 0.1 1  -0.1 0.1 1]
        "integer indices" [0 1 2 0 2 3]
AttributeEnd
Material "diffuse" "spectrum reflectance" [300 0.5 900 0.5]
Shape "trianglemesh" "point3 P" [-10 -10 0  10 -10 0  10 10 0  -10 10 0] "integer indices" [0 1 2 0 2 3]
)";
    Image img = RenderString(scene);
    double F = 4 * CornerRectangleFormFactor(a, a, h);
    auto s = PiecewiseLinearSpectrum::FromInterleaved({400, 0, 450, 1, 600, 1, 650, 0}, false);
    XYZ e = SpectrumToXYZ(*s);
    for (int c = 0; c < 3; ++c) {
        double expect = albedo * F * scale * e[c] / e.Y;
        Stat st = XYZStat(img, c);
        EXPECT_LT(std::abs(st.mean - expect), 5 * st.stderror + 1e-4 * expect)
            << "channel " << c << ": " << st.mean << " vs " << expect << " (stderr " << st.stderror << ")";
        EXPECT_LT(std::abs(st.mean - expect), 0.01 * expect) << "channel " << c;
    }
    // Without ReverseOrientation the light faces up, away from the floor: black.
    std::string up = scene;
    up.replace(up.find("ReverseOrientation"), std::string("ReverseOrientation").size(), "");
    EXPECT_EQ(XYZStat(RenderString(up), 1).mean, 0) << "one-sided area light must not emit backwards";
}

namespace {
// A small box with spectral reflectances and a spectral light (for sampling comparisons).
const char *kSpectralBox = R"(
LookAt 0 1 3.5  0 1 0  0 1 0
Camera "perspective" "float fov" [45]
Film "rgb" "integer xresolution" [24] "integer yresolution" [24]
Sampler "sobol" "integer pixelsamples" [16]
Integrator "path" "integer maxdepth" [3]
PixelFilter "box"
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" [380 0.2 450 1 500 0.3 550 1.2 600 0.6 700 1 780 0.2] "float scale" [4]
  Shape "trianglemesh" "point3 P" [-0.4 1.99 -0.4  0.4 1.99 -0.4  0.4 1.99 0.4  -0.4 1.99 0.4] "integer indices" [0 1 2 0 2 3]
AttributeEnd
Material "diffuse" "spectrum reflectance" [360 0.8 500 0.2 600 0.7 830 0.3]
Shape "trianglemesh" "point3 P" [-1 0 -1  1 0 -1  1 0 1  -1 0 1] "integer indices" [0 1 2 0 2 3]
Shape "trianglemesh" "point3 P" [-1 0 -1  1 0 -1  1 2 -1  -1 2 -1] "integer indices" [0 1 2 0 2 3]
Material "diffuse" "rgb reflectance" [0.7 0.1 0.1]
Shape "trianglemesh" "point3 P" [-1 0 -1  -1 2 -1  -1 2 1  -1 0 1] "integer indices" [0 1 2 0 2 3]
Material "diffuse" "rgb reflectance" [0.1 0.6 0.1]
Shape "trianglemesh" "point3 P" [1 0 -1  1 2 -1  1 2 1  1 0 1] "integer indices" [0 1 2 0 2 3]
)";

// Image-mean XYZ over independent renders (different seeds): mean and its standard error
// from the spread between runs.
std::array<Stat, 3> MeanOverSeeds(const std::string &scene, RenderOptions opts, int runs) {
    std::array<std::vector<double>, 3> v;
    for (int r = 0; r < runs; ++r) {
        opts.seed = 1000 + r;
        Image img = RenderString(scene, opts);
        for (int c = 0; c < 3; ++c) v[c].push_back(XYZStat(img, c).mean);
    }
    std::array<Stat, 3> out;
    for (int c = 0; c < 3; ++c) {
        double s = 0, s2 = 0;
        for (double x : v[c]) { s += x; s2 += x * x; }
        out[c].mean = s / runs;
        out[c].stderror = std::sqrt(std::max(0.0, s2 / runs - out[c].mean * out[c].mean) / (runs - 1));
    }
    return out;
}
}  // namespace

TEST(Render, VisibleAndUniformWavelengthSamplingAgree) {
    RenderOptions vis, uni;
    vis.wavelengthSampling = "visible";
    uni.wavelengthSampling = "uniform";
    uni.lambdaMin = 360;
    uni.lambdaMax = 830;
    vis.spp = uni.spp = 32;
    auto a = MeanOverSeeds(kSpectralBox, vis, 8), b = MeanOverSeeds(kSpectralBox, uni, 8);
    for (int c = 0; c < 3; ++c) {
        double diff = std::abs(a[c].mean - b[c].mean);
        double sigma = std::sqrt(Sqr(a[c].stderror) + Sqr(b[c].stderror));
        EXPECT_LT(diff, 4 * sigma + 1e-6) << "XYZ channel " << c << ": visible " << a[c].mean
                                          << " uniform " << b[c].mean << " sigma " << sigma;
        EXPECT_LT(diff, 0.03 * a[c].mean) << "channel " << c << " sigma " << sigma;
        EXPECT_LT(sigma, 0.01 * a[c].mean) << "too noisy to detect a 3% bias";
        EXPECT_GT(a[c].mean, 0.01) << "the scene must be lit";
    }
}

TEST(Render, AllSamplersConvergeToTheSameImage) {
    RenderOptions opts;
    opts.spp = 32;
    // Every sampler pbrt-v4 names, some with another randomization: the directive's name
    // and parameters replace "sobol".
    auto withSampler = [](const std::string &name) {
        std::string scene = kSpectralBox;
        scene.replace(scene.find("\"sobol\""), 7, name);
        return scene;
    };
    auto ref = MeanOverSeeds(kSpectralBox, opts, 8);
    for (const char *name : {"\"independent\"", "\"stratified\"", "\"halton\"", "\"zsobol\"", "\"paddedsobol\"",
                             "\"pmj02bn\"", "\"halton\" \"string randomization\" \"owen\"",
                             "\"zsobol\" \"string randomization\" \"permutedigits\"",
                             "\"sobol\" \"string randomization\" \"none\""}) {
        auto other = MeanOverSeeds(withSampler(name), opts, 8);
        for (int c = 0; c < 3; ++c) {
            double sigma = std::sqrt(Sqr(ref[c].stderror) + Sqr(other[c].stderror));
            EXPECT_LT(std::abs(ref[c].mean - other[c].mean), 4 * sigma + 1e-6)
                << name << " channel " << c << ": " << other[c].mean << " vs sobol " << ref[c].mean;
            EXPECT_LT(sigma, 0.015 * ref[c].mean) << "too noisy to compare";
        }
    }
}

TEST(Render, DeterministicWhateverTheThreadCount) {
    RenderOptions opts;
    opts.spp = 4;
    Image one = RenderString(kSpectralBox, opts, 1), two = RenderString(kSpectralBox, opts, 2);
    EXPECT_EQ(one.pixels, two.pixels);
    opts.seed = 5;
    EXPECT_NE(RenderString(kSpectralBox, opts, 2).pixels, one.pixels) << "the seed must matter";
    // The samplers that run one sequence over the image too (their pixels' values depend on
    // where the pixel is, never on when it is rendered).
    for (const char *name : {"\"zsobol\"", "\"halton\"", "\"pmj02bn\"", "\"paddedsobol\""}) {
        std::string scene = kSpectralBox;
        scene.replace(scene.find("\"sobol\""), 7, name);
        RenderOptions o;
        o.spp = 4;
        EXPECT_EQ(RenderString(scene, o, 1).pixels, RenderString(scene, o, 2).pixels) << name;
    }
}

TEST(Render, PlyMeshRendersLikeTheInlineMesh) {
    // The box's floor written as a PLY file (ASCII) and referenced by "plymesh".
    auto dir = std::filesystem::temp_directory_path() / ("pbrt_render_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::string ply = (dir / "floor.ply").string();
    {
        std::ofstream f(ply);
        f << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "-1 0 -1\n1 0 -1\n1 0 1\n-1 0 1\n4 0 1 2 3\n";
    }
    std::string inlineScene = kSpectralBox;
    std::string floor = R"(Shape "trianglemesh" "point3 P" [-1 0 -1  1 0 -1  1 0 1  -1 0 1] "integer indices" [0 1 2 0 2 3])";
    std::string plyScene = inlineScene;
    plyScene.replace(plyScene.find(floor), floor.size(), "Shape \"plymesh\" \"string filename\" \"" + ply + "\"");
    RenderOptions opts;
    opts.spp = 4;
    Image a = RenderString(inlineScene, opts), b = RenderString(plyScene, opts);
    EXPECT_EQ(a.pixels, b.pixels) << "same geometry, same seed: the same image";
    std::filesystem::remove_all(dir);
}

TEST(Render, MalformedScenesAreErrorsWithFileAndLine) {
    auto expectError = [](const std::string &text, const std::string &where, const std::string &what) {
        try {
            RenderString(text);
            ADD_FAILURE() << "no error for:\n" << text;
        } catch (const PbrtError &e) {
            std::string msg = e.what();
            EXPECT_NE(msg.find(where), std::string::npos) << msg;
            EXPECT_NE(msg.find(what), std::string::npos) << msg;
        }
    };
    expectError("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n  \"integer indices\" [0 1 5]\n",
                "test.pbrt:2", "out of range");
    expectError("WorldBegin\n\nMaterial \"conductor\"\n", "test.pbrt:3", "conductor");
    expectError("WorldBegin\nMaterial \"diffuse\" \"float roughness\" [0.5]\n", "test.pbrt:2", "roughness");
    expectError("WorldBegin\nNamedMaterial \"nope\"\nShape \"sphere\"\n", "test.pbrt:2", "nope");
    expectError("Camera \"realistic\"\nWorldBegin\n", "test.pbrt:1", "realistic");
    expectError("WorldBegin\nAttributeBegin\nShape \"sphere\"\n", "test.pbrt:2", "AttributeBegin");
    expectError("WorldBegin\nLightSource \"goniometric\"\n", "test.pbrt:2", "goniometric");
}

TEST(Render, CornellBoxFromShared) {
    std::string path = std::string(PBRT_SHARED_DIR) + "/scenes/cornell-box/scene-v4.pbrt";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent";
    RenderOptions opts;
    opts.quiet = true;
    opts.resolution = {32, 32};
    opts.spp = 64;
    opts.maxDepth = 5;
    std::unique_ptr<Scene> scene = LoadScene({path}, opts);
    Render(*scene, 0, true);
    Image img = scene->film->GetImage();
    ASSERT_EQ(img.width, 32);
    double sum = 0, leftR = 0, leftG = 0, rightR = 0, rightG = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(img.Get(x, y, c))) << x << "," << y;
            sum += PixelXYZ(img, x, y).Y;
            // The side walls fill the outer columns of the middle rows.
            if (y < 10 || y >= 22) continue;
            if (x < 3) { leftR += img.Get(x, y, 0); leftG += img.Get(x, y, 1); }
            if (x >= 29) { rightR += img.Get(x, y, 0); rightG += img.Get(x, y, 1); }
        }
    double mean = sum / (32 * 32);
    // The light has luminance 16 (scale) and covers ~1% of the view; diffuse walls of
    // albedo ~0.7 around it put the mean luminance well inside (0.1, 4).
    EXPECT_GT(mean, 0.1);
    EXPECT_LT(mean, 4);
    // The lamp is yellowish, so compare the two sides rather than absolute ratios.
    EXPECT_GT(leftR / leftG, 2) << "the red wall is on the left";
    EXPECT_GT((rightG / rightR) / (leftG / leftR), 5) << "the green wall is on the right";
    // The ceiling light (luminance 16) is the brightest thing, near the top centre.
    double lightY = 0;
    for (int y = 1; y < 6; ++y)
        for (int x = 13; x < 19; ++x) lightY = std::max(lightY, double(PixelXYZ(img, x, y).Y));
    EXPECT_GT(lightY, 5 * mean);
}

namespace {

// The RGB primaries and white a render's EXR file records, read back with OpenEXR.
struct ReadBack {
    Imf::Header header;
    explicit ReadBack(const std::string &path) : header(Imf::InputFile(path.c_str()).header()) {}
    template <typename A>
    const A &Get(const char *name) const {
        const A *a = header.findTypedAttribute<A>(name);
        if (!a) throw std::runtime_error(std::string("no attribute ") + name + " of the expected type");
        return *a;
    }
    bool Has(const char *name) const { return header.find(name) != header.end(); }
};

// Renders scene text and writes its EXR image as pbrt does.
std::pair<std::unique_ptr<Scene>, RenderStats> RenderAndWrite(const std::string &text, RenderOptions opts,
                                                              const std::string &exr) {
    opts.quiet = true;
    std::unique_ptr<Scene> scene = LoadSceneFromString(text, opts, "test.pbrt");
    RenderStats stats = Render(*scene, 1, true);
    scene->film->WriteImage(exr, RenderMetadata(*scene, stats));
    return {std::move(scene), stats};
}

const char *kTiny = R"(
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [20]
Film "rgb" "integer xresolution" [4] "integer yresolution" [4]
Sampler "independent" "integer pixelsamples" [3] "integer seed" [17]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
)";

}  // namespace

TEST(Render, ExrRecordsColourSpaceAndProvenance) {
    TempDir dir;
    // A table (two layouts are read alike; this one is CSV) whose bytes the EXR must hash.
    std::string tableText = "# provenance test\nlambda_nm,pdf0,pdf1,pdf2,pdf3\n";
    for (int l = 380; l <= 780; l += 10) tableText += std::to_string(l) + ",1,2,1," + std::to_string(1 + l % 3) + "\n";
    std::string table = dir.Write("t.csv", tableText);

    struct Case {
        const char *colorSpace;
        Chromaticity r, g, b;
    } cases[] = {{"srgb", {0.64f, 0.33f}, {0.30f, 0.60f}, {0.15f, 0.06f}},
                 {"rec2020", {0.708f, 0.292f}, {0.170f, 0.797f}, {0.131f, 0.046f}},
                 {"dci-p3", {0.680f, 0.320f}, {0.265f, 0.690f}, {0.150f, 0.060f}},
                 {"aces2065-1", {0.7347f, 0.2653f}, {0.0f, 1.0f}, {0.0001f, -0.0770f}}};
    for (const Case &c : cases) {
        std::string text = std::string("ColorSpace \"") + c.colorSpace + "\"\n" + kTiny;
        RenderOptions opts;
        opts.wavelengthTable = table;
        opts.defensiveShare = 0.25f;
        opts.seed = 5000000000ULL;  // beyond 32 bits
        std::string exr = dir.File(std::string(c.colorSpace) + ".exr");
        auto [scene, stats] = RenderAndWrite(text, opts, exr);

        ReadBack h(exr);
        const Imf::Chromaticities &chr = h.Get<Imf::ChromaticitiesAttribute>("chromaticities").value();
        EXPECT_FLOAT_EQ(chr.red.x, c.r.x) << c.colorSpace;
        EXPECT_FLOAT_EQ(chr.red.y, c.r.y) << c.colorSpace;
        EXPECT_FLOAT_EQ(chr.green.x, c.g.x) << c.colorSpace;
        EXPECT_FLOAT_EQ(chr.green.y, c.g.y) << c.colorSpace;
        EXPECT_FLOAT_EQ(chr.blue.x, c.b.x) << c.colorSpace;
        EXPECT_FLOAT_EQ(chr.blue.y, c.b.y) << c.colorSpace;
        // D65 (0.3127, 0.3290) or the ACES white (0.32168, 0.33767), from the illuminant's spectrum.
        bool aces = std::string(c.colorSpace) == "aces2065-1";
        EXPECT_NEAR(chr.white.x, aces ? 0.32168 : 0.3127, 2e-4) << c.colorSpace;
        EXPECT_NEAR(chr.white.y, aces ? 0.33767 : 0.3290, 2e-4) << c.colorSpace;
        EXPECT_EQ(h.Get<Imf::StringAttribute>("colorSpace").value(), c.colorSpace);

        EXPECT_EQ(h.Get<Imf::IntAttribute>("samplesPerPixel").value(), 3);
        EXPECT_EQ(h.Get<Imf::StringAttribute>("seed").value(), "5000000000");
        EXPECT_FLOAT_EQ(h.Get<Imf::FloatAttribute>("renderTimeSeconds").value(), float(stats.wallSeconds));
        EXPECT_GT(h.Get<Imf::FloatAttribute>("renderTimeSeconds").value(), 0.f);
        EXPECT_EQ(h.Get<Imf::StringAttribute>("wavelengthSampler").value(), "table");
        EXPECT_EQ(h.Get<Imf::V2fAttribute>("wavelengthRange").value(), Imath::V2f(380, 780));
        EXPECT_EQ(h.Get<Imf::StringAttribute>("wavelengthTable").value(), table);
        EXPECT_EQ(h.Get<Imf::StringAttribute>("wavelengthTableSHA256").value(), SHA256Hex(tableText));
        EXPECT_FLOAT_EQ(h.Get<Imf::FloatAttribute>("wavelengthDefensiveShare").value(), 0.25f);
    }

    // Built-in sampling: its name and range, the scene's seed, and no table attributes.
    RenderOptions uniform;
    uniform.wavelengthSampling = "uniform";
    uniform.lambdaMin = 400;
    uniform.lambdaMax = 700;
    uniform.spp = 2;
    RenderAndWrite(kTiny, uniform, dir.File("uniform.exr"));
    ReadBack h(dir.File("uniform.exr"));
    EXPECT_EQ(h.Get<Imf::StringAttribute>("wavelengthSampler").value(), "uniform");
    EXPECT_EQ(h.Get<Imf::V2fAttribute>("wavelengthRange").value(), Imath::V2f(400, 700));
    EXPECT_EQ(h.Get<Imf::IntAttribute>("samplesPerPixel").value(), 2);
    EXPECT_EQ(h.Get<Imf::StringAttribute>("seed").value(), "17");
    EXPECT_EQ(h.Get<Imf::StringAttribute>("colorSpace").value(), "srgb");
    for (const char *absent : {"wavelengthTable", "wavelengthTableSHA256", "wavelengthDefensiveShare"})
        EXPECT_FALSE(h.Has(absent)) << absent;
}
