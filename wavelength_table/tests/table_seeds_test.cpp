// The table fuzzer's seeds (wavelength_table/fuzz/corpus/table) and every input that ever crashed it
// (wavelength_table/fuzz/regressions/table), run through the reader in the ordinary build: the seeds
// are valid tables, and every file either reads or throws TableError naming itself.
#include <wavelength_table.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace wt = wavelength_table;
namespace fs = std::filesystem;

namespace {
std::vector<fs::path> FilesIn(const std::string &dir) {
    std::vector<fs::path> files;
    if (!fs::is_directory(dir)) return files;
    for (const auto &e : fs::directory_iterator(dir))
        if (e.is_regular_file() && e.path().filename() != "README.md") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}
}  // namespace

TEST(TableSeeds, SeedsAreValidTables) {
    auto seeds = FilesIn(std::string(WT_FUZZ_DIR) + "/corpus/table");
    ASSERT_GE(seeds.size(), 3u);
    for (const fs::path &f : seeds) {
        try {
            wt::Table t = wt::LoadTable(f.string());
            EXPECT_GE(t.grid.size(), 2u) << f;
            for (int k = 0; k < wt::kNumDensities; ++k) EXPECT_EQ(t.cdf[k].back(), 1.0) << f;
        } catch (const wt::TableError &e) {
            ADD_FAILURE() << f << ": " << e.what();
        }
    }
}

TEST(TableSeeds, RegressionsReadOrFailWithTheirName) {
    for (const fs::path &f : FilesIn(std::string(WT_FUZZ_DIR) + "/regressions/table")) {
        try {
            wt::Table t = wt::LoadTable(f.string());
            // As table_fuzz checks: the four samples of any u lie on the grid's range.
            for (double u : {0.0, 0.25, 0.5, 0.999999}) {
                double lambda[wt::kNumDensities], pdf[wt::kNumDensities];
                wt::SampleFour(t, u, lambda, pdf);
                for (int k = 0; k < wt::kNumDensities; ++k) {
                    EXPECT_GE(lambda[k], t.grid.front()) << f << " u=" << u << " k=" << k;
                    EXPECT_LE(lambda[k], t.grid.back()) << f << " u=" << u << " k=" << k;
                }
            }
        } catch (const wt::TableError &e) {
            EXPECT_EQ(std::string(e.what()).rfind(f.string(), 0), 0u) << e.what();
        }
    }
}
