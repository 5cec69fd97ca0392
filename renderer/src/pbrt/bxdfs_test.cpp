// Tests of the Fresnel terms, the Trowbridge-Reitz distribution, the Henyey-Greenstein phase
// function and the diffuse-transmission, conductor, dielectric and coated-diffuse BxDFs:
//   energy       white-furnace albedo E[f |cos| / pdf] <= 1, and = 1 where lossless;
//   reciprocity  f(wo, wi) = f(wi, wo) for reflection, the eta^2 rule for transmission;
//   sampling     chi-square of sampled directions against the integrated PDF (non-delta
//                components), and Sample_f's f / pdf equal to f() / PDF();
// at roughness 0 (specular) to alpha 1 and cos(theta_o) from 0.05 (grazing) to 1.
// Random numbers come from fixed seeds, so every statistical test is deterministic; the
// thresholds are stated with each test (p-values, or multiples of the measured standard
// error).
#include <pbrt/bsdf.h>
#include <pbrt/bxdfs.h>

#include <pbrt/fresnel.h>
#include <pbrt/microfacet.h>
#include <pbrt/phase.h>
#include <pbrt/util/rng.h>
#include <pbrt/util/sampling.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace pbrt {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vector3f Dir(Float cosTheta, Float phi) {
    return SphericalDirection(SafeSqrt(1 - Sqr(cosTheta)), cosTheta, phi);
}

// ---------------------------------------------------------------------------------------
// Chi-square machinery.

// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a): the chi-square
// p-value is Q(dof / 2, stat / 2). Written here because no packaged library in the build
// provides it (Boost.Math is not a dependency); series for x < a + 1, Lentz's continued
// fraction otherwise (Press et al., "Numerical Recipes", 3rd ed., section 6.2).
double GammaQ(double a, double x) {
    if (x <= 0) return 1;
    double lnPre = a * std::log(x) - x - std::lgamma(a);
    if (x < a + 1) {
        double sum = 1 / a, term = sum;
        for (int n = 1; n < 10000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (std::abs(term) < std::abs(sum) * 1e-15) break;
        }
        return std::max(0.0, 1 - sum * std::exp(lnPre));
    }
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 10000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1 / d;
        double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1) < 1e-15) break;
    }
    return std::exp(lnPre) * h;
}

TEST(ChiSquare, GammaQMatchesKnownValues) {
    // Q(1, x) = exp(-x); chi-square with 2 dof at 5.991 has p = 0.05; with 10 dof at
    // 23.209 has p = 0.01 (standard tables).
    EXPECT_NEAR(GammaQ(1, 2.5), std::exp(-2.5), 1e-12);
    EXPECT_NEAR(GammaQ(1, 0.3), std::exp(-0.3), 1e-12);
    EXPECT_NEAR(GammaQ(1.0, 5.991 / 2), 0.05, 1e-4);
    EXPECT_NEAR(GammaQ(5.0, 23.209 / 2), 0.01, 1e-4);
    EXPECT_NEAR(GammaQ(50.0, 50.0), 0.4812, 1e-3);
}

// A sampler of directions: given (uc, u), a direction or nothing (a failed sample).
using DirSampler = std::function<std::optional<Vector3f>(Float, Point2f)>;
using DirPDF = std::function<double(const Vector3f &)>;

// Histogram of n sampled directions over (theta, phi) bins of the sphere against the
// expected counts n * integral of pdf over each bin; bins expecting fewer than 5 are
// pooled. Returns the p-value; *report gets the statistics. Failed samples (Sample_f
// returning nothing, e.g. a reflection below the horizon) are the missing mass of the pdf:
// their fraction must be 1 - integral of pdf within 4 sigma + 2e-3 (the quadrature's
// accuracy for the total), else the p-value returned is 0.
//
// Each bin's integral uses the midpoint rule on sub x sub cells, doubling sub until the
// change is far below the bin's Poisson noise (narrow lobes near the poles need it).
double ChiSquareTest(const DirSampler &sample, const DirPDF &pdf, int n, uint64_t seed,
                     std::string *report, int nTheta = 24, int nPhi = 48) {
    const int nBins = nTheta * nPhi;
    // One extra cell counts failed samples.
    std::vector<double> observed(nBins + 1, 0), expected(nBins + 1, 0);
    RNG rng(seed);
    for (int i = 0; i < n; ++i) {
        Float uc = rng.UniformFloat();
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        std::optional<Vector3f> w = sample(uc, u);
        if (!w) {
            observed[nBins] += 1;
            continue;
        }
        double theta = std::acos(Clamp(double(w->z), -1.0, 1.0));
        double phi = std::atan2(double(w->y), double(w->x));
        if (phi < 0) phi += 2 * kPi;
        int it = std::min(nTheta - 1, int(theta / kPi * nTheta));
        int ip = std::min(nPhi - 1, int(phi / (2 * kPi) * nPhi));
        observed[it * nPhi + ip] += 1;
    }
    const double dTheta = kPi / nTheta, dPhi = 2 * kPi / nPhi;
    auto integrateBin = [&](int it, int ip, int sub) {
        double sum = 0;
        for (int a = 0; a < sub; ++a)
            for (int b = 0; b < sub; ++b) {
                double theta = (it + (a + 0.5) / sub) * dTheta;
                double phi = (ip + (b + 0.5) / sub) * dPhi;
                Vector3f w(Float(std::sin(theta) * std::cos(phi)),
                           Float(std::sin(theta) * std::sin(phi)), Float(std::cos(theta)));
                sum += pdf(w) * std::sin(theta);
            }
        return sum * dTheta * dPhi / (sub * sub);
    };
    // A coarse pass, then the bins that matter (and their neighbours, where a lobe may
    // start just inside) are refined from 16 vs 32 cells a side until the change is far
    // below the Poisson noise; a jump of the pdf inside a bin (where a transmission lobe
    // starts) needs up to 256.
    std::vector<double> coarse(nBins);
    for (int it = 0; it < nTheta; ++it)
        for (int ip = 0; ip < nPhi; ++ip) coarse[it * nPhi + ip] = integrateBin(it, ip, 8);
    auto heavy = [&](int it, int ip) {
        for (int dt = -1; dt <= 1; ++dt)
            for (int dp = -1; dp <= 1; ++dp) {
                int jt = it + dt, jp = (ip + dp + nPhi) % nPhi;
                if (jt >= 0 && jt < nTheta && n * coarse[jt * nPhi + jp] > 20) return true;
            }
        return false;
    };
    double total = 0;
    for (int it = 0; it < nTheta; ++it)
        for (int ip = 0; ip < nPhi; ++ip) {
            double cur = coarse[it * nPhi + ip];
            if (heavy(it, ip)) {
                int sub = 32;
                double prev = integrateBin(it, ip, 16);
                cur = integrateBin(it, ip, sub);
                while (sub < 256 && n * std::abs(cur - prev) > 0.1 * std::sqrt(n * cur)) {
                    prev = cur;
                    sub *= 2;
                    cur = integrateBin(it, ip, sub);
                }
            }
            expected[it * nPhi + ip] = n * cur;
            total += cur;
        }
    expected[nBins] = n * std::max(0.0, 1 - total);
    double failTol = 4 * std::sqrt(std::max(expected[nBins], 1.0)) + 2e-3 * n;
    bool failuresOk = std::abs(observed[nBins] - expected[nBins]) <= failTol;

    // Pool the sparse cells, then sum (o - e)^2 / e over the direction cells.
    double pooledObs = 0, pooledExp = 0, stat = 0;
    int cells = 0;
    for (int i = 0; i < nBins; ++i) {
        if (expected[i] < 5) {
            pooledObs += observed[i];
            pooledExp += expected[i];
        } else {
            stat += Sqr(observed[i] - expected[i]) / expected[i];
            ++cells;
        }
    }
    if (pooledExp > 0) {
        stat += Sqr(pooledObs - pooledExp) / pooledExp;
        ++cells;
    } else if (pooledObs > 0) {
        stat = INFINITY;  // samples where the pdf is zero
    }
    int dof = std::max(1, cells - 1);
    double p = failuresOk ? GammaQ(dof / 2.0, stat / 2) : 0.0;
    std::ostringstream os;
    os << "chi2 = " << stat << " dof = " << dof << " p = " << p << " integral(pdf) = " << total
       << " failed samples = " << observed[nBins] << "/" << n << " (expected "
       << expected[nBins] << (failuresOk ? ")" : ", too different)");
    *report = os.str();
    return p;
}

