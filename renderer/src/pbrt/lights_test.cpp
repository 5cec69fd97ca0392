// Lights against closed forms: the radiance of a diffuse floor (albedo 0.5) straight below
// each light, seen by a tiny orthographic camera, is albedo / pi * E with E the irradiance
// the light's definition implies (pbrt-v4's 1-nit normalization times "scale", or the
// "power" / "illuminance" it is given).
#include <pbrt/lights.h>

#include <pbrt/test_util.h>
#include <pbrt/util/color.h>
#include <pbrt/util/paramdict.h>
#include <pbrt/util/rng.h>

#include <gtest/gtest.h>

#include <fstream>
#include <string>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

const double kAlbedo = 0.5;

// Luminance of the floor point (0, 0, 0) lit by `lights` (direct lighting only).
Stat FloorLuminance(const std::string &lights, int spp = 256) {
    std::string scene = R"(
LookAt 0 0 0.5  0 0 0  0 1 0
Camera "orthographic" "float screenwindow" [-0.001 0.001 -0.001 0.001]
Film "rgb" "integer xresolution" [4] "integer yresolution" [4]
Sampler "independent" "integer pixelsamples" [)" + std::to_string(spp) + R"(]
Integrator "path" "integer maxdepth" [1]
WorldBegin
Material "diffuse" "spectrum reflectance" [300 0.5 900 0.5]
Shape "trianglemesh" "point3 P" [-20 -20 0  20 -20 0  20 20 0  -20 20 0] "integer indices" [0 1 2 0 2 3]
)" + lights;
    return XYZStat(RenderString(scene), 1);
}

void ExpectLuminance(const std::string &lights, double expect, const char *what) {
    Stat st = FloorLuminance(lights);
    EXPECT_LT(std::abs(st.mean - expect), 5 * st.stderror + 1e-5 * expect)
        << what << ": " << st.mean << " vs " << expect << " (stderr " << st.stderror << ")";
    EXPECT_LT(std::abs(st.mean - expect), 0.01 * expect) << what << ": " << st.mean << " vs " << expect;
}

}  // namespace

TEST(Lights, PointLight) {
    // I has luminous intensity "scale" (1-nit normalization): E = I / h^2.
    ExpectLuminance(R"(LightSource "point" "blackbody I" [3000] "float scale" [2] "point3 from" [0 0 1.5])",
                    kAlbedo / Pi * 2 / (1.5 * 1.5), "point light");
    // "power" is the luminous power: I = power / (4 pi).
    ExpectLuminance(R"(LightSource "point" "float power" [10] "point3 from" [0 0 2])",
                    kAlbedo / Pi * 10 / (4 * Pi) / 4, "point light with power");
    // The CTM places the light: Translate moves "from". An RGB intensity is normalized by
    // its illuminant only (pbrt-v4), so it keeps the RGB's luminance relative to white.
    double lum = RGBColorSpace::sRGB->Luminance(RGB(0.2f, 0.5f, 0.9f));
    ExpectLuminance(R"(Translate 0 0 1  LightSource "point" "rgb I" [0.2 0.5 0.9] "point3 from" [0 0 1])",
                    kAlbedo / Pi / 4 * lum, "translated RGB point light");
}

TEST(Lights, SpotLight) {
    ExpectLuminance(R"(LightSource "spot" "float scale" [3] "point3 from" [0 0 1] "point3 to" [0 0 0] "float coneangle" [20])",
                    kAlbedo / Pi * 3, "spot light on axis");
    Stat off = FloorLuminance(R"(LightSource "spot" "point3 from" [0 0 1] "point3 to" [1 0 1] "float coneangle" [30])", 16);
    EXPECT_EQ(off.mean, 0) << "a point 90 degrees off the spot's axis is dark";
    // In the falloff zone: smoothstep of cos(theta) between the cone and cone - delta
    // (pbrt-v4's parameter "conedeltaangle"; 10 here, not its default 5).
    double theta = Radians(24), ct = std::cos(theta);
    double c0 = std::cos(Radians(30)), c1 = std::cos(Radians(20));
    double t = (ct - c0) / (c1 - c0), falloff = t * t * (3 - 2 * t);
    ExpectLuminance(R"(LightSource "spot" "point3 from" [0 0 1] "point3 to" [)" + std::to_string(std::tan(theta)) +
                        R"( 0 0] "float coneangle" [30] "float conedeltaangle" [10])",
                    kAlbedo / Pi * falloff, "spot light falloff");
    // "conedelta" is not a pbrt-v4 parameter: an error, as in pbrt-v4.
    try {
        LoadSceneFromString("WorldBegin\nLightSource \"spot\" \"float conedelta\" [10]\n", RenderOptions{}, "spot.pbrt");
        ADD_FAILURE() << "\"conedelta\" was accepted";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("spot.pbrt:2:"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("conedelta"), std::string::npos) << e.what();
    }
}

