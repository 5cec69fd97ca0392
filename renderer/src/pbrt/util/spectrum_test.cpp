// Tests of the spectral representations, named spectra and spectral integrals.
#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

using namespace pbrt;

namespace {

// A file in the test's temporary directory with the given contents.
std::string WriteTempFile(const std::string &name, const std::string &contents) {
    std::string path = ::testing::TempDir() + "/" + name;
    std::ofstream(path) << contents;
    return path;
}

// The message of the PbrtError that f throws ("" if none).
template <typename F>
std::string ErrorOf(F f) {
    try {
        f();
    } catch (const PbrtError &e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(SampledSpectrum, Arithmetic) {
    SampledSpectrum a(std::array<Float, 4>{1, 2, 3, 4}), b(2);
    EXPECT_EQ((a + b)[3], 6);
    EXPECT_EQ((a - b)[0], -1);
    EXPECT_EQ((a * b)[2], 6);
    EXPECT_EQ((a / b)[1], 1);
    EXPECT_EQ((2 * a)[3], 8);
    EXPECT_EQ((-a)[0], -1);
    EXPECT_FLOAT_EQ(a.Average(), 2.5f);
    EXPECT_EQ(a.MaxComponentValue(), 4);
    EXPECT_EQ(a.MinComponentValue(), 1);
    EXPECT_TRUE(a.IsNonZero());
    EXPECT_FALSE(SampledSpectrum(0).IsNonZero());
    // SafeDiv: zero where the denominator is zero.
    SampledSpectrum d(std::array<Float, 4>{2, 0, 4, 0});
    SampledSpectrum q = SafeDiv(a, d);
    EXPECT_EQ(q[0], 0.5f);
    EXPECT_EQ(q[1], 0);
    EXPECT_EQ(q[2], 0.75f);
    EXPECT_EQ(q[3], 0);
    EXPECT_FALSE(q.HasNaNs());
    EXPECT_EQ(ClampZero(-a)[2], 0);
    EXPECT_FLOAT_EQ(Sqrt(a)[3], 2);
    EXPECT_FLOAT_EQ(Exp(SampledSpectrum(0))[0], 1);
    EXPECT_FLOAT_EQ(Lerp(0.25f, a, b)[3], 3.5f);
}

TEST(DenselySampledSpectrum, NearestNanometreLikePbrtV4) {
    BlackbodySpectrum bb(4000);
    DenselySampledSpectrum d(bb);
    for (int l = 360; l <= 830; l += 47) EXPECT_FLOAT_EQ(d(Float(l)), bb(Float(l))) << l;
    EXPECT_FLOAT_EQ(d(500.49f), bb(500));
    EXPECT_FLOAT_EQ(d(500.5f), bb(501));
    EXPECT_FLOAT_EQ(d(359.5f), bb(360));
    EXPECT_EQ(d(359.4f), 0);
    EXPECT_FLOAT_EQ(d(830.4f), bb(830));
    EXPECT_EQ(d(830.5f), 0);
    EXPECT_EQ(d(NAN), 0);
    // So the 1 nm sum of InnerProduct is the integral of the product of two such spectra.
    DenselySampledSpectrum a(*GetNamedSpectrum("stdillum-F7"));
    double integral = 0, h = 0.001;
    for (double l = 359.5 + h / 2; l < 830.5; l += h) integral += double(a(Float(l))) * Spectra::Y()(Float(l)) * h;
    EXPECT_NEAR(integral / InnerProduct(a, Spectra::Y()), 1, 1e-5);
    EXPECT_THROW(DenselySampledSpectrum(std::vector<Float>(10, 1.f)), PbrtError);
}

TEST(PiecewiseLinearSpectrum, InterpolatesAndExtendsLikePbrtV4) {
    auto s = PiecewiseLinearSpectrum::FromInterleaved({400, 1, 500, 3, 600, 2}, false);
    EXPECT_FLOAT_EQ((*s)(400), 1);
    EXPECT_FLOAT_EQ((*s)(450), 2);
    EXPECT_FLOAT_EQ((*s)(575), 2.25f);
    EXPECT_FLOAT_EQ(s->MaxValue(), 3);
    // Extended with the end values to 359 and 831 nm (pbrt-v4), zero beyond.
    EXPECT_FLOAT_EQ((*s)(360), 1);
    EXPECT_FLOAT_EQ((*s)(830), 2);
    EXPECT_EQ((*s)(358), 0);
    EXPECT_EQ((*s)(832), 0);
    // A spectrum that already covers 360..830 nm is not extended.
    auto wide = PiecewiseLinearSpectrum::FromInterleaved({300, 1, 900, 1}, false);
    EXPECT_EQ(wide->Lambdas().size(), 2u);
}

TEST(PiecewiseLinearSpectrum, NormalizeGivesLuminanceOne) {
    auto s = PiecewiseLinearSpectrum::FromInterleaved({380, 5, 550, 40, 700, 0.5f, 780, 8}, true);
    EXPECT_NEAR(SpectrumToPhotometric(*s) / CIE_Y_integral, 1, 1e-5);
    EXPECT_NEAR(SpectrumToXYZ(*s).Y, 1, 1e-5);
}

TEST(PiecewiseLinearSpectrum, BadInputIsAnError) {
    FileLoc loc{"scene.pbrt", 12, 3};
    std::string msg = ErrorOf([&] { PiecewiseLinearSpectrum::FromInterleaved({400, 1, 500}, false, &loc); });
    EXPECT_NE(msg.find("scene.pbrt:12:3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("pairs"), std::string::npos) << msg;
    msg = ErrorOf([] { PiecewiseLinearSpectrum::FromInterleaved({500, 1, 400, 1}, false); });
    EXPECT_NE(msg.find("increase"), std::string::npos) << msg;
    msg = ErrorOf([] { PiecewiseLinearSpectrum::FromInterleaved({400, NAN, 500, 1}, false); });
    EXPECT_NE(msg.find("non-finite"), std::string::npos) << msg;
    EXPECT_THROW(PiecewiseLinearSpectrum::FromInterleaved({}, false), PbrtError);
    // Nothing to normalize: zero inside 360..830 nm.
    msg = ErrorOf([] { PiecewiseLinearSpectrum::FromInterleaved({300, 0, 900, 0}, true); });
    EXPECT_NE(msg.find("normalize"), std::string::npos) << msg;
}

TEST(PiecewiseLinearSpectrum, ReadSPD) {
    std::string path = WriteTempFile("good.spd", "# a lamp\n400 1.5  # blue\n\n500 2.5\n600\t0.5\n");
    auto s = PiecewiseLinearSpectrum::ReadSPD(path);
    EXPECT_FLOAT_EQ((*s)(450), 2);
    EXPECT_FLOAT_EQ((*s)(600), 0.5f);

    std::string bad = WriteTempFile("bad.spd", "400 1\n500 x2\n");
    std::string msg = ErrorOf([&] { PiecewiseLinearSpectrum::ReadSPD(bad); });
    EXPECT_NE(msg.find(bad + ":2:5"), std::string::npos) << msg;
    EXPECT_NE(msg.find("x2"), std::string::npos) << msg;

    std::string odd = WriteTempFile("odd.spd", "400 1\n500 2\n600\n");
    msg = ErrorOf([&] { PiecewiseLinearSpectrum::ReadSPD(odd); });
    EXPECT_NE(msg.find(odd + ":3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("odd"), std::string::npos) << msg;

    std::string order = WriteTempFile("order.spd", "400 1\n500 2\n450 2\n");
    msg = ErrorOf([&] { PiecewiseLinearSpectrum::ReadSPD(order); });
    EXPECT_NE(msg.find(order + ":3:1"), std::string::npos) << msg;

    std::string empty = WriteTempFile("empty.spd", "# nothing\n");
    EXPECT_THROW(PiecewiseLinearSpectrum::ReadSPD(empty), PbrtError);
    msg = ErrorOf([] { PiecewiseLinearSpectrum::ReadSPD("/nonexistent/lamp.spd"); });
    EXPECT_NE(msg.find("/nonexistent/lamp.spd"), std::string::npos) << msg;
}

TEST(Blackbody, PeakIsOneAtWiensWavelength) {
    const double b = 2.897771955e-3;  // Wien's displacement constant, m K (CODATA 2018)
    for (Float T : {2000.f, 3200.f, 5000.f, 6500.f, 9000.f}) {
        BlackbodySpectrum bb(T);
        Float peak = Float(b / T * 1e9);
        EXPECT_NEAR(bb(peak), 1, 1e-5) << T;
        // The maximum over a fine scan sits at the peak (Wien's law). The peak is flat, so
        // single precision locates it to a few 1e-4 relative.
        Float best = 0, argmax = 0;
        for (int i = 0; i < 58000; ++i) {
            Float l = 100 + 0.05f * i;
            if (bb(l) > best) { best = bb(l); argmax = l; }
        }
        EXPECT_NEAR(argmax / peak, 1, 3e-4) << T;
        EXPECT_LT(bb(peak * 0.99f), 1) << T;
        EXPECT_LT(bb(peak * 1.01f), 1) << T;
        EXPECT_LE(best, 1 + 1e-5f) << T;
        EXPECT_EQ(bb.MaxValue(), 1);
    }
    EXPECT_THROW(BlackbodySpectrum(0), PbrtError);
    EXPECT_THROW(BlackbodySpectrum(-100), PbrtError);
    EXPECT_EQ(Blackbody(500, 0), 0);
}

TEST(Blackbody, StefanBoltzmann) {
    // pi * integral of Planck's radiance over all wavelengths = sigma T^4.
    const double sigma = 5.670374419e-8;  // W m^-2 K^-4 (CODATA 2018)
    for (Float T : {1500.f, 6000.f}) {
        double sum = 0, dl = 0.5;  // nm
        for (double l = 10 + dl / 2; l < 200000; l += dl) sum += Blackbody(Float(l), T) * dl * 1e-9;
        EXPECT_NEAR(Pi * sum / (sigma * std::pow(double(T), 4)), 1, 1e-3) << T;
    }
}

TEST(RGBSigmoidPolynomial, MaxValueBoundsTheSpectrum) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<Float> u(-20, 20);
    for (int i = 0; i < 200; ++i) {
        RGBSigmoidPolynomial p{u(rng), u(rng), u(rng)};
        Float scan = 0;
        for (Float l = 360; l <= 830; l += 0.25f) scan = std::max(scan, p(l));
        EXPECT_NEAR(p.MaxValue(), scan, 1e-4) << p.c0 << " " << p.c1 << " " << p.c2;
    }
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(Infinity), 1);
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(-Infinity), 0);
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(0), 0.5f);
}

// Sample computes the four wavelengths side by side: the values of operator() at each,
// across the whole range of x, the saturated ends (|x| > 1e15) and infinite coefficients.
TEST(RGBSigmoidPolynomial, SampleEqualsPointEvaluation) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<Float> u(0, 1);
    const Float scales[] = {1, 30, 1e6f, 1e17f, Infinity};
    for (Float scale : scales)
        for (int i = 0; i < 300; ++i) {
            RGBSigmoidPolynomial p{scale * (2 * u(rng) - 1), scale * (2 * u(rng) - 1),
                                   scale * (2 * u(rng) - 1)};
            SampledWavelengths lambda = SampledWavelengths::SampleVisible(u(rng));
            SampledSpectrum v = p.Sample(lambda);
            for (int k = 0; k < NSpectrumSamples; ++k) {
                Float expect = p(lambda[k]);
                if (std::isnan(expect)) {
                    EXPECT_TRUE(std::isnan(v[k]));
                    continue;
                }
                // Within 3e-7 (a few ulp of 0.5, where the sigmoid's additions round): a
                // build may fuse the polynomial's multiply-adds differently in the two.
                EXPECT_NEAR(v[k], expect, 3e-7f) << scale << " " << p.c0 << " " << p.c1 << " " << p.c2;
                EXPECT_TRUE(v[k] >= 0 && v[k] <= 1) << v[k];
            }
        }
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(2e15f), 1);
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(-2e15f), 0);
    EXPECT_LT(RGBSigmoidPolynomial::Sigmoid(1e3f), 1);
    EXPECT_TRUE(std::isnan(RGBSigmoidPolynomial::Sigmoid(std::numeric_limits<Float>::quiet_NaN())));
}