// Significance of each chi-square test: with ~100 such tests in this file, 1e-4 keeps the
// chance of any false rejection near 1% (the seeds are fixed, so results are repeatable).
constexpr double kChi2Alpha = 1e-4;
// Samples per chi-square test: enough to see a 2% error in a lobe's shape.
constexpr int kChi2Samples = 40000;

// ---------------------------------------------------------------------------------------
// Monte Carlo helpers.

struct Estimate {
    double mean = 0, stdErr = 0;
};
Estimate MeanOf(const std::vector<double> &v) {
    Estimate e;
    double s = 0, s2 = 0;
    for (double x : v) {
        s += x;
        s2 += x * x;
    }
    double n = double(v.size());
    e.mean = s / n;
    e.stdErr = std::sqrt(std::max(0.0, s2 / n - Sqr(e.mean)) / n);
    return e;
}

// White-furnace albedo from Sample_f: E[f |cos wi| / pdf] (channel 0; the tests use
// wavelength-independent parameters). With etaScale, transmitted weights are multiplied
// by etap^2, undoing the radiance compression (as the integrator's etaScale does), so
// that energy conservation means exactly <= 1.
template <typename B>
Estimate SampledAlbedo(const B &bxdf, const Vector3f &wo, int n, uint64_t seed, bool etaScale,
                       TransportMode mode = TransportMode::Radiance,
                       double *reflectedFraction = nullptr) {
    RNG rng(seed);
    std::vector<double> w(n, 0);
    int reflected = 0;
    for (int i = 0; i < n; ++i) {
        Float uc = rng.UniformFloat();
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        std::optional<BSDFSample> s = bxdf.Sample_f(wo, uc, u, mode);
        if (!s || s->pdf == 0) continue;
        double x = s->f[0] * AbsCosTheta(s->wi) / s->pdf;
        if (etaScale && s->transmission) x *= Sqr(s->eta);
        w[i] = x;
        if (!s->transmission) ++reflected;
    }
    if (reflectedFraction) *reflectedFraction = double(reflected) / n;
    return MeanOf(w);
}

// Checks, for non-specular samples, that Sample_f's f and pdf equal f() and PDF().
template <typename B>
void ExpectSampleMatchesEval(const B &bxdf, const Vector3f &wo, int n, uint64_t seed,
                             double relTol, const std::string &what) {
    RNG rng(seed);
    int checked = 0;
    for (int i = 0; i < n; ++i) {
        Float uc = rng.UniformFloat();
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        std::optional<BSDFSample> s = bxdf.Sample_f(wo, uc, u);
        if (!s || s->specular) continue;
        ++checked;
        Float pdf = bxdf.PDF(wo, s->wi);
        SampledSpectrum f = bxdf.f(wo, s->wi);
        ASSERT_NEAR(s->pdf, pdf, relTol * std::max(s->pdf, pdf))
            << what << ": Sample_f pdf vs PDF() at wi = " << ToString(s->wi);
        ASSERT_NEAR(s->f[0], f[0], relTol * std::max(s->f[0], f[0]))
            << what << ": Sample_f f vs f() at wi = " << ToString(s->wi);
    }
    EXPECT_GT(checked, n / 3) << what << ": most samples should succeed";
}

std::string Describe(const std::string &name, Float ax, Float ay, Float cosTheta_o) {
    std::ostringstream os;
    os << name << " alpha = (" << ax << ", " << ay << ") cos(theta_o) = " << cosTheta_o;
    return os.str();
}

const Float kCosThetas[] = {0.05f, 0.2f, 0.5f, 1.0f};
// Rough alphas from nearly smooth to alpha = 1 (roughness 1 with or without remapping),
// with an anisotropic pair.
const Float kAlphas[][2] = {{0.1f, 0.1f}, {0.3f, 0.3f}, {1.0f, 1.0f}, {0.1f, 0.5f}};

// =======================================================================================
// Fresnel

TEST(Fresnel, DielectricNormalIncidenceAndSymmetry) {
    for (Float eta : {1.33f, 1.5f, 2.4f, 0.763f}) {
        Float r0 = Sqr((eta - 1) / (eta + 1));
        EXPECT_NEAR(FrDielectric(1, eta), r0, 1e-6) << "eta " << eta;
        EXPECT_NEAR(FrDielectric(-1, eta), r0, 1e-6) << "from inside, eta " << eta;
        // Both sides of a refraction pair see the same reflectance.
        for (Float cosI : {0.05f, 0.3f, 0.7f, 0.99f}) {
            Vector3f wi = Dir(cosI, 0.3f), wt;
            Float etap;
            ASSERT_TRUE(Refract(wi, Vector3f(0, 0, 1), eta, &etap, &wt) || eta < 1);
            if (!Refract(wi, Vector3f(0, 0, 1), eta, &etap, &wt)) continue;
            EXPECT_NEAR(FrDielectric(cosI, eta), FrDielectric(wt.z, eta), 1e-5)
                << "eta " << eta << " cos " << cosI;
        }
    }
    EXPECT_NEAR(FrDielectric(0.4f, 1), 0, 1e-7) << "index-matched boundary reflects nothing";
    // Total internal reflection from inside glass beyond the critical angle.
    Float cosCrit = std::sqrt(1 - 1 / Sqr(1.5f));
    EXPECT_EQ(FrDielectric(-(cosCrit - 0.01f), 1.5f), 1);
    EXPECT_LT(FrDielectric(-(cosCrit + 0.01f), 1.5f), 1);
    EXPECT_EQ(FrDielectric(0.3f, 1 / 1.5f), 1) << "eta < 1 from outside: TIR";
}

TEST(Fresnel, RefractObeysSnellAndReverses) {
    RNG rng(7);
    for (int i = 0; i < 200; ++i) {
        Float eta = 1.1f + rng.UniformFloat();
        Vector3f n = Normalize(Vector3f(rng.UniformFloat() - 0.5f, rng.UniformFloat() - 0.5f, 1));
        Vector3f wi = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
        Vector3f wt;
        Float etap;
        if (!Refract(wi, n, eta, &etap, &wt)) {
            EXPECT_GT(1 - Sqr(Dot(wi, n)), Sqr(1 / eta) - 1e-5f) << "TIR only from the dense side";
            continue;
        }
        // Snell: sin_i = etap sin_t; opposite sides; coplanar.
        Float sinI = Length(Cross(wi, n)), sinT = Length(Cross(wt, n));
        EXPECT_NEAR(sinI, etap * sinT, 1e-4);
        EXPECT_LT(Dot(wi, n) * Dot(wt, n), 0);
        EXPECT_NEAR(Dot(Cross(wi, n), wt), 0, 1e-4);
        // Refracting back recovers wi.
        Vector3f back;
        Float etap2;
        ASSERT_TRUE(Refract(wt, n, eta, &etap2, &back));
        EXPECT_NEAR(Length(back - wi), 0, 1e-4);
        EXPECT_NEAR(etap * etap2, 1, 1e-5);
    }
}

TEST(Fresnel, PrincipalSqrtIsLibmsSqrt) {
    // Every quadrant, both axes (with signed zeros), tiny and large magnitudes: the branch
    // cut (negative real axis) must follow the sign of the imaginary part, as csqrt does.
    const double values[] = {0.0, -0.0, 1e-30, -1e-30, 1e-7, -1e-7, 0.3, -0.3, 1.0, -1.0, 2.5, -2.5, 1e12, -1e12};
    for (double x : values)
        for (double y : values) {
            std::complex<double> want = std::sqrt(std::complex<double>(x, y));
            std::complex<double> got = PrincipalSqrt({x, y});
            double scale = std::abs(want) + 1e-300;
            EXPECT_LE(std::abs(got - want), 4e-16 * scale) << x << " + " << y << "i";
            EXPECT_EQ(std::signbit(got.imag()), std::signbit(want.imag())) << x << " + " << y << "i";
            EXPECT_GE(got.real(), 0) << x << " + " << y << "i";
        }
}

