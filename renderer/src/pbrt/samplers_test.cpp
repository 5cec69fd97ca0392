// Pixel samplers: stratification properties, determinism and uniformity.
#include <pbrt/samplers.h>

#include <pbrt/util/paramdict.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <set>

using namespace pbrt;

TEST(Sampler, PermutationIsABijection) {
    for (uint32_t n : {1u, 2u, 7u, 16u, 100u, 1000u}) {
        for (uint32_t seed : {0u, 1u, 0xdeadbeefu}) {
            std::set<uint32_t> seen;
            for (uint32_t i = 0; i < n; ++i) {
                uint32_t v = PermutationElement(i, n, seed);
                EXPECT_LT(v, n);
                seen.insert(v);
            }
            EXPECT_EQ(seen.size(), n) << "n=" << n << " seed=" << seed;
        }
    }
}

TEST(Sampler, SobolFirstDimensionsAreNets) {
    // 2^m consecutive points of the first two Sobol' dimensions form a (0, m, 2)-net: every
    // elementary interval of area 2^-m holds exactly one point, also after Owen scrambling.
    const int m = 6, n = 1 << m;
    for (uint32_t seed : {0u, 12345u}) {
        for (int k = 0; k <= m; ++k) {
            std::set<std::pair<uint32_t, uint32_t>> cells;
            for (uint32_t i = 0; i < uint32_t(n); ++i) {
                uint32_t x = seed ? OwenScramble(SobolDim0(i), seed) : SobolDim0(i);
                uint32_t y = seed ? OwenScramble(SobolDim1(i), seed * 7 + 1) : SobolDim1(i);
                uint32_t cx = k ? x >> (32 - k) : 0, cy = (m - k) ? y >> (32 - (m - k)) : 0;
                cells.insert({cx, cy});
            }
            EXPECT_EQ(int(cells.size()), n) << "elementary intervals 2^-" << k << " x 2^-" << (m - k);
        }
    }
}

TEST(Sampler, SobolFirstDimensionIsTheBitReversedIndex) {
    // The radical inverse in base 2, bit by bit (whichever bit reversal the build uses).
    uint32_t i = 0x12345678u;
    for (int k = 0; k < 10000; ++k, i = i * 1664525u + 1013904223u) {
        uint32_t want = 0;
        for (int b = 0; b < 32; ++b) want |= ((i >> b) & 1u) << (31 - b);
        ASSERT_EQ(SobolDim0(i), want) << i;
    }
    EXPECT_EQ(SobolDim0(0), 0u);
    EXPECT_EQ(SobolDim0(1), 0x80000000u);
    EXPECT_EQ(SobolDim0(0xffffffffu), 0xffffffffu);
}

namespace {
// Draws the first few dimensions of every sample of one pixel.
std::vector<std::vector<Float>> Draw(Sampler s, Point2i p, int dims) {
    std::vector<std::vector<Float>> out;
    for (int i = 0; i < s.SamplesPerPixel(); ++i) {
        s.StartPixelSample(p, i);
        std::vector<Float> v;
        for (int d = 0; d < dims; ++d) v.push_back(s.Get1D());
        out.push_back(v);
    }
    return out;
}
}  // namespace

TEST(Sampler, StratifiedAndSobolStratifyEveryDimension) {
    // With n samples per pixel, each 1D dimension has one sample in each of the n strata.
    for (Sampler s : {Sampler(SamplerType::Stratified, 16, 3, 4, 4), Sampler(SamplerType::Sobol, 16, 3)}) {
        auto v = Draw(s, {5, 9}, 12);
        for (int d = 0; d < 12; ++d) {
            std::set<int> strata;
            for (auto &sample : v) {
                ASSERT_GE(sample[d], 0);
                ASSERT_LT(sample[d], 1);
                strata.insert(int(sample[d] * 16));
            }
            EXPECT_EQ(strata.size(), 16u) << s.Description() << " dimension " << d;
        }
    }
}

