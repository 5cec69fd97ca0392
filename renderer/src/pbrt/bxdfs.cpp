#include <pbrt/bxdfs.h>

#include <pbrt/util/rng.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace pbrt {

namespace {

BSDFSample MakeSample(const SampledSpectrum &f, const Vector3f &wi, Float pdf, bool specular,
                      bool transmission, Float eta = 1) {
    BSDFSample s;
    s.f = f;
    s.wi = wi;
    s.pdf = pdf;
    s.specular = specular;
    s.transmission = transmission;
    s.eta = eta;
    return s;
}

bool Valid(const std::optional<BSDFSample> &s) {
    return s && s->f.IsNonZero() && s->pdf > 0 && s->wi.z != 0;
}

// Bits of a float (so that hashing distinguishes every value).
uint64_t FloatBits(Float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    return bits;
}
uint64_t HashVector(const Vector3f &v) {
    return HashInts({FloatBits(v.x), FloatBits(v.y), FloatBits(v.z)});
}

// Distance with density a exp(-a x) on [0, inf).
Float SampleExponential(Float u, Float a) { return -std::log(1 - u) / a; }

// Different stream tags keep the walks of f(), Sample_f() and PDF() for the same
// directions uncorrelated.
constexpr uint64_t kTagF = 0x66, kTagSample = 0x73, kTagPDF = 0x70;

}  // namespace

// =======================================================================================
// DiffuseTransmissionBxDF

SampledSpectrum DiffuseTransmissionBxDF::f(const Vector3f &wo, const Vector3f &wi, TransportMode) const {
    return (SameHemisphere(wo, wi) ? R : T) * InvPi;
}

bool DiffuseTransmissionBxDF::LobeProbabilities(BxDFReflTransFlags flags, Float *pr, Float *pt) const {
    Float r = Allows(flags, BxDFReflTransFlags::Reflection) ? R.MaxComponentValue() : 0;
    Float t = Allows(flags, BxDFReflTransFlags::Transmission) ? T.MaxComponentValue() : 0;
    if (!(r + t > 0)) return false;
    *pr = r / (r + t);
    *pt = t / (r + t);
    return true;
}

std::optional<BSDFSample> DiffuseTransmissionBxDF::Sample_f(const Vector3f &wo, Float uc, Point2f u,
                                                            TransportMode, BxDFReflTransFlags flags) const {
    Float pr, pt;
    if (!LobeProbabilities(flags, &pr, &pt)) return std::nullopt;
    // A cosine-distributed direction above the surface, then flipped to wo's side
    // (reflection) or to the other side (transmission).
    bool transmit = !(uc < pr);
    Vector3f wi = SampleCosineHemisphere(u);
    if ((wo.z < 0) != transmit) wi.z = -wi.z;
    Float pdf = CosineHemispherePDF(AbsCosTheta(wi)) * (transmit ? pt : pr);
    if (pdf == 0) return std::nullopt;
    return MakeSample((transmit ? T : R) * InvPi, wi, pdf, false, transmit);
}

Float DiffuseTransmissionBxDF::PDF(const Vector3f &wo, const Vector3f &wi, TransportMode,
                                   BxDFReflTransFlags flags) const {
    Float pr, pt;
    if (!LobeProbabilities(flags, &pr, &pt)) return 0;
    return CosineHemispherePDF(AbsCosTheta(wi)) * (SameHemisphere(wo, wi) ? pr : pt);
}

// =======================================================================================
// ConductorBxDF

