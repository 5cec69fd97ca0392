#include <pbrt/guiding.h>

#include <pbrt/emission.h>
#include <pbrt/integrator.h>
#include <pbrt/render.h>
#include <pbrt/samplers.h>
#include <pbrt/scene.h>
#include <pbrt/util/cie_data.h>
#include <pbrt/util/hash.h>
#include <pbrt/util/output_path.h>
#include <pbrt/util/progress.h>

#include <wavelength_table.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

namespace pbrt {

namespace fs = std::filesystem;

// ---- Kinds of light ---------------------------------------------------------------------------

LightKinds SceneLightKinds(const Scene &scene) {
    // The common grid and every check of the scene's emission (no emitters, no power, a power
    // that is not finite) come from SceneEmissionSpectrum: its nodes are exact for every light.
    const EmissionSpectrum total = SceneEmissionSpectrum(scene);
    LightKinds kinds;
    kinds.lambdas = total.lambdas;
    kinds.kindOfLight.assign(scene.lights.size(), -1);
    kinds.lightLabels.resize(scene.lights.size());
    const size_t n = kinds.lambdas.size();

    // Lights that share a spectrum object (the triangles of one area light, equal tables)
    // first, then spectra equal up to a scale.
    std::map<const Spectrum *, int> kindOfSpectrum;
    std::vector<std::vector<double>> shapes;  // per kind: its spectrum / its peak
    std::vector<double> strongest;            // per kind: the largest light power factor
    for (size_t li = 0; li < scene.lights.size(); ++li) {
        const Light &l = scene.lights[li];
        kinds.lightLabels[li] = l.Loc().ToString();
        const double k = l.PowerFactor() * double(l.Scale());
        if (!(k > 0)) continue;
        const Spectrum *s = l.EmissionSpectrum().get();
        int kind;
        if (auto it = kindOfSpectrum.find(s); it != kindOfSpectrum.end()) {
            kind = it->second;
        } else {
            std::vector<double> v(n);
            double peak = 0;
            for (size_t i = 0; i < n; ++i) {
                v[i] = double((*s)(Float(kinds.lambdas[i])));
                peak = std::max(peak, v[i]);
            }
            kind = -1;
            if (peak > 0) {
                for (double &x : v) x /= peak;
                for (size_t c = 0; c < shapes.size() && kind < 0; ++c) {
                    double diff = 0;
                    for (size_t i = 0; i < n; ++i) diff = std::max(diff, std::abs(shapes[c][i] - v[i]));
                    if (diff <= 1e-6) kind = int(c);
                }
                if (kind < 0) {
                    kind = int(shapes.size());
                    shapes.push_back(std::move(v));
                    kinds.power.emplace_back(n, 0.0);
                    kinds.labels.push_back(l.Loc().ToString());
                    kinds.lights.push_back(0);
                    strongest.push_back(0);
                }
            }
            kindOfSpectrum[s] = kind;
        }
        if (kind < 0) continue;  // emits nothing on 360..830 nm
        kinds.kindOfLight[li] = kind;
        kinds.lights[size_t(kind)] += 1;
        std::vector<double> &p = kinds.power[size_t(kind)];
        for (size_t i = 0; i < n; ++i) p[i] += k * double((*s)(Float(kinds.lambdas[i])));
        if (k > strongest[size_t(kind)]) {
            strongest[size_t(kind)] = k;
            kinds.labels[size_t(kind)] = l.Loc().ToString();
        }
    }
    std::vector<double> yx, yw;
    EmissionWeightCurve("luminance", &yx, &yw);
    for (const std::vector<double> &p : kinds.power) {
        wavelength_table::WeightedNodes q = wavelength_table::WeightedSpectrum(
            kinds.lambdas, p, yx, yw, double(Lambda_min), double(Lambda_max), "a light's luminance");
        double y = wavelength_table::detail::Trapezoid(q.x, q.q);
        // ybar is positive on 360..830 nm, so a kind with power there has luminance; the
        // power's own integral stands in should rounding make it vanish.
        if (!(y > 0)) y = wavelength_table::detail::Trapezoid(kinds.lambdas, p);
        kinds.luminance.push_back(y);
    }
    return kinds;
}

// ---- Clustering -------------------------------------------------------------------------------

namespace {

double Dist2(const std::vector<double> &a, const std::vector<double> &b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
    return s;
}

// Nearest centre of every point (ties: the lower index); returns whether any point moved.
bool Assign(const std::vector<std::vector<double>> &points, const std::vector<std::vector<double>> &centres,
            std::vector<int> *assignment) {
    bool moved = false;
    for (size_t i = 0; i < points.size(); ++i) {
        int best = 0;
        double bestD = Dist2(points[i], centres[0]);
        for (size_t c = 1; c < centres.size(); ++c) {
            double d = Dist2(points[i], centres[c]);
            if (d < bestD) {
                bestD = d;
                best = int(c);
            }
        }
        if ((*assignment)[i] != best) moved = true;
        (*assignment)[i] = best;
    }
    return moved;
}

// Centres as the means of their points; clusters left without points are removed (and the
// assignment renumbered).
void Recentre(const std::vector<std::vector<double>> &points, std::vector<std::vector<double>> *centres,
              std::vector<int> *assignment) {
    const size_t d = points[0].size();
    std::vector<std::vector<double>> sum(centres->size(), std::vector<double>(d, 0.0));
    std::vector<int> count(centres->size(), 0);
    for (size_t i = 0; i < points.size(); ++i) {
        int c = (*assignment)[i];
        count[size_t(c)] += 1;
        for (size_t j = 0; j < d; ++j) sum[size_t(c)][j] += points[i][j];
    }
    std::vector<int> renumber(centres->size(), -1);
    std::vector<std::vector<double>> kept;
    for (size_t c = 0; c < centres->size(); ++c) {
        if (count[c] == 0) continue;
        for (double &v : sum[c]) v /= count[c];
        renumber[c] = int(kept.size());
        kept.push_back(std::move(sum[c]));
    }
    for (int &a : *assignment) a = renumber[size_t(a)];
    *centres = std::move(kept);
}

void Lloyd(const std::vector<std::vector<double>> &points, std::vector<std::vector<double>> *centres,
           std::vector<int> *assignment) {
    for (int iter = 0; iter < 100; ++iter) {
        bool moved = Assign(points, *centres, assignment);
        Recentre(points, centres, assignment);
        if (!moved) break;
    }
}

}  // namespace

MixtureClusters ClusterMixtures(const std::vector<std::vector<double>> &points, int maxClusters,
                                double mergeDistance) {
    if (points.empty()) throw PbrtError("clustering: no mixtures");
    if (maxClusters < 1) throw PbrtError("clustering: at least one cluster is needed");
    const size_t d = points[0].size();
    for (const auto &p : points)
        if (p.size() != d || d == 0) throw PbrtError("clustering: mixtures of different sizes");
    const double merge2 = mergeDistance * mergeDistance;

    // Seeding: the point nearest the mean, then the farthest points.
    std::vector<double> mean(d, 0.0);
    for (const auto &p : points)
        for (size_t j = 0; j < d; ++j) mean[j] += p[j] / double(points.size());
    size_t first = 0;
    for (size_t i = 1; i < points.size(); ++i)
        if (Dist2(points[i], mean) < Dist2(points[first], mean)) first = i;
    std::vector<std::vector<double>> centres{points[first]};
    std::vector<double> nearest(points.size());
    for (size_t i = 0; i < points.size(); ++i) nearest[i] = Dist2(points[i], centres[0]);
    while (int(centres.size()) < maxClusters) {
        size_t far = 0;
        for (size_t i = 1; i < points.size(); ++i)
            if (nearest[i] > nearest[far]) far = i;
        if (!(nearest[far] >= merge2) || nearest[far] == 0) break;
        centres.push_back(points[far]);
        for (size_t i = 0; i < points.size(); ++i) nearest[i] = std::min(nearest[i], Dist2(points[i], centres.back()));
    }

    std::vector<int> assignment(points.size(), -1);
    Lloyd(points, &centres, &assignment);
    // Merging: the closest two centres while they are closer than mergeDistance.
    while (centres.size() > 1) {
        size_t a = 0, b = 0;
        double best = merge2;
        for (size_t i = 0; i < centres.size(); ++i)
            for (size_t j = i + 1; j < centres.size(); ++j) {
                double dd = Dist2(centres[i], centres[j]);
                if (dd < best) {
                    best = dd;
                    a = i;
                    b = j;
                }
            }
        if (a == b) break;
        for (int &x : assignment)
            if (x == int(b)) x = int(a);
        Recentre(points, &centres, &assignment);  // b is empty now: removed
        Lloyd(points, &centres, &assignment);
    }

    // Largest cluster first (ties: the order found).
    std::vector<int> count(centres.size(), 0);
    for (int a : assignment) count[size_t(a)] += 1;
    std::vector<size_t> order(centres.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return count[x] > count[y]; });
    std::vector<int> rank(centres.size());
    MixtureClusters out;
    for (size_t r = 0; r < order.size(); ++r) {
        rank[order[r]] = int(r);
        out.centres.push_back(centres[order[r]]);
        out.count.push_back(count[order[r]]);
    }
    out.assignment.reserve(assignment.size());
    for (int a : assignment) out.assignment.push_back(rank[size_t(a)]);
    return out;
}

