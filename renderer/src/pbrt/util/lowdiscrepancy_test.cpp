// Low-discrepancy sequences and scrambles: nets stay nets, radical inverses are the digits
// mirrored, permutations are bijections, pmj02bn's prefixes are nets with spread-out points.
#include <pbrt/util/lowdiscrepancy.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

using namespace pbrt;

namespace {

// Whether n points (32-bit fractions) form a (0, m, 2)-net in base 2, n = 2^m: every
// elementary interval of area 2^-m (2^-k wide, 2^-(m-k) high, for every k) holds one point.
bool IsNet(const std::vector<std::array<uint32_t, 2>> &pts, int m, std::string *why = nullptr) {
    for (int k = 0; k <= m; ++k) {
        std::set<std::pair<uint32_t, uint32_t>> cells;
        for (const auto &p : pts)
            cells.insert({k ? p[0] >> (32 - k) : 0, (m - k) ? p[1] >> (32 - (m - k)) : 0});
        if (cells.size() != pts.size()) {
            if (why) *why = "intervals 2^-" + std::to_string(k) + " x 2^-" + std::to_string(m - k);
            return false;
        }
    }
    return true;
}

// Digit by digit, in long double: the radical inverse's definition.
long double ReferenceRadicalInverse(int base, uint64_t a) {
    long double v = 0, w = 1.0L / base;
    for (; a; a /= uint64_t(base), w /= base) v += (a % uint64_t(base)) * w;
    return v;
}

bool IsPrime(int n) {
    for (int d = 2; d * d <= n; ++d)
        if (n % d == 0) return false;
    return n >= 2;
}

}  // namespace

TEST(LowDiscrepancy, ScramblesKeepSobolNets) {
    // 2^m consecutive points of the first two Sobol' dimensions, aligned to 2^m, form a
    // (0, m, 2)-net, and every randomization keeps it one.
    const int m = 7;
    for (Randomization r : {Randomization::None, Randomization::PermuteDigits, Randomization::FastOwen,
                            Randomization::Owen})
        for (uint32_t start : {0u, 128u, 1u << 20}) {
            std::vector<std::array<uint32_t, 2>> pts;
            for (uint32_t i = start; i < start + (1u << m); ++i)
                pts.push_back({Scramble(SobolDim0(i), r, 0x1234u), Scramble(SobolDim1(i), r, 0xabcdu)});
            std::string why;
            EXPECT_TRUE(IsNet(pts, m, &why)) << RandomizationName(r) << " from " << start << ": " << why;
        }
}

TEST(LowDiscrepancy, OwenScramblesAreBijectionsThatDependOnTheSeed) {
    for (Randomization r : {Randomization::PermuteDigits, Randomization::FastOwen, Randomization::Owen}) {
        std::set<uint32_t> out;
        int same = 0;
        for (uint32_t v = 0; v < 4096; ++v) {
            uint32_t s = Scramble(v << 20, r, 7);
            out.insert(s >> 20);
            same += s == Scramble(v << 20, r, 8);
        }
        EXPECT_EQ(out.size(), 4096u) << RandomizationName(r) << ": the top 12 bits must be permuted";
        EXPECT_LT(same, 100) << RandomizationName(r) << ": different seeds, different scrambles";
    }
    // Owen scrambling is uniform: over seeds, a fixed value's bits are fair coins.
    int ones[32] = {};
    for (uint32_t seed = 0; seed < 4000; ++seed) {
        uint32_t s = OwenScrambleExact(0x5a5a5a5au, seed);
        for (int b = 0; b < 32; ++b) ones[b] += (s >> b) & 1;
    }
    for (int b = 0; b < 32; ++b) EXPECT_NEAR(ones[b], 2000, 200) << "bit " << b;
}

