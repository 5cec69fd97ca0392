// Tests of the film sensor (pbrt-v4's "cie1931" sensor): Monte Carlo spectra to RGB.
#include <pbrt/sensor.h>
#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/wavelengths.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

using namespace pbrt;

namespace {

// Mean and standard error of each channel of a per-path RGB estimate.
struct RGBEstimate {
    double mean[3] = {0, 0, 0}, se[3] = {0, 0, 0};
};

RGBEstimate Estimate(const FilmSensor &sensor, const Spectrum &L, const WavelengthSampler &sampler, int n,
                     unsigned seed, bool terminate = false) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Float> u01(0, 1);
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        SampledWavelengths lambda = sampler.Sample(u01(rng));
        Float u2 = u01(rng);
        if (terminate) lambda.TerminateSecondary(u2);
        RGB rgb = sensor.ToOutputRGB(L.Sample(lambda), lambda);
        for (int c = 0; c < 3; ++c) {
            sum[c] += rgb[c];
            sum2[c] += double(rgb[c]) * rgb[c];
        }
    }
    RGBEstimate e;
    for (int c = 0; c < 3; ++c) {
        e.mean[c] = sum[c] / n;
        e.se[c] = std::sqrt(std::max(0.0, sum2[c] / n - e.mean[c] * e.mean[c]) / (n - 1));
    }
    return e;
}

// The sensor's expected output: the integrals of the matching functions times L over
// 360..830 nm (midpoint rule, 0.01 nm), in the output space.
RGB Expected(const FilmSensor &sensor, const Spectrum &L) {
    double xyz[3] = {0, 0, 0}, h = 0.01;
    for (double l = 360 + h / 2; l < 830; l += h) {
        double v = L(Float(l)) * h;
        xyz[0] += Spectra::X()(Float(l)) * v;
        xyz[1] += Spectra::Y()(Float(l)) * v;
        xyz[2] += Spectra::Z()(Float(l)) * v;
    }
    return sensor.OutputSpace()->ToRGB(XYZ(Float(xyz[0]), Float(xyz[1]), Float(xyz[2])) * sensor.ImagingRatio());
}

// A spiky lamp-like spectrum (a fixture of our own): weak continuum plus three 1 nm lines.
SpectrumHandle SpikyLamp() {
    std::vector<Float> v = {360, 0.02f, 435, 0.02f, 435.5f, 3, 436.5f, 3, 437, 0.02f, 545.5f, 0.02f, 546, 5,
                            547, 5,   547.5f, 0.02f, 610.5f, 0.02f, 611, 4, 612, 4, 612.5f, 0.02f, 830, 0.02f};
    return PiecewiseLinearSpectrum::FromInterleaved(v, false);
}

}  // namespace

TEST(FilmSensor, IlluminantOfTheOutputSpaceIsWhite) {
    // The normalized D65 (luminance 1) has Y = CIE_Y_integral with raw CMFs, and sRGB's white.
    FilmSensor sensor(RGBColorSpace::sRGB);
    SpectrumHandle d65 = GetNamedSpectrum("stdillum-D65");
    RGB expected = Expected(sensor, *d65);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(expected[c] / CIE_Y_integral, 1, 2e-4) << c;
    RGBEstimate mc = Estimate(sensor, *d65, WavelengthSampler::Visible(), 20000, 1);
    for (int c = 0; c < 3; ++c)
        EXPECT_LT(std::abs(mc.mean[c] - expected[c]), 4 * mc.se[c]) << c << ": " << mc.mean[c] << " vs " << expected[c];
}

TEST(FilmSensor, VisibleAndUniformSamplingConverge) {
    FilmSensor sensor(RGBColorSpace::sRGB);
    for (SpectrumHandle L : {SpikyLamp(), SpectrumHandle(std::make_shared<BlackbodySpectrum>(2700))}) {
        RGB expected = Expected(sensor, *L);
        RGBEstimate visible = Estimate(sensor, *L, WavelengthSampler::Visible(), 40000, 2);
        RGBEstimate uniform = Estimate(sensor, *L, WavelengthSampler::Uniform(360, 830), 40000, 3);
        for (int c = 0; c < 3; ++c) {
            double se = std::hypot(visible.se[c], uniform.se[c]);
            EXPECT_LT(std::abs(visible.mean[c] - uniform.mean[c]), 4 * se) << L->ToString() << " channel " << c;
            EXPECT_LT(std::abs(visible.mean[c] - expected[c]), 4 * visible.se[c]) << L->ToString() << " channel " << c;
            EXPECT_LT(std::abs(uniform.mean[c] - expected[c]), 4 * uniform.se[c]) << L->ToString() << " channel " << c;
        }
    }
}

