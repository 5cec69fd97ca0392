// Pixel filters: exact filter importance sampling (pdf = f / integral, constant weight) and
// the sample / pdf / invert triple.
#include <pbrt/filters.h>

#include <pbrt/util/paramdict.h>
#include <pbrt/util/rng.h>

#include <gtest/gtest.h>

using namespace pbrt;

namespace {
std::vector<Filter> AllFilters() {
    return {Filter::Box({0.5f, 0.5f}), Filter::Box({1.5f, 0.75f}), Filter::Triangle({2, 2}),
            Filter::Triangle({1, 1.5f}), Filter::Gaussian({1.5f, 1.5f}, 0.5f), Filter::Gaussian({2, 1}, 0.7f)};
}
}  // namespace

TEST(Filter, IntegralMatchesQuadrature) {
    for (const Filter &f : AllFilters()) {
        Vector2f r = f.Radius();
        const int n = 800;
        double s = 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                s += f.Evaluate({-r.x + 2 * r.x * (i + 0.5f) / n, -r.y + 2 * r.y * (j + 0.5f) / n});
        s *= 4 * r.x * r.y / (double(n) * n);
        EXPECT_NEAR(s, f.Integral(), 2e-3 * f.Integral()) << f.Description();
    }
}

TEST(Filter, SamplesFollowTheFilter) {
    for (const Filter &f : AllFilters()) {
        RNG rng(1);
        for (int i = 0; i < 2000; ++i) {
            Point2f u(rng.UniformFloat(), rng.UniformFloat());
            FilterSample fs = f.Sample(u);
            EXPECT_LE(std::abs(fs.p.x), f.Radius().x);
            EXPECT_LE(std::abs(fs.p.y), f.Radius().y);
            // pdf = f / integral, so the weight f / pdf is the integral for every sample.
            Float pdf = f.PDF(fs.p);
            if (f.Evaluate(fs.p) > 1e-4f * f.Integral()) {
                EXPECT_NEAR(f.Evaluate(fs.p) / pdf, f.Integral(), 1e-3 * f.Integral()) << f.Description();
                EXPECT_NEAR(fs.weight, f.Integral(), 1e-5 * f.Integral());
            }
            Point2f back = f.InvertSample(fs.p);
            EXPECT_NEAR(back.x, u.x, 1e-3) << f.Description();
            EXPECT_NEAR(back.y, u.y, 1e-3) << f.Description();
        }
        // Monte Carlo check of the pdf's normalization: E_uniform[pdf] * area = 1.
        double s = 0;
        int n = 200000;
        Vector2f r = f.Radius();
        for (int i = 0; i < n; ++i)
            s += f.PDF({(2 * rng.UniformFloat() - 1) * r.x, (2 * rng.UniformFloat() - 1) * r.y});
        EXPECT_NEAR(s / n * 4 * r.x * r.y, 1, 0.02) << f.Description();
    }
}

TEST(Filter, CreateFromParameters) {
    ParsedParameter p;
    p.type = "float";
    p.name = "xradius";
    p.floats = {1.25};
    ParameterDictionary dict({p});
    Filter f = Filter::Create("triangle", dict, FileLoc{"scene.pbrt", 3, 1});
    EXPECT_FLOAT_EQ(f.Radius().x, 1.25f);
    EXPECT_FLOAT_EQ(f.Radius().y, 2.f) << "pbrt-v4's default triangle radius";
    EXPECT_FLOAT_EQ(Filter::Create("box", ParameterDictionary(), FileLoc{}).Radius().x, 0.5f);
    try {
        Filter::Create("mitchell-ish", ParameterDictionary(), FileLoc{"scene.pbrt", 7, 2});
        FAIL() << "unknown filter accepted";
    } catch (const PbrtError &e) {
        EXPECT_NE(std::string(e.what()).find("scene.pbrt:7"), std::string::npos) << e.what();
    }
}