SampledSpectrum ConductorBxDF::f(const Vector3f &wo, const Vector3f &wi, TransportMode) const {
    if (!SameHemisphere(wo, wi) || distrib.EffectivelySmooth()) return SampledSpectrum(0);
    // Torrance-Sparrow: D G F / (4 cos_o cos_i) at the half vector.
    Float cosTheta_o = AbsCosTheta(wo), cosTheta_i = AbsCosTheta(wi);
    if (cosTheta_i == 0 || cosTheta_o == 0) return SampledSpectrum(0);
    Vector3f wm = wi + wo;
    if (LengthSquared(wm) == 0) return SampledSpectrum(0);
    wm = Normalize(wm);
    SampledSpectrum F = FrComplex(AbsDot(wo, wm), eta, k);
    return distrib.D(wm) * F * distrib.G(wo, wi) / (4 * cosTheta_i * cosTheta_o);
}

std::optional<BSDFSample> ConductorBxDF::Sample_f(const Vector3f &wo, Float uc, Point2f u,
                                                  TransportMode, BxDFReflTransFlags flags) const {
    if (!Allows(flags, BxDFReflTransFlags::Reflection)) return std::nullopt;
    if (distrib.EffectivelySmooth()) {
        // Perfect mirror: f = F / |cos| so that f cos / pdf = F.
        Vector3f wi(-wo.x, -wo.y, wo.z);
        SampledSpectrum f = FrComplex(AbsCosTheta(wi), eta, k) / AbsCosTheta(wi);
        return MakeSample(f, wi, 1, true, false);
    }
    // Visible normal, then mirror about it; the density changes by 1 / (4 |wo . wm|).
    if (wo.z == 0) return std::nullopt;
    Vector3f wm = distrib.Sample_wm(wo, u);
    Vector3f wi = Reflect(wo, wm);
    if (!SameHemisphere(wo, wi)) return std::nullopt;
    Float pdf = distrib.PDF(wo, wm) / (4 * AbsDot(wo, wm));
    Float cosTheta_o = AbsCosTheta(wo), cosTheta_i = AbsCosTheta(wi);
    if (cosTheta_i == 0 || cosTheta_o == 0) return std::nullopt;
    SampledSpectrum F = FrComplex(AbsDot(wo, wm), eta, k);
    SampledSpectrum f = distrib.D(wm) * F * distrib.G(wo, wi) / (4 * cosTheta_i * cosTheta_o);
    return MakeSample(f, wi, pdf, false, false);
}

Float ConductorBxDF::PDF(const Vector3f &wo, const Vector3f &wi, TransportMode,
                         BxDFReflTransFlags flags) const {
    if (!Allows(flags, BxDFReflTransFlags::Reflection)) return 0;
    if (!SameHemisphere(wo, wi) || distrib.EffectivelySmooth()) return 0;
    Vector3f wm = wo + wi;
    if (LengthSquared(wm) == 0) return 0;
    wm = FaceForward(Normalize(wm), Vector3f(0, 0, 1));
    return distrib.PDF(wo, wm) / (4 * AbsDot(wo, wm));
}

// =======================================================================================
// DielectricBxDF

namespace {
// The microfacet normal that takes wo to wi (reflection or refraction; Walter et al.
// 2007, generalized half vector wm ~ wo + etap wi), oriented up; etap is the relative IOR
// for the transmission case. Returns false for degenerate or back-facing configurations.
bool DielectricHalfVector(const Vector3f &wo, const Vector3f &wi, Float eta, Vector3f *wm,
                          Float *etap) {
    Float cosTheta_o = CosTheta(wo), cosTheta_i = CosTheta(wi);
    if (cosTheta_i == 0 || cosTheta_o == 0) return false;
    bool reflect = cosTheta_i * cosTheta_o > 0;
    *etap = reflect ? 1 : (cosTheta_o > 0 ? eta : 1 / eta);
    Vector3f m = wi * *etap + wo;
    if (LengthSquared(m) == 0) return false;
    m = FaceForward(Normalize(m), Vector3f(0, 0, 1));
    // Microfacets seen from behind by either direction do not contribute.
    if (Dot(m, wi) * cosTheta_i < 0 || Dot(m, wo) * cosTheta_o < 0) return false;
    *wm = m;
    return true;
}
}  // namespace

