// Sampling routines, each a triple: Sample*(u) maps uniform numbers in [0,1)^n to the
// distribution, *PDF evaluates its density (with respect to the measure named in the
// comment), and Invert*Sample maps a point back to the u that produces it.
// The mappings are the standard published ones (see the pbrt book, 4th edition, ch. A.5).
#pragma once

#include <pbrt/util/vecmath.h>

#include <array>
#include <vector>

namespace pbrt {

// --- MIS -----------------------------------------------------------------------------
// Veach's power heuristic with beta = 2.
inline Float PowerHeuristic(int nf, Float fPdf, int ng, Float gPdf) {
    Float f = nf * fPdf, g = ng * gPdf;
    if (std::isinf(Sqr(f))) return 1;
    if (f == 0 && g == 0) return 0;
    return Sqr(f) / (Sqr(f) + Sqr(g));
}

// --- Linear on [0,1] with density proportional to (1-x) a + x b (a, b >= 0) ----------
Float SampleLinear(Float u, Float a, Float b);
Float LinearPDF(Float x, Float a, Float b);
Float InvertLinearSample(Float x, Float a, Float b);

// --- Tent on [-r, r]: density (r - |x|) / r^2 ------------------------------------------
Float SampleTent(Float u, Float r);
Float TentPDF(Float x, Float r);
Float InvertTentSample(Float x, Float r);

// --- Shifted, truncated Gaussian on [-r, r] (pbrt's Gaussian filter profile):
// density proportional to max(0, g(x) - g(r)), g the N(0, sigma^2) density. -----------
Float SampleShiftedGaussian(Float u, Float sigma, Float r);
Float ShiftedGaussianPDF(Float x, Float sigma, Float r);
Float InvertShiftedGaussianSample(Float x, Float sigma, Float r);
// The unnormalized profile g(x) - g(r) (clamped at 0) and its integral over [-r, r].
Float ShiftedGaussian(Float x, Float sigma, Float r);
Float ShiftedGaussianIntegral(Float sigma, Float r);

// --- Unit disk, Shirley-Chiu concentric mapping: density 1/pi per unit area -------------
Point2f SampleUniformDiskConcentric(Point2f u);
inline Float UniformDiskPDF() { return InvPi; }
Point2f InvertUniformDiskConcentricSample(Point2f p);

// --- Cosine-weighted hemisphere around +z: density cos(theta)/pi per steradian --------
Vector3f SampleCosineHemisphere(Point2f u);
inline Float CosineHemispherePDF(Float cosTheta) { return cosTheta * InvPi; }
Point2f InvertCosineHemisphereSample(const Vector3f &w);

// --- Uniform sphere: density 1/(4 pi) per steradian -----------------------------------
Vector3f SampleUniformSphere(Point2f u);
inline Float UniformSpherePDF() { return Inv4Pi; }
Point2f InvertUniformSphereSample(const Vector3f &w);

// --- Uniform cone around +z with half-angle acos(cosThetaMax) ---------------------------
Vector3f SampleUniformCone(Point2f u, Float cosThetaMax);
inline Float UniformConePDF(Float cosThetaMax) { return 1 / (2 * Pi * (1 - cosThetaMax)); }
Point2f InvertUniformConeSample(const Vector3f &w, Float cosThetaMax);

// --- Uniform triangle: barycentrics (b0, b1, b2), density 1/area per unit area --------
std::array<Float, 3> SampleUniformTriangle(Point2f u);
Point2f InvertUniformTriangleSample(const std::array<Float, 3> &b);

// --- Discrete distribution over n items with probabilities proportional to weights ----
class DiscreteDistribution {
  public:
    DiscreteDistribution() = default;
    // Weights must be finite and >= 0; if they all are 0 the distribution is uniform.
    explicit DiscreteDistribution(const std::vector<Float> &weights);
    size_t size() const { return pmf.size(); }
    // Returns the index; *pmfOut its probability; *uRemapped a fresh uniform number.
    int Sample(Float u, Float *pmfOut = nullptr, Float *uRemapped = nullptr) const;
    Float PMF(int i) const { return pmf[i]; }
    // The middle of the u-interval that selects item i.
    Float Invert(int i) const { return Float(0.5 * (cdf[i] + cdf[i + 1])); }

  private:
    std::vector<Float> pmf;
    std::vector<double> cdf;  // n + 1 entries, cdf[0] = 0, cdf[n] = 1
};

// --- Piecewise-constant density on [min, max] from n function values ------------------
class PiecewiseConstant1D {
  public:
    PiecewiseConstant1D() = default;
    // f: non-negative values on n equal bins over [min, max]. All-zero f gives uniform.
    PiecewiseConstant1D(const std::vector<Float> &f, Float min, Float max);
    Float Sample(Float u, Float *pdf = nullptr, int *offset = nullptr) const;
    Float PDF(Float x) const;
    Float Invert(Float x) const;
    Float Integral() const { return funcInt; }
    size_t size() const { return func.size(); }

  private:
    std::vector<Float> func;
    std::vector<double> cdf;
    Float min = 0, max = 1, funcInt = 0;
};

}  // namespace pbrt
