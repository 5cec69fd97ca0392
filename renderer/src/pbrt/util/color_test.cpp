// Tests of colour spaces and of the RGB-to-spectrum tables (RGB -> spectrum -> RGB).
#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace pbrt;

namespace {

const RGBColorSpace *Space(const std::string &name) {
    const RGBColorSpace *cs = RGBColorSpace::GetNamed(name);
    EXPECT_NE(cs, nullptr) << name;
    return cs;
}

// The RGB of a spectrum seen as a reflectance under the colour space's illuminant (the
// renderer's colorimetry: 1 nm sums over 360..830 nm, normalized so that 1 is white).
RGB ReflectanceRGB(const RGBColorSpace &cs, const Spectrum &s) {
    double xyz[3] = {0, 0, 0}, norm = 0;
    for (int l = 360; l <= 830; ++l) {
        double il = cs.Illuminant()(l), v = s(l);
        xyz[0] += Spectra::X()(l) * il * v;
        xyz[1] += Spectra::Y()(l) * il * v;
        xyz[2] += Spectra::Z()(l) * il * v;
        norm += Spectra::Y()(l) * il;
    }
    return cs.ToRGB(XYZ(Float(xyz[0] / norm), Float(xyz[1] / norm), Float(xyz[2] / norm)));
}

// The RGB of an emission spectrum: XYZ = (InnerProduct with the CMFs) / CIE_Y_integral.
RGB EmissionRGB(const RGBColorSpace &cs, const Spectrum &s) { return cs.ToRGB(SpectrumToXYZ(s)); }

Float MaxAbsDiff(const RGB &a, const RGB &b) {
    return std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b)});
}

// Colours of a cube grid plus random ones, all in [0, 1]^3.
std::vector<RGB> TestColors(int grid, int nRandom, unsigned seed) {
    std::vector<RGB> colors;
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j)
            for (int k = 0; k < grid; ++k)
                colors.emplace_back(Float(i) / (grid - 1), Float(j) / (grid - 1), Float(k) / (grid - 1));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Float> u(0, 1);
    for (int n = 0; n < nRandom; ++n) colors.emplace_back(u(rng), u(rng), u(rng));
    return colors;
}

}  // namespace

TEST(ColorSpace, NamedLookup) {
    EXPECT_EQ(RGBColorSpace::GetNamed("srgb"), RGBColorSpace::sRGB);
    EXPECT_EQ(RGBColorSpace::GetNamed("sRGB"), RGBColorSpace::sRGB);
    EXPECT_EQ(RGBColorSpace::GetNamed("dci-p3"), RGBColorSpace::DCI_P3);
    EXPECT_EQ(RGBColorSpace::GetNamed("rec2020"), RGBColorSpace::Rec2020);
    EXPECT_EQ(RGBColorSpace::GetNamed("aces2065-1"), RGBColorSpace::ACES2065_1);
    EXPECT_EQ(RGBColorSpace::GetNamed("adobe-rgb"), nullptr);
    EXPECT_EQ(RGBColorSpace::Names().size(), 4u);
    for (const std::string &n : RGBColorSpace::Names()) {
        ASSERT_NE(RGBColorSpace::GetNamed(n), nullptr) << n;
        EXPECT_TRUE(RGBColorSpace::GetNamed(n)->HasSpectrumTable()) << n;
    }
}

