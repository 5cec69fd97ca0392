// Sampling routines as sample / pdf / invert triples: every sample maps back to its u
// (round trip), its pdf integrates to 1 over the domain, and sample histograms follow pdf.
#include <pbrt/util/sampling.h>

#include <pbrt/util/rng.h>

#include <gtest/gtest.h>

#include <functional>

using namespace pbrt;

namespace {

// Midpoint-rule integral of f over [a, b].
double Integrate1D(const std::function<double(double)> &f, double a, double b, int n = 200000) {
    double h = (b - a) / n, s = 0;
    for (int i = 0; i < n; ++i) s += f(a + (i + 0.5) * h);
    return s * h;
}

// Integral over the unit sphere of a function of direction, by (theta, phi) quadrature.
double IntegrateSphere(const std::function<double(const Vector3f &)> &f, int n = 600) {
    double s = 0;
    for (int i = 0; i < n; ++i) {
        double theta = Pi * (i + 0.5) / n;
        for (int j = 0; j < 2 * n; ++j) {
            double phi = 2 * Pi * (j + 0.5) / (2 * n);
            Vector3f w = SphericalDirection(std::sin(theta), std::cos(theta), phi);
            s += f(w) * std::sin(theta);
        }
    }
    return s * (Pi / n) * (2 * Pi / (2 * n));
}

// Checks u -> sample -> invert -> u on a grid of 2D u values.
template <typename Sample, typename Invert>
void Check2DRoundTrip(Sample sample, Invert invert, const char *what, float tol = 2e-4f) {
    RNG rng(7);
    for (int i = 0; i < 2000; ++i) {
        Point2f u(rng.UniformFloat(), rng.UniformFloat());
        Point2f back = invert(sample(u));
        EXPECT_NEAR(back.x, u.x, tol) << what << " u=(" << u.x << "," << u.y << ")";
        EXPECT_NEAR(back.y, u.y, tol) << what << " u=(" << u.x << "," << u.y << ")";
    }
}

}  // namespace

TEST(Sampling, LinearTriple) {
    for (auto ab : {std::pair<Float, Float>{0, 1}, {1, 0}, {0.3f, 2.f}, {1, 1}}) {
        const Float a = ab.first, b = ab.second;  // (clang 14 cannot capture a structured binding)
        EXPECT_NEAR(Integrate1D([&](double x) { return LinearPDF(Float(x), a, b); }, 0, 1), 1, 1e-4);
        for (Float u = 0.01f; u < 1; u += 0.0437f) {
            Float x = SampleLinear(u, a, b);
            EXPECT_GE(x, 0);
            EXPECT_LT(x, 1);
            EXPECT_NEAR(InvertLinearSample(x, a, b), u, 1e-5) << "a=" << a << " b=" << b;
        }
    }
}

TEST(Sampling, TentTriple) {
    for (Float r : {0.5f, 1.f, 2.f}) {
        EXPECT_NEAR(Integrate1D([&](double x) { return TentPDF(Float(x), r); }, -r, r), 1, 1e-4);
        for (Float u = 0.005f; u < 1; u += 0.0311f) {
            Float x = SampleTent(u, r);
            EXPECT_LE(std::abs(x), r);
            EXPECT_NEAR(InvertTentSample(x, r), u, 2e-5) << "r=" << r;
        }
    }
}

TEST(Sampling, ShiftedGaussianTriple) {
    Float sigma = 0.5f, r = 1.5f;
    EXPECT_NEAR(Integrate1D([&](double x) { return ShiftedGaussianPDF(Float(x), sigma, r); }, -r, r), 1, 1e-4);
    for (Float u = 0.005f; u < 1; u += 0.0311f) {
        Float x = SampleShiftedGaussian(u, sigma, r);
        EXPECT_LE(std::abs(x), r);
        EXPECT_NEAR(InvertShiftedGaussianSample(x, sigma, r), u, 2e-5);
    }
    // Histogram of samples against the pdf (20 bins, 20000 stratified samples).
    const int n = 20000, bins = 20;
    std::vector<int> h(bins, 0);
    for (int i = 0; i < n; ++i) {
        Float x = SampleShiftedGaussian((i + 0.5f) / n, sigma, r);
        h[std::min(bins - 1, int((x + r) / (2 * r) * bins))]++;
    }
    for (int b = 0; b < bins; ++b) {
        double lo = -r + 2 * r * b / bins, hi = lo + 2 * r / bins;
        double expect = n * Integrate1D([&](double x) { return ShiftedGaussianPDF(Float(x), sigma, r); }, lo, hi, 2000);
        EXPECT_NEAR(h[b], expect, 2.0 + 0.01 * expect) << "bin " << b;
    }
}

TEST(Sampling, ConcentricDiskTriple) {
    Check2DRoundTrip(SampleUniformDiskConcentric, InvertUniformDiskConcentricSample, "disk");
    // Uniform density 1/pi: the fraction of samples within radius 0.5 is 1/4.
    RNG rng(3);
    int inside = 0, n = 100000;
    for (int i = 0; i < n; ++i) {
        Point2f p = SampleUniformDiskConcentric({rng.UniformFloat(), rng.UniformFloat()});
        ASSERT_LE(p.x * p.x + p.y * p.y, 1.0001f);
        inside += (p.x * p.x + p.y * p.y < 0.25f);
    }
    double sigma = std::sqrt(0.25 * 0.75 / n);
    EXPECT_NEAR(double(inside) / n, 0.25, 5 * sigma);
}

