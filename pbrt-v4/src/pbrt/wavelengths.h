// Wavelength sampling: the sample / pdf / invert triples of the built-in densities, and
// WavelengthSampler, the one seam through which the renderer draws the four wavelengths
// of a path (SPEC sections 1 and 5).
#pragma once

#include <pbrt/pbrt.h>
#include <pbrt/util/spectrum.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <variant>
#include <vector>

// patches/include/wavelength_table.h (included by wavelengths.cpp only).
namespace wavelength_table {
struct Table;
}

namespace pbrt {

// ---- pbrt-v4's visible-wavelength density ------------------------------------------------
// p(lambda) proportional to sech^2(A (lambda - C)) on [Lambda_min, Lambda_max], zero
// elsewhere, with A = 0.0072 / nm and C = 538 nm: the constants of pbrt-v4's
// SampleVisibleWavelengths (PBR book 4th ed., chapter 5, sensor response; a fit in the
// spirit of Radziszewski et al. 2009), fixed in SPEC section 5. Its CDF is analytic:
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

inline Float SampleVisibleWavelengths(Float u) {
    using namespace visible_density;
    double t = T0() + std::clamp(double(u), 0.0, 1.0) * (T1() - T0());
    double lambda = C + std::atanh(t) / A;
    return Float(std::clamp(lambda, double(Lambda_min), double(Lambda_max)));
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

// ---- The samplers WavelengthSampler can be ------------------------------------------------
// Each is a small struct with Sample / PDF / Description / range; a new kind (such as
// issue 4's table-driven sampler below) is one more struct and one more variant alternative.

// pbrt-v4's default: four stratified wavelengths from the visible density.
struct VisibleWavelengthSampler {
    SampledWavelengths Sample(Float u) const { return SampledWavelengths::SampleVisible(u); }
    Float PDF(Float lambda) const { return VisibleWavelengthsPDF(lambda); }
    std::string Description() const;
    Float MinLambda() const { return Lambda_min; }
    Float MaxLambda() const { return Lambda_max; }
};

// Four stratified wavelengths, uniform on [lmin, lmax] (the evaluation's baseline).
struct UniformWavelengthSampler {
    Float lmin = Lambda_min, lmax = Lambda_max;
    SampledWavelengths Sample(Float u) const {
        return SampledWavelengths::SampleUniform(u, lmin, lmax);
    }
    Float PDF(Float lambda) const { return UniformWavelengthsPDF(lambda, lmin, lmax); }
    std::string Description() const;
    Float MinLambda() const { return lmin; }
    Float MaxLambda() const { return lmax; }
};

// Issue 4: four wavelengths from one u, lambda_k = F_k^-1(u) for the four densities of a
// table (patches/include/wavelength_table.h), each carrying the mixture density
// (1/4) sum_k p_k(lambda) the film divides by (the balance heuristic, SPEC section 1).
struct TableWavelengthSampler {
    std::shared_ptr<const wavelength_table::Table> table;  // already mixed with `share`
    Float share = 0;  // defensive uniform share mixed in (0: the table as written)
    std::string file;    // the table file as named on the command line
    std::string sha256;  // SHA-256 of the bytes read from it (hexadecimal)
    SampledWavelengths Sample(Float u) const;
    Float PDF(Float lambda) const;
    std::string Description() const;
    Float MinLambda() const;
    Float MaxLambda() const;
};

// The seam: the renderer draws the wavelengths of every path through one of these.
class WavelengthSampler {
  public:
    static WavelengthSampler Visible();
    // Throws PbrtError unless 0 < lmin < lmax are finite.
    static WavelengthSampler Uniform(Float lmin, Float lmax);
    // Reads a wavelength table (either layout of SPEC section 2); a bad table throws
    // PbrtError "FILE:LINE: reason". defensiveShare in [0, 1] mixes each density with a
    // uniform density over the table's range (the fix for zero densities, SPEC section 1).
    static WavelengthSampler FromTable(const std::string &path, Float defensiveShare = 0);

    // Four wavelengths (and the per-wavelength densities the film divides by) from one u.
    SampledWavelengths Sample(Float u) const;
    // The per-wavelength density pdf(lambda) the estimator uses: for a mixture of N
    // densities, (1/N) sum_k p_k(lambda) (SPEC section 1). Zero where it never samples.
    Float PDF(Float lambda) const;
    std::string Description() const;
    Float MinLambda() const;
    Float MaxLambda() const;
    // Whether this samples from a table (FromTable).
    bool IsTable() const;
    // "visible", "uniform" or "table": the kind, as the command line names it.
    std::string Name() const;
    // The table sampler (its file, hash and defensive share); nullptr unless IsTable().
    const TableWavelengthSampler *Table() const { return std::get_if<TableWavelengthSampler>(&impl); }
    // Stretches [a, b] nm inside [MinLambda(), MaxLambda()] where PDF is zero (a table whose
    // four densities vanish together); empty for the built-in samplers.
    std::vector<std::pair<Float, Float>> ZeroDensityIntervals() const;

  private:
    using Impl = std::variant<VisibleWavelengthSampler, UniformWavelengthSampler,
                              TableWavelengthSampler>;
    explicit WavelengthSampler(Impl impl) : impl(std::move(impl)) {}
    Impl impl;
};

}  // namespace pbrt