TEST(ColorMatrix, InverseAndProduct) {
    ColorMatrix3 m;
    double v[3][3] = {{0.4, 0.3, 0.2}, {0.2, 0.7, 0.1}, {0.02, 0.1, 0.9}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m.m[i][j] = v[i][j];
    auto inv = m.Inverse();
    ASSERT_TRUE(inv.has_value());
    ColorMatrix3 id = m * *inv;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(id.m[i][j], i == j ? 1 : 0, 1e-12) << i << "," << j;
    ColorMatrix3 singular;
    singular.m[2][0] = singular.m[0][0];
    singular.m[2][1] = singular.m[0][1];
    singular.m[2][2] = singular.m[0][2];
    EXPECT_FALSE(singular.Inverse().has_value());
}

TEST(ColorSpace, WhiteAndPrimaries) {
    for (const std::string &n : RGBColorSpace::Names()) {
        const RGBColorSpace &cs = *Space(n);
        // RGB (1,1,1) is the illuminant's chromaticity at Y = 1 ...
        XYZ white = cs.ToXYZ(RGB(1, 1, 1));
        Chromaticity illum = SpectrumToXYZ(cs.Illuminant()).xy();
        EXPECT_NEAR(white.Y, 1, 1e-6) << n;
        EXPECT_NEAR(white.xy().x, illum.x, 1e-6) << n;
        EXPECT_NEAR(white.xy().y, illum.y, 1e-6) << n;
        // ... and the illuminant itself (luminance 1) maps to RGB (1,1,1).
        EXPECT_LT(MaxAbsDiff(EmissionRGB(cs, cs.Illuminant()), RGB(1, 1, 1)), 2e-6) << n;
        // Each primary has its chromaticity.
        const Chromaticity prim[3] = {cs.r, cs.g, cs.b};
        for (int c = 0; c < 3; ++c) {
            RGB rgb;
            rgb[c] = 1;
            Chromaticity xy = cs.ToXYZ(rgb).xy();
            EXPECT_NEAR(xy.x, prim[c].x, 1e-6) << n << " primary " << c;
            EXPECT_NEAR(xy.y, prim[c].y, 1e-6) << n << " primary " << c;
        }
        // RGB -> XYZ -> RGB is the identity.
        RGB rgb(0.3f, 1.7f, 0.05f);
        EXPECT_LT(MaxAbsDiff(cs.ToRGB(cs.ToXYZ(rgb)), rgb), 1e-6) << n;
    }
}

TEST(ColorSpace, LuminanceCoefficientsMatchStandards) {
    // The Y row of RGB -> XYZ as the standards publish it (from their nominal white points;
    // ours come from the illuminant spectra, which sit within 1e-4 in xy of them).
    struct Case {
        const char *name;
        double y[3];
    } cases[] = {
        {"srgb", {0.2126, 0.7152, 0.0722}},                // ITU-R BT.709
        {"rec2020", {0.2627, 0.6780, 0.0593}},             // ITU-R BT.2020
        {"dci-p3", {0.2289746, 0.6917385, 0.0792869}},     // P3 primaries, D65 white
        {"aces2065-1", {0.3439664, 0.7281661, -0.0721325}},  // SMPTE ST 2065-1
    };
    for (const Case &c : cases) {
        const RGBColorSpace &cs = *Space(c.name);
        for (int j = 0; j < 3; ++j)
            EXPECT_NEAR(cs.XYZFromRGB.m[1][j], c.y[j], 1e-3) << c.name << " column " << j;
    }
}

TEST(ColorSpace, ConvertBetweenSpaces) {
    ColorMatrix3 m = ConvertRGBColorSpace(*RGBColorSpace::sRGB, *RGBColorSpace::Rec2020);
    RGB srgb(0.8f, 0.2f, 0.4f);
    double out[3];
    m.Apply(srgb.r, srgb.g, srgb.b, out);
    RGB direct = RGBColorSpace::Rec2020->ToRGB(RGBColorSpace::sRGB->ToXYZ(srgb));
    EXPECT_LT(MaxAbsDiff(RGB(Float(out[0]), Float(out[1]), Float(out[2])), direct), 1e-6);
    // sRGB lies inside Rec. 2020, so its colours have non-negative Rec. 2020 components.
    EXPECT_GT(out[0], 0);
    EXPECT_GT(out[1], 0);
    EXPECT_GT(out[2], 0);
}

TEST(RGBToSpectrumTable, ZNodesIncreaseFromBlackToWhite) {
    EXPECT_EQ(RGBToSpectrumTable::ZNode(0), 0);
    EXPECT_EQ(RGBToSpectrumTable::ZNode(RGBToSpectrumTable::kRes - 1), 1);
    for (int k = 1; k < RGBToSpectrumTable::kRes; ++k)
        EXPECT_LT(float(RGBToSpectrumTable::ZNode(k - 1)), float(RGBToSpectrumTable::ZNode(k))) << k;
    // Tiny and huge arguments of the sigmoid stay in [0, 1].
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(-1e30f), 0);
    EXPECT_EQ(RGBSigmoidPolynomial::Sigmoid(1e30f), 1);
    RGBSigmoidPolynomial nearlyBlack = RGBColorSpace::sRGB->ToRGBCoeffs(RGB(1e-40f, 1e-40f, 1e-40f));
    EXPECT_LT(nearlyBlack(550), 1e-20f);
}

