#include <pbrt/materials.h>

#include <pbrt/bumpmap.h>
#include <pbrt/util/paramdict.h>

#include <cmath>
#include <cstdio>

namespace pbrt {

TrowbridgeReitzDistribution MaterialRoughness::Distribution(const TextureEvalContext &ctx) const {
    Float ur = u->Evaluate(ctx), vr = v->Evaluate(ctx);
    if (remap) {
        ur = TrowbridgeReitzDistribution::RoughnessToAlpha(ur);
        vr = TrowbridgeReitzDistribution::RoughnessToAlpha(vr);
    }
    return TrowbridgeReitzDistribution(ur, vr);
}

namespace {

// The relative IOR of a dielectric (coat) at the path's wavelengths: a constant spectrum
// gives one value for all; any other spectrum terminates the secondary wavelengths first
// (design §1) so that the kept wavelength (now in every slot) decides the refraction. eta 0
// means 1 (pbrt-v4's convention for "no interface").
Float SampleEta(const Spectrum &eta, SampledWavelengths &lambda, FunctionRef<Float()> uFresh) {
    if (!dynamic_cast<const ConstantSpectrum *>(&eta)) lambda.TerminateSecondary(uFresh());
    Float e = eta(lambda[0]);
    return e == 0 ? 1 : e;
}

// The BxDF of each material at a hit.
struct MakeBxDF {
    const TextureEvalContext &ctx;
    SampledWavelengths &lambda;
    FunctionRef<Float()> uFresh;
    SampledSpectrumCache *spectra;

