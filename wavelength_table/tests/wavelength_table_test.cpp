// Tests of wavelength_table/include/wavelength_table.h: the sample / pdf / invert triples, SampleFour
// and its balance-heuristic estimator, zero densities and the defensive mixture, both file
// layouts and every reject class, the 4 x 81 tables of Dobos 2025, and the test vectors written
// by the Python sampler (scripts/make_test_vectors.py).

#include "wavelength_table.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace wt = wavelength_table;

namespace {

using Values = std::array<std::vector<double>, wt::kNumDensities>;

// An awkward table: irregular grid, exact zeros (a left tail, an interior gap, a right tail),
// a 0.2 nm spike, a nearly flat segment, a segment rising from zero and one falling to zero.
wt::Table AwkwardTable() {
    std::vector<double> grid = {380, 381.5, 400, 450, 500, 520, 545.9,
                                546.0, 546.1, 560, 600, 650, 700, 780};
    Values v;
    v[0] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};                      // flat
    v[1] = {0, 0, 0, 0, 2, 3, 0.5, 400, 0.5, 1, 1, 1, 0, 0};                // tails + spike
    v[2] = {5, 4, 3, 2, 0, 0, 0, 0, 0, 1, 2, 3, 4, 5};                      // interior gap
    v[3] = {1, 1 + 1e-12, 1, 0.2, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0, 0, 0};  // near-flat
    return wt::MakeTable(grid, v, "awkward");
}

// A table whose mixture is zero on [500, 520] (all four densities vanish there).
wt::Table TableWithMixtureGap() {
    std::vector<double> grid = {380, 450, 500, 510, 520, 600, 780};
    Values v;
    v[0] = {1, 1, 0, 0, 0, 1, 1};
    v[1] = {0, 2, 0, 0, 0, 0, 0};
    v[2] = {0, 0, 0, 0, 0, 1, 3};
    v[3] = {3, 1, 0, 0, 0, 1, 0};
    return wt::MakeTable(grid, v, "gap");
}

std::string Num(double v) {
    std::ostringstream os;
    os.precision(17);
    os << v;
    return os.str();
}

std::string TempPath(const std::string &name) {
    return (std::filesystem::path(testing::TempDir()) / ("wt_" + name)).string();
}

std::string WriteFile(const std::string &name, const std::string &text) {
    const std::string path = TempPath(name);
    std::ofstream out(path, std::ios::binary);
    out << text;
    return path;
}

// The commented CSV layout of `values` on `grid`.
std::string CsvText(const std::vector<double> &grid, const Values &v) {
    std::string s = "# test table\nlambda_nm,pdf0,pdf1,pdf2,pdf3\n";
    for (size_t i = 0; i < grid.size(); ++i) {
        s += Num(grid[i]);
        for (int k = 0; k < 4; ++k)
            s += "," + Num(v[k][i]);
        s += "\n";
    }
    return s;
}

// The headerless 4 x 81 layout (with the trailing commas of the files of Dobos 2025).
std::string WideText(const Values &v) {
    std::string s;
    for (int k = 0; k < 4; ++k) {
        for (double x : v[k])
            s += Num(x) + ",";
        s += "\n";
    }
    return s;
}

std::vector<double> WideGrid() {
    std::vector<double> g;
    for (int i = 0; i < 81; ++i)
        g.push_back(380.0 + 5.0 * i);
    return g;
}

// Smooth positive densities on the 4 x 81 grid (not normalized).
Values WideValues() {
    Values v;
    for (int k = 0; k < 4; ++k)
        for (int i = 0; i < 81; ++i)
            v[k].push_back(1.0 + k + std::sin(0.1 * i * (k + 1)));
    return v;
}

// Integral of p_k over [a, b] by Simpson's rule on each grid segment (exact for linear p;
// the density jumps to 0 at the ends of the grid, so the range is clipped to it first).
double IntegratePdf(const wt::Table &t, int k, double a, double b) {
    a = std::max(a, t.grid.front());
    b = std::min(b, t.grid.back());
    if (!(a < b))
        return 0.0;
    std::vector<double> cuts = {a};
    for (double g : t.grid)
        if (g > a && g < b)
            cuts.push_back(g);
    cuts.push_back(b);
    double sum = 0;
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        const double x0 = cuts[i], x1 = cuts[i + 1];
        sum += (x1 - x0) / 6 *
               (wt::Pdf(t, k, x0) + 4 * wt::Pdf(t, k, 0.5 * (x0 + x1)) + wt::Pdf(t, k, x1));
    }
    return sum;
}

