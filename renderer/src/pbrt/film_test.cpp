// Tests of the spectral film's share of light that kept one wavelength (design §6.8).
#include <pbrt/film.h>
#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>

#include <gtest/gtest.h>

using namespace pbrt;

namespace {

FilmSettings OnePixelSpectral() {
    FilmSettings s;
    s.fullResolution = {1, 1};
    s.pixelBounds = Bounds2i{{0, 0}, {1, 1}};
    s.colorSpace = RGBColorSpace::sRGB;
    s.nBuckets = 4;
    s.lambdaMin = 380;
    s.lambdaMax = 780;
    return s;
}

SampledWavelengths Four() {
    const Float lambda[NSpectrumSamples] = {450, 520, 580, 640};
    const Float pdf[NSpectrumSamples] = {1.f / 400, 1.f / 400, 1.f / 400, 1.f / 400};
    return SampledWavelengths::FromArrays(lambda, pdf);
}

float TerminatedShare(const RGBFilm &film) {
    Image img = film.GetImage();
    EXPECT_EQ(img.channelNames.back(), "wavelengths.terminated");
    EXPECT_EQ(img.channels, 3 + 4 + 1);
    return img.pixels[size_t(img.channels) - 1];
}

}  // namespace

TEST(SpectralFilm, TerminatedShareIsTheLuminanceOfPathsThatKeptOneWavelength) {
    RGBFilm film(OnePixelSpectral(), 1);
    SampledSpectrum L(1.f);
    SampledWavelengths all = Four();
    film.AddSpectralSample({0, 0}, L, all, 1);
    EXPECT_EQ(TerminatedShare(film), 0.f);

    SampledWavelengths one = Four();
    one.TerminateSecondary(0.1f);
    const Float yAll = L.y(all), yOne = L.y(one);
    ASSERT_GT(yAll, 0);
    ASSERT_GT(yOne, 0);
    film.AddSpectralSample({0, 0}, L, one, 2);  // weight 2
    EXPECT_NEAR(TerminatedShare(film), 2 * yOne / (yAll + 2 * yOne), 1e-6);
}

TEST(SpectralFilm, NoLightNoShare) {
    RGBFilm film(OnePixelSpectral(), 1);
    SampledWavelengths one = Four();
    one.TerminateSecondary(0.7f);
    film.AddSpectralSample({0, 0}, SampledSpectrum(0.f), one, 1);
    EXPECT_EQ(TerminatedShare(film), 0.f);
}
