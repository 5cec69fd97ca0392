// The BxDFs of the "diffusetransmission", "conductor", "dielectric" and "coateddiffuse"
// materials, in the local shading frame (z = shading normal), following the models of the
// pbrt book, 4th ed.:
//   DiffuseTransmissionBxDF  Lambertian reflection R / pi on the side of wo and Lambertian
//                      transmission T / pi to the other side (a thin translucent sheet).
//   ConductorBxDF      section 9.6: specular (smooth) or Trowbridge-Reitz microfacet
//                      reflection with the conductor Fresnel term (complex IOR eta + i k).
//   DielectricBxDF     sections 9.5 and 9.7: specular or microfacet reflection and
//                      transmission with the dielectric Fresnel term; rough transmission
//                      uses the generalized half vector (Walter et al. 2007).
//   CoatedDiffuseBxDF  section 14.3: a dielectric coat over a Lambertian base with a
//                      homogeneous medium between them, evaluated and sampled by random
//                      walks through the layer (Guo et al. 2018, "Position-Free Monte
//                      Carlo Simulation for Arbitrary Layered BSDFs").
//
// Each class has IsBlack, IsSpecular, f, Sample_f and PDF as the BxDF variant of bsdf.h
// calls them, plus two trailing arguments with defaults that the layered model needs from
// its components: the transport mode (radiance or importance: refraction scales radiance
// by 1/eta^2, importance not) and which of reflection/transmission Sample_f/PDF may choose.
#pragma once

// BSDFSample, DiffuseBxDF, CosTheta/SameHemisphere.
#include <pbrt/bxdf.h>
#include <pbrt/fresnel.h>
#include <pbrt/microfacet.h>
#include <pbrt/phase.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>

#include <cstdint>
#include <optional>

namespace pbrt {

// Whether a path carries radiance (from the camera) or importance (from the lights).
enum class TransportMode { Radiance, Importance };
inline TransportMode operator!(TransportMode mode) {
    return mode == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
}

// Which kinds of scattering Sample_f / PDF are restricted to.
enum class BxDFReflTransFlags { Reflection = 1, Transmission = 2, All = 3 };
inline bool Allows(BxDFReflTransFlags flags, BxDFReflTransFlags kind) {
    return (int(flags) & int(kind)) != 0;
}

// ---------------------------------------------------------------------------------------
// f(wo, wi) = R / pi when wi is on wo's side of the surface, T / pi on the other side; no
// refraction (eta 1), so f is symmetric in wo and wi in both transport modes. Sample_f picks
// reflection or transmission with probabilities proportional to the largest value of R and
// of T over the path's wavelengths (restricted by flags), then a cosine-distributed
// direction in that hemisphere; PDF is that mixture's density.
class DiffuseTransmissionBxDF {
  public:
    DiffuseTransmissionBxDF(const SampledSpectrum &R, const SampledSpectrum &T) : R(R), T(T) {}

    bool IsBlack() const { return !R.IsNonZero() && !T.IsNonZero(); }
    bool IsSpecular() const { return false; }

