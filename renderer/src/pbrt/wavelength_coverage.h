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

#include <wavelength_table.h>

#include <string>
#include <utility>
#include <vector>

namespace pbrt {

// How much of one emitter's light falls where the sampler's density is zero: the header's
// measure (wavelength_table::Coverage, design §1.5), with the light's directive.
struct UnsampledEmission : wavelength_table::Coverage {
    FileLoc loc;  // the light's directive (empty if unknown)
};

// One entry per distinct emitter (lights that share a spectrum and a directive, such as the
// triangles of one area light, count once) that emits where a table-driven sampler has zero
// density. Empty for the built-in samplers (visible, uniform), whose range is chosen on
// purpose. Lights with zero power are skipped.
std::vector<UnsampledEmission> FindUnsampledEmission(const WavelengthSampler &sampler,
                                                     const std::vector<Light> &lights);

// The thresholds of design §1.5, the header's.
using wavelength_table::kOutsideLuminanceWarnFraction;
using wavelength_table::kOutsideTristimulusWarnFraction;

// The warning texts (each starts with the light's file:line:column when known): the header's
// (wavelength_table::CoverageWarnings), with this renderer's other fix for emission outside
// the table's range, uniform sampling over the same range.
std::vector<std::string> UnsampledEmissionWarnings(const WavelengthSampler &sampler,
                                                   const std::vector<Light> &lights);

}  // namespace pbrt
