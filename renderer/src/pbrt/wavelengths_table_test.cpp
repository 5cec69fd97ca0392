// Table-driven wavelength sampling in the renderer (design §1, §5.2): WavelengthSampler::FromTable
// goes through wavelength_table/include/wavelength_table.h and hands the film the mixture density;
// the scene builder warns when a light emits where the table never samples.
//
// The render tests use a "furnace": a diffuse sphere under a constant spectral sky fills the
// frame; a convex surface sees only the sky, so every pixel's expected XYZ is known exactly:
// scale * sum_lambda cmf * rho * L / photometric(L). Tolerances come from the noise measured
// across pixels (which all share that expectation), and each test also checks that the
// noise is small enough to see a 2% bias, so that it can fail.
#include <pbrt/test_tempdir.h>
#include <pbrt/test_util.h>
#include <pbrt/wavelength_coverage.h>
#include <pbrt/wavelengths.h>

#include <gtest/gtest.h>

#include <wavelength_table.h>

#include <sys/stat.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

// One directory per test process: fixed names in a shared temp folder collide when two
// test runs (two build folders, CI beside a developer) overlap.
const TempDir &TestDir() {
    static TempDir dir;
    return dir;
}

std::string WriteTemp(const std::string &name, const std::string &text) {
    return TestDir().Write("pbrt_wt_" + name, text);
}

// A CSV table on 380..780 nm (5 nm) with densities from a function of (k, lambda).
std::string WriteTable(const std::string &name, const std::function<double(int, double)> &f) {
    std::ostringstream s;
    s << "# test table\nlambda_nm,pdf0,pdf1,pdf2,pdf3\n";
    for (int l = 380; l <= 780; l += 5) {
        s << l;
        for (int k = 0; k < 4; ++k) s << "," << f(k, l);
        s << "\n";
    }
    return WriteTemp(name, s.str());
}

// The mixture has a gap on [450, 500]: all four densities vanish there.
const char *kGapTable =
    "# test table\n"
    "lambda_nm,pdf0,pdf1,pdf2,pdf3\n"
    "380,1,0,2,1\n"
    "450,0,0,0,0\n"
    "500,0,0,0,0\n"
    "600,1,3,1,0.5\n"
    "780,1,1,0,2\n";

// Three 10 nm wide lines at 445, 545 and 610 nm on a weak floor, zero at 380 and 780 nm
// (so nothing is emitted outside the tables' range: table and uniform 380..780 sampling
// estimate the same integral).
const std::vector<Float> kLines = {380, 0, 385, 0.05, 440, 0.05, 445, 3, 450, 0.05, 540, 0.05,
                                   545, 3, 550, 0.05, 605, 0.05, 610, 3,   615, 0.05, 775, 0.05,
                                   780, 0};
const std::vector<Float> kRho = {380, 0.2, 500, 0.9, 600, 0.4, 780, 0.7};
constexpr Float kScale = 2;

std::string Array(const std::vector<Float> &v) {
    std::ostringstream s;
    s << "[";
    for (Float x : v) s << " " << x;
    return s.str() + " ]";
}

std::string Furnace(int spp) {
    return R"(
LookAt 0 0 -4  0 0 0  0 1 0
Camera "perspective" "float fov" [10]
Film "rgb" "integer xresolution" [32] "integer yresolution" [32]
Sampler "sobol" "integer pixelsamples" [)" +
           std::to_string(spp) + R"(]
Integrator "path" "integer maxdepth" [3]
WorldBegin
LightSource "infinite" "spectrum L" )" +
           Array(kLines) + R"( "float scale" [2]
Material "diffuse" "spectrum reflectance" )" +
           Array(kRho) + R"(
Shape "sphere" "float radius" [1]
)";
}