TEST(Fresnel, SpectralComplexIsThePerWavelengthFormula) {
    // The four-wavelength version (written for vector registers) against the scalar one, over
    // metals, dielectric-like and absorbing-dielectric values, at every angle.
    RNG rng(21);
    for (int i = 0; i < 20000; ++i) {
        SampledSpectrum eta, k;
        for (int j = 0; j < NSpectrumSamples; ++j) {
            eta[j] = i % 3 == 0 ? 0.05f + 3 * rng.UniformFloat() : 1 + rng.UniformFloat();
            k[j] = i % 3 == 1 ? 0.f : (i % 3 == 2 ? 0.01f : 8.f) * rng.UniformFloat();
        }
        Float cosI = i % 50 == 0 ? Float(i % 100 == 0) : rng.UniformFloat();
        SampledSpectrum F = FrComplex(cosI, eta, k);
        for (int j = 0; j < NSpectrumSamples; ++j) {
            Float want = FrComplex(cosI, std::complex<Float>(eta[j], k[j]));
            ASSERT_NEAR(F[j], want, 2e-6f * want + 1e-7f) << "eta " << eta[j] << " k " << k[j] << " cos " << cosI;
        }
    }
}

TEST(Fresnel, ComplexReducesToDielectricAndToPerfectMirror) {
    for (Float cosI : {0.02f, 0.2f, 0.6f, 1.0f}) {
        EXPECT_NEAR(FrComplex(cosI, std::complex<Float>(1.5f, 0)), FrDielectric(cosI, 1.5f), 1e-5)
            << "k = 0 is a dielectric, cos " << cosI;
        EXPECT_GT(FrComplex(cosI, std::complex<Float>(1, 1e4f)), 0.999f)
            << "huge k is a perfect mirror, cos " << cosI;
    }
    // Normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
    Float n = 0.2f, k = 3.9f;
    EXPECT_NEAR(FrComplex(1, std::complex<Float>(n, k)), (Sqr(n - 1) + k * k) / (Sqr(n + 1) + k * k), 1e-5);
    // Per-wavelength version.
    SampledSpectrum eta(std::array<Float, 4>{0.2f, 0.9f, 1.1f, 1.5f}), kk(std::array<Float, 4>{3.9f, 2.4f, 2.1f, 0});
    SampledSpectrum F = FrComplex(0.5f, eta, kk);
    for (int i = 0; i < 4; ++i)
        EXPECT_FLOAT_EQ(F[i], FrComplex(0.5f, std::complex<Float>(eta[i], kk[i])));
    EXPECT_NEAR(F[3], FrDielectric(0.5f, 1.5f), 1e-5);
}

// =======================================================================================
// Trowbridge-Reitz

TEST(TrowbridgeReitz, RoughnessRemappingAndSmoothThreshold) {
    // pbrt-v4: alpha = sqrt(roughness); specular below alpha 1e-3.
    EXPECT_FLOAT_EQ(TrowbridgeReitzDistribution::RoughnessToAlpha(0.25f), 0.5f);
    EXPECT_FLOAT_EQ(TrowbridgeReitzDistribution::RoughnessToAlpha(1), 1);
    EXPECT_EQ(TrowbridgeReitzDistribution::RoughnessToAlpha(0), 0);
    EXPECT_TRUE(TrowbridgeReitzDistribution(0, 0).EffectivelySmooth());
    EXPECT_TRUE(TrowbridgeReitzDistribution(9e-4f, 5e-4f).EffectivelySmooth());
    EXPECT_FALSE(TrowbridgeReitzDistribution(1e-3f, 1e-3f).EffectivelySmooth());
    EXPECT_FALSE(TrowbridgeReitzDistribution(0, 0.2f).EffectivelySmooth());
}

// Integrates g over the upper hemisphere on a (theta, phi) grid refined near the pole.
double IntegrateHemisphere(const std::function<double(const Vector3f &)> &g, int nTheta = 500,
                           int nPhi = 250) {
    double sum = 0;
    // theta = (pi/2) t^2 concentrates nodes near the pole, where narrow lobes live.
    for (int i = 0; i < nTheta; ++i) {
        double t = (i + 0.5) / nTheta, theta = kPi / 2 * t * t, dTheta = kPi * t / nTheta;
        for (int j = 0; j < nPhi; ++j) {
            double phi = (j + 0.5) / nPhi * 2 * kPi;
            Vector3f w(Float(std::sin(theta) * std::cos(phi)), Float(std::sin(theta) * std::sin(phi)),
                       Float(std::cos(theta)));
            sum += g(w) * std::sin(theta) * dTheta * (2 * kPi / nPhi);
        }
    }
    return sum;
}

TEST(TrowbridgeReitz, NormalizationAndVisibleNormals) {
    for (auto &a : kAlphas) {
        TrowbridgeReitzDistribution d(a[0], a[1]);
        // Projected microfacet area equals the macro area: integral of D cos = 1.
        double projected = IntegrateHemisphere([&](const Vector3f &wm) { return d.D(wm) * wm.z; });
        EXPECT_NEAR(projected, 1, 2e-3) << "alpha " << a[0] << "," << a[1];
        // Visible normals integrate to 1 from any direction: this ties Lambda (G1) to D.
        for (Float c : {0.05f, 0.5f, 1.0f, -0.3f}) {
            Vector3f w = Dir(c, 0.7f);
            double visible = IntegrateHemisphere([&](const Vector3f &wm) { return d.D(w, wm); });
            EXPECT_NEAR(visible, 1, 3e-3) << Describe("D_w", a[0], a[1], c);
        }
    }
    TrowbridgeReitzDistribution iso(0.4f, 0.4f);
    EXPECT_NEAR(iso.G1(Vector3f(0, 0, 1)), 1, 1e-6) << "no masking at normal incidence";
    EXPECT_EQ(iso.G1(Vector3f(1, 0, 0)), 0) << "full masking at grazing";
    Vector3f wo = Dir(0.3f, 1), wi = Dir(0.8f, 2);
    EXPECT_FLOAT_EQ(iso.G(wo, wi), iso.G(wi, wo));
    EXPECT_LE(iso.G(wo, wi), std::min(iso.G1(wo), iso.G1(wi)));
}

TEST(TrowbridgeReitz, VisibleNormalSamplingChiSquare) {
    for (auto &a : kAlphas) {
        TrowbridgeReitzDistribution d(a[0], a[1]);
        for (Float c : {0.05f, 0.5f, 1.0f, -0.5f}) {
            Vector3f w = Dir(c, 0.9f);
            std::string report;
            double p = ChiSquareTest(
                [&](Float, Point2f u) -> std::optional<Vector3f> { return d.Sample_wm(w, u); },
                [&](const Vector3f &wm) { return wm.z > 0 ? double(d.PDF(w, wm)) : 0.0; }, kChi2Samples, 11,
                &report);
            EXPECT_GT(p, kChi2Alpha) << Describe("Sample_wm", a[0], a[1], c) << ": " << report;
        }
    }
}

// =======================================================================================
// Henyey-Greenstein

TEST(HGPhaseFunction, NormalizedSymmetricAndSampledExactly) {
    for (Float g : {-0.7f, 0.0f, 0.3f, 0.9f}) {
        HGPhaseFunction phase(g);
        Vector3f wo = Normalize(Vector3f(0.3f, -0.2f, 0.9f));
        // Integral over the sphere (both hemispheres, mirrored w.r.t. z).
        double integral =
            IntegrateHemisphere([&](const Vector3f &w) { return phase.p(wo, w); }, 1200, 400) +
            IntegrateHemisphere([&](const Vector3f &w) { return phase.p(wo, Vector3f(w.x, w.y, -w.z)); },
                                1200, 400);
        EXPECT_NEAR(integral, 1, 5e-3) << "g = " << g;
        Vector3f wi = Normalize(Vector3f(-0.5f, 0.1f, 0.2f));
        EXPECT_FLOAT_EQ(phase.p(wo, wi), phase.p(wi, wo));
        if (g > 0) {
            EXPECT_GT(phase.p(wo, -wo), phase.p(wo, wo)) << "forward scattering";
        }
        std::string report;
        double p = ChiSquareTest(
            [&](Float, Point2f u) -> std::optional<Vector3f> {
                auto s = phase.Sample_p(wo, u);
                if (!s) return std::nullopt;
                EXPECT_NEAR(s->pdf, phase.PDF(wo, s->wi), 1e-3f * s->pdf);
                return s->wi;
            },
            [&](const Vector3f &w) { return double(phase.PDF(wo, w)); }, kChi2Samples, 13, &report);
        EXPECT_GT(p, kChi2Alpha) << "HG g = " << g << ": " << report;
    }
}