TEST(Sampler, Stratified2DUsesTheGrid) {
    Sampler s(SamplerType::Stratified, 12, 1, 4, 3);
    std::set<std::pair<int, int>> cells;
    for (int i = 0; i < 12; ++i) {
        s.StartPixelSample({0, 0}, i);
        Point2f u = s.Get2D();
        cells.insert({int(u.x * 4), int(u.y * 3)});
    }
    EXPECT_EQ(cells.size(), 12u);
}

TEST(Sampler, DeterministicAndPixelDependent) {
    for (SamplerType t : {SamplerType::Independent, SamplerType::Stratified, SamplerType::Sobol}) {
        Sampler s(t, 4, 42, 2, 2);
        auto a = Draw(s, {3, 4}, 8), b = Draw(s, {3, 4}, 8), c = Draw(s, {4, 3}, 8);
        EXPECT_EQ(a, b) << "same pixel, same values";
        EXPECT_NE(a, c) << "different pixels, different values";
        auto d = Draw(Sampler(t, 4, 43, 2, 2), {3, 4}, 8);
        EXPECT_NE(a, d) << "different seeds, different values";
    }
}

TEST(Sampler, UniformMeanAndVariance) {
    // Over many pixels the values of any dimension have mean 1/2 and variance 1/12.
    for (SamplerType t : {SamplerType::Independent, SamplerType::Stratified, SamplerType::Sobol}) {
        Sampler s(t, 4, 0, 2, 2);
        double sum = 0, sum2 = 0;
        int n = 0;
        for (int py = 0; py < 50; ++py)
            for (int px = 0; px < 50; ++px)
                for (int i = 0; i < 4; ++i) {
                    s.StartPixelSample({px, py}, i);
                    for (int d = 0; d < 5; ++d) {
                        Float u = s.Get1D();
                        sum += u;
                        sum2 += u * u;
                        ++n;
                    }
                }
        double mean = sum / n, var = sum2 / n - mean * mean;
        EXPECT_NEAR(mean, 0.5, 5 * std::sqrt(1.0 / 12 / n)) << s.Description();
        EXPECT_NEAR(var, 1.0 / 12, 0.005) << s.Description();
    }
}

namespace {
ParsedParameter IntParam(const std::string &name, int v) {
    ParsedParameter p;
    p.type = "integer";
    p.name = name;
    p.ints = {v};
    return p;
}
}  // namespace

TEST(Sampler, CreateAppliesPbrtV4DefaultsAndTheCommandLine) {
    const FileLoc loc{"scene.pbrt", 4, 1};
    Sampler z = Sampler::Create("zsobol", ParameterDictionary(), 0, std::nullopt, std::nullopt, loc);
    EXPECT_EQ(z.Type(), SamplerType::ZSobol);
    EXPECT_EQ(z.GetRandomization(), Randomization::FastOwen);
    EXPECT_EQ(z.SamplesPerPixel(), 16) << "pbrt-v4's default pixelsamples";
    EXPECT_EQ(z.Seed(), 0u);

    // Seed: --seed over the directive's "seed" over Option "seed".
    ParameterDictionary seeded({IntParam("seed", 9), IntParam("pixelsamples", 3)});
    EXPECT_EQ(Sampler::Create("independent", seeded, 5, std::nullopt, std::nullopt, loc).Seed(), 9u);
    EXPECT_EQ(Sampler::Create("independent", seeded, 5, uint64_t(11), std::nullopt, loc).Seed(), 11u);
    EXPECT_EQ(Sampler::Create("independent", ParameterDictionary(), 5, std::nullopt, std::nullopt, loc).Seed(), 5u);
    EXPECT_EQ(Sampler::Create("independent", seeded, 5, std::nullopt, std::nullopt, loc).SamplesPerPixel(), 3);
    EXPECT_EQ(Sampler::Create("halton", seeded, 5, std::nullopt, 8, loc).SamplesPerPixel(), 8) << "--spp wins";

    // Stratified: xsamples x ysamples (4 x 4 by default); --spp as its most square factorization.
    EXPECT_EQ(Sampler::Create("stratified", ParameterDictionary(), 0, std::nullopt, std::nullopt, loc).SamplesPerPixel(), 16);
    for (int n : {1, 7, 12, 36, 40}) {
        Sampler s = Sampler::Create("stratified", ParameterDictionary(), 0, std::nullopt, n, loc);
        EXPECT_EQ(s.Type(), SamplerType::Stratified);
        EXPECT_EQ(s.SamplesPerPixel(), n);
    }

    for (const char *bad : {"lowdiscrepancy", "pixelsamples0"}) {
        try {
            if (std::string(bad) == "pixelsamples0")
                Sampler::Create("sobol", ParameterDictionary({IntParam("pixelsamples", 0)}), 0, std::nullopt,
                                std::nullopt, loc);
            else
                Sampler::Create(bad, ParameterDictionary(), 0, std::nullopt, std::nullopt, loc);
            FAIL() << bad << " accepted";
        } catch (const PbrtError &e) {
            EXPECT_NE(std::string(e.what()).find("scene.pbrt:4"), std::string::npos) << e.what();
        }
    }
}