TEST(Sampling, CosineHemisphereTriple) {
    Check2DRoundTrip(SampleCosineHemisphere, InvertCosineHemisphereSample, "cosine hemisphere");
    double total = IntegrateSphere([](const Vector3f &w) { return w.z > 0 ? CosineHemispherePDF(w.z) : 0.0; });
    EXPECT_NEAR(total, 1, 1e-3);
    // E[cos theta] under the cosine density is 2/3.
    RNG rng(5);
    double s = 0;
    int n = 100000;
    for (int i = 0; i < n; ++i) s += SampleCosineHemisphere({rng.UniformFloat(), rng.UniformFloat()}).z;
    EXPECT_NEAR(s / n, 2.0 / 3.0, 5 * std::sqrt(1.0 / 18 / n));
}

TEST(Sampling, UniformSphereTriple) {
    Check2DRoundTrip(SampleUniformSphere, InvertUniformSphereSample, "sphere");
    EXPECT_NEAR(IntegrateSphere([](const Vector3f &) { return UniformSpherePDF(); }), 1, 1e-3);
}

TEST(Sampling, UniformConeTriple) {
    for (Float cosMax : {0.2f, 0.9f, 0.999f}) {
        Check2DRoundTrip([&](Point2f u) { return SampleUniformCone(u, cosMax); },
                         [&](const Vector3f &w) { return InvertUniformConeSample(w, cosMax); }, "cone", 2e-3f);
        // Integral over the cap: pdf * 2 pi sin(theta) d theta from 0 to acos(cosMax).
        double total = Integrate1D([&](double th) { return UniformConePDF(cosMax) * 2 * Pi * std::sin(th); },
                                   0, std::acos(double(cosMax)));
        EXPECT_NEAR(total, 1, 1e-3) << "cosThetaMax " << cosMax;
        RNG rng(9);
        for (int i = 0; i < 1000; ++i) {
            Vector3f w = SampleUniformCone({rng.UniformFloat(), rng.UniformFloat()}, cosMax);
            EXPECT_GE(w.z, cosMax - 1e-5f);
            EXPECT_NEAR(Length(w), 1, 1e-5);
        }
    }
}

TEST(Sampling, UniformTriangleTriple) {
    Check2DRoundTrip([](Point2f u) { return SampleUniformTriangle(u); },
                     [](const std::array<Float, 3> &b) { return InvertUniformTriangleSample(b); }, "triangle", 1e-3f);
    // Uniform in area: the mean barycentric coordinates are 1/3 each.
    RNG rng(11);
    double m[3] = {0, 0, 0};
    int n = 100000;
    for (int i = 0; i < n; ++i) {
        auto b = SampleUniformTriangle({rng.UniformFloat(), rng.UniformFloat()});
        EXPECT_NEAR(b[0] + b[1] + b[2], 1, 1e-5);
        for (int k = 0; k < 3; ++k) m[k] += b[k];
    }
    // Var of a barycentric coordinate is 1/18.
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(m[k] / n, 1.0 / 3, 5 * std::sqrt(1.0 / 18 / n));
}

TEST(Sampling, DiscreteDistribution) {
    DiscreteDistribution d({1, 0, 3, 0});
    EXPECT_FLOAT_EQ(d.PMF(0), 0.25f);
    EXPECT_FLOAT_EQ(d.PMF(1), 0.f);
    EXPECT_FLOAT_EQ(d.PMF(2), 0.75f);
    int counts[4] = {0, 0, 0, 0};
    for (int i = 0; i < 1000; ++i) {
        Float pmf, ur;
        int k = d.Sample((i + 0.5f) / 1000, &pmf, &ur);
        counts[k]++;
        EXPECT_EQ(pmf, d.PMF(k));
        EXPECT_GE(ur, 0);
        EXPECT_LT(ur, 1);
    }
    EXPECT_EQ(counts[0], 250);
    EXPECT_EQ(counts[2], 750);
    EXPECT_EQ(counts[1] + counts[3], 0) << "zero-weight items must never be chosen";
    for (int k : {0, 2}) EXPECT_EQ(d.Sample(d.Invert(k)), k);
    // All-zero weights fall back to uniform.
    DiscreteDistribution z({0, 0});
    EXPECT_FLOAT_EQ(z.PMF(1), 0.5f);
}

TEST(Sampling, PiecewiseConstant1DTriple) {
    PiecewiseConstant1D d({1, 3, 0, 4}, 2, 6);
    EXPECT_NEAR(d.Integral(), 8, 1e-5);
    EXPECT_NEAR(Integrate1D([&](double x) { return d.PDF(Float(x)); }, 2, 6), 1, 1e-4);
    for (Float u = 0.01f; u < 1; u += 0.0173f) {
        Float pdf;
        Float x = d.Sample(u, &pdf);
        EXPECT_GT(pdf, 0) << "samples must avoid the zero bin";
        EXPECT_FLOAT_EQ(pdf, d.PDF(x));
        EXPECT_NEAR(d.Invert(x), u, 1e-5);
    }
}

TEST(Sampling, PowerHeuristic) {
    EXPECT_FLOAT_EQ(PowerHeuristic(1, 1, 1, 1), 0.5f);
    EXPECT_FLOAT_EQ(PowerHeuristic(1, 3, 1, 1) + PowerHeuristic(1, 1, 1, 3), 1.f);
    EXPECT_FLOAT_EQ(PowerHeuristic(1, 2, 1, 0), 1.f);
}