// =======================================================================================
// ConductorBxDF

// A perfectly reflecting conductor: eta = 1, k huge (Fresnel reflectance > 0.9999).
ConductorBxDF PerfectConductor(Float ax, Float ay) {
    return ConductorBxDF(TrowbridgeReitzDistribution(ax, ay), SampledSpectrum(1), SampledSpectrum(1e4f));
}

TEST(ConductorBxDF, SmoothIsALosslessMirrorWithFresnel) {
    for (Float c : kCosThetas) {
        Vector3f wo = Dir(c, 0.4f);
        ConductorBxDF perfect = PerfectConductor(0, 0);
        EXPECT_TRUE(perfect.IsSpecular());
        Estimate e = SampledAlbedo(perfect, wo, 100, 1, false);
        EXPECT_NEAR(e.mean, 1, 1e-3) << "smooth perfect conductor albedo, cos " << c;
        // A real metal reflects exactly its Fresnel reflectance, into the mirror direction.
        SampledSpectrum eta(std::array<Float, 4>{0.2f, 0.92f, 1.1f, 0.14f});
        SampledSpectrum k(std::array<Float, 4>{3.9f, 2.45f, 2.14f, 3.98f});
        ConductorBxDF gold(TrowbridgeReitzDistribution(0, 0), eta, k);
        auto s = gold.Sample_f(wo, 0.5f, {0.3f, 0.7f});
        ASSERT_TRUE(s);
        EXPECT_TRUE(s->specular);
        EXPECT_NEAR(Length(s->wi - Vector3f(-wo.x, -wo.y, wo.z)), 0, 1e-6);
        SampledSpectrum weight = s->f * AbsCosTheta(s->wi) / s->pdf;
        SampledSpectrum F = FrComplex(c, eta, k);
        for (int i = 0; i < 4; ++i) EXPECT_NEAR(weight[i], F[i], 1e-5) << "channel " << i;
        EXPECT_EQ(gold.f(wo, s->wi)[0], 0) << "delta lobe: f() is 0";
        EXPECT_EQ(gold.PDF(wo, s->wi), 0) << "delta lobe: PDF() is 0";
    }
}

TEST(ConductorBxDF, RoughEnergyAtMostOneAndNearlySmoothLossless) {
    for (auto &a : kAlphas)
        for (Float c : kCosThetas) {
            Estimate e = SampledAlbedo(PerfectConductor(a[0], a[1]), Dir(c, 0.4f), 40000, 3, false);
            // Single-scattering microfacets lose energy at high roughness, never gain it.
            EXPECT_LE(e.mean, 1 + 4 * e.stdErr + 1e-4)
                << Describe("rough perfect conductor albedo", a[0], a[1], c) << " = " << e.mean;
            EXPECT_GT(e.mean, 0.2) << Describe("rough perfect conductor albedo", a[0], a[1], c);
        }
    // Just above the smoothness threshold the model is essentially a mirror: albedo ~ 1.
    for (Float c : kCosThetas) {
        Estimate e = SampledAlbedo(PerfectConductor(1.5e-3f, 1.5e-3f), Dir(c, 0.4f), 20000, 5, false);
        EXPECT_NEAR(e.mean, 1, 0.01) << "alpha 1.5e-3, cos " << c;
    }
    // Roughness 1 through pbrt's remapping is alpha 1 (tested above); a real metal is darker.
    SampledSpectrum eta(std::array<Float, 4>{0.2f, 0.92f, 1.1f, 0.14f});
    SampledSpectrum k(std::array<Float, 4>{3.9f, 2.45f, 2.14f, 3.98f});
    ConductorBxDF gold(TrowbridgeReitzDistribution(0.2f, 0.2f), eta, k);
    Estimate eg = SampledAlbedo(gold, Dir(0.7f, 0), 20000, 6, false);
    Estimate ep = SampledAlbedo(PerfectConductor(0.2f, 0.2f), Dir(0.7f, 0), 20000, 6, false);
    EXPECT_LT(eg.mean, ep.mean) << "a real metal absorbs";
}

TEST(ConductorBxDF, Reciprocity) {
    SampledSpectrum eta(std::array<Float, 4>{0.2f, 0.92f, 1.1f, 0.14f});
    SampledSpectrum k(std::array<Float, 4>{3.9f, 2.45f, 2.14f, 3.98f});
    RNG rng(17);
    for (auto &a : kAlphas) {
        ConductorBxDF b(TrowbridgeReitzDistribution(a[0], a[1]), eta, k);
        for (int i = 0; i < 500; ++i) {
            Vector3f wo = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
            Vector3f wi = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
            if (i % 2) wi.z = std::copysign(wi.z, wo.z);  // half of the pairs reflect
            SampledSpectrum f1 = b.f(wo, wi), f2 = b.f(wi, wo);
            for (int c = 0; c < 4; ++c)
                ASSERT_NEAR(f1[c], f2[c], 1e-4f * std::max(f1[c], f2[c]) + 1e-7f)
                    << Describe("conductor", a[0], a[1], wo.z) << " wi " << ToString(wi);
        }
    }
}

TEST(ConductorBxDF, SamplingMatchesPDFChiSquare) {
    for (auto &a : kAlphas)
        for (Float c : kCosThetas) {
            ConductorBxDF b = PerfectConductor(a[0], a[1]);
            Vector3f wo = Dir(c, 0.4f);
            ExpectSampleMatchesEval(b, wo, 2000, 19, 1e-3, Describe("conductor", a[0], a[1], c));
            std::string report;
            double p = ChiSquareTest(
                [&](Float uc, Point2f u) -> std::optional<Vector3f> {
                    auto s = b.Sample_f(wo, uc, u);
                    if (!s) return std::nullopt;
                    return s->wi;
                },
                [&](const Vector3f &wi) { return double(b.PDF(wo, wi)); }, kChi2Samples, 23, &report);
            EXPECT_GT(p, kChi2Alpha) << Describe("conductor", a[0], a[1], c) << ": " << report;
        }
    // Seen from below, the conductor is the mirror image.
    ConductorBxDF b = PerfectConductor(0.3f, 0.3f);
    Vector3f wo = Dir(-0.5f, 0.4f);
    std::string report;
    double p = ChiSquareTest(
        [&](Float uc, Point2f u) -> std::optional<Vector3f> {
            auto s = b.Sample_f(wo, uc, u);
            if (!s) return std::nullopt;
            return s->wi;
        },
        [&](const Vector3f &wi) { return double(b.PDF(wo, wi)); }, kChi2Samples, 29, &report);
    EXPECT_GT(p, kChi2Alpha) << "conductor from below: " << report;
}

// =======================================================================================
// DielectricBxDF

const Float kEtas[] = {1.5f, 0.763f};  // glass, and the scenes' ice-to-air interface
const Float kSignedCos[] = {0.05f, 0.2f, 0.5f, 1.0f, -0.05f, -0.5f, -1.0f};
const Float kSignedCosChi2[] = {0.05f, 0.5f, 1.0f, -0.2f, -1.0f};