TEST(Sampler, RNGJumpsEqualAdvance) {
    // The sampler's table of affine jumps gives the states Advance gives, on any stream.
    for (uint64_t seq : {0ull, 1ull, 0x9e3779b97f4a7c15ull}) {
        for (int64_t delta : {int64_t(0), int64_t(1), int64_t(7), int64_t(1) << 20, int64_t(255) << 20,
                              int64_t(65535) << 20, (int64_t(1) << 40) + 12345}) {
            RNG a(seq, 0), b(seq, 0);
            a.Advance(delta);
            b.Advance(RNG::JumpFor(delta));
            for (int k = 0; k < 4; ++k) ASSERT_EQ(a.Uniform32(), b.Uniform32()) << seq << " " << delta;
        }
    }
    // Sample indices beyond the table (none here: spp 4) still advance step by step.
    Sampler s(SamplerType::Independent, 4, 11);
    RNG ref;
    for (int index : {0, 3, 100000}) {
        s.StartPixelSample({5, 6}, index);
        Float u = s.Get1D();
        ref.SetSequence(HashInts({5, 6, 11}), 0);
        ref.Advance(int64_t(index) << 20);
        ASSERT_EQ(u, ref.UniformFloat()) << index;
    }
}

// --- Every sampler a pbrt-v4 scene can name --------------------------------------------
namespace {

const Randomization kAllRandomizations[] = {Randomization::None, Randomization::PermuteDigits,
                                            Randomization::FastOwen, Randomization::Owen};

// Every type with every randomization it has, spp samples per pixel on a res image.
std::vector<Sampler> AllSamplers(int spp, uint64_t seed, Point2i res = {64, 48}) {
    std::vector<Sampler> out;
    out.emplace_back(SamplerType::Independent, spp, seed);
    int div = int(std::sqrt(double(spp)));
    while (spp % div) --div;
    out.emplace_back(SamplerType::Stratified, spp, seed, spp / div, div);
    for (SamplerType t : {SamplerType::Sobol, SamplerType::PaddedSobol, SamplerType::ZSobol, SamplerType::Halton})
        for (Randomization r : kAllRandomizations)
            if (!(t == SamplerType::Halton && r == Randomization::FastOwen)) out.emplace_back(t, spp, seed, r, res);
    out.emplace_back(SamplerType::PMJ02BN, spp, seed, Randomization::None, res);
    return out;
}

bool StartsAtTwo(const Sampler &s) {
    return s.Type() == SamplerType::Halton || s.Type() == SamplerType::PMJ02BN;
}

// The values of a render's pixel sample: film position, wavelength, lens, then a mix of 1D
// and 2D draws as a path takes them.
std::vector<Float> PathValues(Sampler &s, Point2i p, int index) {
    s.StartPixelSample(p, index);
    std::vector<Float> v;
    Point2f f = s.GetPixel2D();
    v.push_back(f.x);
    v.push_back(f.y);
    for (int k = 0; k < 12; ++k) {
        v.push_back(s.Get1D());
        Point2f u = s.Get2D();
        v.push_back(u.x);
        v.push_back(u.y);
    }
    return v;
}

// A point of [0, 1)^2 as 32-bit fractions (exact for floats).
std::array<uint32_t, 2> Fixed(Point2f u) {
    return {uint32_t(double(u.x) * 0x1p32), uint32_t(double(u.y) * 0x1p32)};
}

bool IsNet(const std::vector<std::array<uint32_t, 2>> &pts, int m) {
    for (int k = 0; k <= m; ++k) {
        std::set<std::pair<uint32_t, uint32_t>> cells;
        for (const auto &p : pts) cells.insert({k ? p[0] >> (32 - k) : 0, (m - k) ? p[1] >> (32 - (m - k)) : 0});
        if (cells.size() != pts.size()) return false;
    }
    return true;
}

}  // namespace