TEST(CIE, MatchingFunctionsIntegral) {
    // Our ybar table sums to pbrt-v4's CIE_Y_integral.
    EXPECT_NEAR(InnerProduct(Spectra::Y(), ConstantSpectrum(1)) / CIE_Y_integral, 1, 1e-6);
    // Equal-energy white has chromaticity (1/3, 1/3) (the CMFs' defining property).
    Chromaticity e = SpectrumToXYZ(ConstantSpectrum(1)).xy();
    EXPECT_NEAR(e.x, 1.0 / 3, 2e-4);
    EXPECT_NEAR(e.y, 1.0 / 3, 2e-4);
}

TEST(NamedSpectra, IlluminantsHaveLuminanceOne) {
    std::vector<std::string> names = NamedSpectrumNames();
    for (const char *n : {"stdillum-A", "stdillum-D50", "stdillum-D65", "illum-acesD60", "stdillum-F1",
                          "stdillum-F12"})
        EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
    EXPECT_EQ(names.size(), 16u);
    for (const std::string &n : names) {
        SpectrumHandle s = GetNamedSpectrum(n);
        ASSERT_NE(s, nullptr) << n;
        EXPECT_NEAR(SpectrumToXYZ(*s).Y, 1, 1e-5) << n;
        EXPECT_NEAR(SpectrumToPhotometric(*s), CIE_Y_integral, 1e-3) << n;
    }
    EXPECT_EQ(GetNamedSpectrum("stdillum-D93"), nullptr);
}