// ---- Tables -----------------------------------------------------------------------------------

namespace {

std::vector<double> Normalized(const std::vector<double> &x, std::vector<double> v, const char *what) {
    const double mass = wavelength_table::detail::Trapezoid(x, v);
    if (!(mass > 0) || !std::isfinite(mass)) throw PbrtError(std::string(what) + " has no emission on 360-830 nm");
    for (double &y : v) y /= mass;
    return v;
}

}  // namespace

std::vector<double> MixtureSpectrum(const LightKinds &kinds, const std::vector<double> &w) {
    if (w.size() != kinds.size()) throw PbrtError("a mixture needs one share per kind of light");
    std::vector<double> m(kinds.lambdas.size(), 0.0);
    for (size_t k = 0; k < kinds.size(); ++k) {
        if (!(w[k] > 0)) continue;
        const double f = w[k] / kinds.luminance[k];
        for (size_t i = 0; i < m.size(); ++i) m[i] += f * kinds.power[k][i];
    }
    return Normalized(kinds.lambdas, std::move(m), "the mixture");
}

std::vector<double> SceneSpectrum(const LightKinds &kinds) {
    std::vector<double> phi(kinds.lambdas.size(), 0.0);
    for (const std::vector<double> &p : kinds.power)
        for (size_t i = 0; i < phi.size(); ++i) phi[i] += p[i];
    return Normalized(kinds.lambdas, std::move(phi), "the scene");
}