TEST(Samplers, ValuesInTheUnitIntervalAndReplayedInAnyOrder) {
    for (int spp : {1, 5, 16}) {
        for (Sampler s : AllSamplers(spp, 17)) {
            // Pixels visited in two orders (threads and tiles may take them in any): the same
            // values, and a sample replayed (--wavelength-repeats) gives its values again.
            const Point2i pixels[] = {{0, 0}, {63, 47}, {5, 9}, {33, 2}};
            std::vector<std::vector<Float>> first;
            for (Point2i p : pixels)
                for (int i = 0; i < s.SamplesPerPixel(); ++i) first.push_back(PathValues(s, p, i));
            for (const auto &v : first)
                for (Float u : v) ASSERT_TRUE(u >= 0 && u < 1) << s.Description() << ": " << u;
            size_t k = first.size();
            for (int pi = 3; pi >= 0; --pi)
                for (int i = s.SamplesPerPixel() - 1; i >= 0; --i) {
                    --k;
                    ASSERT_EQ(PathValues(s, pixels[pi], i), first[k]) << s.Description();
                    ASSERT_EQ(PathValues(s, pixels[pi], i), first[k]) << s.Description() << " replayed";
                }
            // Starting at dimension d gives the values from dimension d on.
            s.StartPixelSample({5, 9}, 0);
            std::vector<Float> seq;
            for (int d = 0; d < 30; ++d) seq.push_back(s.Get1D());
            const int offset = StartsAtTwo(s) ? 2 : 0;
            for (int d : {2, 3, 7, 20}) {
                s.StartPixelSample({5, 9}, 0, d);
                EXPECT_EQ(s.Get1D(), seq[size_t(d - offset)]) << s.Description() << " from dimension " << d;
            }
        }
    }
}

TEST(Samplers, SeedsAndPixelsChangeTheValues) {
    auto a = AllSamplers(16, 1), b = AllSamplers(16, 2);
    for (size_t t = 0; t < a.size(); ++t) {
        if (a[t].Type() == SamplerType::Halton && a[t].GetRandomization() == Randomization::None) continue;
        int sameSeed = 0, samePixel = 0, n = 0;
        for (int i = 0; i < 16; ++i) {
            auto va = PathValues(a[t], {3, 4}, i), vb = PathValues(b[t], {3, 4}, i), vc = PathValues(a[t], {4, 3}, i);
            for (size_t k = 0; k < va.size(); ++k, ++n) {
                sameSeed += va[k] == vb[k];
                samePixel += va[k] == vc[k];
            }
        }
        EXPECT_LT(sameSeed, n / 10) << a[t].Description() << ": different seeds, different values";
        EXPECT_LT(samePixel, n / 10) << a[t].Description() << ": different pixels, different values";
    }
}