    SampledSpectrum f(const Vector3f &wo, const Vector3f &wi,
                      TransportMode mode = TransportMode::Radiance) const;
    std::optional<BSDFSample> Sample_f(const Vector3f &wo, Float uc, Point2f u,
                                       TransportMode mode = TransportMode::Radiance,
                                       BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;
    Float PDF(const Vector3f &wo, const Vector3f &wi, TransportMode mode = TransportMode::Radiance,
              BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;

  private:
    // The probabilities of choosing reflection and transmission (summing to 1), or false
    // when flags leave nothing to choose.
    bool LobeProbabilities(BxDFReflTransFlags flags, Float *pr, Float *pt) const;

    SampledSpectrum R, T;
};

// ---------------------------------------------------------------------------------------
class ConductorBxDF {
  public:
    // eta and k: real and imaginary parts of the conductor's IOR relative to the outside,
    // at the path's wavelengths.
    ConductorBxDF(const TrowbridgeReitzDistribution &distrib, const SampledSpectrum &eta,
                  const SampledSpectrum &k)
        : distrib(distrib), eta(eta), k(k) {}

    bool IsBlack() const { return false; }
    bool IsSpecular() const { return distrib.EffectivelySmooth(); }

    SampledSpectrum f(const Vector3f &wo, const Vector3f &wi,
                      TransportMode mode = TransportMode::Radiance) const;
    std::optional<BSDFSample> Sample_f(const Vector3f &wo, Float uc, Point2f u,
                                       TransportMode mode = TransportMode::Radiance,
                                       BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;
    Float PDF(const Vector3f &wo, const Vector3f &wi, TransportMode mode = TransportMode::Radiance,
              BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;

  private:
    TrowbridgeReitzDistribution distrib;
    SampledSpectrum eta, k;
};

// ---------------------------------------------------------------------------------------
class DielectricBxDF {
  public:
    // eta: IOR of the inside (below the surface, z < 0) over the outside. One value for
    // all wavelengths: a dispersive material terminates the secondary wavelengths first.
    DielectricBxDF(Float eta, const TrowbridgeReitzDistribution &distrib)
        : eta(eta), distrib(distrib) {}

    bool IsBlack() const { return false; }
    // eta == 1 is an index-matched boundary: light passes straight through.
    bool IsSpecular() const { return eta == 1 || distrib.EffectivelySmooth(); }
    Float Eta() const { return eta; }

    SampledSpectrum f(const Vector3f &wo, const Vector3f &wi,
                      TransportMode mode = TransportMode::Radiance) const;
    std::optional<BSDFSample> Sample_f(const Vector3f &wo, Float uc, Point2f u,
                                       TransportMode mode = TransportMode::Radiance,
                                       BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;
    Float PDF(const Vector3f &wo, const Vector3f &wi, TransportMode mode = TransportMode::Radiance,
              BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;

    // Sample_f's direction (the same one for the same numbers, all lobes allowed) with only
    // the ratio f / pdf, which is all a random walk through a layer needs: the microfacet
    // density D(wm) cancels from it, leaving (G / G1) F / (P |cos wi|) for a rough surface
    // (F: the Fresnel reflectance or transmittance, P: the probability of the lobe chosen).
    // Nothing where Sample_f returns no sample or a zero f or pdf.
    struct RatioSample {
        Vector3f wi;
        Float ratio;  // f / pdf, cosine of wi not included
        bool specular, transmission;
    };
    std::optional<RatioSample> SampleRatio(const Vector3f &wo, Float uc, Point2f u,
                                           TransportMode mode = TransportMode::Radiance) const;

  private:
    Float eta;
    TrowbridgeReitzDistribution distrib;
};

// ---------------------------------------------------------------------------------------
// pbrt-v4's "coateddiffuse": LayeredBxDF<DielectricBxDF, DiffuseBxDF, twoSided = true>.
// The coat (top, z = thickness) and the base (bottom, z = 0) enclose a medium with
// extinction 1 per unit thickness, single-scattering albedo `albedo` (0: purely absorbing)
// and a Henyey-Greenstein phase function with asymmetry g. Two-sided: seen from below,
// both directions are mirrored. The base is opaque, so nothing is transmitted.
//
// f() is an unbiased stochastic estimate (nSamples random walks of at most maxDepth
// scattering events, with Russian roulette); its random numbers come from a generator
// seeded by hashing (seed, wo, wi), so f is deterministic for each pair of directions.
// Sample_f follows one random walk from wo and returns f and pdf whose ratio is an
// unbiased weight; PDF() is pbrt-v4's approximation of the sampling density (the coat's
// reflection plus one stochastic estimate of the transmit-reflect-transmit term, mixed
// with a uniform density). For multiple importance sampling, the pdf that Sample_f
// returns for a non-specular sample is PDF(wo, wi), with f scaled to keep the weight
// f / pdf (what pbrt-v4's integrators do with its "pdfIsProportional" samples).
class CoatedDiffuseBxDF {
  public:
    CoatedDiffuseBxDF(const DielectricBxDF &top, const DiffuseBxDF &bottom, Float thickness,
                      const SampledSpectrum &albedo, Float g, int maxDepth, int nSamples,
                      uint64_t seed = 0);

    bool IsBlack() const { return false; }
    bool IsSpecular() const { return false; }

    SampledSpectrum f(Vector3f wo, Vector3f wi, TransportMode mode = TransportMode::Radiance) const;
    std::optional<BSDFSample> Sample_f(Vector3f wo, Float uc, Point2f u,
                                       TransportMode mode = TransportMode::Radiance,
                                       BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;
    Float PDF(Vector3f wo, Vector3f wi, TransportMode mode = TransportMode::Radiance,
              BxDFReflTransFlags flags = BxDFReflTransFlags::All) const;
    // Sample_f without the rescaling to PDF(): the walk's own density, marked
    // pdfIsProportional when not specular (the same weight f / pdf; PDF(wo, wi) is left to
    // the caller, who needs it only for multiple importance sampling).
    std::optional<BSDFSample> SampleProportional(Vector3f wo, Float uc, Point2f u,
                                                 TransportMode mode = TransportMode::Radiance) const;

  private:
    std::optional<BSDFSample> SampleWalk(Vector3f wo, Float uc, Point2f u, TransportMode mode) const;
    // Transmittance through the medium over a height difference dz along w.
    static Float Tr(Float dz, const Vector3f &w);

    DielectricBxDF top;
    DiffuseBxDF bottom;
    Float thickness, g;
    SampledSpectrum albedo;
    int maxDepth, nSamples;
    uint64_t seed;
};

}  // namespace pbrt
