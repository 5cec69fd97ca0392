#include <pbrt/emission.h>

#include <pbrt/lights.h>
#include <pbrt/materials.h>
#include <pbrt/scene.h>
#include <pbrt/util/output_path.h>
#include <pbrt/util/spectrum.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

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

// Writes `path` through `body` (which returns false when a write failed) under a temporary
// name, renamed into place only when every write succeeded: never a partial file.
template <typename Body>
static void WriteAtomically(const std::string &path, Body body) {
    TemporaryOutput tmp(path);  // removed on an error or a SIGTERM (util/output_path.h)
    FILE *f = std::fopen(tmp.Path().c_str(), "w");
    if (!f) throw PbrtError("\"" + path + "\": cannot be written");
    bool ok = body(f);
    ok = (std::fclose(f) == 0) && ok;
    if (!ok || !tmp.Commit()) throw PbrtError("\"" + path + "\": writing failed");
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
