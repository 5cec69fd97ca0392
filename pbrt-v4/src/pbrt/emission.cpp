#include <pbrt/emission.h>

#include <pbrt/lights.h>
#include <pbrt/scene.h>
#include <pbrt/util/spectrum.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace pbrt {

namespace {

// The nodes between which s is linear, or nullptr when it is not piecewise linear.
const std::vector<Float> *Nodes(const Spectrum &s) {
    if (auto *p = dynamic_cast<const IndexedPiecewiseLinearSpectrum *>(&s)) return &p->Lambdas();
    if (auto *p = dynamic_cast<const PiecewiseLinearSpectrum *>(&s)) return &p->Lambdas();
    return nullptr;
}

}  // namespace

EmissionSpectrum SceneEmissionSpectrum(const Scene &scene) {
    if (scene.lights.empty())
        throw PbrtError("the scene has no emitters (no LightSource and no shape with an "
                        "AreaLightSource), so it emits no spectral power");
    std::vector<double> grid{double(Lambda_min), double(Lambda_max)};
    bool smooth = false;
    for (const Light &l : scene.lights) {
        if (const std::vector<Float> *nodes = Nodes(*l.EmissionSpectrum())) {
            for (Float x : *nodes)
                if (x >= Lambda_min && x <= Lambda_max) grid.push_back(double(x));
        } else {
            smooth = true;
        }
    }
    if (smooth)
        for (int x = int(Lambda_min); x <= int(Lambda_max); ++x) grid.push_back(double(x));
    std::sort(grid.begin(), grid.end());
    grid.erase(std::unique(grid.begin(), grid.end()), grid.end());

    EmissionSpectrum out;
    out.lambdas = grid;
    out.values.assign(grid.size(), 0.0);
    for (const Light &l : scene.lights) {
        double k = l.PowerFactor() * double(l.Scale());
        if (k == 0) continue;
        const Spectrum &s = *l.EmissionSpectrum();
        for (size_t i = 0; i < grid.size(); ++i) out.values[i] += k * double(s(Float(grid[i])));
    }
    bool positive = false;
    for (double v : out.values) {
        if (!std::isfinite(v))
            throw PbrtError("the scene's total emitted power is not finite (a light's scale, "
                            "power or the scene's extent overflows)");
        positive = positive || v > 0;
    }
    if (!positive)
        throw PbrtError("the scene's lights emit no power between " + std::to_string(int(Lambda_min)) +
                        " and " + std::to_string(int(Lambda_max)) + " nm (every \"scale\" is 0?)");
    return out;
}

void CheckOutputFilePath(const std::string &path) {
    namespace fs = std::filesystem;
    auto fail = [&](const std::string &why) { return PbrtError("\"" + path + "\": " + why); };
    if (path.empty()) throw fail("empty output file name");
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw fail("is a directory; the output needs a file name");
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty()) dir = ".";
    if (!fs::is_directory(dir, ec)) throw fail("the output directory does not exist");
    if (access(dir.c_str(), W_OK) != 0) throw fail("the output directory is not writable");
}

void WriteEmissionSpectrum(const std::string &path, const EmissionSpectrum &s) {
    std::string tmp = path + ".tmp" + std::to_string(getpid());
    FILE *f = std::fopen(tmp.c_str(), "w");
    if (!f) throw PbrtError("\"" + path + "\": cannot be written");
    bool ok = std::fprintf(f,
                           "# The scene's total emitted spectral power (design section 5.6): "
                           "lambda (nm), power per nm\n") > 0;
    for (size_t i = 0; i < s.lambdas.size() && ok; ++i)
        ok = std::fprintf(f, "%.17g %.17g\n", s.lambdas[i], s.values[i]) > 0;
    ok = (std::fclose(f) == 0) && ok;
    std::error_code ec;
    if (ok) std::filesystem::rename(tmp, path, ec);
    if (!ok || ec) {
        std::filesystem::remove(tmp, ec);
        throw PbrtError("\"" + path + "\": writing failed");
    }
}

}  // namespace pbrt