// The expected XYZ of every furnace pixel: the film sums raw CMF * L / pdf (design §5), the sky
// is normalized to 1 nit by its 1 nm luminance sum and multiplied by its scale.
std::array<double, 3> FurnaceXYZ() {
    std::vector<Float> ll, lv, rl, rv;
    for (size_t i = 0; i < kLines.size(); i += 2) ll.push_back(kLines[i]), lv.push_back(kLines[i + 1]);
    for (size_t i = 0; i < kRho.size(); i += 2) rl.push_back(kRho[i]), rv.push_back(kRho[i + 1]);
    PiecewiseLinearSpectrum light(ll, lv), refl(rl, rv);
    std::array<double, 3> xyz = {0, 0, 0};
    const double h = 0.01;  // midpoint rule, fine against the 1 nm CMF steps and 5 nm lines
    for (double l = 380 + h / 2; l < 780; l += h) {
        double e = double(light(Float(l))) * refl(Float(l)) * h;
        xyz[0] += e * Spectra::X()(Float(l));
        xyz[1] += e * Spectra::Y()(Float(l));
        xyz[2] += e * Spectra::Z()(Float(l));
    }
    double norm = kScale / SpectrumToPhotometric(light);
    for (double &c : xyz) c *= norm;
    return xyz;
}

Image RenderFurnace(RenderOptions opts, int spp = 64) {
    opts.seed = 7;
    return RenderString(Furnace(spp), opts);
}

// Image-mean XYZ of a furnace render and its standard error (every pixel has the same
// expected value).
std::array<Stat, 3> Means(const Image &img) {
    return {XYZStat(img, 0), XYZStat(img, 1), XYZStat(img, 2)};
}

// The reference: stratified uniform sampling over the tables' range, 380..780 nm, which
// estimates the same integral as every table without gaps.
const std::array<Stat, 3> &UniformReference();

// Every channel's image mean within 4 standard errors of the uniform reference, with noise
// small enough that a 2% bias would show; and within 0.5% of the analytic value (which
// ignores the renderer's float rounding and ray offsets: about 0.1% here).
void ExpectUnbiased(const Image &img, const std::string &what) {
    const std::array<Stat, 3> &ref = UniformReference();
    std::array<double, 3> expect = FurnaceXYZ();
    for (int c = 0; c < 3; ++c) {
        Stat st = XYZStat(img, c);
        double sigma = std::sqrt(st.stderror * st.stderror + ref[c].stderror * ref[c].stderror);
        EXPECT_LT(std::abs(st.mean - ref[c].mean), 4 * sigma)
            << what << ": XYZ channel " << c << " mean " << st.mean << " uniform " << ref[c].mean
            << " sigma " << sigma;
        EXPECT_LT(sigma, 0.005 * expect[c])
            << what << " channel " << c << ": too noisy to detect a 2% bias";
        EXPECT_LT(std::abs(st.mean - expect[c]), 0.005 * expect[c])
            << what << " channel " << c << ": mean " << st.mean << " analytic " << expect[c];
    }
}

RenderOptions WithTable(const std::string &path, Float share = 0) {
    RenderOptions o;
    o.wavelengthTable = path;
    o.defensiveShare = share;
    return o;
}

const std::array<Stat, 3> &UniformReference() {
    static const std::array<Stat, 3> ref = [] {
        RenderOptions uni;
        uni.wavelengthSampling = "uniform";
        uni.lambdaMin = 380;
        uni.lambdaMax = 780;
        uni.seed = 99;
        return Means(RenderString(Furnace(1024), uni));
    }();
    return ref;
}

}  // namespace

TEST(TableWavelengths, SampleMatchesTheHeaderAndCarriesTheMixtureDensity) {
    std::string path = WriteTemp("gap.csv", kGapTable);
    WavelengthSampler ws = WavelengthSampler::FromTable(path);
    wavelength_table::Table t = wavelength_table::LoadTable(path);
    EXPECT_TRUE(ws.IsTable());
    EXPECT_FALSE(WavelengthSampler::Visible().IsTable());
    EXPECT_EQ(ws.MinLambda(), 380);
    EXPECT_EQ(ws.MaxLambda(), 780);
    EXPECT_NE(ws.Description().find(path), std::string::npos) << ws.Description();
    for (Float u : {0.f, 0.1f, 0.37f, 0.5f, 0.77f, 0.9f, 0.999f}) {
        SampledWavelengths w = ws.Sample(u);
        double lambda[4], pdf[4];
        wavelength_table::SampleFour(t, u, lambda, pdf);
        for (int i = 0; i < NSpectrumSamples; ++i) {
            EXPECT_NEAR(w[i], lambda[i], 1e-4) << "u=" << u << " i=" << i;
            EXPECT_NEAR(w.PDF()[i], pdf[i], 1e-6 * pdf[i]) << "u=" << u << " i=" << i;
            // The mixture density: (1/4) sum_k p_k at the sampled wavelength.
            double mix = 0;
            for (int k = 0; k < 4; ++k) mix += wavelength_table::Pdf(t, k, lambda[i]) / 4;
            EXPECT_NEAR(w.PDF()[i], mix, 1e-5 * mix + 1e-9) << "u=" << u << " i=" << i;
            EXPECT_NEAR(ws.PDF(w[i]), mix, 1e-4 * mix + 1e-9) << "u=" << u;
            // Wavelength i follows density i: F_i(lambda_i) = u.
            EXPECT_NEAR(wavelength_table::Invert(t, i, lambda[i]), u, 1e-6) << "u=" << u;
        }
    }
}