TEST(RGBToSpectrumTable, GreysAreConstant) {
    for (const std::string &n : RGBColorSpace::Names()) {
        const RGBColorSpace &cs = *Space(n);
        for (Float v : {0.f, 0.001f, 0.18f, 0.5f, 0.9f, 1.f}) {
            RGBSigmoidPolynomial p = cs.ToRGBCoeffs(RGB(v, v, v));
            EXPECT_EQ(p.c0, 0);
            EXPECT_EQ(p.c1, 0);
            for (Float lambda : {360.f, 500.f, 830.f}) EXPECT_NEAR(p(lambda), v, 1e-6) << n << " " << v;
        }
    }
}

TEST(RGBToSpectrumTable, ContinuousAcrossLargestComponentSwitch) {
    // Where the largest component changes, two different tables meet; the spectra must agree.
    const RGBColorSpace &cs = *RGBColorSpace::sRGB;
    for (Float third : {0.05f, 0.3f, 0.6f}) {
        RGBSigmoidPolynomial a = cs.ToRGBCoeffs(RGB(0.7f, 0.7f - 1e-4f, third));
        RGBSigmoidPolynomial b = cs.ToRGBCoeffs(RGB(0.7f - 1e-4f, 0.7f, third));
        for (int l = 360; l <= 830; l += 10) EXPECT_NEAR(a(l), b(l), 2e-3) << "third " << third << " at " << l;
    }
}

TEST(RGBToSpectrumTable, RejectsOutOfRange) {
    EXPECT_THROW(RGBColorSpace::sRGB->ToRGBCoeffs(RGB(1.5f, 0, 0)), PbrtError);
    EXPECT_THROW(RGBColorSpace::sRGB->ToRGBCoeffs(RGB(-0.1f, 0, 0)), PbrtError);
    EXPECT_THROW(RGBAlbedoSpectrum(*RGBColorSpace::sRGB, RGB(0.5f, 1.2f, 0)), PbrtError);
    EXPECT_THROW(RGBUnboundedSpectrum(*RGBColorSpace::sRGB, RGB(0.5f, -1, 0)), PbrtError);
    EXPECT_THROW(RGBIlluminantSpectrum(*RGBColorSpace::sRGB, RGB(NAN, 1, 0)), PbrtError);
}

// RGB -> RGBAlbedoSpectrum -> RGB under the colour space's illuminant, over the whole sRGB
// cube. The error comes from interpolating the 64^3 coefficient grid (the scheme pbrt-v4
// uses); it is largest for bright, nearly grey colours, where the coefficients change fast.
TEST(RGBRoundTrip, AlbedoSRGBWholeCube) {
    const RGBColorSpace &cs = *RGBColorSpace::sRGB;
    Float worst = 0, worstBelow09 = 0;
    RGB worstRGB;
    int above1e3 = 0;
    std::vector<RGB> colors = TestColors(11, 5000, 1);
    for (const RGB &rgb : colors) {
        RGBAlbedoSpectrum s(cs, rgb);
        Float err = MaxAbsDiff(ReflectanceRGB(cs, s), rgb);
        if (err > worst) { worst = err; worstRGB = rgb; }
        if (rgb.MaxComponentValue() <= 0.9f) worstBelow09 = std::max(worstBelow09, err);
        above1e3 += err > 1e-3;
        ASSERT_GE(s.MaxValue(), 0);
        ASSERT_LE(s.MaxValue(), 1);
    }
    std::printf("[ info ] srgb albedo round trip: max |error| %.3g at %s; %.3g for max component "
                "<= 0.9; %d of %zu colours above 1e-3\n",
                worst, worstRGB.ToString().c_str(), worstBelow09, above1e3, colors.size());
    EXPECT_LT(worst, 5e-3) << "worst at " << worstRGB.ToString();
    EXPECT_LT(worstBelow09, 2e-3);
    EXPECT_LT(above1e3, int(colors.size() / 100)) << "more than 1% of colours above 1e-3";
}