SampledSpectrum DielectricBxDF::f(const Vector3f &wo, const Vector3f &wi, TransportMode mode) const {
    if (eta == 1 || distrib.EffectivelySmooth()) return SampledSpectrum(0);
    Vector3f wm;
    Float etap;
    if (!DielectricHalfVector(wo, wi, eta, &wm, &etap)) return SampledSpectrum(0);
    Float F = FrDielectric(Dot(wo, wm), eta);
    if (SameHemisphere(wo, wi))
        return SampledSpectrum(distrib.D(wm) * distrib.G(wo, wi) * F /
                               std::abs(4 * CosTheta(wi) * CosTheta(wo)));
    // Transmission (Walter et al. 2007, eq. 21, written with the relative IOR etap).
    Float denom = Sqr(Dot(wi, wm) + Dot(wo, wm) / etap) * CosTheta(wi) * CosTheta(wo);
    Float ft = distrib.D(wm) * (1 - F) * distrib.G(wo, wi) *
               std::abs(Dot(wi, wm) * Dot(wo, wm) / denom);
    // Radiance is compressed into the denser medium's smaller solid angle.
    if (mode == TransportMode::Radiance) ft /= Sqr(etap);
    return SampledSpectrum(ft);
}

std::optional<BSDFSample> DielectricBxDF::Sample_f(const Vector3f &wo, Float uc, Point2f u,
                                                   TransportMode mode,
                                                   BxDFReflTransFlags flags) const {
    if (eta == 1 || distrib.EffectivelySmooth()) {
        // Specular: reflect or refract with the Fresnel probabilities (restricted by flags).
        Float R = FrDielectric(CosTheta(wo), eta), T = 1 - R;
        Float pr = Allows(flags, BxDFReflTransFlags::Reflection) ? R : 0;
        Float pt = Allows(flags, BxDFReflTransFlags::Transmission) ? T : 0;
        if (pr == 0 && pt == 0) return std::nullopt;
        if (uc < pr / (pr + pt)) {
            Vector3f wi(-wo.x, -wo.y, wo.z);
            return MakeSample(SampledSpectrum(R / AbsCosTheta(wi)), wi, pr / (pr + pt), true, false);
        }
        Vector3f wi;
        Float etap;
        if (!Refract(wo, Vector3f(0, 0, 1), eta, &etap, &wi)) return std::nullopt;
        SampledSpectrum ft(T / AbsCosTheta(wi));
        if (mode == TransportMode::Radiance) ft /= Sqr(etap);
        return MakeSample(ft, wi, pt / (pr + pt), true, true, etap);
    }

    // Rough: a visible microfacet normal, then reflection or refraction about it.
    if (wo.z == 0) return std::nullopt;
    Vector3f wm = distrib.Sample_wm(wo, u);
    Float R = FrDielectric(Dot(wo, wm), eta), T = 1 - R;
    Float pr = Allows(flags, BxDFReflTransFlags::Reflection) ? R : 0;
    Float pt = Allows(flags, BxDFReflTransFlags::Transmission) ? T : 0;
    if (pr == 0 && pt == 0) return std::nullopt;
    if (uc < pr / (pr + pt)) {
        Vector3f wi = Reflect(wo, wm);
        if (!SameHemisphere(wo, wi)) return std::nullopt;
        Float pdf = distrib.PDF(wo, wm) / (4 * AbsDot(wo, wm)) * pr / (pr + pt);
        SampledSpectrum f(distrib.D(wm) * distrib.G(wo, wi) * R /
                          std::abs(4 * CosTheta(wi) * CosTheta(wo)));
        return MakeSample(f, wi, pdf, false, false);
    }
    Vector3f wi;
    Float etap;
    if (!Refract(wo, wm, eta, &etap, &wi)) return std::nullopt;
    if (SameHemisphere(wo, wi) || wi.z == 0) return std::nullopt;
    // Density: visible normal density times the Jacobian dwm/dwi of refraction.
    Float denom = Sqr(Dot(wi, wm) + Dot(wo, wm) / etap);
    Float dwm_dwi = AbsDot(wi, wm) / denom;
    Float pdf = distrib.PDF(wo, wm) * dwm_dwi * pt / (pr + pt);
    Float ft = T * distrib.D(wm) * distrib.G(wo, wi) *
               std::abs(Dot(wi, wm) * Dot(wo, wm) / (CosTheta(wi) * CosTheta(wo) * denom));
    if (mode == TransportMode::Radiance) ft /= Sqr(etap);
    return MakeSample(SampledSpectrum(ft), wi, pdf, false, true, etap);
}

