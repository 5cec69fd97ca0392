// Spectral distributions: the four-wavelength SampledSpectrum / SampledWavelengths that
// carry radiance along a path, and the Spectrum representations that scenes describe
// (constant, densely sampled, piecewise linear, blackbody, RGB-derived, named).
//
// Conventions follow pbrt-v4 (Pharr, Jakob, Humphreys, "Physically Based Rendering",
// 4th ed., sections 4.5 and 4.6), so that a scene renders to the same picture:
// wavelengths are in nm over [Lambda_min, Lambda_max]; a tabulated spectrum is zero outside
// its samples after being extended to cover the visible range; "normalized" spectra have a
// luminance of 1 (InnerProduct with ybar equal to CIE_Y_integral).
#pragma once

#include <pbrt/pbrt.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace pbrt {

class RGBColorSpace;
class SampledWavelengths;
struct RGB;
struct XYZ;

// Four wavelengths per path (pbrt-v4's default NSpectrumSamples).
constexpr int NSpectrumSamples = 4;
// The wavelength range every spectral integral runs over (pbrt-v4, book section 4.5).
constexpr Float Lambda_min = 360, Lambda_max = 830;
// Sum of the CIE 1931 ybar table at 1 nm over 360..830 nm (pbrt-v4's constant; our table
// in cie_data.cpp sums to 106.856917, a relative difference of 2e-7).
constexpr Float CIE_Y_integral = 106.856895f;

// Values of a spectrum at the NSpectrumSamples wavelengths of a SampledWavelengths.
class SampledSpectrum {
  public:
    explicit SampledSpectrum(Float c = 0) { values.fill(c); }
    explicit SampledSpectrum(const std::array<Float, NSpectrumSamples> &v) : values(v) {}

    Float operator[](int i) const { return values[i]; }
    Float &operator[](int i) { return values[i]; }

    bool IsNonZero() const {
        bool nonZero = false;  // no early exit: one vector comparison
        for (Float v : values) nonZero |= v != 0;
        return nonZero;
    }
    Float MaxComponentValue() const { return *std::max_element(values.begin(), values.end()); }
    Float MinComponentValue() const { return *std::min_element(values.begin(), values.end()); }
    Float Average() const {
        Float sum = 0;
        for (Float v : values) sum += v;
        return sum / NSpectrumSamples;
    }
    bool HasNaNs() const {
        for (Float v : values)
            if (std::isnan(v)) return true;
        return false;
    }

    // Luminance Y and XYZ estimates of this (radiance) spectrum as pbrt-v4 defines them:
    // the Monte Carlo estimate of the integral with ybar (xbar, ybar, zbar) divided by
    // CIE_Y_integral, so that a spectrum of luminance 1 gives Y = 1. Zero-pdf entries count 0.
    Float y(const SampledWavelengths &lambda) const;
    XYZ ToXYZ(const SampledWavelengths &lambda) const;

    // Element-wise arithmetic with spectra and scalars.
    SampledSpectrum &operator+=(const SampledSpectrum &s) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] += s.values[i];
        return *this;
    }
    SampledSpectrum &operator+=(Float a) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] += a;
        return *this;
    }
    SampledSpectrum operator+(const SampledSpectrum &s) const { SampledSpectrum r = *this; return r += s; }
    SampledSpectrum operator+(Float a) const { SampledSpectrum r = *this; return r += a; }
    SampledSpectrum &operator-=(const SampledSpectrum &s) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] -= s.values[i];
        return *this;
    }
    SampledSpectrum &operator-=(Float a) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] -= a;
        return *this;
    }
    SampledSpectrum operator-(const SampledSpectrum &s) const { SampledSpectrum r = *this; return r -= s; }
    SampledSpectrum operator-(Float a) const { SampledSpectrum r = *this; return r -= a; }
    SampledSpectrum &operator*=(const SampledSpectrum &s) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] *= s.values[i];
        return *this;
    }
    SampledSpectrum &operator*=(Float a) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] *= a;
        return *this;
    }
    SampledSpectrum operator*(const SampledSpectrum &s) const { SampledSpectrum r = *this; return r *= s; }
    SampledSpectrum operator*(Float a) const { SampledSpectrum r = *this; return r *= a; }
    SampledSpectrum &operator/=(const SampledSpectrum &s) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] /= s.values[i];
        return *this;
    }
    SampledSpectrum &operator/=(Float a) {
        for (int i = 0; i < NSpectrumSamples; ++i) values[i] /= a;
        return *this;
    }
    SampledSpectrum operator/(const SampledSpectrum &s) const { SampledSpectrum r = *this; return r /= s; }
    SampledSpectrum operator/(Float a) const { SampledSpectrum r = *this; return r /= a; }

    SampledSpectrum operator-() const {
        SampledSpectrum r;
        for (int i = 0; i < NSpectrumSamples; ++i) r.values[i] = -values[i];
        return r;
    }
    bool operator==(const SampledSpectrum &s) const { return values == s.values; }
    bool operator!=(const SampledSpectrum &s) const { return values != s.values; }

  private:
    std::array<Float, NSpectrumSamples> values;
};

