// Tests of the wavelength sampling triples, SampledWavelengths and WavelengthSampler.
#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>
#include <pbrt/wavelengths.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

using namespace pbrt;

namespace {

// A sampling triple under test.
struct Triple {
    std::function<Float(Float)> sample, pdf, invert;
    Float lmin, lmax;
};

Triple Visible() {
    return {SampleVisibleWavelengths, VisibleWavelengthsPDF, InvertVisibleWavelengthsSample, Lambda_min,
            Lambda_max};
}

Triple Uniform(Float lmin, Float lmax) {
    return {[=](Float u) { return SampleUniformWavelengths(u, lmin, lmax); },
            [=](Float l) { return UniformWavelengthsPDF(l, lmin, lmax); },
            [=](Float l) { return InvertUniformWavelengthsSample(l, lmin, lmax); }, lmin, lmax};
}

// Chi-square critical value at significance 1e-4 (Wilson-Hilferty approximation).
double ChiSquareCritical(int dof) {
    const double z = 3.719;  // standard normal quantile for p = 1e-4
    double a = 2.0 / (9 * dof);
    return dof * std::pow(1 - a + z * std::sqrt(a), 3);
}

// The properties every triple must have.
void CheckTriple(const Triple &t, const char *what) {
    // The pdf integrates to 1 over its range (midpoint rule) and is zero outside.
    double integral = 0, h = 0.01;
    for (double l = t.lmin + h / 2; l < t.lmax; l += h) integral += t.pdf(Float(l)) * h;
    EXPECT_NEAR(integral, 1, 1e-4) << what;
    EXPECT_EQ(t.pdf(t.lmin - 1), 0) << what;
    EXPECT_EQ(t.pdf(t.lmax + 1), 0) << what;

    // Round trips: invert(sample(u)) = u and sample(invert(lambda)) = lambda.
    for (int i = 0; i <= 1000; ++i) {
        Float u = i / 1000.f;
        Float l = t.sample(u);
        EXPECT_GE(l, t.lmin) << what;
        EXPECT_LE(l, t.lmax) << what;
        EXPECT_NEAR(t.invert(l), u, 2e-5) << what << " u " << u;
        Float lambda = t.lmin + (t.lmax - t.lmin) * u;
        EXPECT_NEAR(t.sample(t.invert(lambda)), lambda, 5e-3) << what << " lambda " << lambda;
    }
    // The inverse is the CDF, whose derivative is the pdf.
    for (Float l = t.lmin + 1; l < t.lmax - 1; l += 7) {
        double dcdf = (double(t.invert(l + 0.5f)) - double(t.invert(l - 0.5f))) / 1.0;
        EXPECT_NEAR(dcdf / t.pdf(l), 1, 2e-3) << what << " at " << l;
    }

    // Chi-square: histogram of samples against the pdf's bin probabilities.
    const int nBins = 47, n = 200000;
    std::vector<int> counts(nBins, 0);
    std::mt19937 rng(11);
    std::uniform_real_distribution<Float> u01(0, 1);
    Float width = (t.lmax - t.lmin) / nBins;
    for (int i = 0; i < n; ++i) {
        int b = std::min(nBins - 1, int((t.sample(u01(rng)) - t.lmin) / width));
        ++counts[b];
    }
    double chi2 = 0;
    for (int b = 0; b < nBins; ++b) {
        double p = double(t.invert(t.lmin + (b + 1) * width)) - double(t.invert(t.lmin + b * width));
        double expected = n * p;
        chi2 += (counts[b] - expected) * (counts[b] - expected) / expected;
    }
    EXPECT_LT(chi2, ChiSquareCritical(nBins - 1)) << what;
}

// Integral of f over [a, b] (midpoint rule, 0.01 nm).
double Integrate(const std::function<double(double)> &f, double a, double b) {
    double sum = 0, h = 0.01;
    for (double l = a + h / 2; l < b; l += h) sum += f(l) * h;
    return sum;
}

// A test integrand: ybar times a 3000 K blackbody times a line-rich modulation.
double TestIntegrand(double l) {
    static BlackbodySpectrum bb(3000);
    return Spectra::Y()(Float(l)) * bb(Float(l)) * (1.2 + std::sin(l / 3));
}

// Mean and standard error of the per-path estimate (1/4) sum_i f(lambda_i) / pdf_i.
std::pair<double, double> Estimate(const std::function<SampledWavelengths(Float, Float)> &draw, int n,
                                   unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Float> u01(0, 1);
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        Float u = u01(rng), u2 = u01(rng);
        SampledWavelengths lambda = draw(u, u2);
        SampledSpectrum f;
        for (int j = 0; j < NSpectrumSamples; ++j) f[j] = Float(TestIntegrand(lambda[j]));
        double est = SafeDiv(f, lambda.PDF()).Average();
        sum += est;
        sum2 += est * est;
    }
    double mean = sum / n;
    return {mean, std::sqrt((sum2 / n - mean * mean) / (n - 1))};
}

}  // namespace

