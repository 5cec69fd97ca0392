// BSDFs: the scattering functions materials produce at a hit. BxDFs work in the local
// shading frame (z = shading normal); BSDF wraps one with the frame. Variants, not virtual
// calls (bxdf.h: DiffuseBxDF; bxdfs.h: diffuse transmission, conductor, dielectric, coated
// diffuse).
#pragma once

#include <pbrt/bxdf.h>
#include <pbrt/bxdfs.h>
#include <pbrt/util/sampling.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>

#include <optional>
#include <type_traits>
#include <variant>

namespace pbrt {

using BxDF = std::variant<DiffuseBxDF, ConductorBxDF, DielectricBxDF, CoatedDiffuseBxDF,
                          DiffuseTransmissionBxDF>;

class BSDF {
  public:
    BSDF(const Normal3f &ns, const Vector3f &dpdu, BxDF bxdf)
        : frame(Frame::FromXZ(Normalize(dpdu - ns * Dot(dpdu, ns)), ns)), bxdf(std::move(bxdf)) {
        if (frame.x.HasNaN() || LengthSquared(frame.x) < 0.5f) frame = Frame::FromZ(ns);
    }
    bool IsBlack() const { return std::visit([](auto &b) { return b.IsBlack(); }, bxdf); }
    bool IsNonSpecular() const { return std::visit([](auto &b) { return !b.IsSpecular(); }, bxdf); }
    // f and PDF are stochastic estimates costing many evaluations (the coated layer).
    bool HasCostlyF() const { return std::holds_alternative<CoatedDiffuseBxDF>(bxdf); }
    // wo and wi on the same side of the shading surface, as f sees them (a reflection-only
    // BxDF's f is 0 otherwise).
    bool SameSide(const Vector3f &woW, const Vector3f &wiW) const {
        return SameHemisphere(frame.ToLocal(woW), frame.ToLocal(wiW));
    }

    SampledSpectrum f(const Vector3f &woW, const Vector3f &wiW) const {
        Vector3f wo = frame.ToLocal(woW), wi = frame.ToLocal(wiW);
        if (wo.z == 0) return SampledSpectrum(0);
        return std::visit([&](auto &b) { return b.f(wo, wi); }, bxdf);
    }
    // exactPdf false lets a sample report its sampling density instead of PDF(wo, wi)
    // (pdfIsProportional; the coated layer's walk), to be completed by DeferredPDF.
    std::optional<BSDFSample> Sample_f(const Vector3f &woW, Float uc, Point2f u, bool exactPdf = true) const {
        Vector3f wo = frame.ToLocal(woW);
        if (wo.z == 0) return std::nullopt;
        auto s = std::visit([&](auto &b) -> std::optional<BSDFSample> {
            if constexpr (std::is_same_v<std::decay_t<decltype(b)>, CoatedDiffuseBxDF>)
                if (!exactPdf) return b.SampleProportional(wo, uc, u);
            return b.Sample_f(wo, uc, u);
        }, bxdf);
        if (!s || !s->f.IsNonZero() || s->pdf == 0 || s->wi.z == 0) return std::nullopt;
        s->woLocal = wo;
        s->wiLocal = s->wi;
        s->wi = frame.FromLocal(s->wi);
        return s;
    }
    // PDF(wo, wi) of a sample this BSDF returned: the value Sample_f with exactPdf would
    // have reported.
    Float DeferredPDF(const BSDFSample &s) const {
        return std::visit([&](auto &b) { return b.PDF(s.woLocal, s.wiLocal); }, bxdf);
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
