// libFuzzer target: the wavelength-table reader of wavelength_table.h (both file layouts).
// Every input must either give a table the sampler can use or throw TableError naming
// FILE:LINE. For a table that loads, sampling, densities and inversion are checked too:
// samples inside the grid, finite non-negative densities, Invert(Sample(u)) close to u.
#include <wavelength_table.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

namespace wt = wavelength_table;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    std::istringstream in(std::string(reinterpret_cast<const char *>(data), size));
    wt::Table t;
    try {
        t = wt::ParseTable(in, "fuzz.csv");
    } catch (const wt::TableError &e) {
        if (std::string(e.what()).rfind("fuzz.csv", 0) != 0) std::abort();  // FILE first
        return 0;
    }
    const double lo = t.grid.front(), hi = t.grid.back();
    for (double u : {0.0, 0.25, 0.5, 0.999999}) {
        double lambda[wt::kNumDensities], pdf[wt::kNumDensities];
        wt::SampleFour(t, u, lambda, pdf);
        for (int k = 0; k < wt::kNumDensities; ++k) {
            if (!(lambda[k] >= lo && lambda[k] <= hi)) std::abort();
            if (!std::isfinite(pdf[k]) || pdf[k] < 0) std::abort();
            double x = wt::Sample(t, k, u);
            double p = wt::Pdf(t, k, x), c = wt::Invert(t, k, x);
            if (!std::isfinite(p) || p < 0 || !(c >= 0 && c <= 1)) std::abort();
        }
        if (!std::isfinite(wt::MixturePdf(t, lo + u * (hi - lo)))) std::abort();
    }
    return 0;
}