// For the wide-gamut spaces only part of the cube is reachable by a reflectance. Colours of
// sRGB reflectances are reachable in the D65 spaces (same illuminant) and, a little
// desaturated and darkened, under ACES's D60 white; they must round-trip.
TEST(RGBRoundTrip, AlbedoWideGamutsOnReachableColors) {
    for (const char *name : {"dci-p3", "rec2020", "aces2065-1"}) {
        const RGBColorSpace &cs = *Space(name);
        Float worst = 0;
        RGB worstRGB;
        int tested = 0;
        for (const RGB &c : TestColors(9, 2000, 2)) {
            // 10% towards grey and 10% darker, then the same colour (XYZ) in this space.
            RGB grey(c.Average(), c.Average(), c.Average());
            RGB srgb = (grey + (c - grey) * 0.9f) * 0.9f;
            RGB rgb = cs.ToRGB(RGBColorSpace::sRGB->ToXYZ(srgb));
            if (rgb.MinComponentValue() < 0 || rgb.MaxComponentValue() > 1) continue;
            ++tested;
            RGBAlbedoSpectrum s(cs, rgb);
            Float err = MaxAbsDiff(ReflectanceRGB(cs, s), rgb);
            if (err > worst) { worst = err; worstRGB = rgb; }
        }
        std::printf("[ info ] %s albedo round trip (%d sRGB colours): max |error| %.3g at %s\n", name,
                    tested, worst, worstRGB.ToString().c_str());
        EXPECT_GT(tested, 2000) << name;
        EXPECT_LT(worst, 2.5e-3) << name << " worst at " << worstRGB.ToString();
    }
}

TEST(RGBRoundTrip, UnboundedAndIlluminant) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<Float> u(0, 1);
    for (const std::string &n : RGBColorSpace::Names()) {
        const RGBColorSpace &cs = *Space(n);
        Float worstU = 0, worstI = 0;
        for (int i = 0; i < 300; ++i) {
            // Unbounded RGBs of sRGB colours, scaled up to 20x: relative error.
            RGB srgb(u(rng), u(rng), u(rng));
            RGB rgb = cs.ToRGB(RGBColorSpace::sRGB->ToXYZ(srgb * 0.95f));
            if (rgb.MinComponentValue() < 0) continue;
            Float scale = 1 + 19 * u(rng);
            rgb = rgb * scale;
            RGBUnboundedSpectrum su(cs, rgb);
            worstU = std::max(worstU, MaxAbsDiff(ReflectanceRGB(cs, su), rgb) / scale);
            // An RGB illuminant: XYZ / CIE_Y_integral gives back the RGB.
            RGBIlluminantSpectrum si(cs, rgb);
            worstI = std::max(worstI, MaxAbsDiff(EmissionRGB(cs, si), rgb) / scale);
        }
        std::printf("[ info ] %s unbounded / illuminant round trip: max relative error %.3g / %.3g\n",
                    n.c_str(), worstU, worstI);
        EXPECT_LT(worstU, 2e-3) << n;
        EXPECT_LT(worstI, 2e-3) << n;
    }
    // Black emits nothing.
    RGBIlluminantSpectrum black(*RGBColorSpace::sRGB, RGB(0, 0, 0));
    EXPECT_EQ(black(550), 0);
    EXPECT_EQ(black.MaxValue(), 0);
}
