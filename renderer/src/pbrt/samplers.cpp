#include <pbrt/samplers.h>

#include <pbrt/util/paramdict.h>

#include <array>
#include <cmath>
#include <mutex>

namespace pbrt {

// The pmj02bn sampler's data: point sets (one 2D dimension pair each; set 0 also gives the
// film positions), and for a tile of 2^tileLog2 x 2^tileLog2 pixels the film positions of
// each pixel's samples: set 0's points fall spp to a pixel, so that its blue-noise spacing
// spreads each sample index evenly over neighbouring pixels (pbrt-v4 cuts its 65536 points
// over tiles of up to 256 x 256 pixels; 4096 points over up to 64 x 64 here, generated in
// a tenth of a second on first use).
struct PMJ02BNTables {
    static constexpr int kSets = 5, kMaxSamples = 1 << 16, kTilePoints = 1 << 12;
    int tileLog2 = 0;
    std::array<std::shared_ptr<const std::vector<std::array<uint32_t, 2>>>, kSets> sets;
    std::vector<std::array<uint32_t, 2>> pixelSamples;  // [pixel in tile][sample], in-pixel fractions
};

namespace {

int Log2Floor(uint64_t v) { return 63 - __builtin_clzll(v); }
bool IsPowerOf2(int v) { return v > 0 && (v & (v - 1)) == 0; }
bool IsPowerOf4(int v) { return IsPowerOf2(v) && (Log2Floor(uint64_t(v)) % 2 == 0); }

// Point set k of pmj02bn, at least n points long (a power of two). Generated on first use
// and kept: longer requests extend it (a set's prefixes do not depend on its length).
std::shared_ptr<const std::vector<std::array<uint32_t, 2>>> PMJ02BNSet(int k, int n) {
    static std::mutex mutex;
    static std::array<std::shared_ptr<const std::vector<std::array<uint32_t, 2>>>, PMJ02BNTables::kSets> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto &c = cache[size_t(k)];
    if (!c || int(c->size()) < n)
        c = std::make_shared<const std::vector<std::array<uint32_t, 2>>>(GeneratePMJ02BN(n, uint64_t(k) + 1));
    return c;
}

std::shared_ptr<const PMJ02BNTables> MakePMJ02BNTables(int spp) {
    auto t = std::make_shared<PMJ02BNTables>();
    // A tile of 4^(6 - c) pixels with 4^c >= spp: each pixel holds 4^c of set 0's points.
    int c = 0;
    while ((1 << (2 * c)) < spp) ++c;
    t->tileLog2 = std::max(0, 6 - c);
    const int setZero = std::max(PMJ02BNTables::kTilePoints, 1 << (2 * c));
    int needed = 1;
    while (needed < spp) needed *= 2;
    for (int k = 0; k < PMJ02BNTables::kSets; ++k)
        t->sets[size_t(k)] = PMJ02BNSet(k, k == 0 ? setZero : needed);
    const int tile = 1 << t->tileLog2;
    t->pixelSamples.resize(size_t(tile) * size_t(tile) * size_t(spp));
    std::vector<int> stored(size_t(tile) * size_t(tile), 0);
    for (int i = 0; i < setZero; ++i) {
        const auto &p = (*t->sets[0])[size_t(i)];
        uint32_t cx = t->tileLog2 ? p[0] >> (32 - t->tileLog2) : 0;
        uint32_t cy = t->tileLog2 ? p[1] >> (32 - t->tileLog2) : 0;
        size_t cell = size_t(cy) * size_t(tile) + cx;
        if (stored[cell] == spp) continue;  // spp not a power of 4: the cell's first spp
        t->pixelSamples[cell * size_t(spp) + size_t(stored[cell]++)] = {p[0] << t->tileLog2, p[1] << t->tileLog2};
    }
    return t;
}

Randomization DefaultRandomization(SamplerType t) {
    return t == SamplerType::Halton ? Randomization::PermuteDigits : Randomization::FastOwen;
}

bool IsLowDiscrepancy(SamplerType t) {
    return t != SamplerType::Independent && t != SamplerType::Stratified;
}

}  // namespace

Sampler Sampler::Create(const std::string &name, const ParameterDictionary &params,
                        uint64_t defaultSeed, std::optional<uint64_t> seedOverride,
                        std::optional<int> sppOverride, const FileLoc &loc, Point2i fullRes,
                        bool quick) {
    int samplerSeed = params.GetOneInt("seed", int(defaultSeed));
    uint64_t seed = seedOverride ? *seedOverride : uint64_t(int64_t(samplerSeed));
    // pbrt-v4's defaults: 4 samples per pixel for "independent", 16 for the others.
    int spp = params.GetOneInt("pixelsamples", name == "independent" ? 4 : 16);
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
        if (quick) xs = ys = 1;
        if (xs < 1 || ys < 1) throw PbrtError(loc, "stratified sampler: xsamples and ysamples must be >= 1");
        return Sampler(SamplerType::Stratified, xs * ys, seed, xs, ys, jitter);
    }
    if (sppOverride) spp = *sppOverride;
    if (quick) spp = 1;
    if (spp < 1) throw PbrtError(loc, "\"pixelsamples\" must be at least 1");
    if (name == "independent") return Sampler(SamplerType::Independent, spp, seed);