// Upper 1e-4 quantile of the chi-square distribution (Wilson-Hilferty approximation,
// z = 3.719 is the standard-normal 1e-4 upper quantile).
double ChiSquareLimit(int dof) {
    const double c = 2.0 / (9.0 * dof);
    return dof * std::pow(1 - c + 3.719 * std::sqrt(c), 3);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// The sample / pdf / invert triple.
// ---------------------------------------------------------------------------------------

// The branch-free search against std::upper_bound: every size up to 70, runs of equal values
// (a CDF is flat over a zero-density segment), values below, between, on and above the nodes,
// and NaN (which maps to 0, as u = NaN counts as 0).
TEST(WavelengthTable, LastNotAboveIsTheLastNodeNotAboveTheValue) {
    std::mt19937_64 rng(7);
    std::uniform_int_distribution<int> step(0, 2);  // 0: a tie with the previous node
    for (int n = 1; n <= 70; ++n) {
        std::vector<double> x(n);
        double at = 0;
        for (double &xi : x) xi = at += step(rng);
        std::vector<double> probes = {-1.0, x.back() + 1, std::numeric_limits<double>::quiet_NaN()};
        for (double xi : x) {
            probes.push_back(xi);
            probes.push_back(xi + 0.5);
        }
        for (double v : probes) {
            const int got = wt::kernel::LastNotAbove(x.data(), n, v);
            const int want = std::max(0, int(std::upper_bound(x.begin(), x.end(), v) - x.begin()) - 1);
            EXPECT_EQ(got, std::isnan(v) ? 0 : want) << "n = " << n << ", v = " << v;
        }
    }
}

TEST(WavelengthTable, PdfIntegratesToOneAndCdfIsItsIntegral) {
    const wt::Table t = AwkwardTable();
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> lam(370, 790);
    for (int k = 0; k < 4; ++k) {
        const double total = IntegratePdf(t, k, 360, 800);
        EXPECT_NEAR(total, 1.0, 1e-12) << "pdf" << k;
        EXPECT_EQ(t.cdf[k].front(), 0.0);
        EXPECT_EQ(t.cdf[k].back(), 1.0);
        // Invert is the integral of Pdf, everywhere (also outside the grid).
        for (int n = 0; n < 200; ++n) {
            const double l = lam(rng);
            EXPECT_NEAR(wt::Invert(t, k, l), IntegratePdf(t, k, 360, l), 1e-12)
                << "pdf" << k << " at " << l;
        }
    }
}

TEST(WavelengthTable, RoundTripSampleInvert) {
    const wt::Table t = AwkwardTable();
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> uni(0, 1);
    for (int k = 0; k < 4; ++k) {
        for (int n = 0; n < 20000; ++n) {
            const double u = uni(rng);
            const double l = wt::Sample(t, k, u);
            EXPECT_NEAR(wt::Invert(t, k, l), u, 1e-13) << "pdf" << k << " u=" << u;
            // Where the density is positive, Sample inverts Invert too.
            if (wt::Pdf(t, k, l) > 1e-6) {
                EXPECT_NEAR(wt::Sample(t, k, wt::Invert(t, k, l)), l, 1e-9) << "pdf" << k;
            }
        }
    }
}

TEST(WavelengthTable, SamplesFollowThePdfChiSquare) {
    const wt::Table t = AwkwardTable();
    const int n = 200000;
    for (int k = 0; k < 4; ++k) {
        // Bins: every grid segment cut in 4; expected counts from integrating Pdf.
        std::vector<double> edges;
        for (size_t i = 0; i + 1 < t.grid.size(); ++i)
            for (int j = 0; j < 4; ++j)
                edges.push_back(t.grid[i] + (t.grid[i + 1] - t.grid[i]) * j / 4.0);
        edges.push_back(t.grid.back());
        std::vector<double> observed(edges.size() - 1, 0.0);
        std::mt19937_64 rng(10 + k);
        std::uniform_real_distribution<double> uni(0, 1);
        for (int s = 0; s < n; ++s) {
            const double l = wt::Sample(t, k, uni(rng));
            ASSERT_GE(l, t.grid.front());
            ASSERT_LE(l, t.grid.back());
            const size_t b = std::upper_bound(edges.begin(), edges.end(), l) - edges.begin();
            observed[std::min(b, edges.size() - 1) - 1] += 1;
        }
        // Pool bins (left to right) until each expects >= 5 samples; zero bins stay empty.
        double chi2 = 0, obs = 0, expd = 0;
        int dof = -1;
        for (size_t b = 0; b < observed.size(); ++b) {
            const double e = n * IntegratePdf(t, k, edges[b], edges[b + 1]);
            if (e == 0) {
                EXPECT_EQ(observed[b], 0) << "pdf" << k << " sampled a zero bin at " << edges[b];
                continue;
            }
            obs += observed[b];
            expd += e;
            if (expd >= 5) {
                chi2 += (obs - expd) * (obs - expd) / expd;
                ++dof;
                obs = expd = 0;
            }
        }
        ASSERT_GT(dof, 5);
        EXPECT_LT(chi2, ChiSquareLimit(dof)) << "pdf" << k << ": chi2 " << chi2 << ", dof " << dof;
    }
}

TEST(WavelengthTable, DerivativeOfInvertIsPdf) {
    const wt::Table t = AwkwardTable();
    for (int k = 0; k < 4; ++k)
        for (size_t i = 0; i + 1 < t.grid.size(); ++i) {
            // The midpoint of each segment and two points near its ends.
            for (double a : {0.1, 0.5, 0.9}) {
                const double l = t.grid[i] + a * (t.grid[i + 1] - t.grid[i]);
                const double h = 1e-4 * (t.grid[i + 1] - t.grid[i]);
                const double fd = (wt::Invert(t, k, l + h) - wt::Invert(t, k, l - h)) / (2 * h);
                EXPECT_NEAR(fd, wt::Pdf(t, k, l), 1e-6 * (1 + wt::Pdf(t, k, l)))
                    << "pdf" << k << " at " << l;
            }
        }
}

TEST(WavelengthTable, AnalyticSegments) {
    // Uniform density on [400, 500]: lambda = 400 + 100 u.
    {
        Values v = {{{1, 1}, {1, 1}, {1, 1}, {1, 1}}};
        const wt::Table t = wt::MakeTable({400, 500}, v, "uniform");
        for (double u : {0.0, 0.125, 0.5, 0.9, 1.0})
            EXPECT_NEAR(wt::Sample(t, 0, u), 400 + 100 * u, 1e-12) << u;
        EXPECT_DOUBLE_EQ(wt::Pdf(t, 0, 450), 0.01);
    }
    // Ramp from 0 on [0 + 400, 400 + 10]: p = 2 t / 100, F = t^2 / 100, t = 10 sqrt(u).
    {
        Values v = {{{0, 1}, {0, 1}, {0, 1}, {0, 1}}};
        const wt::Table t = wt::MakeTable({400, 410}, v, "ramp");
        for (double u : {1e-300, 1e-20, 1e-6, 0.01, 0.3, 0.99, 1.0}) {
            const double want = 400 + 10 * std::sqrt(u);
            EXPECT_NEAR(wt::Sample(t, 0, u), want, 1e-12 * want) << u;
        }
    }
    // Falling to 0: p = 2 (10 - t) / 100, F = 1 - (10 - t)^2 / 100, t = 10 (1 - sqrt(1 - u)).
    // Near the zero, lambda is ill-conditioned in u (d lambda / du = 1 / p), so the tolerance
    // is a few rounding errors of u divided by the density there; u = 1 is exact.
    {
        Values v = {{{1, 0}, {1, 0}, {1, 0}, {1, 0}}};
        const wt::Table t = wt::MakeTable({400, 410}, v, "fall");
        for (double u : {0.0, 1e-12, 0.3, 0.999999, 1 - 1e-12, 1 - 1e-15}) {
            const double want = 400 + 10 * (1 - std::sqrt(1 - u));
            const double tol = 1e-12 * want + 4e-16 / wt::Pdf(t, 0, want);
            EXPECT_NEAR(wt::Sample(t, 0, u), want, tol) << u;
        }
        EXPECT_EQ(wt::Sample(t, 0, 1.0), 410.0);
        EXPECT_EQ(wt::Sample(t, 0, 0.0), 400.0);
    }
    // A nearly flat segment (slope 1e-12 relative) must not lose digits: t ~ r / p0.
    {
        Values v = {{{1, 1 + 1e-12}, {1, 1}, {1, 1}, {1, 1}}};
        const wt::Table t = wt::MakeTable({400, 500}, v, "flat");
        for (double u : {1e-15, 1e-9, 0.25, 0.75}) {
            const double got = wt::Sample(t, 0, u) - 400;
            EXPECT_NEAR(got, 100 * u, 1e-10 * 100 * u + 1e-13) << u;
        }
    }
}

TEST(WavelengthTable, ExtremeArguments) {
    const wt::Table t = AwkwardTable();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (int k = 0; k < 4; ++k) {
        EXPECT_EQ(wt::Sample(t, k, -1.0), wt::Sample(t, k, 0.0));
        EXPECT_EQ(wt::Sample(t, k, nan), wt::Sample(t, k, 0.0));
        EXPECT_EQ(wt::Sample(t, k, 2.0), wt::Sample(t, k, 1.0));
        EXPECT_EQ(wt::Pdf(t, k, 379.999), 0.0);
        EXPECT_EQ(wt::Pdf(t, k, 780.001), 0.0);
        EXPECT_EQ(wt::Pdf(t, k, nan), 0.0);
        EXPECT_EQ(wt::Invert(t, k, 100.0), 0.0);
        EXPECT_EQ(wt::Invert(t, k, 1000.0), 1.0);
        EXPECT_EQ(wt::Invert(t, k, nan), 0.0);
        EXPECT_EQ(wt::Pdf(t, k, 380.0), t.pdf[k].front());
        EXPECT_EQ(wt::Pdf(t, k, 780.0), t.pdf[k].back());
    }
}

// ---------------------------------------------------------------------------------------
// Exact zeros.
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, ZeroDensityRegionsAreNeverSampled) {
    const wt::Table t = AwkwardTable();
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uni(0, 1);
    for (int k = 0; k < 4; ++k)
        for (int n = 0; n < 20000; ++n) {
            const double u = uni(rng);
            if (u == 0)
                continue;
            const double l = wt::Sample(t, k, u);
            EXPECT_GT(wt::Pdf(t, k, l), 0.0) << "pdf" << k << " u=" << u << " lambda=" << l;
        }
    // pdf1 is zero on [380, 450] and [700, 780]: u = 0 and u = 1 map to the support's ends.
    EXPECT_EQ(wt::Sample(t, 1, 0.0), 450.0);
    EXPECT_EQ(wt::Sample(t, 1, 1.0), 700.0);
    // pdf3 is zero on [650, 780].
    EXPECT_EQ(wt::Sample(t, 3, 1.0), 650.0);
    // pdf2 is zero on [500, 546.1]: F is flat there. u = F(500) selects the segment that
    // starts at 546.1 (the last node with F <= u); the Python sampler does the same.
    const double u = wt::Invert(t, 2, 500.0);
    EXPECT_EQ(wt::Sample(t, 2, u), 546.1);
    EXPECT_EQ(wt::Invert(t, 2, 546.1), u);
    EXPECT_LT(wt::Sample(t, 2, std::nextafter(u, 0.0)), 500.0);
}

