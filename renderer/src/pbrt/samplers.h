// Pixel samplers: the sample values a path consumes, one dimension after another.
//
// Every value depends only on (pixel, sample index, dimension, seed) and the film's full
// resolution, so a render is the same whatever the number of threads or the order in which
// pixels are visited, and StartPixelSample(p, i) replays sample i of pixel p exactly.
//
// The samplers of pbrt-v4's scene format (any of them converges to the same image; the
// low-discrepancy ones take "randomization": none, permutedigits, fastowen or owen):
//   "independent"   uniform random numbers (PCG32 per pixel sample); "pixelsamples" 4
//   "stratified"    jittered strata, per dimension randomly permuted ("xsamples" x
//                   "ysamples" per pixel, "jitter")
//   "sobol"         this renderer's Sobol' sampler: each pair of dimensions is the first two
//                   Sobol' dimensions (a (0,2)-sequence) with the index shuffled per pixel
//                   and dimension by a nested scramble (Burley 2020), values scrambled as
//                   "randomization" says (default fastowen). pbrt-v4's "sobol" instead runs
//                   one Sobol' sequence over the whole image (same expectation, different
//                   noise pattern; kept so that images stay as they were, README)
//   "paddedsobol"   pbrt-v4's PaddedSobolSampler: per pixel and dimension a random
//                   permutation of the sample indices, then the first two Sobol' dimensions
//   "zsobol"        pbrt-v4's default, ZSobolSampler (Ahmed and Wonka 2020): one Sobol'
//                   sequence over the image in randomly shuffled z-order, which spreads the
//                   error as blue noise; renders 2^floor(log2 n) samples per pixel
//   "halton"        pbrt-v4's HaltonSampler: one Halton sequence over the image (tiles of
//                   128 x 128 pixels), the first two dimensions choosing the pixel;
//                   randomization permutedigits (default), owen or none
//   "pmj02bn"       pbrt-v4's PMJ02BNSampler: progressive multi-jittered (0,2) point sets
//                   with blue-noise ordering (util/lowdiscrepancy.h) for 2D dimensions and the
//                   film position, jittered strata for 1D ones, all rotated per pixel by a
//                   dither mask; at most 65536 samples per pixel
#pragma once

#include <pbrt/util/lowdiscrepancy.h>
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

enum class SamplerType { Independent, Stratified, Sobol, PaddedSobol, ZSobol, Halton, PMJ02BN };

// The pmj02bn sampler's point sets and per-pixel film positions (shared by copies).
struct PMJ02BNTables;

class Sampler {
  public:
    Sampler() = default;
    // For Stratified, spp = xSamples * ySamples. Low-discrepancy types get their default
    // randomization and a 1 x 1 image.
    Sampler(SamplerType type, int samplesPerPixel, uint64_t seed, int xSamples = 1,
            int ySamples = 1, bool jitter = true);
    // A low-discrepancy sampler with its randomization; zsobol and halton follow one
    // sequence over an image of fullResolution pixels. zsobol rounds samplesPerPixel down
    // to a power of two (as pbrt-v4 does).
    Sampler(SamplerType type, int samplesPerPixel, uint64_t seed, Randomization randomization,
            Point2i fullResolution);

    // From a Sampler directive ("pixelsamples", "seed", and per type "xsamples", "ysamples",
    // "jitter", "randomization"). The seed is `seed` if given (--seed), else the directive's
    // "seed", else defaultSeed (Option "seed"); spp (--spp) replaces the sample count (for
    // "stratified", as its most square factorization, as pbrt-v4 does); quick (--quick)
    // makes it 1. fullResolution is the film's. Throws PbrtError at loc (or at the
    // parameter) for unknown types, bad counts and randomizations a type does not have.
    static Sampler Create(const std::string &name, const ParameterDictionary &params,
                          uint64_t defaultSeed, std::optional<uint64_t> seed,
                          std::optional<int> spp, const FileLoc &loc,
                          Point2i fullResolution = {1, 1}, bool quick = false);

