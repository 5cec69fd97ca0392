// Emission that a table-driven wavelength sampler never samples (design §1).
//
// A path only carries wavelengths where the sampler's density is positive. Where a light
// emits but the density is zero, its light is missing from the image: the render is biased,
// however many samples it takes. Two places can hide such emission:
//   - a gap inside the table's range, where all four densities vanish together; the
//     defensive mixture (--wavelength-pdf-defensive) removes it;
//   - the ends outside [lambda_0, lambda_M]: the colour matching functions run over
//     360..830 nm, and pbrt-v4 extends a piecewise-linear spectrum with its end values, so
//     a lamp given on 380..780 nm with non-zero ends does emit there. The defensive mixture
//     is uniform over the table's own range and cannot help; only a wider grid can.
// The scene builder turns the findings into warnings before rendering.
#pragma once

#include <pbrt/lights.h>
#include <pbrt/pbrt.h>
#include <pbrt/wavelengths.h>

#include <string>
#include <utility>
#include <vector>

namespace pbrt {

// How much of one emitter's light falls where the sampler's density is zero. Fractions are
// of the emitter's tristimulus integrals over 360..830 nm (the range the CMFs cover).
struct UnsampledEmission {
    FileLoc loc;                                // the light's directive (empty if unknown)
    std::vector<std::pair<Float, Float>> gaps;  // zero-density stretches [nm] where it emits
    Float gapLuminanceFraction = 0;             // of its luminance (Y) inside those gaps
    // Outside [MinLambda(), MaxLambda()] (but inside 360..830 nm):
    std::vector<std::pair<Float, Float>> outside;  // the stretches [nm] where it emits
    Float outsideLuminanceFraction = 0;            // of its luminance (Y)
    Float outsideTristimulusFraction = 0;          // the largest over X, Y and Z
};

// One entry per distinct emitter (lights that share a spectrum and a directive, such as the
// triangles of one area light, count once) that emits where a table-driven sampler has zero
// density. Empty for the built-in samplers (visible, uniform), whose range is chosen on
// purpose. Lights with zero power are skipped.
std::vector<UnsampledEmission> FindUnsampledEmission(const WavelengthSampler &sampler,
                                                     const std::vector<Light> &lights);

// Emission outside the table's range below these fractions is not worth a warning: a table on
// the default 380..780 nm grid misses about 1e-5 of the luminance of a lamp with a flat floor
// (the CMFs are tiny at the ends). 1e-3 of a tristimulus value is about 0.1 CIEDE2000.
constexpr Float kOutsideLuminanceWarnFraction = 1e-4;
constexpr Float kOutsideTristimulusWarnFraction = 1e-3;

// The warning texts (each starts with the light's file:line:column when known): every gap
// where a light emits, and emission outside the range above the thresholds.
std::vector<std::string> UnsampledEmissionWarnings(const WavelengthSampler &sampler,
                                                   const std::vector<Light> &lights);

}  // namespace pbrt
