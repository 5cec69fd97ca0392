// The materials end to end: every material type (and bump mapping) renders a small scene
// with finite, non-zero values; a smooth dielectric sphere in a white furnace is invisible
// (lossless), with a constant, a constant-given-as-spectrum and a dispersive eta (the last
// two go through SampledWavelengths::TerminateSecondary, so this checks that keeping one
// wavelength leaves the image unbiased); a constant spectral eta renders like the same
// float eta in a coloured scene; a "diffusetransmission" sheet has its parameters as pbrt-v4
// defines them, a lossless one vanishes in a white furnace and a filter sheet has the colour
// of its spectra (warning when it would give out more light than it receives); bad
// parameters are errors; and the six evaluation scenes of ../shared build and render a few
// pixels.
#include <pbrt/materials.h>
#include <pbrt/scene.h>
#include <pbrt/test_util.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

std::string ErrorOf(const std::string &scene) {
    try {
        LoadSceneFromString(scene, RenderOptions{}, "mat.pbrt");
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

// A sphere of the given material under a constant sky and a small spherical area light.
std::string SphereScene(const std::string &material, int spp = 16) {
    return R"(
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [30]
Film "rgb" "integer xresolution" [12] "integer yresolution" [12]
Sampler "independent" "integer pixelsamples" [)" + std::to_string(spp) + R"(]
Integrator "path" "integer maxdepth" [8]
WorldBegin
LightSource "infinite" "spectrum L" [300 0.3 900 0.3]
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" [400 0 450 5 600 5 650 0]
  Translate 2 2 -2
  Shape "sphere" "float radius" [0.3]
AttributeEnd
Texture "bumps" "float" "checkerboard" "float uscale" [8] "float vscale" [8]
    "float tex1" [0] "float tex2" [0.02]
Texture "checks" "spectrum" "checkerboard" "float uscale" [4] "float vscale" [4]
    "rgb tex1" [0.8 0.2 0.1] "rgb tex2" [0.1 0.3 0.9]
)" + material + R"(
Shape "sphere" "float radius" [1]
)";
}

// Mean and standard error of the per-pixel difference of two images' XYZ channel c: with
// independent noise and equal expectations the mean is 0 within a few standard errors.
Stat DiffStat(const Image &a, const Image &b, int c) {
    double s = 0, s2 = 0;
    int n = a.width * a.height;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            double d = PixelXYZ(a, x, y)[c] - PixelXYZ(b, x, y)[c];
            s += d;
            s2 += d * d;
        }
    Stat st;
    st.mean = s / n;
    st.stderror = std::sqrt(std::max(0.0, s2 / n - st.mean * st.mean) / (n - 1));
    return st;
}

}  // namespace

TEST(Materials, EveryTypeRendersFiniteNonZeroImages) {
    const char *materials[] = {
        R"(Material "diffuse" "texture reflectance" "checks")",
        R"(Material "diffuse" "rgb reflectance" [0.5 0.5 0.5] "texture displacement" "bumps")",
        R"(Material "conductor" "rgb eta" [0.2 0.92 1.1] "rgb k" [3.9 2.45 2.14] "float roughness" [0])",
        R"(Material "conductor" "rgb eta" [0.2 0.92 1.1] "rgb k" [3.9 2.45 2.14]
              "float uroughness" [0.05] "float vroughness" [0.4] "bool remaproughness" false)",
        R"(Material "conductor" "rgb eta" [1.66 0.88 0.52] "rgb k" [9.2 6.3 4.8] "float roughness" [1]
              "texture displacement" "bumps")",
        R"(Material "conductor" "texture reflectance" "checks" "float roughness" [0.3])",
        R"(Material "dielectric" "float eta" [1.5])",
        R"(Material "dielectric" "float eta" [1.33] "float roughness" [0.3])",
        R"(Material "dielectric" "spectrum eta" [300 1.7 900 1.45] "float roughness" [0.05])",
        R"(Material "dielectric" "float eta" [0])",
        R"(Material "diffusetransmission")",
        R"(Material "diffusetransmission" "texture reflectance" "checks"
              "spectrum transmittance" [400 0.05 500 0.7 560 0.6 620 0.02] "float scale" [1.2]
              "texture displacement" "bumps")",
        R"(Material "coateddiffuse" "texture reflectance" "checks")",
        R"(Material "coateddiffuse" "rgb reflectance" [0.9 0.9 0.9] "float uroughness" [0.001]
              "float vroughness" [0.001] "bool remaproughness" false)",
        R"(Material "coateddiffuse" "float roughness" [1] "rgb albedo" [0.8 0.5 0.2] "float g" [0.6]
              "float thickness" [0.1] "integer maxdepth" [4] "integer nsamples" [2]
              "spectrum eta" [300 1.6 900 1.4] "texture displacement" "bumps")",
    };
    for (const char *m : materials) {
        Image img = RenderString(SphereScene(m));
        double sumY = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x)
                for (int c = 0; c < 3; ++c) {
                    ASSERT_TRUE(std::isfinite(img.Get(x, y, c))) << m << ": pixel " << x << "," << y;
                    // Luminance cannot be negative (RGB can: saturated spectra are outside sRGB).
                    ASSERT_GE(PixelXYZ(img, x, y).Y, -1e-4) << m << ": pixel " << x << "," << y;
                }
        for (int y = 3; y < 9; ++y)
            for (int x = 3; x < 9; ++x) sumY += PixelXYZ(img, x, y).Y;
        // The sky alone gives luminance 0.3 around the sphere; the sphere reflects some.
        EXPECT_GT(sumY / 36, 0.01) << m;
        EXPECT_LT(sumY / 36, 10) << m;
    }
}