    SamplerType Type() const { return type; }
    Randomization GetRandomization() const { return randomization; }
    int SamplesPerPixel() const { return spp; }
    uint64_t Seed() const { return seed; }
    std::string Description() const;

    // Begins sample `sampleIndex` of pixel p; dimension counting restarts at `dimension`.
    void StartPixelSample(Point2i p, int sampleIndex, int dimension = 0);
    Float Get1D();
    Point2f Get2D();
    // The film position sample within the pixel, drawn first in every pixel sample (halton
    // and pmj02bn have their own; the others take the next 2D dimensions).
    Point2f GetPixel2D();

  private:
    void InitLowDiscrepancy(Point2i fullResolution);
    uint64_t DimensionHash(int dim) const { return MixBits(pixelHash ^ (uint64_t(dim + 1) * 0x9e3779b97f4a7c15ULL)); }
    // The same without the pixel: for the samplers that run one sequence over the image.
    uint64_t GlobalDimensionHash(int dim) const { return MixBits(seedHash ^ (uint64_t(dim + 1) * 0x9e3779b97f4a7c15ULL)); }
    Float HaltonSample(int dim) const;
    uint32_t DitherMask(int dim) const;  // pmj02bn's per-pixel rotation, a 32-bit fraction

    SamplerType type = SamplerType::Independent;
    Randomization randomization = Randomization::FastOwen;
    int spp = 1, xSamples = 1, ySamples = 1;
    bool jitter = true;
    uint64_t seed = 0, seedHash = 0, pixelHash = 0;
    Point2i pixel;
    int sampleIndex = 0, dimension = 0;
    uint32_t reversedIndex = 0;  // the bit-reversed sample index (Sobol)
    // zsobol: bits of the z-order index (2 log2 of the resolution rounded up to a power of
    // two, plus log2 spp), the pixel's Morton code followed by the sample index.
    int log2spp = 0, zBits = 0;
    uint64_t mortonIndex = 0;
    // halton: 2^exp[0] >= min(width, 128) and 3^exp[1] >= min(height, 128) pixels per tile,
    // and the index of the current sample in the image-wide sequence.
    int haltonExp[2] = {0, 0};
    uint64_t haltonScale[2] = {1, 1}, haltonInverse = 0, haltonIndex = 0;
    std::shared_ptr<const PMJ02BNTables> pmj;
    // RNG::JumpFor(i << 20) for every sample index i (for the samplers that draw from the
    // RNG; shared by the copies each thread makes): StartPixelSample's advance in O(1).
    std::shared_ptr<const std::vector<RNG::Jump>> jumps;
    RNG rng;
};

// --wavelength-net (design §5.2): the numbers of sample `sampleIndex` of pixel p that decide
// which spectrum the sample sees, drawn together with its wavelength number: dimensions 0-3 of
// the Sobol' sequence, each Owen-scrambled by a hash of the pixel, the dimension and seed, give
// the film position (0, 1), the wavelength number (2) and the first next-event estimation's
// choice of light (3). A pixel's first 2^m samples are then a (1, m, 3)-net in position and
// wavelength and, for m >= 4, a (1, m, 2)-net in wavelength and light: the samples that land
// on one side of an edge in the pixel, or that pick one lamp, still have wavelength numbers
// spread over [0, 1). Every pixel sampler draws these from separate dimensions, so a pixel's
// stratified wavelengths are stratified only over all of its samples together, and where its
// samples see different spectra that removes little. Each point is uniform on [0, 1)^4 and
// independent of the sampler's other dimensions: unbiased. Made once per pixel (the scrambles'
// seeds), then asked for each sample.
class WavelengthNet {
  public:
    WavelengthNet(Point2i p, uint64_t seed);
    void Sample(int sampleIndex, Point2f *uFilm, Float *uLambda, Float *uLight) const;

  private:
    uint32_t scramble[4];
};

}  // namespace pbrt
