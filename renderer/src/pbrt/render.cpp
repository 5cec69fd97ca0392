#include <pbrt/render.h>

#include <pbrt/guiding.h>
#include <pbrt/scene.h>
#include <pbrt/util/lowdiscrepancy.h>
#include <pbrt/util/progress.h>
#include <pbrt/util/rng.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <sys/resource.h>

#include <atomic>
#include <cmath>
#include <memory>

namespace pbrt {

double ProcessCPUSeconds() {
    rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

ImageMetadata RenderMetadata(const Scene &scene, const RenderStats &stats) {
    ImageMetadata m;
    m.ints["samplesPerPixel"] = scene.sampler.SamplesPerPixel();
    m.floats["renderTimeSeconds"] = float(stats.wallSeconds);
    m.floats["renderCPUSeconds"] = float(stats.cpuSeconds);
    m.floats["meanPathDepth"] = stats.paths ? float(double(stats.scatterings) / double(stats.paths)) : 0.f;
    if (stats.wavelengthRepeats > 1) m.ints["wavelengthRepeats"] = stats.wavelengthRepeats;
    if (scene.wavelengthNet) m.ints["wavelengthNet"] = 1;
    if (scene.wavelengthSeed) m.strings["wavelengthSeed"] = std::to_string(*scene.wavelengthSeed);
    m.strings["seed"] = std::to_string(scene.sampler.Seed());
    // pbrt-v4's camera matrices (cameras.h), row by row.
    auto rows = [](const SquareMatrix4 &a) {
        std::array<float, 16> v;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) v[size_t(4 * i + j)] = float(a.m[i][j]);
        return v;
    };
    m.matrices["worldToCamera"] = rows(scene.camera->CameraFromWorld());
    m.matrices["worldToNDC"] = rows(scene.camera->NDCFromWorld());
    m.strings["wavelengthSampler"] = scene.wavelengths.Name();
    m.float2s["wavelengthRange"] = {float(scene.wavelengths.MinLambda()), float(scene.wavelengths.MaxLambda())};
    if (const TableWavelengthSampler *t = scene.wavelengths.Table()) {
        if (!t->emissionWeight.empty()) {
            // Emission sampling: a table built from the scene, not read from a file.
            m.strings["wavelengthEmissionWeight"] = t->emissionWeight;
        } else {
            m.strings["wavelengthTable"] = t->file;
            m.strings["wavelengthTableSHA256"] = t->sha256;
            m.floats["wavelengthDefensiveShare"] = float(t->share);
        }
    }
    return m;
}

namespace {

bool IsFinite(const SampledSpectrum &L) {
    for (int i = 0; i < NSpectrumSamples; ++i)
        if (!std::isfinite(L[i])) return false;
    return true;
}

// Names the scene statement of the first surface the camera ray hits, so that the user can
// find what produces the NaN or infinity (once per statement: Warning drops repeats).
void WarnNonFinite(const Scene &scene, const Ray &cameraRay) {
    SurfaceInteraction si;
    if (scene.accel->Intersect(cameraRay, &si) && si.shapeLoc && !si.shapeLoc->filename.empty())
        Warning(*si.shapeLoc, "paths whose camera ray first hits this shape returned a "
                              "non-finite radiance value; those samples were replaced by 0");
    else
        Warning("paths that first hit no shape (lights at infinity) returned a non-finite "
                "radiance value; those samples were replaced by 0");
}

}  // namespace

RenderStats Render(const Scene &scene, int nThreads, bool quiet, int wavelengthRepeats,
                   const std::function<void(int sppDone)> &afterPass, const WavelengthGuide *guide) {
    std::unique_ptr<tbb::global_control> limit;
    if (nThreads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(nThreads));

    RGBFilm &film = *scene.film;
    const Bounds2i bounds = film.PixelBounds();
    const int spp = scene.sampler.SamplesPerPixel();
    const int maxDepth = scene.integrator.maxDepth;
    constexpr int kTile = 16;
    const int nx = (bounds.Width() + kTile - 1) / kTile, ny = (bounds.Height() + kTile - 1) / kTile;

    const int repeats = std::max(1, wavelengthRepeats);
    ProgressReporter progress(int64_t(bounds.Area()) * spp, "Rendering", quiet);
    double cpu0 = ProcessCPUSeconds();
    std::atomic<uint64_t> scatterings{0};

    // One pass of every sample, or passes of 1, 1, 2, 4, ..., 64 samples when afterPass is given.
    for (int s0 = 0, passSize = 1; s0 < spp;) {
        const int s1 = afterPass ? std::min(spp, s0 + passSize) : spp;
        tbb::parallel_for(tbb::blocked_range<int>(0, nx * ny, 1), [&](const tbb::blocked_range<int> &range) {
            pbrt::Sampler sampler = scene.sampler;
            uint64_t depthSum = 0;
            for (int tile = range.begin(); tile != range.end(); ++tile) {
                int x0 = bounds.pMin.x + (tile % nx) * kTile, y0 = bounds.pMin.y + (tile / nx) * kTile;
                int x1 = std::min(x0 + kTile, bounds.pMax.x), y1 = std::min(y0 + kTile, bounds.pMax.y);
                for (int y = y0; y < y1; ++y)
                    for (int x = x0; x < x1; ++x) {
                        Point2i p{x, y};
                        // Wavelength guiding: the pixel's own table (design §1.8).
                        const WavelengthSampler &wavelengths = guide ? guide->SamplerAt(p) : scene.wavelengths;
                        std::optional<WavelengthNet> net;
                        if (scene.wavelengthNet) net.emplace(p, scene.sampler.Seed());
                        for (int s = s0; s < s1; ++s) {
                            RGB rgb(0, 0, 0);
                            FilterSample fs;
                            for (int r = 0; r < repeats; ++r) {
                                // A repeat replays the sample's numbers from its start; only the
                                // wavelength number is shifted (r = 0: the sample as it is).
                                sampler.StartPixelSample(p, s);
                                Point2f uFilter = sampler.GetPixel2D();
                                // Four wavelengths from one number: the seam for other samplers.
                                Float uLambda = sampler.Get1D();
                                // Both drawn from the sampler either way, so that the path's
                                // dimensions are the same with and without the net.
                                Float uLight = 0;
                                if (net) net->Sample(s, &uFilter, &uLambda, &uLight);
                                // Drawn after the sampler's (and the net's) so that every other
                                // number of the path stays as it is.
                                if (scene.wavelengthSeed)
                                    uLambda = ToUnitFloat(uint32_t(
                                        HashInts({uint64_t(uint32_t(x)), uint64_t(uint32_t(y)), uint64_t(s),
                                                  *scene.wavelengthSeed, 0x776c73ULL}) >> 32));
                                // Film position from the filter's distribution around the pixel centre.
                                fs = scene.disablePixelJitter ? FilterSample{Point2f(0, 0), 1}
                                                              : scene.filter.Sample(uFilter);
                                Point2f pFilm(x + 0.5f + fs.p.x, y + 0.5f + fs.p.y);
                                if (scene.disableWavelengthJitter) uLambda = 0.5f;
                                if (r > 0) {
                                    uLambda += Float(r) / Float(repeats);
                                    uLambda -= std::floor(uLambda);
                                }
                                SampledWavelengths lambda = wavelengths.Sample(uLambda);
                                Point2f uLens = sampler.Get2D();
                                Ray ray = scene.camera->GenerateRay(pFilm, uLens);
                                int depth = 0;
                                SampledSpectrum L = PathLi(scene, ray, lambda, sampler, maxDepth, &depth, nullptr,
                                                           net ? &uLight : nullptr);
                                depthSum += uint64_t(depth);
                                if (!IsFinite(L)) {
                                    WarnNonFinite(scene, ray);
                                    L = SampledSpectrum(0);
                                }
                                RGB c = film.ToRGB(L, lambda);
                                if (film.IsSpectral()) film.AddSpectralSample(p, L, lambda, fs.weight / Float(repeats));
                                if (repeats == 1) rgb = c;
                                else rgb += c / Float(repeats);
                            }
                            film.AddSample(p, rgb, fs.weight);
                        }
                    }
                progress.Update(int64_t(x1 - x0) * (y1 - y0) * (s1 - s0));
            }
            scatterings += depthSum;
        });
        if (afterPass) afterPass(s1);
        if (s0 > 0) passSize = std::min(2 * passSize, 64);
        s0 = s1;
    }
    progress.Done();

    RenderStats stats;
    stats.wallSeconds = progress.ElapsedSeconds();
    stats.cpuSeconds = ProcessCPUSeconds() - cpu0;
    stats.paths = uint64_t(bounds.Area()) * uint64_t(spp) * uint64_t(repeats);
    stats.scatterings = scatterings.load();
    stats.wavelengthRepeats = repeats;
    return stats;
}

}  // namespace pbrt