TEST(Lights, DistantLight) {
    // Radiance "L" normalized to 1 nit times scale arrives as irradiance scale * cos(theta).
    ExpectLuminance(R"(LightSource "distant" "point3 from" [0 1 1] "point3 to" [0 0 0] "float scale" [3])",
                    kAlbedo / Pi * 3 / std::sqrt(2.0), "distant light at 45 degrees");
    ExpectLuminance(R"(LightSource "distant" "point3 from" [0 0 1] "point3 to" [0 0 0] "float illuminance" [7])",
                    kAlbedo / Pi * 7, "distant light with illuminance");
}

TEST(Lights, UniformInfiniteLight) {
    // A constant sky of luminance L gives an open floor E = pi L; "illuminance" sets E.
    ExpectLuminance(R"(LightSource "infinite" "float scale" [2])", kAlbedo * 2, "sky");
    ExpectLuminance(R"(LightSource "infinite" "spectrum L" [400 1 700 0.2] "float illuminance" [5])",
                    kAlbedo / Pi * 5, "sky with illuminance");
}

TEST(Lights, SphereAreaLight) {
    // A sphere of radius R at distance d, luminance L: E = pi L (R / d)^2. Exercises cone
    // sampling and the MIS weights of BSDF-sampled hits on the sphere.
    ExpectLuminance(R"(AttributeBegin AreaLightSource "diffuse" "float scale" [4] Translate 0 0 3
                       Shape "sphere" "float radius" [1] AttributeEnd)",
                    kAlbedo * 4 / 9, "sphere light");
    // Scaled sphere (similarity transform): the same sphere.
    ExpectLuminance(R"(AttributeBegin AreaLightSource "diffuse" "float scale" [4] Translate 0 0 3 Scale 2 2 2
                       Shape "sphere" "float radius" [0.5] AttributeEnd)",
                    kAlbedo * 4 / 9, "scaled sphere light");
    // A reversed sphere emits inwards: nothing reaches the floor.
    EXPECT_EQ(FloorLuminance(R"(AttributeBegin ReverseOrientation AreaLightSource "diffuse" Translate 0 0 3
                                Shape "sphere" AttributeEnd)", 16).mean, 0);
}

TEST(Lights, TwoSidedQuadLight) {
    // A large two-sided quad far above acts like a sky patch: E = pi L F; a quad whose
    // normal points up lights the floor only when "twosided" is set.
    std::string quad = R"(Shape "trianglemesh" "point3 P" [-1 -1 1  1 -1 1  1 1 1  -1 1 1] "integer indices" [0 1 2 0 2 3])";
    EXPECT_EQ(FloorLuminance("AttributeBegin AreaLightSource \"diffuse\"\n" + quad + " AttributeEnd", 16).mean, 0);
    // Form factor of a 2 x 2 square at height 1 centred above the point: 4 corner rectangles.
    double A = 1, F = 4 * (A / std::sqrt(1 + A * A) * std::atan(A / std::sqrt(1 + A * A))) * 2 / (2 * Pi);
    ExpectLuminance("AttributeBegin AreaLightSource \"diffuse\" \"bool twosided\" true \"float scale\" [2]\n" + quad +
                        " AttributeEnd",
                    kAlbedo * 2 * F, "two-sided quad");
    // ReverseOrientation turns it down; a mirroring transform (which reverses the winding)
    // does not change the side (pbrt flips the normal when the transform swaps handedness).
    ExpectLuminance("AttributeBegin Scale -1 1 1 ReverseOrientation AreaLightSource \"diffuse\" \"float scale\" [2]\n" +
                        quad + " AttributeEnd",
                    kAlbedo * 2 * F, "reversed, mirrored quad");
    EXPECT_EQ(FloorLuminance("AttributeBegin Scale -1 1 1 AreaLightSource \"diffuse\"\n" + quad + " AttributeEnd", 16).mean, 0);
}