std::optional<DielectricBxDF::RatioSample> DielectricBxDF::SampleRatio(const Vector3f &wo, Float uc,
                                                                       Point2f u, TransportMode mode) const {
    // Sample_f's steps with all lobes allowed (so pr + pt = R + T = 1), keeping only f / pdf.
    if (eta == 1 || distrib.EffectivelySmooth()) {
        Float R = FrDielectric(CosTheta(wo), eta), T = 1 - R;
        if (uc < R) {
            Vector3f wi(-wo.x, -wo.y, wo.z);
            if (!(R > 0) || wi.z == 0) return std::nullopt;
            return RatioSample{wi, R / (R * AbsCosTheta(wi)), true, false};
        }
        Vector3f wi;
        Float etap;
        if (!(T > 0) || !Refract(wo, Vector3f(0, 0, 1), eta, &etap, &wi) || wi.z == 0) return std::nullopt;
        Float ratio = T / (T * AbsCosTheta(wi));
        if (mode == TransportMode::Radiance) ratio /= Sqr(etap);
        return RatioSample{wi, ratio, true, true};
    }
    if (wo.z == 0) return std::nullopt;
    Vector3f wm = distrib.Sample_wm(wo, u);
    Float cosFacing = wo.z > 0 ? Dot(wo, wm) : -Dot(wo, wm);
    // Sample_f's pdf is 0 where the visible-normal density is (wm facing away from wo).
    if (!(cosFacing > 0) || !(distrib.D(wm) > 0)) return std::nullopt;
    Float R = FrDielectric(Dot(wo, wm), eta), T = 1 - R;
    // G(wo, wi) / (G1(wo) |cos wi|): what is left of f / pdf once D and F / P cancel (F = P
    // with all lobes allowed).
    Float lambdaO = distrib.Lambda(wo);
    auto maskingRatio = [&](const Vector3f &wi) {
        return (1 + lambdaO) / (1 + lambdaO + distrib.Lambda(wi)) / AbsCosTheta(wi);
    };
    if (uc < R) {
        Vector3f wi = Reflect(wo, wm);
        if (!SameHemisphere(wo, wi) || !(R > 0)) return std::nullopt;
        // f = D G R / (4 |cos wi cos wo|), pdf = G1(wo) D / (4 |cos wo|) R.
        Float ratio = maskingRatio(wi);
        if (!(ratio > 0)) return std::nullopt;
        return RatioSample{wi, ratio, false, false};
    }
    Vector3f wi;
    Float etap;
    if (!(T > 0) || !Refract(wo, wm, eta, &etap, &wi)) return std::nullopt;
    if (SameHemisphere(wo, wi) || wi.z == 0 || Dot(wi, wm) == 0) return std::nullopt;
    // f = T D G |wi.wm wo.wm| / (|cos wi cos wo| denom), pdf = G1(wo) D |wo.wm| |wi.wm| / (|cos wo| denom) T.
    Float ratio = maskingRatio(wi);
    if (mode == TransportMode::Radiance) ratio /= Sqr(etap);
    if (!(ratio > 0)) return std::nullopt;
    return RatioSample{wi, ratio, false, true};
}