    SamplerType type;
    if (name == "sobol") type = SamplerType::Sobol;
    else if (name == "paddedsobol") type = SamplerType::PaddedSobol;
    else if (name == "zsobol") type = SamplerType::ZSobol;
    else if (name == "halton") type = SamplerType::Halton;
    else if (name == "pmj02bn") type = SamplerType::PMJ02BN;
    else
        throw PbrtError(loc, "Sampler \"" + name + "\" is not a pbrt-v4 sampler (use zsobol, "
                             "paddedsobol, sobol, halton, pmj02bn, stratified or independent)");

    Randomization r = DefaultRandomization(type);
    if (type != SamplerType::PMJ02BN) {
        const std::string given = params.GetOneString("randomization", RandomizationName(r));
        bool known = false;
        for (Randomization c : {Randomization::None, Randomization::PermuteDigits,
                                Randomization::FastOwen, Randomization::Owen})
            if (given == RandomizationName(c)) {
                r = c;
                known = true;
            }
        if (!known)
            throw PbrtError(params.Loc("randomization"), "Sampler \"" + name + "\": unknown \"randomization\" \"" +
                                                             given + "\" (expected none, permutedigits, fastowen or owen)");
        if (type == SamplerType::Halton && r == Randomization::FastOwen)
            throw PbrtError(params.Loc("randomization"),
                            "Sampler \"halton\": \"fastowen\" randomization is for base 2 only (as in "
                            "pbrt-v4); use \"permutedigits\" (the default), \"owen\" or \"none\"");
    }
    if (type == SamplerType::PMJ02BN) {
        if (spp > PMJ02BNTables::kMaxSamples)
            throw PbrtError(loc, "Sampler \"pmj02bn\": at most 65536 samples per pixel (as in pbrt-v4), not " +
                                     std::to_string(spp));
        if (!IsPowerOf4(spp))
            Warning(loc, "Sampler \"pmj02bn\": " + std::to_string(spp) + " samples per pixel; its "
                         "results are best with a power of 4 (1, 4, 16, 64, ...)");
    }
    if ((type == SamplerType::PaddedSobol || type == SamplerType::ZSobol) && !IsPowerOf2(spp)) {
        if (type == SamplerType::ZSobol)
            Warning(loc, "Sampler \"zsobol\": " + std::to_string(spp) + " samples per pixel is not a "
                         "power of two; rendering " + std::to_string(1 << Log2Floor(uint64_t(spp))) +
                         " (as pbrt-v4 does)");
        else
            Warning(loc, "Sampler \"paddedsobol\": " + std::to_string(spp) + " samples per pixel is not "
                         "a power of two, which stratifies less well");
    }
    if (type == SamplerType::ZSobol) {
        int res = std::max({fullRes.x, fullRes.y, 1});
        int bits = 2 * (Log2Floor(uint64_t(res)) + ((res & (res - 1)) ? 1 : 0)) + Log2Floor(uint64_t(spp));
        if (bits > 64)
            throw PbrtError(loc, "Sampler \"zsobol\": a " + std::to_string(fullRes.x) + "x" +
                                     std::to_string(fullRes.y) + " image at " + std::to_string(spp) +
                                     " samples per pixel needs a z-order index of " + std::to_string(bits) +
                                     " bits, more than 64; use \"paddedsobol\"");
    }
    return Sampler(type, spp, seed, r, fullRes);
}

