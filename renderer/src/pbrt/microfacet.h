// The anisotropic Trowbridge-Reitz (GGX) microfacet distribution in the local shading frame
// (z = macro normal), with Smith's height-correlated masking-shadowing and sampling of
// the distribution of visible normals.
//
// Sources: Trowbridge and Reitz 1975; Walter et al. 2007, "Microfacet Models for
// Refraction through Rough Surfaces"; Heitz 2014, "Understanding the Masking-Shadowing
// Function in Microfacet-Based BRDFs" (Lambda, G1, visible normals D_w); Heitz 2018,
// "Sampling the GGX Distribution of Visible Normals", JCGT 7(4) (Sample_wm); conventions
// (alpha per axis, RoughnessToAlpha, the smoothness threshold) of the pbrt book, 4th ed.,
// section 9.6.
#pragma once

#include <pbrt/util/sampling.h>
#include <pbrt/util/vecmath.h>

#include <algorithm>
#include <cmath>

namespace pbrt {

class TrowbridgeReitzDistribution {
  public:
    TrowbridgeReitzDistribution() = default;
    TrowbridgeReitzDistribution(Float alpha_x, Float alpha_y) : alpha_x(alpha_x), alpha_y(alpha_y) {
        // A rough surface with one nearly-zero axis would divide by ~0 in D: keep a floor.
        if (!EffectivelySmooth()) {
            this->alpha_x = std::max<Float>(alpha_x, 1e-4f);
            this->alpha_y = std::max<Float>(alpha_y, 1e-4f);
        }
    }

    // pbrt-v4's user-facing roughness: alpha = sqrt(roughness) (book, section 9.6.1;
    // "remaproughness" true in the scene file format).
    static Float RoughnessToAlpha(Float roughness) { return std::sqrt(std::max<Float>(0, roughness)); }

    // Below this alpha the surface is treated as perfectly smooth (specular); the
    // microfacet terms would be too peaked for floating point (pbrt: 1e-3).
    bool EffectivelySmooth() const { return std::max(alpha_x, alpha_y) < 1e-3f; }
    Float AlphaX() const { return alpha_x; }
    Float AlphaY() const { return alpha_y; }

    // Density of microfacet normals wm (unit) per projected solid angle:
    // D = 1 / (pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2), the Cartesian form of
    // 1 / (pi ax ay cos^4 (1 + tan^2 (cos^2 phi/ax^2 + sin^2 phi/ay^2))^2).
    Float D(const Vector3f &wm) const {
        Float s = Sqr(wm.x / alpha_x) + Sqr(wm.y / alpha_y) + Sqr(wm.z);
        if (s == 0) return 0;
        return 1 / (Pi * alpha_x * alpha_y * Sqr(s));
    }

    // Smith's auxiliary function for the GGX slope distribution:
    // Lambda = (sqrt(1 + alpha(phi)^2 tan^2 theta) - 1) / 2, with
    // alpha(phi)^2 tan^2 theta = (ax^2 x^2 + ay^2 y^2) / z^2. Infinite at grazing.
    Float Lambda(const Vector3f &w) const {
        if (w.z == 0) return Infinity;
        Float a2tan2 = (Sqr(alpha_x * w.x) + Sqr(alpha_y * w.y)) / Sqr(w.z);
        return (std::sqrt(1 + a2tan2) - 1) / 2;
    }
    // Masking for one direction, and height-correlated masking-shadowing for a pair.
    Float G1(const Vector3f &w) const { return 1 / (1 + Lambda(w)); }
    Float G(const Vector3f &wo, const Vector3f &wi) const { return 1 / (1 + Lambda(wo) + Lambda(wi)); }

    // Distribution of normals visible from w: D_w(wm) = G1(w) max(0, w . wm) D(wm) / cos theta_w,
    // a density over upper-hemisphere normals wm per solid angle that integrates to 1. For w
    // below the surface it is that of -w (the side Sample_wm mirrors w to).
    Float D(const Vector3f &w, const Vector3f &wm) const {
        if (w.z == 0) return 0;
        Float cosFacing = w.z > 0 ? Dot(w, wm) : -Dot(w, wm);
        if (cosFacing <= 0) return 0;
        return G1(w) / std::abs(w.z) * D(wm) * cosFacing;
    }
    // Sample_wm draws from D(w, .); this is its density.
    Float PDF(const Vector3f &w, const Vector3f &wm) const { return D(w, wm); }

    // Heitz 2018: stretch w to the configuration with alpha = 1, sample the visible
    // hemisphere there as a uniform disk warped towards the projected half disk, lift it
    // onto the hemisphere, and unstretch. w below the surface is mirrored first, so wm is
    // always in the upper hemisphere.
    Vector3f Sample_wm(const Vector3f &w, Point2f u) const {
        Vector3f wh = Normalize(Vector3f(alpha_x * w.x, alpha_y * w.y, w.z));
        if (wh.z < 0) wh = -wh;
        // Orthonormal basis (T1, T2, wh) with T1 horizontal.
        Vector3f T1 = (wh.z < 0.99999f) ? Normalize(Cross(Vector3f(0, 0, 1), wh)) : Vector3f(1, 0, 0);
        Vector3f T2 = Cross(wh, T1);
        // Uniform disk point. Given p.x, p.y is uniform in [-h, h]; the lerp squeezes it
        // into [h (1 - 2 s), h], the projection of the visible half of the hemisphere.
        Point2f p = SampleUniformDiskConcentric(u);
        Float h = std::sqrt(std::max<Float>(0, 1 - Sqr(p.x)));
        Float s = (1 + wh.z) / 2;
        p.y = (1 - s) * h + s * p.y;
        // Lift to the hemisphere and unstretch.
        Float pz = std::sqrt(std::max<Float>(0, 1 - Sqr(p.x) - Sqr(p.y)));
        Vector3f nh = p.x * T1 + p.y * T2 + pz * wh;
        return Normalize(Vector3f(alpha_x * nh.x, alpha_y * nh.y, std::max<Float>(1e-6f, nh.z)));
    }

  private:
    Float alpha_x = 0, alpha_y = 0;
};

}  // namespace pbrt