TEST(TableWavelengths, ZeroIntervalsAndTheDefensiveShare) {
    std::string path = WriteTemp("gap2.csv", kGapTable);
    auto gaps = WavelengthSampler::FromTable(path).ZeroDensityIntervals();
    ASSERT_EQ(gaps.size(), 1u);
    EXPECT_EQ(gaps[0].first, 450);
    EXPECT_EQ(gaps[0].second, 500);
    WavelengthSampler d = WavelengthSampler::FromTable(path, 0.05f);
    EXPECT_TRUE(d.ZeroDensityIntervals().empty());
    EXPECT_NEAR(d.PDF(475), 0.05 / 400, 1e-9);
    EXPECT_NE(d.Description().find("defensive share 0.05"), std::string::npos) << d.Description();
    EXPECT_TRUE(WavelengthSampler::Visible().ZeroDensityIntervals().empty());
    EXPECT_THROW(WavelengthSampler::FromTable(path, 1.5f), PbrtError);
    EXPECT_THROW(WavelengthSampler::FromTable(path, -0.1f), PbrtError);
}

TEST(TableWavelengths, BadTablesThrowWithFileLineAndReason) {
    const std::string head = "lambda_nm,pdf0,pdf1,pdf2,pdf3\n380,1,1,1,1\n";
    struct Case {
        std::string name, text;
        int line;
        std::string reason;
    } cases[] = {
        {"nan", head + "390,1,nan,1,1\n", 3, "pdf1 is NaN"},
        {"inf", head + "390,1,1,inf,1\n", 3, "pdf2 is infinite"},
        {"negative", head + "390,1,-2,1,1\n", 3, "pdf1 is negative"},
        {"zero", "lambda_nm,pdf0,pdf1,pdf2,pdf3\n380,1,1,0,1\n390,1,1,0,1\n", 2, "pdf2 is zero everywhere"},
        {"grid", head + "390,1,1,1,1\n385,1,1,1,1\n", 4, "not strictly increasing"},
        {"columns", head + "390,1,1,1\n", 3, "4 columns, expected 5"},
        {"one-node", head, 2, "at least 2 grid nodes"},
        {"wide-ragged", "1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n1,1,1,1,1,1\n", 1, "expected 81"},
        {"text", head + "390,1,one,1,1\n", 3, "cannot parse number"},
    };
    for (const Case &c : cases) {
        std::string path = WriteTemp("bad-" + c.name + ".csv", c.text);
        std::string prefix = path + ":" + std::to_string(c.line) + ": ";
        // Both through the sampler and through the scene builder (what pbrt runs).
        for (int viaScene = 0; viaScene < 2; ++viaScene) {
            try {
                if (viaScene)
                    LoadSceneFromString(Furnace(1), WithTable(path), "test.pbrt");
                else
                    WavelengthSampler::FromTable(path);
                ADD_FAILURE() << c.name << ": the bad table was accepted";
            } catch (const PbrtError &e) {
                std::string what = e.what();
                EXPECT_EQ(what.rfind(prefix, 0), 0u) << c.name << ": " << what;
                EXPECT_NE(what.find(c.reason), std::string::npos) << c.name << ": " << what;
            }
        }
    }
    std::string missing = TestDir().File("pbrt_wt_missing.csv");
    std::remove(missing.c_str());
    try {
        WavelengthSampler::FromTable(missing);
        ADD_FAILURE() << "a missing table was accepted";
    } catch (const PbrtError &e) {
        EXPECT_EQ(std::string(e.what()), missing + ": no such file");
    }
    // A directory, an endless file (a device) and a FIFO nobody writes to: an error before
    // any read, not a hang or exhausted memory (design §2.3: regular files only).
    const std::string fifo = TestDir().File("pbrt_wt_fifo.csv");
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    for (const std::string &notTable : {TestDir().path, std::string("/dev/zero"), fifo}) {
        if (!std::filesystem::exists(notTable)) continue;
        try {
            WavelengthSampler::FromTable(notTable);
            ADD_FAILURE() << notTable << " was accepted as a table";
        } catch (const PbrtError &e) {
            std::string what = e.what();
            EXPECT_EQ(what.rfind(notTable + ": ", 0), 0u) << what;
            EXPECT_TRUE(what.find("is a directory") != std::string::npos ||
                        what.find("not a regular file") != std::string::npos)
                << what;
        }
    }
}