Sampler::Sampler(SamplerType type, int samplesPerPixel, uint64_t seed, int xSamples,
                 int ySamples, bool jitter)
    : type(type), randomization(DefaultRandomization(type)), spp(samplesPerPixel),
      xSamples(xSamples), ySamples(ySamples), jitter(jitter), seed(seed) {
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
    if (IsLowDiscrepancy(type)) InitLowDiscrepancy({1, 1});
}

Sampler::Sampler(SamplerType type, int samplesPerPixel, uint64_t seed, Randomization r,
                 Point2i fullResolution)
    : type(type), randomization(r), spp(samplesPerPixel), seed(seed) {
    if (spp < 1) throw PbrtError("the number of samples per pixel must be at least 1");
    if (!IsLowDiscrepancy(type)) throw PbrtError("independent and stratified samplers have no randomization");
    InitLowDiscrepancy(fullResolution);
}

void Sampler::InitLowDiscrepancy(Point2i fullRes) {
    seedHash = MixBits(seed * 0x9e3779b97f4a7c15ULL + 0x5eed);
    if (type == SamplerType::ZSobol) {
        log2spp = Log2Floor(uint64_t(spp));
        spp = 1 << log2spp;
        int res = std::max({fullRes.x, fullRes.y, 1});
        int log2res = Log2Floor(uint64_t(res)) + ((res & (res - 1)) ? 1 : 0);
        zBits = 2 * log2res + log2spp;
        if (zBits > 64) throw PbrtError("zsobol: the z-order index needs more than 64 bits");
    } else if (type == SamplerType::Halton) {
        // Pixels per tile along x (base 2) and y (base 3), covering up to 128 pixels.
        for (int i = 0; i < 2; ++i) {
            const uint64_t base = i == 0 ? 2 : 3;
            const int res = std::min(std::max(i == 0 ? fullRes.x : fullRes.y, 1), 128);
            haltonScale[i] = 1;
            haltonExp[i] = 0;
            while (haltonScale[i] < uint64_t(res)) {
                haltonScale[i] *= base;
                ++haltonExp[i];
            }
        }
        // The inverse of 2^exp[0] modulo 3^exp[1] (at most 243: a search will do).
        haltonInverse = 0;
        while (haltonScale[1] > 1 && (haltonScale[0] * haltonInverse) % haltonScale[1] != 1) ++haltonInverse;
    } else if (type == SamplerType::PMJ02BN) {
        if (spp > PMJ02BNTables::kMaxSamples) throw PbrtError("pmj02bn: at most 65536 samples per pixel");
        pmj = MakePMJ02BNTables(spp);
    }
}

std::string Sampler::Description() const {
    const std::string r = RandomizationName(randomization);
    switch (type) {
    case SamplerType::Independent: return "independent";
    case SamplerType::Stratified:
        return "stratified " + std::to_string(xSamples) + "x" + std::to_string(ySamples);
    case SamplerType::Sobol:
        return randomization == Randomization::FastOwen ? "owen-scrambled sobol" : "sobol (" + r + ")";
    case SamplerType::PaddedSobol: return "paddedsobol (" + r + ")";
    case SamplerType::ZSobol: return "zsobol (" + r + ")";
    case SamplerType::Halton: return "halton (" + r + ")";
    case SamplerType::PMJ02BN: return "pmj02bn";
    }
    return "?";
}

void Sampler::StartPixelSample(Point2i p, int index, int dim) {
    pixel = p;
    pixelHash = HashInts({uint64_t(p.x), uint64_t(p.y), seed});
    sampleIndex = index;
    reversedIndex = ReverseBits32(uint32_t(index));
    dimension = dim;
    switch (type) {
    case SamplerType::Independent:
    case SamplerType::Stratified:
        if (type == SamplerType::Stratified && !jitter) break;
        // One PCG32 stream per pixel; sample i starts 2^20 draws after sample i - 1.
        rng.SetSequence(pixelHash, 0);
        if (jumps && index >= 0 && size_t(index) < jumps->size())
            rng.Advance((*jumps)[size_t(index)]);
        else
            rng.Advance(int64_t(index) << 20);
        if (dim > 0) rng.Advance(int64_t(dim));  // one draw per dimension before dim
        break;
    case SamplerType::ZSobol:
        mortonIndex = (EncodeMorton2(uint32_t(p.x), uint32_t(p.y)) << log2spp) | uint64_t(index);
        break;
    case SamplerType::Halton: {
        // The index of the sequence's first point in pixel p (mod 128): its first exp[0]
        // base-2 digits mirrored give x, its first exp[1] base-3 digits mirrored give y;
        // the two residues combine by the Chinese remainder theorem (2^a and 3^b are coprime).
        const uint64_t m0 = haltonScale[0], m1 = haltonScale[1], stride = m0 * m1;
        uint64_t r0 = InverseRadicalInverse(uint64_t(p.x % 128), 2, haltonExp[0]);
        uint64_t r1 = InverseRadicalInverse(uint64_t(p.y % 128), 3, haltonExp[1]);
        // offset = r0 + m0 k = r1 (mod m1) for k = (r1 - r0) / m0 (mod m1).
        uint64_t k = ((r1 + m1 - r0 % m1) % m1) * haltonInverse % m1;
        haltonIndex = (r0 + m0 * k) % stride + uint64_t(index) * stride;
        dimension = std::max(2, dim);
        break;
    }
    case SamplerType::PMJ02BN: dimension = std::max(2, dim); break;
    case SamplerType::Sobol:
    case SamplerType::PaddedSobol: break;
    }
}