inline SampledSpectrum operator+(Float a, const SampledSpectrum &s) { return s + a; }
inline SampledSpectrum operator*(Float a, const SampledSpectrum &s) { return s * a; }
inline SampledSpectrum operator-(Float a, const SampledSpectrum &s) { return SampledSpectrum(a) - s; }
inline SampledSpectrum operator/(Float a, const SampledSpectrum &s) { return SampledSpectrum(a) / s; }

// Element-wise helpers. SafeDiv gives 0 where the denominator is 0.
SampledSpectrum SafeDiv(const SampledSpectrum &a, const SampledSpectrum &b);
SampledSpectrum Sqrt(const SampledSpectrum &s);
SampledSpectrum Exp(const SampledSpectrum &s);
SampledSpectrum Pow(const SampledSpectrum &s, Float e);
SampledSpectrum Clamp(const SampledSpectrum &s, Float low, Float high);
SampledSpectrum ClampZero(const SampledSpectrum &s);
SampledSpectrum Lerp(Float t, const SampledSpectrum &a, const SampledSpectrum &b);

// The wavelengths a path carries and the per-wavelength density the estimator divides by:
// the film averages L_i * cmf(lambda_i) / pdf_i over the four entries (entries with
// pdf_i = 0 contribute 0).
class SampledWavelengths {
  public:
    SampledWavelengths() { lambda.fill(0); pdf.fill(0); }

    Float operator[](int i) const { return lambda[i]; }
    SampledSpectrum PDF() const { return SampledSpectrum(pdf); }

    // pbrt-v4's visible sampling: lambda_i = SampleVisibleWavelengths((u + i/4) mod 1),
    // each with the visible density (see wavelengths.h).
    static SampledWavelengths SampleVisible(Float u);
    // Stratified uniform: lambda_i = lmin + (lmax - lmin) * ((u + i/4) mod 1),
    // pdf_i = 1 / (lmax - lmin). Throws PbrtError unless 0 < lmin < lmax are finite.
    static SampledWavelengths SampleUniform(Float u, Float lmin = Lambda_min, Float lmax = Lambda_max);
    // Wavelengths and per-wavelength densities computed elsewhere (table-driven sampling;
    // design §1: pdf_j = (1/4) sum_k p_k(lambda_j)).
    static SampledWavelengths FromArrays(const Float lambda[NSpectrumSamples],
                                         const Float pdf[NSpectrumSamples]);

    // For wavelength-dependent refraction (design §1): keep ONE of the four wavelengths,
    // index min(floor(4u), 3) for a fresh uniform u, divide its pdf by 4 and zero the other
    // pdfs. Every slot then holds the kept wavelength (so lambda[0] is the one to refract
    // with), while only the kept slot has a nonzero pdf; the spectra a path carries stay
    // aligned slot by slot. The expected film value is unchanged. No-op when already done.
    void TerminateSecondary(Float u);
    bool SecondaryTerminated() const { return terminated; }
    // The slot that survived TerminateSecondary (-1 before it).
    int SurvivingIndex() const { return survivor; }