// The edge-case tables every table reader reads alike (tests/data/tables/edge/expected.csv;
// the Python reader and the header are tested on the same files): through the sampler and
// through the scene builder, as pbrt --wavelength-pdf reads them.
TEST(TableWavelengths, EdgeTablesAsEveryReaderReadsThem) {
    const std::string dir = PBRT_EDGE_TABLES_DIR;
    std::ifstream in(dir + "/expected.csv");
    ASSERT_TRUE(in) << dir << "/expected.csv is missing";
    std::string line;
    int cases = 0;
    bool header = false;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        if (!header) {
            header = true;  // file,nodes,line,reason
            continue;
        }
        size_t a = line.find(','), b = line.find(',', a + 1), c = line.find(',', b + 1);
        const std::string file = line.substr(0, a), nodes = line.substr(a + 1, b - a - 1);
        const std::string at = line.substr(b + 1, c - b - 1), reason = line.substr(c + 1);
        const std::string path = dir + "/" + file;
        ++cases;
        if (!nodes.empty()) {
            WavelengthSampler w = WavelengthSampler::FromTable(path);
            EXPECT_NE(w.Description().find("(" + nodes + " nodes"), std::string::npos)
                << file << ": " << w.Description();
            continue;
        }
        try {
            WavelengthSampler::FromTable(path);
            ADD_FAILURE() << file << ": accepted, expected line " << at << ": " << reason;
        } catch (const PbrtError &e) {
            std::string what = e.what();
            EXPECT_EQ(what.rfind(path + ":" + at + ": ", 0), 0u) << what;
            EXPECT_NE(what.find(reason), std::string::npos) << what;
        }
    }
    EXPECT_GE(cases, 20);
}

TEST(TableWavelengths, SubnormalDensitiesRenderUnbiased) {
    // Every density 5e-324 on a grid of 1.3 and 1.2 nm steps: summed in subnormal numbers
    // each segment's area rounded to a whole multiple of 5e-324, the mass came out 20% low,
    // and the image 20% too dark. The table is uniform sampling over 380..780 nm.
    std::ostringstream s;
    s << "lambda_nm,pdf0,pdf1,pdf2,pdf3\n";
    for (int j = 0; j < 160; ++j)
        for (double step : {0.0, 1.3}) s << 380 + 2.5 * j + step << ",5e-324,5e-324,5e-324,5e-324\n";
    s << "780,5e-324,5e-324,5e-324,5e-324\n";
    ExpectUnbiased(RenderFurnace(WithTable(WriteTemp("subnormal.csv", s.str())), 512),
                   "subnormal table");
}