TEST(FilmSensor, EmitterNormalizedToOneNitHasYEqualToScale) {
    // pbrt-v4's emitter convention (design §5): L = scale * s / SpectrumToPhotometric(s), with
    // the light's spectrum kept densely sampled (as pbrt-v4's lights keep it). The film then
    // sees Y = scale (up to the half-nanometre bins at 360 and 830 nm, where ybar ~ 0).
    SpectrumHandle s = SpikyLamp();
    const Float scale = 7.5f, k = scale / SpectrumToPhotometric(*s);
    std::vector<Float> v(DenselySampledSpectrum::kNumSamples);
    for (int i = 0; i < DenselySampledSpectrum::kNumSamples; ++i) v[i] = k * (*s)(Lambda_min + i);
    DenselySampledSpectrum L(v);
    FilmSensor sensor(RGBColorSpace::sRGB);
    XYZ expected = RGBColorSpace::sRGB->ToXYZ(Expected(sensor, L));
    EXPECT_NEAR(expected.Y / scale, 1, 1e-5);
    // And the sensor's Monte Carlo estimate of Y is unbiased.
    std::mt19937 rng(4);
    std::uniform_real_distribution<Float> u01(0, 1);
    double sum = 0, sum2 = 0;
    const int n = 40000;
    for (int i = 0; i < n; ++i) {
        SampledWavelengths lambda = SampledWavelengths::SampleVisible(u01(rng));
        double y = sensor.ToXYZ(L.Sample(lambda), lambda).Y;
        sum += y;
        sum2 += y * y;
    }
    double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / (n - 1));
    EXPECT_LT(std::abs(mean - expected.Y), 4 * se) << mean << " vs " << expected.Y;
}

TEST(FilmSensor, ZeroPdfEntriesContributeNothing) {
    FilmSensor sensor(RGBColorSpace::sRGB);
    const Float lambda[4] = {450, 550, 600, 650}, pdf[4] = {0.01f, 0, 0.02f, 0};
    SampledWavelengths w = SampledWavelengths::FromArrays(lambda, pdf);
    SampledSpectrum L(std::array<Float, 4>{1, 1000, 2, NAN});
    XYZ xyz = sensor.ToXYZ(L, w);
    double y = (Spectra::Y()(450) * 1 / 0.01 + Spectra::Y()(600) * 2 / 0.02) / 4;
    EXPECT_NEAR(xyz.Y / y, 1, 1e-6);
    EXPECT_FALSE(std::isnan(xyz.X) || std::isnan(xyz.Y) || std::isnan(xyz.Z));
}

TEST(FilmSensor, ImagingRatioScales) {
    FilmSensor one(RGBColorSpace::sRGB), two(RGBColorSpace::sRGB, 2);
    SampledWavelengths w = SampledWavelengths::SampleVisible(0.3f);
    SampledSpectrum L = GetNamedSpectrum("stdillum-A")->Sample(w);
    RGB a = one.ToOutputRGB(L, w), b = two.ToOutputRGB(L, w);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c], 2 * a[c], 1e-5f * std::abs(a[c])) << c;
    EXPECT_THROW(FilmSensor(nullptr), PbrtError);
}

TEST(FilmSensor, OutputSpaceChangesOnlyTheBasis) {
    // The same radiance in two output spaces: one RGB is the other's conversion.
    FilmSensor srgb(RGBColorSpace::sRGB), aces(RGBColorSpace::ACES2065_1);
    SampledWavelengths w = SampledWavelengths::SampleVisible(0.71f);
    SampledSpectrum L = SpikyLamp()->Sample(w);
    RGB a = srgb.ToOutputRGB(L, w), b = aces.ToOutputRGB(L, w);
    RGB converted = RGBColorSpace::ACES2065_1->ToRGB(RGBColorSpace::sRGB->ToXYZ(a));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c], converted[c], 1e-4f * std::max<Float>(1, std::abs(b[c]))) << c;
}

TEST(FilmSensor, TerminatedWavelengthsStayUnbiased) {
    FilmSensor sensor(RGBColorSpace::sRGB);
    SpectrumHandle L = SpikyLamp();
    RGB expected = Expected(sensor, *L);
    RGBEstimate t = Estimate(sensor, *L, WavelengthSampler::Visible(), 60000, 5, true);
    for (int c = 0; c < 3; ++c)
        EXPECT_LT(std::abs(t.mean[c] - expected[c]), 4 * t.se[c]) << c << ": " << t.mean[c] << " vs " << expected[c];
}
