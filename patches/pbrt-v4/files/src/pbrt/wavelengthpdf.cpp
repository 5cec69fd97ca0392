// wavelengthpdf.cpp -- loading the --wavelength-pdf table and checking it against the
// scene's lights (added by the wavelength-pdf patch; Apache-2.0). See wavelengthpdf.h.
#include <pbrt/wavelengthpdf.h>

#include <pbrt/options.h>
#include <pbrt/paramdict.h>
#include <pbrt/util/colorspace.h>
#include <pbrt/util/error.h>
#include <pbrt/util/spectrum.h>

#if defined(PBRT_BUILD_GPU_RENDERER)
#include <pbrt/gpu/util.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <mutex>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

namespace pbrt {

WavelengthTableState WavelengthTableCPU;
#if defined(PBRT_BUILD_GPU_RENDERER)
__constant__ WavelengthTableState WavelengthTableGPU;
#endif

namespace {

// The table as loaded (host), for the emission check; nullptr without --wavelength-pdf.
const wavelength_table::Table *hostTable = nullptr;
std::string tableDescription;

[[noreturn]] void Fail(const std::string &message) {
    // The message format of the toolkit's own pbrt: "pbrt: FILE:LINE: reason", status 1.
    std::fprintf(stderr, "pbrt: %s\n", message.c_str());
    std::exit(1);
}

// SampledWavelengthsLayout is only right while SampledWavelengths stores lambda, then pdf.
void CheckLayout() {
    SampledWavelengthsLayout l;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        l.lambda[i] = Float(400 + i);
        l.pdf[i] = Float(0.5 + i);
    }
    SampledWavelengths s = ToSampledWavelengths(l);
    for (int i = 0; i < NSpectrumSamples; ++i)
        if (s[i] != l.lambda[i] || s.PDF()[i] != l.pdf[i])
            Fail("--wavelength-pdf: this pbrt-v4's SampledWavelengths does not store "
                 "lambda then pdf; the wavelength-pdf patch does not fit this version");
}

std::string Percent(double f) {
    std::ostringstream s;
    s << std::setprecision(3) << 100 * f << "%";
    return s.str();
}

std::string Intervals(const std::vector<std::pair<double, double>> &v) {
    std::ostringstream s;
    for (size_t i = 0; i < v.size(); ++i) {
        if (i)
            s << (i + 1 == v.size() ? " and " : ", ");
        s << "[" << v[i].first << ", " << v[i].second << "]";
    }
    s << " nm";
    return s.str();
}

// Emission outside the table's range below these fractions is not worth a warning (the
// thresholds of the toolkit's pbrt, design §5): a 380..780 nm table misses about 1e-5 of the
// luminance of a flat lamp; 1e-3 of a tristimulus value is about 0.1 CIEDE2000.
constexpr double kOutsideLuminanceWarnFraction = 1e-4;
constexpr double kOutsideTristimulusWarnFraction = 1e-3;
// Midpoint-rule step [nm]: sees the edges of 5 nm table segments and 1 nm emission lines.
constexpr double kStep = 0.1;

}  // namespace

void InitWavelengthTable(const std::string &path, const std::string &defensiveText) {
    if (path.empty()) {
        if (!defensiveText.empty())
            Fail("--wavelength-pdf-defensive needs --wavelength-pdf");
        return;
    }
    double defensiveShare = 0;
    if (!defensiveText.empty()) {
        char *end = nullptr;
        defensiveShare = std::strtod(defensiveText.c_str(), &end);
        if (end == defensiveText.c_str() || *end != '\0' ||
            !(defensiveShare >= 0 && defensiveShare <= 1))
            Fail("--wavelength-pdf-defensive: expected a share in [0, 1], got \"" +
                 defensiveText + "\"");
    }
    CheckLayout();
    wavelength_table::Table table;
    try {
        table = wavelength_table::LoadTable(path);
        if (defensiveShare > 0)
            table = wavelength_table::WithDefensiveMixture(table, defensiveShare);
    } catch (const wavelength_table::TableError &e) {
        Fail(e.what());  // "FILE:LINE: reason" (or "FILE: reason" for a missing file)
    }
    const std::vector<double> packed = wavelength_table::Pack(table);
    const int n = int(table.grid.size());
    {
        std::ostringstream s;
        s << "table " << table.source << " (" << n << " nodes, " << table.grid.front() << ".."
          << table.grid.back() << " nm";
        if (defensiveShare > 0)
            s << ", defensive share " << defensiveShare;
        s << ")";
        tableDescription = s.str();
    }
    hostTable = new wavelength_table::Table(std::move(table));

    // The packed arrays live for the rest of the run.
    double *cpuCopy = new double[packed.size()];
    std::copy(packed.begin(), packed.end(), cpuCopy);
    WavelengthTableCPU.view = wavelength_table::ViewPacked(cpuCopy, n);
    WavelengthTableCPU.active = true;
#if defined(PBRT_BUILD_GPU_RENDERER)
    if (Options->useGPU) {
        // Managed memory the device reads; the state itself goes to a __constant__.
        double *gpuCopy = nullptr;
        CUDA_CHECK(cudaMallocManaged(&gpuCopy, packed.size() * sizeof(double)));
        std::copy(packed.begin(), packed.end(), gpuCopy);
        WavelengthTableState gpuState;
        gpuState.active = true;
        gpuState.view = wavelength_table::ViewPacked(gpuCopy, n);
        CUDA_CHECK(cudaMemcpyToSymbol(WavelengthTableGPU, &gpuState, sizeof(gpuState)));
        CUDA_CHECK(cudaDeviceSynchronize());
    }
#endif
    if (!Options->quiet)
        std::printf("Wavelengths: %s, balance heuristic over its four densities.\n",
                    tableDescription.c_str());
}