TEST(Samplers, EveryDimensionIsStratifiedWithinAPixel) {
    // With n samples per pixel each 1D dimension puts one value in each of the n strata
    // (halton: in its own base, n = 25 for base 5); 2D dimensions of the Sobol' samplers are
    // (0, 4, 2)-nets, and so are pmj02bn's film positions.
    for (Sampler s : AllSamplers(16, 5)) {
        if (s.Type() == SamplerType::Independent || s.Type() == SamplerType::Halton) continue;
        for (Point2i p : {Point2i{0, 0}, Point2i{17, 30}}) {
            std::vector<std::vector<Float>> oneD(10);
            std::vector<std::vector<std::array<uint32_t, 2>>> twoD(6);
            for (int i = 0; i < 16; ++i) {
                s.StartPixelSample(p, i);
                twoD[0].push_back(Fixed(s.GetPixel2D()));
                for (int d = 0; d < 5; ++d) {
                    oneD[size_t(d)].push_back(s.Get1D());
                    twoD[size_t(d + 1)].push_back(Fixed(s.Get2D()));
                }
            }
            for (int d = 0; d < 5; ++d) {
                std::set<int> strata;
                for (Float u : oneD[size_t(d)]) strata.insert(int(u * 16));
                EXPECT_EQ(strata.size(), 16u) << s.Description() << " 1D draw " << d;
            }
            bool sobolLike = s.Type() == SamplerType::Sobol || s.Type() == SamplerType::PaddedSobol ||
                             s.Type() == SamplerType::ZSobol;
            if (sobolLike)
                for (int d = 0; d < 6; ++d) EXPECT_TRUE(IsNet(twoD[size_t(d)], 4)) << s.Description() << " 2D draw " << d;
            if (s.Type() == SamplerType::PMJ02BN) EXPECT_TRUE(IsNet(twoD[0], 4)) << "pmj02bn film positions";
        }
    }
    for (Randomization r : {Randomization::None, Randomization::PermuteDigits, Randomization::Owen}) {
        Sampler h(SamplerType::Halton, 25, 5, r, {64, 48});
        std::set<int> strata;
        for (int i = 0; i < 25; ++i) {
            h.StartPixelSample({7, 8}, i);
            strata.insert(int(h.Get1D() * 25));
        }
        EXPECT_EQ(strata.size(), 25u) << h.Description() << ": base 5 over 25 samples";
    }
}

TEST(Samplers, ZSobolRunsOneSequenceOverTheImage) {
    // All samples of an 8 x 8 image at 4 spp are the z-order sampler's indices 0 ... 255 in
    // some order: each 2D dimension over the whole image is a (0, 8, 2)-net, while one
    // pixel's four samples are a (0, 2, 2)-net.
    for (Randomization r : kAllRandomizations) {
        Sampler s(SamplerType::ZSobol, 4, 9, r, {8, 8});
        std::vector<std::array<uint32_t, 2>> film, lens;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x)
                for (int i = 0; i < 4; ++i) {
                    s.StartPixelSample({x, y}, i);
                    film.push_back(Fixed(s.GetPixel2D()));
                    s.Get1D();
                    lens.push_back(Fixed(s.Get2D()));
                }
        EXPECT_TRUE(IsNet(film, 8)) << RandomizationName(r);
        EXPECT_TRUE(IsNet(lens, 8)) << RandomizationName(r);
    }
}

TEST(Samplers, HaltonFollowsTheImageWideHaltonSequence) {
    // On a 100 x 50 film pixel x takes the first 7 base-2 digits (2^7 = 128 >= 100) and y
    // the first 4 base-3 digits (81 >= 50): sample i of a pixel is point h + i * 128 * 81 of
    // the Halton sequence, h the first index whose digits name the pixel (pixels repeat
    // every 128). Without randomization the values are the radical inverses.
    const uint64_t s0 = 128, s1 = 81, stride = s0 * s1;
    Sampler s(SamplerType::Halton, 8, 0, Randomization::None, {100, 50});
    for (Point2i p : {Point2i{0, 0}, Point2i{99, 49}, Point2i{37, 12}}) {
        uint64_t h = 0;
        while (!(uint64_t(RadicalInverse(2, h) * s0) == uint64_t(p.x) &&
                 uint64_t(RadicalInverse(3, h) * s1 + 1e-9) == uint64_t(p.y))) {
            ++h;
            ASSERT_LT(h, stride);
        }
        for (int i = 0; i < 8; ++i) {
            const uint64_t hi = h + uint64_t(i) * stride;
            s.StartPixelSample(p, i);
            Point2f f = s.GetPixel2D();
            EXPECT_EQ(f.x, Float(RadicalInverse(2, hi >> 7)));
            EXPECT_EQ(f.y, Float(RadicalInverse(3, hi / s1)));
            // The film position's digits continue the pixel's: x = (p.x + f.x) / 128.
            EXPECT_NEAR((p.x + f.x) / s0, RadicalInverse(2, hi), 1e-6);
            EXPECT_EQ(s.Get1D(), Float(RadicalInverse(5, hi)));
            EXPECT_EQ(s.Get1D(), Float(RadicalInverse(7, hi)));
            Point2f u = s.Get2D();
            EXPECT_EQ(u.x, Float(RadicalInverse(11, hi)));
            EXPECT_EQ(u.y, Float(RadicalInverse(13, hi)));
        }
    }
    // Wider images repeat the 128-pixel tile; past the last prime base the dimensions
    // start over at 5.
    Sampler w(SamplerType::Halton, 4, 0, Randomization::PermuteDigits, {300, 300});
    w.StartPixelSample({130, 3}, 2);
    std::vector<Float> a = {w.Get1D(), w.Get1D()};
    w.StartPixelSample({2, 3}, 2);
    EXPECT_EQ((std::vector<Float>{w.Get1D(), w.Get1D()}), a);
    w.StartPixelSample({2, 3}, 2, kHaltonDimensions - 1);
    w.Get1D();
    EXPECT_EQ(w.Get1D(), a[0]) << "dimension 1000 wraps to dimension 2";
}

