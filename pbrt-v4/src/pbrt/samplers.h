// Pixel samplers: the sample values a path consumes, one dimension after another.
//
// Every value depends only on (pixel, sample index, dimension, seed), so a render is the
// same whatever the number of threads or the order in which pixels are visited.
//
// Scene-file names and what renders them (any of them converges to the same image):
//   "independent"                    uniform random numbers (PCG32 per pixel sample)
//   "stratified"                     jittered strata, per dimension randomly permuted
//                                    ("xsamples" x "ysamples" per pixel, "jitter")
//   "sobol", "zsobol", "paddedsobol", Owen-scrambled (0,2)-sequence: every pair of
//   "halton", "pmj02bn"              dimensions is an independently scrambled 2D Sobol'
//                                    point set with a shuffled order (Burley 2020,
//                                    "Practical Hash-based Owen Scrambling", JCGT 9(4))
#pragma once

#include <pbrt/util/rng.h>
#include <pbrt/util/vecmath.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pbrt {

class ParameterDictionary;
struct FileLoc;

enum class SamplerType { Independent, Stratified, Sobol };

class Sampler {
  public:
    Sampler() = default;
    // For Stratified, spp = xSamples * ySamples.
    Sampler(SamplerType type, int samplesPerPixel, uint64_t seed, int xSamples = 1,
            int ySamples = 1, bool jitter = true);

    // From a Sampler directive ("pixelsamples" 16, "seed", and per type "xsamples",
    // "ysamples", "jitter", "randomization"). The seed is `seed` if given (--seed), else the
    // directive's "seed", else defaultSeed (Option "seed"); spp (--spp) replaces the
    // sample count (for "stratified", as its most square factorization, as pbrt-v4 does).
    // Throws PbrtError at loc for unsupported types and bad counts.
    static Sampler Create(const std::string &name, const ParameterDictionary &params,
                          uint64_t defaultSeed, std::optional<uint64_t> seed,
                          std::optional<int> spp, const FileLoc &loc);

    SamplerType Type() const { return type; }
    int SamplesPerPixel() const { return spp; }
    uint64_t Seed() const { return seed; }
    std::string Description() const;

    // Begins sample `sampleIndex` of pixel p; dimension counting restarts at `dimension`.
    void StartPixelSample(Point2i p, int sampleIndex, int dimension = 0);
    Float Get1D();
    Point2f Get2D();
    // The film position sample: always the first 2D dimension pair of a pixel sample.
    Point2f GetPixel2D();

  private:
    uint64_t DimensionHash(int dim) const { return MixBits(pixelHash ^ (uint64_t(dim + 1) * 0x9e3779b97f4a7c15ULL)); }

    SamplerType type = SamplerType::Independent;
    int spp = 1, xSamples = 1, ySamples = 1;
    bool jitter = true;
    uint64_t seed = 0, pixelHash = 0;
    Point2i pixel;
    int sampleIndex = 0, dimension = 0;
    uint32_t reversedIndex = 0;  // the bit-reversed sample index (Sobol)
    // RNG::JumpFor(i << 20) for every sample index i (for the samplers that draw from the
    // RNG; shared by the copies each thread makes): StartPixelSample's advance in O(1).
    std::shared_ptr<const std::vector<RNG::Jump>> jumps;
    RNG rng;
};

// --- Low-level pieces, exposed for tests ----------------------------------------------
// Random permutation of [0, n) chosen by seed, element i (Kensler 2013, "Correlated
// Multi-Jittered Sampling", Pixar Technical Memo 13-01).
uint32_t PermutationElement(uint32_t i, uint32_t n, uint32_t seed);
// Nested uniform (Owen) scramble of the binary digits of a 32-bit fraction (Burley 2020).
uint32_t OwenScramble(uint32_t v, uint32_t seed);
// The first two dimensions of the Sobol' sequence, as 32-bit fractions.
uint32_t SobolDim0(uint32_t index);
uint32_t SobolDim1(uint32_t index);

}  // namespace pbrt
