// Random numbers and hashing: the PCG32 generator (O'Neill 2014, "PCG: A Family of Simple
// Fast Space-Efficient Statistically Good Algorithms for Random Number Generation",
// XSH-RR output on a 64-bit LCG with the constants of the reference implementation), and a
// 64-bit bit mixer (the SplitMix64 finalizer, "Mix13" constants of D. Stafford 2011) used
// to derive independent seeds from pixel coordinates, sample indices and dimensions.
#pragma once

#include <pbrt/util/vecmath.h>

#include <cstdint>
#include <initializer_list>

namespace pbrt {

inline uint64_t MixBits(uint64_t v) {
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ULL;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dULL;
    v ^= v >> 33;
    return v;
}

// Hash of a list of integers (order matters).
inline uint64_t HashInts(std::initializer_list<uint64_t> values) {
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (uint64_t v : values) h = MixBits(h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2)));
    return h;
}

class RNG {
  public:
    RNG() = default;
    RNG(uint64_t seqIndex, uint64_t offset) { SetSequence(seqIndex, offset); }
    explicit RNG(uint64_t seqIndex) { SetSequence(seqIndex, MixBits(seqIndex)); }

    // Selects one of 2^63 streams and a starting offset in it.
    void SetSequence(uint64_t seqIndex, uint64_t offset) {
        state = 0u;
        inc = (seqIndex << 1u) | 1u;
        Uniform32();
        state += offset;
        Uniform32();
    }

    uint32_t Uniform32() {
        uint64_t old = state;
        state = old * kMultiplier + inc;
        uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    // A float uniform in [0, 1).
    Float UniformFloat() { return std::min<Float>(OneMinusEpsilon, Uniform32() * 0x1p-32f); }

    // Jumps the generator by delta steps (Brown 1994, "Random number generation with
    // arbitrary strides"), in O(log delta).
    // Advance(delta) as an affine map of the state, state -> mult * state + plus1 * inc:
    // the loop below is linear in inc, so plus1 is its accPlus for inc = 1. A caller that
    // advances by the same deltas again and again keeps these (Sampler) and Jump()s.
    struct Jump {
        uint64_t mult = 1, plus1 = 0;
    };
    static Jump JumpFor(int64_t idelta) {
        uint64_t curMult = kMultiplier, curPlus = 1u;
        Jump j;
        for (uint64_t delta = uint64_t(idelta); delta > 0; delta /= 2) {
            if (delta & 1) {
                j.mult *= curMult;
                j.plus1 = j.plus1 * curMult + curPlus;
            }
            curPlus = (curMult + 1) * curPlus;
            curMult *= curMult;
        }
        return j;
    }
    void Advance(const Jump &j) { state = j.mult * state + j.plus1 * inc; }

    void Advance(int64_t idelta) {
        uint64_t curMult = kMultiplier, curPlus = inc, accMult = 1u, accPlus = 0u;
        uint64_t delta = uint64_t(idelta);
        while (delta > 0) {
            if (delta & 1) {
                accMult *= curMult;
                accPlus = accPlus * curMult + curPlus;
            }
            curPlus = (curMult + 1) * curPlus;
            curMult *= curMult;
            delta /= 2;
        }
        state = accMult * state + accPlus;
    }

  private:
    static constexpr uint64_t kMultiplier = 0x5851f42d4c957f2dULL;
    uint64_t state = 0x853c49e6748fea9bULL, inc = 0xda3e39cb94b95bdbULL;
};

}  // namespace pbrt
