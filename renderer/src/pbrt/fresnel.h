// Specular scattering at a smooth interface: the mirror and refraction directions and the
// Fresnel reflectance of dielectrics and conductors (unpolarized light: the mean of the
// parallel and perpendicular amplitude reflectances squared). Directions are unit vectors
// pointing away from the surface; n is the (micro)surface normal. See the pbrt book, 4th
// ed., sections 9.3 (specular reflection/refraction) and 9.5 (Fresnel equations).
#pragma once

#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>

#include <complex>

namespace pbrt {

// Mirror direction of wo about n.
inline Vector3f Reflect(const Vector3f &wo, const Vector3f &n) { return -wo + 2 * Dot(wo, n) * n; }

// Refraction of wi through a surface with normal n. eta is the relative index of
// refraction eta_t / eta_i for light arriving from the side n points to; wi on the other
// side sees 1/eta. Returns false on total internal reflection; otherwise *wt is the
// refracted direction and *etap the relative IOR actually used.
inline bool Refract(const Vector3f &wi, Vector3f n, Float eta, Float *etap, Vector3f *wt) {
    Float cosTheta_i = Dot(n, wi);
    // Coming from below: flip the interface so that wi is "above".
    if (cosTheta_i < 0) {
        eta = 1 / eta;
        cosTheta_i = -cosTheta_i;
        n = -n;
    }
    // Snell's law on sines; sin^2 >= 1 means total internal reflection.
    Float sin2Theta_i = std::max<Float>(0, 1 - Sqr(cosTheta_i));
    Float sin2Theta_t = sin2Theta_i / Sqr(eta);
    if (sin2Theta_t >= 1) return false;
    Float cosTheta_t = SafeSqrt(1 - sin2Theta_t);
    *wt = -wi / eta + (cosTheta_i / eta - cosTheta_t) * n;
    if (etap) *etap = eta;
    return true;
}

// Fresnel reflectance of a dielectric interface with relative IOR eta (transmitted side
// over incident side for cosTheta_i > 0). cosTheta_i < 0 means the light arrives from the
// other side, which sees 1/eta; total internal reflection gives 1.
inline Float FrDielectric(Float cosTheta_i, Float eta) {
    cosTheta_i = Clamp(cosTheta_i, -1, 1);
    if (cosTheta_i < 0) {
        eta = 1 / eta;
        cosTheta_i = -cosTheta_i;
    }
    Float sin2Theta_t = (1 - Sqr(cosTheta_i)) / Sqr(eta);
    if (sin2Theta_t >= 1) return 1;
    Float cosTheta_t = SafeSqrt(1 - sin2Theta_t);
    Float rParallel = (eta * cosTheta_i - cosTheta_t) / (eta * cosTheta_i + cosTheta_t);
    Float rPerpendicular = (cosTheta_i - eta * cosTheta_t) / (cosTheta_i + eta * cosTheta_t);
    return (Sqr(rParallel) + Sqr(rPerpendicular)) / 2;
}

// The principal square root of z, with the textbook formulas (t = sqrt((|x| + |z|) / 2),
// no cancellation) instead of libm's csqrt, which guards against overflow and infinities a
// relative IOR cannot produce and costs about four times as much. |z| in double cannot
// overflow here (z comes from float values).
inline std::complex<double> PrincipalSqrt(std::complex<double> z) {
    double x = z.real(), y = z.imag();
    double r = std::sqrt(x * x + y * y);
    if (r == 0) return {0, y};
    double t = std::sqrt(0.5 * (r + std::abs(x)));
    if (x >= 0) return {t, y / (2 * t)};
    return {std::abs(y) / (2 * t), std::copysign(t, y)};
}

// Fresnel reflectance of a conductor with complex relative IOR eta = n + i k, for light
// arriving from the dielectric side (cosTheta_i is clamped to [0, 1]). The same
// amplitude formulas as the dielectric case, with complex arithmetic; no total internal
// reflection is possible. The renderer uses the four-wavelength version below; this one,
// written with std::complex, is the formula that version is tested against.
//
// Written without complex division (a libgcc call with C99's infinity rules, slow on the
// hot path): |a / b|^2 = |a|^2 / |b|^2, and s / e for real s is s conj(e) / |e|^2. In
// double, so that |eta|^4 cannot overflow for any sane eta. The same value as the direct
// complex formula up to rounding.
inline Float FrComplex(Float cosTheta_i, std::complex<Float> etaF) {
    using Complex = std::complex<double>;
    double c = Clamp(cosTheta_i, 0, 1);
    double sin2Theta_i = 1 - c * c;
    Complex eta(etaF.real(), etaF.imag());
    Complex eta2 = eta * eta;
    Complex sin2Theta_t = sin2Theta_i * std::conj(eta2) / std::norm(eta2);
    Complex cosTheta_t = PrincipalSqrt(1.0 - sin2Theta_t);
    Complex ec = eta * c, et = eta * cosTheta_t;
    double rParallel = std::norm(ec - cosTheta_t) / std::norm(ec + cosTheta_t);
    double rPerpendicular = std::norm(c - et) / std::norm(c + et);
    return Float((rParallel + rPerpendicular) / 2);
}

// FrComplex at each of the sampled wavelengths (eta and k per wavelength): the same
// operations written out on real and imaginary parts, with selects instead of
// PrincipalSqrt's branches, so that the compiler runs the wavelengths side by side in
// vector registers (the same values up to rounding; tested against the scalar version).
inline SampledSpectrum FrComplex(Float cosTheta_i, const SampledSpectrum &eta,
                                 const SampledSpectrum &k) {
    const double c = Clamp(cosTheta_i, 0, 1), sin2Theta_i = 1 - c * c;
    double out[NSpectrumSamples];
#if defined(__clang__)
#pragma clang loop vectorize(assume_safety)
#elif defined(__GNUC__)
#pragma GCC ivdep
#endif
    for (int i = 0; i < NSpectrumSamples; ++i) {
        double n = eta[i], kk = k[i];
        double e2r = n * n - kk * kk, e2i = 2 * n * kk;  // eta^2
        double s = sin2Theta_i / (e2r * e2r + e2i * e2i);
        double x = 1 - s * e2r, y = s * e2i;  // 1 - sin^2(theta_t) = 1 - sin2 conj(eta^2) / |eta^2|^2
        // cos(theta_t): the principal square root of x + i y.
        double r = std::sqrt(x * x + y * y);
        double t = std::sqrt(0.5 * (r + std::abs(x)));
        double half = t > 0 ? 0.5 / t : 0;
        double ctr = x >= 0 ? t : std::abs(y) * half, cti = x >= 0 ? y * half : std::copysign(t, y);
        if (r == 0) ctr = 0, cti = y;
        double ecr = n * c, eci = kk * c;                          // eta c
        double etr = n * ctr - kk * cti, eti = n * cti + kk * ctr;  // eta cos(theta_t)
        double rPar = (Sqr(ecr - ctr) + Sqr(eci - cti)) / (Sqr(ecr + ctr) + Sqr(eci + cti));
        double rPerp = (Sqr(c - etr) + Sqr(eti)) / (Sqr(c + etr) + Sqr(eti));
        out[i] = (rPar + rPerp) / 2;
    }
    SampledSpectrum fr;
    for (int i = 0; i < NSpectrumSamples; ++i) fr[i] = Float(out[i]);
    return fr;
}

}  // namespace pbrt
