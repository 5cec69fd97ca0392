// Wavelength guiding (guiding.h, design §1.8): kinds of light, the clustering, the tables'
// defensive mixture, and the guide on small scenes.
#include <pbrt/guiding.h>

#include <pbrt/emission.h>
#include <pbrt/options.h>
#include <pbrt/render.h>
#include <pbrt/scene.h>

#include <wavelength_table.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace pbrt;

namespace {

// A floor seen from above, lit by two quads facing down: lamp A over one half, lamp B over the
// other (which half of the image is which depends on the camera's handedness).
std::string TwoLampScene(const std::string &lampA, const std::string &lampB, int w = 32, int h = 16) {
    return R"(
LookAt 0 10 0  0 0 0  0 0 -1
Camera "orthographic" "float screenwindow" [-2 2 -1 1]
Sampler "independent" "integer pixelsamples" [4]
Integrator "path" "integer maxdepth" [2]
Film "rgb" "integer xresolution" [)" +
           std::to_string(w) + R"(] "integer yresolution" [)" + std::to_string(h) + R"(]
    "string filename" "/no/such/dir/x.exr"
WorldBegin
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Shape "trianglemesh" "point3 P" [-3 0 -2  3 0 -2  3 0 2  -3 0 2] "integer indices" [0 1 2 0 2 3]
AttributeBegin
  AreaLightSource "diffuse" )" +
           lampA + R"(
  Shape "trianglemesh" "point3 P" [-1.6 0.3 -0.2  -1.2 0.3 -0.2  -1.2 0.3 0.2  -1.6 0.3 0.2] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" )" +
           lampB + R"(
  Shape "trianglemesh" "point3 P" [1.2 0.3 -0.2  1.6 0.3 -0.2  1.6 0.3 0.2  1.2 0.3 0.2] "integer indices" [0 1 2 0 2 3]
AttributeEnd
)";
}

const char *kBlue = R"("spectrum L" [360 0 440 0 450 1 460 0 830 0] "float scale" [4])";
const char *kBlueBrighter = R"("spectrum L" [360 0 440 0 450 3 460 0 830 0] "float scale" [9])";
const char *kRed = R"("spectrum L" [360 0 590 0 600 1 610 0 830 0] "float scale" [4])";

std::unique_ptr<Scene> Load(const std::string &text, bool guiding = true) {
    RenderOptions opts;
    opts.outfile = "unused.exr";
    opts.wavelengthGuiding = guiding;
    return LoadSceneFromString(text, opts, "test.pbrt");
}

double MixtureAt(const wavelength_table::Table &t, double l) { return wavelength_table::MixturePdf(t, l); }

}  // namespace

// ---- Kinds ----------------------------------------------------------------------------------

TEST(GuidingKinds, LightsWithSpectraEqualUpToAScaleAreOneKind) {
    auto scene = Load(TwoLampScene(kBlue, kBlueBrighter));
    LightKinds kinds = SceneLightKinds(*scene);
    ASSERT_EQ(kinds.size(), 1u);
    EXPECT_EQ(kinds.lights[0], 4u);  // two triangles per quad
    // Its power is the scene's whole emission.
    EmissionSpectrum e = SceneEmissionSpectrum(*scene);
    ASSERT_EQ(e.lambdas, kinds.lambdas);
    for (size_t i = 0; i < e.values.size(); ++i) EXPECT_NEAR(kinds.power[0][i], e.values[i], 1e-12 * e.values[i] + 1e-300);
}

TEST(GuidingKinds, DifferentSpectraAreDifferentKinds) {
    auto scene = Load(TwoLampScene(kBlue, kRed));
    LightKinds kinds = SceneLightKinds(*scene);
    ASSERT_EQ(kinds.size(), 2u);
    for (size_t l = 0; l < scene->lights.size(); ++l) EXPECT_GE(kinds.kindOfLight[l], 0);
    EXPECT_NE(kinds.kindOfLight.front(), kinds.kindOfLight.back());
    EXPECT_NE(kinds.labels[0].find("test.pbrt:"), std::string::npos) << kinds.labels[0];
    for (double y : kinds.luminance) EXPECT_GT(y, 0);
}