TEST(DielectricBxDF, SmoothIsLosslessWithFresnelSplit) {
    for (Float eta : kEtas)
        for (Float c : kSignedCos) {
            DielectricBxDF b(eta, TrowbridgeReitzDistribution(0, 0));
            EXPECT_TRUE(b.IsSpecular());
            Vector3f wo = Dir(c, 1.1f);
            double reflected = 0;
            Estimate e = SampledAlbedo(b, wo, 20000, 31, true, TransportMode::Radiance, &reflected);
            std::ostringstream what;
            what << "smooth dielectric eta " << eta << " cos " << c;
            // Every sample carries weight exactly 1 (reflection R / (R/(R+T)), transmission
            // T / (T/(R+T)) after undoing the eta^2 radiance scaling): R + T = 1.
            EXPECT_NEAR(e.mean, 1, 1e-4) << what.str();
            EXPECT_LT(e.stdErr, 1e-5) << what.str();
            // Importance transport has no eta^2 factor: the same without the compensation.
            Estimate ei = SampledAlbedo(b, wo, 2000, 37, false, TransportMode::Importance);
            EXPECT_NEAR(ei.mean, 1, 1e-4) << what.str() << " (importance)";
            // The reflected fraction is the Fresnel reflectance (binomial noise, 5 sigma).
            Float R = FrDielectric(c, eta);
            EXPECT_NEAR(reflected, R, 5 * std::sqrt(R * (1 - R) / 20000) + 1e-6) << what.str();
            // Radiance transport divides transmitted radiance by etap^2.
            auto st = b.Sample_f(wo, 0.9999f, {0.5f, 0.5f});
            if (R < 1 && st && st->transmission) {
                Float etap = c > 0 ? eta : 1 / eta;
                EXPECT_FLOAT_EQ(st->eta, etap);
                EXPECT_NEAR(st->f[0] * AbsCosTheta(st->wi) / st->pdf, 1 / Sqr(etap), 1e-5) << what.str();
            }
        }
    // Index-matched (eta = 1): straight through with weight 1.
    DielectricBxDF same(1, TrowbridgeReitzDistribution(0.3f, 0.3f));
    EXPECT_TRUE(same.IsSpecular());
    Vector3f wo = Dir(0.3f, 2);
    auto s = same.Sample_f(wo, 0.2f, {0.1f, 0.9f});
    ASSERT_TRUE(s);
    EXPECT_TRUE(s->transmission && s->specular);
    EXPECT_NEAR(Length(s->wi + wo), 0, 1e-6);
    EXPECT_NEAR(s->f[0] * AbsCosTheta(s->wi) / s->pdf, 1, 1e-6);
}

TEST(DielectricBxDF, RoughEnergyAtMostOne) {
    for (Float eta : kEtas)
        for (auto &a : kAlphas)
            for (Float c : kSignedCos) {
                DielectricBxDF b(eta, TrowbridgeReitzDistribution(a[0], a[1]));
                Estimate e = SampledAlbedo(b, Dir(c, 0.8f), 20000, 41, true);
                std::ostringstream what;
                what << Describe("rough dielectric", a[0], a[1], c) << " eta " << eta << " albedo "
                     << e.mean << " +- " << e.stdErr;
                EXPECT_LE(e.mean, 1 + 4 * e.stdErr + 1e-4) << what.str();
                EXPECT_GT(e.mean, 0.3) << what.str();
            }
    // Nearly smooth: nearly lossless.
    for (Float c : kSignedCos) {
        DielectricBxDF b(1.5f, TrowbridgeReitzDistribution(1.5e-3f, 1.5e-3f));
        Estimate e = SampledAlbedo(b, Dir(c, 0.8f), 20000, 43, true);
        EXPECT_NEAR(e.mean, 1, 0.01) << "alpha 1.5e-3 dielectric, cos " << c;
    }
}

TEST(DielectricBxDF, SampleRatioIsSampleFsRatio) {
    // The layered walk's shortcut: the same direction and lobe as Sample_f for the same numbers,
    // f / pdf to rounding, and nothing exactly where Sample_f gives no usable sample.
    RNG rng(77);
    int compared = 0;
    for (Float eta : {1.5f, 1 / 1.5f, 1.f, 2.4f})
        for (Float alpha : {0.f, 0.0316f, 0.1f, 0.5f})
            for (int i = 0; i < 2000; ++i) {
                DielectricBxDF b(eta, TrowbridgeReitzDistribution(alpha, alpha * (i % 2 ? 1 : 0.6f)));
                Vector3f wo = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
                Float uc = rng.UniformFloat();
                Point2f u(rng.UniformFloat(), rng.UniformFloat());
                for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                    std::optional<BSDFSample> s = b.Sample_f(wo, uc, u, mode);
                    std::optional<DielectricBxDF::RatioSample> r = b.SampleRatio(wo, uc, u, mode);
                    bool usable = s && s->f.IsNonZero() && s->pdf > 0 && s->wi.z != 0;
                    ASSERT_EQ(usable, r.has_value()) << "eta " << eta << " alpha " << alpha << " i " << i;
                    if (!usable) continue;
                    EXPECT_EQ(s->wi, r->wi);
                    EXPECT_EQ(s->specular, r->specular);
                    EXPECT_EQ(s->transmission, r->transmission);
                    Float want = s->f[0] / s->pdf;
                    EXPECT_NEAR(r->ratio, want, 2e-5f * want) << "eta " << eta << " alpha " << alpha;
                    ++compared;
                }
            }
    EXPECT_GT(compared, 50000);
}

TEST(DielectricBxDF, Reciprocity) {
    RNG rng(47);
    for (Float eta : kEtas)
        for (auto &a : kAlphas) {
            DielectricBxDF b(eta, TrowbridgeReitzDistribution(a[0], a[1]));
            int transmissive = 0;
            for (int i = 0; i < 1000; ++i) {
                Vector3f wo = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
                Vector3f wi = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
                std::string what = Describe("dielectric", a[0], a[1], wo.z) + " wi " + ToString(wi);
                Float fR = b.f(wo, wi, TransportMode::Radiance)[0];
                Float fRrev = b.f(wi, wo, TransportMode::Radiance)[0];
                Float fIrev = b.f(wi, wo, TransportMode::Importance)[0];
                Float tol = 2e-4f * std::max({fR, fRrev, fIrev}) + 1e-6f;
                // Near total internal reflection (refraction grazing the microfacet) 1 - F
                // has an infinite slope, so float rounding of the half vector shows up as a
                // relative difference: 3% there.
                Vector3f wm = FaceForward(Normalize(wo + wi * (wo.z > 0 ? eta : 1 / eta)), Vector3f(0, 0, 1));
                if (!SameHemisphere(wo, wi) && std::min(AbsDot(wo, wm), AbsDot(wi, wm)) < 0.03f)
                    tol = 0.03f * std::max({fR, fRrev, fIrev}) + 1e-6f;
                if (SameHemisphere(wo, wi)) {
                    ASSERT_NEAR(fR, fRrev, tol) << "reflection: " << what;
                } else {
                    if (fR > 0) ++transmissive;
                    // The adjoint: radiance f(wo, wi) = importance f(wi, wo) ...
                    ASSERT_NEAR(fR, fIrev, tol) << "transmission adjoint: " << what;
                    // ... and f(wi, wo) / eta_o^2 = f(wo, wi) / eta_i^2 with eta_o, eta_i the
                    // indices on wo's and wi's sides: f(wi, wo) = etap^2 f(wo, wi).
                    Float etap = wo.z > 0 ? eta : 1 / eta;
                    ASSERT_NEAR(fRrev, Sqr(etap) * fR, tol * Sqr(etap)) << "transmission eta^2: " << what;
                }
            }
            EXPECT_GT(transmissive, 50) << "transmission pairs should be exercised";
        }
}

TEST(DielectricBxDF, SamplingMatchesPDFChiSquare) {
    for (Float eta : kEtas)
        for (auto &a : kAlphas)
            for (Float c : kSignedCosChi2) {
                DielectricBxDF b(eta, TrowbridgeReitzDistribution(a[0], a[1]));
                Vector3f wo = Dir(c, 0.8f);
                std::ostringstream what;
                what << Describe("dielectric", a[0], a[1], c) << " eta " << eta;
                ExpectSampleMatchesEval(b, wo, 2000, 53, 1e-3, what.str());
                std::string report;
                double p = ChiSquareTest(
                    [&](Float uc, Point2f u) -> std::optional<Vector3f> {
                        auto s = b.Sample_f(wo, uc, u);
                        if (!s) return std::nullopt;
                        return s->wi;
                    },
                    [&](const Vector3f &wi) { return double(b.PDF(wo, wi)); }, kChi2Samples, 59, &report);
                EXPECT_GT(p, kChi2Alpha) << what.str() << ": " << report;
            }
}

// =======================================================================================
// CoatedDiffuseBxDF

struct CoatConfig {
    const char *name;
    Float alpha, eta, reflectance, thickness, albedo, g;
    int maxDepth, nSamples;
    bool lossless;  // reflectance 1, no absorption, walks long enough: albedo exactly 1
};
CoatedDiffuseBxDF MakeCoat(const CoatConfig &c, uint64_t seed = 0, int nSamples = 0) {
    return CoatedDiffuseBxDF(DielectricBxDF(c.eta, TrowbridgeReitzDistribution(c.alpha, c.alpha)),
                             DiffuseBxDF(SampledSpectrum(c.reflectance)), c.thickness,
                             SampledSpectrum(c.albedo), c.g, c.maxDepth,
                             nSamples > 0 ? nSamples : c.nSamples, seed);
}
std::string Describe(const CoatConfig &c, Float cosTheta) {
    std::ostringstream os;
    os << "coateddiffuse[" << c.name << "] cos(theta_o) = " << cosTheta;
    return os.str();
}