    bool operator==(const SampledWavelengths &w) const {
        return lambda == w.lambda && pdf == w.pdf && terminated == w.terminated;
    }
    bool operator!=(const SampledWavelengths &w) const { return !(*this == w); }

  private:
    std::array<Float, NSpectrumSamples> lambda, pdf;
    bool terminated = false;
    int survivor = -1;
};

// A spectral distribution: immutable, shared between scene objects through SpectrumHandle.
class Spectrum {
  public:
    virtual ~Spectrum();
    // Value at wavelength lambda (nm).
    virtual Float operator()(Float lambda) const = 0;
    // Values at the four sampled wavelengths.
    virtual SampledSpectrum Sample(const SampledWavelengths &lambda) const;
    // An upper bound (usually the maximum) over all wavelengths.
    virtual Float MaxValue() const = 0;
    virtual std::string ToString() const = 0;
};
using SpectrumHandle = std::shared_ptr<const Spectrum>;

// The values of a few spectra at one set of wavelengths, remembered: a path evaluates its
// emitters' spectra (next-event estimation, emission hits) and its conductors' eta and k at
// the same four wavelengths at every vertex, and a tabulated spectrum costs a search per
// wavelength. The owner must
// Clear() it whenever the wavelengths change. The values are those of Spectrum::Sample.
class SampledSpectrumCache {
  public:
    void Clear() { keys.fill(nullptr); }
    const SampledSpectrum &Get(const Spectrum &s, const SampledWavelengths &lambda) {
        for (int i = 0; i < kSize; ++i)
            if (keys[i] == &s) return values[i];
        int i = next;
        next = (next + 1) % kSize;
        keys[i] = &s;
        values[i] = s.Sample(lambda);
        return values[i];
    }

  private:
    static constexpr int kSize = 8;  // a few lamps and a few metals
    std::array<const Spectrum *, kSize> keys{};
    std::array<SampledSpectrum, kSize> values;
    int next = 0;
};

// c at every wavelength.
class ConstantSpectrum : public Spectrum {
  public:
    explicit ConstantSpectrum(Float c) : c(c) {}
    Float operator()(Float) const override { return c; }
    SampledSpectrum Sample(const SampledWavelengths &) const override { return SampledSpectrum(c); }
    Float MaxValue() const override { return c; }
    std::string ToString() const override;

  private:
    Float c;
};

// One value per nanometre over 360..830 nm, looked up at the nearest nanometre (zero
// outside [359.5, 830.5)), as pbrt-v4 does. pbrt-v4 keeps the CIE matching functions and
// every light's emission in this form, which makes the 1 nm sums of InnerProduct /
// SpectrumToPhotometric the exact integrals of what the film and the lights evaluate (so an
// emitter divided by SpectrumToPhotometric has exactly 1 nit).
class DenselySampledSpectrum : public Spectrum {
  public:
    static constexpr int kNumSamples = int(Lambda_max - Lambda_min) + 1;
    // Samples s at 360, 361, ..., 830 nm.
    explicit DenselySampledSpectrum(const Spectrum &s);
    // Values at 360, 361, ..., 830 nm (exactly kNumSamples of them).
    explicit DenselySampledSpectrum(std::vector<Float> values);

    Float operator()(Float lambda) const override;
    SampledSpectrum Sample(const SampledWavelengths &lambda) const override;
    Float MaxValue() const override;
    std::string ToString() const override;
    // The value at integer wavelength Lambda_min + i.
    Float At(int i) const { return values[i]; }
    // The sample operator() reads at lambda (the nearest nanometre), or -1 where it is 0.
    static int Index(Float lambda) {
        if (!(lambda >= Lambda_min - 0.5f && lambda < Lambda_max + 0.5f)) return -1;
        // lround without the library call: lambda >= 359.5 here, and lambda + 0.5 is exact
        // in double, so truncation rounds halves away from 0 as lround does.
        int i = int(double(lambda) + 0.5) - int(Lambda_min);
        return std::clamp(i, 0, kNumSamples - 1);
    }

  private:
    std::vector<Float> values;
};