// ---------------------------------------------------------------------------------------
// Four wavelengths from one u, and the estimator they feed.
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, SampleFourUsesOneUAndTheMixtureDensity) {
    const wt::Table t = AwkwardTable();
    std::vector<double> us = {0.0, 0.01, 0.37, 0.5, 0.999, 1.0};
    for (int k = 0; k < 4; ++k)  // u that put a wavelength exactly on a node
        us.insert(us.end(), t.cdf[k].begin(), t.cdf[k].end());
    for (double u : us) {
        double lambda[4], pdf[4];
        wt::SampleFour(t, u, lambda, pdf);
        for (int k = 0; k < 4; ++k) {
            EXPECT_EQ(lambda[k], wt::Sample(t, k, u)) << "k=" << k << " u=" << u;
            double mix = 0;
            for (int j = 0; j < 4; ++j)
                mix += wt::Pdf(t, j, lambda[k]);
            // (SampleFour reuses the segment it sampled in; Pdf searches for it.)
            EXPECT_NEAR(pdf[k], mix / 4, 1e-14 * mix) << "k=" << k << " u=" << u;
            EXPECT_NEAR(pdf[k], wt::MixturePdf(t, lambda[k]), 1e-14 * mix);
        }
    }
}

// The packed layout for device memory: a view over a copy of Pack() gives the same numbers.
TEST(WavelengthTable, PackedViewMatchesTheTable) {
    const wt::Table t = AwkwardTable();
    const std::vector<double> packed = wt::Pack(t);
    ASSERT_EQ(packed.size(), 9 * t.grid.size());
    const std::vector<double> device(packed);  // stands for a copy in GPU memory
    const wt::TableView v = wt::ViewPacked(device.data(), static_cast<int>(t.grid.size()));
    for (double u : {0.0, 1e-9, 0.2, 0.5, 0.77, 1 - 1e-12, 1.0}) {
        double l1[4], p1[4], l2[4], p2[4];
        wt::SampleFour(t, u, l1, p1);
        wt::kernel::SampleFour(v, u, l2, p2);
        for (int k = 0; k < 4; ++k) {
            EXPECT_EQ(l1[k], l2[k]) << "k=" << k << " u=" << u;
            EXPECT_EQ(p1[k], p2[k]) << "k=" << k << " u=" << u;
        }
    }
}

namespace {

// The renderer's estimate of the integral of f with stratified u: the mean over u of
// (1/4) sum_j f(lambda_j) / pdf_j (samples with pdf_j = 0 count as 0).
template <typename F>
double EstimateIntegral(const wt::Table &t, F f, int n) {
    double est = 0;
    for (int s = 0; s < n; ++s) {
        double lambda[4], pdf[4];
        wt::SampleFour(t, (s + 0.5) / n, lambda, pdf);
        for (int j = 0; j < 4; ++j)
            if (pdf[j] > 0)
                est += f(lambda[j]) / pdf[j] / 4;
    }
    return est / n;
}

// The integral of f over the grid range, counting only where `keep(lambda)` (midpoint rule).
template <typename F, typename K>
double Integral(const wt::Table &t, F f, K keep) {
    double sum = 0;
    for (size_t i = 0; i + 1 < t.grid.size(); ++i) {
        const int m = 20000;
        const double h = (t.grid[i + 1] - t.grid[i]) / m;
        for (int j = 0; j < m; ++j) {
            const double l = t.grid[i] + (j + 0.5) * h;
            if (keep(l))
                sum += f(l) * h;
        }
    }
    return sum;
}

}  // namespace

// The estimator is unbiased where the mixture is positive: every density of the awkward
// table has zeros, but never all four at once.
TEST(WavelengthTable, BalanceHeuristicEstimatorIsUnbiased) {
    auto f = [](double l) {
        return 0.2 + std::exp(-0.5 * std::pow((l - 546.0) / 0.05, 2)) +
               0.5 * std::exp(-0.5 * std::pow((l - 611.0) / 3.0, 2));
    };
    const wt::Table t = AwkwardTable();
    const double want = Integral(t, f, [](double) { return true; });
    EXPECT_NEAR(EstimateIntegral(t, f, 400000), want, 1e-4 * want);
}

// Where the mixture is zero the estimator misses f (the bias the renderer warns about), and
// the defensive mixture removes it. f vanishes at the edges of the gap: a density falling
// linearly to zero there makes f / pdf unbounded (infinite variance), another reason for
// the defensive share.
TEST(WavelengthTable, ZeroMixtureBiasesAndTheDefensiveMixtureFixesIt) {
    auto f = [](double l) {
        return std::exp(-0.5 * std::pow((l - 510.0) / 1.5, 2)) +
               0.5 * std::exp(-0.5 * std::pow((l - 611.0) / 3.0, 2));
    };
    const wt::Table t = TableWithMixtureGap();
    const double all = Integral(t, f, [](double) { return true; });
    const double support = Integral(t, f, [&](double l) { return wt::MixturePdf(t, l) > 0; });
    ASSERT_LT(support, 0.7 * all) << "the test function must put mass into the gap";
    EXPECT_NEAR(EstimateIntegral(t, f, 400000), support, 1e-4 * support);
    EXPECT_NEAR(EstimateIntegral(wt::WithDefensiveMixture(t, 0.05), f, 400000), all, 1e-4 * all);
}

// ---------------------------------------------------------------------------------------
// Zero mixture density and the defensive mixture.
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, ZeroMixtureIntervalsFindsTheGap) {
    const auto gaps = wt::ZeroMixtureIntervals(TableWithMixtureGap());
    ASSERT_EQ(gaps.size(), 1u);
    EXPECT_EQ(gaps[0].first, 500.0);
    EXPECT_EQ(gaps[0].second, 520.0);
    // The awkward table has zeros in every density but never in all four together.
    EXPECT_TRUE(wt::ZeroMixtureIntervals(AwkwardTable()).empty());
    // Two separate gaps and an isolated zero node (not an interval).
    Values v;
    for (int k = 0; k < 4; ++k)
        v[k] = {0, 0, 1, 0, 1, 0, 0, 0};
    const auto two = wt::ZeroMixtureIntervals(
        wt::MakeTable({380, 390, 400, 410, 420, 430, 440, 780}, v, "two"));
    ASSERT_EQ(two.size(), 2u);
    EXPECT_EQ(two[0], std::make_pair(380.0, 390.0));
    EXPECT_EQ(two[1], std::make_pair(430.0, 780.0));
}