TEST(LowDiscrepancy, FirstThreeSobolDimensionsAreA1Net) {
    // 2^m aligned consecutive points of dimensions 0-2, scrambled or not: every elementary box
    // of volume 2^(1-m) (2^-a x 2^-b x 2^-c, a + b + c = m - 1) holds exactly 2 of them, and
    // dimension 2 alone is a (0, m, 1)-net. A wrong direction number breaks this at some m.
    for (int m = 1; m <= 10; ++m)
        for (Randomization r : {Randomization::None, Randomization::Owen})
            for (uint32_t start : {0u, 1u << m, 5u << 16}) {
                std::vector<std::array<uint32_t, 3>> pts;
                for (uint32_t i = start; i < start + (1u << m); ++i)
                    pts.push_back({Scramble(SobolDim0(i), r, 0x51u), Scramble(SobolDim1(i), r, 0x77u),
                                   Scramble(SobolDim2(i), r, 0x3c3cu)});
                std::set<uint32_t> strata;
                for (const auto &p : pts) strata.insert(p[2] >> (32 - m));
                EXPECT_EQ(strata.size(), pts.size()) << "m " << m;
                for (int a = 0; a < m; ++a)
                    for (int b = 0; a + b < m; ++b) {
                        const int c = m - 1 - a - b;
                        std::map<std::array<uint32_t, 3>, int> boxes;
                        for (const auto &p : pts)
                            ++boxes[{a ? p[0] >> (32 - a) : 0, b ? p[1] >> (32 - b) : 0,
                                     c ? p[2] >> (32 - c) : 0}];
                        bool two = boxes.size() == pts.size() / 2;
                        for (const auto &[box, n] : boxes) two = two && n == 2;
                        EXPECT_TRUE(two) << "m " << m << " boxes 2^-" << a << " x 2^-" << b << " x 2^-" << c
                                         << " from " << start << " (" << RandomizationName(r) << ")";
                    }
            }
}

TEST(LowDiscrepancy, SobolDimensionsTwoAndThreeAreA1NetFrom16Points) {
    // The wavelength and light numbers of --wavelength-net: dimension 3 alone is a
    // (0, m, 1)-net, and with dimension 2 a (1, m, 2)-net for m >= 4 (t = 2 at m = 3).
    for (int m = 4; m <= 10; ++m) {
        std::set<uint32_t> strata;
        for (uint32_t i = 0; i < (1u << m); ++i) strata.insert(SobolDim3(i) >> (32 - m));
        EXPECT_EQ(strata.size(), size_t(1) << m) << "m " << m;
        for (int a = 0; a < m; ++a) {
            const int b = m - 1 - a;
            std::map<std::pair<uint32_t, uint32_t>, int> boxes;
            for (uint32_t i = 0; i < (1u << m); ++i)
                ++boxes[{a ? SobolDim2(i) >> (32 - a) : 0, b ? SobolDim3(i) >> (32 - b) : 0}];
            bool two = boxes.size() == (size_t(1) << (m - 1));
            for (const auto &[box, n] : boxes) two = two && n == 2;
            EXPECT_TRUE(two) << "m " << m << " boxes 2^-" << a << " x 2^-" << b;
        }
    }
}

TEST(LowDiscrepancy, SobolDim1WideExtendsSobolDim1) {
    for (uint32_t i : {0u, 1u, 2u, 3u, 255u, 256u, 0x12345678u, 0xffffffffu}) EXPECT_EQ(SobolDim1Wide(i), SobolDim1(i));
    // Past 32 bits the index still matters, and aligned blocks stay nets.
    EXPECT_NE(SobolDim1Wide(1ULL << 40), 0u);
    for (uint64_t start : {1ULL << 33, (1ULL << 45) + (5ULL << 8), 0xfedcba9876540000ULL}) {
        std::vector<std::array<uint32_t, 2>> pts;
        for (uint64_t i = start; i < start + 256; ++i) pts.push_back({SobolDim0Wide(i), SobolDim1Wide(i)});
        EXPECT_TRUE(IsNet(pts, 8)) << start;
    }
}

