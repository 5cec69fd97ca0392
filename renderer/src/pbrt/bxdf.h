// The pieces every BxDF shares: local-frame trigonometry (z = shading normal), the sample
// record Sample_f returns, and the Lambertian DiffuseBxDF (also the base of the coated
// diffuse layer). bsdf.h collects the BxDFs into one variant.
#pragma once

#include <pbrt/util/sampling.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>

#include <optional>

namespace pbrt {

inline Float CosTheta(const Vector3f &w) { return w.z; }
inline Float AbsCosTheta(const Vector3f &w) { return std::abs(w.z); }
inline bool SameHemisphere(const Vector3f &a, const Vector3f &b) { return a.z * b.z > 0; }

struct BSDFSample {
    SampledSpectrum f;
    Vector3f wi;         // world space in BSDF::Sample_f results
    Float pdf = 0;
    bool specular = false, transmission = false;
    Float eta = 1;       // relative IOR for transmission
    // pdf is the density of the sampling procedure (f / pdf is the sample's weight), not
    // PDF(wo, wi), which multiple importance sampling needs: the coated layer's random walk,
    // whose PDF is a costly estimate of its own; BSDF::DeferredPDF gives it when needed.
    bool pdfIsProportional = false;
    Vector3f woLocal, wiLocal;  // the pair in the shading frame (set by BSDF::Sample_f)
};

// Lambertian reflection, f = R / pi (pbrt-v4's DiffuseBxDF).
class DiffuseBxDF {
  public:
    explicit DiffuseBxDF(const SampledSpectrum &R) : R(R) {}
    bool IsBlack() const { return !R.IsNonZero(); }
    bool IsSpecular() const { return false; }
    SampledSpectrum f(const Vector3f &wo, const Vector3f &wi) const {
        if (!SameHemisphere(wo, wi)) return SampledSpectrum(0);
        return R * InvPi;
    }
    std::optional<BSDFSample> Sample_f(const Vector3f &wo, Float uc, Point2f u) const {
        Vector3f wi = SampleCosineHemisphere(u);
        if (wo.z < 0) wi.z = -wi.z;
        Float pdf = CosineHemispherePDF(AbsCosTheta(wi));
        if (pdf == 0) return std::nullopt;
        BSDFSample s;
        s.f = R * InvPi;
        s.wi = wi;
        s.pdf = pdf;
        return s;
    }
    Float PDF(const Vector3f &wo, const Vector3f &wi) const {
        if (!SameHemisphere(wo, wi)) return 0;
        return CosineHemispherePDF(AbsCosTheta(wi));
    }

  private:
    SampledSpectrum R;
};

}  // namespace pbrt