TEST(Samplers, PMJ02BNMaskStratifiesNeighbouringPixels) {
    // At 1 spp a 1D draw of pmj02bn is its dither mask: over every aligned 2 x 2 (4 x 4)
    // block of pixels the values fall in distinct quarters (sixteenths).
    Sampler s(SamplerType::PMJ02BN, 1, 3, Randomization::None, {64, 64});
    for (int size : {2, 4})
        for (int by = 0; by < 64; by += size)
            for (int bx = 120; bx < 136; bx += size) {
                std::set<int> strata;
                for (int y = by; y < by + size; ++y)
                    for (int x = bx; x < bx + size; ++x) {
                        s.StartPixelSample({x, y}, 0);
                        strata.insert(int(s.Get1D() * size * size));
                    }
                ASSERT_EQ(int(strata.size()), size * size) << "block at " << bx << "," << by;
            }
    // A sample count that is not a power of 4 takes the first points of each pixel.
    Sampler eight(SamplerType::PMJ02BN, 8, 3, Randomization::None, {64, 64});
    std::set<std::array<uint32_t, 2>> seen;
    for (int i = 0; i < 8; ++i) {
        eight.StartPixelSample({1, 1}, i);
        seen.insert(Fixed(eight.GetPixel2D()));
    }
    EXPECT_EQ(seen.size(), 8u);
}