TEST(NamedSpectra, ChromaticitiesOfTheStandardIlluminants) {
    // CIE 015:2018 table 3 (2-degree observer) and SMPTE ST 2065-1 for the ACES white.
    struct Case {
        const char *name;
        double x, y, tol;
    } cases[] = {
        {"stdillum-A", 0.44757, 0.40745, 2e-4},  {"stdillum-D50", 0.34567, 0.35850, 2e-4},
        {"stdillum-D65", 0.31271, 0.32902, 2e-4}, {"illum-acesD60", 0.32168, 0.33767, 2e-4},
        {"stdillum-F2", 0.37208, 0.37529, 5e-4},  {"stdillum-F11", 0.38052, 0.37713, 5e-4},
    };
    for (const Case &c : cases) {
        Chromaticity xy = SpectrumToXYZ(*GetNamedSpectrum(c.name)).xy();
        EXPECT_NEAR(xy.x, c.x, c.tol) << c.name;
        EXPECT_NEAR(xy.y, c.y, c.tol) << c.name;
    }
    // The fluorescent tables (380..780 nm) are extended with their end values (pbrt-v4).
    SpectrumHandle f1 = GetNamedSpectrum("stdillum-F1");
    EXPECT_FLOAT_EQ((*f1)(365), (*f1)(380));
    EXPECT_FLOAT_EQ((*f1)(825), (*f1)(780));
}