wavelength_table::Table StratifiedGuidedTable(const LightKinds &kinds, const std::vector<double> &w,
                                              double S, const std::string &weight) {
    const std::vector<double> m = MixtureSpectrum(kinds, w), phi = SceneSpectrum(kinds);
    std::vector<double> q(m.size());
    for (size_t i = 0; i < q.size(); ++i) q[i] = (1 - S) * m[i] + S * phi[i];
    std::vector<double> wx, wv;
    EmissionWeightCurve(weight, &wx, &wv);
    try {
        return wavelength_table::StratifiedTable(kinds.lambdas, q, wx, wv, double(Lambda_min),
                                                 double(Lambda_max), "a guided table's mixture");
    } catch (const wavelength_table::TableError &e) {
        throw PbrtError(std::string("wavelength guiding: ") + e.what());
    }
}

wavelength_table::Table DefensiveGuidedTable(const wavelength_table::Table &t, const LightKinds &kinds,
                                             double S) {
    // The defensive spectrum cut into four equal-mass bands (design §1.7, the spectrum alone),
    // density k taking band k: the mixture (the densities' mean) gains S/4 times the bands'
    // sum 4 phi, S phi, as it would from phi mixed into every density, but each density stays
    // where the table's one random number puts it. Mixed into every density whole, phi moves each density's inverse CDF
    // everywhere and undoes the coupling an optimized table is made of (docs/guiding.md).
    wavelength_table::Table bands;
    try {
        bands = wavelength_table::StratifiedTable(kinds.lambdas, SceneSpectrum(kinds), {}, {},
                                                  double(Lambda_min), double(Lambda_max),
                                                  "the scene's emission");
    } catch (const wavelength_table::TableError &e) {
        throw PbrtError(std::string("wavelength guiding: ") + e.what());
    }
    std::vector<double> grid = t.grid;
    grid.insert(grid.end(), bands.grid.begin(), bands.grid.end());
    std::sort(grid.begin(), grid.end());
    grid.erase(std::unique(grid.begin(), grid.end()), grid.end());
    std::array<std::vector<double>, wavelength_table::kNumDensities> values;
    for (int k = 0; k < wavelength_table::kNumDensities; ++k) {
        values[size_t(k)].resize(grid.size());
        for (size_t i = 0; i < grid.size(); ++i)
            values[size_t(k)][i] =
                (1 - S) * wavelength_table::Pdf(t, k, grid[i]) + S * wavelength_table::Pdf(bands, k, grid[i]);
    }
    try {
        return wavelength_table::MakeTable(std::move(grid), std::move(values), t.source);
    } catch (const wavelength_table::TableError &e) {
        throw PbrtError(std::string("wavelength guiding: ") + e.what());
    }
}