TEST(Samplers, CreateReadsTheSamplerDirective) {
    const FileLoc loc{"scene.pbrt", 4, 1};
    auto create = [&](const std::string &name, ParameterDictionary params, std::optional<int> spp = std::nullopt,
                      bool quick = false) {
        return Sampler::Create(name, params, 0, std::nullopt, spp, loc, {64, 48}, quick);
    };
    auto str = [](const std::string &name, const std::string &v) {
        ParsedParameter p;
        p.type = "string";
        p.name = name;
        p.strings = {v};
        p.loc = FileLoc{"scene.pbrt", 5, 7};
        return p;
    };
    EXPECT_EQ(create("independent", {}).SamplesPerPixel(), 4) << "pbrt-v4's default for independent";
    for (const char *name : {"sobol", "paddedsobol", "zsobol", "halton", "pmj02bn", "stratified"})
        EXPECT_EQ(create(name, {}).SamplesPerPixel(), 16) << name;
    EXPECT_EQ(create("halton", {}).GetRandomization(), Randomization::PermuteDigits);
    EXPECT_EQ(create("paddedsobol", {}).GetRandomization(), Randomization::FastOwen);
    EXPECT_EQ(create("pmj02bn", {}).Type(), SamplerType::PMJ02BN);
    EXPECT_EQ(create("sobol", ParameterDictionary({str("randomization", "owen")})).GetRandomization(), Randomization::Owen);
    EXPECT_EQ(create("halton", ParameterDictionary({str("randomization", "none")})).GetRandomization(), Randomization::None);
    EXPECT_EQ(create("zsobol", {}, 100).SamplesPerPixel(), 64) << "zsobol: a power of two, rounded down";
    EXPECT_EQ(create("paddedsobol", {}, 100).SamplesPerPixel(), 100);
    for (const char *name : {"sobol", "zsobol", "halton", "pmj02bn", "independent", "stratified"})
        EXPECT_EQ(create(name, {}, 64, true).SamplesPerPixel(), 1) << name << " with --quick";

    auto refused = [&](const std::function<void()> &f, const std::string &where, const std::string &what) {
        try {
            f();
            ADD_FAILURE() << what << " accepted";
        } catch (const PbrtError &e) {
            std::string msg = e.what();
            EXPECT_EQ(msg.rfind(where, 0), 0u) << msg;
            EXPECT_NE(msg.find(what), std::string::npos) << msg;
        }
    };
    refused([&] { create("halton", ParameterDictionary({str("randomization", "fastowen")})); }, "scene.pbrt:5:7", "fastowen");
    refused([&] { create("zsobol", ParameterDictionary({str("randomization", "random")})); }, "scene.pbrt:5:7", "random");
    refused([&] { create("pmj02bn", {}, 65537); }, "scene.pbrt:4:1", "65536");
    refused([&] { create("lowdiscrepancy", {}); }, "scene.pbrt:4:1", "zsobol");
    refused([&] { Sampler::Create("zsobol", {}, 0, std::nullopt, 1 << 20, loc, {1 << 30, 4}); }, "scene.pbrt:4:1", "64");
}

TEST(Samplers, WavelengthNetStratifiesEachPartOfAPixelAndEachLightChoice) {
    // A pixel's 64 samples: wavelength numbers one per 1/64; those in either half of the pixel
    // two per 1/16; those whose light number picks a quarter of [0, 1) two per 1/8. Plus
    // uniformity over many pixels, and other pixels and seeds giving other points.
    const int n = 64;
    auto stratum = [](Float u, int k) { return int(u * Float(k)); };
    double sum[4] = {0, 0, 0, 0};
    int count = 0;
    for (uint64_t seed : {1u, 2u})
        for (int py = 0; py < 8; ++py)
            for (int px = 0; px < 8; ++px) {
                std::vector<int> all(n, 0), left(16, 0), right(16, 0), quarter[4];
                for (auto &q : quarter) q.assign(8, 0);
                for (int i = 0; i < n; ++i) {
                    Point2f f;
                    Float l, light;
                    WavelengthNet({px, py}, seed).Sample(i, &f, &l, &light);
                    for (Float v : {f.x, f.y, l, light}) ASSERT_TRUE(v >= 0 && v < 1);
                    ++all[size_t(stratum(l, n))];
                    ++(f.x < 0.5f ? left : right)[size_t(stratum(l, 16))];
                    ++quarter[stratum(light, 4)][size_t(stratum(l, 8))];
                    sum[0] += f.x, sum[1] += f.y, sum[2] += l, sum[3] += light;
                    ++count;
                }
                for (int c : all) EXPECT_EQ(c, 1);
                for (int c : left) EXPECT_EQ(c, 2);
                for (int c : right) EXPECT_EQ(c, 2);
                for (const auto &q : quarter)
                    for (int c : q) EXPECT_EQ(c, 2);
            }
    for (double s : sum) EXPECT_NEAR(s / count, 0.5, 0.01);
    Point2f a, b;
    Float la, lb, ua, ub;
    WavelengthNet({3, 4}, 1).Sample(5, &a, &la, &ua);
    WavelengthNet({3, 4}, 1).Sample(5, &b, &lb, &ub);
    EXPECT_TRUE(a.x == b.x && a.y == b.y && la == lb && ua == ub);  // a sample replays
    WavelengthNet({4, 3}, 1).Sample(5, &b, &lb, &ub);
    EXPECT_NE(la, lb);
    WavelengthNet({3, 4}, 2).Sample(5, &b, &lb, &ub);
    EXPECT_NE(la, lb);
}