TEST(Lights, IndexedSpectrumMatchesPiecewiseLinear) {
    RNG rng(3);
    std::vector<Float> v;
    Float l = 379.5f;
    for (int i = 0; i < 300; ++i) {
        v.push_back(l);
        v.push_back(rng.UniformFloat() < 0.3f ? 0 : rng.UniformFloat());
        l += 0.3f + 2 * rng.UniformFloat();
    }
    auto pl = PiecewiseLinearSpectrum::FromInterleaved(v, false);
    IndexedPiecewiseLinearSpectrum fast(*pl);
    for (Float x = 350; x < 850; x += 0.0137f) ASSERT_EQ(fast(x), (*pl)(x)) << "lambda " << x;
    for (size_t i = 0; i < pl->Lambdas().size(); ++i)
        ASSERT_EQ(fast(pl->Lambdas()[i]), (*pl)(pl->Lambdas()[i])) << "at node " << i;
}

TEST(Lights, IndexedSpectrumEvenNodesMatchPiecewiseLinear) {
    // Evenly spaced nodes (0.5 nm, as tabulated lamp spectra come) take the direct index.
    RNG rng(5);
    std::vector<Float> v;
    for (int i = 0; i < 941; ++i) {
        v.push_back(360 + 0.5f * i);
        v.push_back(rng.UniformFloat() < 0.1f ? 0 : 10 * rng.UniformFloat());
    }
    auto pl = PiecewiseLinearSpectrum::FromInterleaved(v, false);
    IndexedPiecewiseLinearSpectrum fast(*pl);
    for (Float x = 350; x < 840; x += 0.00731f) ASSERT_EQ(fast(x), (*pl)(x)) << "lambda " << x;
    for (size_t i = 0; i < pl->Lambdas().size(); ++i) {
        Float node = pl->Lambdas()[i];
        for (Float x : {node, std::nextafter(node, 0.f), std::nextafter(node, 1e4f)})
            ASSERT_EQ(fast(x), (*pl)(x)) << "near node " << i;
    }
}

TEST(Lights, AreaLightPointMatchesTheSurfaceInteraction) {
    // SurfacePoint (light sampling) gives Interaction's p, pError and n, with and without
    // shading normals (which can flip n) and with the stored face normals.
    for (bool withN : {false, true}) {
        std::vector<std::array<Float, 3>> N;
        if (withN) N = {{0, 0, -1}, {0.1f, 0, -1}, {0, 0.2f, -1}, {0, 0, -1}};
        auto mesh = MakeTriangleMesh(Transform(), false, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.3f}, {0, 1, 0}},
                                     {0, 1, 2, 0, 2, 3}, N, {}, {}, FileLoc{});
        for (bool stored : {false, true}) {
            if (stored) mesh->PrecomputeFaceNormals();
            RNG rng(7);
            for (int k = 0; k < 200; ++k) {
                size_t tri = size_t(k % 2);
                if (stored) ASSERT_EQ(mesh->GeometricNormal(tri), mesh->ComputeGeometricNormal(tri));
                Float b1 = rng.UniformFloat(), b2 = rng.UniformFloat() * (1 - b1);
                SurfaceInteraction si;
                mesh->Interaction(tri, b1, b2, &si);
                Point3f p;
                Vector3f err;
                Normal3f n;
                mesh->SurfacePoint(tri, b1, b2, &p, &err, &n);
                ASSERT_EQ(p, si.p);
                ASSERT_EQ(err, si.pError);
                ASSERT_EQ(n, si.n);
            }
        }
    }
}

TEST(Lights, EqualTabulatedSpectraAreShared) {
    // Lights given the same table each (as scene files repeat a lamp per light) share one
    // spectrum object afterwards, so that a path's spectrum cache evaluates it once; other
    // tables and other kinds of spectra keep theirs.
    auto table = [](Float scale) {
        std::vector<Float> v;
        for (int i = 0; i < 50; ++i) v.insert(v.end(), {400 + 2.5f * i, scale * (1 + std::sin(0.3f * i))});
        return FastLookup(PiecewiseLinearSpectrum::FromInterleaved(v, false));
    };
    auto point = [](SpectrumHandle spec) {
        return Light::Create("point", ParameterDictionary(), Transform(), std::move(spec), *RGBColorSpace::sRGB, FileLoc{});
    };
    std::vector<Light> lights = {point(table(1)), point(table(1)) /* equal to 0, another object */,
                                 point(table(2)) /* other values */,
                                 point(std::make_shared<ConstantSpectrum>(1.f)), point(table(1))};
    ASSERT_NE(lights[0].EmissionSpectrum(), lights[1].EmissionSpectrum());
    SampledWavelengths lambda = SampledWavelengths::SampleUniform(0.3f);
    SampledSpectrum before = lights[4].EmissionSpectrum()->Sample(lambda);
    Light::ShareEqualSpectra(lights);
    EXPECT_EQ(lights[1].EmissionSpectrum(), lights[0].EmissionSpectrum());
    EXPECT_EQ(lights[4].EmissionSpectrum(), lights[0].EmissionSpectrum());
    EXPECT_NE(lights[2].EmissionSpectrum(), lights[0].EmissionSpectrum());
    EXPECT_TRUE(dynamic_cast<const ConstantSpectrum *>(lights[3].EmissionSpectrum().get()));
    SampledSpectrum after = lights[4].EmissionSpectrum()->Sample(lambda);
    for (int i = 0; i < NSpectrumSamples; ++i) EXPECT_EQ(after[i], before[i]);
}