TEST(Materials, SmoothDielectricSphereVanishesInAWhiteFurnace) {
    // A lossless sphere in a uniform sky: every pixel shows the sky's radiance, Y = 2.
    for (const char *eta : {R"("float eta" [1.5])", R"("spectrum eta" [300 1.5 900 1.5])",
                            R"("spectrum eta" [300 1.75 600 1.5 900 1.35])"}) {
        std::string scene = R"(
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [20]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16]
Sampler "independent" "integer pixelsamples" [256]
Integrator "path" "integer maxdepth" [100]
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1] "float scale" [2]
Material "dielectric" )" + std::string(eta) + R"(
Shape "sphere" "float radius" [1]
)";
        Image img = RenderString(scene);
        XYZ e = SpectrumToXYZ(ConstantSpectrum(1));
        for (int c = 0; c < 3; ++c) {
            Stat st = XYZStat(img, c);
            double expect = 2 / e.Y * e[c];
            EXPECT_LT(std::abs(st.mean - expect), 5 * st.stderror + 1e-3 * expect)
                << eta << ": XYZ channel " << c << " " << st.mean << " vs " << expect << " +- " << st.stderror;
            EXPECT_LT(st.stderror, 0.02 * expect) << eta << ": too noisy to see a 10% bias";
        }
    }
}

TEST(Materials, ConstantSpectralEtaRendersLikeTheFloatEta) {
    // A glass sphere over a coloured checkerboard, lit by a coloured lamp: the spectral
    // (constant) eta terminates the secondary wavelengths, the float eta does not; both
    // must give the same image in expectation.
    auto scene = [](const std::string &eta) {
        return R"(
LookAt 0 3 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16]
Sampler "independent" "integer pixelsamples" [384]
Integrator "path" "integer maxdepth" [10]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" [400 0 430 4 520 1 600 6 650 0]
  Translate 0 5 0
  Shape "sphere" "float radius" [1.5]
AttributeEnd
Texture "checks" "spectrum" "checkerboard" "float uscale" [6] "float vscale" [6]
    "rgb tex1" [0.8 0.2 0.1] "rgb tex2" [0.1 0.3 0.9]
Material "diffuse" "texture reflectance" "checks"
Shape "trianglemesh" "point3 P" [-3 -1 -3  3 -1 -3  3 -1 3  -3 -1 3] "integer indices" [0 1 2 0 2 3]
    "point2 uv" [0 0 1 0 1 1 0 1]
Material "dielectric" )" + eta + R"(
Shape "sphere" "float radius" [1]
)";
    };
    RenderOptions opts;
    opts.seed = 11;
    Image a = RenderString(scene(R"("float eta" [1.5])"), opts);
    opts.seed = 12;
    Image b = RenderString(scene(R"("spectrum eta" [300 1.5 900 1.5])"), opts);
    for (int c = 0; c < 3; ++c) {
        Stat d = DiffStat(a, b, c);
        double level = XYZStat(a, c).mean;
        EXPECT_LT(std::abs(d.mean), 4.5 * d.stderror) << "XYZ channel " << c << ": float - spectral eta "
                                                      << d.mean << " +- " << d.stderror;
        EXPECT_LT(d.stderror, 0.03 * level) << "too noisy to see a 15% bias";
    }
}

