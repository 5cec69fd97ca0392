// Wavelength guiding (design §1.8, §5.2): each pixel samples the lamps that light it.
//
// 1. A short pre-pass (guiding.cpp, BuildWavelengthGuide) traces a few paths through every
//    tile of T x T pixels, its own random numbers (a fixed seed, never the image's), and
//    records how much luminance each *kind* of light (lights whose spectra are equal up to a
//    scale, SceneLightKinds) brings to the tile: next-event estimation and emitter hits,
//    tagged by light (integrator.h, LightContributions). Its samples are not used in the image.
// 2. The tiles' mixtures (luminance shares of the kinds, summing to 1) are clustered into at
//    most K groups (ClusterMixtures: farthest-point seeding, then Lloyd iterations, then merging
//    groups closer than kGuidingMergeDistance), and each group gets one table: the
//    stratified table of design §1.7 of its mixture spectrum with a defensive share S of the
//    scene's whole emission mixed in before the cut (StratifiedGuidedTable), or an optimized
//    table for its mixture spectrum read from a folder, mixed with the same share of the
//    scene's emission cut into four bands, one per density (DefensiveGuidedTable). A scene
//    with one kind of light gets exactly one table, the emission-sampling table
//    (--wavelength-sampling emission).
// 3. The render draws each pixel's wavelengths from the table of its tile (SamplerAt) and
//    weights them with that table's own four densities (the balance heuristic of design
//    §1.3): every table is positive wherever any light of the scene emits, and the choice of
//    table does not depend on the image's samples, so every pixel stays unbiased.
#pragma once

#include <pbrt/util/image.h>
#include <pbrt/util/vecmath.h>
#include <pbrt/wavelengths.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace wavelength_table {
struct Table;
}

namespace pbrt {

struct Scene;

// ---- Defaults and limits of the options (design §5.2) ---------------------------------------
constexpr double kDefaultGuidingPrepassShare = 0.03;  // --guiding-prepass-share
constexpr int kDefaultGuidingTables = 8;              // --guiding-tables (K)
constexpr int kMaxGuidingTables = 16;
constexpr double kDefaultGuidingDefensive = 0.05;     // --guiding-defensive (S)
constexpr int kDefaultGuidingTile = 8;                // --guiding-tile (pixels per side)
constexpr int kMaxGuidingTile = 256;
// Two mixtures whose kind shares differ by less than this (Euclidean distance of the share
// vectors) share a table: their tables would sample almost alike.
constexpr double kGuidingMergeDistance = 0.1;
// At least this many pre-pass paths per tile, whatever the share.
constexpr int kMinPrepassPathsPerTile = 16;
// More kinds than this (distinct light spectra) and guiding falls back to one table.
constexpr int kMaxGuidingKinds = 256;
// The pre-pass's seed (fixed: the query run and the render run choose the same tables, and
// it never shares random numbers with the image, whose seed is --seed).
constexpr uint64_t kGuidingPrepassSeed = 0x67756964696e6701ULL;

// ---- Kinds of light -------------------------------------------------------------------------
// The scene's lights grouped by spectrum: lights whose emission spectra are equal up to a
// scale (at every node of the common grid, to 1e-6 of their peak) are one kind.
struct LightKinds {
    std::vector<int> kindOfLight;              // per light of the scene; -1: zero power
    std::vector<double> lambdas;               // nodes on 360..830 nm where every Phi is exact
    std::vector<std::vector<double>> power;    // per kind: Phi_kind(lambda) at lambdas (§5.6)
    std::vector<double> luminance;             // per kind: integral of Phi_kind * ybar (> 0)
    std::vector<std::string> labels;           // per kind: FILE:LINE:COL of its strongest light
    std::vector<size_t> lights;                // per kind: how many lights
    std::vector<std::string> lightLabels;      // per light of the scene: FILE:LINE:COL
    size_t size() const { return power.size(); }
};
// Throws PbrtError as SceneEmissionSpectrum does (no emitters, no power, power not finite).
LightKinds SceneLightKinds(const Scene &scene);

// ---- Clustering -----------------------------------------------------------------------------
struct MixtureClusters {
    std::vector<std::vector<double>> centres;  // per cluster: the mean of its points
    std::vector<int> assignment;               // per point: its cluster
    std::vector<int> count;                    // per cluster: its points (clusters by count, descending)
};
// Deterministic k-means of points of equal dimension: the first centre is the point nearest
// the mean, then the point farthest from every centre while it lies at least mergeDistance
// from them and fewer than maxClusters exist; Lloyd iterations (nearest centre, ties to the
// lower index) until no point moves (at most 100); then any two centres closer than
// mergeDistance are merged (their points pooled) until none are. Points that coincide always
// share a cluster. Throws PbrtError for no points, ragged points or maxClusters < 1.
MixtureClusters ClusterMixtures(const std::vector<std::vector<double>> &points, int maxClusters,
                                double mergeDistance = kGuidingMergeDistance);

// ---- Tables ---------------------------------------------------------------------------------
// The mixture spectrum of kind shares w (luminance shares, any scale): sum_k w_k Phi_k / Y_k,
// the light of that mixture with each kind at its share of the luminance, at kinds.lambdas,
// normalized to integrate to 1 (trapezoid). Throws PbrtError when it has no mass.
std::vector<double> MixtureSpectrum(const LightKinds &kinds, const std::vector<double> &w);
// The scene's whole emission sum_k Phi_k at kinds.lambdas, normalized to integrate to 1.
std::vector<double> SceneSpectrum(const LightKinds &kinds);
// Design §1.7's table of q = (1 - S) m + S phi (m the mixture spectrum of w, phi the scene's)
// times the emission weight ("spd", "luminance" or "xyz", emission.h), on 360..830 nm. Its
// mixture density is at least S phi / (its mass) wherever the scene emits.
wavelength_table::Table StratifiedGuidedTable(const LightKinds &kinds, const std::vector<double> &w,
                                              double S, const std::string &weight);
// (1 - S) p_k + S b_k for each density of a given table (an optimized table for a mixture),
// b_k the k-th of four equal-mass bands of the scene's emission phi (design §1.7's stratified
// table of phi), on the union of both grids: the mixture gains (S/4) sum_k b_k = S phi (as
// from phi in every density), positive wherever the scene emits, and each density keeps its
// place in u.
wavelength_table::Table DefensiveGuidedTable(const wavelength_table::Table &t, const LightKinds &kinds,
                                             double S);

// ---- The guide ------------------------------------------------------------------------------
struct GuidingSettings {
    double prepassShare = kDefaultGuidingPrepassShare;  // pre-pass paths = share x spp per pixel
    int maxTables = kDefaultGuidingTables;
    double defensive = kDefaultGuidingDefensive;
    int tile = kDefaultGuidingTile;
    std::string weight = "spd";  // the stratified tables' emission weight
    std::string tablesDir;       // optimized tables mixture-<hash>.csv (empty: stratified)
};

struct GuidingTable {
    std::vector<double> shares;      // kind shares of the cluster's centre (sum 1)
    std::vector<double> mixture;     // its mixture spectrum at the kinds' lambdas (integral 1)
    std::string hash;                // 16 hex digits naming the mixture (MixtureSpectrumText)
    std::string source;              // "stratified", or the optimized table's file
    int tiles = 0;                   // tiles that use it
    std::shared_ptr<const wavelength_table::Table> table;
    WavelengthSampler sampler = WavelengthSampler::Visible();
};

class WavelengthGuide {
  public:
    const WavelengthSampler &SamplerAt(Point2i p) const { return tables[size_t(IndexAt(p))].sampler; }
    int IndexAt(Point2i p) const {
        int tx = (p.x - bounds.pMin.x) / tile, ty = (p.y - bounds.pMin.y) / tile;
        return tileIndex[size_t(ty) * size_t(tilesX) + size_t(tx)];
    }

