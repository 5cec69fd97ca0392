#include <pbrt/materials.h>

#include <pbrt/paramdict.h>

namespace pbrt {

std::optional<BSDF> GetBSDF(const Material &m, const SurfaceInteraction &si,
                            const SampledWavelengths &lambda) {
    if (const auto *d = std::get_if<DiffuseMaterial>(&m)) {
        TextureEvalContext ctx{si.p, si.uv};
        SampledSpectrum R = Clamp(d->reflectance->Evaluate(ctx, lambda), Float(0), Float(1));
        return BSDF(si.ns, si.dpdu, DiffuseBxDF(R));
    }
    return std::nullopt;
}

Material CreateMaterial(const std::string &type, const ParameterDictionary &params,
                        const TextureResolver &textures, const FileLoc &loc) {
    // Features of pbrt-v4 materials that change the picture and are not implemented yet.
    for (const char *p : {"displacement", "normalmap"})
        if (params.Find(p))
            throw PbrtError(params.Loc(p), std::string("material parameter \"") + p +
                                               "\" is not supported yet");
    if (type == "diffuse") {
        SpectrumTextureHandle r = textures.spectrum(
            "reflectance", std::make_shared<ConstantSpectrum>(0.5f), SpectrumType::Albedo);
        return DiffuseMaterial{r};
    }
    if (type == "interface") return InterfaceMaterial{};
    if (type.empty()) throw PbrtError(loc, "material without a \"string type\"");
    throw PbrtError(loc, "material type \"" + type +
                             "\" is not supported yet (supported: diffuse, interface)");
}

}  // namespace pbrt