Float Sampler::HaltonSample(int dim) const {
    const int base = Prime(dim);
    double v = randomization == Randomization::None
                   ? RadicalInverse(base, haltonIndex)
                   : ScrambledRadicalInverse(base, haltonIndex, GlobalDimensionHash(dim), randomization);
    return std::min(Float(v), OneMinusEpsilon);
}

uint32_t Sampler::DitherMask(int dim) const {
    // pbrt-v4 rotates pmj02bn's points per pixel by blue-noise textures. Here: in each tile of
    // 128 x 128 pixels, the radical inverses of the pixels' z-order indices with the base-4
    // digits shuffled level by level (as zsobol does), Owen-scrambled: the values of every
    // aligned 2^k x 2^k block of pixels are stratified in 4^k intervals (an ordered-dither
    // mask with random structure), each value uniform over seeds.
    uint64_t h = HashInts({uint64_t(pixel.x >> 7), uint64_t(pixel.y >> 7), uint64_t(dim), seed});
    uint64_t z = ShuffleBase4Digits(EncodeMorton2(uint32_t(pixel.x & 127), uint32_t(pixel.y & 127)), 14, h);
    return OwenScramble(SobolDim0Wide(z), uint32_t(h >> 32));
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
        if (randomization != Randomization::FastOwen)
            return ToUnitFloat(Scramble(SobolDim0(index), randomization, uint32_t(h >> 32)));
        return ToUnitFloat(ReverseBits32(LaineKarrasPermutation(index, uint32_t(h >> 32))));
    }
    case SamplerType::PaddedSobol: {
        uint64_t h = DimensionHash(dim);
        uint32_t index = PermutationElement(uint32_t(sampleIndex), uint32_t(spp), uint32_t(h));
        return ToUnitFloat(Scramble(SobolDim0(index), randomization, uint32_t(h >> 32)));
    }
    case SamplerType::ZSobol: {
        uint64_t h = GlobalDimensionHash(dim);
        uint64_t index = ShuffleBase4Digits(mortonIndex, zBits, h);
        return ToUnitFloat(Scramble(SobolDim0Wide(index), randomization, uint32_t(h >> 32)));
    }
    case SamplerType::Halton:
        if (dim >= kHaltonDimensions) {  // past the last prime: start over at dimension 2
            dim = 2;
            dimension = 3;
        }
        return HaltonSample(dim);
    case SamplerType::PMJ02BN: {
        // Jittered strata, randomly permuted per pixel and dimension, all shifted by the mask.
        uint32_t s = PermutationElement(uint32_t(sampleIndex), uint32_t(spp), uint32_t(DimensionHash(dim)));
        Float delta = DitherMask(dim) * 0x1p-32f;
        return std::min<Float>((s + delta) / spp, OneMinusEpsilon);
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
        if (randomization != Randomization::FastOwen)
            return {ToUnitFloat(Scramble(SobolDim0(index), randomization, uint32_t(h >> 32))),
                    ToUnitFloat(Scramble(SobolDim1(index), randomization, uint32_t(h2)))};
        return {ToUnitFloat(ReverseBits32(LaineKarrasPermutation(index, uint32_t(h >> 32)))),
                ToUnitFloat(ReverseBits32(LaineKarrasPermutation(
                    kSobolDim1Reversed[0][index & 0xff] ^ kSobolDim1Reversed[1][(index >> 8) & 0xff] ^
                    kSobolDim1Reversed[2][(index >> 16) & 0xff] ^ kSobolDim1Reversed[3][index >> 24],
                    uint32_t(h2))))};
    }
    case SamplerType::PaddedSobol: {
        uint64_t h = DimensionHash(dim);
        uint32_t index = PermutationElement(uint32_t(sampleIndex), uint32_t(spp), uint32_t(h));
        return {ToUnitFloat(Scramble(SobolDim0(index), randomization, uint32_t(h >> 32))),
                ToUnitFloat(Scramble(SobolDim1(index), randomization, uint32_t(MixBits(h))))};
    }
    case SamplerType::ZSobol: {
        uint64_t h = GlobalDimensionHash(dim);
        uint64_t index = ShuffleBase4Digits(mortonIndex, zBits, h);
        return {ToUnitFloat(Scramble(SobolDim0Wide(index), randomization, uint32_t(h >> 32))),
                ToUnitFloat(Scramble(SobolDim1Wide(index), randomization, uint32_t(MixBits(h))))};
    }
    case SamplerType::Halton:
        if (dim + 1 >= kHaltonDimensions) {
            dim = 2;
            dimension = 4;
        }
        return {HaltonSample(dim), HaltonSample(dim + 1)};
    case SamplerType::PMJ02BN: {
        // Dimension pairs 1-4 use point sets 1-4 by sample index, as pbrt-v4 does (every pixel
        // the same points, rotated by its mask); further pairs cycle through the sets with
        // the index permuted per pixel and dimension.
        int set = dim / 2;
        uint32_t index = uint32_t(sampleIndex);
        if (set >= PMJ02BNTables::kSets)
            index = PermutationElement(index, uint32_t(spp), uint32_t(DimensionHash(dim)));
        const std::array<uint32_t, 2> &u = (*pmj->sets[size_t(set % PMJ02BNTables::kSets)])[index];
        return {ToUnitFloat(u[0] + DitherMask(dim)), ToUnitFloat(u[1] + DitherMask(dim + 1))};
    }
    }
    return {};
}

