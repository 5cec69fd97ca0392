// The scene's total emitted spectral power (emission.h, design §5.6) against a hand
// computation: pbrt-v4's light power from the scene's areas, scales and spectra.
#include <pbrt/emission.h>

#include <pbrt/options.h>
#include <pbrt/scene.h>
#include <pbrt/util/cie_data.h>
#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>

#include <wavelength_table.h>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace pbrt;

namespace {

const double kPi = 3.14159265358979323846;

// A piecewise-linear function in double precision (the hand computation's own).
struct Lin {
    std::vector<double> x, y;
    double operator()(double l) const {
        if (l < x.front() || l > x.back()) return 0;
        for (size_t i = 0; i + 1 < x.size(); ++i)
            if (l <= x[i + 1]) return y[i] + (y[i + 1] - y[i]) * (l - x[i]) / (x[i + 1] - x[i]);
        return y.back();
    }
    // pbrt-v4's 1-nit normalization: the sum of s * ybar over 360, 361, ..., 830 nm.
    double Luminance() const {
        double sum = 0;
        for (int i = 0; i < cie::kNumSamples; ++i) sum += (*this)(cie::kLambdaMin + i) * cie::CIE_Y[i];
        return sum;
    }
};

const char *kCamera = R"(
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [8] "integer yresolution" [8] "string filename" "/no/such/dir/x.exr"
WorldBegin
)";

std::unique_ptr<Scene> Load(const std::string &world) {
    RenderOptions opts;
    opts.emissionSpectrum = "unused.spd";  // as the command sets it: the film's path is not checked
    return LoadSceneFromString(std::string(kCamera) + world, opts);
}

double Relative(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

}  // namespace

TEST(Emission, TwoQuadsAndAPointLightMatchTheHandComputation) {
    // Quad A: 1 x 2 in object space, scaled by 3 in x: area 6 in render space, two-sided,
    // scale 4. Quad B: 2 x 0.5 = area 1, one-sided, scale 0.5. A point light of scale 3.
    Lin a{{350, 500, 850}, {1, 3, 2}}, b{{360, 600, 830}, {0, 5, 1}}, p{{360, 830}, {2, 2}};
    std::string world = R"(
AttributeBegin
  Scale 3 1 1
  AreaLightSource "diffuse" "spectrum L" [350 1 500 3 850 2] "float scale" [4] "bool twosided" true
  Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  1 2 0  0 2 0] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
  Translate 0 0 -1
  AreaLightSource "diffuse" "spectrum L" [360 0 600 5 830 1] "float scale" [0.5]
  Shape "trianglemesh" "point3 P" [0 0 0  2 0 0  2 0.5 0  0 0.5 0] "integer indices" [0 1 2 0 2 3]
AttributeEnd
LightSource "point" "spectrum I" [360 2 830 2] "float scale" [3] "point3 from" [0 3 0]
)";
    EmissionSpectrum e = SceneEmissionSpectrum(*Load(world));
    // The nodes: the union of the three spectra's nodes inside 360..830 nm.
    EXPECT_EQ(e.lambdas, (std::vector<double>{360, 500, 600, 830}));
    for (size_t i = 0; i < e.lambdas.size(); ++i) {
        double l = e.lambdas[i];
        double hand = kPi * 6 * 2 * 4 * a(l) / a.Luminance() + kPi * 1 * 0.5 * b(l) / b.Luminance() +
                      4 * kPi * 3 * p(l) / p.Luminance();
        EXPECT_LT(Relative(e.values[i], hand), 1e-6) << l << " nm: " << e.values[i] << " vs " << hand;
    }
}

TEST(Emission, SpotAndPowerParameters) {
    // A spot light: 2 pi I scale (1 - (cos start + cos end) / 2). An area light with
    // "power" P: its scale becomes P / (pi area) per triangle, so it emits P in total
    // (per unit luminance) times its "scale", as in pbrt-v4.
    Lin s{{360, 830}, {1, 3}};
    std::string world = R"(
LightSource "spot" "spectrum I" [360 1 830 3] "float scale" [2] "float coneangle" [40] "float conedeltaangle" [10]
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" [360 1 830 3] "float power" [7] "float scale" [100]
  Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  0 1 0] "integer indices" [0 1 2]
