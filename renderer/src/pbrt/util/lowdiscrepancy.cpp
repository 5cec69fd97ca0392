#include <pbrt/util/lowdiscrepancy.h>

#include <pbrt/util/rng.h>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace pbrt {

namespace {

// The product of a Sobol' generator matrix (its columns v, 32-bit fractions) with an index is
// linear over GF(2), so it is tabulated per index byte: entry b of table `byte` is the XOR of
// the columns of the bits of b, shifted to that byte.
template <int NBytes>
std::array<std::array<uint32_t, 256>, NBytes> ByteTables(const std::array<uint32_t, 8 * NBytes> &v) {
    std::array<std::array<uint32_t, 256>, NBytes> t{};
    for (size_t byte = 0; byte < size_t(NBytes); ++byte)
        for (size_t b = 0; b < 256; ++b)
            for (size_t k = 0; k < 8; ++k)
                if (b & (size_t(1) << k)) t[byte][b] ^= v[8 * byte + k];
    return t;
}

// The XOR of the four byte tables' entries for an index's bytes.
uint32_t SobolFromTables(const std::array<std::array<uint32_t, 256>, 4> &t, uint32_t index) {
    return t[0][index & 0xff] ^ t[1][(index >> 8) & 0xff] ^ t[2][(index >> 16) & 0xff] ^ t[3][index >> 24];
}

// Direction numbers of the second Sobol' dimension (primitive polynomial x + 1): the
// generator matrix is the upper-triangular Pascal matrix mod 2, v_k = v_{k-1} ^ (v_{k-1} >> 1),
// truncated to 32 bits of fraction (row j of column k only depends on rows <= j of column
// k - 1, so the recurrence holds for every column k < 64).
template <int NBytes>
std::array<std::array<uint32_t, 256>, NBytes> MakeSobolDim1Tables() {
    std::array<uint32_t, 8 * NBytes> v{};
    v[0] = 1u << 31;
    for (int k = 1; k < 8 * NBytes; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    return ByteTables<NBytes>(v);
}
const std::array<std::array<uint32_t, 256>, 4> kSobolDim1 = MakeSobolDim1Tables<4>();
const std::array<std::array<uint32_t, 256>, 8> kSobolDim1Wide = MakeSobolDim1Tables<8>();

// Direction numbers of a Sobol' dimension as 32-bit fractions v_k = m_k 2^(32-k), from
// Sobol's recurrence for its primitive polynomial x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1
// (`a` holds a_1 .. a_(s-1) as bits, a_1 highest) and its initial m_1 .. m_s (each odd, < 2^k):
// m_k = 2 a_1 m_(k-1) ^ 4 a_2 m_(k-2) ^ ... ^ 2^s m_(k-s) ^ m_(k-s).
std::array<uint32_t, 32> MakeSobolDirections(int s, uint32_t a, std::initializer_list<uint64_t> initial) {
    std::array<uint64_t, 33> m{};
    int k = 1;
    for (uint64_t mk : initial) m[size_t(k++)] = mk;
    for (; k <= 32; ++k) {
        uint64_t v = (m[size_t(k - s)] << s) ^ m[size_t(k - s)];
        for (int j = 1; j < s; ++j)
            if ((a >> (s - 1 - j)) & 1) v ^= m[size_t(k - j)] << j;
        m[size_t(k)] = v;
    }
    std::array<uint32_t, 32> v{};
    for (int j = 1; j <= 32; ++j) v[size_t(j - 1)] = uint32_t(m[size_t(j)] << (32 - j));
    return v;
}
// Dimension 2: x^2 + x + 1, m = 1, 3; dimension 3: x^3 + x + 1, m = 1, 3, 1 (the initial
// numbers of Joe and Kuo 2008).
const std::array<std::array<uint32_t, 256>, 4> kSobolDim2 = ByteTables<4>(MakeSobolDirections(2, 0b1, {1, 3}));
const std::array<std::array<uint32_t, 256>, 4> kSobolDim3 = ByteTables<4>(MakeSobolDirections(3, 0b01, {1, 3, 1}));

// The same with every entry bit-reversed: bit reversal is linear over GF(2), so
// ReverseBits32(SobolDim1(i)) is the XOR of these (one reversal less per 2D sample).
std::array<std::array<uint32_t, 256>, 4> ReversedTables(std::array<std::array<uint32_t, 256>, 4> t) {
    for (auto &row : t)
        for (uint32_t &v : row) v = ReverseBits32(v);
    return t;
}

// The first kHaltonDimensions primes (sieve of Eratosthenes; the 1000th prime is 7919).
std::vector<int> MakePrimes() {
    std::vector<int> primes;
    std::vector<char> composite(8000, 0);
    for (int i = 2; i < int(composite.size()) && int(primes.size()) < kHaltonDimensions; ++i) {
        if (composite[size_t(i)]) continue;
        primes.push_back(i);
        for (int j = i * i; j < int(composite.size()); j += i) composite[size_t(j)] = 1;
    }
    return primes;
}
const std::vector<int> kPrimes = MakePrimes();

// The 24 permutations of {0, 1, 2, 3}, in lexicographic order.
std::array<std::array<uint8_t, 4>, 24> MakePermutations4() {
    std::array<std::array<uint8_t, 4>, 24> out{};
    std::array<uint8_t, 4> p = {0, 1, 2, 3};
    for (auto &o : out) {
        o = p;
        std::next_permutation(p.begin(), p.end());
    }
    return out;
}
const std::array<std::array<uint8_t, 4>, 24> kPermutations4 = MakePermutations4();

constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ULL;

}  // namespace

const std::array<std::array<uint32_t, 256>, 4> kSobolDim1Reversed = ReversedTables(kSobolDim1);

const char *RandomizationName(Randomization r) {
    switch (r) {
    case Randomization::None: return "none";
    case Randomization::PermuteDigits: return "permutedigits";
    case Randomization::FastOwen: return "fastowen";
    case Randomization::Owen: return "owen";
    }
    return "?";
}

uint32_t PermutationElement(uint32_t i, uint32_t l, uint32_t p) {
    uint32_t w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    // Cycle-walk a hash-based bijection on [0, w] until it lands inside [0, l).
    do {
        i ^= p;
        i *= 0xe170893du;
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i *= 0x0929eb3fu;
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i *= 1 | p >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= l);
    return (i + p) % l;
}

uint32_t SobolDim0(uint32_t index) { return ReverseBits32(index); }

uint32_t SobolDim1(uint32_t index) { return SobolFromTables(kSobolDim1, index); }

uint32_t SobolDim2(uint32_t index) { return SobolFromTables(kSobolDim2, index); }
uint32_t SobolDim3(uint32_t index) { return SobolFromTables(kSobolDim3, index); }

uint32_t SobolDim1Wide(uint64_t index) {
    uint32_t r = 0;
    for (int byte = 0; byte < 8 && index; ++byte, index >>= 8) r ^= kSobolDim1Wide[size_t(byte)][index & 0xff];
    return r;
}

uint32_t OwenScramble(uint32_t v, uint32_t seed) {
    return ReverseBits32(LaineKarrasPermutation(ReverseBits32(v), seed));
}

uint32_t OwenScrambleExact(uint32_t v, uint32_t seed) {
    // Bit 31 - k flips or not by a hash of the seed, k and the k bits above it: nodes of the
    // binary digit tree flip independently (the k leading bits are marked by a 1 above them
    // so that prefixes of different lengths never share a key).
    const uint64_t s = MixBits(uint64_t(seed) * kGolden + 1);
    uint32_t out = v;
    for (int k = 0; k < 32; ++k) {
        uint64_t prefix = k == 0 ? 1 : ((1ULL << k) | (v >> (32 - k)));
        if (MixBits(s ^ (prefix * kGolden)) & 1) out ^= 1u << (31 - k);
    }
    return out;
}

int Prime(int i) { return kPrimes[size_t(i)]; }

double RadicalInverse(int base, uint64_t a) {
    const double inv = 1.0 / base;
    double v = 0, w = inv;
    while (a) {
        v += double(a % uint64_t(base)) * w;
        a /= uint64_t(base);
        w *= inv;
    }
    return std::min(v, 1.0 - 0x1p-53);
}

double ScrambledRadicalInverse(int base, uint64_t a, uint64_t seed, Randomization r) {
    const double inv = 1.0 / base;
    const bool nested = r == Randomization::Owen;
    double v = 0, w = inv;
    uint64_t prefix = 0, scale = 1;  // the digits so far (a's low digits), base^k
    for (int k = 0; w > 0x1p-32; ++k) {
        uint32_t d = uint32_t(a % uint64_t(base));
        a /= uint64_t(base);
        uint64_t key = MixBits(seed + uint64_t(k + 1) * kGolden);
        if (nested) key = MixBits(key ^ (prefix * kGolden));
        v += double(PermutationElement(d, uint32_t(base), uint32_t(key >> 32))) * w;
        w *= inv;
        if (nested && d) prefix += d * scale;  // d != 0 only while scale <= the index
        scale *= uint64_t(base);
    }
    return std::min(v, 1.0 - 0x1p-53);
}

uint64_t InverseRadicalInverse(uint64_t v, int base, int nDigits) {
    uint64_t r = 0;
    for (int i = 0; i < nDigits; ++i) {
        r = r * uint64_t(base) + v % uint64_t(base);
        v /= uint64_t(base);
    }
    return r;
}

uint64_t EncodeMorton2(uint32_t x, uint32_t y) {
    auto spread = [](uint64_t v) {
        v = (v | (v << 16)) & 0x0000ffff0000ffffULL;
        v = (v | (v << 8)) & 0x00ff00ff00ff00ffULL;
        v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0fULL;
        v = (v | (v << 2)) & 0x3333333333333333ULL;
        v = (v | (v << 1)) & 0x5555555555555555ULL;
        return v;
    };
    return spread(x) | (spread(y) << 1);
}

uint64_t ShuffleBase4Digits(uint64_t index, int nBits, uint64_t hash) {
    const bool odd = nBits & 1;
    uint64_t out = 0;
    for (int shift = nBits - 2; shift >= (odd ? 1 : 0); shift -= 2) {
        uint64_t digit = (index >> shift) & 3;
        uint64_t above = shift + 2 >= 64 ? 0 : index >> (shift + 2);
        uint64_t h = MixBits(hash ^ (above * kGolden) ^ uint64_t(shift));
        out |= uint64_t(kPermutations4[(h >> 32) % 24][digit]) << shift;
    }
    if (odd) out |= (index & 1) ^ (MixBits(hash ^ ((index >> 1) * kGolden) ^ 0xff) & 1);
    return out;
}

std::vector<std::array<uint32_t, 2>> GeneratePMJ02BN(int n, uint64_t seed) {
    if (n < 1 || n > (1 << 16) || (n & (n - 1)))
        throw PbrtError("pmj02bn: the number of points must be a power of two up to 65536");
    // Point i is Sobol' point i (dimensions 0 and 1) through a nested scramble of each
    // coordinate: bit d flips or not by a choice attached to the bits above it (a node of
    // the binary digit tree), so every prefix of 2^m points is a (0, m, 2)-net. The choices
    // are made lazily, when a point first reaches a node: point i in [2^(m-1), 2^m) meets
    // fresh nodes from depth m down (its box of 2^-m x 2^-m is already fixed) and may place
    // itself anywhere in that box; nodes above depth 16 are shared with later points and
    // remembered, deeper ones belong to one point of the 2^16.
    constexpr int kShared = 16;
    std::array<std::vector<int8_t>, 2 * kShared> flips;  // [coordinate * 16 + depth][prefix]: -1 undecided
    for (int c = 0; c < 2; ++c)
        for (int d = 0; d < kShared; ++d) flips[size_t(c * kShared + d)].assign(size_t(1) << d, -1);
    auto unscrambled = [](uint32_t i, int c) { return c == 0 ? SobolDim0(i) : SobolDim1(i); };
    // Point i with `choice`'s bits at the undecided nodes (record: remember them).
    auto place = [&](uint32_t i, const std::array<uint32_t, 2> &choice, bool record) {
        std::array<uint32_t, 2> p{};
        for (int c = 0; c < 2; ++c) {
            const uint32_t u = unscrambled(i, c);
            uint32_t v = 0;
            for (int d = 0; d < 32; ++d) {
                const uint32_t bit = (u >> (31 - d)) & 1, want = (choice[size_t(c)] >> (31 - d)) & 1;
                uint32_t flip = want ^ bit;  // a fresh node: the scrambled bit is choice's
                if (d < kShared) {
                    int8_t &f = flips[size_t(c * kShared + d)][d ? u >> (32 - d) : 0];
                    if (f >= 0) flip = uint32_t(f);
                    else if (record) f = int8_t(flip);
                }
                v |= (bit ^ flip) << (31 - d);
            }
            p[size_t(c)] = v;
        }
        return p;
    };

    // Best candidate (Mitchell 1991): of a few random remaining points of the block, each at
    // a few random places in its box, the one farthest (on the torus) from those before it.
    constexpr int kCandidates = 4, kPlaces = 16;
    RNG rng(MixBits(seed ^ 0x706d6a3032626eULL));
    auto coord = [](uint32_t v) { return double(v) * 0x1p-32; };
    std::vector<std::array<uint32_t, 2>> pts(static_cast<size_t>(n));
    pts[0] = place(0, {rng.Uniform32(), rng.Uniform32()}, true);
    for (int B = 1; B < n; B *= 2) {
        // A grid of g x g cells (g a power of two) holding about one of the 2B points each.
        int g = 1, log2g = 0;
        while (g * g < 2 * B) {
            g *= 2;
            ++log2g;
        }
        std::vector<std::vector<std::array<uint32_t, 2>>> cells(size_t(g) * size_t(g));
        auto cellOf = [&](const std::array<uint32_t, 2> &p) {
            int cx = log2g ? int(p[0] >> (32 - log2g)) : 0, cy = log2g ? int(p[1] >> (32 - log2g)) : 0;
            return std::array<int, 2>{cx, cy};
        };
        auto insert = [&](const std::array<uint32_t, 2> &p) {
            auto c = cellOf(p);
            cells[size_t(c[1]) * size_t(g) + size_t(c[0])].push_back(p);
        };
        auto nearest2 = [&](const std::array<uint32_t, 2> &q) {
            const double qx = coord(q[0]), qy = coord(q[1]), cs = 1.0 / g;
            auto c = cellOf(q);
            double best = 2;
            for (int r = 0; r <= g / 2; ++r) {
                if (r > 0 && Sqr((r - 1) * cs) >= best) break;
                for (int dy = -r; dy <= r; ++dy)
                    for (int dx = -r; dx <= r; ++dx) {
                        if (std::max(std::abs(dx), std::abs(dy)) != r) continue;  // the ring only
                        int x = ((c[0] + dx) % g + g) % g, y = ((c[1] + dy) % g + g) % g;
                        for (const auto &o : cells[size_t(y) * size_t(g) + size_t(x)]) {
                            double ex = std::abs(coord(o[0]) - qx), ey = std::abs(coord(o[1]) - qy);
                            ex = std::min(ex, 1 - ex);
                            ey = std::min(ey, 1 - ey);
                            best = std::min(best, ex * ex + ey * ey);
                        }
                    }
                if (2 * r + 1 >= g) break;  // every cell seen
            }
            return best;
        };
        for (int i = 0; i < B; ++i) insert(pts[size_t(i)]);
        std::vector<uint32_t> remaining;
        for (uint32_t i = uint32_t(B); i < uint32_t(2 * B); ++i) remaining.push_back(i);
        for (int t = B; t < 2 * B; ++t) {
            size_t bestSlot = 0;
            std::array<uint32_t, 2> bestChoice{};
            double bestD = -1;
            const int k = std::min<int>(kCandidates, int(remaining.size()));
            for (int c = 0; c < k; ++c) {
                const size_t slot = size_t(rng.Uniform32() % uint32_t(remaining.size()));
                for (int j = 0; j < kPlaces; ++j) {
                    const std::array<uint32_t, 2> choice = {rng.Uniform32(), rng.Uniform32()};
                    const double d = nearest2(place(remaining[slot], choice, false));
                    if (d > bestD) {
                        bestD = d;
                        bestSlot = slot;
                        bestChoice = choice;
                    }
                }
            }
            pts[size_t(t)] = place(remaining[bestSlot], bestChoice, true);
            insert(pts[size_t(t)]);
            remaining[bestSlot] = remaining.back();
            remaining.pop_back();
        }
    }
    return pts;
}

}  // namespace pbrt