TEST(WavelengthTable, DefensiveMixtureRemovesZeroIntervals) {
    const wt::Table t = TableWithMixtureGap();
    const double range = t.grid.back() - t.grid.front();
    for (double share : {1e-6, 0.05, 0.5, 1.0}) {
        const wt::Table d = wt::WithDefensiveMixture(t, share);
        EXPECT_TRUE(wt::ZeroMixtureIntervals(d).empty()) << share;
        for (int k = 0; k < 4; ++k) {
            EXPECT_NEAR(IntegratePdf(d, k, 380, 780), 1.0, 1e-12);
            for (double l : {380.0, 470.0, 510.0, 520.0, 700.0}) {
                const double want = (1 - share) * wt::Pdf(t, k, l) + share / range;
                EXPECT_NEAR(wt::Pdf(d, k, l), want, 1e-13 * want) << share << " " << l;
                EXPECT_GT(wt::Pdf(d, k, l), 0.0);
            }
        }
    }
    // share 0 keeps the table.
    const wt::Table same = wt::WithDefensiveMixture(t, 0.0);
    for (int k = 0; k < 4; ++k)
        for (size_t i = 0; i < t.grid.size(); ++i)
            EXPECT_DOUBLE_EQ(same.pdf[k][i], t.pdf[k][i]);
    for (double bad : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()})
        EXPECT_THROW(wt::WithDefensiveMixture(t, bad), wt::TableError) << bad;
}

// ---------------------------------------------------------------------------------------
// Coverage (design §1.5): the measure, the thresholds and the warnings.
// ---------------------------------------------------------------------------------------

namespace {

// Colour-matching functions equal to 1: every fraction is then a fraction of wavelengths.
void FlatCmfs(double, double xyz[3]) { xyz[0] = xyz[1] = xyz[2] = 1.0; }

}  // namespace

TEST(Coverage, MeasuresTheGapAndTheEndsWhereALightEmits) {
    // Mixture zero on [500, 520] inside a 380..780 nm table; a flat lamp over 360..830 nm.
    const wt::Table t = TableWithMixtureGap();
    const wt::Coverage c = wt::MeasureCoverage(t, [](double) { return 2.0; }, FlatCmfs);
    ASSERT_EQ(c.gaps.size(), 1u);
    EXPECT_EQ(c.gaps[0], std::make_pair(500.0, 520.0));
    EXPECT_NEAR(c.gapLuminanceFraction, 20.0 / 470.0, 1e-12);
    ASSERT_EQ(c.outside.size(), 2u);
    EXPECT_EQ(c.outside[0], std::make_pair(360.0, 380.0));
    EXPECT_EQ(c.outside[1], std::make_pair(780.0, 830.0));
    EXPECT_NEAR(c.outsideLuminanceFraction, 70.0 / 470.0, 1e-12);
    EXPECT_NEAR(c.outsideTristimulusFraction, 70.0 / 470.0, 1e-12);

    const std::vector<std::string> w =
        wt::CoverageWarnings(c, "this light", 380, 780, "table t.csv", "use a wider table");
    ASSERT_EQ(w.size(), 2u);
    EXPECT_EQ(w[0], "the wavelength sampling density is zero on [500, 520] nm, where this light "
                    "emits (4.26% of its luminance): paths never carry those wavelengths, so the "
                    "image is biased; mix a uniform share into the table with "
                    "--wavelength-pdf-defensive 0.01 [table t.csv]");
    EXPECT_EQ(w[1], "this light emits on [360, 380] and [780, 830] nm, outside the range of the "
                    "wavelength table [380, 780] nm, where paths never carry wavelengths: the "
                    "image misses 14.9% of its luminance (up to 14.9% of X, Y or Z). "
                    "--wavelength-pdf-defensive only covers the table's range; extend the "
                    "table's grid to 360..830 nm, or use a wider table [table t.csv]");
    // Without another fix the sentence ends after the grid.
    EXPECT_NE(wt::CoverageWarnings(c, "a light", 380, 780, "t").back().find(
                  "grid to 360..830 nm [t]"), std::string::npos);
}

TEST(Coverage, NoWarningWhereTheLightIsDarkOrBelowTheThresholds) {
    const wt::Table t = TableWithMixtureGap();
    // Dark in the gap and outside the range: covered.
    auto inside = [](double l) { return l >= 380 && l <= 780 && !(l > 500 && l < 520) ? 1.0 : 0.0; };
    const wt::Coverage covered = wt::MeasureCoverage(t, inside, FlatCmfs);
    EXPECT_TRUE(covered.gaps.empty() && covered.outside.empty());
    EXPECT_TRUE(wt::CoverageWarnings(covered, "this light", 380, 780, "t").empty());
    // A faint floor outside the range: reported as measured, warned about only above 1e-4 of
    // the luminance (here the CMFs are flat, so X, Y and Z share the fraction).
    for (const double floor : {1e-5, 1e-3}) {
        auto lamp = [&](double l) { return l >= 380 && l <= 780 ? (l > 500 && l < 520 ? 0.0 : 1.0) : floor; };
        const wt::Coverage c = wt::MeasureCoverage(t, lamp, FlatCmfs);
        ASSERT_EQ(c.outside.size(), 2u);
        const double fraction = 70 * floor / (380 + 70 * floor);
        EXPECT_NEAR(c.outsideLuminanceFraction, fraction, 1e-9 * fraction);
        EXPECT_EQ(wt::CoverageWarnings(c, "this light", 380, 780, "t").size(),
                  fraction > wt::kOutsideLuminanceWarnFraction ? 1u : 0u)
            << floor;
        EXPECT_EQ(fraction > wt::kOutsideLuminanceWarnFraction, floor == 1e-3);
    }
    // X alone outside the range, above its threshold while Y stays below its own.
    auto redOutside = [](double l, double xyz[3]) {
        const bool out = l < 380 || l > 780;
        xyz[0] = out ? 1.0 : 1e-3;
        xyz[1] = out ? 1e-9 : 1.0;
        xyz[2] = 1.0;
    };
    auto flatLamp = [](double l) { return l > 500 && l < 520 ? 0.0 : 1.0; };
    const wt::Coverage red = wt::MeasureCoverage(t, flatLamp, redOutside);
    EXPECT_LT(red.outsideLuminanceFraction, wt::kOutsideLuminanceWarnFraction);
    EXPECT_GT(red.outsideTristimulusFraction, wt::kOutsideTristimulusWarnFraction);
    EXPECT_EQ(wt::CoverageWarnings(red, "this light", 380, 780, "t").size(), 1u);
}

// ---------------------------------------------------------------------------------------
// Reading tables: both layouts.
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, BothLayoutsGiveTheSameTable) {
    const Values v = WideValues();
    const wt::Table a = wt::LoadTable(WriteFile("layout_csv.csv", CsvText(WideGrid(), v)));
    const wt::Table b = wt::LoadTable(WriteFile("layout_wide.csv", WideText(v)));
    ASSERT_EQ(a.grid, WideGrid());
    ASSERT_EQ(b.grid, WideGrid());
    for (int k = 0; k < 4; ++k) {
        ASSERT_EQ(a.pdf[k].size(), 81u);
        ASSERT_EQ(b.pdf[k].size(), 81u);
        for (int i = 0; i < 81; ++i) {
            EXPECT_EQ(a.pdf[k][i], b.pdf[k][i]) << k << " " << i;
            EXPECT_EQ(a.cdf[k][i], b.cdf[k][i]) << k << " " << i;
            // Renormalized, proportional to the values in the file.
            EXPECT_NEAR(a.pdf[k][i] / v[k][i], a.pdf[k][0] / v[k][0], 1e-15);
        }
        EXPECT_NEAR(IntegratePdf(a, k, 380, 780), 1.0, 1e-12);
    }
    EXPECT_NE(a.source.find("layout_csv.csv"), std::string::npos);
}

TEST(WavelengthTable, ReaderToleratesCommentsBlankLinesCrlfAndSpaces) {
    const std::string text =
        "\xEF\xBB\xBF# a comment\r\n"
        "   # an indented comment\r\n"
        "\r\n"
        "Lambda_nm, pdf0, pdf1, pdf2, pdf3\r\n"
        "380, 1, 2, 0, 4\r\n"
        "\r\n"
        "# comment between rows\r\n"
        "+400.5,1e0,2.,1,  4 ,\r\n"
        "780,1,2,1,4\r\n";
    std::istringstream in(text);
    const wt::Table t = wt::ParseTable(in, "in-memory");
    EXPECT_EQ(t.grid, (std::vector<double>{380, 400.5, 780}));
    EXPECT_EQ(t.source, "in-memory");
    EXPECT_EQ(t.pdf[2][0], 0.0);
    EXPECT_NEAR(t.pdf[0][1], 1.0 / 400, 1e-15);
}