AttributeEnd
)";
    EmissionSpectrum e = SceneEmissionSpectrum(*Load(world));
    double cosStart = std::cos(30 * kPi / 180), cosEnd = std::cos(40 * kPi / 180);
    for (size_t i = 0; i < e.lambdas.size(); ++i) {
        double l = e.lambdas[i];
        double hand = (2 * kPi * 2 * (1 - (cosStart + cosEnd) / 2) + 100 * 7) * s(l) / s.Luminance();
        EXPECT_LT(Relative(e.values[i], hand), 1e-6) << l << " nm";
    }
}

TEST(Emission, SmoothSpectraAddTheNanometreGrid) {
    // A blackbody point light is not piecewise linear: every nanometre of 360..830 is written.
    std::string world = R"(
LightSource "point" "blackbody I" [3000] "float scale" [2]
)";
    EmissionSpectrum e = SceneEmissionSpectrum(*Load(world));
    ASSERT_EQ(e.lambdas.size(), size_t(471));
    BlackbodySpectrum bb(3000);
    double y = 0;
    for (int i = 0; i < cie::kNumSamples; ++i) y += double(bb(Float(cie::kLambdaMin + i))) * cie::CIE_Y[i];
    for (size_t i = 0; i < e.lambdas.size(); ++i) {
        EXPECT_EQ(e.lambdas[i], 360.0 + double(i));
        double hand = 4 * kPi * 2 * double(bb(Float(e.lambdas[i]))) / y;
        EXPECT_LT(Relative(e.values[i], hand), 1e-6) << e.lambdas[i] << " nm";
    }
}

TEST(Emission, InfiniteLightUsesTheSceneRadius) {
    // Bounds [-1, 1]^2 x {0}: radius sqrt(2); a uniform sky emits 4 pi^2 r^2 scale L.
    std::string world = R"(
LightSource "infinite" "spectrum L" [360 1 830 1] "float scale" [0.25]
Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]
)";
    EmissionSpectrum e = SceneEmissionSpectrum(*Load(world));
    Lin one{{360, 830}, {1, 1}};
    double hand = 4 * kPi * kPi * 2 * 0.25 / one.Luminance();
    for (double v : e.values) EXPECT_LT(Relative(v, hand), 1e-6) << v << " vs " << hand;
}

TEST(Emission, NoEmittersIsAnError) {
    std::string world = R"(
Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  0 1 0] "integer indices" [0 1 2]
)";
    auto scene = Load(world);
    try {
        SceneEmissionSpectrum(*scene);
        FAIL() << "expected an error";
    } catch (const PbrtError &err) {
        EXPECT_NE(std::string(err.what()).find("no emitters"), std::string::npos) << err.what();
    }
    EXPECT_THROW(SceneEmissionSpectrum(*Load(R"(LightSource "point" "float scale" [0])")), PbrtError);
}

TEST(MaterialReflectances, AsTheRendererBuildsThem) {
    std::string world = R"(
LightSource "point" "float scale" [1]
Texture "checks" "spectrum" "checkerboard" "rgb tex1" [1 0 0] "rgb tex2" [0 0 1] "float uscale" [4] "float vscale" [4]
AttributeBegin
  Material "diffuse" "rgb reflectance" [0.8 0.2 0.1]
  Shape "sphere"
AttributeEnd
Material "diffuse" "spectrum reflectance" [300 0.1 900 0.9]
Material "coateddiffuse" "texture reflectance" "checks"
Shape "sphere"
Material "diffuse" "rgb reflectance" [0 0 0]
Shape "sphere"
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
)";
    MaterialReflectances m = SceneMaterialReflectances(*Load(world));
    // The unused spectrum material, the black one and the unused grey one are left out.
    ASSERT_EQ(m.labels.size(), size_t(2));
    EXPECT_EQ(m.labels[0], "<string>:10:3");  // where the material was defined
    RGBAlbedoSpectrum rgb(*RGBColorSpace::sRGB, RGB(0.8f, 0.2f, 0.1f));
    RGBAlbedoSpectrum red(*RGBColorSpace::sRGB, RGB(1, 0, 0)), blue(*RGBColorSpace::sRGB, RGB(0, 0, 1));
    for (int i = 0; i <= 470; ++i) {
        Float l = 360 + Float(i);
        EXPECT_NEAR(m.values[0][size_t(i)], double(rgb(l)), 1e-7) << l;
        // A 4 x 4 checkerboard over uv: half of each, exactly, at the 32 x 32 cell centres.
        EXPECT_NEAR(m.values[1][size_t(i)], 0.5 * (double(red(l)) + double(blue(l))), 1e-6) << l;
    }
    EXPECT_THROW(SceneMaterialReflectances(*Load(R"(Material "dielectric"
Shape "sphere")")), PbrtError);
}

TEST(MaterialReflectances, RepeatedColoursCountOnce) {
    std::string world = R"(
LightSource "point" "float scale" [1]
Material "diffuse" "rgb reflectance" [0.3 0.4 0.5]
Shape "sphere"
Material "diffuse" "rgb reflectance" [0.3 0.4 0.5]
Shape "sphere"
Material "diffuse" "rgb reflectance" [0.5 0.4 0.3]
Shape "sphere"
)";
    MaterialReflectances m = SceneMaterialReflectances(*Load(world));
    ASSERT_EQ(m.labels.size(), size_t(2));
    EXPECT_NE(m.values[0], m.values[1]);
}