// ---- Clustering -----------------------------------------------------------------------------

namespace {

std::vector<std::vector<double>> Noisy(const std::vector<std::vector<double>> &centres, int each, double noise,
                                       unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-noise, noise);
    std::vector<std::vector<double>> pts;
    for (int i = 0; i < each; ++i)
        for (const auto &c : centres) {
            std::vector<double> p = c;
            double sum = 0;
            for (double &v : p) sum += (v = std::max(0.0, v + u(rng)));
            for (double &v : p) v /= sum;
            pts.push_back(p);
        }
    return pts;
}

}  // namespace

TEST(GuidingClusters, SeparatesClearlyDifferentMixtures) {
    const std::vector<std::vector<double>> truth{{1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0}, {0, 0, 1}};
    auto pts = Noisy(truth, 25, 0.02, 1);
    MixtureClusters c = ClusterMixtures(pts, 8);
    ASSERT_EQ(c.centres.size(), 4u);
    // Points made from the same mixture share a cluster, and no two mixtures share one.
    for (size_t i = 0; i < pts.size(); ++i) EXPECT_EQ(c.assignment[i], c.assignment[i % 4]) << i;
    for (size_t a = 0; a < 4; ++a)
        for (size_t b = a + 1; b < 4; ++b) EXPECT_NE(c.assignment[a], c.assignment[b]);
    for (int n : c.count) EXPECT_EQ(n, 25);
    // Each centre is its mixture's mean, within the noise.
    for (size_t m = 0; m < 4; ++m)
        for (size_t j = 0; j < 3; ++j) EXPECT_NEAR(c.centres[size_t(c.assignment[m])][j], truth[m][j], 0.02);
}

TEST(GuidingClusters, IsDeterministicAndRespectsK) {
    auto pts = Noisy({{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.3, 0.3, 0.4}}, 20, 0.05, 7);
    MixtureClusters a = ClusterMixtures(pts, 3), b = ClusterMixtures(pts, 3);
    EXPECT_EQ(a.assignment, b.assignment);
    EXPECT_EQ(a.centres, b.centres);
    EXPECT_EQ(a.centres.size(), 3u);
    EXPECT_EQ(ClusterMixtures(pts, 1).centres.size(), 1u);
    // Largest first.
    for (size_t i = 1; i < a.count.size(); ++i) EXPECT_GE(a.count[i - 1], a.count[i]);
}

TEST(GuidingClusters, MergesIdenticalAndNearbyMixtures) {
    std::vector<std::vector<double>> same(50, std::vector<double>{0.7, 0.3});
    MixtureClusters c = ClusterMixtures(same, 16);
    ASSERT_EQ(c.centres.size(), 1u);
    EXPECT_EQ(c.count[0], 50);
    // Mixtures closer than the merge distance share a table.
    std::vector<std::vector<double>> near{{0.70, 0.30}, {0.72, 0.28}, {0.69, 0.31}, {0.74, 0.26}};
    EXPECT_EQ(ClusterMixtures(near, 16).centres.size(), 1u);
    // A single-kind scene's mixtures are all {1}.
    EXPECT_EQ(ClusterMixtures(std::vector<std::vector<double>>(9, {1.0}), 8).centres.size(), 1u);
}

TEST(GuidingClusters, RefusesBadInput) {
    EXPECT_THROW(ClusterMixtures({}, 4), PbrtError);
    EXPECT_THROW(ClusterMixtures({{1, 0}, {1}}, 4), PbrtError);
    EXPECT_THROW(ClusterMixtures({{1, 0}}, 0), PbrtError);
}

// ---- Tables ---------------------------------------------------------------------------------

