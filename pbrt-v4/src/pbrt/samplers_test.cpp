// Pixel samplers: stratification properties, determinism and uniformity.
#include <pbrt/samplers.h>

#include <pbrt/util/paramdict.h>

#include <gtest/gtest.h>

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
    EXPECT_EQ(z.Type(), SamplerType::Sobol);
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
