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

// Throws PbrtError ("\"PATH\": reason") unless a file can be written at path (not a
// directory; its directory exists), checked before the scene is parsed.
void CheckOutputFilePath(const std::string &path);

}  // namespace pbrt