TEST(WavelengthTable, OldMacLineEndingsCountAsLines) {
    std::istringstream in("# c\rlambda_nm,pdf0,pdf1,pdf2,pdf3\r380,1,1,1,1\r390,1,1,x,1\r");
    try {
        wt::ParseTable(in, "cr");
        ADD_FAILURE() << "accepted 'x'";
    } catch (const wt::TableError &e) {
        EXPECT_EQ(std::string(e.what()), "cr:4: cannot parse number 'x'");
    }
}

TEST(WavelengthTable, ParseTableNamesTheStream) {
    std::istringstream in("lambda_nm,pdf0,pdf1,pdf2,pdf3\n380,1,1,1,1\n390,1,1,-1,1\n");
    try {
        wt::ParseTable(in, "stream-name");
        ADD_FAILURE() << "accepted a negative value";
    } catch (const wt::TableError &e) {
        EXPECT_EQ(std::string(e.what()).rfind("stream-name:3: pdf2 is negative", 0), 0u)
            << e.what();
    }
}

// ---------------------------------------------------------------------------------------
// Reading tables: what is not a file's content. Every reject class of a table's content is
// a file of tests/data/tables/edge (EdgeTablesAsEveryReaderReadsThem, below).
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, MissingFileAndDirectoryAreNamed) {
    const std::string missing = TempPath("does_not_exist.csv");
    std::filesystem::remove(missing);
    try {
        wt::LoadTable(missing);
        ADD_FAILURE() << "a missing file was accepted";
    } catch (const wt::TableError &e) {
        EXPECT_EQ(std::string(e.what()), missing + ": no such file");
        EXPECT_EQ(e.line(), 0);
    }
    try {
        wt::LoadTable(testing::TempDir());
        ADD_FAILURE() << "a directory was accepted";
    } catch (const wt::TableError &e) {
        EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
    }
}

// Mangled files (bytes deleted, duplicated or replaced) either load as a valid table or
// throw TableError with the name; nothing else (no other exception, crash or hang).
TEST(WavelengthTable, MangledInputIsRejectedOrValid) {
    const std::string good = CsvText({380, 400, 450.5, 600, 780},
                                     {{{1, 2, 3, 4, 5}, {0, 1, 0, 1, 0}, {1, 1, 1, 1, 1},
                                       {5, 0, 0, 0, 1}}});
    const std::string alphabet = "0123456789.,-+eE#\nnaifl \t";
    std::mt19937 rng(7);
    int accepted = 0, rejected = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        std::string text = trial % 2 ? good : WideText(WideValues());
        const int edits = 1 + static_cast<int>(rng() % 4);
        for (int e = 0; e < edits; ++e) {
            const size_t at = rng() % text.size();
            switch (rng() % 3) {
            case 0: text.erase(at, 1 + rng() % 3); break;
            case 1: text.insert(at, 1, alphabet[rng() % alphabet.size()]); break;
            default: text[at] = alphabet[rng() % alphabet.size()]; break;
            }
            if (text.empty())
                text = "#";
        }
        std::istringstream in(text);
        try {
            const wt::Table t = wt::ParseTable(in, "mangled");
            ++accepted;
            ASSERT_GE(t.grid.size(), 2u);
            for (size_t i = 1; i < t.grid.size(); ++i)
                ASSERT_GT(t.grid[i], t.grid[i - 1]);
            for (int k = 0; k < 4; ++k) {
                ASSERT_EQ(t.cdf[k].back(), 1.0);
                for (double p : t.pdf[k])
                    ASSERT_TRUE(std::isfinite(p) && p >= 0) << text;
            }
        } catch (const wt::TableError &e) {
            ++rejected;
            ASSERT_EQ(std::string(e.what()).rfind("mangled", 0), 0u) << e.what();
            ASSERT_FALSE(e.reason().empty());
        }
    }
    // Both outcomes occur, so the mangling is neither too weak nor too strong.
    EXPECT_GT(accepted, 100);
    EXPECT_GT(rejected, 100);
}

TEST(WavelengthTable, MakeTableRejectsWithTheName) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    auto expect = [](std::vector<double> grid, Values v, const std::string &reason) {
        try {
            wt::MakeTable(grid, v, "my-table");
            ADD_FAILURE() << "accepted, expected " << reason;
        } catch (const wt::TableError &e) {
            EXPECT_EQ(std::string(e.what()), "my-table: " + reason);
        }
    };
    expect({380, 390}, {{{1, 1}, {1, nan}, {1, 1}, {1, 1}}}, "pdf1 is NaN at 390 nm");
    expect({380, 390}, {{{1, 1}, {1, 1}, {0, 0}, {1, 1}}}, "pdf2 is zero everywhere");
    expect({380}, {{{1}, {1}, {1}, {1}}}, "a table needs at least 2 grid nodes, got 1");
    expect({380, 390}, {{{1, 1}, {1, 1}, {1}, {1, 1}}}, "pdf2 has 1 values, the grid has 2");
    expect({390, 380}, {{{1, 1}, {1, 1}, {1, 1}, {1, 1}}},
           "grid is not strictly increasing (390 then 380 nm)");
    expect({-1e308, 1e308}, {{{1, 1}, {1, 1}, {1, 1}, {1, 1}}},
           "pdf0 integrates to infinity (the grid is too wide)");
    expect({0, 5e-324}, {{{1, 1}, {1, 1}, {1, 1}, {1, 1}}},
           "pdf0 cannot be normalized exactly (the grid is too narrow)");
    // Values near the largest double are scaled by a power of two, not refused.
    const wt::Table big = wt::MakeTable({380, 390}, {{{1e308, 1e308}, {1, 1}, {1, 1}, {1, 1}}}, "big");
    EXPECT_DOUBLE_EQ(big.pdf[0][0], 0.1);
}

// ---------------------------------------------------------------------------------------
// The edge-case tables every reader reads alike (tests/data/tables/edge/expected.csv, the
// same files and expectations as the Python reader's and the renderer's tests; design §2).
// ---------------------------------------------------------------------------------------

namespace {

struct EdgeCase {
    std::string file;
    int nodes = 0;  // > 0: accepted with this many nodes
    int line = 0;   // else refused at this line
    std::string reason;
};

// The rows of a manifest of tests/data/tables/edge (comment lines and the column header
// skipped) as `columns` fields: the last one takes the rest of the line, commas included.
std::vector<std::vector<std::string>> ManifestRows(const std::string &name, int columns) {
    std::ifstream in(std::string(WT_EDGE_TABLES_DIR) + "/" + name);
    std::vector<std::vector<std::string>> rows;
    std::string line;
    bool header = false;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#')
            continue;
        if (!header) {
            header = true;
            continue;
        }
        std::vector<std::string> f;
        std::size_t start = 0;
        for (int i = 0; i + 1 < columns; ++i) {
            const std::size_t comma = line.find(',', start);
            f.push_back(line.substr(start, comma - start));
            start = comma + 1;
        }
        f.push_back(line.substr(start));
        rows.push_back(std::move(f));
    }
    return rows;
}