// ---- The guide --------------------------------------------------------------------------------

size_t WavelengthGuide::MemoryBytes() const {
    size_t bytes = tileIndex.size() * sizeof(uint8_t);
    std::vector<const wavelength_table::Table *> seen;
    for (const GuidingTable &t : tables) {
        if (std::find(seen.begin(), seen.end(), t.table.get()) != seen.end()) continue;
        seen.push_back(t.table.get());
        bytes += t.table->grid.size() * sizeof(double) * (1 + 2 * wavelength_table::kNumDensities);
    }
    return bytes;
}

std::string MixtureSpectrumText(const LightKinds &kinds, const std::vector<double> &mixture) {
    std::string s;
    char line[96];
    for (size_t i = 0; i < kinds.lambdas.size(); ++i) {
        std::snprintf(line, sizeof line, "%.17g %.17g\n", kinds.lambdas[i], mixture[i]);
        s += line;
    }
    return s;
}

namespace {

std::string Label(const std::string &loc) {
    std::string s = loc.empty() ? std::string("unknown") : loc;
    std::replace(s.begin(), s.end(), ',', ' ');
    return s;
}

std::string ReadFileOrEmpty(const fs::path &p) {
    std::ifstream in(p, std::ios::binary);
    if (!in) return "";
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// Writes `text` to `path` under a temporary name renamed into place (util/output_path.h).
void WriteTextAtomically(const fs::path &path, const std::string &text) {
    WriteAtomically(path.string(),
                    [&](std::FILE *f) { return std::fwrite(text.data(), 1, text.size(), f) == text.size(); });
}

std::string TableText(const WavelengthGuide &g, size_t k) {
    const GuidingTable &t = g.tables[k];
    std::ostringstream s;
    s << "# wavelength guiding (design section 1.8): table " << k << " of " << g.tables.size()
      << ", used by " << t.tiles << " tiles of " << g.tile << "x" << g.tile << " pixels\n";
    s << "# mixture: mixture-" << t.hash << " (kind shares:";
    for (size_t i = 0; i < t.shares.size(); ++i)
        s << (i ? "; " : " ") << Label(g.kinds.labels[i]) << " " << t.shares[i];
    s << ")\n# source: " << t.source << "; defensive share " << g.settings.defensive
      << " of the scene's whole emission\n";
    s << wavelength_table::kHeader << "\n";
    const wavelength_table::Table &tab = *t.table;
    char line[160];
    for (size_t i = 0; i < tab.grid.size(); ++i) {
        std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g,%.17g\n", tab.grid[i], tab.pdf[0][i],
                      tab.pdf[1][i], tab.pdf[2][i], tab.pdf[3][i]);
        s << line;
    }
    return s.str();
}

std::string ClustersText(const WavelengthGuide &g, bool withSource) {
    std::ostringstream s;
    s << "# wavelength guiding (design section 1.8): the tables, their tiles and the luminance "
         "share of each kind of light in their mixture\n";
    s << "table,tiles,mixture" << (withSource ? ",source" : "");
    for (const std::string &l : g.kinds.labels) s << ",share " << Label(l);
    s << "\n";
    s.precision(17);
    for (size_t k = 0; k < g.tables.size(); ++k) {
        const GuidingTable &t = g.tables[k];
        s << k << "," << t.tiles << ",mixture-" << t.hash;
        if (withSource) s << "," << Label(t.source);
        for (double w : t.shares) s << "," << w;
        s << "\n";
    }
    return s.str();
}

}  // namespace

