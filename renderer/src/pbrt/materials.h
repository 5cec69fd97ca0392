// Materials: what a surface does with light, as textures that produce a BSDF at a hit.
//   "diffuse"        reflectance (spectrum texture, default 0.5)
//   "conductor"      eta, k (spectrum textures; default the named spectra metal-Cu-eta/-k)
//                    or reflectance; roughness / uroughness / vroughness (default 0),
//                    remaproughness (true: alpha = sqrt(roughness))
//   "dielectric"     eta (float or spectrum, default 1.5; 0 means 1), roughness as above
//   "coateddiffuse"  reflectance 0.5, roughness 0, remaproughness, thickness 0.01, eta 1.5,
//                    albedo 0, g 0, maxdepth 10, nsamples 1
//   "diffusetransmission"  reflectance 0.25, transmittance 0.25 (spectrum textures), scale 1
//                    (float >= 0): Lambertian reflection clamp(scale * reflectance, 0, 1) and
//                    Lambertian transmission clamp(scale * transmittance, 0, 1)
//   "interface"      no surface at all: rays pass through (marks medium boundaries)
// Every material but "interface" takes a float texture "displacement" (bump mapping,
// bumpmap.h). A spectrally varying eta (dielectric, coateddiffuse) disperses light: the
// BSDF keeps one of the path's wavelengths (SampledWavelengths::TerminateSecondary, design §1)
// and refracts with eta at it. Every other material type is reported as an error.
#pragma once

#include <pbrt/bsdf.h>
#include <pbrt/interaction.h>
#include <pbrt/microfacet.h>
#include <pbrt/textures.h>
#include <pbrt/util/function_ref.h>

#include <cstdint>
#include <optional>
#include <string>
#include <variant>

namespace pbrt {

class ParameterDictionary;

struct DiffuseMaterial {
    SpectrumTextureHandle reflectance;
    FloatTextureHandle displacement;  // null: no bump mapping
    SpectrumHandle reflectanceConstant;  // its spectrum when constant (cached per path)
};
// Roughness parameters shared by the microfacet materials.
struct MaterialRoughness {
    FloatTextureHandle u, v;
    bool remap = true;
    // The Trowbridge-Reitz distribution at ctx (alpha = sqrt(roughness) when remapped).
    TrowbridgeReitzDistribution Distribution(const TextureEvalContext &ctx) const;
};
struct ConductorMaterial {
    SpectrumTextureHandle eta, k;     // both set, or both null and reflectance set
    SpectrumHandle etaConstant, kConstant;  // their spectra when constant (cached per path)
    SpectrumTextureHandle reflectance;
    MaterialRoughness roughness;
    FloatTextureHandle displacement;
};
struct DielectricMaterial {
    SpectrumHandle eta;
    MaterialRoughness roughness;
    FloatTextureHandle displacement;
};
struct CoatedDiffuseMaterial {
    SpectrumTextureHandle reflectance, albedo;
    MaterialRoughness roughness;
    FloatTextureHandle thickness, g;
    SpectrumHandle eta;
    int maxDepth = 10, nSamples = 1;
    uint64_t seed = 0;
    FloatTextureHandle displacement;
};
struct DiffuseTransmissionMaterial {
    SpectrumTextureHandle reflectance, transmittance;
    Float scale = 1;
    FloatTextureHandle displacement;
};
struct InterfaceMaterial {};

using Material = std::variant<DiffuseMaterial, InterfaceMaterial, ConductorMaterial,
                              DielectricMaterial, CoatedDiffuseMaterial, DiffuseTransmissionMaterial>;

// The BSDF at a hit; nullopt for "interface". A material with a spectrally varying eta
// terminates the secondary wavelengths of lambda (design §1), choosing the kept one with a
// fresh uniform number from uFresh (called only then). spectra, when given, holds constant
// spectra at lambda for the path (a conductor's eta and k), so that they are evaluated once
// per path; the caller clears it when lambda changes.
std::optional<BSDF> GetBSDF(const Material &m, const SurfaceInteraction &si,
                            SampledWavelengths &lambda, FunctionRef<Float()> uFresh,
                            SampledSpectrumCache *spectra = nullptr);

// Creates a material of the given type ("string type" of MakeNamedMaterial, or the name
// in Material). Throws PbrtError at loc for unsupported types and parameters. seed feeds
// the random walks of "coateddiffuse" (the --seed option; pbrt-v4 hashes its seed too).
Material CreateMaterial(const std::string &type, const ParameterDictionary &params,
                        const TextureResolver &textures, const FileLoc &loc, uint64_t seed = 0);

}  // namespace pbrt