    GuidingSettings settings;
    LightKinds kinds;
    std::vector<GuidingTable> tables;
    Bounds2i bounds;                  // the film's pixel bounds
    int tile = 1, tilesX = 0, tilesY = 0;
    std::vector<uint8_t> tileIndex;   // per tile (row by row): its table
    std::vector<std::vector<double>> tileLuminance;  // per tile: the pre-pass's luminance per kind
    int prepassPathsPerTile = 0;
    uint64_t prepassPaths = 0;
    double cpuSeconds = 0, wallSeconds = 0;  // pre-pass, clustering and tables
    bool fallback = false;            // too many kinds: one table (the scene's emission)

    // Bytes the render keeps for guiding: the tables' arrays and the index map.
    size_t MemoryBytes() const;
};

// The pre-pass, the clustering and the tables. scene.wavelengths must be the scene's
// emission-sampling table (the pre-pass samples with it). nThreads 0: every core. Throws
// PbrtError for an optimized table that cannot be read (FILE:LINE: reason) or when none of
// the tables settings.tablesDir should hold is there.
WavelengthGuide BuildWavelengthGuide(const Scene &scene, const GuidingSettings &settings,
                                     int nThreads, bool quiet);

// The text of a mixture spectrum as a pbrt .spd file's numbers (`lambda value` lines, full
// precision); its SHA-256's first 16 hex digits name it (mixture-<hash>.spd / .csv).
std::string MixtureSpectrumText(const LightKinds &kinds, const std::vector<double> &mixture);

// --wavelength-guiding-spectra DIR: writes DIR/mixture-<hash>.spd for every table (a file
// already there with the same numbers is left alone, so an optimizer's cache keyed by it stays
// valid), DIR/clusters.txt and DIR/tiles.txt (CSV text, named so that `wavelength-pdf batch
// DIR`, which reads .csv, .spd and .pbrt files, optimizes the spectra alone; tiles.txt is the
// tiles.csv of WriteGuidingOutputs), DIR/table-<k>.txt (each table as this run samples it) and
// DIR/defensive.txt (the scene's emission every table is mixed with, and the share S, in a
// comment line); creates DIR when missing. Throws PbrtError on failure.
void WriteGuidingSpectra(const std::string &dir, const WavelengthGuide &guide, const std::string &source);

// Beside the image OUT.ext: OUT.guiding/ with table-<k>.csv (each table as sampled, design §2
// layout), clusters.csv (each table's kind shares, tiles, mixture hash and source), kinds.csv
// and tiles.csv (the index of every tile); written under a temporary name and renamed.
std::string GuidingOutputDir(const std::string &imagePath);
void WriteGuidingOutputs(const std::string &imagePath, const WavelengthGuide &guide, const std::string &source);

// The image's guiding attributes (render.h lists them) and its per-pixel table index, the
// EXR channel "wavelengthTable.index".
void AddGuidingMetadata(ImageMetadata &m, const WavelengthGuide &guide);

}  // namespace pbrt