std::vector<EdgeCase> EdgeCases() {
    std::vector<EdgeCase> out;
    for (const std::vector<std::string> &f : ManifestRows("expected.csv", 4)) {  // file,nodes,line,reason
        EdgeCase c;
        c.file = f[0];
        c.nodes = f[1].empty() ? 0 : std::stoi(f[1]);
        c.line = f[2].empty() ? 0 : std::stoi(f[2]);
        c.reason = f[3];
        out.push_back(c);
    }
    return out;
}

}  // namespace

TEST(WavelengthTable, EdgeTablesAsEveryReaderReadsThem) {
    const std::vector<EdgeCase> cases = EdgeCases();
    ASSERT_GE(cases.size(), 20u) << "tests/data/tables/edge/expected.csv is missing or short";
    for (const EdgeCase &c : cases) {
        SCOPED_TRACE(c.file);
        const std::string path = std::string(WT_EDGE_TABLES_DIR) + "/" + c.file;
        if (c.nodes > 0) {
            wt::Table t;
            ASSERT_NO_THROW(t = wt::LoadTable(path));
            EXPECT_EQ(t.grid.size(), std::size_t(c.nodes));
            for (int k = 0; k < wt::kNumDensities; ++k) {
                EXPECT_NEAR(IntegratePdf(t, k, t.grid.front(), t.grid.back()), 1.0, 1e-13) << k;
                for (double p : t.pdf[k])
                    EXPECT_TRUE(std::isfinite(p) && p >= 0) << p;
            }
            continue;
        }
        try {
            wt::LoadTable(path);
            ADD_FAILURE() << "accepted; expected line " << c.line << ": " << c.reason;
        } catch (const wt::TableError &e) {
            const std::string msg = e.what();
            EXPECT_EQ(msg.rfind(path + ":" + std::to_string(c.line) + ": ", 0), 0u) << msg;
            EXPECT_NE(msg.find(c.reason), std::string::npos) << msg;
        }
    }
}

// The pairs of tests/data/tables/edge/same.csv (the Python reader's test reads them too):
// line ends, blanks and a byte-order mark change nothing, both layouts give one table, and
// the densities are the exact renormalization written in the *-normalized.csv files.
TEST(WavelengthTable, EdgeTablesThatAreTheSameTable) {
    const std::vector<std::vector<std::string>> pairs = ManifestRows("same.csv", 2);  // file,same_as
    ASSERT_GE(pairs.size(), 5u) << "tests/data/tables/edge/same.csv is missing or short";
    for (const std::vector<std::string> &pair : pairs) {
        SCOPED_TRACE(pair[0] + " = " + pair[1]);
        const wt::Table a = wt::LoadTable(std::string(WT_EDGE_TABLES_DIR) + "/" + pair[0]);
        const wt::Table b = wt::LoadTable(std::string(WT_EDGE_TABLES_DIR) + "/" + pair[1]);
        ASSERT_EQ(a.grid, b.grid);
        for (int k = 0; k < wt::kNumDensities; ++k)
            for (std::size_t i = 0; i < a.grid.size(); ++i)
                EXPECT_LE(std::abs(a.pdf[k][i] - b.pdf[k][i]),
                          1e-14 * std::max(std::abs(a.pdf[k][i]), std::abs(b.pdf[k][i])))
                    << k << " " << i << ": " << a.pdf[k][i] << " " << b.pdf[k][i];
    }
}

TEST(WavelengthTable, SubnormalDensitiesAreRenormalizedExactly) {
    // 5e-324 everywhere is a uniform density; summed in subnormal numbers its mass came out
    // 16 % off and pbrt rendered too dark.
    const wt::Table t = wt::LoadTable(std::string(WT_EDGE_TABLES_DIR) + "/denormal.csv");
    const double span = t.grid.back() - t.grid.front();
    for (int k = 0; k < wt::kNumDensities; ++k)
        for (double p : t.pdf[k])
            EXPECT_NEAR(p * span, 1.0, 1e-13);
}

#if defined(__SSE2__)
// A renderer built with -ffast-math (or Dr.Jit's threads, where the Mitsuba plugin reads its
// table) runs with the FPU flushing subnormal numbers to zero: the tables read the same.
TEST(WavelengthTable, EdgeTablesReadTheSameWithSubnormalsFlushedToZero) {
    const unsigned int saved = _mm_getcsr();
    std::vector<wt::Table> plain, flushed;
    std::vector<std::string> names;
    for (const EdgeCase &c : EdgeCases())
        if (c.nodes > 0) names.push_back(std::string(WT_EDGE_TABLES_DIR) + "/" + c.file);
    for (const std::string &n : names)
        plain.push_back(wt::LoadTable(n));
    _mm_setcsr(saved | 0x8040);  // FTZ and DAZ
    std::vector<std::string> errors;
    for (const std::string &n : names) {
        try {
            flushed.push_back(wt::LoadTable(n));
        } catch (const wt::TableError &e) {
            errors.push_back(e.what());
        }
    }
    _mm_setcsr(saved);
    ASSERT_TRUE(errors.empty()) << errors.front();
    for (std::size_t j = 0; j < names.size(); ++j) {
        SCOPED_TRACE(names[j]);
        EXPECT_EQ(flushed[j].grid, plain[j].grid);
        for (int k = 0; k < wt::kNumDensities; ++k)
            for (std::size_t i = 0; i < plain[j].grid.size(); ++i) {
                // Equal, except values below the normal doubles that FTZ flushes to 0.
                const double a = plain[j].pdf[k][i], b = flushed[j].pdf[k][i];
                EXPECT_TRUE(a == b || (b == 0 && a < 2.3e-308)) << k << " " << i << ": " << a << " " << b;
            }
    }
}
#endif

// ---------------------------------------------------------------------------------------
// What is not a table file: regular files of at most 64 MiB only (design §2.3).
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, DevicesAndFifosAreRefusedWithoutReading) {
    const std::string fifo = TempPath("fifo.csv");
    std::filesystem::remove(fifo);
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    const std::string reason = "not a regular file (a device, FIFO or socket), not a table file";
    for (const std::string &path : {fifo, std::string("/dev/zero")}) {
        try {
            wt::LoadTable(path);  // used to block on the FIFO, or read /dev/zero for ever
            ADD_FAILURE() << path << " was accepted";
        } catch (const wt::TableError &e) {
            EXPECT_EQ(std::string(e.what()), path + ": " + reason);
        }
    }
    std::filesystem::remove(fifo);
}

// 64 MiB + 1 bytes are refused for their size; 64 MiB are read (NUL bytes here, refused at
// line 1 for what they are). Sparse files: nothing is written to disk.
TEST(WavelengthTable, TableLargerThan64MiBIsRefusedBeforeItIsRead) {
    const std::string path = TempPath("big.csv");
    for (const std::size_t size : {wt::kMaxTableBytes, wt::kMaxTableBytes + 1}) {
        { std::ofstream touch(path, std::ios::binary | std::ios::trunc); }
        std::filesystem::resize_file(path, size);
        try {
            wt::LoadTable(path);
            ADD_FAILURE() << "a table of " << size << " bytes was accepted";
        } catch (const wt::TableError &e) {
            if (size > wt::kMaxTableBytes)
                EXPECT_EQ(std::string(e.what()), path + ": larger than 64 MiB, not a table file");
            else
                EXPECT_EQ(std::string(e.what()).rfind(path + ":1: control character U+0000", 0), 0u)
                    << e.what();
        }
    }
    std::filesystem::remove(path);
}

// ---------------------------------------------------------------------------------------
// The 4 x 81 tables of Dobos 2025 (../shared, skipped when absent).
// ---------------------------------------------------------------------------------------