WavelengthGuide BuildWavelengthGuide(const Scene &scene, const GuidingSettings &settings, int nThreads,
                                     bool quiet) {
    const double cpu0 = ProcessCPUSeconds();
    const auto wall0 = std::chrono::steady_clock::now();
    std::unique_ptr<tbb::global_control> limit;
    if (nThreads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                       size_t(nThreads));
    const TableWavelengthSampler *emission = scene.wavelengths.Table();
    if (!emission || !emission->table)
        throw PbrtError("wavelength guiding needs the scene's emission table (a scene with lights)");

    WavelengthGuide g;
    g.settings = settings;
    g.kinds = SceneLightKinds(scene);
    g.bounds = scene.film->PixelBounds();
    g.tile = std::max(1, settings.tile);
    g.tilesX = (g.bounds.Width() + g.tile - 1) / g.tile;
    g.tilesY = (g.bounds.Height() + g.tile - 1) / g.tile;
    const size_t nTiles = size_t(g.tilesX) * size_t(g.tilesY);
    const size_t nKinds = g.kinds.size();
    std::vector<double> sceneShares(nKinds);
    {
        double sum = std::accumulate(g.kinds.luminance.begin(), g.kinds.luminance.end(), 0.0);
        for (size_t k = 0; k < nKinds; ++k) sceneShares[k] = g.kinds.luminance[k] / sum;
    }

    MixtureClusters clusters;
    if (nKinds > size_t(kMaxGuidingKinds)) {
        Warning("wavelength guiding: the scene has " + std::to_string(nKinds) +
                " distinct light spectra, more than " + std::to_string(kMaxGuidingKinds) +
                "; every pixel samples the scene's whole emission (one table)");
        g.fallback = true;
    }
    if (nKinds == 1 || g.fallback) {
        // One kind of light: every mixture is that light's, so there is one table and no
        // pre-pass is needed.
        clusters.centres = {sceneShares};
        clusters.count = {int(nTiles)};
        clusters.assignment.assign(nTiles, 0);
    } else {
        // The pre-pass: paths through random points of each tile (uniform over its area), with
        // the wavelengths of the scene's emission table; each light kind's luminance.
        const int spp = scene.sampler.SamplesPerPixel();
        const double want = std::ceil(settings.prepassShare * double(spp) * double(g.tile) * double(g.tile));
        g.prepassPathsPerTile = int(std::min(double(1 << 30), std::max(double(kMinPrepassPathsPerTile), want)));
        g.prepassPaths = uint64_t(nTiles) * uint64_t(g.prepassPathsPerTile);
        g.tileLuminance.assign(nTiles, std::vector<double>(nKinds, 0.0));
        ProgressReporter progress(int64_t(nTiles), "Guiding pre-pass", quiet);
        const int maxDepth = scene.integrator.maxDepth;
        const FilmSensor &sensor = scene.film->Sensor();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, nTiles, 1), [&](const tbb::blocked_range<size_t> &r) {
            // Independent numbers keyed by (tile, path): a low-discrepancy sampler here is set up
            // for a 1 x 1 image and would repeat its points across tiles.
            Sampler sampler(SamplerType::Independent, g.prepassPathsPerTile, kGuidingPrepassSeed);
            LightContributions byLight;
            byLight.groupOfLight = &g.kinds.kindOfLight;
            byLight.byGroup.assign(nKinds, SampledSpectrum(0));
            for (size_t t = r.begin(); t != r.end(); ++t) {
                const int tx = int(t % size_t(g.tilesX)), ty = int(t / size_t(g.tilesX));
                const Float x0 = Float(g.bounds.pMin.x + tx * g.tile), y0 = Float(g.bounds.pMin.y + ty * g.tile);
                const Float x1 = std::min(x0 + Float(g.tile), Float(g.bounds.pMax.x));
                const Float y1 = std::min(y0 + Float(g.tile), Float(g.bounds.pMax.y));
                std::vector<double> &acc = g.tileLuminance[t];
                for (int i = 0; i < g.prepassPathsPerTile; ++i) {
                    sampler.StartPixelSample(Point2i{tx, ty}, i);
                    Point2f u = sampler.GetPixel2D();
                    Point2f pFilm(x0 + u.x * (x1 - x0), y0 + u.y * (y1 - y0));
                    SampledWavelengths lambda = scene.wavelengths.Sample(sampler.Get1D());
                    Ray ray = scene.camera->GenerateRay(pFilm, sampler.Get2D());
                    for (SampledSpectrum &c : byLight.byGroup) c = SampledSpectrum(0);
                    PathLi(scene, ray, lambda, sampler, maxDepth, nullptr, &byLight);
                    for (size_t k = 0; k < nKinds; ++k) {
                        if (!byLight.byGroup[k].IsNonZero()) continue;
                        double y = double(sensor.ToXYZ(byLight.byGroup[k], lambda).Y);
                        if (std::isfinite(y) && y > 0) acc[k] += y;
                    }
                }
                progress.Update(1);
            }
        });
        progress.Done();

        // The tiles that saw light, by their kind shares; the others join the cluster nearest
        // the scene's own mixture.
        std::vector<std::vector<double>> points;
        std::vector<size_t> lit;
        for (size_t t = 0; t < nTiles; ++t) {
            double sum = std::accumulate(g.tileLuminance[t].begin(), g.tileLuminance[t].end(), 0.0);
            if (!(sum > 0) || !std::isfinite(sum)) continue;
            std::vector<double> w(nKinds);
            for (size_t k = 0; k < nKinds; ++k) w[k] = g.tileLuminance[t][k] / sum;
            points.push_back(std::move(w));
            lit.push_back(t);
        }
        if (points.empty()) points.push_back(sceneShares);
        MixtureClusters c = ClusterMixtures(points, settings.maxTables);
        clusters.centres = c.centres;
        clusters.count.assign(c.centres.size(), 0);
        int dark = 0;
        for (size_t i = 1; i < c.centres.size(); ++i)
            if (Dist2(c.centres[i], sceneShares) < Dist2(c.centres[size_t(dark)], sceneShares)) dark = int(i);
        clusters.assignment.assign(nTiles, dark);
        for (size_t i = 0; i < lit.size(); ++i) clusters.assignment[lit[i]] = c.assignment[i];
        for (int a : clusters.assignment) clusters.count[size_t(a)] += 1;
    }

    // The tables.
    std::vector<std::string> missing;
    int found = 0;
    for (size_t c = 0; c < clusters.centres.size(); ++c) {
        GuidingTable t;
        t.shares = clusters.centres[c];
        t.tiles = clusters.count[c];
        t.mixture = (nKinds == 1 || g.fallback) ? SceneSpectrum(g.kinds) : MixtureSpectrum(g.kinds, t.shares);
        t.hash = SHA256Hex(MixtureSpectrumText(g.kinds, t.mixture)).substr(0, 16);
        std::string optimized;
        if (!settings.tablesDir.empty()) {
            fs::path p = fs::path(settings.tablesDir) / ("mixture-" + t.hash + ".csv");
            std::error_code ec;
            if (fs::is_regular_file(p, ec)) optimized = p.string();
            else missing.push_back(p.string());
        }
        if (!optimized.empty()) {
            try {
                wavelength_table::Table opt = wavelength_table::LoadTable(optimized);
                t.table = std::make_shared<const wavelength_table::Table>(
                    DefensiveGuidedTable(opt, g.kinds, settings.defensive));
            } catch (const wavelength_table::TableError &e) {
                throw PbrtError(e.what());
            }
            t.source = optimized;
            ++found;
        } else if (nKinds == 1 || g.fallback) {
            t.table = emission->table;  // exactly --wavelength-sampling emission
            t.source = "stratified";
        } else {
            t.table = std::make_shared<const wavelength_table::Table>(
                StratifiedGuidedTable(g.kinds, t.shares, settings.defensive, settings.weight));
            t.source = "stratified";
        }
        t.sampler = WavelengthSampler::FromGuided(t.table, std::to_string(c) + " (mixture-" + t.hash + ", " +
                                                               t.source + ")");
        g.tables.push_back(std::move(t));
    }
    if (!settings.tablesDir.empty()) {
        if (found == 0) {
            std::string list;
            for (const std::string &m : missing) list += "\n  " + m;
            throw PbrtError("--wavelength-guiding-tables " + settings.tablesDir + ": none of the " +
                            std::to_string(g.tables.size()) + " tables this render needs is there:" + list +
                            "\n(write the mixtures with --wavelength-guiding-spectra DIR and the same scene, "
                            "--spp, resolution and --guiding-* options, then optimize them: "
                            "wavelength-pdf batch DIR -o TABLES)");
        }
        for (const std::string &m : missing)
            Warning("wavelength guiding: no optimized table " + m + "; that table is the stratified one");
    }
    g.tileIndex.resize(nTiles);
    for (size_t t = 0; t < nTiles; ++t) g.tileIndex[t] = uint8_t(clusters.assignment[t]);
    g.cpuSeconds = ProcessCPUSeconds() - cpu0;
    g.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    return g;
}