TEST(LowDiscrepancy, PrimesAndRadicalInverses) {
    EXPECT_EQ(Prime(0), 2);
    EXPECT_EQ(Prime(1), 3);
    EXPECT_EQ(Prime(2), 5);
    for (int i = 1; i < kHaltonDimensions; ++i) {
        ASSERT_GT(Prime(i), Prime(i - 1));
        ASSERT_TRUE(IsPrime(Prime(i))) << Prime(i);
        for (int n = Prime(i - 1) + 1; n < Prime(i); ++n) ASSERT_FALSE(IsPrime(n)) << n << " skipped";
    }
    // 5 = 12 in base 3, so 0.21 in base 3 = 7/9; 6 = 110 in base 2, so 0.011 = 3/8.
    EXPECT_DOUBLE_EQ(RadicalInverse(3, 5), 7.0 / 9);
    EXPECT_DOUBLE_EQ(RadicalInverse(2, 6), 3.0 / 8);
    uint64_t a = 0x0123456789abcdefULL;
    for (int k = 0; k < 300; ++k, a = a * 6364136223846793005ULL + 1442695040888963407ULL)
        for (int base : {2, 3, 5, 7, 31, 7919})
            ASSERT_NEAR(RadicalInverse(base, a >> (k % 64)), double(ReferenceRadicalInverse(base, a >> (k % 64))), 1e-15);
    // InverseRadicalInverse finds the index whose first n digits, mirrored, are v.
    for (int base : {2, 3, 5})
        for (int n = 0; n <= 5; ++n) {
            uint64_t bn = 1;
            for (int i = 0; i < n; ++i) bn *= uint64_t(base);
            for (uint64_t v = 0; v < bn; ++v) {
                uint64_t i = InverseRadicalInverse(v, base, n);
                ASSERT_LT(i, bn);
                ASSERT_EQ(uint64_t(std::floor(RadicalInverse(base, i) * double(bn) + 1e-9)), v) << base << " " << n;
            }
        }
}

TEST(LowDiscrepancy, ScrambledRadicalInversesStratifyAndDependOnTheSeed) {
    // Digit permutations (plain or nested) of the first b^k indices leave one value in each
    // of the b^k intervals of width b^-k; values lie in [0, 1).
    for (Randomization r : {Randomization::PermuteDigits, Randomization::Owen})
        for (int base : {3, 5, 7}) {
            const int n = base * base * base;
            std::set<int> strata;
            int same = 0;
            for (int i = 0; i < n; ++i) {
                double v = ScrambledRadicalInverse(base, uint64_t(i), 42, r);
                ASSERT_GE(v, 0);
                ASSERT_LT(v, 1);
                strata.insert(int(v * n));
                same += v == ScrambledRadicalInverse(base, uint64_t(i), 43, r);
                ASSERT_EQ(v, ScrambledRadicalInverse(base, uint64_t(i), 42, r));
            }
            EXPECT_EQ(int(strata.size()), n) << RandomizationName(r) << " base " << base;
            EXPECT_LT(same, n / 10) << RandomizationName(r) << " base " << base;
        }
    // Owen's permutations depend on the digits before: index 1 and 2 in base 3 share no
    // first digit, so their second digits permute independently; over seeds the second
    // digits of 1 and 4 (first digit 1, second 0 and 1) differ, those of 1 and 2 sometimes agree.
    int agree = 0;
    for (uint64_t seed = 0; seed < 300; ++seed) {
        auto second = [&](uint64_t i) { return int(ScrambledRadicalInverse(3, i, seed, Randomization::Owen) * 9) % 3; };
        ASSERT_NE(second(1), second(4));
        agree += second(1) == second(2);
    }
    EXPECT_GT(agree, 50) << "nested permutations are independent between different prefixes";
    EXPECT_LT(agree, 150);
}