// Values at increasing wavelengths, linear in between, zero outside [lambdas.front(),
// lambdas.back()].
class PiecewiseLinearSpectrum : public Spectrum {
  public:
    PiecewiseLinearSpectrum(std::vector<Float> lambdas, std::vector<Float> values);

    // From (lambda, value) pairs as scene files give them, following pbrt-v4: wavelengths
    // must increase strictly; samples that do not reach 360 (830) nm are extended with the
    // first (last) value to 359 (831) nm; with normalize, the spectrum is scaled to a
    // luminance of 1. Throws PbrtError (prefixed with *loc when given) on an odd or zero
    // count, non-finite values, non-increasing wavelengths, or normalizing a spectrum that
    // is zero over 360..830 nm.
    static std::shared_ptr<const PiecewiseLinearSpectrum> FromInterleaved(
        const std::vector<Float> &interleaved, bool normalize, const FileLoc *loc = nullptr);
    // Reads a .spd file: whitespace-separated "lambda value" pairs, '#' starts a comment.
    // Errors name the file and line.
    static std::shared_ptr<const PiecewiseLinearSpectrum> ReadSPD(const std::string &path,
                                                                 bool normalize = false);

    Float operator()(Float lambda) const override;
    Float MaxValue() const override;
    std::string ToString() const override;
    const std::vector<Float> &Lambdas() const { return lambdas; }
    const std::vector<Float> &Values() const { return values; }

  private:
    std::vector<Float> lambdas, values;
};

// Planck's law: emitted radiance of a blackbody at temperature T (K) and wavelength
// lambda (nm), in W / (m^2 sr m). Zero for T <= 0.
Float Blackbody(Float lambda, Float T);

// Planck's law normalized to a peak value of 1 (the peak is at Wien's wavelength
// b / T), as pbrt-v4 documents for "blackbody" parameters. Throws PbrtError for T <= 0.
class BlackbodySpectrum : public Spectrum {
  public:
    explicit BlackbodySpectrum(Float T);
    Float operator()(Float lambda) const override;
    Float MaxValue() const override { return 1; }
    std::string ToString() const override;
    Float Temperature() const { return T; }

  private:
    Float T, normalizationFactor;
};

// The sigmoid-polynomial spectral shape of Jakob and Hanika 2019: s(x) = 1/2 +
// x / (2 sqrt(1 + x^2)) of a quadratic in the normalized wavelength
// t = (lambda - 595) / 235 (t in [-1, 1] over 360..830 nm). The tables store coefficients
// for t rather than for lambda in nm (as pbrt-v4 does) because the quadratic is then far
// better conditioned in single precision; the spectra are the same.
struct RGBSigmoidPolynomial {
    static constexpr double kCenter = 595, kHalfWidth = 235;
    Float c0 = 0, c1 = 0, c2 = 0;  // x = (c0 t + c1) t + c2

    Float operator()(Float lambda) const { return Sigmoid(Polynomial(lambda)); }
    // The values at the wavelengths of lambda, those of operator() at each: each step over
    // all four wavelengths, with selects instead of branches, so that the compiler makes
    // each one vector instruction.
    SampledSpectrum Sample(const SampledWavelengths &lambda) const {
        std::array<Float, NSpectrumSamples> x, s;
        for (int i = 0; i < NSpectrumSamples; ++i) x[i] = Polynomial(lambda[i]);
        for (int i = 0; i < NSpectrumSamples; ++i) s[i] = SigmoidFinite(x[i]);
        for (int i = 0; i < NSpectrumSamples; ++i) s[i] = Saturated(x[i], s[i]);
        return SampledSpectrum(s);
    }
    Float MaxValue() const;
    static Float Sigmoid(Float x) { return Saturated(x, SigmoidFinite(x)); }

  private:
    // x at lambda.
    Float Polynomial(Float lambda) const {
        Float t = Float((double(lambda) - kCenter) * (1 / kHalfWidth));
        return (c0 * t + c1) * t + c2;
    }
    // 1/2 + x / (2 sqrt(1 + x^2)) for |x| up to 1e15 (beyond, x * x could overflow).
    static Float SigmoidFinite(Float x) {
        Float xc = x < -1e15f ? -1e15f : (x > 1e15f ? 1e15f : x);
        return 0.5f + xc / (2 * std::sqrt(1 + xc * xc));
    }
    // Beyond 1e15 the sigmoid is within 1e-30 of its limit: exactly 0 or 1 there.
    static Float Saturated(Float x, Float s) {
        Float limit = x > 0 ? 1.f : 0.f;
        return std::abs(x) > 1e15f ? limit : s;
    }
};

