// BSDFs: the scattering functions materials produce at a hit. BxDFs work in the local
// shading frame (z = shading normal); BSDF wraps one with the frame. Variants, not virtual
// calls: the later materials issue adds its BxDFs to the variant.
#pragma once

#include <pbrt/sampling.h>
#include <pbrt/spectrum.h>
#include <pbrt/vecmath.h>

#include <optional>
#include <variant>

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

using BxDF = std::variant<DiffuseBxDF>;

class BSDF {
  public:
    BSDF(const Normal3f &ns, const Vector3f &dpdu, BxDF bxdf)
        : frame(Frame::FromXZ(Normalize(dpdu - ns * Dot(dpdu, ns)), ns)), bxdf(std::move(bxdf)) {
        if (frame.x.HasNaN() || LengthSquared(frame.x) < 0.5f) frame = Frame::FromZ(ns);
    }
    bool IsBlack() const { return std::visit([](auto &b) { return b.IsBlack(); }, bxdf); }
    bool IsNonSpecular() const { return std::visit([](auto &b) { return !b.IsSpecular(); }, bxdf); }

    SampledSpectrum f(const Vector3f &woW, const Vector3f &wiW) const {
        Vector3f wo = frame.ToLocal(woW), wi = frame.ToLocal(wiW);
        if (wo.z == 0) return SampledSpectrum(0);
        return std::visit([&](auto &b) { return b.f(wo, wi); }, bxdf);
    }
    std::optional<BSDFSample> Sample_f(const Vector3f &woW, Float uc, Point2f u) const {
        Vector3f wo = frame.ToLocal(woW);
        if (wo.z == 0) return std::nullopt;
        auto s = std::visit([&](auto &b) { return b.Sample_f(wo, uc, u); }, bxdf);
        if (!s || !s->f.IsNonZero() || s->pdf == 0 || s->wi.z == 0) return std::nullopt;
        s->wi = frame.FromLocal(s->wi);
        return s;
    }
    Float PDF(const Vector3f &woW, const Vector3f &wiW) const {
        Vector3f wo = frame.ToLocal(woW), wi = frame.ToLocal(wiW);
        if (wo.z == 0) return 0;
        return std::visit([&](auto &b) { return b.PDF(wo, wi); }, bxdf);
    }

  private:
    Frame frame;
    BxDF bxdf;
};

}  // namespace pbrt