const CoatConfig kCoats[] = {
    // pbrt-v4's defaults (reflectance 0.5, thickness 0.01, albedo 0, g 0, maxdepth 10,
    // nsamples 1) with a smooth, a moderately rough and a very rough coat.
    {"default smooth", 0, 1.5f, 0.5f, 0.01f, 0, 0, 10, 1, false},
    {"default alpha 0.3", 0.3f, 1.5f, 0.5f, 0.01f, 0, 0, 10, 1, false},
    {"default alpha 1", 1.0f, 1.5f, 0.5f, 0.01f, 0, 0, 10, 1, false},
    // Lossless: white base under a negligibly thin clear layer ...
    {"white thin smooth", 0, 1.5f, 1, 1e-6f, 0, 0, 200, 1, true},
    // ... and under a thick purely scattering (albedo 1) forward-scattering medium.
    {"white scattering smooth", 0, 1.5f, 1, 0.5f, 1, 0.6f, 500, 1, true},
    // Absorbing-and-scattering medium under a rough coat.
    {"medium alpha 0.3", 0.3f, 1.5f, 0.8f, 0.3f, 0.7f, -0.3f, 50, 1, false},
};

// Energy: the Sample_f white furnace, and the same albedo from f() (integral of f cos over
// cosine-distributed directions). With a smooth coat f() lacks the specular reflection R,
// so for a lossless layer its integral is exactly 1 - R(theta_o).
TEST(CoatedDiffuseBxDF, EnergyWhiteFurnace) {
    for (const CoatConfig &cfg : kCoats)
        for (Float c : kCosThetas) {
            CoatedDiffuseBxDF b = MakeCoat(cfg);
            Vector3f wo = Dir(c, 0.3f);
            std::string what = Describe(cfg, c);
            Estimate es = SampledAlbedo(b, wo, 20000, 61, false);
            EXPECT_LE(es.mean, 1 + 4 * es.stdErr + 1e-3) << what << " sampled albedo " << es.mean;
            if (cfg.lossless) {
                EXPECT_NEAR(es.mean, 1, 4 * es.stdErr + 2e-3)
                    << what << " lossless sampled albedo " << es.mean << " +- " << es.stdErr;
            }

            RNG rng(67);
            std::vector<double> fv(6000);
            for (double &x : fv) {
                Vector3f wi = SampleCosineHemisphere({rng.UniformFloat(), rng.UniformFloat()});
                x = b.f(wo, wi)[0] * Pi;  // f cos / (cos / pi)
            }
            Estimate ef = MeanOf(fv);
            Float Rspec = cfg.alpha == 0 ? FrDielectric(c, cfg.eta) : 0;
            EXPECT_LE(ef.mean + Rspec, 1 + 4 * ef.stdErr + 1e-3) << what << " f() albedo " << ef.mean;
            if (cfg.lossless) {
                EXPECT_NEAR(ef.mean, 1 - Rspec, 4 * ef.stdErr + 2e-3)
                    << what << " lossless f() albedo " << ef.mean << " +- " << ef.stdErr;
            }
            // Both are unbiased estimates of the same albedo.
            Float sampledNonSpecular = Float(es.mean) - Rspec;
            EXPECT_NEAR(ef.mean, sampledNonSpecular, 4 * std::hypot(ef.stdErr, es.stdErr) + 2e-3)
                << what << ": f() albedo " << ef.mean << " vs Sample_f albedo (non-specular) "
                << sampledNonSpecular;
        }
}

// Sampling agrees with evaluation per direction bin: E[f cos / pdf ; wi in bin] from Sample_f
// equals the integral of f() cos over the bin. (Sample_f's true density has no closed form
// and PDF() is an approximation used only for MIS, so the chi-square is over these
// weighted histograms: sum of (a - b)^2 / (var a + var b) over bins ~ chi-square(bins).)
// f() is evaluated with 4 walks per call: single walks are heavy-tailed (Russian roulette
// scales survivors up to weight 1), which makes 300-point bin means too skewed for the
// normal approximation (measured: 1 false rejection in 180 seeded runs, none with 4).
TEST(CoatedDiffuseBxDF, SamplingAgreesWithEvaluationPerBin) {
    const int nTheta = 4, nPhi = 6, nBins = nTheta * nPhi;
    for (const CoatConfig &cfg : kCoats)
        for (Float c : {0.05f, 0.5f, 1.0f}) {
            CoatedDiffuseBxDF b = MakeCoat(cfg);
            CoatedDiffuseBxDF bEval = MakeCoat(cfg, 0, /*nSamples=*/4);
            Vector3f wo = Dir(c, 0.3f);
            auto binOf = [&](const Vector3f &w) {
                int it = std::min(nTheta - 1, int((1 - w.z) * nTheta));  // bins of equal solid angle
                Float phi = std::atan2(w.y, w.x);
                if (phi < 0) phi += 2 * Pi;
                int ip = std::min(nPhi - 1, int(phi / (2 * Pi) * nPhi));
                return it * nPhi + ip;
            };
            // Weighted histogram of Sample_f (specular samples excluded: f() has no delta).
            const int nS = 40000;
            std::vector<double> sw(nBins, 0), sw2(nBins, 0);
            RNG rng(71);
            for (int i = 0; i < nS; ++i) {
                Float uc = rng.UniformFloat();
                Point2f u(rng.UniformFloat(), rng.UniformFloat());
                auto s = b.Sample_f(wo, uc, u);
                if (!s || s->specular) continue;
                ASSERT_GT(s->wi.z, 0) << "opaque base: no transmission";
                double w = s->f[0] * AbsCosTheta(s->wi) / s->pdf;
                int k = binOf(s->wi);
                sw[k] += w;
                sw2[k] += w * w;
            }
            // Integral of f cos over each bin: uniform points in the bin (solid angle
            // 2 pi / nBins each).
            const int nF = 400;
            double stat = 0;
            int dof = 0;
            std::ostringstream worst;
            double worstZ2 = 0;
            for (int it = 0; it < nTheta; ++it)
                for (int ip = 0; ip < nPhi; ++ip) {
                    std::vector<double> v(nF);
                    for (int j = 0; j < nF; ++j) {
                        Float z = 1 - (it + rng.UniformFloat()) / nTheta;
                        Float phi = (ip + rng.UniformFloat()) / nPhi * 2 * Pi;
                        Vector3f wi = Dir(z, phi);
                        v[j] = bEval.f(wo, wi)[0] * AbsCosTheta(wi) * (2 * kPi / nBins);
                    }
                    Estimate ef = MeanOf(v);
                    int k = it * nPhi + ip;
                    double ms = sw[k] / nS, varS = std::max(0.0, sw2[k] / nS - ms * ms) / nS;
                    double var = varS + Sqr(ef.stdErr);
                    if (var <= 0) continue;
                    double z2 = Sqr(ms - ef.mean) / var;
                    stat += z2;
                    ++dof;
                    if (z2 > worstZ2) {
                        worstZ2 = z2;
                        worst.str("");
                        worst << "bin (" << it << "," << ip << ") sampled " << ms << " vs f() " << ef.mean;
                    }
                }
            double p = GammaQ(dof / 2.0, stat / 2);
            EXPECT_GT(p, kChi2Alpha) << Describe(cfg, c) << ": chi2 = " << stat << " dof = " << dof
                                     << " p = " << p << "; worst " << worst.str();
        }
}

