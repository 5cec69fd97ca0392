// Wavelength sampling: the sample / pdf / invert triples of the built-in densities, and
// WavelengthSampler, the one seam through which the renderer draws the four wavelengths
// of a path (design §1 and §5).
#pragma once

#include <pbrt/pbrt.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/util/wavelength_densities.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <variant>
#include <vector>

// wavelength_table/include/wavelength_table.h (included by wavelengths.cpp only).
namespace wavelength_table {
struct Table;
}

namespace pbrt {

// ---- The samplers WavelengthSampler can be ------------------------------------------------
// Each is a small struct with Sample / PDF / Description / range; a new kind (such as
// the table-driven sampler below) is one more struct and one more variant alternative.

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

// From a table: four wavelengths from one u, lambda_k = F_k^-1(u) for the four densities of a
// table (wavelength_table/include/wavelength_table.h), each carrying the mixture density
// (1/4) sum_k p_k(lambda) the film divides by (the balance heuristic, design §1).
// Emission sampling (--wavelength-sampling emission) is the same sampler on a table built in
// memory from the scene's lights (emission.h): it has no file, and names its weight.
struct TableWavelengthSampler {
    std::shared_ptr<const wavelength_table::Table> table;  // already mixed with `share`
    Float share = 0;  // defensive uniform share mixed in (0: the table as written)
    std::string file;    // the table file as named on the command line (empty: emission)
    std::string sha256;  // SHA-256 of the bytes read from it (hexadecimal)
    std::string emissionWeight;  // emission sampling: its weight (spd, luminance, xyz)
    double buildSeconds = 0;     // emission sampling: the time to build the table
    std::string guided;          // one of wavelength guiding's tables (guiding.h): what it is
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
    // Reads a wavelength table (either layout of design §2); a bad table throws
    // PbrtError "FILE:LINE: reason". defensiveShare in [0, 1] mixes each density with a
    // uniform density over the table's range (the fix for zero densities, design §1).
    static WavelengthSampler FromTable(const std::string &path, Float defensiveShare = 0);
    // Emission sampling: the table the scene's lights give (emission.h, SceneEmissionTable),
    // built with `weight` in `buildSeconds`; sampled exactly as a table file is.
    static WavelengthSampler FromEmission(std::shared_ptr<const wavelength_table::Table> table,
                                          const std::string &weight, double buildSeconds);
    // One of wavelength guiding's per-pixel tables (guiding.h), built in memory; `label` says
    // which (its mixture and source). Sampled exactly as a table file is.
    static WavelengthSampler FromGuided(std::shared_ptr<const wavelength_table::Table> table,
                                        const std::string &label);

    // Four wavelengths (and the per-wavelength densities the film divides by) from one u.
    SampledWavelengths Sample(Float u) const;
    // The per-wavelength density pdf(lambda) the estimator uses: for a mixture of N
    // densities, (1/N) sum_k p_k(lambda) (design §1). Zero where it never samples.
    Float PDF(Float lambda) const;
    std::string Description() const;
    Float MinLambda() const;
    Float MaxLambda() const;
    // Whether this samples from a table (FromTable or FromEmission).
    bool IsTable() const;
    // "visible", "uniform", "table", "emission" or "guided": the kind, as the command line
    // names it.
    std::string Name() const;
    // The table sampler (its file, hash and defensive share, or its emission weight);
    // nullptr unless IsTable().
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
