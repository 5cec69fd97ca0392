// pbrt: renders pbrt-v4 scene files with the spectral path tracer.
#include <pbrt/emission.h>
#include <pbrt/guiding.h>
#include <pbrt/options.h>
#include <pbrt/render.h>
#include <pbrt/scene.h>
#include <pbrt/util/output_path.h>

#include <wavelength_table.h>

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

using namespace pbrt;

namespace {

const char *kUsage = R"(usage: pbrt [options] scene.pbrt...   (standard input if no file)
Options take "--name value", "--name=value" or a single dash ("-spp 16"), as in pbrt-v4.

Rendering:
  --spp N                      samples per pixel (overrides the scene's "pixelsamples")
  --seed N                     seed of the sampler (overrides the scene's)
  --maxdepth N                 maximum path depth (overrides the integrator's "maxdepth")
  --nthreads N                 number of threads (default: all cores)
  --quick                      a quarter of the resolution each way and 1 sample per pixel
  --cropwindow X0,X1,Y0,Y1     render only this part of the image (fractions in [0, 1]);
                               replaces the film's "cropwindow"/"pixelbounds"; the EXR's
                               data window places it in the frame
  --pixelbounds X0,X1,Y0,Y1    the same in pixels (X1, Y1 excluded)
  --pixel X,Y                  render only this pixel
  --disable-pixel-jitter       sample every pixel at its centre
  --disable-wavelength-jitter  the same four wavelengths for every path (u = 1/2)
  --wavelength-net             draw each sample's wavelength number together with its film
                               position and first choice of light, from one scrambled
                               Sobol' net per pixel, so that each part of a pixel (each side
                               of an edge) and each lamp gets stratified wavelengths; the
                               sampler's other dimensions are unchanged (design §5.2)
Output:
  --outfile FILE               image to write (.exr: linear 32-bit float, the colour space's
                               chromaticities and the render's provenance as attributes;
                               .png: sRGB 8-bit); default: the film's "filename"
  --resolution WxH             render at W x H pixels instead of the film's resolution
  --resolution-scale S         multiply the film's (or --resolution's) resolution by S
  --write-partial-images       render in passes of 1, 1, 2, 4, ..., 64 samples per pixel
                               and write the image after each
  --mse-reference-image FILE   print the mean squared error of the image against FILE (an
                               image of the same size, or of the full frame when cropping)
                               and record it in the EXR ("MSE")
  --mse-reference-out FILE     with --mse-reference-image: render in passes (as above) and
                               write "spp MSE" lines to FILE, one per pass
Wavelengths (four per path from one random number):
  --wavelength-sampling NAME   visible   pbrt-v4's visible sampling over 360-830 nm (default)
                               uniform   stratified uniform over --wavelength-range
                               emission  the scene's own lamps: their emitted power (as
                                         --emission-spectrum sums it) cut into four
                                         equal-mass bands, a table built at scene load
                                         (design §1.7; nothing to install, no file). Use it
                                         for spiky lamps (fluorescent, LED, metal halide,
                                         sodium); an optimized table (--wavelength-pdf)
                                         where the benchmark shows it pays more
  --emission-weight W          with emission: spd (the emitted power alone, default),
                               luminance (times ybar) or xyz (times xbar + ybar + zbar)
  --wavelength-range LO HI     range of uniform sampling in nm (default 360 830)
  --wavelength-pdf FILE        sample from a wavelength table (design §1, §2: four
                               densities on one grid, one u per path, balance heuristic);
                               a bad table stops pbrt before rendering (FILE:LINE: reason)
  --wavelength-pdf-defensive S mix a uniform share S in [0, 1] into each density of the
                               table, over the table's range (e.g. 0.01): removes zero
                               sampling density where a light emits, which biases the image
  --wavelength-guiding         each pixel samples the lamps that light it (design §1.8):
                               a short pre-pass (its own random numbers, not in the image)
                               measures which kinds of light reach each tile of pixels;
                               their mixtures are clustered into at most K tables (the
                               emission construction of each mixture, with a defensive
                               share of the whole scene's emission); each pixel draws its
                               wavelengths from its tile's table. One kind of light: one
                               table, exactly --wavelength-sampling emission's. The EXR
                               gets a channel wavelengthTable.index; OUT.guiding/ beside
                               the image holds the tables (table-K.csv), clusters.csv,
                               kinds.csv and tiles.csv. Takes --emission-weight
  --guiding-prepass-share F    pre-pass paths per pixel, as a share of --spp (default 0.03;
                               at least 16 paths per tile), in (0, 1]
  --guiding-tables K           at most K tables, 1..16 (default 8; fewer when mixtures
                               coincide)
  --guiding-defensive S        share S in (0, 1] of the scene's whole emission in every
                               table (default 0.05): a lamp the pre-pass missed is still
                               sampled, so the image stays unbiased
  --guiding-tile N             pixels per side of a pre-pass tile, 1..256 (default 8)
  --wavelength-guiding-tables DIR
                               optimized tables for the mixtures: DIR/mixture-HASH.csv
                               (from wavelength-pdf batch on the spectra below), each
                               mixed with the defensive share
  --wavelength-guiding-spectra DIR
                               render nothing: run the pre-pass and write each table's
                               mixture spectrum to DIR/mixture-HASH.spd (and clusters.txt,
                               tiles.txt, table-K.txt, defensive.txt for wavelength-pdf
                               choose-guiding); give the render's own --spp, resolution and
                               --guiding-* options, so that the render chooses the same mixtures
  --wavelength-repeats K       trace each camera sample K times with the same random
                               numbers but the wavelength number shifted by k/K, and
                               average: wavelength noise averaged away at K times the cost
                               (the benchmark's floor, design §5.2; default 1)
  --wavelength-seed S          draw each sample's wavelength number from a hash of the
                               pixel, the sample index and S alone, every other number
                               unchanged: renders with one --seed and two S trace the same
                               paths at independent wavelengths (a pixel's spread, design
                               §6.8); same expectation, u no longer stratified
Scene:
  --emission-spectrum FILE     render nothing: write the scene's total emitted spectral
                               power (pbrt-v4's light power summed over its lights) to FILE
                               as `lambda value` lines (a .spd file, design §5.6); a scene
                               with no emitters is an error (exit 1, no file)
  --material-reflectances FILE render nothing: write the diffuse reflectances of the
                               materials the scene's shapes use (RGB through the
                               renderer's own tables, textures by their mean) to FILE as
                               a CSV, one column per material (design §3.4, §5.6)
  --emission-table FILE        render nothing: write the table --wavelength-sampling
                               emission samples from (with --emission-weight) to FILE as
                               a wavelength table CSV (design §2), for renderers that
                               read tables
Other:
  --quiet                      no progress bar or summary
  --stats                      print the render's statistics at the end (time, CPU time,
                               paths, surface hits, peak memory)
  --log-level LEVEL            verbose (also what was loaded and how), error (default:
                               warnings and errors) or fatal (errors only)
  --log-file FILE              warnings and verbose lines go to FILE (implies verbose)
  --log-utilization            with verbose logging: the CPU and memory use at the end
  --version                    the version of pbrt (the project's) and exit
  -h, --help                   this text and exit
  --wavefront, --render-coord-sys NAME, --disable-texture-filtering,
  --displacement-edge-scale S  accepted with a warning; they change nothing here (one CPU
                               integrator, rendering in world space, bilinear textures)
  Refused (exit 1): --gpu, --gpu-device, --interactive, --fullscreen, --display-server,
  --pixelmaterial, --pixelstats, --debugstart (features of upstream pbrt-v4 this renderer
  lacks) and --format, --toply, --upgrade (use upstream pbrt-v4 for those)
)";

[[noreturn]] void Usage(const std::string &msg) {
    if (!msg.empty()) std::fprintf(stderr, "pbrt: %s\n", msg.c_str());
    std::fputs(kUsage, stderr);
    std::exit(1);
}

long long ParseInt(const std::string &flag, const char *s, long long lo, long long hi) {
    char *end = nullptr;
    errno = 0;
    long long v = std::strtoll(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi)
        Usage(flag + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
              "], got \"" + s + "\"");
    return v;
}

double ParseFloat(const std::string &flag, const char *s) {
    char *end = nullptr;
    double v = std::strtod(s, &end);
    if (end == s || *end || !std::isfinite(v)) Usage(flag + ": expected a number, got \"" + s + "\"");
    return v;
}

// "a,b,c,d": exactly n comma-separated fields, as pbrt-v4 takes lists on its command line.
std::vector<std::string> SplitList(const std::string &flag, const std::string &s, size_t n) {
    std::vector<std::string> parts;
    size_t start = 0;
    for (size_t comma; (comma = s.find(',', start)) != std::string::npos; start = comma + 1)
        parts.push_back(s.substr(start, comma - start));
    parts.push_back(s.substr(start));
    if (parts.size() != n)
        Usage(flag + ": expected " + std::to_string(n) + " comma-separated values, got \"" + s + "\"");
    return parts;
}

// A reference for --mse-reference-image: the size of the rendered image, or of the full
// frame when rendering a crop of it; three channels or more (the first three compared).
void CheckMSEReference(const std::string &path, const Image &ref, const FilmSettings &fs) {
    const bool whole = ref.width == fs.pixelBounds.Width() && ref.height == fs.pixelBounds.Height();
    const bool frame = ref.width == fs.fullResolution.x && ref.height == fs.fullResolution.y;
    if (!whole && !frame)
        throw PbrtError(path + ": the reference image is " + std::to_string(ref.width) + "x" +
                        std::to_string(ref.height) + ", the render " + std::to_string(fs.pixelBounds.Width()) +
                        "x" + std::to_string(fs.pixelBounds.Height()) + " (of a " +
                        std::to_string(fs.fullResolution.x) + "x" + std::to_string(fs.fullResolution.y) + " frame)");
    if (ref.channels < 3)
        throw PbrtError(path + ": the reference image has " + std::to_string(ref.channels) +
                        " channel(s); it needs R, G and B");
}

// Mean over pixels and the R, G, B channels of the squared difference (pbrt-v4's MSE); a
// full-frame reference is compared where the image lies in the frame.
double MeanSquaredError(const Image &img, const Image &ref) {
    const bool frame = ref.width != img.width || ref.height != img.height;
    const int ox = frame ? img.originX : 0, oy = frame ? img.originY : 0;
    double sum = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const double d = double(img.Get(x, y, c)) - double(ref.Get(x + ox, y + oy, c));
                sum += d * d;
            }
    return sum / (3.0 * img.width * img.height);
}

double PeakMemoryBytes() {
    struct rusage u;
    return getrusage(RUSAGE_SELF, &u) == 0 ? double(u.ru_maxrss) * 1024 : 0;
}

// --stats: pbrt-v4 prints its statistics on standard output after the render.
void PrintStats(const RenderStats &s) {
    std::printf("Statistics:\n");
    std::printf("  Render time                 %12.3f s\n", s.wallSeconds);
    std::printf("  CPU time                    %12.3f s\n", s.cpuSeconds);
    std::printf("  Camera paths                %12llu\n", (unsigned long long)s.paths);
    std::printf("  Surface interactions        %12llu\n", (unsigned long long)s.scatterings);
    std::printf("  Surfaces per path           %12.3f\n", s.paths ? double(s.scatterings) / double(s.paths) : 0.0);
    std::printf("  Paths per CPU-second        %12.4g\n", s.paths / std::max(s.cpuSeconds, 1e-9));
    std::printf("  Peak memory                 %12.1f MB\n", PeakMemoryBytes() / 1e6);
}

// Flags of upstream pbrt-v4 for features this renderer lacks: refused, with the reason.
const char *UnsupportedFlag(const std::string &flag) {
    if (flag == "--gpu" || flag == "--gpu-device")
        return "this renderer runs on the CPU only (for the GPU, patch upstream pbrt-v4: wavelength_table/README.md)";
    if (flag == "--interactive" || flag == "--fullscreen" || flag == "--display-server")
        return "this renderer has no interactive display";
    if (flag == "--pixelmaterial" || flag == "--pixelstats" || flag == "--debugstart")
        return "this debugging aid of upstream pbrt-v4 is not implemented here";
    if (flag == "--format" || flag == "--toply" || flag == "--upgrade")
        return "this renderer does not rewrite scene files; use upstream pbrt-v4's pbrt for that";
    return nullptr;
}

}  // namespace

int main(int argc, char **argv) {
    RenderOptions opts;
    std::vector<std::string> files;
    bool hasDefensive = false, hasBuiltinSampling = false, hasRange = false, hasWeight = false;
    std::string guidingOption;  // a --guiding-* option given (it needs --wavelength-guiding)
    bool logUtilization = false, hasLogLevel = false;
    std::vector<std::string> ignored;  // accepted flags that change nothing here

    // Flags take "--flag value" or "--flag=value".
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        // pbrt-v4 takes "-spp" for "--spp" (a lone "-h" stays the short help).
        if (arg.size() > 2 && arg[0] == '-' && arg[1] != '-' && !std::isdigit((unsigned char)arg[1]) &&
            arg[1] != '.')
            arg = "-" + arg;
        if (arg.size() < 2 || arg.compare(0, 2, "--") != 0 || arg == "--") {
            if (arg == "-h") {
                std::fputs(kUsage, stdout);
                return 0;
            }
            if (!arg.empty() && arg[0] == '-' && arg != "-") Usage("unknown option \"" + arg + "\"");
            files.push_back(arg);
            continue;
        }
        std::string flag = arg, inlineValue;
        bool hasInline = false;
        if (size_t eq = arg.find('='); eq != std::string::npos) {
            flag = arg.substr(0, eq);
            inlineValue = arg.substr(eq + 1);
            hasInline = true;
        }
        auto value = [&]() -> const char * {
            if (hasInline) return inlineValue.c_str();
            if (i + 1 >= argc) Usage(flag + " needs a value");
            return argv[++i];
        };
        if (flag == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        } else if (flag == "--version") {
            std::printf("pbrt (wavelength-pdf) %s: a pbrt-v4-compatible spectral path tracer\n",
                        PBRT_PROJECT_VERSION);
            return 0;
        } else if (flag == "--quiet") {
            opts.quiet = true;
        } else if (flag == "--quick") {
            opts.quick = true;
        } else if (flag == "--stats") {
            opts.stats = true;
        } else if (flag == "--write-partial-images") {
            opts.writePartialImages = true;
        } else if (flag == "--disable-pixel-jitter") {
            opts.disablePixelJitter = true;
        } else if (flag == "--disable-wavelength-jitter") {
            opts.disableWavelengthJitter = true;
        } else if (flag == "--wavelength-net") {
            opts.wavelengthNet = true;
        } else if (flag == "--cropwindow") {
            std::vector<std::string> v = SplitList(flag, value(), 4);
            std::array<Float, 4> c;
            for (size_t k = 0; k < 4; ++k) c[k] = Float(ParseFloat(flag, v[k].c_str()));
            opts.cropWindow = c;
        } else if (flag == "--pixelbounds" || flag == "--pixel") {
            const size_t n = flag == "--pixel" ? 2 : 4;
            std::vector<std::string> v = SplitList(flag, value(), n);
            std::array<int, 4> b;
            for (size_t k = 0; k < n; ++k) b[k] = int(ParseInt(flag, v[k].c_str(), 0, 1 << 30));
            if (n == 2) b = {b[0], b[0] + 1, b[1], b[1] + 1};
            if (b[0] >= b[1] || b[2] >= b[3]) Usage(flag + ": the bounds are empty (need X0 < X1 and Y0 < Y1)");
            opts.pixelBounds = b;
        } else if (flag == "--mse-reference-image") {
            opts.mseReference = value();
            if (opts.mseReference.empty()) Usage("--mse-reference-image needs a file name");
        } else if (flag == "--mse-reference-out") {
            opts.mseReferenceOut = value();
            if (opts.mseReferenceOut.empty()) Usage("--mse-reference-out needs a file name");
        } else if (flag == "--log-level") {
            hasLogLevel = true;
            opts.logLevel = value();
            if (opts.logLevel != "verbose" && opts.logLevel != "error" && opts.logLevel != "fatal")
                Usage("--log-level: expected verbose, error or fatal, got \"" + opts.logLevel + "\"");
        } else if (flag == "--log-file") {
            opts.logFile = value();
            if (opts.logFile.empty()) Usage("--log-file needs a file name");
        } else if (flag == "--log-utilization") {
            logUtilization = true;
        } else if (flag == "--wavefront" || flag == "--disable-texture-filtering") {
            ignored.push_back(flag);
        } else if (flag == "--render-coord-sys") {
            std::string v = value();
            if (v != "camera" && v != "cameraworld" && v != "world")
                Usage("--render-coord-sys: expected camera, cameraworld or world, got \"" + v + "\"");
            ignored.push_back(flag);
        } else if (flag == "--displacement-edge-scale") {
            if (!(ParseFloat(flag, value()) > 0)) Usage("--displacement-edge-scale must be positive");
            ignored.push_back(flag);
        } else if (const char *why = UnsupportedFlag(flag)) {
            Usage(flag + ": not supported: " + why);
        } else if (flag == "--spp") {
            opts.spp = int(ParseInt(flag, value(), 1, 1 << 30));
        } else if (flag == "--seed") {
            opts.seed = uint64_t(ParseInt(flag, value(), 0, (1LL << 62)));
        } else if (flag == "--maxdepth") {
            opts.maxDepth = int(ParseInt(flag, value(), 0, 100000));
        } else if (flag == "--nthreads") {
            opts.nThreads = int(ParseInt(flag, value(), 0, 4096));
        } else if (flag == "--outfile") {
            opts.outfile = value();
        } else if (flag == "--resolution") {
            std::string v = value();
            size_t x = v.find_first_of("xX");
            if (x == std::string::npos) Usage("--resolution: expected WxH, got \"" + v + "\"");
            opts.resolution.x = int(ParseInt(flag, v.substr(0, x).c_str(), 1, 1 << 16));
            opts.resolution.y = int(ParseInt(flag, v.substr(x + 1).c_str(), 1, 1 << 16));
        } else if (flag == "--resolution-scale") {
            opts.resolutionScale = Float(ParseFloat(flag, value()));
            if (!(opts.resolutionScale > 0)) Usage("--resolution-scale must be positive");
        } else if (flag == "--wavelength-sampling") {
            opts.wavelengthSampling = value();
            if (opts.wavelengthSampling != "visible" && opts.wavelengthSampling != "uniform" &&
                opts.wavelengthSampling != "emission")
                Usage("--wavelength-sampling: expected visible, uniform or emission, got \"" +
                      opts.wavelengthSampling + "\"");
        } else if (flag == "--emission-weight") {
            hasWeight = true;
            opts.emissionWeight = value();
            const std::vector<std::string> &weights = EmissionWeights();
            if (std::find(weights.begin(), weights.end(), opts.emissionWeight) == weights.end())
                Usage("--emission-weight: expected spd, luminance or xyz, got \"" + opts.emissionWeight + "\"");
        } else if (flag == "--wavelength-range") {
            hasRange = true;
            if (hasInline) Usage("--wavelength-range takes two values: --wavelength-range LO HI");
            if (i + 2 >= argc) Usage("--wavelength-range needs two values");
            opts.lambdaMin = Float(ParseFloat(flag, argv[++i]));
            opts.lambdaMax = Float(ParseFloat(flag, argv[++i]));
            if (!(opts.lambdaMin >= 360 && opts.lambdaMax <= 830 && opts.lambdaMin < opts.lambdaMax))
                Usage("--wavelength-range: need 360 <= LO < HI <= 830");
        } else if (flag == "--emission-spectrum") {
            opts.emissionSpectrum = value();
            if (opts.emissionSpectrum.empty()) Usage("--emission-spectrum needs a file name");
        } else if (flag == "--emission-table") {
            opts.emissionTable = value();
            if (opts.emissionTable.empty()) Usage("--emission-table needs a file name");
        } else if (flag == "--material-reflectances") {
            opts.materialReflectances = value();
            if (opts.materialReflectances.empty()) Usage("--material-reflectances needs a file name");
        } else if (flag == "--wavelength-pdf") {
            opts.wavelengthTable = value();
            if (opts.wavelengthTable.empty()) Usage("--wavelength-pdf needs a file name");
        } else if (flag == "--wavelength-guiding") {
            opts.wavelengthGuiding = true;
        } else if (flag == "--guiding-prepass-share") {
            guidingOption = flag;
            opts.guidingPrepassShare = ParseFloat(flag, value());
            if (!(opts.guidingPrepassShare > 0 && opts.guidingPrepassShare <= 1))
                Usage("--guiding-prepass-share: expected a share in (0, 1]");
        } else if (flag == "--guiding-tables") {
            guidingOption = flag;
            opts.guidingTables = int(ParseInt(flag, value(), 1, kMaxGuidingTables));
        } else if (flag == "--guiding-defensive") {
            guidingOption = flag;
            opts.guidingDefensive = ParseFloat(flag, value());
            if (!(opts.guidingDefensive > 0 && opts.guidingDefensive <= 1))
                Usage("--guiding-defensive: expected a share in (0, 1] (0 would leave lamps the "
                      "pre-pass missed unsampled: a biased image)");
        } else if (flag == "--guiding-tile") {
            guidingOption = flag;
            opts.guidingTile = int(ParseInt(flag, value(), 1, kMaxGuidingTile));
        } else if (flag == "--wavelength-guiding-tables") {
            guidingOption = flag;
            opts.guidingTablesDir = value();
            if (opts.guidingTablesDir.empty()) Usage("--wavelength-guiding-tables needs a folder");
        } else if (flag == "--wavelength-guiding-spectra") {
            guidingOption = flag;
            opts.guidingSpectraDir = value();
            if (opts.guidingSpectraDir.empty()) Usage("--wavelength-guiding-spectra needs a folder");
        } else if (flag == "--wavelength-repeats") {
            opts.wavelengthRepeats = int(ParseInt(flag, value(), 1, 1 << 16));
        } else if (flag == "--wavelength-seed") {
            opts.wavelengthSeed = uint64_t(ParseInt(flag, value(), 0, (1LL << 62)));
        } else if (flag == "--wavelength-pdf-defensive") {
            hasDefensive = true;
            opts.defensiveShare = Float(ParseFloat(flag, value()));
            if (!(opts.defensiveShare >= 0 && opts.defensiveShare <= 1))
                Usage("--wavelength-pdf-defensive: expected a share in [0, 1]");
        } else {
            Usage("unknown option \"" + flag + "\"");
        }
        if (flag == "--wavelength-sampling" || flag == "--wavelength-range") hasBuiltinSampling = true;
    }
    if (opts.cropWindow && opts.pixelBounds) Usage("give --cropwindow or --pixelbounds (--pixel), not both");
    if (!opts.mseReferenceOut.empty() && opts.mseReference.empty())
        Usage("--mse-reference-out needs --mse-reference-image");
    if (hasDefensive && opts.wavelengthTable.empty())
        Usage("--wavelength-pdf-defensive needs --wavelength-pdf");
    if (hasBuiltinSampling && !opts.wavelengthTable.empty())
        Usage("--wavelength-pdf replaces --wavelength-sampling/--wavelength-range: give one or the other");
    if (hasRange && opts.wavelengthSampling == "emission")
        Usage("--wavelength-range is for uniform sampling; emission sampling covers 360-830 nm "
              "(wherever the scene's lights emit)");
    if (hasWeight && opts.wavelengthSampling != "emission" && opts.emissionTable.empty() &&
        !opts.wavelengthGuiding)
        Usage("--emission-weight needs --wavelength-sampling emission, --wavelength-guiding or "
              "--emission-table");
    if (!guidingOption.empty() && !opts.wavelengthGuiding)
        Usage(guidingOption + " needs --wavelength-guiding");
    if (opts.wavelengthGuiding && (hasBuiltinSampling || !opts.wavelengthTable.empty()))
        Usage("--wavelength-guiding chooses each pixel's wavelength sampling itself: give no "
              "--wavelength-sampling, --wavelength-range or --wavelength-pdf with it");
    if (!opts.guidingSpectraDir.empty() && !opts.guidingTablesDir.empty())
        Usage("--wavelength-guiding-spectra writes the mixtures that --wavelength-guiding-tables "
              "reads the optimized tables of: give one or the other");
    if (!opts.guidingSpectraDir.empty() &&
        (!opts.emissionSpectrum.empty() || !opts.materialReflectances.empty() || !opts.emissionTable.empty()))
        Usage("--wavelength-guiding-spectra is a query of its own: run --emission-spectrum, "
              "--material-reflectances and --emission-table separately");

