// Low-discrepancy sequences and their randomizations: the pieces the pixel samplers
// (samplers.h) are built from.
//
//   Sobol'      the first three dimensions of the Sobol' sequence (Sobol' 1967): dimension 0
//               is the base-2 radical inverse of the index, dimension 1 the product of the
//               index's bits with the upper-triangular Pascal matrix mod 2, dimension 2 that
//               of x^2 + x + 1. Any 2^k consecutive points, aligned to 2^k, form a
//               (0, k, 2)-net in base 2 in the first two, a (1, k, 3)-net in all three.
//   Halton      radical inverses in the first kHaltonDimensions prime bases (Halton 1960).
//   scrambles   of a 32-bit binary fraction: a random digit permutation (XOR with a random
//               word), Owen's nested uniform scrambling (Owen 1995) computed bit by bit, and
//               its fast hash approximation (Burley 2020, "Practical Hash-based Owen
//               Scrambling", JCGT 9(4), after Laine and Karras 2011); in base b, random digit
//               permutations (Faure and Lemieux 2009) and nested (Owen) permutations.
//   pmj02bn     progressive multi-jittered (0, 2) point sets with blue-noise ordering
//               (Christensen, Kensler and Kilpatrick 2018), see GeneratePMJ02BN.
//   z-order     the Morton index of a pixel with its base-4 digits randomly permuted level by
//               level (Ahmed and Wonka 2020, "Screen-Space Blue-Noise Diffusion of Monte Carlo
//               Sampling Error via Hierarchical Ordering of Pixels", SIGGRAPH Asia).
//
// Randomizations keep the nets nets: a nested scramble permutes whole elementary intervals.
#pragma once

#include <pbrt/util/vecmath.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#if defined(__GFNI__) && defined(__SSE2__)
#include <immintrin.h>
#endif

