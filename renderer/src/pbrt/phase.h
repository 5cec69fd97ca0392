// The Henyey-Greenstein phase function (Henyey and Greenstein 1941), used by the layered
// BSDF's scattering medium. Both directions point away from the scattering point (pbrt's
// convention): light travels along -wo and leaves along wi, so g > 0 (forward scattering)
// favours wi close to -wo. Sample and density form the usual pair; the sampled density is
// exactly p (the distribution is normalized over the sphere).
#pragma once

#include <pbrt/util/vecmath.h>

#include <cmath>
#include <optional>

namespace pbrt {

struct PhaseFunctionSample {
    Float p;       // phase function value
    Vector3f wi;
    Float pdf;     // equal to p
};

class HGPhaseFunction {
  public:
    explicit HGPhaseFunction(Float g) : g(Clamp(g, -0.99f, 0.99f)) {}

    // p = (1 - g^2) / (4 pi (1 + g^2 + 2 g cos)^(3/2)) with cos = wo . wi.
    Float p(const Vector3f &wo, const Vector3f &wi) const { return HG(Dot(wo, wi)); }
    Float PDF(const Vector3f &wo, const Vector3f &wi) const { return p(wo, wi); }

    // Inverts the CDF of mu = cos(angle between the travel direction -wo and wi):
    // mu = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) / (2 g); uniform mu when g ~ 0.
    std::optional<PhaseFunctionSample> Sample_p(const Vector3f &wo, Point2f u) const {
        Float mu;
        if (std::abs(g) < 1e-3f)
            mu = 1 - 2 * u.x;
        else
            mu = (1 + Sqr(g) - Sqr((1 - Sqr(g)) / (1 - g + 2 * g * u.x))) / (2 * g);
        mu = Clamp(mu, -1, 1);
        Float sinTheta = SafeSqrt(1 - Sqr(mu));
        Float phi = 2 * Pi * u.y;
        Frame frame = Frame::FromZ(-wo);
        Vector3f wi = frame.FromLocal(SphericalDirection(sinTheta, mu, phi));
        Float pdf = HG(-mu);
        return PhaseFunctionSample{pdf, wi, pdf};
    }

  private:
    Float HG(Float cosTheta) const {
        Float denom = 1 + Sqr(g) + 2 * g * cosTheta;
        return Inv4Pi * (1 - Sqr(g)) / (denom * SafeSqrt(denom));
    }
    Float g;
};

}  // namespace pbrt