TEST(GuidingTables, StratifiedTableIsTheDefensiveMixtureStratified) {
    auto scene = Load(TwoLampScene(kBlue, kRed));
    LightKinds kinds = SceneLightKinds(*scene);
    const double S = 0.05;
    const std::vector<double> w{1, 0};  // all kind 0
    wavelength_table::Table t = StratifiedGuidedTable(kinds, w, S, "spd");
    const std::vector<double> m = MixtureSpectrum(kinds, w), phi = SceneSpectrum(kinds);
    // The table's mixture is q = (1 - S) m + S phi exactly (design §1.7), and so at least
    // S phi wherever the scene emits: kind 1's line is sampled although the mixture lacks it.
    for (size_t i = 0; i < kinds.lambdas.size(); ++i) {
        double q = (1 - S) * m[i] + S * phi[i];
        EXPECT_NEAR(MixtureAt(t, kinds.lambdas[i]), q, 1e-9 * std::max(q, 1e-3)) << kinds.lambdas[i];
    }
    EXPECT_GT(MixtureAt(t, 600), 0.9 * S * phi[size_t(std::find(kinds.lambdas.begin(), kinds.lambdas.end(), 600.0) -
                                                       kinds.lambdas.begin())]);
    // Each density carries a quarter of the mass (stratified): the cuts lie in the blue line.
    EXPECT_LT(wavelength_table::Sample(t, 0, 0.5), 460);
    EXPECT_LT(wavelength_table::Sample(t, 2, 0.5), 460);
}

TEST(GuidingTables, DefensiveMixtureOfAGivenTable) {
    auto scene = Load(TwoLampScene(kBlue, kRed));
    LightKinds kinds = SceneLightKinds(*scene);
    // A table that samples 440-460 only (as an optimizer's table for the blue mixture might).
    std::array<std::vector<double>, 4> v;
    for (auto &d : v) d = {0, 1, 0};
    wavelength_table::Table opt = wavelength_table::MakeTable({440, 450, 460}, v, "opt");
    const double S = 0.1;
    wavelength_table::Table t = DefensiveGuidedTable(opt, kinds, S);
    const std::vector<double> phi = SceneSpectrum(kinds);
    for (double l : {445.0, 450.0, 455.0, 600.0, 595.0, 500.0, 700.0}) {
        double phiL = wavelength_table::detail::Interp(kinds.lambdas, phi, l, 0, 0);
        EXPECT_NEAR(MixtureAt(t, l), (1 - S) * MixtureAt(opt, l) + S * phiL, 1e-9) << l;
    }
    EXPECT_GT(MixtureAt(t, 600), 0);
    EXPECT_TRUE(wavelength_table::ZeroMixtureIntervals(t).empty() ||
                MixtureAt(t, 600) > 0);  // zero only where no lamp emits
    // Each density takes its own quarter of the defensive mass (design §1.8), not all of phi:
    // outside the given table, density k is S times the k-th equal-mass band of phi, and
    // wherever the scene emits one band alone is positive (two only at a cut's hand-over).
    wavelength_table::Table bands =
        wavelength_table::StratifiedTable(kinds.lambdas, phi, {}, {}, 360, 830, "phi");
    int emitting = 0, single = 0;
    for (double l = 360.25; l < 830; l += 0.5) {
        if (l > 439 && l < 461) continue;
        int positive = 0;
        for (int k = 0; k < 4; ++k) {
            EXPECT_NEAR(wavelength_table::Pdf(t, k, l), S * wavelength_table::Pdf(bands, k, l), 1e-12) << k << " " << l;
            positive += wavelength_table::Pdf(t, k, l) > 0;
        }
        EXPECT_LE(positive, 2) << l;
        emitting += positive > 0;
        single += positive == 1;
    }
    EXPECT_GT(emitting, 0);
    EXPECT_GE(single, emitting - 3);
}

// ---- The guide ------------------------------------------------------------------------------