TEST(Lights, ShadowRaysSkipOnlyTheSampledSphere) {
    // A sphere light (radius 1 at z = 3) and a second sphere (radius 0.5 at z = 6, behind it).
    // Cone samples of the light name its sphere; the shadow ray to such a sample gives the same
    // answer with and without skipping that sphere (the segment never crosses it), a ray right
    // through the light is unoccluded only when the light's sphere is skipped, and a ray
    // through both spheres stays occluded when only the light's is skipped.
    auto scene = LoadSceneFromString(R"(
LookAt 0 0 -1  0 0 0  0 1 0
Camera "orthographic"
Film "rgb" "integer xresolution" [4] "integer yresolution" [4]
WorldBegin
AttributeBegin AreaLightSource "diffuse" Translate 0 0 3 Shape "sphere" "float radius" [1] AttributeEnd
AttributeBegin Translate 0 0 6 Shape "sphere" "float radius" [0.5] AttributeEnd
)", RenderOptions{}, "test.pbrt");
    ASSERT_EQ(scene->lights.size(), 1u);
    const Light &light = scene->lights[0];
    SampledWavelengths lambda = SampledWavelengths::SampleVisible(0.3f);
    SampledSpectrumCache cache;
    RNG rng(7);
    uint32_t id = 0;
    int crossed = 0;
    for (int i = 0; i < 2000; ++i) {
        Point3f p(4 * rng.UniformFloat() - 2, 4 * rng.UniformFloat() - 2, -1 + rng.UniformFloat());
        LightSampleContext ctx{p, Normal3f(0, 0, 0), Vector3f(0, 0, 0)};
        auto ls = light.SampleLi(ctx, Point2f(rng.UniformFloat(), rng.UniformFloat()), lambda, &cache);
        if (!ls) continue;
        ASSERT_NE(ls->unblockingSphere, 0u);
        if (id == 0) id = ls->unblockingSphere;
        ASSERT_EQ(ls->unblockingSphere, id);
        Ray r(p, ls->pLight - p, 1 - 1e-4f);  // as a shadow ray: it stops short of pLight
        bool all = scene->accel->Occluded(r), skipped = scene->accel->Occluded(r, id);
        EXPECT_EQ(all, skipped) << i;
        crossed += all;
    }
    EXPECT_LT(crossed, 20);  // self-occlusion by rounding, if any, is rare
    Ray through(Point3f(0, 0, -1), Vector3f(0, 0, 3.5f), 1);  // ends at z = 2.5, inside the light
    EXPECT_TRUE(scene->accel->Occluded(through));
    EXPECT_FALSE(scene->accel->Occluded(through, id));
    Ray both(Point3f(0, 0, -1), Vector3f(0, 0, 10), 1);  // through the light and the second sphere
    EXPECT_TRUE(scene->accel->Occluded(both, id));
    EXPECT_TRUE(scene->accel->Occluded(both, id + 1000));
}

// Which parameter carries a light's spectrum: the table the Python scene reader's test reads
// too (tests/data/emitter-parameters.csv), so the two implementations of the rule agree.
TEST(Lights, EmissionParameterAsTheSharedTableSays) {
    std::ifstream in(PBRT_EMITTER_PARAMETERS_CSV);
    ASSERT_TRUE(in) << PBRT_EMITTER_PARAMETERS_CSV << " is missing";
    std::string line;
    bool header = false;
    int rows = 0, intensity = 0;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        if (!header) {
            header = true;  // directive,type,parameter
            continue;
        }
        const size_t a = line.find(','), b = line.find(',', a + 1);
        const std::string directive = line.substr(0, a), type = line.substr(a + 1, b - a - 1);
        const std::string parameter = line.substr(b + 1);
        EXPECT_EQ(EmissionParameterName(directive, type), parameter) << line;
        ++rows;
        intensity += parameter == "I";
    }
    EXPECT_GE(rows, 7);
    EXPECT_EQ(intensity, 4);
    // An area light is never an intensity light, whatever its type is called.
    EXPECT_STREQ(EmissionParameterName("AreaLightSource", "point"), "L");
}