    // Logging, before anything can warn. A log file implies verbose logging (pbrt-v4).
    std::unique_ptr<std::FILE, int (*)(std::FILE *)> logFile(nullptr, &std::fclose);
    if (!opts.logFile.empty()) {
        logFile.reset(std::fopen(opts.logFile.c_str(), "w"));
        if (!logFile) {
            std::fprintf(stderr, "pbrt: %s: cannot write the log file: %s\n", opts.logFile.c_str(), std::strerror(errno));
            return 1;
        }
        SetLogFile(logFile.get());
        if (!hasLogLevel) opts.logLevel = "verbose";
    }
    SetVerbose(opts.logLevel == "verbose");
    if (opts.logLevel == "fatal") SuppressWarnings(true);
    for (const std::string &f : ignored)
        Warning(f + " has no effect here (one CPU integrator, rendering in world space, bilinear textures)");

    try {
        // A bad wavelength table stops pbrt before the scene is even parsed (the scene
        // builder loads it again for the render; reading a table is cheap).
        if (!opts.wavelengthTable.empty())
            WavelengthSampler::FromTable(opts.wavelengthTable, opts.defensiveShare);
        // Fail before parsing and rendering, not after, when the image cannot be written
        // there (the scene builder checks the film's "filename" the same way).
        if (!opts.emissionSpectrum.empty() || !opts.materialReflectances.empty() ||
            !opts.emissionTable.empty()) {
            // Scene queries (design §5.6): everything is computed before anything is written.
            for (const std::string &p : {opts.emissionSpectrum, opts.materialReflectances, opts.emissionTable})
                if (!p.empty()) CheckOutputFilePath(p);
            std::unique_ptr<Scene> scene = LoadScene(files, opts);
            std::optional<EmissionSpectrum> e;
            std::optional<MaterialReflectances> m;
            std::optional<EmissionTable> t;
            if (!opts.emissionSpectrum.empty()) e = SceneEmissionSpectrum(*scene);
            if (!opts.materialReflectances.empty()) m = SceneMaterialReflectances(*scene);
            if (!opts.emissionTable.empty()) {
                if (scene->lights.empty()) (void)SceneEmissionSpectrum(*scene);  // "no emitters"
                t = SceneEmissionTable(*scene, opts.emissionWeight);
            }
            if (e) WriteEmissionSpectrum(opts.emissionSpectrum, *e);
            if (m) WriteMaterialReflectances(opts.materialReflectances, *m);
            if (t) {
                std::string source;
                for (const std::string &f : files) source += (source.empty() ? "" : " ") + f;
                WriteEmissionTable(opts.emissionTable, *t, source.empty() ? "<standard input>" : source);
            }
            if (!opts.quiet && t)
                std::fprintf(stderr, "pbrt: wrote %s: the emission-sampling table (%s weight), %zu "
                                     "nodes, built in %.3g ms\n",
                             opts.emissionTable.c_str(), t->weight.c_str(), t->table->grid.size(),
                             t->seconds * 1e3);
            if (!opts.quiet && e)
                std::fprintf(stderr, "pbrt: wrote %s: the emitted spectral power at %zu wavelengths\n",
                             opts.emissionSpectrum.c_str(), e->lambdas.size());
            if (!opts.quiet && m)
                std::fprintf(stderr, "pbrt: wrote %s: the reflectances of %zu materials\n",
                             opts.materialReflectances.c_str(), m->labels.size());
            return 0;
        }
        std::string source;
        for (const std::string &f : files) source += (source.empty() ? "" : " ") + f;
        if (source.empty()) source = "<standard input>";
        GuidingSettings guiding;
        guiding.prepassShare = opts.guidingPrepassShare;
        guiding.maxTables = opts.guidingTables;
        guiding.defensive = opts.guidingDefensive;
        guiding.tile = opts.guidingTile;
        guiding.weight = opts.emissionWeight;
        guiding.tablesDir = opts.guidingTablesDir;
        if (!opts.guidingTablesDir.empty()) {
            std::error_code ec;
            if (!std::filesystem::is_directory(opts.guidingTablesDir, ec))
                throw PbrtError("--wavelength-guiding-tables \"" + opts.guidingTablesDir +
                                "\": not a folder");
        }
        if (!opts.guidingSpectraDir.empty()) {
            // Wavelength guiding's query (design §5.2): the pre-pass and the mixtures, no image.
            std::error_code ec;
            std::filesystem::path dir(opts.guidingSpectraDir);
            if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
                throw PbrtError("--wavelength-guiding-spectra \"" + opts.guidingSpectraDir + "\": not a folder");
            // The folder (made when missing) must be writable, or its parent when it is missing.
            CheckOutputFilePath(std::filesystem::is_directory(dir, ec) ? (dir / "clusters.txt").string()
                                                                       : dir.string());
            std::unique_ptr<Scene> scene = LoadScene(files, opts);
            if (scene->lights.empty()) (void)SceneEmissionSpectrum(*scene);  // "no emitters"
            WavelengthGuide guide = BuildWavelengthGuide(*scene, guiding, opts.nThreads, opts.quiet);
            WriteGuidingSpectra(opts.guidingSpectraDir, guide, source);
            if (!opts.quiet)
                std::fprintf(stderr, "pbrt: wrote %zu mixture spectra to %s (%zu kinds of light, pre-pass "
                                     "%d paths per tile of %dx%d, %.3g s CPU)\n",
                             guide.tables.size(), opts.guidingSpectraDir.c_str(), guide.kinds.size(),
                             guide.prepassPathsPerTile, guide.tile, guide.tile, guide.cpuSeconds);
            return 0;
        }
        if (!opts.outfile.empty()) CheckOutputImagePath(opts.outfile);
        if (!opts.mseReferenceOut.empty()) CheckOutputFilePath(opts.mseReferenceOut);
        // The reference is read before the scene: a bad one stops pbrt before any work.
        std::optional<Image> reference;
        if (!opts.mseReference.empty()) reference = ReadImage(opts.mseReference, false);
        std::unique_ptr<Scene> scene = LoadScene(files, opts);
        std::string outfile = opts.outfile.empty() ? scene->film->Settings().filename : opts.outfile;
        std::optional<WavelengthGuide> guide;
        if (opts.wavelengthGuiding) {
            std::error_code ec;
            const std::string dir = GuidingOutputDir(outfile);
            if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
                throw PbrtError("\"" + dir + "\": the guiding output folder's name is taken by a file");
        }
        const FilmSettings &fs = scene->film->Settings();
        if (reference) CheckMSEReference(opts.mseReference, *reference, fs);
        if (!opts.quiet)
            std::fprintf(stderr, "pbrt: %dx%d pixels, %d spp (%s), maxdepth %d, wavelengths: %s\n",
                         fs.pixelBounds.Width(), fs.pixelBounds.Height(),
                         scene->sampler.SamplesPerPixel(), scene->sampler.Description().c_str(),
                         scene->integrator.maxDepth, scene->wavelengths.Description().c_str());
        Verbose("film " + std::to_string(fs.fullResolution.x) + "x" + std::to_string(fs.fullResolution.y) +
                ", pixel bounds [" + std::to_string(fs.pixelBounds.pMin.x) + ", " + std::to_string(fs.pixelBounds.pMax.x) +
                ") x [" + std::to_string(fs.pixelBounds.pMin.y) + ", " + std::to_string(fs.pixelBounds.pMax.y) +
                "), camera " + scene->camera->Description() + ", output " + outfile);

        // Wavelength guiding: the pre-pass and the tables count in the render's time.
        if (opts.wavelengthGuiding && scene->wavelengths.IsTable())
            guide = BuildWavelengthGuide(*scene, guiding, opts.nThreads, opts.quiet);
        if (guide && !opts.quiet)
            std::fprintf(stderr, "pbrt: wavelength guiding: %zu table%s for %zu kinds of light, pre-pass "
                                 "%d paths per tile of %dx%d pixels, %.3g s CPU, %zu bytes\n",
                         guide->tables.size(), guide->tables.size() == 1 ? "" : "s", guide->kinds.size(),
                         guide->prepassPathsPerTile, guide->tile, guide->tile, guide->cpuSeconds,
                         guide->MemoryBytes());

        // Passes only when something is done between them (pbrt-v4's waves).
        std::ofstream mseOut;
        if (!opts.mseReferenceOut.empty()) mseOut.open(opts.mseReferenceOut);
        std::function<void(int)> afterPass;
        if (opts.writePartialImages || mseOut.is_open())
            afterPass = [&](int sppDone) {
                if (mseOut.is_open())
                    mseOut << sppDone << " " << MeanSquaredError(scene->film->GetImage(), *reference) << "\n";
                if (opts.writePartialImages && sppDone < scene->sampler.SamplesPerPixel()) {
                    ImageMetadata m;
                    m.ints["samplesPerPixel"] = sppDone;
                    scene->film->WriteImage(outfile, m);
                    Verbose("wrote the partial image " + outfile + " at " + std::to_string(sppDone) + " spp");
                }
            };
        RenderStats stats = Render(*scene, opts.nThreads, opts.quiet, opts.wavelengthRepeats, afterPass,
                                   guide ? &*guide : nullptr);
        if (guide) {
            stats.cpuSeconds += guide->cpuSeconds;
            stats.wallSeconds += guide->wallSeconds;
        }
        ImageMetadata metadata = RenderMetadata(*scene, stats);
        if (guide) {
            AddGuidingMetadata(metadata, *guide);
            WriteGuidingOutputs(outfile, *guide, source);
        }
        std::optional<double> mse;
        if (reference) metadata.floats["MSE"] = float(*(mse = MeanSquaredError(scene->film->GetImage(), *reference)));
        scene->film->WriteImage(outfile, metadata);
        if (mseOut.is_open() && !mseOut.flush())
            throw PbrtError(opts.mseReferenceOut + ": cannot write the MSE values");
        if (!opts.quiet)
            std::fprintf(stderr,
                         "pbrt: wrote %s; rendered in %.2f s: %llu paths, %.3f M paths/s, "
                         "%.3f M paths per CPU-second\n",
                         outfile.c_str(), stats.wallSeconds, (unsigned long long)stats.paths,
                         stats.paths / std::max(stats.wallSeconds, 1e-9) * 1e-6,
                         stats.paths / std::max(stats.cpuSeconds, 1e-9) * 1e-6);
        if (mse) std::printf("MSE vs %s: %.9g\n", opts.mseReference.c_str(), *mse);
        if (opts.stats) PrintStats(stats);
        if (logUtilization)
            Verbose("utilization: " + std::to_string(stats.cpuSeconds) + " CPU seconds in " +
                    std::to_string(stats.wallSeconds) + " s (" +
                    std::to_string(stats.cpuSeconds / std::max(stats.wallSeconds, 1e-9)) + " cores), peak memory " +
                    std::to_string(PeakMemoryBytes() / 1e6) + " MB");
    } catch (const PbrtError &e) {
        std::fprintf(stderr, "pbrt: %s\n", e.what());
        if (logFile) std::fprintf(logFile.get(), "pbrt: %s\n", e.what());
        return 1;
    } catch (const std::bad_alloc &) {
        std::fprintf(stderr, "pbrt: out of memory\n");
        return 1;
    }
    return 0;
}