    BxDF operator()(const DiffuseMaterial &d) const {
        // A constant reflectance is evaluated once per path (a path meets the same walls
        // again and again), a texture at every hit.
        return DiffuseBxDF(Clamp(spectra && d.reflectanceConstant ? spectra->Get(*d.reflectanceConstant, lambda)
                                                                  : d.reflectance->Evaluate(ctx, lambda),
                                 Float(0), Float(1)));
    }
    BxDF operator()(const ConductorMaterial &c) const {
        SampledSpectrum eta, k;
        if (spectra && c.etaConstant && c.kConstant) {
            eta = spectra->Get(*c.etaConstant, lambda);
            k = spectra->Get(*c.kConstant, lambda);
        } else if (c.eta) {
            eta = c.eta->Evaluate(ctx, lambda);
            k = c.k->Evaluate(ctx, lambda);
        } else {
            // A reflectance r at normal incidence: eta = 1, k = 2 sqrt(r) / sqrt(1 - r)
            // (pbrt-v4's ConductorMaterial; solves the conductor Fresnel term for r).
            SampledSpectrum r = Clamp(c.reflectance->Evaluate(ctx, lambda), Float(0), Float(0.9999));
            eta = SampledSpectrum(1);
            for (int i = 0; i < NSpectrumSamples; ++i) k[i] = 2 * std::sqrt(r[i]) / std::sqrt(1 - r[i]);
        }
        return ConductorBxDF(c.roughness.Distribution(ctx), eta, k);
    }
    BxDF operator()(const DielectricMaterial &d) const {
        Float eta = SampleEta(*d.eta, lambda, uFresh);
        return DielectricBxDF(eta, d.roughness.Distribution(ctx));
    }
    BxDF operator()(const CoatedDiffuseMaterial &m) const {
        SampledSpectrum r = Clamp(m.reflectance->Evaluate(ctx, lambda), Float(0), Float(1));
        TrowbridgeReitzDistribution distrib = m.roughness.Distribution(ctx);
        Float thickness = m.thickness->Evaluate(ctx);
        Float eta = SampleEta(*m.eta, lambda, uFresh);
        SampledSpectrum albedo = Clamp(m.albedo->Evaluate(ctx, lambda), Float(0), Float(1));
        Float g = Clamp(m.g->Evaluate(ctx), Float(-1), Float(1));
        return CoatedDiffuseBxDF(DielectricBxDF(eta, distrib), DiffuseBxDF(r), thickness, albedo, g,
                                 m.maxDepth, m.nSamples, m.seed);
    }
    BxDF operator()(const DiffuseTransmissionMaterial &m) const {
        SampledSpectrum r = Clamp(m.scale * m.reflectance->Evaluate(ctx, lambda), Float(0), Float(1));
        SampledSpectrum t = Clamp(m.scale * m.transmittance->Evaluate(ctx, lambda), Float(0), Float(1));
        return DiffuseTransmissionBxDF(r, t);
    }
    BxDF operator()(const InterfaceMaterial &) const { return DiffuseBxDF(SampledSpectrum(0)); }
};

// The displacement texture of a material (null for none and for "interface").
const FloatTexture *Displacement(const Material &m) {
    return std::visit(
        [](const auto &mat) -> const FloatTexture * {
            if constexpr (std::is_same_v<std::decay_t<decltype(mat)>, InterfaceMaterial>) return nullptr;
            else return mat.displacement.get();
        },
        m);
}

}  // namespace

std::optional<BSDF> GetBSDF(const Material &m, const SurfaceInteraction &si,
                            SampledWavelengths &lambda, FunctionRef<Float()> uFresh,
                            SampledSpectrumCache *spectra) {
    if (std::holds_alternative<InterfaceMaterial>(m)) return std::nullopt;
    // Bump mapping first: it changes the shading frame the BSDF lives in.
    Normal3f ns = si.ns;
    Vector3f dpdu = si.dpdu;
    if (const FloatTexture *disp = Displacement(m)) {
        BumpedFrame b = BumpMap(*disp, si);
        ns = b.ns;
        dpdu = b.dpdu;
    }
    TextureEvalContext ctx{si.p, si.uv};
    return BSDF(ns, dpdu, std::visit(MakeBxDF{ctx, lambda, uFresh, spectra}, m));
}

namespace {

// roughness / uroughness / vroughness / remaproughness (pbrt-v4's names and defaults).
MaterialRoughness GetRoughness(const ParameterDictionary &params, const TextureResolver &textures) {
    MaterialRoughness r;
    FloatTextureHandle both = textures.floats("roughness", Float(0));
    r.u = textures.floats("uroughness", std::nullopt);
    r.v = textures.floats("vroughness", std::nullopt);
    if (!r.u) r.u = both;
    if (!r.v) r.v = both;
    r.remap = params.GetOneBool("remaproughness", true);
    return r;
}

// A spectrum-valued "eta" that must not vary over the surface (float or spectrum).
SpectrumHandle GetEta(const ParameterDictionary &params, const TextureResolver &textures) {
    if (!params.GetTexture("eta").empty())
        throw PbrtError(params.Loc("eta"), "\"eta\" must be a float or a spectrum, not a texture");
    SpectrumTextureHandle t =
        textures.spectrum("eta", std::make_shared<ConstantSpectrum>(1.5f), SpectrumType::Unbounded);
    SpectrumHandle s = t ? t->Constant() : nullptr;
    if (!s) throw PbrtError(params.Loc("eta"), "\"eta\" must be a float or a spectrum");
    return s;
}

// The default eta / k of "conductor" (pbrt-v4: copper) as a named spectrum, or an error
// naming the missing data (this renderer ships no measured metal spectra).
SpectrumTextureHandle NamedMetal(const char *name, const FileLoc &loc) {
    SpectrumHandle s = GetNamedSpectrum(name);
    if (!s)
        throw PbrtError(loc, std::string("conductor without \"eta\" and \"k\": their default, the named "
                                         "spectrum \"") + name + "\", is not available in this renderer; "
                                         "give \"eta\" and \"k\" (rgb or spectrum) or \"reflectance\"");
    return MakeConstantSpectrumTexture(s);
}

// "diffusetransmission": reflectance and transmittance 0.25 and scale 1 by default (pbrt-v4's
// defaults). scale must be finite and >= 0. Constant spectra whose scaled sum exceeds 1 at
// some wavelength reflect and transmit more than they receive (pbrt-v4 renders them so):
// a warning, not an error.
DiffuseTransmissionMaterial CreateDiffuseTransmission(const ParameterDictionary &params,
                                                      const TextureResolver &textures) {
    DiffuseTransmissionMaterial m;
    m.reflectance = textures.spectrum("reflectance", std::make_shared<ConstantSpectrum>(0.25f),
                                      SpectrumType::Albedo);
    m.transmittance = textures.spectrum("transmittance", std::make_shared<ConstantSpectrum>(0.25f),
                                        SpectrumType::Albedo);
    m.scale = params.GetOneFloat("scale", 1);
    if (!std::isfinite(m.scale) || m.scale < 0)
        throw PbrtError(params.Loc("scale"), "diffusetransmission: \"scale\" must be finite and >= 0");
    m.displacement = textures.floats("displacement", std::nullopt);
    SpectrumHandle r = m.reflectance->Constant(), t = m.transmittance->Constant();
    if (r && t) {
        for (int nm = int(Lambda_min); nm <= int(Lambda_max); ++nm) {
            Float sum = std::min<Float>(1, m.scale * (*r)(Float(nm))) + std::min<Float>(1, m.scale * (*t)(Float(nm)));
            if (sum > 1.001f) {
                FileLoc where = params.Find("transmittance") ? params.Loc("transmittance")
                              : params.Find("reflectance") ? params.Loc("reflectance") : params.Loc("scale");
                char value[32];
                std::snprintf(value, sizeof(value), "%.3g", double(sum));
                Warning(where, std::string("diffusetransmission: scale * (reflectance + transmittance) is ") +
                                   value + " at " + std::to_string(nm) +
                                   " nm: the surface gives out more light than it receives");
                break;
            }
        }
    }
    return m;
}

}  // namespace

Material CreateMaterial(const std::string &type, const ParameterDictionary &params,
                        const TextureResolver &textures, const FileLoc &loc, uint64_t seed) {
    if (params.Find("normalmap"))
        throw PbrtError(params.Loc("normalmap"), "material parameter \"normalmap\" is not supported");
    if (type == "interface") return InterfaceMaterial{};
    if (type.empty()) throw PbrtError(loc, "material without a \"string type\"");
    FloatTextureHandle displacement = textures.floats("displacement", std::nullopt);

    if (type == "diffuse") {
        SpectrumTextureHandle r = textures.spectrum(
            "reflectance", std::make_shared<ConstantSpectrum>(0.5f), SpectrumType::Albedo);
        return DiffuseMaterial{r, displacement, r ? r->Constant() : nullptr};
    }
    if (type == "conductor") {
        ConductorMaterial c;
        c.eta = textures.spectrum("eta", nullptr, SpectrumType::Unbounded);
        c.k = textures.spectrum("k", nullptr, SpectrumType::Unbounded);
        c.reflectance = textures.spectrum("reflectance", nullptr, SpectrumType::Albedo);
        if (c.reflectance && (c.eta || c.k))
            throw PbrtError(params.Loc("reflectance"),
                            "conductor: give either \"reflectance\" or \"eta\" and \"k\", not both");
        if (!c.reflectance) {
            if (!c.eta) c.eta = NamedMetal("metal-Cu-eta", loc);
            if (!c.k) c.k = NamedMetal("metal-Cu-k", loc);
        }
        if (c.eta) c.etaConstant = c.eta->Constant();
        if (c.k) c.kConstant = c.k->Constant();
        c.roughness = GetRoughness(params, textures);
        c.displacement = displacement;
        return c;
    }
    if (type == "dielectric") {
        DielectricMaterial d;
        d.eta = GetEta(params, textures);
        d.roughness = GetRoughness(params, textures);
        d.displacement = displacement;
        return d;
    }
    if (type == "coateddiffuse") {
        CoatedDiffuseMaterial m;
        m.reflectance = textures.spectrum("reflectance", std::make_shared<ConstantSpectrum>(0.5f),
                                          SpectrumType::Albedo);
        m.albedo = textures.spectrum("albedo", std::make_shared<ConstantSpectrum>(0.f), SpectrumType::Albedo);
        m.roughness = GetRoughness(params, textures);
        m.thickness = textures.floats("thickness", Float(0.01));
        m.g = textures.floats("g", Float(0));
        m.eta = GetEta(params, textures);
        m.maxDepth = params.GetOneInt("maxdepth", 10);
        m.nSamples = params.GetOneInt("nsamples", 1);
        if (m.maxDepth < 1 || m.nSamples < 1)
            throw PbrtError(params.Loc(m.maxDepth < 1 ? "maxdepth" : "nsamples"),
                            "coateddiffuse: \"maxdepth\" and \"nsamples\" must be >= 1");
        m.seed = seed;
        m.displacement = displacement;
        return m;
    }
    if (type == "diffusetransmission") return CreateDiffuseTransmission(params, textures);
    throw PbrtError(loc, "material type \"" + type +
                             "\" is not supported (supported: diffuse, conductor, dielectric, "
                             "coateddiffuse, diffusetransmission, interface)");
}

}  // namespace pbrt