TEST(Materials, BadParametersAreErrors) {
    auto expectError = [](const std::string &material, const char *what) {
        std::string msg = ErrorOf("WorldBegin\n" + material + "\n");
        EXPECT_NE(msg.find("mat.pbrt:2"), std::string::npos) << material << " -> " << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << material << " -> " << msg;
    };
    // No eta/k: the default named copper spectra are not part of this renderer.
    expectError(R"(Material "conductor")", "metal-Cu-eta");
    expectError(R"(Material "conductor" "rgb reflectance" [0.5 0.5 0.5] "rgb eta" [1 1 1])", "not both");
    expectError(R"(Material "coateddiffuse" "integer maxdepth" [0])", "maxdepth");
    expectError(R"(Material "dielectric" "texture eta" "x")", "eta");
    expectError(R"(Material "diffuse" "normalmap" "n.png")", "normalmap");
    expectError(R"(Material "hair")", "hair");
    expectError(R"(Material "diffusetransmission" "float scale" [-0.5])", "\"scale\" must be finite and >= 0");
    expectError(R"(Material "diffusetransmission" "texture scale" "x")", "scale");
    expectError(R"(Material "diffusetransmission" "rgb transmittance" [0.2 1.7 0.3])", "component > 1");
    expectError(R"(Material "diffusetransmission" "float transmission" [0.5])", "transmission");
}

// diffusetransmission: pbrt-v4's defaults (reflectance and transmittance 0.25, scale 1),
// scale multiplying both, each clamped to [0, 1] after scaling, as the BSDF sees them.
TEST(Materials, DiffuseTransmissionParameters) {
    auto scene = LoadSceneFromString(R"(
Camera "perspective"
WorldBegin
Material "diffusetransmission"
Shape "sphere"
Material "diffusetransmission" "spectrum reflectance" [300 0.1 900 0.1]
    "spectrum transmittance" [300 0.4 900 0.4] "float scale" [2]
Shape "sphere" "float radius" [2]
Material "diffusetransmission" "spectrum reflectance" [300 0.3 900 0.3]
    "spectrum transmittance" [300 0.9 900 0.9] "float scale" [1.5]
Shape "sphere" "float radius" [3]
)", RenderOptions{}, "dt.pbrt");
    const std::pair<Float, Float> want[] = {{0.25f, 0.25f}, {0.2f, 0.8f}, {0.45f, 1.0f}};
    SurfaceInteraction si;
    si.p = Point3f(0, 0, 1);
    si.n = si.ns = Normal3f(0, 0, 1);
    si.dpdu = Vector3f(1, 0, 0);
    Vector3f wo = Normalize(Vector3f(0.2f, 0.1f, 1)), wr = Normalize(Vector3f(-0.3f, 0.4f, 1));
    Vector3f wt = Normalize(Vector3f(-0.3f, 0.4f, -1));
    int found = 0;
    for (const Material &m : scene->materials) {
        if (!std::holds_alternative<DiffuseTransmissionMaterial>(m)) continue;
        ASSERT_LT(found, 3);
        SampledWavelengths lambda = SampledWavelengths::SampleVisible(0.4f);
        std::optional<BSDF> bsdf = GetBSDF(m, si, lambda, [] { return Float(0.5); });
        ASSERT_TRUE(bsdf);
        for (int i = 0; i < NSpectrumSamples; ++i) {
            EXPECT_NEAR(bsdf->f(wo, wr)[i], want[found].first * InvPi, 1e-6) << "material " << found;
            EXPECT_NEAR(bsdf->f(wo, wt)[i], want[found].second * InvPi, 1e-6) << "material " << found;
        }
        ++found;
    }
    EXPECT_EQ(found, 3);
}