TEST(TableWavelengths, RenderConvergesToTheFurnaceWithAnyTableWithoutGaps) {
    // The reference itself against the analytic value.
    std::array<double, 3> expect = FurnaceXYZ();
    for (int c = 0; c < 3; ++c) {
        EXPECT_LT(std::abs(UniformReference()[c].mean - expect[c]), 0.005 * expect[c]) << "channel " << c;
        EXPECT_LT(UniformReference()[c].stderror, 0.002 * expect[c]) << "channel " << c;
    }
    // Three densities on the lines (on a floor), one flat: what an optimizer would make.
    const double centre[3] = {445, 545, 610};
    std::string peaked = WriteTable("peaked.csv", [&](int k, double l) {
        return k < 3 ? 0.02 + std::exp(-0.5 * std::pow((l - centre[k]) / 4, 2)) : 1.0;
    });
    ExpectUnbiased(RenderFurnace(WithTable(peaked)), "peaked table");
    // All four densities crowded to the blue end, non-zero everywhere.
    std::string lopsided = WriteTable("lopsided.csv", [](int k, double l) {
        return 0.03 + std::exp(-(l - 380) / (60.0 + 10 * k));
    });
    ExpectUnbiased(RenderFurnace(WithTable(lopsided), 256), "lopsided table");
}

TEST(TableWavelengths, TheTableReducesNoiseOnSpikyLight) {
    // The point of the method: with the same spp, a table that follows the lines is less
    // noisy than uniform sampling over the same range (per-pixel spread of Y).
    RenderOptions uni;
    uni.wavelengthSampling = "uniform";
    uni.lambdaMin = 380;
    uni.lambdaMax = 780;
    const double centre[3] = {445, 545, 610};
    std::string peaked = WriteTable("peaked2.csv", [&](int k, double l) {
        return k < 3 ? 0.02 + std::exp(-0.5 * std::pow((l - centre[k]) / 4, 2)) : 1.0;
    });
    double sUni = XYZStat(RenderFurnace(uni), 1).stderror;
    double sTab = XYZStat(RenderFurnace(WithTable(peaked)), 1).stderror;
    EXPECT_LT(sTab, 0.7 * sUni) << "table " << sTab << " uniform " << sUni;
}

TEST(TableWavelengths, AGapOverALineIsBiasedAndWarnedTheDefensiveShareFixesIt) {
    // No density on [530, 625] nm, where two of the three lines are: those are never sampled.
    std::string gap = WriteTable("lopsided-gap.csv", [](int k, double l) {
        return (l >= 530 && l <= 625) ? 0.0 : 0.1 + std::exp(-(l - 380) / (60.0 + 10 * k));
    });
    // The scene builder prints the warning (before rendering).
    ::testing::internal::CaptureStderr();
    std::unique_ptr<Scene> scene = LoadSceneFromString(Furnace(1), WithTable(gap), "test.pbrt");
    std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("warning: test.pbrt:8:"), std::string::npos) << err;
    std::vector<UnsampledEmission> found = FindUnsampledEmission(scene->wavelengths, scene->lights);
    ASSERT_EQ(found.size(), 1u);
    EXPECT_EQ(found[0].loc.filename, "test.pbrt");
    EXPECT_EQ(found[0].loc.line, 8);  // the LightSource line of Furnace()
    ASSERT_EQ(found[0].gaps.size(), 1u);
    EXPECT_EQ(found[0].gaps[0].first, 530);
    EXPECT_EQ(found[0].gaps[0].second, 625);
    EXPECT_GT(found[0].gapLuminanceFraction, 0.3);
    EXPECT_TRUE(found[0].outside.empty());
    std::vector<std::string> warnings = UnsampledEmissionWarnings(scene->wavelengths, scene->lights);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0].rfind("test.pbrt:8:", 0), 0u) << warnings[0];
    EXPECT_NE(warnings[0].find("[530, 625] nm"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("--wavelength-pdf-defensive 0.01"), std::string::npos) << warnings[0];

    // The image misses the two lines: far below the furnace value, beyond the noise.
    Image biased = RenderFurnace(WithTable(gap));
    std::array<double, 3> expect = FurnaceXYZ();
    Stat y = XYZStat(biased, 1);
    EXPECT_LT(y.mean, expect[1] - 10 * y.stderror) << "the gap must bias the image";
    EXPECT_LT(y.mean, 0.8 * expect[1]);

    // With a defensive share: no gap, no warning, and the image converges again (a larger
    // share than the suggested 0.01 keeps the noise of the rarely sampled lines low here).
    std::unique_ptr<Scene> fixed = LoadSceneFromString(Furnace(1), WithTable(gap, 0.01f), "test.pbrt");
    EXPECT_TRUE(UnsampledEmissionWarnings(fixed->wavelengths, fixed->lights).empty());
    ExpectUnbiased(RenderFurnace(WithTable(gap, 0.2f), 1024), "gap table, defensive share 0.2");
}

