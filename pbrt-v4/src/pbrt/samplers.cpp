#include <pbrt/samplers.h>

#include <pbrt/util/paramdict.h>

#include <array>
#include <cmath>

#if defined(__GFNI__) && defined(__SSE2__)
#include <immintrin.h>
#endif

namespace pbrt {

namespace {

uint32_t ReverseBits32(uint32_t n) {
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
uint32_t LaineKarrasPermutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Direction numbers of the second Sobol' dimension (primitive polynomial x + 1): the
// generator matrix is the upper-triangular Pascal matrix mod 2, v_k = v_{k-1} ^ (v_{k-1} >> 1).
// The product with an index is linear over GF(2), so it is tabulated per index byte.
std::array<std::array<uint32_t, 256>, 4> MakeSobolDim1Tables() {
    std::array<uint32_t, 32> v{};
    v[0] = 1u << 31;
    for (int k = 1; k < 32; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
    std::array<std::array<uint32_t, 256>, 4> t{};
    for (int byte = 0; byte < 4; ++byte)
        for (int b = 0; b < 256; ++b) {
            uint32_t r = 0;
            for (int k = 0; k < 8; ++k)
                if (b & (1 << k)) r ^= v[8 * byte + k];
            t[byte][b] = r;
        }
    return t;
}
const std::array<std::array<uint32_t, 256>, 4> kSobolDim1 = MakeSobolDim1Tables();
// The same with every entry bit-reversed: bit reversal is linear over GF(2), so
// ReverseBits32(SobolDim1(i)) is the XOR of these (one reversal less per 2D sample).
std::array<std::array<uint32_t, 256>, 4> ReversedTables(std::array<std::array<uint32_t, 256>, 4> t) {
    for (auto &row : t)
        for (uint32_t &v : row) v = ReverseBits32(v);
    return t;
}
const std::array<std::array<uint32_t, 256>, 4> kSobolDim1Reversed = ReversedTables(kSobolDim1);

Float ToUnitFloat(uint32_t v) { return std::min<Float>(v * 0x1p-32f, OneMinusEpsilon); }

}  // namespace

Sampler Sampler::Create(const std::string &name, const ParameterDictionary &params,
                        uint64_t defaultSeed, std::optional<uint64_t> seedOverride,
                        std::optional<int> sppOverride, const FileLoc &loc) {
    int samplerSeed = params.GetOneInt("seed", int(defaultSeed));
    uint64_t seed = seedOverride ? *seedOverride : uint64_t(int64_t(samplerSeed));
    int spp = params.GetOneInt("pixelsamples", 16);
    if (name == "stratified") {
        int xs = params.GetOneInt("xsamples", 4), ys = params.GetOneInt("ysamples", 4);
        bool jitter = params.GetOneBool("jitter", true);
        if (sppOverride) {
            // pbrt-v4: the most square factorization of the requested count.
            int n = *sppOverride, div = int(std::sqrt(double(n)));
            while (n % div) --div;
            ys = n / div;
            xs = n / ys;
        }
        if (xs < 1 || ys < 1) throw PbrtError(loc, "stratified sampler: xsamples and ysamples must be >= 1");
        return Sampler(SamplerType::Stratified, xs * ys, seed, xs, ys, jitter);
    }
    if (sppOverride) spp = *sppOverride;
    if (spp < 1) throw PbrtError(loc, "\"pixelsamples\" must be at least 1");
    if (name == "independent") return Sampler(SamplerType::Independent, spp, seed);
    if (name == "sobol" || name == "zsobol" || name == "paddedsobol" || name == "halton" ||
        name == "pmj02bn") {
        params.GetOneString("randomization", "");  // any scrambling converges alike
        return Sampler(SamplerType::Sobol, spp, seed);
    }
    throw PbrtError(loc, "Sampler \"" + name + "\" is not supported");
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

uint32_t OwenScramble(uint32_t v, uint32_t seed) {
    return ReverseBits32(LaineKarrasPermutation(ReverseBits32(v), seed));
}

uint32_t SobolDim0(uint32_t index) { return ReverseBits32(index); }

uint32_t SobolDim1(uint32_t index) {
    return kSobolDim1[0][index & 0xff] ^ kSobolDim1[1][(index >> 8) & 0xff] ^
           kSobolDim1[2][(index >> 16) & 0xff] ^ kSobolDim1[3][index >> 24];
}

Sampler::Sampler(SamplerType type, int samplesPerPixel, uint64_t seed, int xSamples,
                 int ySamples, bool jitter)
    : type(type), spp(samplesPerPixel), xSamples(xSamples), ySamples(ySamples),
      jitter(jitter), seed(seed) {
    if (spp < 1) throw PbrtError("the number of samples per pixel must be at least 1");
    if (type == SamplerType::Stratified && xSamples * ySamples != spp)
        throw PbrtError("stratified sampler: xsamples * ysamples must equal the pixel samples");
    constexpr int kMaxJumps = 1 << 16;  // 1 MB; beyond, StartPixelSample advances step by step
    if ((type == SamplerType::Independent || (type == SamplerType::Stratified && jitter)) &&
        spp <= kMaxJumps) {
        auto table = std::make_shared<std::vector<RNG::Jump>>(size_t(spp));
        for (int i = 0; i < spp; ++i) (*table)[size_t(i)] = RNG::JumpFor(int64_t(i) << 20);
        jumps = std::move(table);
    }
}

std::string Sampler::Description() const {
    switch (type) {
    case SamplerType::Independent: return "independent";
    case SamplerType::Stratified:
        return "stratified " + std::to_string(xSamples) + "x" + std::to_string(ySamples);
    case SamplerType::Sobol: return "owen-scrambled sobol";
    }
    return "?";
}

void Sampler::StartPixelSample(Point2i p, int index, int dim) {
    pixel = p;
    pixelHash = HashInts({uint64_t(p.x), uint64_t(p.y), seed});
    sampleIndex = index;
    reversedIndex = ReverseBits32(uint32_t(index));
    dimension = dim;
    if (type == SamplerType::Independent || (type == SamplerType::Stratified && jitter))
    {
        // One PCG32 stream per pixel; sample i starts 2^20 draws after sample i - 1.
        rng.SetSequence(pixelHash, 0);
        if (jumps && index >= 0 && size_t(index) < jumps->size())
            rng.Advance((*jumps)[size_t(index)]);
        else
            rng.Advance(int64_t(index) << 20);
    }
}

Float Sampler::Get1D() {
    int dim = dimension++;
    switch (type) {
    case SamplerType::Independent: return rng.UniformFloat();
    case SamplerType::Stratified: {
        uint32_t s = PermutationElement(uint32_t(sampleIndex % spp), uint32_t(spp),
                                        uint32_t(DimensionHash(dim)));
        Float delta = jitter ? rng.UniformFloat() : 0.5f;
        return std::min<Float>((s + delta) / spp, OneMinusEpsilon);
    }
    case SamplerType::Sobol: {
        // OwenScramble(SobolDim0(i), s) with both bit reversals of dimension 0 cancelled:
        // Reverse(LK(Reverse(Reverse(i)))) = Reverse(LK(i)); reversedIndex likewise caches
        // the first reversal of the index scramble (the same numbers, fewer operations).
        uint64_t h = DimensionHash(dim);
        uint32_t index = ReverseBits32(LaineKarrasPermutation(reversedIndex, uint32_t(h)));
        return ToUnitFloat(ReverseBits32(LaineKarrasPermutation(index, uint32_t(h >> 32))));
    }
    }
    return 0;
}

Point2f Sampler::Get2D() {
    int dim = dimension;
    dimension += 2;
    switch (type) {
    case SamplerType::Independent: {
        Float a = rng.UniformFloat();
        return {a, rng.UniformFloat()};
    }
    case SamplerType::Stratified: {
        uint32_t s = PermutationElement(uint32_t(sampleIndex % spp), uint32_t(spp),
                                        uint32_t(DimensionHash(dim)));
        int x = int(s) % xSamples, y = int(s) / xSamples;
        Float dx = jitter ? rng.UniformFloat() : 0.5f;
        Float dy = jitter ? rng.UniformFloat() : 0.5f;
        return {std::min<Float>((x + dx) / xSamples, OneMinusEpsilon),
                std::min<Float>((y + dy) / ySamples, OneMinusEpsilon)};
    }
    case SamplerType::Sobol: {
        // Both coordinates share one shuffled index so the pair stays a (0,2)-sequence.
        uint64_t h = DimensionHash(dim);
        uint64_t h2 = MixBits(h);
        uint32_t index = ReverseBits32(LaineKarrasPermutation(reversedIndex, uint32_t(h)));
        return {ToUnitFloat(ReverseBits32(LaineKarrasPermutation(index, uint32_t(h >> 32)))),
                ToUnitFloat(ReverseBits32(LaineKarrasPermutation(
                    kSobolDim1Reversed[0][index & 0xff] ^ kSobolDim1Reversed[1][(index >> 8) & 0xff] ^
                    kSobolDim1Reversed[2][(index >> 16) & 0xff] ^ kSobolDim1Reversed[3][index >> 24],
                    uint32_t(h2))))};
    }
    }
    return {};
}

Point2f Sampler::GetPixel2D() { return Get2D(); }

}  // namespace pbrt