// More light out than in (scale * (reflectance + transmittance) > 1) renders as in pbrt-v4,
// with a warning naming the parameter; a physically possible filter gets none.
TEST(Materials, DiffuseTransmissionWarnsWhenItGainsEnergy) {
    ::testing::internal::CaptureStderr();
    LoadSceneFromString("WorldBegin\nMaterial \"diffusetransmission\"\n"
                        "  \"spectrum transmittance\" [300 0.5 600 0.9 900 0.5] \"rgb reflectance\" [0.3 0.3 0.3]\n",
                        RenderOptions{}, "gain.pbrt");
    std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("gain.pbrt:3:3: diffusetransmission: scale * (reflectance + transmittance)"),
              std::string::npos) << err;
    ::testing::internal::CaptureStderr();
    LoadSceneFromString("WorldBegin\nMaterial \"diffusetransmission\"\n"
                        "  \"spectrum transmittance\" [300 0.5 600 0.9 900 0.5] \"rgb reflectance\" [0.08 0.08 0.08]\n",
                        RenderOptions{}, "nogain.pbrt");
    err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(err.find("diffusetransmission"), std::string::npos) << err;
}

// A closed sphere that reflects 30% and transmits 70% loses nothing: in a uniform sky it
// vanishes (every pixel is the sky's Y = 2), whichever side a path is on. Paths scatter
// inside it until they leave, so this checks sampling, evaluation and next-event estimation
// through the surface together.
TEST(Materials, LosslessDiffuseTransmissionSphereVanishesInAWhiteFurnace) {
    std::string scene = R"(
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [20]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16]
Sampler "independent" "integer pixelsamples" [128]
Integrator "path" "integer maxdepth" [200]
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1] "float scale" [2]
Material "diffusetransmission" "spectrum reflectance" [300 0.3 900 0.3]
    "spectrum transmittance" [300 0.7 900 0.7]
Shape "sphere" "float radius" [1]
)";
    Image img = RenderString(scene);
    XYZ e = SpectrumToXYZ(ConstantSpectrum(1));
    for (int c = 0; c < 3; ++c) {
        Stat st = XYZStat(img, c);
        double expect = 2 / e.Y * e[c];
        EXPECT_LT(std::abs(st.mean - expect), 5 * st.stderror + 1e-3 * expect)
            << "XYZ channel " << c << " " << st.mean << " vs " << expect << " +- " << st.stderror;
        EXPECT_LT(st.stderror, 0.02 * expect) << "too noisy to see a 10% bias";
    }
}

// A coloured filter sheet filling the view, in a uniform white sky: what the camera sees is
// the sky reflected on its side plus the sky transmitted from the other, scale * (r + t) times
// the sky's radiance at every wavelength; its XYZ is that spectrum's.
TEST(Materials, DiffuseTransmissionFilterHasItsSpectralColour) {
    std::string scene = R"(
LookAt 0 0 -1  0 0 0  0 1 0
Camera "perspective" "float fov" [30]
Film "rgb" "integer xresolution" [8] "integer yresolution" [8]
Sampler "independent" "integer pixelsamples" [64]
Integrator "path" "integer maxdepth" [5]
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1] "float scale" [2]
Material "diffusetransmission" "spectrum reflectance" [300 0.05 900 0.05]
    "spectrum transmittance" [300 0.02 480 0.02 530 0.8 580 0.02 900 0.02] "float scale" [0.9]
Shape "trianglemesh" "point3 P" [-50 -50 0  50 -50 0  50 50 0  -50 50 0] "integer indices" [0 1 2 0 2 3]
)";
    Image img = RenderString(scene);
    auto filter = PiecewiseLinearSpectrum::FromInterleaved(
        {300, 0.9f * 0.07f, 480, 0.9f * 0.07f, 530, 0.9f * 0.85f, 580, 0.9f * 0.07f, 900, 0.9f * 0.07f}, false);
    XYZ want = SpectrumToXYZ(*filter), e = SpectrumToXYZ(ConstantSpectrum(1));
    for (int c = 0; c < 3; ++c) {
        Stat st = XYZStat(img, c);
        double expect = 2 / e.Y * want[c];
        EXPECT_LT(std::abs(st.mean - expect), 5 * st.stderror + 2e-3 * expect)
            << "XYZ channel " << c << " " << st.mean << " vs " << expect << " +- " << st.stderror;
    }
    // Green: Y well above X and Z.
    EXPECT_GT(XYZStat(img, 1).mean, 1.5 * XYZStat(img, 0).mean);
}

