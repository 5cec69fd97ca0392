// Materials: what a surface does with light, as textures that produce a BSDF at a hit.
//   "diffuse"    reflectance (spectrum texture, default 0.5)
//   "interface"  no surface at all: rays pass through (marks medium boundaries)
// Every other material type is reported as an error naming it (a later issue adds them).
#pragma once

#include <pbrt/bsdf.h>
#include <pbrt/interaction.h>
#include <pbrt/textures.h>

#include <functional>
#include <optional>
#include <string>
#include <variant>

namespace pbrt {

class ParameterDictionary;

struct DiffuseMaterial {
    SpectrumTextureHandle reflectance;
};
struct InterfaceMaterial {};

using Material = std::variant<DiffuseMaterial, InterfaceMaterial>;

// The BSDF at a hit; nullopt for "interface".
std::optional<BSDF> GetBSDF(const Material &m, const SurfaceInteraction &si,
                            const SampledWavelengths &lambda);

// How a material's parameters become textures (implemented by the scene builder, which
// knows the named textures and the current colour space). Both return nullptr when the
// parameter is absent and there is no default.
struct TextureResolver {
    std::function<SpectrumTextureHandle(const std::string &name, SpectrumHandle def, SpectrumType)>
        spectrum;
    std::function<FloatTextureHandle(const std::string &name, std::optional<Float> def)> floats;
};

// Creates a material of the given type ("string type" of MakeNamedMaterial, or the name
// in Material). Throws PbrtError at loc for unsupported types and parameters.
Material CreateMaterial(const std::string &type, const ParameterDictionary &params,
                        const TextureResolver &textures, const FileLoc &loc);

}  // namespace pbrt