TEST(SpectrumToPhotometric, RGBIlluminantCountsOnlyItsIlluminant) {
    for (const std::string &n : RGBColorSpace::Names()) {
        const RGBColorSpace &cs = *RGBColorSpace::GetNamed(n);
        Float illum = SpectrumToPhotometric(cs.Illuminant());
        EXPECT_NEAR(illum, CIE_Y_integral, 1e-3) << n;
        for (RGB rgb : {RGB(1, 1, 1), RGB(5, 0.1f, 0.2f), RGB(0, 0, 3)}) {
            RGBIlluminantSpectrum s(cs, rgb);
            EXPECT_EQ(SpectrumToPhotometric(s), illum) << n << " " << rgb.ToString();
        }
        // While its own luminance follows the RGB.
        RGB pink(3, 1.5f, 2);
        RGBIlluminantSpectrum s(cs, pink);
        EXPECT_NEAR(SpectrumToXYZ(s).Y / cs.Luminance(pink), 1, 2e-3) << n;
    }
}

TEST(Spectrum, SampleMatchesPointEvaluation) {
    SampledWavelengths lambda = SampledWavelengths::SampleVisible(0.3f);
    std::vector<SpectrumHandle> spectra = {
        std::make_shared<ConstantSpectrum>(0.7f), std::make_shared<BlackbodySpectrum>(3000),
        GetNamedSpectrum("stdillum-F4"),
        std::make_shared<RGBAlbedoSpectrum>(*RGBColorSpace::sRGB, RGB(0.2f, 0.5f, 0.9f)),
        std::make_shared<RGBUnboundedSpectrum>(*RGBColorSpace::sRGB, RGB(2, 0.5f, 0.9f)),
        std::make_shared<RGBIlluminantSpectrum>(*RGBColorSpace::sRGB, RGB(2, 0.5f, 0.9f))};
    for (const SpectrumHandle &s : spectra) {
        SampledSpectrum v = s->Sample(lambda);
        for (int i = 0; i < NSpectrumSamples; ++i)
            EXPECT_NEAR(v[i], (*s)(lambda[i]), 1e-6f * std::max<Float>(1, v[i])) << s->ToString();
        Float scan = 0;
        for (Float l = 360; l <= 830; l += 0.5f) scan = std::max(scan, (*s)(l));
        EXPECT_GE(s->MaxValue() * (1 + 1e-5f), scan) << s->ToString();
    }
}

