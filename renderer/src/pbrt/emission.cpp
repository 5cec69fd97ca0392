#include <pbrt/emission.h>

#include <pbrt/lights.h>
#include <pbrt/materials.h>
#include <pbrt/scene.h>
#include <pbrt/util/output_path.h>
#include <pbrt/util/spectrum.h>

#include <pbrt/util/cie_data.h>

#include <wavelength_table.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

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
    // Lights that share a spectrum (the triangles of an area light; equal tables, which
    // Light::ShareEqualSpectra merges) are summed first: each distinct spectrum is then
    // evaluated once, however many triangles emit it.
    struct Group {
        const Spectrum *spectrum;
        double k = 0;          // sum of PowerFactor() * Scale() over its lights
        const Light *largest;  // the light with the largest share (named in errors)
        double largestK = 0;
    };
    std::vector<Group> groups;
    std::map<const Spectrum *, size_t> index;
    for (const Light &l : scene.lights) {
        const double k = l.PowerFactor() * double(l.Scale());
        if (!std::isfinite(k))
            throw PbrtError(l.Loc(), "this light's emitted power is not finite (its \"scale\" or "
                                     "\"power\", its area or the scene's extent overflows)");
        if (k == 0) continue;
        auto [it, added] = index.emplace(l.EmissionSpectrum().get(), groups.size());
        if (added) groups.push_back(Group{l.EmissionSpectrum().get(), 0, &l, 0});
        Group &g = groups[it->second];
        g.k += k;
        if (k > g.largestK) {
            g.largest = &l;
            g.largestK = k;
        }
    }
    std::vector<double> grid{double(Lambda_min), double(Lambda_max)};
    bool smooth = false;
    for (const Group &g : groups) {
        if (const std::vector<Float> *nodes = Nodes(*g.spectrum)) {
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
    const Group *largest = nullptr;
    for (const Group &g : groups) {
        if (!largest || g.k > largest->k) largest = &g;
        for (size_t i = 0; i < grid.size(); ++i) {
            const double v = g.k * double((*g.spectrum)(Float(grid[i])));
            if (!std::isfinite(v))
                throw PbrtError(g.largest->Loc(),
                                "this light's emitted power is not finite at " +
                                    std::to_string(int(grid[i])) + " nm (its \"scale\" or "
                                    "\"power\", its area or the scene's extent overflows)");
            out.values[i] += v;
        }
    }
    bool positive = false;
    for (double v : out.values) {
        if (!std::isfinite(v))
            throw PbrtError(largest->largest->Loc(),
                            "the scene's total emitted power is not finite: this light and the "
                            "others together overflow (a \"scale\" or \"power\" too large)");
        positive = positive || v > 0;
    }
    if (!positive)
        throw PbrtError(scene.lights.front().Loc(),
                        "no light of the scene emits between " + std::to_string(int(Lambda_min)) +
                            " and " + std::to_string(int(Lambda_max)) +
                            " nm: this light and every other has zero power (\"scale\" 0?)");
    return out;
}

// ---- Emission sampling ------------------------------------------------------------------

const std::vector<std::string> &EmissionWeights() {
    static const std::vector<std::string> w{"spd", "luminance", "xyz"};
    return w;
}

void EmissionWeightCurve(const std::string &weight, std::vector<double> *x, std::vector<double> *w) {
    x->clear();
    w->clear();
    if (weight == "spd") return;
    for (int i = 0; i < cie::kNumSamples; ++i) {
        x->push_back(double(cie::kLambdaMin + i));
        w->push_back(weight == "luminance" ? cie::CIE_Y[i]
                                           : (cie::CIE_X[i] + cie::CIE_Y[i]) + cie::CIE_Z[i]);
    }
}

EmissionTable SceneEmissionTable(const Scene &scene, const std::string &weight) {
    const std::vector<std::string> &known = EmissionWeights();
    if (std::find(known.begin(), known.end(), weight) == known.end())
        throw PbrtError("unknown emission weight \"" + weight + "\" (expected spd, luminance or xyz)");
    const auto start = std::chrono::steady_clock::now();
    EmissionSpectrum e = SceneEmissionSpectrum(scene);
    // The weight at the CMFs' 1 nm nodes (none for "spd": the spectrum alone).
    std::vector<double> wx, wv;
    EmissionWeightCurve(weight, &wx, &wv);
    EmissionTable t;
    t.weight = weight;
    t.emissionNodes = e.lambdas.size();
    try {
        t.table = std::make_shared<const wavelength_table::Table>(wavelength_table::StratifiedTable(
            e.lambdas, e.values, wx, wv, double(Lambda_min), double(Lambda_max),
            "the scene's emission times the \"" + weight + "\" weight"));
    } catch (const wavelength_table::TableError &err) {
        // Only a weight without mass gets here (Phi is positive somewhere and every weight
        // is positive on 360..830 nm), which the checks above make unreachable in practice.
        throw PbrtError(scene.lights.front().Loc(), std::string("emission sampling: ") + err.what());
    }
    t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return t;
}

void WriteEmissionSpectrum(const std::string &path, const EmissionSpectrum &s) {
    WriteAtomically(path, [&](FILE *f) {
        bool ok = std::fprintf(f,
                               "# The scene's total emitted spectral power (design section 5.6): "
                               "lambda (nm), power per nm\n") > 0;
        for (size_t i = 0; i < s.lambdas.size() && ok; ++i)
            ok = std::fprintf(f, "%.17g %.17g\n", s.lambdas[i], s.values[i]) > 0;
        return ok;
    });
}

void WriteEmissionTable(const std::string &path, const EmissionTable &t, const std::string &source) {
    const wavelength_table::Table &table = *t.table;
    WriteAtomically(path, [&](FILE *f) {
        bool ok = std::fprintf(f,
                               "# method: %s\n"
                               "# source: %s (the scene's total emitted spectral power, design "
                               "section 5.6)\n"
                               "# stratified sampling of the scene's emission%s: four equal-mass "
                               "bands (design section 1.7), as pbrt --wavelength-sampling emission "
                               "samples it\n"
                               "lambda_nm,pdf0,pdf1,pdf2,pdf3\n",
                               t.weight.c_str(), source.c_str(),
                               t.weight == "spd" ? ""
                               : t.weight == "luminance" ? " times ybar"
                                                         : " times xbar + ybar + zbar") > 0;
        for (size_t i = 0; i < table.grid.size() && ok; ++i)
            ok = std::fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g\n", table.grid[i], table.pdf[0][i],
                              table.pdf[1][i], table.pdf[2][i], table.pdf[3][i]) > 0;
        return ok;
    });
}

}  // namespace pbrt