TEST(CoatedDiffuseBxDF, DeferredPDFCompletesAProportionalSample) {
    // A path tracer may take the walk's own density and ask for PDF(wo, wi) only when it needs
    // it (a hit on an emitter): the same directions, the same weight f / pdf up to rounding,
    // and DeferredPDF equal to the pdf the eager sample reports.
    for (const CoatConfig &cfg : kCoats) {
        Vector3f n = Normalize(Vector3f(0.2f, 0.1f, 1));
        CoatedDiffuseBxDF coat = MakeCoat(cfg);
        BSDF bsdf(Normal3f(n.x, n.y, n.z), Vector3f(1, 0, -0.2f), coat);
        Vector3f wo = Normalize(Vector3f(0.3f, -0.4f, 0.8f));
        RNG rng(91);
        int proportional = 0;
        for (int i = 0; i < 1000; ++i) {
            Float uc = rng.UniformFloat();
            Point2f u(rng.UniformFloat(), rng.UniformFloat());
            auto lazy = bsdf.Sample_f(wo, uc, u, /*exactPdf=*/false);
            if (!lazy) continue;
            // The eager sample from the same local direction (the world-to-local rounding
            // may differ between two calls of BSDF::Sample_f when the compiler fuses
            // multiply-adds differently, and the walk hashes its directions).
            auto eager = coat.Sample_f(lazy->woLocal, uc, u);
            ASSERT_TRUE(eager) << Describe(cfg, 0.8f);
            ASSERT_FALSE(eager->pdfIsProportional);
            ASSERT_EQ(eager->wi, lazy->wiLocal);
            ASSERT_EQ(lazy->pdfIsProportional, !lazy->specular);
            if (!lazy->pdfIsProportional) continue;
            ++proportional;
            EXPECT_EQ(bsdf.DeferredPDF(*lazy), eager->pdf);
            for (int c = 0; c < NSpectrumSamples; ++c)
                EXPECT_NEAR(lazy->f[c] / lazy->pdf, eager->f[c] / eager->pdf, 1e-5f * (eager->f[c] / eager->pdf) + 1e-12f);
        }
        EXPECT_GT(proportional, 100) << Describe(cfg, 0.8f);
        // Next-event estimation skips the layer's f where SameSide is false: f is 0 there.
        for (int i = 0; i < 200; ++i) {
            Vector3f wi = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
            if (!bsdf.SameSide(wo, wi)) EXPECT_FALSE(bsdf.f(wo, wi).IsNonZero()) << Describe(cfg, 0.8f);
        }
    }
}

TEST(CoatedDiffuseBxDF, SampleReportsPDFForMISAndStaysOnOneSide) {
    for (const CoatConfig &cfg : kCoats)
        for (Float c : {0.05f, 0.5f, 1.0f, -0.5f}) {
            CoatedDiffuseBxDF b = MakeCoat(cfg);
            Vector3f wo = Dir(c, 0.3f);
            RNG rng(73);
            int nonSpecular = 0;
            for (int i = 0; i < 2000; ++i) {
                Float uc = rng.UniformFloat();
                Point2f u(rng.UniformFloat(), rng.UniformFloat());
                auto s = b.Sample_f(wo, uc, u);
                if (!s) continue;
                ASSERT_TRUE(SameHemisphere(wo, s->wi)) << Describe(cfg, c) << ": two-sided, opaque";
                ASSERT_FALSE(s->transmission);
                if (s->specular) {
                    ASSERT_EQ(cfg.alpha, 0) << "only a smooth coat reflects specularly";
                    continue;
                }
                ++nonSpecular;
                ASSERT_FLOAT_EQ(s->pdf, b.PDF(wo, s->wi)) << Describe(cfg, c);
                ASSERT_GT(s->pdf, 0);
            }
            EXPECT_GT(nonSpecular, 200) << Describe(cfg, c);
            // f and PDF are deterministic per direction pair, and two-sided.
            Vector3f wi = Dir(0.6f, 2.0f);
            if (wo.z < 0) wi = -wi;
            EXPECT_EQ(b.f(wo, wi)[0], b.f(wo, wi)[0]);
            EXPECT_EQ(b.f(wo, wi)[0], b.f(-wo, -wi)[0]) << Describe(cfg, c);
            EXPECT_EQ(b.PDF(wo, wi), b.PDF(-wo, -wi)) << Describe(cfg, c);
            EXPECT_EQ(b.f(wo, -wi)[0], 0) << "nothing is transmitted through the base";
            EXPECT_EQ(b.PDF(wo, -wi), 0);
        }
}

// Reciprocity holds in expectation: average f over independent seeds (each f() call is one
// deterministic estimate) and compare the two orders within 4.5 standard errors.
TEST(CoatedDiffuseBxDF, Reciprocity) {
    const std::pair<Float, Float> pairs[] = {{0.05f, 0.9f}, {0.3f, 0.7f}, {1.0f, 0.2f}, {0.6f, 0.6f}};
    for (const CoatConfig &cfg : kCoats)
        for (auto [co, ci] : pairs) {
            Vector3f wo = Dir(co, 0.3f), wi = Dir(ci, 2.5f);
            std::vector<double> d(200);
            double sum = 0;
            for (int k = 0; k < int(d.size()); ++k) {
                CoatedDiffuseBxDF b = MakeCoat(cfg, /*seed=*/1000 + k, /*nSamples=*/4);
                double a = b.f(wo, wi)[0], r = b.f(wi, wo)[0];
                d[k] = a - r;
                sum += a + r;
            }
            Estimate e = MeanOf(d);
            double mean = sum / (2 * d.size());
            EXPECT_LT(std::abs(e.mean), 4.5 * e.stdErr + 1e-4 * mean)
                << Describe(cfg, co) << " cos(theta_i) = " << ci << ": f(wo,wi) - f(wi,wo) = " << e.mean
                << " +- " << e.stdErr << " (f ~ " << mean << ")";
            EXPECT_GT(mean, 0) << Describe(cfg, co);
        }
}

// =======================================================================================
// DiffuseTransmissionBxDF

// Reflectance and transmittance pairs: pbrt-v4's default (0.25, 0.25), a lossless sheet, a
// spectrally selective filter (different at each of the four wavelengths), reflection only,
// transmission only.
struct DiffTransConfig {
    const char *name;
    std::array<Float, 4> R, T;
};
const DiffTransConfig kDiffTrans[] = {
    {"default", {0.25f, 0.25f, 0.25f, 0.25f}, {0.25f, 0.25f, 0.25f, 0.25f}},
    {"lossless", {0.3f, 0.3f, 0.3f, 0.3f}, {0.7f, 0.7f, 0.7f, 0.7f}},
    {"green filter", {0.08f, 0.1f, 0.06f, 0.05f}, {0.02f, 0.75f, 0.3f, 0.01f}},
    {"reflection only", {0.6f, 0.5f, 0.4f, 0.3f}, {0, 0, 0, 0}},
    {"transmission only", {0, 0, 0, 0}, {0.9f, 0.2f, 0.5f, 0.1f}},
};
DiffuseTransmissionBxDF MakeDiffTrans(const DiffTransConfig &c) {
    return DiffuseTransmissionBxDF(SampledSpectrum(c.R), SampledSpectrum(c.T));
}
std::string Describe(const DiffTransConfig &c, Float cosTheta) {
    std::ostringstream os;
    os << "diffusetransmission[" << c.name << "] cos(theta_o) = " << cosTheta;
    return os.str();
}

TEST(DiffuseTransmissionBxDF, IsLambertianOnEachSide) {
    for (const DiffTransConfig &cfg : kDiffTrans) {
        DiffuseTransmissionBxDF b = MakeDiffTrans(cfg);
        EXPECT_FALSE(b.IsSpecular());
        EXPECT_FALSE(b.IsBlack()) << cfg.name;
        for (Float c : kSignedCos) {
            Vector3f wo = Dir(c, 0.7f);
            for (Float ci : {0.01f, 0.4f, 1.0f})
                for (Float phi : {0.0f, 2.0f, 4.5f}) {
                    Vector3f same = Dir(std::copysign(ci, c), phi), other = Dir(-std::copysign(ci, c), phi);
                    SampledSpectrum fr = b.f(wo, same), ft = b.f(wo, other);
                    for (int i = 0; i < 4; ++i) {
                        EXPECT_FLOAT_EQ(fr[i], cfg.R[i] / Float(kPi)) << Describe(cfg, c);
                        EXPECT_FLOAT_EQ(ft[i], cfg.T[i] / Float(kPi)) << Describe(cfg, c);
                    }
                }
        }
    }
    DiffuseTransmissionBxDF black(SampledSpectrum(0), SampledSpectrum(0));
    EXPECT_TRUE(black.IsBlack());
    EXPECT_FALSE(black.Sample_f(Dir(0.5f, 0), 0.3f, {0.2f, 0.6f}));
    EXPECT_EQ(black.PDF(Dir(0.5f, 0), Dir(-0.5f, 1)), 0);
}