// ---- Emission sampling (design §1.7): the table built from the scene's emitted power -------

TEST(EmissionTable, ItsMixtureIsTheEmittedPowerTimesTheWeight) {
    std::string world = R"(
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" [360 0  436 9  437 0  500 1  611 5  620 1  830 0] "float scale" [2]
  Shape "trianglemesh" "point3 P" [0 0 0  1 0 0  1 1 0] "integer indices" [0 1 2]
AttributeEnd
LightSource "point" "blackbody I" [2700] "float scale" [0.5]
)";
    auto scene = Load(world);
    EmissionSpectrum e = SceneEmissionSpectrum(*scene);
    for (const std::string &w : EmissionWeights()) {
        EmissionTable t = SceneEmissionTable(*scene, w);
        ASSERT_TRUE(t.table);
        EXPECT_EQ(t.weight, w);
        EXPECT_GE(t.seconds, 0.0);
        EXPECT_EQ(t.table->grid.front(), 360.0);
        EXPECT_EQ(t.table->grid.back(), 830.0);
        // (1/4) sum_k p_k = q / M with q = Phi * w, linear between Phi's and the CMFs' nodes.
        auto weight = [&](double l) {
            if (w == "spd") return 1.0;
            const int i = int(l) - cie::kLambdaMin;
            return w == "luminance" ? cie::CIE_Y[i] : cie::CIE_X[i] + cie::CIE_Y[i] + cie::CIE_Z[i];
        };
        double mass = 0;
        for (size_t i = 0; i + 1 < e.lambdas.size(); ++i)  // Phi's nodes include the 1 nm grid here
            mass += 0.5 * (e.values[i] * weight(e.lambdas[i]) + e.values[i + 1] * weight(e.lambdas[i + 1])) *
                    (e.lambdas[i + 1] - e.lambdas[i]);
        for (size_t i = 0; i < e.lambdas.size(); ++i) {
            const double want = e.values[i] * weight(e.lambdas[i]) / mass;
            EXPECT_NEAR(wavelength_table::MixturePdf(*t.table, e.lambdas[i]), want, 1e-9 * want + 1e-15)
                << w << " at " << e.lambdas[i] << " nm";
        }
    }
    EXPECT_THROW(SceneEmissionTable(*scene, "ybar"), PbrtError);
}

TEST(EmissionTable, BadLightsAreNamed) {
    // Every light emits nothing: the first light's directive is named.
    try {
        SceneEmissionTable(*Load("\nLightSource \"point\" \"float scale\" [0]\n"), "spd");
        FAIL() << "expected an error";
    } catch (const PbrtError &err) {
        EXPECT_EQ(std::string(err.what()).rfind("<string>:7:1: no light of the scene emits", 0), 0u)
            << err.what();
    }
    // A light whose power overflows (a tiny luminance normalized to 1 nit, a huge scale).
    try {
        SceneEmissionTable(*Load(R"(
LightSource "point" "float scale" [1]
LightSource "point" "spectrum I" [400 1e-30 700 1e-30] "float scale" [3e38]
)"), "spd");
        FAIL() << "expected an error";
    } catch (const PbrtError &err) {
        EXPECT_EQ(std::string(err.what()).rfind("<string>:8:1: this light's emitted power is not finite", 0), 0u)
            << err.what();
    }
}