namespace pbrt {

inline uint32_t ReverseBits32(uint32_t n) {
#if defined(__GFNI__) && defined(__SSE2__)
    // With GFNI (a -march=native build on a CPU that has it): one affine transform over GF(2)
    // reverses the bits of every byte (the matrix whose byte j is 1 << j), a byte swap does
    // the rest. Four of these per 2D sample, so the sampler's cost drops measurably.
    __m128i v = _mm_gf2p8affine_epi64_epi8(_mm_cvtsi32_si128(int(n)),
                                           _mm_set1_epi64x(int64_t(0x8040201008040201ULL)), 0);
    return __builtin_bswap32(uint32_t(_mm_cvtsi128_si32(v)));
#else
    n = __builtin_bswap32(n);  // the two byte-level steps in one instruction
    n = ((n & 0x0f0f0f0fu) << 4) | ((n & 0xf0f0f0f0u) >> 4);
    n = ((n & 0x33333333u) << 2) | ((n & 0xccccccccu) >> 2);
    n = ((n & 0x55555555u) << 1) | ((n & 0xaaaaaaaau) >> 1);
    return n;
#endif
}

// A hash in which every bit depends only on itself and the bits below it: a random
// permutation of each subtree of the binary digit tree when applied to reversed bits
// (constants of Burley 2020, after Laine and Karras 2011).
inline uint32_t LaineKarrasPermutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// A 32-bit binary fraction as a float in [0, 1).
inline Float ToUnitFloat(uint32_t v) { return std::min<Float>(v * 0x1p-32f, OneMinusEpsilon); }

// Random permutation of [0, n) chosen by seed, element i (Kensler 2013, "Correlated
// Multi-Jittered Sampling", Pixar Technical Memo 13-01).
uint32_t PermutationElement(uint32_t i, uint32_t n, uint32_t seed);

// --- Base 2 -----------------------------------------------------------------------------
// The first two dimensions of the Sobol' sequence, as 32-bit fractions.
uint32_t SobolDim0(uint32_t index);
uint32_t SobolDim1(uint32_t index);
// The same for indices of up to 64 bits (the z-order sampler's): dimension 0 only sees the
// low 32 bits, dimension 1 every bit.
inline uint32_t SobolDim0Wide(uint64_t index) { return ReverseBits32(uint32_t(index)); }
uint32_t SobolDim1Wide(uint64_t index);
// Dimension 2 of the Sobol' sequence: primitive polynomial x^2 + x + 1, initial direction
// numbers m_1 = 1, m_2 = 3. With dimensions 0 and 1 it makes a (1, 3)-sequence in base 2:
// any 2^k consecutive points aligned to 2^k hold 2 points in every elementary box of volume
// 2^(1-k).
uint32_t SobolDim2(uint32_t index);
// Dimension 3: x^3 + x + 1, m = 1, 3, 1; dimensions 0-3 are a (3, 4)-sequence.
uint32_t SobolDim3(uint32_t index);
// Tables of dimension 1's generator columns per index byte, bit-reversed (the Sobol sampler's
// hot path XORs four of these): ReverseBits32(SobolDim1(i)) = XOR of kSobolDim1Reversed[b][byte b of i].
extern const std::array<std::array<uint32_t, 256>, 4> kSobolDim1Reversed;

// Scrambles of a 32-bit binary fraction, each chosen by seed.
enum class Randomization { None, PermuteDigits, FastOwen, Owen };
// pbrt-v4's names: "none", "permutedigits", "fastowen", "owen".
const char *RandomizationName(Randomization r);
// Nested uniform (Owen) scramble, fast hash approximation (Burley 2020): "fastowen".
uint32_t OwenScramble(uint32_t v, uint32_t seed);
// Nested uniform (Owen) scramble, one independent random flip per bit and prefix: "owen".
uint32_t OwenScrambleExact(uint32_t v, uint32_t seed);
// Random digit permutation in base 2, i.e. the same random flip of each digit: "permutedigits".
inline uint32_t BinaryPermuteScramble(uint32_t v, uint32_t seed) { return v ^ seed; }
inline uint32_t Scramble(uint32_t v, Randomization r, uint32_t seed) {
    switch (r) {
    case Randomization::None: return v;
    case Randomization::PermuteDigits: return BinaryPermuteScramble(v, seed);
    case Randomization::FastOwen: return OwenScramble(v, seed);
    case Randomization::Owen: return OwenScrambleExact(v, seed);
    }
    return v;
}

// --- Base b (Halton) --------------------------------------------------------------------
// The number of prime bases, and so of Halton dimensions (as in pbrt-v4: the first 1000).
constexpr int kHaltonDimensions = 1000;
// The i-th prime, i in [0, kHaltonDimensions): 2, 3, 5, 7, 11, ...
int Prime(int i);
// The radical inverse of a in base b: its base-b digits mirrored about the radix point.
double RadicalInverse(int base, uint64_t a);
// The digits of the radical inverse, each through a random permutation of [0, base): one
// permutation per digit position ("permutedigits"), or one per digit position and value of
// the digits before it, i.e. nested (Owen) scrambling ("owen"). The digits run on past a's
// own (permuted zeros are not zero) until their weight is below 2^-32.
double ScrambledRadicalInverse(int base, uint64_t a, uint64_t seed, Randomization r);
// The index whose first nDigits base-b digits, mirrored, are v's (v < base^nDigits): the
// index i with floor(RadicalInverse(base, i) * base^nDigits) = v.
uint64_t InverseRadicalInverse(uint64_t v, int base, int nDigits);

// --- z-order -----------------------------------------------------------------------------
// Interleaves the bits of x (even positions) and y (odd positions).
uint64_t EncodeMorton2(uint32_t x, uint32_t y);
// The index of the z-order sampler: `index` has nBits bits (its top digits first: pixel
// Morton code, then sample bits); each base-4 digit (the lowest bit alone when nBits is odd)
// goes through a random permutation chosen by the digits above it and by hash, so that each
// aligned block of 4^k indices maps onto another aligned block of 4^k.
uint64_t ShuffleBase4Digits(uint64_t index, int nBits, uint64_t hash);

// --- pmj02bn ------------------------------------------------------------------------------
// n points (n a power of two, at most 2^16) of a progressive multi-jittered (0, 2) sequence:
// every prefix of 2^m points is a (0, m, 2)-net in base 2 (one point in each elementary
// interval of area 2^-m), as 32-bit fractions. Built as Sobol' points through nested
// scrambles whose random choices are made when a point first needs them (which is what
// pmj02's random stratum choices amount to), each new point chosen by best candidate
// (Mitchell 1991): of a few remaining points of its block [2^(m-1), 2^m), each at a few
// places its choices allow, the one farthest from the points before it. That gives the
// sequence's prefixes pmj02bn's blue-noise spacing (Christensen et al. select among
// candidate positions the same way). Deterministic for a given seed; a longer set starts
// with the shorter one.
std::vector<std::array<uint32_t, 2>> GeneratePMJ02BN(int n, uint64_t seed);

}  // namespace pbrt