TEST(DenselySampledSpectrum, IndexIsTheNearestNanometre) {
    for (Float l = 355; l < 835; l += 0.01f) {
        int expect = (l >= 359.5f && l < 830.5f) ? std::clamp(int(std::lround(l)) - 360, 0, 470) : -1;
        ASSERT_EQ(DenselySampledSpectrum::Index(l), expect) << l;
    }
    for (Float l : {359.5f, 400.5f, 829.5f, std::nextafter(830.5f, 0.f)})
        EXPECT_EQ(DenselySampledSpectrum::Index(l), int(std::lround(l)) - 360) << l;
    EXPECT_EQ(DenselySampledSpectrum::Index(NAN), -1);
}

TEST(SampledSpectrumCache, GivesSampleAndForgetsOnClear) {
    auto a = std::make_shared<BlackbodySpectrum>(3000);
    auto b = std::make_shared<RGBAlbedoSpectrum>(*RGBColorSpace::sRGB, RGB(0.2f, 0.5f, 0.9f));
    std::vector<std::shared_ptr<const Spectrum>> more;
    for (int i = 0; i < 6; ++i) more.push_back(std::make_shared<ConstantSpectrum>(0.1f * i));
    SampledWavelengths l1 = SampledWavelengths::SampleVisible(0.3f), l2 = SampledWavelengths::SampleVisible(0.8f);
    SampledSpectrumCache cache;
    EXPECT_EQ(cache.Get(*a, l1), a->Sample(l1));
    EXPECT_EQ(cache.Get(*b, l1), b->Sample(l1));
    EXPECT_EQ(cache.Get(*a, l1), a->Sample(l1));
    for (auto &s : more) EXPECT_EQ(cache.Get(*s, l1), s->Sample(l1));  // evicts a and b
    EXPECT_EQ(cache.Get(*a, l1), a->Sample(l1));
    cache.Clear();
    EXPECT_EQ(cache.Get(*a, l2), a->Sample(l2));  // new wavelengths after Clear
    EXPECT_EQ(cache.Get(*b, l2), b->Sample(l2));
}