TEST(Guide, OneKindOfLightIsOneTableExactlyEmissionSampling) {
    auto scene = Load(TwoLampScene(kBlue, kBlueBrighter));
    WavelengthGuide g = BuildWavelengthGuide(*scene, GuidingSettings{}, 1, true);
    ASSERT_EQ(g.tables.size(), 1u);
    EXPECT_EQ(g.prepassPaths, 0u);  // nothing to learn: no pre-pass
    EXPECT_EQ(g.tables[0].table.get(), scene->wavelengths.Table()->table.get());
    // The same image as --wavelength-sampling emission, pixel for pixel.
    Render(*scene, 1, true, 1, {}, &g);
    Image guided = scene->film->GetImage();
    RenderOptions opts;
    opts.outfile = "unused.exr";
    opts.wavelengthSampling = "emission";
    auto em = LoadSceneFromString(TwoLampScene(kBlue, kBlueBrighter), opts, "test.pbrt");
    Render(*em, 1, true);
    EXPECT_EQ(guided.pixels, em->film->GetImage().pixels);
}

TEST(Guide, EachSideGetsItsLampsTableAndTheChoiceIsDeterministic) {
    auto scene = Load(TwoLampScene(kBlue, kRed, 64, 16));
    GuidingSettings s;
    s.prepassShare = 1;
    WavelengthGuide g = BuildWavelengthGuide(*scene, s, 2, true);
    ASSERT_GE(g.tables.size(), 2u);
    ASSERT_EQ(g.tilesX, 8);
    ASSERT_EQ(g.tilesY, 2);
    EXPECT_GT(g.prepassPaths, 0u);
    const int kindBlue = g.kinds.kindOfLight.front();
    // Which side the blue lamp lights is read from the image itself (the camera's handedness
    // decides it), so the guide is checked against what the render shows at each pixel.
    Render(*scene, 1, true);
    const Image img = scene->film->GetImage();
    // The lamps face the floor, out of the camera's sight: a tile's colour is the light that
    // reaches its part of the floor.
    auto blueness = [&](int x) {
        const int x0 = x / g.tile * g.tile;
        double b = 0;
        for (int xi = x0; xi < x0 + g.tile; ++xi)
            for (int y = 0; y < 16; ++y) b += img.Get(xi, y, 2) - img.Get(xi, y, 0);
        return b;
    };
    ASSERT_NE(blueness(2) > 0, blueness(61) > 0) << "one side blue, the other red";
    const int blueX = blueness(2) > 0 ? 2 : 61, redX = 63 - blueX;
    const GuidingTable &blueSide = g.tables[size_t(g.IndexAt({blueX, 8}))], &redSide = g.tables[size_t(g.IndexAt({redX, 8}))];
    EXPECT_GT(blueSide.shares[size_t(kindBlue)], 0.9);
    EXPECT_LT(redSide.shares[size_t(kindBlue)], 0.1);
    // The blue side's table samples mostly the blue line, the red side's the red line.
    EXPECT_GT(wavelength_table::MixturePdf(*blueSide.table, 450), wavelength_table::MixturePdf(*redSide.table, 450));
    EXPECT_GT(wavelength_table::MixturePdf(*redSide.table, 600), wavelength_table::MixturePdf(*blueSide.table, 600));
    // Every table covers both lamps.
    for (const GuidingTable &t : g.tables) {
        EXPECT_GT(wavelength_table::MixturePdf(*t.table, 450), 0);
        EXPECT_GT(wavelength_table::MixturePdf(*t.table, 600), 0);
    }
    // Another thread count, the same guide.
    WavelengthGuide h = BuildWavelengthGuide(*scene, s, 1, true);
    EXPECT_EQ(g.tileIndex, h.tileIndex);
    ASSERT_EQ(g.tables.size(), h.tables.size());
    for (size_t k = 0; k < g.tables.size(); ++k) EXPECT_EQ(g.tables[k].hash, h.tables[k].hash);
    // Memory: the tables and the index map.
    EXPECT_EQ(g.tileIndex.size(), 16u);
    EXPECT_GT(g.MemoryBytes(), 16u);
}

TEST(Guide, MissingOptimizedTablesAreAnError) {
    auto scene = Load(TwoLampScene(kBlue, kRed));
    GuidingSettings s;
    s.tablesDir = "/nonexistent-guiding-tables";
    try {
        BuildWavelengthGuide(*scene, s, 1, true);
        FAIL() << "no error";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("none of the"), std::string::npos) << e.what();
    }
}
