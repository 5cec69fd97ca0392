// The scene's total emitted spectral power (design §5.6): what `pbrt --emission-spectrum`
// writes, and what the optimizer's whole-scene mode (design §3.1) optimizes one table for.
#pragma once

#include <string>
#include <vector>

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

// Throws PbrtError when the scene has no light with positive power.
EmissionSpectrum SceneEmissionSpectrum(const Scene &scene);

// Writes `lambda value` lines (a pbrt .spd file, full double precision) to path, through a
// temporary file renamed into place (never a partial file). Throws PbrtError on failure.
void WriteEmissionSpectrum(const std::string &path, const EmissionSpectrum &s);

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