// ---- Output -------------------------------------------------------------------------------------

// The table of every tile, one row per row of tiles, after a comment line naming the tile size
// and the film's pixel bounds (tiles.csv beside an image, tiles.txt beside the mixtures).
static std::string TilesText(const WavelengthGuide &g) {
    std::ostringstream tiles;
    tiles << "# wavelength guiding: the table of each tile of " << g.tile << "x" << g.tile
          << " pixels, one row per row of tiles, from the film's pixel bounds " << g.bounds.pMin.x << " "
          << g.bounds.pMin.y << " " << g.bounds.pMax.x << " " << g.bounds.pMax.y << "\n";
    for (int ty = 0; ty < g.tilesY; ++ty) {
        for (int tx = 0; tx < g.tilesX; ++tx)
            tiles << (tx ? "," : "") << int(g.tileIndex[size_t(ty) * size_t(g.tilesX) + size_t(tx)]);
        tiles << "\n";
    }
    return tiles.str();
}

// Each light statement of the scene (deduplicated: the triangles of one area light share it)
// with its kind, after each kind's spectrum (its lights' emitted power, integral 1) as
// "# kind K" and "lambda value" lines: what choose-guiding needs to light a copy of the scene
// by one kind at a time (design §6.8).
static std::string KindsText(const LightKinds &kinds, const std::string &source) {
    std::ostringstream s;
    s << "# wavelength guiding's kinds of light of " << source
      << " (lights whose spectra are equal up to a scale; design section 1.8)\n";
    for (size_t k = 0; k < kinds.size(); ++k) {
        const double sum = wavelength_table::detail::Trapezoid(kinds.lambdas, kinds.power[k]);
        std::vector<double> v = kinds.power[k];
        for (double &x : v) x /= sum;
        s << "# kind " << k << "\n" << MixtureSpectrumText(kinds, v);
    }
    s << "kind,light\n";
    std::set<std::pair<int, std::string>> seen;
    for (size_t li = 0; li < kinds.kindOfLight.size(); ++li) {
        if (kinds.kindOfLight[li] < 0) continue;
        if (seen.insert({kinds.kindOfLight[li], kinds.lightLabels[li]}).second)
            s << kinds.kindOfLight[li] << "," << Label(kinds.lightLabels[li]) << "\n";
    }
    return s.str();
}