Float DielectricBxDF::PDF(const Vector3f &wo, const Vector3f &wi, TransportMode,
                          BxDFReflTransFlags flags) const {
    if (eta == 1 || distrib.EffectivelySmooth()) return 0;
    Vector3f wm;
    Float etap;
    if (!DielectricHalfVector(wo, wi, eta, &wm, &etap)) return 0;
    Float R = FrDielectric(Dot(wo, wm), eta), T = 1 - R;
    Float pr = Allows(flags, BxDFReflTransFlags::Reflection) ? R : 0;
    Float pt = Allows(flags, BxDFReflTransFlags::Transmission) ? T : 0;
    if (pr == 0 && pt == 0) return 0;
    if (SameHemisphere(wo, wi)) return distrib.PDF(wo, wm) / (4 * AbsDot(wo, wm)) * pr / (pr + pt);
    Float denom = Sqr(Dot(wi, wm) + Dot(wo, wm) / etap);
    Float dwm_dwi = AbsDot(wi, wm) / denom;
    return distrib.PDF(wo, wm) * dwm_dwi * pt / (pr + pt);
}

// =======================================================================================
// CoatedDiffuseBxDF

CoatedDiffuseBxDF::CoatedDiffuseBxDF(const DielectricBxDF &top, const DiffuseBxDF &bottom,
                                     Float thickness, const SampledSpectrum &albedo, Float g,
                                     int maxDepth, int nSamples, uint64_t seed)
    : top(top),
      bottom(bottom),
      // A zero thickness would make the two boundaries indistinguishable.
      thickness(std::max(thickness, std::numeric_limits<Float>::min())),
      g(g),
      albedo(albedo),
      maxDepth(maxDepth),
      nSamples(std::max(1, nSamples)),
      seed(seed) {}

Float CoatedDiffuseBxDF::Tr(Float dz, const Vector3f &w) {
    if (std::abs(dz) <= std::numeric_limits<Float>::min()) return 1;
    return std::exp(-std::abs(dz / w.z));
}

