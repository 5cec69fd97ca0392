#include <pbrt/util/sampling.h>

#include <algorithm>
#include <cmath>

namespace pbrt {

// --- Linear ----------------------------------------------------------------------------
Float SampleLinear(Float u, Float a, Float b) {
    if (u == 0 && a == 0) return 0;
    // Inverse of the quadratic CDF, written to avoid cancellation when a ~ b.
    Float x = u * (a + b) / (a + std::sqrt(Lerp(u, Sqr(a), Sqr(b))));
    return std::min(x, OneMinusEpsilon);
}
Float LinearPDF(Float x, Float a, Float b) {
    if (x < 0 || x > 1) return 0;
    return 2 * Lerp(x, a, b) / (a + b);
}
Float InvertLinearSample(Float x, Float a, Float b) { return x * (a * (2 - x) + b * x) / (a + b); }

// --- Tent ------------------------------------------------------------------------------
Float SampleTent(Float u, Float r) {
    // Choose a side with probability 1/2, then sample the linear ramp on it.
    if (u < 0.5f) {
        Float up = std::min(u * 2, OneMinusEpsilon);
        return -r + r * SampleLinear(up, 0, 1);
    }
    Float up = std::min((u - 0.5f) * 2, OneMinusEpsilon);
    return r * SampleLinear(up, 1, 0);
}
Float TentPDF(Float x, Float r) {
    if (std::abs(x) >= r) return 0;
    return (r - std::abs(x)) / Sqr(r);
}
Float InvertTentSample(Float x, Float r) {
    if (x <= 0) return InvertLinearSample((x + r) / r, 0, 1) / 2;
    return 0.5f + InvertLinearSample(x / r, 1, 0) / 2;
}

// --- Shifted Gaussian ------------------------------------------------------------------
namespace {
double GaussianDensity(double x, double sigma) {
    return std::exp(-x * x / (2 * sigma * sigma)) / (std::sqrt(2 * 3.14159265358979323846) * sigma);
}
double NormalCDF(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
// Unnormalized CDF of g(x) - g(r) on [-r, x].
double ShiftedGaussianCDF(double x, double sigma, double r) {
    return NormalCDF(x / sigma) - NormalCDF(-r / sigma) - GaussianDensity(r, sigma) * (x + r);
}
}  // namespace

Float ShiftedGaussian(Float x, Float sigma, Float r) {
    if (std::abs(x) >= r) return 0;
    return Float(std::max(0.0, GaussianDensity(x, sigma) - GaussianDensity(r, sigma)));
}
Float ShiftedGaussianIntegral(Float sigma, Float r) { return Float(ShiftedGaussianCDF(r, sigma, r)); }

Float ShiftedGaussianPDF(Float x, Float sigma, Float r) {
    return ShiftedGaussian(x, sigma, r) / ShiftedGaussianIntegral(sigma, r);
}

Float SampleShiftedGaussian(Float u, Float sigma, Float r) {
    // Solve CDF(x) = u * total by Newton's method, kept inside a shrinking bracket
    // (bisection whenever a Newton step leaves it).
    double target = double(u) * ShiftedGaussianCDF(r, sigma, r);
    double gr = GaussianDensity(r, sigma);
    double lo = -r, hi = r, x = 0;
    for (int iter = 0; iter < 60; ++iter) {
        double f = ShiftedGaussianCDF(x, sigma, r) - target;
        if (f > 0) hi = x; else lo = x;
        if (std::abs(f) < 1e-12 || hi - lo < 1e-9 * r) break;
        double fp = GaussianDensity(x, sigma) - gr;
        double xn = fp > 0 ? x - f / fp : lo - 1;
        x = (xn > lo && xn < hi) ? xn : 0.5 * (lo + hi);
    }
    return Clamp(Float(x), -r, r);
}

Float InvertShiftedGaussianSample(Float x, Float sigma, Float r) {
    return Float(ShiftedGaussianCDF(Clamp(x, -r, r), sigma, r) / ShiftedGaussianCDF(r, sigma, r));
}

// --- Concentric disk ---------------------------------------------------------------------
Point2f SampleUniformDiskConcentric(Point2f u) {
    Point2f uo(2 * u.x - 1, 2 * u.y - 1);
    if (uo.x == 0 && uo.y == 0) return {0, 0};
    Float r, theta;
    if (std::abs(uo.x) > std::abs(uo.y)) {
        r = uo.x;
        theta = PiOver4 * (uo.y / uo.x);
    } else {
        r = uo.y;
        theta = PiOver2 - PiOver4 * (uo.x / uo.y);
    }
    return {r * std::cos(theta), r * std::sin(theta)};
}

Point2f InvertUniformDiskConcentricSample(Point2f p) {
    Float r = std::sqrt(Sqr(p.x) + Sqr(p.y));
    if (r == 0) return {0.5f, 0.5f};
    Point2f uo;
    if (std::abs(p.x) >= std::abs(p.y)) {
        // Wedge around the x axis: theta = pi/4 * uo.y / uo.x and tan(theta) = y / x.
        uo.x = p.x >= 0 ? r : -r;
        uo.y = uo.x * std::atan(p.y / p.x) / PiOver4;
    } else {
        // Wedge around the y axis: pi/2 - theta = pi/4 * uo.x / uo.y, tan of it = x / y.
        uo.y = p.y >= 0 ? r : -r;
        uo.x = uo.y * std::atan(p.x / p.y) / PiOver4;
    }
    return {Clamp((uo.x + 1) / 2, 0, OneMinusEpsilon), Clamp((uo.y + 1) / 2, 0, OneMinusEpsilon)};
}

// --- Cosine hemisphere (Malley's method) ------------------------------------------------
Vector3f SampleCosineHemisphere(Point2f u) {
    Point2f d = SampleUniformDiskConcentric(u);
    Float z = SafeSqrt(1 - Sqr(d.x) - Sqr(d.y));
    return {d.x, d.y, z};
}
Point2f InvertCosineHemisphereSample(const Vector3f &w) {
    return InvertUniformDiskConcentricSample({w.x, w.y});
}

// --- Uniform sphere ----------------------------------------------------------------------
Vector3f SampleUniformSphere(Point2f u) {
    Float z = 1 - 2 * u.x;
    Float r = SafeSqrt(1 - Sqr(z));
    Float phi = 2 * Pi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
Point2f InvertUniformSphereSample(const Vector3f &w) {
    Float phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2 * Pi;
    return {Clamp((1 - w.z) / 2, 0, OneMinusEpsilon), Clamp(phi / (2 * Pi), 0, OneMinusEpsilon)};
}

// --- Uniform cone ------------------------------------------------------------------------
Vector3f SampleUniformCone(Point2f u, Float cosThetaMax) {
    Float cosTheta = (1 - u.x) + u.x * cosThetaMax;
    Float sinTheta = SafeSqrt(1 - Sqr(cosTheta));
    Float phi = u.y * 2 * Pi;
    return SphericalDirection(sinTheta, cosTheta, phi);
}
Point2f InvertUniformConeSample(const Vector3f &w, Float cosThetaMax) {
    Float phi = std::atan2(w.y, w.x);
    if (phi < 0) phi += 2 * Pi;
    Float u0 = (1 - w.z) / (1 - cosThetaMax);
    return {Clamp(u0, 0, OneMinusEpsilon), Clamp(phi / (2 * Pi), 0, OneMinusEpsilon)};
}

// --- Uniform triangle --------------------------------------------------------------------
std::array<Float, 3> SampleUniformTriangle(Point2f u) {
    Float su0 = std::sqrt(u.x);
    Float b0 = 1 - su0, b1 = u.y * su0;
    return {b0, b1, 1 - b0 - b1};
}
Point2f InvertUniformTriangleSample(const std::array<Float, 3> &b) {
    Float su0 = 1 - b[0];
    if (su0 <= 0) return {0, 0};
    return {Clamp(Sqr(su0), 0, OneMinusEpsilon), Clamp(b[1] / su0, 0, OneMinusEpsilon)};
}

// --- Discrete ------------------------------------------------------------------------------
DiscreteDistribution::DiscreteDistribution(const std::vector<Float> &weights) {
    size_t n = weights.size();
    pmf.resize(n);
    cdf.assign(n + 1, 0.0);
    double total = 0;
    for (size_t i = 0; i < n; ++i) total += std::max<Float>(0, weights[i]);
    for (size_t i = 0; i < n; ++i) {
        double p = total > 0 ? std::max<Float>(0, weights[i]) / total : 1.0 / n;
        pmf[i] = Float(p);
        cdf[i + 1] = cdf[i] + p;
    }
    if (n > 0) cdf[n] = 1;
}

int DiscreteDistribution::Sample(Float u, Float *pmfOut, Float *uRemapped) const {
    // First index with cdf[i + 1] > u (items with zero probability are never chosen).
    int n = int(pmf.size());
    int i = int(std::upper_bound(cdf.begin(), cdf.end(), double(u)) - cdf.begin()) - 1;
    i = Clamp(i, 0, n - 1);
    while (i > 0 && pmf[i] == 0) --i;
    if (pmfOut) *pmfOut = pmf[i];
    if (uRemapped) {
        double w = cdf[i + 1] - cdf[i];
        *uRemapped = w > 0 ? Clamp(Float((u - cdf[i]) / w), 0, OneMinusEpsilon) : 0;
    }
    return i;
}

// --- Piecewise constant --------------------------------------------------------------------
PiecewiseConstant1D::PiecewiseConstant1D(const std::vector<Float> &f, Float min, Float max)
    : func(f), min(min), max(max) {
    size_t n = func.size();
    for (Float &v : func) v = std::abs(v);
    cdf.assign(n + 1, 0.0);
    for (size_t i = 0; i < n; ++i) cdf[i + 1] = cdf[i] + double(func[i]) * (max - min) / n;
    funcInt = Float(cdf[n]);
    for (size_t i = 1; i <= n; ++i) cdf[i] = funcInt == 0 ? double(i) / n : cdf[i] / cdf[n];
}

Float PiecewiseConstant1D::Sample(Float u, Float *pdf, int *offset) const {
    int n = int(func.size());
    int o = int(std::upper_bound(cdf.begin(), cdf.end(), double(u)) - cdf.begin()) - 1;
    o = Clamp(o, 0, n - 1);
    if (offset) *offset = o;
    double w = cdf[o + 1] - cdf[o];
    double du = w > 0 ? (u - cdf[o]) / w : 0;
    if (pdf) *pdf = funcInt > 0 ? func[o] / funcInt : 1 / (max - min);
    return Float(min + (o + du) / n * (max - min));
}

Float PiecewiseConstant1D::PDF(Float x) const {
    if (x < min || x > max) return 0;
    int n = int(func.size());
    int o = Clamp(int((x - min) / (max - min) * n), 0, n - 1);
    return funcInt > 0 ? func[o] / funcInt : 1 / (max - min);
}

Float PiecewiseConstant1D::Invert(Float x) const {
    int n = int(func.size());
    double t = Clamp(double(x - min) / (max - min), 0.0, 1.0) * n;
    int o = Clamp(int(t), 0, n - 1);
    return Float(cdf[o] + (t - o) * (cdf[o + 1] - cdf[o]));
}

}  // namespace pbrt