// The six evaluation scenes (outside the repository) build and render 4 x 4 pixels at 1 spp.
TEST(Materials, EvaluationScenesBuildAndRender) {
    namespace fs = std::filesystem;
    const fs::path scenes = fs::path(PBRT_SHARED_DIR) / "scenes";
    if (!fs::is_directory(scenes)) GTEST_SKIP() << scenes << " is not present";
    for (const char *name : {"cornell-box", "veach-mis", "teapot", "veach-bidir", "staircase",
                             "glass-of-water"}) {
        fs::path file = scenes / name / "scene-v4.pbrt";
        if (!fs::exists(file)) {
            ADD_FAILURE() << file << " is missing";
            continue;
        }
        RenderOptions opts;
        opts.quiet = true;
        opts.resolution = {4, 4};
        opts.spp = 1;
        opts.maxDepth = 3;
        std::unique_ptr<Scene> scene;
        ASSERT_NO_THROW(scene = LoadScene({file.string()}, opts)) << file;
        Render(*scene, 0, true);
        Image img = scene->film->GetImage();
        ASSERT_EQ(img.width, 4) << file;
        for (float v : img.pixels) EXPECT_TRUE(std::isfinite(v)) << file;
    }
}

TEST(Materials, ConstantDiffuseReflectanceFromThePathCacheIsTheSame) {
    // A constant reflectance is taken from the path's spectrum cache (evaluated once per
    // path); a textured one at each hit. Both give the BSDF the texture gives.
    auto scene = LoadSceneFromString(R"(
Camera "perspective"
WorldBegin
Material "diffuse" "rgb reflectance" [0.7 0.3 0.05]
Shape "sphere"
Texture "checks" "spectrum" "checkerboard" "rgb tex1" [0.8 0.2 0.1] "rgb tex2" [0.1 0.3 0.9]
Material "diffuse" "texture reflectance" "checks"
Shape "sphere" "float radius" [2]
)", RenderOptions{}, "cache.pbrt");
    ASSERT_GE(scene->materials.size(), 3u);
    SurfaceInteraction si;
    si.p = Point3f(0.1f, 0.2f, 0.97f);
    si.n = si.ns = Normalize(Vector3f(si.p));
    si.dpdu = Vector3f(1, 0, 0);
    si.uv = Point2f(0.3f, 0.6f);
    Vector3f wo = Normalize(Vector3f(0.2f, 0.1f, 1)), wi = Normalize(Vector3f(-0.3f, 0.4f, 1));
    int constants = 0;
    for (size_t m = 0; m < scene->materials.size(); ++m) {
        const auto *d = std::get_if<DiffuseMaterial>(&scene->materials[m]);
        if (!d) continue;
        constants += d->reflectanceConstant != nullptr;
        for (Float u : {0.1f, 0.6f}) {
            SampledWavelengths lambda = SampledWavelengths::SampleVisible(u);
            SampledSpectrumCache cache;
            auto none = [] { return Float(0.5); };
            std::optional<BSDF> plain = GetBSDF(scene->materials[m], si, lambda, none);
            std::optional<BSDF> first = GetBSDF(scene->materials[m], si, lambda, none, &cache);
            std::optional<BSDF> again = GetBSDF(scene->materials[m], si, lambda, none, &cache);
            ASSERT_TRUE(plain && first && again);
            SampledSpectrum f = plain->f(wo, wi);
            ASSERT_TRUE(f.IsNonZero());
            for (int i = 0; i < NSpectrumSamples; ++i) {
                EXPECT_EQ(first->f(wo, wi)[i], f[i]) << "material " << m;
                EXPECT_EQ(again->f(wo, wi)[i], f[i]) << "material " << m;
            }
        }
    }
    EXPECT_EQ(constants, 2);  // the default material and the rgb one; not the texture
}