SampledSpectrum CoatedDiffuseBxDF::f(Vector3f wo, Vector3f wi, TransportMode mode) const {
    // Two-sided: work with wo above the surface. The base is opaque, so only directions on
    // wo's side get anything.
    if (wo.z < 0) {
        wo = -wo;
        wi = -wi;
    }
    if (!SameHemisphere(wo, wi)) return SampledSpectrum(0);

    // Light enters and leaves through the coat (the "exit interface", at z = thickness).
    // Reflection at the coat itself is evaluated exactly.
    SampledSpectrum f = Float(nSamples) * top.f(wo, wi, mode);

    RNG rng(HashInts({kTagF, seed, HashVector(wo)}), HashVector(wi));
    // (Numbers are drawn in statement order: function arguments have no evaluation order,
    // the elements of a braced list do.)
    auto r = [&rng]() { return rng.UniformFloat(); };
    HGPhaseFunction phase(g);
    const bool topSpecular = top.IsSpecular();
    const BxDFReflTransFlags kR = BxDFReflTransFlags::Reflection,
                             kT = BxDFReflTransFlags::Transmission;

    for (int s = 0; s < nSamples; ++s) {
        // The walk starts with a refraction of wo into the layer; wis is the refraction of
        // wi, sampled in the adjoint mode, to which every vertex of the walk connects.
        Float uc = r();
        std::optional<BSDFSample> wos = top.Sample_f(wo, uc, {r(), r()}, mode, kT);
        if (!Valid(wos)) continue;
        uc = r();
        std::optional<BSDFSample> wis = top.Sample_f(wi, uc, {r(), r()}, !mode, kT);
        if (!Valid(wis)) continue;

        SampledSpectrum beta = wos->f * AbsCosTheta(wos->wi) / wos->pdf;
        Float z = thickness;
        Vector3f w = wos->wi;

        for (int depth = 0; depth < maxDepth; ++depth) {
            // Russian roulette once the throughput is small.
            if (depth > 3 && beta.MaxComponentValue() < 0.25f) {
                Float q = std::max<Float>(0, 1 - beta.MaxComponentValue());
                if (r() < q) break;
                beta /= 1 - q;
            }

            if (!albedo.IsNonZero()) {
                // No scattering: go straight to the other boundary, attenuated.
                z = (z == thickness) ? 0 : thickness;
                beta *= Tr(thickness, w);
            } else {
                // Free flight in the medium (extinction 1): scatter inside or reach a boundary.
                Float dz = SampleExponential(r(), 1 / AbsCosTheta(w));
                Float zp = w.z > 0 ? (z + dz) : (z - dz);
                if (zp == z) continue;
                if (0 < zp && zp < thickness) {
                    // Connect the scattering vertex to wi through the coat, MIS-weighted
                    // against phase sampling hitting the coat's transmission lobe.
                    Float wt = 1;
                    if (!topSpecular)
                        wt = PowerHeuristic(1, wis->pdf, 1, phase.PDF(-w, -wis->wi));
                    f += beta * albedo * phase.p(-w, -wis->wi) * wt * Tr(zp - thickness, wis->wi) *
                         wis->f / wis->pdf;
                    // Continue in a phase-sampled direction.
                    std::optional<PhaseFunctionSample> ps = phase.Sample_p(-w, {r(), r()});
                    if (!ps || ps->pdf == 0 || ps->wi.z == 0) break;
                    beta *= albedo * ps->p / ps->pdf;
                    w = ps->wi;
                    z = zp;
                    // The same path found the other way: phase sampling towards the coat,
                    // then transmission to wi. The MIS weight compares with the density of
                    // the connection strategy for this direction, top.PDF(wi, -w) in the
                    // adjoint mode (pbrt-v4 uses top.PDF(-w, wi) here, which differs by
                    // the refraction Jacobian for a rough coat; weights must sum to 1).
                    if (w.z > 0 && !topSpecular) {
                        SampledSpectrum fExit = top.f(-w, wi, mode);
                        if (fExit.IsNonZero()) {
                            Float exitPDF = top.PDF(wi, -w, !mode, kT);
                            Float wt2 = PowerHeuristic(1, ps->pdf, 1, exitPDF);
                            f += beta * Tr(zp - thickness, ps->wi) * fExit * wt2;
                        }
                    }
                    continue;
                }
                z = Clamp(zp, 0, thickness);
            }

            if (z == thickness) {
                // At the coat from inside: only reflection continues the walk (leaving is
                // accounted for by the connections).
                uc = r();
                std::optional<BSDFSample> rs = top.Sample_f(-w, uc, {r(), r()}, mode, kR);
                if (!Valid(rs)) break;
                beta *= rs->f * AbsCosTheta(rs->wi) / rs->pdf;
                w = rs->wi;
            } else {
                // At the diffuse base: connect to wi through the coat (MIS against the
                // base's sampling reaching the coat's transmission lobe) ...
                Float wt = 1;
                if (!topSpecular)
                    wt = PowerHeuristic(1, wis->pdf, 1, bottom.PDF(-w, -wis->wi));
                f += beta * bottom.f(-w, -wis->wi) * AbsCosTheta(wis->wi) * wt *
                     Tr(thickness, wis->wi) * wis->f / wis->pdf;
                // ... then sample the base's reflection ...
                uc = r();
                std::optional<BSDFSample> bs = bottom.Sample_f(-w, uc, {r(), r()});
                if (!Valid(bs)) break;
                beta *= bs->f * AbsCosTheta(bs->wi) / bs->pdf;
                w = bs->wi;
                // ... and count its direction if it leaves through a rough coat to wi.
                if (!topSpecular) {
                    SampledSpectrum fExit = top.f(-w, wi, mode);
                    if (fExit.IsNonZero()) {
                        Float exitPDF = top.PDF(wi, -w, !mode, kT);
                        Float wt2 = PowerHeuristic(1, bs->pdf, 1, exitPDF);
                        f += beta * Tr(thickness, bs->wi) * fExit * wt2;
                    }
                }
            }
        }
    }
    return f / Float(nSamples);
}