TEST(WavelengthTable, EveryReferenceTableLoads) {
    const std::filesystem::path dir = std::filesystem::path(WT_SHARED_DIR) / "tables" / "reference-4x81";
    if (!std::filesystem::is_directory(dir))
        GTEST_SKIP() << dir << " is absent";
    int count = 0;
    for (const auto &entry : std::filesystem::directory_iterator(dir)) {
        if (entry.path().extension() != ".csv")
            continue;
        ++count;
        SCOPED_TRACE(entry.path().string());
        wt::Table t;
        ASSERT_NO_THROW(t = wt::LoadTable(entry.path().string()));
        ASSERT_EQ(t.grid, WideGrid());
        for (int k = 0; k < 4; ++k) {
            EXPECT_NEAR(IntegratePdf(t, k, 380, 780), 1.0, 1e-12);
            for (double u : {0.001, 0.25, 0.5, 0.75, 0.999})
                EXPECT_NEAR(wt::Invert(t, k, wt::Sample(t, k, u)), u, 1e-12);
        }
        // Whatever zero gaps a table has, the defensive mixture closes them.
        EXPECT_TRUE(wt::ZeroMixtureIntervals(wt::WithDefensiveMixture(t, 0.01)).empty());
    }
    EXPECT_GE(count, 1) << "no .csv tables in " << dir;
}

// ---------------------------------------------------------------------------------------
// Cross-language test vectors (design §8.1): written by scripts/make_test_vectors.py
// with python/wavelength_pdf/sampling.py; C++ must agree to 1e-5 relative.
// ---------------------------------------------------------------------------------------

namespace {

// Relative agreement with a tiny absolute floor for exact zeros.
bool Agree(double got, double want, double rel) {
    return std::abs(got - want) <= rel * std::max(std::abs(got), std::abs(want)) + 1e-300;
}

}  // namespace

TEST(WavelengthTable, AgreesWithThePythonSamplerOnTestVectors) {
    const std::string dir = WT_TEST_DATA_DIR;
    const wt::Table t = wt::LoadTable(dir + "/vectors-table.csv");
    std::ifstream in(dir + "/vectors.csv");
    ASSERT_TRUE(in) << dir << "/vectors.csv is missing; run scripts/make_test_vectors.py";
    std::string line;
    int lineNo = 0, rows = 0;
    bool sawZero = false, sawNearOne = false;
    bool header = false;
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.empty() || line[0] == '#')
            continue;
        if (!header) {
            EXPECT_EQ(line, "u,lambda0,lambda1,lambda2,lambda3,mixture_pdf0,mixture_pdf1,"
                            "mixture_pdf2,mixture_pdf3");
            header = true;
            continue;
        }
        std::istringstream row(line);
        row.imbue(std::locale::classic());
        double v[9];
        char comma;
        for (int c = 0; c < 9; ++c) {
            ASSERT_TRUE(row >> v[c]) << "vectors.csv:" << lineNo << ": column " << c;
            if (c < 8) {
                ASSERT_TRUE(row >> comma && comma == ',') << "vectors.csv:" << lineNo;
            }
        }
        ++rows;
        const double u = v[0];
        sawZero = sawZero || u == 0.0;
        sawNearOne = sawNearOne || (u > 1 - 1e-9 && u < 1.0);
        double lambda[4], pdf[4];
        wt::SampleFour(t, u, lambda, pdf);
        for (int k = 0; k < 4; ++k) {
            EXPECT_PRED3(Agree, lambda[k], v[1 + k], 1e-5)
                << "vectors.csv:" << lineNo << ": lambda" << k << " at u=" << Num(u);
            EXPECT_PRED3(Agree, pdf[k], v[5 + k], 1e-5)
                << "vectors.csv:" << lineNo << ": mixture_pdf" << k << " at u=" << Num(u);
        }
    }
    EXPECT_TRUE(header);
    EXPECT_GE(rows, 20);
    EXPECT_TRUE(sawZero) << "the vectors must include u = 0";
    EXPECT_TRUE(sawNearOne) << "the vectors must include a u just below 1";
}

// ---------------------------------------------------------------------------------------
// The equal-mass construction (design §1.7): EqualMassTable against the Python reference
// (wavelength_pdf.stratified.equal_mass_table) on the vectors of scripts/make_test_vectors.py,
// and its own properties.
// ---------------------------------------------------------------------------------------

namespace {

// The numeric rows of a CSV file with '#' comments and one header line (checked).
std::vector<std::vector<double>> ReadNumericCsv(const std::string &path, const std::string &header) {
    std::ifstream in(path);
    EXPECT_TRUE(in) << path << " is missing; run scripts/make_test_vectors.py";
    std::vector<std::vector<double>> rows;
    std::string line;
    bool sawHeader = false;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#')
            continue;
        if (!sawHeader) {
            EXPECT_EQ(line, header) << path;
            sawHeader = true;
            continue;
        }
        std::vector<double> row;
        const char *p = line.c_str();
        while (*p) {
            char *end = nullptr;
            row.push_back(std::strtod(p, &end));
            EXPECT_NE(end, p) << path << ": " << line;
            if (end == p)
                break;
            p = *end == ',' ? end + 1 : end;
        }
        rows.push_back(std::move(row));
    }
    return rows;
}

// The trapezoid-rule mass of q (linear between the nodes x) inside [a, b].
double MassBetween(const std::vector<double> &x, const std::vector<double> &q, double a, double b) {
    // Exact for a piecewise-linear q: integrate on the union of x and {a, b}.
    std::vector<double> nodes{a, b};
    for (double v : x)
        if (v > a && v < b)
            nodes.push_back(v);
    std::sort(nodes.begin(), nodes.end());
    double sum = 0;
    for (size_t i = 0; i + 1 < nodes.size(); ++i) {
        const double l = wt::detail::Interp(x, q, nodes[i], 0, 0);
        const double r = wt::detail::Interp(x, q, nodes[i + 1], 0, 0);
        sum += 0.5 * (l + r) * (nodes[i + 1] - nodes[i]);
    }
    return sum;
}

}  // namespace

TEST(EqualMassTable, AgreesWithThePythonReferenceOnTestVectors) {
    const std::string dir = WT_TEST_DATA_DIR;
    const auto inputs = ReadNumericCsv(dir + "/equal-mass-inputs.csv", "case,x_nm,q");
    const auto tables =
        ReadNumericCsv(dir + "/equal-mass-tables.csv", "case,lambda_nm,pdf0,pdf1,pdf2,pdf3");
    std::map<int, std::pair<std::vector<double>, std::vector<double>>> in;
    for (const auto &r : inputs) {
        ASSERT_EQ(r.size(), 3u);
        in[int(r[0])].first.push_back(r[1]);
        in[int(r[0])].second.push_back(r[2]);
    }
    std::map<int, std::vector<std::vector<double>>> want;
    for (const auto &r : tables) {
        ASSERT_EQ(r.size(), 6u);
        want[int(r[0])].push_back(r);
    }
    ASSERT_GE(in.size(), 8u);
    ASSERT_EQ(in.size(), want.size());
    double worst = 0;
    for (const auto &[c, xq] : in) {
        const wt::Table t = wt::EqualMassTable(xq.first, xq.second, "case " + std::to_string(c));
        const auto &w = want[c];
        ASSERT_EQ(t.grid.size(), w.size()) << "case " << c << ": grid size";
        std::array<double, 4> peak{};
        for (const auto &r : w)
            for (int k = 0; k < 4; ++k)
                peak[k] = std::max(peak[k], r[2 + k]);
        for (size_t i = 0; i < w.size(); ++i) {
            EXPECT_PRED3(Agree, t.grid[i], w[i][1], 1e-12) << "case " << c << " node " << i;
            worst = std::max(worst, std::abs(t.grid[i] - w[i][1]) / std::abs(w[i][1]));
            for (int k = 0; k < 4; ++k) {
                const double d = std::abs(t.pdf[k][i] - w[i][2 + k]) / peak[k];
                worst = std::max(worst, d);
                EXPECT_LE(d, 1e-12) << "case " << c << " node " << i << " (" << Num(t.grid[i])
                                    << " nm): pdf" << k << " " << Num(t.pdf[k][i]) << " vs "
                                    << Num(w[i][2 + k]);
            }
        }
    }
    std::printf("EqualMassTable vs Python: largest relative difference %.3g\n", worst);
}

