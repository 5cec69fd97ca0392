#include <pbrt/integrator.h>

#include <pbrt/materials.h>
#include <pbrt/samplers.h>
#include <pbrt/scene.h>
#include <pbrt/util/paramdict.h>

namespace pbrt {

IntegratorSettings IntegratorSettings::Create(const std::string &name,
                                              const ParameterDictionary &params,
                                              const FileLoc &loc) {
    IntegratorSettings s;
    s.name = name;
    s.maxDepth = params.GetOneInt("maxdepth", 5);
    if (s.maxDepth < 0) throw PbrtError(params.Loc("maxdepth"), "\"maxdepth\" must be >= 0");
    if (params.GetOneBool("regularize", false))
        throw PbrtError(params.Loc("regularize"), "\"regularize\" true is not supported");
    // Any light sampler gives the same expectation; ours picks lights by power.
    params.GetOneString("lightsampler", "bvh");
    if (name != "path") {
        Warning(loc, "Integrator \"" + name + "\" is not supported; rendering with \"path\" "
                     "(same image in expectation for scenes without participating media)");
        // Parameters of the substituted integrator have no meaning for "path".
        for (const ParsedParameter &p : params.Parameters()) p.lookedUp = true;
    }
    return s;
}

namespace {

// Direct lighting at a surface point: one light chosen by power, one sample on it, weighted
// by MIS against BSDF sampling.
SampledSpectrum SampleLd(const Scene &scene, const SurfaceInteraction &si, const BSDF &bsdf,
                         const SampledWavelengths &lambda, Sampler &sampler,
                         SampledSpectrumCache &spectra, int *lightOut, const Float *uLightGiven) {
    Float uLight = sampler.Get1D();
    if (uLightGiven) uLight = *uLightGiven;
    Point2f u = sampler.Get2D();
    Float pmf;
    int li = scene.lightSampler.Sample(uLight, &pmf);
    *lightOut = li;
    if (li < 0 || pmf == 0) return SampledSpectrum(0);
    const Light &light = scene.lights[li];
    LightSampleContext ctx{si.p, si.n, si.pError};
    std::optional<LightLiSample> ls = light.SampleLi(ctx, u, lambda, &spectra);
    if (!ls || !ls->L.IsNonZero() || ls->pdf == 0) return SampledSpectrum(0);

    // A shadow ray costs less than the coated layer's f (a random walk): test visibility
    // first there, and f first for the others, whose f is cheap and often 0 (light behind
    // the surface). Either order gives the same value.
    auto unoccluded = [&] { return scene.Unoccluded(si.SpawnRayTo(ls->pLight, ls->nLight, ls->pLightError),
                                                         ls->unblockingSphere); };
    const bool costlyF = bsdf.HasCostlyF();
    if (costlyF && (!bsdf.SameSide(si.wo, ls->wi) || !unoccluded()))  // f = 0 on the other side
        return SampledSpectrum(0);
    SampledSpectrum f = bsdf.f(si.wo, ls->wi) * AbsDot(ls->wi, si.ns);
    if (!f.IsNonZero() || (!costlyF && !unoccluded())) return SampledSpectrum(0);

    Float p_l = pmf * ls->pdf;
    if (light.IsDelta()) return ls->L * f / p_l;
    Float p_b = bsdf.PDF(si.wo, ls->wi);
    return ls->L * f * (PowerHeuristic(1, p_l, 1, p_b) / p_l);
}

}  // namespace

SampledSpectrum PathLi(const Scene &scene, Ray ray, SampledWavelengths &lambda,
                       Sampler &sampler, int maxDepth, int *depthOut, LightContributions *byLight,
                       const Float *uFirstLight) {
    SampledSpectrum L(0), beta(1);
    int depth = 0, skips = 0;
    Float p_b = 1, etaScale = 1;
    bool specularBounce = false;
    LightSampleContext prevCtx;
    // The last BSDF sample's PDF, when the sample left it for later (the coated layer's
    // walk estimates it at some cost): only a hit on an emitter needs it, for MIS.
    std::optional<BSDF> pdfBsdf;
    BSDFSample pdfSample;
    // The MIS weight of an emitter hit whose light-sampling density is p_l. With p_l = 0
    // (a light next-event estimation never picks) it is 1 whatever p_b is, as long as p_b > 0,
    // which holds for a deferred PDF (the layer's PDF has a uniform share), so the estimate
    // is skipped there.
    auto misWeight = [&](Float p_l) {
        if (pdfBsdf) {
            if (p_l == 0) return Float(1);
            p_b = pdfBsdf->DeferredPDF(pdfSample);
            pdfBsdf.reset();
        }
        return PowerHeuristic(1, p_b, 1, p_l);
    };
    SurfaceInteraction si;
    SampledSpectrumCache spectra;  // emitters' and conductors' spectra at lambda (cleared when it changes)

    while (true) {
        if (!scene.accel->Intersect(ray, &si)) {
            // Escaped: radiance of the infinite lights, MIS-weighted against NEE.
            for (int li : scene.infiniteLights) {
                const Light &light = scene.lights[li];
                SampledSpectrum Le = light.Le(lambda, &spectra);
                if (!Le.IsNonZero()) continue;
                SampledSpectrum c = beta * Le;
                if (depth != 0 && !specularBounce)
                    c *= misWeight(scene.lightSampler.PMF(li) * light.PDF_Li(prevCtx, ray.d, si));
                L += c;
                if (byLight) byLight->Add(li, c);
            }
            break;
        }

        // Emission from an area light that was hit.
        if (si.areaLight >= 0) {
            const Light &light = scene.lights[si.areaLight];
            SampledSpectrum Le = light.L(si.n, si.wo, lambda, &spectra);
            if (Le.IsNonZero()) {
                SampledSpectrum c = beta * Le;
                if (depth != 0 && !specularBounce)
                    c *= misWeight(scene.lightSampler.PMF(si.areaLight) *
                                   light.PDF_Li(prevCtx, Normalize(ray.d), si));
                L += c;
                if (byLight) byLight->Add(si.areaLight, c);
            }
        }

        // "interface" surfaces: continue through without counting a bounce.
        // Initialized, not assigned: the BSDF is built in place (no copy of its variant).
        bool wasTerminated = lambda.SecondaryTerminated();
        std::optional<BSDF> bsdf = si.material >= 0
            ? GetBSDF(scene.materials[si.material], si, lambda, [&] { return sampler.Get1D(); }, &spectra)
            : std::nullopt;
        if (si.material >= 0) {
            // Dispersion kept one wavelength: the other slots no longer count (their pdf is
            // 0); zero their throughput so that they cannot steer Russian roulette.
            if (!wasTerminated && lambda.SecondaryTerminated()) {
                for (int i = 0; i < NSpectrumSamples; ++i)
                    if (i != lambda.SurvivingIndex()) beta[i] = 0;
                spectra.Clear();
            }
        }
        if (!bsdf) {
            if (++skips > 256) break;
            ray = si.SpawnRay(ray.d);
            continue;
        }
        if (depth++ == maxDepth) break;
        if (bsdf->IsBlack()) break;

        if (bsdf->IsNonSpecular()) {
            int li = -1;
            SampledSpectrum c = beta * SampleLd(scene, si, *bsdf, lambda, sampler, spectra, &li, uFirstLight);
            uFirstLight = nullptr;
            L += c;
            if (byLight && li >= 0) byLight->Add(li, c);
        }

        // Continue the path in a BSDF-sampled direction.
        Float uc = sampler.Get1D();
        std::optional<BSDFSample> bs = bsdf->Sample_f(si.wo, uc, sampler.Get2D(), /*exactPdf=*/false);
        if (!bs) break;
        beta *= bs->f * (AbsDot(bs->wi, si.ns) / bs->pdf);
        p_b = bs->pdf;
        pdfBsdf.reset();
        if (bs->pdfIsProportional) {
            pdfBsdf = std::move(bsdf);
            pdfSample = *bs;
        }
        specularBounce = bs->specular;
        if (bs->transmission) etaScale *= Sqr(bs->eta);
        prevCtx = LightSampleContext{si.p, si.n, si.pError};
        ray = si.SpawnRay(bs->wi);

        // Russian roulette once the path throughput is small.
        SampledSpectrum rrBeta = beta * etaScale;
        Float maxBeta = rrBeta.MaxComponentValue();
        if (maxBeta < 1 && depth > 1) {
            Float q = std::max<Float>(0, 1 - maxBeta);
            if (sampler.Get1D() < q) break;
            beta /= 1 - q;
        }
    }
    if (depthOut) *depthOut = depth;
    return L;
}

}  // namespace pbrt