std::optional<BSDFSample> CoatedDiffuseBxDF::SampleWalk(Vector3f wo, Float uc, Point2f u,
                                                        TransportMode mode) const {
    bool flipWi = false;
    if (wo.z < 0) {
        wo = -wo;
        flipWi = true;
    }
    // First interaction: the coat. Reflection there ends the walk.
    std::optional<BSDFSample> bs = top.Sample_f(wo, uc, u, mode);
    if (!Valid(bs)) return std::nullopt;
    if (!bs->transmission) {
        if (flipWi) bs->wi = -bs->wi;
        return bs;
    }

    // Otherwise follow the refracted direction through the layer until it leaves through
    // the coat. Only the walk's weight, the product of the events' f / pdf, is kept: the
    // sample is returned with pdf 1 (pdfIsProportional; Sample_f replaces it by PDF(wo, wi)
    // and rescales f), so the coat's events need only their ratios (SampleRatio).
    RNG rng(HashInts({kTagSample, seed, HashVector(wo)}),
            HashInts({FloatBits(uc), FloatBits(u.x), FloatBits(u.y)}));
    auto r = [&rng]() { return rng.UniformFloat(); };
    HGPhaseFunction phase(g);
    Vector3f w = bs->wi;
    bool specularPath = bs->specular;
    SampledSpectrum beta = bs->f * (AbsCosTheta(bs->wi) / bs->pdf);
    Float z = thickness;

    for (int depth = 0; depth < maxDepth; ++depth) {
        // Russian roulette on the weight.
        Float rrBeta = beta.MaxComponentValue();
        if (depth > 3 && rrBeta < 0.25f) {
            Float q = std::max<Float>(0, 1 - rrBeta);
            if (r() < q) return std::nullopt;
            beta /= 1 - q;
        }
        if (w.z == 0) return std::nullopt;

        if (albedo.IsNonZero()) {
            Float dz = SampleExponential(r(), 1 / AbsCosTheta(w));
            Float zp = w.z > 0 ? (z + dz) : (z - dz);
            if (zp == z) return std::nullopt;
            if (0 < zp && zp < thickness) {
                std::optional<PhaseFunctionSample> ps = phase.Sample_p(-w, {r(), r()});
                if (!ps || ps->pdf == 0 || ps->wi.z == 0) return std::nullopt;
                beta *= albedo * (ps->p / ps->pdf);
                specularPath = false;
                w = ps->wi;
                z = zp;
                continue;
            }
            z = Clamp(zp, 0, thickness);
        } else {
            z = (z == thickness) ? 0 : thickness;
            beta *= Tr(thickness, w);
        }

        // Scatter at the boundary reached (base at z = 0, coat at z = thickness).
        Float uc1 = r();
        Point2f u2{r(), r()};
        if (z == 0) {
            std::optional<BSDFSample> is = bottom.Sample_f(-w, uc1, u2);
            if (!Valid(is)) return std::nullopt;
            beta *= is->f * (AbsCosTheta(is->wi) / is->pdf);
            specularPath &= is->specular;
            w = is->wi;
            continue;  // the base reflects
        }
        std::optional<DielectricBxDF::RatioSample> is = top.SampleRatio(-w, uc1, u2, mode);
        if (!is) return std::nullopt;
        beta *= is->ratio;
        specularPath &= is->specular;
        w = is->wi;
        if (is->transmission) {
            // Left through the coat, on wo's side (the base is opaque): a reflection.
            if (!beta.IsNonZero()) return std::nullopt;
            return MakeSample(beta, flipWi ? -w : w, 1, specularPath, false);
        }
        beta *= AbsCosTheta(is->wi);
    }
    return std::nullopt;
}