TEST(EqualMassTable, BandsHaveEqualMassAndTheMixtureIsTheWeight) {
    // Lines on a continuum, on an irregular grid.
    std::vector<double> x, q;
    for (double l = 380; l <= 780; l += 0.7) {
        x.push_back(l);
        double v = 0.02 + 0.001 * (l - 380) / 400;
        for (auto [a, c] : {std::pair{1.0, 436.0}, {3.0, 546.1}, {2.0, 611.3}})
            v += a * std::exp(-0.5 * std::pow((l - c) / 0.9, 2));
        q.push_back(v);
    }
    const wt::Table t = wt::EqualMassTable(x, q);
    const double M = MassBetween(x, q, x.front(), x.back());
    for (int k = 0; k < 4; ++k) {
        // Density k is q / m_k on its band, m_k the mass it carried before normalizing: every
        // node where it alone is positive gives m_k = q / p_k, which must be M / 4.
        int nodes = 0;
        for (size_t i = 0; i < t.grid.size(); ++i) {
            bool alone = t.pdf[k][i] > 0;
            for (int j = 0; j < 4; ++j)
                alone = alone && (j == k || t.pdf[j][i] == 0);
            if (!alone)
                continue;
            ++nodes;
            const double m = wt::detail::Interp(x, q, t.grid[i], 0, 0) / t.pdf[k][i];
            EXPECT_NEAR(m / M, 0.25, 1e-12) << "density " << k << " at " << t.grid[i] << " nm";
        }
        EXPECT_GT(nodes, 10) << "density " << k;
    }
    // The mixture (1/4) sum_k p_k is q / M everywhere (q is linear between the nodes).
    for (double l = 380; l <= 780; l += 0.013) {
        const double want = wt::detail::Interp(x, q, l, 0, 0) / M;
        EXPECT_NEAR(wt::MixturePdf(t, l), want, 1e-9 * want + 1e-15) << l << " nm";
    }
    // One u stratifies: lambda_k = F_k^-1(u) lies in band k, increasing with k.
    for (double u : {0.001, 0.3, 0.77, 0.999}) {
        double l[4], p[4];
        wt::SampleFour(t, u, l, p);
        for (int k = 1; k < 4; ++k)
            EXPECT_LT(l[k - 1], l[k]) << "u=" << u;
    }
}

TEST(EqualMassTable, UniformWeightIsFourEqualBands) {
    const wt::Table t = wt::EqualMassTable({380, 780}, {3, 3});
    for (double u : {0.0, 0.25, 0.5, 0.9}) {
        double l[4], p[4];
        wt::SampleFour(t, u, l, p);
        for (int k = 0; k < 4; ++k) {
            EXPECT_NEAR(l[k], 380 + 100 * (k + u), 0.011) << "u=" << u << " k=" << k;
            EXPECT_NEAR(p[k], 1.0 / 400, 1e-12);
        }
    }
}

TEST(EqualMassTable, PositiveMixtureWhereverTheWeightIsPositive) {
    // Random weights with zero stretches: the mixture is never zero where q is not (the table
    // is unbiased for anything q covers), and the densities are normalized.
    std::mt19937_64 rng(29);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int trial = 0; trial < 300; ++trial) {
        const int n = 2 + int(unit(rng) * 40);
        std::vector<double> x{380}, q;
        for (int i = 1; i < n; ++i)
            x.push_back(x.back() + (unit(rng) < 0.2 ? 0.001 : 0.01 + 30 * unit(rng)));
        for (int i = 0; i < n; ++i)
            q.push_back(unit(rng) < 0.4 ? 0.0 : std::pow(10.0, -6 + 12 * unit(rng)));
        if (MassBetween(x, q, x.front(), x.back()) <= 0) {
            EXPECT_THROW(wt::EqualMassTable(x, q), wt::TableError);
            continue;
        }
        const wt::Table t = wt::EqualMassTable(x, q);
        EXPECT_EQ(t.grid.front(), x.front());
        EXPECT_EQ(t.grid.back(), x.back());
        for (size_t i = 0; i < x.size(); ++i)
            if (q[i] > 0)
                EXPECT_GT(wt::MixturePdf(t, x[i]), 0) << "trial " << trial << " node " << i;
        for (int k = 0; k < 4; ++k)
            EXPECT_DOUBLE_EQ(t.cdf[k].back(), 1.0);
    }
}

TEST(EqualMassTable, RefusesWhatThePythonReferenceRefuses) {
    const double inf = std::numeric_limits<double>::infinity();
    const std::vector<std::pair<std::vector<double>, std::vector<double>>> bad = {
        {{380}, {1}},                      // one node
        {{380, 380}, {1, 1}},              // not increasing
        {{380, 400}, {0, 0}},              // no mass
        {{380, 400}, {1, -1}},             // negative
        {{380, 400}, {1, std::nan("")}},   // NaN
        {{380, inf}, {1, 1}},              // infinite node
        {{380, 400, 420}, {1, 1}},         // one weight short
    };
    for (const auto &[x, q] : bad) {
        try {
            wt::EqualMassTable(x, q, "the lamp");
            ADD_FAILURE() << "accepted a bad weight (" << x.size() << " nodes)";
        } catch (const wt::TableError &e) {
            EXPECT_EQ(std::string(e.what()).rfind("the lamp: ", 0), 0u) << e.what();
            EXPECT_FALSE(e.reason().empty());
        }
    }
}

TEST(EqualMassTable, StratifiedTableWeighsTheSpectrumOnTheUnionOfNodes) {
    // A spectrum on 5 nm nodes times a weight on 1 nm nodes: the table's grid holds both
    // (inside the range), and its mixture is s * w normalized.
    std::vector<double> sx, sv, wx, wv;
    for (double l = 350; l <= 850; l += 5) {
        sx.push_back(l);
        sv.push_back(1 + std::sin(l / 17));
    }
    for (double l = 360; l <= 830; l += 1) {
        wx.push_back(l);
        wv.push_back(std::exp(-std::pow((l - 555) / 80, 2)));
    }
    const wt::WeightedNodes w = wt::WeightedSpectrum(sx, sv, wx, wv, 380, 780);
    EXPECT_EQ(w.x.front(), 380);
    EXPECT_EQ(w.x.back(), 780);
    EXPECT_EQ(w.x.size(), 401u);  // every 1 nm node; the 5 nm nodes are among them
    for (size_t i = 0; i < w.x.size(); ++i)
        EXPECT_DOUBLE_EQ(w.q[i], wt::detail::Interp(sx, sv, w.x[i], 0, 0) *
                                     wt::detail::Interp(wx, wv, w.x[i], 0, 0));
    const wt::Table t = wt::StratifiedTable(sx, sv, wx, wv, 380, 780, "lamp");
    const wt::Table u = wt::EqualMassTable(w.x, w.q, "lamp");
    EXPECT_EQ(t.grid, u.grid);
    // No weight: the spectrum alone, on its own nodes and the range's ends.
    const wt::WeightedNodes s = wt::WeightedSpectrum(sx, sv, {}, {}, 381, 779);
    EXPECT_EQ(s.x.size(), 79u + 2u);  // 385, 390, ..., 775 and the ends
    EXPECT_THROW(wt::WeightedSpectrum(sx, sv, {}, {}, 500, 400), wt::TableError);
}