TEST(TableWavelengths, EmissionOutsideTheTableRange) {
    // A flat sky: the part of its luminance outside the table's range, from the CMFs alone.
    const std::string flat = R"(
WorldBegin
LightSource "infinite" "spectrum L" [300 1 900 1]
Shape "sphere" "float radius" [1]
)";
    // The CMFs are constant on each 1 nm bin [l - 0.5, l + 0.5] (nearest nanometre), so a
    // range with integer ends holds half of each end's bin.
    auto outsideY = [](int lo, int hi) {
        auto sum = [](int a, int b) {
            double s = 0;
            for (int l = a; l <= b; ++l) s += (l == a || l == b ? 0.5 : 1.0) * Spectra::Y()(l);
            return s;
        };
        return 1 - sum(lo, hi) / sum(360, 830);
    };
    // A narrow table (450..650 nm): a large part of the luminance is never sampled.
    std::string narrow = WriteTemp("narrow.csv", "lambda_nm,pdf0,pdf1,pdf2,pdf3\n"
                                                 "450,1,1,1,1\n550,1,2,1,1\n650,1,1,1,1\n");
    std::unique_ptr<Scene> s = LoadSceneFromString(flat, WithTable(narrow), "sky.pbrt");
    auto found = FindUnsampledEmission(s->wavelengths, s->lights);
    ASSERT_EQ(found.size(), 1u);
    EXPECT_TRUE(found[0].gaps.empty());
    ASSERT_EQ(found[0].outside.size(), 2u);
    EXPECT_EQ(found[0].outside[0], std::make_pair(360.0, 450.0));
    EXPECT_EQ(found[0].outside[1], std::make_pair(650.0, 830.0));
    EXPECT_NEAR(found[0].outsideLuminanceFraction, outsideY(450, 650), 1e-4 * outsideY(450, 650));
    EXPECT_GT(found[0].outsideTristimulusFraction, found[0].outsideLuminanceFraction);
    auto warnings = UnsampledEmissionWarnings(s->wavelengths, s->lights);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0].rfind("sky.pbrt:3:", 0), 0u) << warnings[0];
    EXPECT_NE(warnings[0].find("[360, 450] and [650, 830] nm"), std::string::npos) << warnings[0];
    // The defensive share is over the table's range: it does not silence this warning.
    std::unique_ptr<Scene> d = LoadSceneFromString(flat, WithTable(narrow, 0.1f), "sky.pbrt");
    EXPECT_EQ(UnsampledEmissionWarnings(d->wavelengths, d->lights).size(), 1u);

    // The default 380..780 grid under the same flat sky: a fraction far below the
    // threshold, so ordinary scenes stay quiet.
    std::string full = WriteTable("flat.csv", [](int, double) { return 1.0; });
    std::unique_ptr<Scene> f = LoadSceneFromString(flat, WithTable(full), "sky.pbrt");
    found = FindUnsampledEmission(f->wavelengths, f->lights);
    ASSERT_EQ(found.size(), 1u);  // it does emit there ...
    EXPECT_NEAR(found[0].outsideLuminanceFraction, outsideY(380, 780), 1e-3 * outsideY(380, 780));
    EXPECT_LT(found[0].outsideLuminanceFraction, kOutsideLuminanceWarnFraction);
    EXPECT_TRUE(UnsampledEmissionWarnings(f->wavelengths, f->lights).empty());  // ... quietly

    // A built-in sampler's range is chosen on purpose: never a warning.
    RenderOptions uni;
    uni.wavelengthSampling = "uniform";
    uni.lambdaMin = 450;
    uni.lambdaMax = 650;
    std::unique_ptr<Scene> u = LoadSceneFromString(flat, uni, "sky.pbrt");
    EXPECT_TRUE(FindUnsampledEmission(u->wavelengths, u->lights).empty());
}