void WriteGuidingSpectra(const std::string &dir, const WavelengthGuide &g, const std::string &source) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        fs::create_directory(dir, ec);
        if (ec) throw PbrtError("\"" + dir + "\": cannot create the folder (" + ec.message() + ")");
    }
    for (const GuidingTable &t : g.tables) {
        const fs::path p = fs::path(dir) / ("mixture-" + t.hash + ".spd");
        std::ostringstream s;
        s << "# wavelength guiding's mixture spectrum (design section 1.8) of " << source << ":";
        for (size_t i = 0; i < t.shares.size(); ++i)
            s << (i ? ";" : "") << " " << Label(g.kinds.labels[i]) << " " << t.shares[i];
        s << " (luminance shares); integral 1\n" << MixtureSpectrumText(g.kinds, t.mixture);
        const std::string text = s.str();
        if (ReadFileOrEmpty(p) == text) continue;  // the same mixture: left alone (cache)
        WriteTextAtomically(p, text);
    }
    WriteTextAtomically(fs::path(dir) / "clusters.txt", ClustersText(g, false));  // not a spectrum: .txt
    WriteTextAtomically(fs::path(dir) / "tiles.txt", TilesText(g));  // the tile map, for choose-guiding
    // What choose-guiding predicts with: each table as this run samples it and the defensive
    // spectrum every table is mixed with (.txt: not spectra for batch to optimize).
    for (size_t k = 0; k < g.tables.size(); ++k)
        WriteTextAtomically(fs::path(dir) / ("table-" + std::to_string(k) + ".txt"), TableText(g, k));
    std::ostringstream d;
    d.precision(17);
    d << "# wavelength guiding's defensive spectrum (design section 1.8): the scene's whole emission, "
         "integral 1, mixed into every table at the share below\n"
         "# defensive share " << g.settings.defensive
      << "\n" << MixtureSpectrumText(g.kinds, SceneSpectrum(g.kinds));
    WriteTextAtomically(fs::path(dir) / "defensive.txt", d.str());
    WriteTextAtomically(fs::path(dir) / "kinds.txt", KindsText(g.kinds, source));
}