namespace pbrt {

namespace {

// The mean of a reflectance texture at the wavelengths lambda0 .. lambda0 + 3.
std::array<double, NSpectrumSamples> TextureMean(const SpectrumTexture &tex, Float lambda0) {
    Float lam[NSpectrumSamples], pdf[NSpectrumSamples];
    for (int i = 0; i < NSpectrumSamples; ++i) {
        lam[i] = std::min(lambda0 + Float(i), Lambda_max);
        pdf[i] = 1;
    }
    SampledWavelengths lambda = SampledWavelengths::FromArrays(lam, pdf);
    std::array<double, NSpectrumSamples> sum{};
    if (SpectrumHandle s = tex.Constant()) {
        for (int i = 0; i < NSpectrumSamples; ++i) sum[i] = double((*s)(lam[i]));
        return sum;
    }
    constexpr int n = 32;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            TextureEvalContext ctx;
            ctx.uv = Point2f((x + 0.5f) / n, (y + 0.5f) / n);
            ctx.p = Point3f(ctx.uv.x, ctx.uv.y, 0);
            SampledSpectrum v = tex.Evaluate(ctx, lambda);
            for (int i = 0; i < NSpectrumSamples; ++i) sum[i] += double(v[i]) / (n * n);
        }
    return sum;
}

const SpectrumTexture *Reflectance(const Material &m) {
    if (auto *d = std::get_if<DiffuseMaterial>(&m)) return d->reflectance.get();
    if (auto *c = std::get_if<CoatedDiffuseMaterial>(&m)) return c->reflectance.get();
    if (auto *c = std::get_if<ConductorMaterial>(&m)) return c->reflectance.get();
    return nullptr;
}

}  // namespace

MaterialReflectances SceneMaterialReflectances(const Scene &scene) {
    MaterialReflectances out;
    const int n = int(Lambda_max - Lambda_min) + 1;
    for (size_t m = 0; m < scene.materials.size(); ++m) {
        if (m >= scene.materialUsed.size() || !scene.materialUsed[m]) continue;
        const SpectrumTexture *tex = Reflectance(scene.materials[m]);
        if (!tex) continue;
        std::vector<double> v(static_cast<size_t>(n));
        for (int i = 0; i < n; i += NSpectrumSamples) {
            auto r = TextureMean(*tex, Lambda_min + Float(i));
            for (int k = 0; k < NSpectrumSamples && i + k < n; ++k) v[size_t(i + k)] = r[k];
        }
        if (*std::max_element(v.begin(), v.end()) <= 0) continue;
        // A reflectance already listed (several materials of the same colour) counts once.
        if (std::find(out.values.begin(), out.values.end(), v) != out.values.end()) continue;
        std::string label = scene.materialWhere[m];
        std::replace(label.begin(), label.end(), ',', ' ');
        out.labels.push_back(label);
        out.values.push_back(std::move(v));
    }
    if (out.labels.empty())
        throw PbrtError("no shape of the scene uses a material with a non-zero diffuse "
                        "reflectance (diffuse, coateddiffuse, or conductor with \"reflectance\")");
    return out;
}

void WriteMaterialReflectances(const std::string &path, const MaterialReflectances &m) {
    WriteAtomically(path, [&](FILE *f) {
        bool ok = std::fprintf(f, "# The diffuse reflectances of the scene's materials (design section 5.6)\n"
                                  "lambda_nm") > 0;
        for (const std::string &l : m.labels) ok = ok && std::fprintf(f, ",%s", l.c_str()) > 0;
        ok = ok && std::fputc('\n', f) != EOF;
        const int n = int(Lambda_max - Lambda_min) + 1;
        for (int i = 0; i < n && ok; ++i) {
            ok = std::fprintf(f, "%d", int(Lambda_min) + i) > 0;
            for (const auto &v : m.values) ok = ok && std::fprintf(f, ",%.17g", v[size_t(i)]) > 0;
            ok = ok && std::fputc('\n', f) != EOF;
        }
        return ok;
    });
}

}  // namespace pbrt