std::optional<BSDFSample> CoatedDiffuseBxDF::Sample_f(Vector3f wo, Float uc, Point2f u,
                                                      TransportMode mode,
                                                      BxDFReflTransFlags flags) const {
    if (!Allows(flags, BxDFReflTransFlags::Reflection)) return std::nullopt;
    std::optional<BSDFSample> s = SampleProportional(wo, uc, u, mode);
    if (!s || !s->pdfIsProportional) return s;
    // Report PDF(wo, wi) for MIS and keep the unbiased weight f / pdf.
    Float p = PDF(wo, s->wi, mode);
    if (!(p > 0)) return std::nullopt;
    s->f *= p / s->pdf;
    s->pdf = p;
    s->pdfIsProportional = false;
    return s;
}

std::optional<BSDFSample> CoatedDiffuseBxDF::SampleProportional(Vector3f wo, Float uc, Point2f u,
                                                                TransportMode mode) const {
    std::optional<BSDFSample> s = SampleWalk(wo, uc, u, mode);
    if (!s || s->specular) return s;
    // PDF(wo, wi) is zero (and Sample_f returns nothing) exactly when wi is not on wo's
    // side; elsewhere its uniform share keeps it positive.
    if (!SameHemisphere(wo, s->wi)) return std::nullopt;
    s->pdfIsProportional = true;
    return s;
}

Float CoatedDiffuseBxDF::PDF(Vector3f wo, Vector3f wi, TransportMode mode,
                             BxDFReflTransFlags flags) const {
    if (!Allows(flags, BxDFReflTransFlags::Reflection)) return 0;
    if (wo.z < 0) {
        wo = -wo;
        wi = -wi;
    }
    // Sample_f never leaves through the opaque base.
    if (!SameHemisphere(wo, wi)) return 0;

    RNG rng(HashInts({kTagPDF, seed, HashVector(wi)}), HashVector(wo));
    auto r = [&rng]() { return rng.UniformFloat(); };
    const BxDFReflTransFlags kR = BxDFReflTransFlags::Reflection,
                             kT = BxDFReflTransFlags::Transmission;

    // Reflection at the coat, exactly.
    Float pdfSum = Float(nSamples) * top.PDF(wo, wi, mode, kR);
    // Transmission-reflection-transmission, estimated stochastically (pbrt-v4, book
    // section 14.3.3): refract both directions into the layer and combine the base's
    // density between them with the coat's density from a base-sampled direction.
    for (int s = 0; s < nSamples; ++s) {
        Float uc = r();
        std::optional<BSDFSample> wos = top.Sample_f(wo, uc, {r(), r()}, mode, kT);
        uc = r();
        std::optional<BSDFSample> wis = top.Sample_f(wi, uc, {r(), r()}, !mode, kT);
        if (!Valid(wos) || !Valid(wis)) continue;
        if (top.IsSpecular()) {
            pdfSum += bottom.PDF(-wos->wi, -wis->wi);
        } else {
            uc = r();
            std::optional<BSDFSample> rs = bottom.Sample_f(-wos->wi, uc, {r(), r()});
            if (!Valid(rs)) continue;
            Float rPDF = bottom.PDF(-wos->wi, -wis->wi);
            pdfSum += PowerHeuristic(1, wis->pdf, 1, rPDF) * rPDF;
            Float tPDF = top.PDF(-rs->wi, wi, mode);
            pdfSum += PowerHeuristic(1, rs->pdf, 1, tPDF) * tPDF;
        }
    }
    // Higher orders scatter more uniformly: mix in a uniform density.
    return Lerp(0.9f, 1 / (4 * Pi), pdfSum / Float(nSamples));
}

}  // namespace pbrt