TEST(LowDiscrepancy, MortonAndBase4ShuffleKeepBlocks) {
    EXPECT_EQ(EncodeMorton2(0, 0), 0u);
    EXPECT_EQ(EncodeMorton2(1, 0), 1u);
    EXPECT_EQ(EncodeMorton2(0, 1), 2u);
    EXPECT_EQ(EncodeMorton2(3, 3), 15u);
    EXPECT_EQ(EncodeMorton2(0xffffffffu, 0), 0x5555555555555555ULL);
    for (int nBits : {0, 1, 2, 5, 8, 11}) {
        const uint64_t n = 1ULL << nBits;
        std::set<uint64_t> out;
        for (uint64_t i = 0; i < n; ++i) {
            uint64_t s = ShuffleBase4Digits(i, nBits, 99);
            ASSERT_LT(s, n);
            out.insert(s);
        }
        EXPECT_EQ(out.size(), n) << nBits << " bits: a permutation";
        // An aligned block of 4^k indices (2^k for the odd lowest bit) lands on one.
        for (int blockBits = nBits & 1; blockBits <= nBits; blockBits += 2)
            for (uint64_t b = 0; b < (n >> blockBits); ++b) {
                std::set<uint64_t> blocks;
                for (uint64_t j = 0; j < (1ULL << blockBits); ++j)
                    blocks.insert(ShuffleBase4Digits((b << blockBits) | j, nBits, 99) >> blockBits);
                ASSERT_EQ(blocks.size(), 1u) << nBits << " bits, blocks of " << blockBits;
            }
    }
    // Different hashes, different shuffles; the full 64 bits work.
    int same = 0;
    for (uint64_t i = 0; i < 256; ++i) same += ShuffleBase4Digits(i, 8, 1) == ShuffleBase4Digits(i, 8, 2);
    EXPECT_LT(same, 128);
    EXPECT_NE(ShuffleBase4Digits(~0ULL, 64, 5), ShuffleBase4Digits(~0ULL, 64, 6));
}

TEST(LowDiscrepancy, PMJ02BNPrefixesAreNetsWithSpreadOutPoints) {
    const int n = 1 << 12;
    auto pts = GeneratePMJ02BN(n, 3);
    ASSERT_EQ(int(pts.size()), n);
    for (int m = 0; m <= 12; ++m) {
        std::vector<std::array<uint32_t, 2>> prefix(pts.begin(), pts.begin() + (1 << m));
        std::string why;
        EXPECT_TRUE(IsNet(prefix, m, &why)) << "first 2^" << m << " points: " << why;
    }
    // Deterministic, and a longer set starts with the shorter one.
    EXPECT_EQ(GeneratePMJ02BN(n, 3), pts);
    auto longer = GeneratePMJ02BN(2 * n, 3);
    EXPECT_TRUE(std::equal(pts.begin(), pts.end(), longer.begin()));
    EXPECT_NE(GeneratePMJ02BN(n, 4), pts);

    // Blue noise: the points of a prefix lie farther apart (mean nearest-neighbour distance on
    // the torus, over four sets) than those of Owen-scrambled Sobol' points, the same
    // sequence with every choice random; most between powers of two.
    auto meanNN = [](const std::vector<std::array<uint32_t, 2>> &p, int count) {
        double sum = 0;
        for (int i = 0; i < count; ++i) {
            double best = 2;
            for (int j = 0; j < count; ++j) {
                if (i == j) continue;
                double dx = std::abs(p[i][0] * 0x1p-32 - p[j][0] * 0x1p-32), dy = std::abs(p[i][1] * 0x1p-32 - p[j][1] * 0x1p-32);
                dx = std::min(dx, 1 - dx);
                dy = std::min(dy, 1 - dy);
                best = std::min(best, dx * dx + dy * dy);
            }
            sum += std::sqrt(best);
        }
        return sum / count;
    };
    double between = 0;
    int nBetween = 0;
    for (int count : {24, 48, 64, 96, 192, 256, 384, 512}) {
        double bn = 0, plain = 0;
        for (uint64_t seed = 1; seed <= 4; ++seed) {
            auto p = GeneratePMJ02BN(512, seed);
            std::vector<std::array<uint32_t, 2>> q;
            for (uint32_t i = 0; i < 512; ++i)
                q.push_back({OwenScramble(SobolDim0(i), uint32_t(seed) * 7), OwenScramble(SobolDim1(i), uint32_t(seed) * 11)});
            bn += meanNN(p, count);
            plain += meanNN(q, count);
        }
        EXPECT_GT(bn, 0.99 * plain) << count << " points: " << bn / 4 << " vs " << plain / 4;
        if (count & (count - 1)) {
            between += bn / plain;
            ++nBetween;
        }
    }
    EXPECT_GT(between / nBetween, 1.1) << "blue-noise spacing between powers of two";
    EXPECT_THROW(GeneratePMJ02BN(3, 1), PbrtError);
    EXPECT_THROW(GeneratePMJ02BN(1 << 17, 1), PbrtError);
}
