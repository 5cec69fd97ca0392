// The built-in wavelength densities as sample / pdf / invert triples: pbrt-v4's visible
// density and the uniform density. Header only, with no dependency on the renderer, so the
// spectra (util/spectrum.cpp) and the build-time RGB-to-spectrum tool can use them.
#pragma once

#include <pbrt/pbrt.h>
#include <pbrt/util/spectrum.h>

#include <algorithm>
#include <cmath>

namespace pbrt {

// ---- pbrt-v4's visible-wavelength density ------------------------------------------------
// p(lambda) proportional to sech^2(A (lambda - C)) on [Lambda_min, Lambda_max], zero
// elsewhere, with A = 0.0072 / nm and C = 538 nm: the constants of pbrt-v4's
// SampleVisibleWavelengths (PBR book 4th ed., chapter 5, sensor response; a fit in the
// spirit of Radziszewski et al. 2009), fixed in design §5. Its CDF is analytic:
// F(lambda) = (tanh(A (lambda - C)) - T0) / (T1 - T0), T0/T1 = tanh(A (Lambda_min/max - C)).
namespace visible_density {
constexpr double A = 0.0072, C = 538;
inline double T0() {
    static const double t0 = std::tanh(A * (double(Lambda_min) - C));
    return t0;
}
inline double T1() {
    static const double t1 = std::tanh(A * (double(Lambda_max) - C));
    return t1;
}
}  // namespace visible_density

inline Float VisibleWavelengthsPDF(Float lambda) {
    using namespace visible_density;
    if (!(lambda >= Lambda_min && lambda <= Lambda_max)) return 0;
    double ch = std::cosh(A * (double(lambda) - C));
    // Normalization: the integral of sech^2 over the range is (T1 - T0) / A.
    return Float(A / ((T1() - T0()) * ch * ch));
}

// tanh(A (lambda - C)) of the wavelength SampleVisibleWavelengths(u) returns (before its
// rounding to Float), and the density there from it.
inline double VisibleWavelengthsTanh(Float u) {
    using namespace visible_density;
    return T0() + std::clamp(double(u), 0.0, 1.0) * (T1() - T0());
}
inline Float VisibleWavelengthsPDFFromTanh(double t) {
    using namespace visible_density;
    return Float(A / (T1() - T0()) * (1 - t * t));
}

// The wavelength whose tanh(A (lambda - C)) is t, given log((1 + t) / (1 - t)) = 2 atanh(t):
// atanh as a logarithm is within 3e-16 of std::atanh for |t| <= 0.97 (this range), a
// fraction of a float's rounding, and half the time of libm's atanh (docs/performance.md).
inline double VisibleWavelengthsAtanhRatio(double t) { return (1 + t) / (1 - t); }
inline Float VisibleWavelengthFromLogRatio(double logRatio) {
    using namespace visible_density;
    double lambda = C + 0.5 * logRatio / A;
    return Float(std::clamp(lambda, double(Lambda_min), double(Lambda_max)));
}

inline Float SampleVisibleWavelengths(Float u) {
    return VisibleWavelengthFromLogRatio(std::log(VisibleWavelengthsAtanhRatio(VisibleWavelengthsTanh(u))));
}

inline Float InvertVisibleWavelengthsSample(Float lambda) {
    using namespace visible_density;
    double l = std::clamp(double(lambda), double(Lambda_min), double(Lambda_max));
    return Float((std::tanh(A * (l - C)) - T0()) / (T1() - T0()));
}

// ---- Uniform density on [lmin, lmax] ------------------------------------------------------
inline Float UniformWavelengthsPDF(Float lambda, Float lmin, Float lmax) {
    return (lambda >= lmin && lambda <= lmax) ? 1 / (lmax - lmin) : 0;
}

inline Float SampleUniformWavelengths(Float u, Float lmin, Float lmax) {
    return std::clamp(lmin + std::clamp(u, Float(0), Float(1)) * (lmax - lmin), lmin, lmax);
}

inline Float InvertUniformWavelengthsSample(Float lambda, Float lmin, Float lmax) {
    return std::clamp((lambda - lmin) / (lmax - lmin), Float(0), Float(1));
}

}  // namespace pbrt