TEST(VisibleWavelengths, Triple) { CheckTriple(Visible(), "visible"); }

TEST(VisibleWavelengths, MatchesPbrtV4Constants) {
    // pbrt-v4 writes the density as 0.0039398042 / cosh^2(0.0072 (lambda - 538)) and the
    // sample as 538 - 138.888889 atanh(0.85691062 - 1.82750197 u).
    EXPECT_NEAR(VisibleWavelengthsPDF(538), 0.0039398042, 1e-9);
    EXPECT_NEAR(VisibleWavelengthsPDF(450), 0.0039398042 / std::pow(std::cosh(0.0072 * (450 - 538)), 2), 1e-9);
    for (Float u : {0.f, 0.1f, 0.5f, 0.77f, 1.f})
        EXPECT_NEAR(SampleVisibleWavelengths(u), 538 - 138.888889 * std::atanh(0.85691062 - 1.82750197 * u), 2e-3)
            << u;
}

TEST(UniformWavelengths, Triple) {
    CheckTriple(Uniform(360, 830), "uniform 360-830");
    CheckTriple(Uniform(380, 780), "uniform 380-780");
}

TEST(SampledWavelengths, VisibleIsStratified) {
    for (Float u : {0.01f, 0.13f, 0.62f, 0.9999f}) {  // (off the quarter boundaries)
        SampledWavelengths w = SampledWavelengths::SampleVisible(u);
        std::vector<bool> quarter(4, false);
        for (int i = 0; i < NSpectrumSamples; ++i) {
            Float up = std::fmod(u + i / 4.f, 1.f);
            EXPECT_FLOAT_EQ(w[i], SampleVisibleWavelengths(up)) << u << " " << i;
            EXPECT_FLOAT_EQ(w.PDF()[i], VisibleWavelengthsPDF(w[i]));
            quarter[std::min(3, int(4 * InvertVisibleWavelengthsSample(w[i])))] = true;
        }
        for (int q = 0; q < 4; ++q) EXPECT_TRUE(quarter[q]) << "no wavelength in CDF quarter " << q;
    }
}

TEST(SampledWavelengths, UniformIsStratified) {
    SampledWavelengths w = SampledWavelengths::SampleUniform(0.3f, 380, 780);
    const Float expected[4] = {500, 600, 700, 400};
    for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(w[i], expected[i], 1e-3) << i;
        EXPECT_FLOAT_EQ(w.PDF()[i], 1.f / 400);
    }
    EXPECT_THROW(SampledWavelengths::SampleUniform(0.3f, 700, 400), PbrtError);
    EXPECT_THROW(SampledWavelengths::SampleUniform(0.3f, 0, 400), PbrtError);
    EXPECT_THROW(SampledWavelengths::SampleUniform(0.3f, NAN, 400), PbrtError);
}

TEST(SampledWavelengths, EstimatorsAreUnbiased) {
    const int n = 40000;
    double exact = Integrate(TestIntegrand, 360, 830);
    auto [visible, seVisible] = Estimate([](Float u, Float) { return SampledWavelengths::SampleVisible(u); }, n, 1);
    auto [uniform, seUniform] =
        Estimate([](Float u, Float) { return SampledWavelengths::SampleUniform(u, 360, 830); }, n, 2);
    EXPECT_LT(std::abs(visible - exact), 4 * seVisible) << visible << " vs " << exact;
    EXPECT_LT(std::abs(uniform - exact), 4 * seUniform) << uniform << " vs " << exact;
    // Uniform on a sub-range integrates over that range only.
    double exact2 = Integrate(TestIntegrand, 380, 780);
    auto [sub, seSub] = Estimate([](Float u, Float) { return SampledWavelengths::SampleUniform(u, 380, 780); }, n, 3);
    EXPECT_LT(std::abs(sub - exact2), 4 * seSub) << sub << " vs " << exact2;
}

TEST(SampledWavelengths, TerminateSecondaryKeepsOneWavelength) {
    SampledWavelengths w = SampledWavelengths::SampleVisible(0.4f);
    SampledWavelengths t = w;
    EXPECT_FALSE(t.SecondaryTerminated());
    t.TerminateSecondary(0.6f);  // slot 2
    EXPECT_TRUE(t.SecondaryTerminated());
    EXPECT_EQ(t.SurvivingIndex(), 2);
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(t[i], w[2]) << i;
        EXPECT_EQ(t.PDF()[i], i == 2 ? w.PDF()[2] / 4 : 0) << i;
    }
    // A second call changes nothing.
    SampledWavelengths again = t;
    again.TerminateSecondary(0.1f);
    EXPECT_EQ(again, t);
}

