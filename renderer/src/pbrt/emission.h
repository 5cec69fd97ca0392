// The scene's total emitted spectral power (design §5.6): what `pbrt --emission-spectrum`
// writes, and what the optimizer's whole-scene mode (design §3.1) optimizes one table for.
#pragma once

#include <memory>
#include <string>
#include <vector>

// wavelength_table/include/wavelength_table.h (included by the .cpp files that build tables).
namespace wavelength_table {
struct Table;
}

namespace pbrt {

struct Scene;

// Phi(lambda) = sum over the scene's lights of PowerFactor() * Scale() * spectrum(lambda)
// (pbrt-v4's light power, Light::Phi), sampled where the sum is exact: the sum of
// piecewise-linear spectra is piecewise linear between the union of their nodes, so those
// nodes are kept; any other spectrum (blackbody, RGB illuminant, densely sampled) adds the
// 1 nm grid 360, 361, ..., 830 nm. Only 360..830 nm is kept (the range the renderer
// samples), with nodes at both ends. Values are in the scene's units (W/nm for scenes in
// pbrt-v4's radiometric units).
struct EmissionSpectrum {
    std::vector<double> lambdas, values;
};

// Throws PbrtError when the scene has no emitters, when its lights all have zero power (naming
// the first light's file:line:column), or when a light's power is not finite (naming it).
EmissionSpectrum SceneEmissionSpectrum(const Scene &scene);

// Writes `lambda value` lines (a pbrt .spd file, full double precision) to path, through a
// temporary file renamed into place (never a partial file). Throws PbrtError on failure.
void WriteEmissionSpectrum(const std::string &path, const EmissionSpectrum &s);

// ---- Emission sampling (design §1.7, §5.2): --wavelength-sampling emission ----------------
// The table the renderer samples wavelengths from when asked to sample the scene's own lamps:
// q = Phi(lambda) * w(lambda) on 360..830 nm, Phi the scene's emitted spectral power above,
// w the weight, cut into four equal-mass densities (wavelength_table::StratifiedTable, the
// construction of wavelength_pdf.stratified). The weights: "spd" (w = 1: the nodes of Phi
// alone, exact for piecewise-linear spectra), "luminance" (ybar) and "xyz" (xbar + ybar +
// zbar), the renderer's CIE 1931 functions at 1 nm, linear between (their nodes join Phi's).

// The weight emission sampling uses unless --emission-weight says otherwise (one constant:
// the benchmark, docs/benchmark.md, decides it).
constexpr const char *kDefaultEmissionWeight = "spd";
// Every weight --emission-weight accepts, in the order the help lists them.
const std::vector<std::string> &EmissionWeights();

// The weight's nodes and values: none for "spd" (w = 1, the spectrum alone), else ybar or
// xbar + ybar + zbar at the CIE 1931 functions' 1 nm nodes 360..830 nm.
void EmissionWeightCurve(const std::string &weight, std::vector<double> *x, std::vector<double> *w);

struct EmissionTable {
    std::shared_ptr<const wavelength_table::Table> table;
    std::string weight;        // one of EmissionWeights()
    size_t emissionNodes = 0;  // nodes of Phi (the table adds the weight's and the cuts)
    double seconds = 0;        // wall-clock time to build it: Phi, the weight and the cuts
};

// Throws PbrtError for an unknown weight and for every error of SceneEmissionSpectrum.
EmissionTable SceneEmissionTable(const Scene &scene, const std::string &weight);

// Writes the table in the commented CSV layout of design §2 (full double precision), through
// a temporary file renamed into place. `source` names the scene in the comments.
void WriteEmissionTable(const std::string &path, const EmissionTable &t, const std::string &source);

// The diffuse reflectances of the materials that the scene's shapes use (design §5.6): the
// "reflectance" of "diffuse", "coateddiffuse" and "conductor" (when given as a reflectance)
// materials, as the renderer builds them (RGB through its sigmoid-polynomial tables), a
// texture by its mean over uv in [0, 1]^2 (32 x 32 cell centres), at 360, 361, ..., 830 nm.
// Materials whose reflectance is zero everywhere are left out (a black surface has no colour
// to estimate), and so are repeats of a reflectance already listed (the first material of
// each distinct reflectance names it). Throws PbrtError when no material is left.
struct MaterialReflectances {
    std::vector<std::string> labels;            // where each material was defined
    std::vector<std::vector<double>> values;    // per material, 471 values
};
MaterialReflectances SceneMaterialReflectances(const Scene &scene);

// Writes them as a reflectance CSV (design §3.4): a "lambda_nm,LABEL..." header, then one
// row per nanometre; through a temporary file renamed into place.
void WriteMaterialReflectances(const std::string &path, const MaterialReflectances &m);

}  // namespace pbrt