// A reflectance in [0, 1] from an RGB in [0, 1]^3 of the colour space. Throws PbrtError for
// components outside [0, 1] or NaN.
class RGBAlbedoSpectrum : public Spectrum {
  public:
    RGBAlbedoSpectrum(const RGBColorSpace &cs, RGB rgb);
    Float operator()(Float lambda) const override { return rsp(lambda); }
    // The four values without a virtual call each (the same numbers).
    SampledSpectrum Sample(const SampledWavelengths &lambda) const override;
    Float MaxValue() const override { return rsp.MaxValue(); }
    std::string ToString() const override;

  private:
    RGBSigmoidPolynomial rsp;
};

// Any non-negative RGB: scale * s(lambda) with scale = 2 max(r, g, b) and s the albedo
// spectrum of rgb / scale (pbrt-v4's construction). Throws PbrtError for negative/NaN.
class RGBUnboundedSpectrum : public Spectrum {
  public:
    RGBUnboundedSpectrum(const RGBColorSpace &cs, RGB rgb);
    Float operator()(Float lambda) const override { return scale * rsp(lambda); }
    SampledSpectrum Sample(const SampledWavelengths &lambda) const override;
    Float MaxValue() const override { return scale * rsp.MaxValue(); }
    std::string ToString() const override;

  private:
    Float scale = 0;
    RGBSigmoidPolynomial rsp;
};

// An RGB emission: the unbounded spectrum of rgb times the colour space's (normalized)
// illuminant, so that rgb (1, 1, 1) is the colour space's white.
class RGBIlluminantSpectrum : public Spectrum {
  public:
    RGBIlluminantSpectrum(const RGBColorSpace &cs, RGB rgb);
    Float operator()(Float lambda) const override {
        return scale * rsp(lambda) * (*illuminant)(lambda);
    }
    SampledSpectrum Sample(const SampledWavelengths &lambda) const override;
    Float MaxValue() const override { return scale * rsp.MaxValue() * illuminant->MaxValue(); }
    std::string ToString() const override;
    // The colour space's illuminant (what SpectrumToPhotometric measures).
    const Spectrum &Illuminant() const { return *illuminant; }

  private:
    Float scale = 0;
    RGBSigmoidPolynomial rsp;
    SpectrumHandle illuminant;
};

// The CIE 1931 colour matching functions xbar, ybar, zbar (cie_data.cpp).
namespace Spectra {
const DenselySampledSpectrum &X();
const DenselySampledSpectrum &Y();
const DenselySampledSpectrum &Z();
}  // namespace Spectra

// Named spectra as pbrt-v4 documents them for "spectrum" parameters; nullptr if unknown.
// Illuminants: "stdillum-A", "stdillum-D50", "stdillum-D65", "stdillum-F1".."stdillum-F12",
// "illum-acesD60" (normalized to luminance 1, as pbrt-v4 does).
SpectrumHandle GetNamedSpectrum(const std::string &name);
// All names GetNamedSpectrum knows (for error messages).
std::vector<std::string> NamedSpectrumNames();

// Sum over lambda = 360, 361, ..., 830 nm of f(lambda) g(lambda) (pbrt-v4's InnerProduct).
Float InnerProduct(const Spectrum &f, const Spectrum &g);
// InnerProduct with ybar; for an RGBIlluminantSpectrum, of its illuminant only (pbrt-v4's
// rule, so that an RGB emitter's "scale" does not depend on its colour). Emitters are
// divided by this, then multiplied by their "scale" (design §5).
Float SpectrumToPhotometric(const Spectrum &s);
// (InnerProduct with xbar, ybar, zbar) / CIE_Y_integral.
XYZ SpectrumToXYZ(const Spectrum &s);

}  // namespace pbrt