TEST(SampledWavelengths, TerminateSecondaryIsUnbiased) {
    // Exactly: averaged over the four equally likely choices, the terminated estimate equals
    // the full one, for any values in the slots.
    SampledWavelengths w = SampledWavelengths::SampleVisible(0.77f);
    SampledSpectrum L(std::array<Float, 4>{0.3f, 2.0f, 0.7f, 1.1f});
    double full = SafeDiv(L, w.PDF()).Average(), avg = 0;
    for (int k = 0; k < 4; ++k) {
        SampledWavelengths t = w;
        t.TerminateSecondary((k + 0.5f) / 4);
        avg += SafeDiv(L, t.PDF()).Average() / 4;
    }
    EXPECT_NEAR(avg / full, 1, 1e-6);

    // By Monte Carlo for a mixture of four different densities (as a wavelength table gives,
    // design §1): keeping a uniformly chosen wavelength is unbiased, always keeping the
    // first one is not.
    Triple dens[4] = {Uniform(360, 830), Visible(), Uniform(400, 700), Uniform(500, 600)};
    auto mixture = [&](Float u, SampledWavelengths *out) {
        Float lambda[4], pdf[4];
        for (int j = 0; j < 4; ++j) lambda[j] = dens[j].sample(u);
        for (int j = 0; j < 4; ++j) {
            pdf[j] = 0;
            for (int k = 0; k < 4; ++k) pdf[j] += dens[k].pdf(lambda[j]) / 4;
        }
        *out = SampledWavelengths::FromArrays(lambda, pdf);
    };
    const int n = 60000;
    double exact = Integrate(TestIntegrand, 360, 830);
    auto [untouched, se0] = Estimate([&](Float u, Float) { SampledWavelengths w; mixture(u, &w); return w; }, n, 4);
    auto [random, se1] = Estimate(
        [&](Float u, Float u2) { SampledWavelengths w; mixture(u, &w); w.TerminateSecondary(u2); return w; }, n, 5);
    auto [first, se2] = Estimate(
        [&](Float u, Float) { SampledWavelengths w; mixture(u, &w); w.TerminateSecondary(0); return w; }, n, 6);
    EXPECT_LT(std::abs(untouched - exact), 4 * se0) << untouched << " vs " << exact;
    EXPECT_LT(std::abs(random - exact), 4 * se1) << random << " vs " << exact;
    EXPECT_GT(std::abs(first - exact), 10 * se2) << "keeping slot 0 should be biased: " << first << " vs " << exact;
}

TEST(WavelengthSampler, SeamDelegatesToTheSamplers) {
    WavelengthSampler visible = WavelengthSampler::Visible();
    WavelengthSampler uniform = WavelengthSampler::Uniform(380, 780);
    for (Float u : {0.f, 0.25f, 0.6f}) {
        EXPECT_EQ(visible.Sample(u), SampledWavelengths::SampleVisible(u));
        EXPECT_EQ(uniform.Sample(u), SampledWavelengths::SampleUniform(u, 380, 780));
    }
    EXPECT_EQ(visible.PDF(538), VisibleWavelengthsPDF(538));
    EXPECT_EQ(uniform.PDF(500), 1.f / 400);
    EXPECT_EQ(uniform.PDF(370), 0);
    EXPECT_EQ(visible.MinLambda(), 360);
    EXPECT_EQ(visible.MaxLambda(), 830);
    EXPECT_EQ(uniform.MinLambda(), 380);
    EXPECT_EQ(uniform.MaxLambda(), 780);
    EXPECT_NE(visible.Description(), uniform.Description());
    EXPECT_NE(uniform.Description().find("380"), std::string::npos) << uniform.Description();
    EXPECT_THROW(WavelengthSampler::Uniform(780, 380), PbrtError);
    EXPECT_THROW(WavelengthSampler::Uniform(-5, 380), PbrtError);
    EXPECT_THROW(WavelengthSampler::Uniform(380, Infinity), PbrtError);
}

TEST(SampledWavelengths, VisiblePdfFromTheSamplersTanhIsTheDensity) {
    // SampleVisible takes each pdf from the tanh it inverted instead of a cosh of the
    // rounded wavelength: the same density up to that rounding, over the whole range.
    double worst = 0;
    for (int k = 0; k <= 20000; ++k) {
        SampledWavelengths w = SampledWavelengths::SampleVisible(std::min<Float>(k / 20000.f, OneMinusEpsilon));
        for (int i = 0; i < NSpectrumSamples; ++i) {
            ASSERT_GT(w.PDF()[i], 0);
            worst = std::max(worst, std::abs(double(w.PDF()[i]) / VisibleWavelengthsPDF(w[i]) - 1));
        }
    }
    EXPECT_LT(worst, 2e-6);
}