Point2f Sampler::GetPixel2D() {
    if (type == SamplerType::Halton) {
        // The digits of the sequence's first two dimensions after those that chose the pixel.
        return {std::min(Float(RadicalInverse(2, haltonIndex >> haltonExp[0])), OneMinusEpsilon),
                std::min(Float(RadicalInverse(3, haltonIndex / haltonScale[1])), OneMinusEpsilon)};
    }
    if (type == SamplerType::PMJ02BN) {
        // The tile's film positions, the tile shifted by the seed (wrapping around).
        const int mask = (1 << pmj->tileLog2) - 1;
        const int px = int((uint64_t(pixel.x) + (seedHash & 0xffff)) & uint64_t(mask));
        const int py = int((uint64_t(pixel.y) + ((seedHash >> 16) & 0xffff)) & uint64_t(mask));
        const auto &u = pmj->pixelSamples[(size_t(py) * size_t(mask + 1) + size_t(px)) * size_t(spp) +
                                          size_t(sampleIndex)];
        return {ToUnitFloat(u[0]), ToUnitFloat(u[1])};
    }
    return Get2D();
}

WavelengthNet::WavelengthNet(Point2i p, uint64_t seed) {
    const uint64_t h = HashInts({uint64_t(uint32_t(p.x)), uint64_t(uint32_t(p.y)), seed, 0x6e6574ULL});
    for (uint64_t d = 0; d < 4; ++d) scramble[d] = uint32_t(MixBits(h ^ (d + 1)));
}

void WavelengthNet::Sample(int sampleIndex, Point2f *uFilm, Float *uLambda, Float *uLight) const {
    // Sample index i of the pixel's own sequence: the net needs the pixel's samples to be
    // consecutive Sobol' points, which the image-wide "sobol" sampler's are not.
    const uint32_t i = uint32_t(sampleIndex);
    *uFilm = {ToUnitFloat(OwenScramble(SobolDim0(i), scramble[0])),
              ToUnitFloat(OwenScramble(SobolDim1(i), scramble[1]))};
    *uLambda = ToUnitFloat(OwenScramble(SobolDim2(i), scramble[2]));
    *uLight = ToUnitFloat(OwenScramble(SobolDim3(i), scramble[3]));
}

}  // namespace pbrt