std::string GuidingOutputDir(const std::string &imagePath) {
    fs::path p(imagePath);
    p.replace_extension(".guiding");
    return p.string();
}

void WriteGuidingOutputs(const std::string &imagePath, const WavelengthGuide &g, const std::string &source) {
    const fs::path dir = GuidingOutputDir(imagePath);
    const fs::path tmp = dir.string() + ".tmp" + std::to_string(getpid());
    std::error_code ec;
    fs::remove_all(tmp, ec);
    if (!fs::create_directory(tmp, ec) || ec)
        throw PbrtError("\"" + dir.string() + "\": cannot create the guiding output folder");
    try {
        for (size_t k = 0; k < g.tables.size(); ++k)
            WriteTextAtomically(tmp / ("table-" + std::to_string(k) + ".csv"), TableText(g, k));
        WriteTextAtomically(tmp / "clusters.csv", ClustersText(g, true));
        std::ostringstream kinds;
        kinds << "# wavelength guiding: the kinds of light of " << source
              << " (lights whose spectra are equal up to a scale)\nkind,light,lights,luminance_share\n";
        double sum = std::accumulate(g.kinds.luminance.begin(), g.kinds.luminance.end(), 0.0);
        kinds.precision(17);
        for (size_t k = 0; k < g.kinds.size(); ++k)
            kinds << k << "," << Label(g.kinds.labels[k]) << "," << g.kinds.lights[k] << ","
                  << g.kinds.luminance[k] / sum << "\n";
        WriteTextAtomically(tmp / "kinds.csv", kinds.str());
        WriteTextAtomically(tmp / "tiles.csv", TilesText(g));
        // Into place: an earlier folder of the same name goes only once the new one is complete.
        const fs::path old = dir.string() + ".old" + std::to_string(getpid());
        if (fs::exists(dir, ec)) {
            fs::rename(dir, old, ec);
            if (ec) throw PbrtError("\"" + dir.string() + "\": cannot replace it (" + ec.message() + ")");
        }
        fs::rename(tmp, dir, ec);
        if (ec) throw PbrtError("\"" + dir.string() + "\": cannot write it (" + ec.message() + ")");
        fs::remove_all(old, ec);
    } catch (...) {
        fs::remove_all(tmp, ec);
        throw;
    }
}

void AddGuidingMetadata(ImageMetadata &m, const WavelengthGuide &g) {
    m.strings["wavelengthSampler"] = "guided";
    m.ints["wavelengthGuidingTables"] = int(g.tables.size());
    m.ints["wavelengthGuidingKinds"] = int(g.kinds.size());
    m.ints["wavelengthGuidingTile"] = g.tile;
    m.ints["wavelengthGuidingPrepassPathsPerTile"] = g.prepassPathsPerTile;
    m.ints["wavelengthGuidingBytes"] = int(std::min<size_t>(g.MemoryBytes(), size_t(INT32_MAX)));
    m.floats["wavelengthGuidingPrepassShare"] = float(g.settings.prepassShare);
    m.floats["wavelengthGuidingDefensive"] = float(g.settings.defensive);
    m.floats["wavelengthGuidingCPUSeconds"] = float(g.cpuSeconds);
    if (!g.settings.tablesDir.empty()) m.strings["wavelengthGuidingTablesDir"] = g.settings.tablesDir;
    std::vector<float> index(size_t(g.bounds.Area()));
    size_t i = 0;
    for (int y = g.bounds.pMin.y; y < g.bounds.pMax.y; ++y)
        for (int x = g.bounds.pMin.x; x < g.bounds.pMax.x; ++x) index[i++] = float(g.IndexAt(Point2i{x, y}));
    m.channels["wavelengthTable.index"] = std::move(index);
}

}  // namespace pbrt