// Energy: each sample's weight f |cos| / pdf is R / P_r or T / P_t, so the white-furnace
// albedo is exactly R + T at every wavelength; f() integrated over the sphere agrees, and
// PDF() integrates to 1 (to 0 when both lobes are black).
TEST(DiffuseTransmissionBxDF, EnergyIsReflectancePlusTransmittance) {
    for (const DiffTransConfig &cfg : kDiffTrans)
        for (Float c : kSignedCos) {
            DiffuseTransmissionBxDF b = MakeDiffTrans(cfg);
            Vector3f wo = Dir(c, 0.3f);
            RNG rng(71);
            const int n = 20000;
            std::vector<double> w[4];
            for (int i = 0; i < n; ++i) {
                Float uc = rng.UniformFloat();
                Point2f u(rng.UniformFloat(), rng.UniformFloat());
                std::optional<BSDFSample> s = b.Sample_f(wo, uc, u);
                for (int k = 0; k < 4; ++k)
                    w[k].push_back(s ? double(s->f[k]) * AbsCosTheta(s->wi) / s->pdf : 0.0);
            }
            for (int k = 0; k < 4; ++k) {
                Estimate e = MeanOf(w[k]);
                double want = cfg.R[k] + cfg.T[k];
                EXPECT_NEAR(e.mean, want, 4 * e.stdErr + 1e-6) << Describe(cfg, c) << " channel " << k;
            }
            auto upper = [&](const std::function<double(const Vector3f &)> &g) {
                // Both hemispheres: the integral over the upper one of g(w) + g(-w).
                return IntegrateHemisphere([&](const Vector3f &v) { return g(v) + g(-v); }, 100, 50);
            };
            double pdfIntegral = upper([&](const Vector3f &wi) { return double(b.PDF(wo, wi)); });
            EXPECT_NEAR(pdfIntegral, 1, 2e-3) << Describe(cfg, c);
            for (int k = 0; k < 4; ++k) {
                double albedo = upper([&](const Vector3f &wi) { return b.f(wo, wi)[k] * AbsCosTheta(wi); });
                EXPECT_NEAR(albedo, cfg.R[k] + cfg.T[k], 2e-3) << Describe(cfg, c) << " channel " << k;
            }
        }
}

// Reciprocity: no refraction, so f(wo, wi) = f(wi, wo) for reflection and transmission
// alike, and importance transport sees the same f.
TEST(DiffuseTransmissionBxDF, Reciprocity) {
    RNG rng(73);
    for (const DiffTransConfig &cfg : kDiffTrans) {
        DiffuseTransmissionBxDF b = MakeDiffTrans(cfg);
        for (int i = 0; i < 400; ++i) {
            Vector3f wo = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
            Vector3f wi = SampleUniformSphere({rng.UniformFloat(), rng.UniformFloat()});
            SampledSpectrum a = b.f(wo, wi), r = b.f(wi, wo), imp = b.f(wi, wo, TransportMode::Importance);
            for (int k = 0; k < 4; ++k) {
                ASSERT_EQ(a[k], r[k]) << cfg.name << " wo " << ToString(wo) << " wi " << ToString(wi);
                ASSERT_EQ(a[k], imp[k]) << cfg.name << " (importance)";
            }
        }
    }
}

// Sampling: Sample_f's f and pdf are f() and PDF() at every wavelength; reflected samples
// stay on wo's side and transmitted ones cross (flagged, with eta 1); the directions follow
// PDF() (chi-square over the whole sphere), also with the lobes restricted by flags.
TEST(DiffuseTransmissionBxDF, SamplingMatchesEvaluationAndPDF) {
    for (const DiffTransConfig &cfg : kDiffTrans)
        for (Float c : kSignedCosChi2) {
            DiffuseTransmissionBxDF b = MakeDiffTrans(cfg);
            Vector3f wo = Dir(c, 0.8f);
            std::string what = Describe(cfg, c);
            RNG rng(79);
            int reflected = 0;
            const int n = 4000;
            for (int i = 0; i < n; ++i) {
                Float uc = rng.UniformFloat();
                Point2f u(rng.UniformFloat(), rng.UniformFloat());
                std::optional<BSDFSample> s = b.Sample_f(wo, uc, u);
                ASSERT_TRUE(s) << what;
                EXPECT_FALSE(s->specular);
                EXPECT_EQ(s->eta, 1);
                EXPECT_EQ(s->transmission, !SameHemisphere(wo, s->wi)) << what;
                reflected += !s->transmission;
                ASSERT_NEAR(s->pdf, b.PDF(wo, s->wi), 1e-6f * s->pdf) << what;
                SampledSpectrum f = b.f(wo, s->wi);
                for (int k = 0; k < 4; ++k) ASSERT_EQ(s->f[k], f[k]) << what << " channel " << k;
            }
            // Reflection is chosen with probability max R / (max R + max T).
            Float maxR = *std::max_element(cfg.R.begin(), cfg.R.end());
            Float maxT = *std::max_element(cfg.T.begin(), cfg.T.end());
            double pr = maxR / (maxR + maxT);
            EXPECT_NEAR(double(reflected) / n, pr, 4 * std::sqrt(pr * (1 - pr) / n) + 1e-9) << what;

            for (BxDFReflTransFlags flags : {BxDFReflTransFlags::All, BxDFReflTransFlags::Reflection,
                                             BxDFReflTransFlags::Transmission}) {
                bool possible = (Allows(flags, BxDFReflTransFlags::Reflection) && maxR > 0) ||
                                (Allows(flags, BxDFReflTransFlags::Transmission) && maxT > 0);
                if (!possible) {
                    EXPECT_FALSE(b.Sample_f(wo, 0.5f, {0.5f, 0.5f}, TransportMode::Radiance, flags)) << what;
                    EXPECT_EQ(b.PDF(wo, Dir(0.5f, 0), TransportMode::Radiance, flags), 0) << what;
                    EXPECT_EQ(b.PDF(wo, Dir(-0.5f, 0), TransportMode::Radiance, flags), 0) << what;
                    continue;
                }
                std::string report;
                double p = ChiSquareTest(
                    [&](Float uc, Point2f u) -> std::optional<Vector3f> {
                        auto s = b.Sample_f(wo, uc, u, TransportMode::Radiance, flags);
                        if (!s) return std::nullopt;
                        return s->wi;
                    },
                    [&](const Vector3f &wi) { return double(b.PDF(wo, wi, TransportMode::Radiance, flags)); },
                    kChi2Samples, 83, &report);
                EXPECT_GT(p, kChi2Alpha) << what << " flags " << int(flags) << ": " << report;
            }
        }
}

// Through the BSDF wrapper (world space, an arbitrary shading frame): the same values, and
// a transmitted sample leaves through the other side of the surface.
TEST(DiffuseTransmissionBxDF, InABSDF) {
    Normal3f n(Normalize(Vector3f(0.3f, -0.5f, 0.8f)));
    BSDF bsdf(n, Vector3f(1, 0, 0), DiffuseTransmissionBxDF(SampledSpectrum(0.2f), SampledSpectrum(0.6f)));
    EXPECT_TRUE(bsdf.IsNonSpecular());
    EXPECT_FALSE(bsdf.HasCostlyF());
    Vector3f wo = Normalize(Vector3f(0.1f, -0.2f, 1));
    RNG rng(89);
    int transmitted = 0;
    for (int i = 0; i < 1000; ++i) {
        Float uc = rng.UniformFloat();
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        std::optional<BSDFSample> s = bsdf.Sample_f(wo, uc, u);
        ASSERT_TRUE(s);
        bool crosses = Dot(s->wi, Vector3f(n)) * Dot(wo, Vector3f(n)) < 0;
        EXPECT_EQ(crosses, s->transmission);
        transmitted += s->transmission;
        EXPECT_FLOAT_EQ(bsdf.f(wo, s->wi)[0], (s->transmission ? 0.6f : 0.2f) / Float(kPi));
        EXPECT_NEAR(bsdf.PDF(wo, s->wi), s->pdf, 1e-5f * s->pdf);
    }
    EXPECT_NEAR(transmitted / 1000.0, 0.75, 0.06);  // P_t = 0.6 / (0.2 + 0.6)
}

}  // namespace
}  // namespace pbrt