void WarnUnsampledEmission(const std::string &lightName, const ParameterDictionary &params,
                           const FileLoc *loc) {
    if (!hostTable)
        return;
    // One report per directive (AddLight/AddAreaLight may see one twice under instancing).
    static std::mutex mutex;
    static std::set<std::string> seen;
    const std::string where = loc ? loc->ToString() : std::string();
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (!seen.insert(where + "|" + lightName).second)
            return;
    }
    // The light's emission spectrum as upstream's light constructors get it: "L" (area,
    // distant, infinite) or "I" (point, spot, goniometric, projection); without one, the
    // colour space's illuminant, which the lights default to.
    Spectrum s = params.GetOneSpectrum("L", nullptr, SpectrumType::Illuminant, Allocator());
    if (!s)
        s = params.GetOneSpectrum("I", nullptr, SpectrumType::Illuminant, Allocator());
    if (!s && params.ColorSpace())
        s = Spectrum(const_cast<DenselySampledSpectrum *>(&params.ColorSpace()->illuminant));
    if (!s || (lightName == "infinite" && !params.GetOneString("filename", "").empty()))
        return;  // an image's emission has no single spectrum to check

    const wavelength_table::Table &t = *hostTable;
    const double lo = t.grid.front(), hi = t.grid.back();
    const std::vector<std::pair<double, double>> gaps = wavelength_table::ZeroMixtureIntervals(t);
    double total[3] = {0, 0, 0}, outside[3] = {0, 0, 0}, inGapsY = 0;
    std::vector<bool> gapEmits(gaps.size(), false);
    bool emitsBelow = false, emitsAbove = false;
    const int nSteps = int(std::lround((Lambda_max - Lambda_min) / kStep));
    for (int i = 0; i < nSteps; ++i) {
        const double lambda = Lambda_min + (i + 0.5) * kStep;
        // Upstream's lights hold a DenselySampledSpectrum: the value at the nearest nm.
        const double e = s(Float(std::lround(lambda)));
        if (!(e > 0))
            continue;
        const Float l = Float(lambda);
        const double w[3] = {e * Spectra::X()(l), e * Spectra::Y()(l), e * Spectra::Z()(l)};
        for (int c = 0; c < 3; ++c)
            total[c] += w[c];
        if (lambda < lo || lambda > hi) {
            (lambda < lo ? emitsBelow : emitsAbove) = true;
            for (int c = 0; c < 3; ++c)
                outside[c] += w[c];
            continue;
        }
        for (size_t g = 0; g < gaps.size(); ++g)
            if (lambda > gaps[g].first && lambda < gaps[g].second) {
                gapEmits[g] = true;
                inGapsY += w[1];
            }
    }
    if (!(total[1] > 0 || total[0] > 0 || total[2] > 0))
        return;
    std::vector<std::pair<double, double>> emittingGaps;
    for (size_t g = 0; g < gaps.size(); ++g)
        if (gapEmits[g])
            emittingGaps.push_back(gaps[g]);
    const double gapY = total[1] > 0 ? inGapsY / total[1] : 0;
    const double outsideY = total[1] > 0 ? outside[1] / total[1] : 0;
    double outsideXYZ = 0;
    for (int c = 0; c < 3; ++c)
        if (total[c] > 0)
            outsideXYZ = std::max(outsideXYZ, outside[c] / total[c]);

    if (!emittingGaps.empty()) {
        std::ostringstream m;
        m << "the wavelength sampling density is zero on " << Intervals(emittingGaps)
          << ", where this light emits (" << Percent(gapY) << " of its luminance): paths "
          << "never carry those wavelengths, so the image is biased; mix a uniform share into "
          << "the table with --wavelength-pdf-defensive 0.01 [" << tableDescription << "]";
        Warning(loc, "%s", m.str());
    }
    if ((emitsBelow || emitsAbove) && (outsideY > kOutsideLuminanceWarnFraction ||
                                       outsideXYZ > kOutsideTristimulusWarnFraction)) {
        std::vector<std::pair<double, double>> out;
        if (emitsBelow)
            out.emplace_back(Lambda_min, lo);
        if (emitsAbove)
            out.emplace_back(hi, Lambda_max);
        std::ostringstream m;
        m << "this light emits on " << Intervals(out) << ", outside the range of the "
          << "wavelength table [" << lo << ", " << hi << "] nm, where paths never carry "
          << "wavelengths: the image misses " << Percent(outsideY) << " of its luminance (up "
          << "to " << Percent(outsideXYZ) << " of X, Y or Z). --wavelength-pdf-defensive only "
          << "covers the table's range; extend the table's grid to 360..830 nm ["
          << tableDescription << "]";
        Warning(loc, "%s", m.str());
    }
}

}  // namespace pbrt
