// wavelengthpdf.cpp -- loading the --wavelength-pdf table and checking it against the
// scene's lights (added by the wavelength-pdf patch; Apache-2.0). See wavelengthpdf.h.
#include <pbrt/wavelengthpdf.h>

#include <pbrt/lights.h>
#include <pbrt/options.h>
#include <pbrt/paramdict.h>
#include <pbrt/util/colorspace.h>
#include <pbrt/util/error.h>
#include <pbrt/util/spectrum.h>

#if defined(PBRT_BUILD_GPU_RENDERER)
#include <pbrt/gpu/util.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <map>
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

// --wavelength-sampling emission: requested, and its weight.
bool emissionRequested = false;
std::string emissionWeight = "spd";

// Where each light was defined, for the emission table's error messages.
struct EmitterInfo {
    std::string where;                 // "FILE:LINE:COL" of its directive
    bool image = false;                // its emission is an RGB image ("filename")
    const RGBColorSpace *colorSpace = nullptr;
};
std::mutex emitterMutex;
std::vector<EmitterInfo> lightSources;             // in BasicScene::AddLight order
std::map<const void *, EmitterInfo> emitterByLight;  // by the light's object

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

// Makes `table` the one every camera path samples, on the CPU and (with --gpu) the device.
void InstallTable(wavelength_table::Table table, const std::string &description) {
    CheckLayout();
    const std::vector<double> packed = wavelength_table::Pack(table);
    const int n = int(table.grid.size());
    tableDescription = description;

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

// The parameter `name` of a directive, without marking it as used (upstream reports
// parameters nobody looked up; a lookup here must not hide that).
const ParsedParameter *FindParameter(const ParameterDictionary &params, const char *name) {
    for (const ParsedParameter *p : params.GetParameterVector())
        if (p->name == name)
            return p;
    return nullptr;
}

EmitterInfo MakeEmitterInfo(const ParameterDictionary &params, const FileLoc *loc) {
    EmitterInfo info;
    info.where = loc ? loc->ToString() : std::string("a light");
    const ParsedParameter *file = FindParameter(params, "filename");
    info.image = file && !file->strings.empty() && !file->strings[0].empty();
    info.colorSpace = params.ColorSpace();
    return info;
}

}  // namespace

void InitWavelengthTable(const std::string &path, const std::string &defensiveText,
                         const std::string &sampling, const std::string &weight) {
    if (!sampling.empty() && sampling != "visible" && sampling != "emission")
        Fail("--wavelength-sampling: expected visible or emission, got \"" + sampling + "\"");
    if (!weight.empty() && sampling != "emission")
        Fail("--emission-weight needs --wavelength-sampling emission");
    if (!weight.empty() && weight != "spd" && weight != "luminance" && weight != "xyz")
        Fail("--emission-weight: expected spd, luminance or xyz, got \"" + weight + "\"");
    if (sampling == "emission") {
        if (!path.empty())
            Fail("--wavelength-pdf replaces --wavelength-sampling emission: give one or the other");
        if (!defensiveText.empty())
            Fail("--wavelength-pdf-defensive needs --wavelength-pdf");
        emissionRequested = true;
        if (!weight.empty())
            emissionWeight = weight;
        CheckLayout();
        return;
    }
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
    wavelength_table::Table table;
    try {
        table = wavelength_table::LoadTable(path);
        if (defensiveShare > 0)
            table = wavelength_table::WithDefensiveMixture(table, defensiveShare);
    } catch (const wavelength_table::TableError &e) {
        Fail(e.what());  // "FILE:LINE: reason" (or "FILE: reason" for a missing file)
    }
    std::ostringstream s;
    s << "table " << table.source << " (" << table.grid.size() << " nodes, " << table.grid.front()
      << ".." << table.grid.back() << " nm";
    if (defensiveShare > 0)
        s << ", defensive share " << defensiveShare;
    s << ")";
    hostTable = new wavelength_table::Table(table);
    InstallTable(std::move(table), s.str());
}

// ---- --wavelength-sampling emission ------------------------------------------------------

void NoteLightSource(const std::string &, const ParameterDictionary &params, const FileLoc *loc) {
    if (!emissionRequested)
        return;
    std::lock_guard<std::mutex> lock(emitterMutex);
    lightSources.push_back(MakeEmitterInfo(params, loc));
}

void NoteLightSourceCreated(size_t index, const Light &light) {
    if (!emissionRequested || !light)
        return;
    std::lock_guard<std::mutex> lock(emitterMutex);
    if (index < lightSources.size())
        emitterByLight[light.ptr()] = lightSources[index];
}

void NoteAreaLight(const Light &light, const ParameterDictionary &params, const FileLoc *loc) {
    if (!emissionRequested || !light)
        return;
    EmitterInfo info = MakeEmitterInfo(params, loc);
    std::lock_guard<std::mutex> lock(emitterMutex);
    emitterByLight[light.ptr()] = std::move(info);
}

void InitEmissionWavelengthTable(const Light *lights, size_t count) {
    if (!emissionRequested || WavelengthTableCPU.active)
        return;
    const auto start = std::chrono::steady_clock::now();
    if (count == 0) {
        Warning("the scene has no lights: --wavelength-sampling emission has no emission to "
                "sample; upstream's wavelength sampling instead");
        return;
    }
    constexpr int lo = int(Lambda_min), hi = int(Lambda_max), nBins = hi - lo + 1;
    auto infoOf = [&](const Light &l) {
        std::lock_guard<std::mutex> lock(emitterMutex);
        auto it = emitterByLight.find(l.ptr());
        return it != emitterByLight.end() ? it->second : EmitterInfo{"a light", false, nullptr};
    };
    auto wavelengths = [](const Float l[NSpectrumSamples]) {
        SampledWavelengthsLayout layout;
        for (int j = 0; j < NSpectrumSamples; ++j) {
            layout.lambda[j] = l[j];
            layout.pdf[j] = 1;
        }
        return ToSampledWavelengths(layout);
    };
    // Phi at every whole nanometre (upstream's lights are step functions of the nearest nm).
    std::vector<double> phi(nBins, 0.0), one(nBins);
    for (size_t i = 0; i < count; ++i) {
        const Light &light = lights[i];
        const bool image = light.Is<ImageInfiniteLight>() || light.Is<PortalImageInfiniteLight>() ||
                           light.Is<ProjectionLight>();
        EmitterInfo info = infoOf(light);
        if (image || info.image) {
            // The colour space's illuminant times the light's power relative to it, measured
            // at four wavelengths across the visible range (exact for a grey image).
            const RGBColorSpace *cs = info.colorSpace ? info.colorSpace : RGBColorSpace::sRGB;
            const Float probe[NSpectrumSamples] = {450, 510, 570, 630};
            SampledSpectrum p = light.Phi(wavelengths(probe));
            double num = 0, den = 0;
            for (int j = 0; j < NSpectrumSamples; ++j) {
                num += double(p[j]);
                den += double(cs->illuminant(probe[j]));
            }
            const double power = den > 0 ? num / den : 0;
            for (int b = 0; b < nBins; ++b)
                one[b] = power * double(cs->illuminant(Float(lo + b)));
        } else {
            for (int b = 0; b < nBins; b += NSpectrumSamples) {
                Float l[NSpectrumSamples];
                for (int j = 0; j < NSpectrumSamples; ++j)
                    l[j] = Float(std::min(lo + b + j, hi));
                SampledSpectrum p = light.Phi(wavelengths(l));
                for (int j = 0; j < NSpectrumSamples && b + j < nBins; ++j)
                    one[b + j] = double(p[j]);
            }
        }
        for (int b = 0; b < nBins; ++b) {
            if (!std::isfinite(one[b]) || one[b] < 0)
                Fail(info.where + ": this light's emitted power is " +
                     (std::isnan(one[b]) ? "NaN" : one[b] < 0 ? "negative" : "infinite") +
                     " at " + std::to_string(lo + b) + " nm (a blackbody of 0 K, a \"scale\" "
                     "or \"power\" that overflows?), so --wavelength-sampling emission cannot "
                     "weigh it");
            phi[b] += one[b];
            if (!std::isfinite(phi[b]))
                Fail(info.where + ": the scene's total emitted power overflows at this light");
        }
    }
    // q = Phi * weight as a step function on the nanometre bins [k - 1/2, k + 1/2).
    auto weight = [](int lambda) -> double {
        const Float l = Float(lambda);
        if (emissionWeight == "luminance")
            return Spectra::Y()(l);
        if (emissionWeight == "xyz")
            return double(Spectra::X()(l)) + double(Spectra::Y()(l)) + double(Spectra::Z()(l));
        return 1.0;
    };
    constexpr double kHandOver = 1e-3;  // nm on either side of a half-nanometre
    std::vector<double> x{double(lo)}, q{phi[0] * weight(lo)};
    for (int b = 0; b + 1 < nBins; ++b) {
        const double edge = lo + b + 0.5;
        x.push_back(edge - kHandOver);
        q.push_back(phi[b] * weight(lo + b));
        x.push_back(edge + kHandOver);
        q.push_back(phi[b + 1] * weight(lo + b + 1));
    }
    x.push_back(double(hi));
    q.push_back(phi[nBins - 1] * weight(hi));
    if (!(*std::max_element(q.begin(), q.end()) > 0))
        Fail(infoOf(lights[0]).where + ": no light of the scene emits between " +
             std::to_string(lo) + " and " + std::to_string(hi) + " nm (every \"scale\" is 0?), "
             "so --wavelength-sampling emission has nothing to sample");
    wavelength_table::Table table;
    try {
        table = wavelength_table::EqualMassTable(x, q, "the scene's emission");
    } catch (const wavelength_table::TableError &e) {
        Fail(infoOf(lights[0]).where + ": --wavelength-sampling emission: " + e.what());
    }
    const double ms =
        1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::ostringstream s;
    s << "emission (the scene's emitted power"
      << (emissionWeight == "luminance" ? " times ybar"
          : emissionWeight == "xyz"     ? " times xbar + ybar + zbar"
                                        : "")
      << " in four equal-mass bands: " << table.grid.size() << " nodes, " << lo << ".." << hi
      << " nm, " << count << " lights, built in " << std::setprecision(3) << ms << " ms)";
    InstallTable(std::move(table), s.str());
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

    // The measure, thresholds and texts of design §1.5 are the header's (the toolkit's pbrt
    // warns by the same rule). Upstream's lights hold a DenselySampledSpectrum: the value at
    // the nearest nanometre.
    const wavelength_table::Coverage coverage = wavelength_table::MeasureCoverage(
        *hostTable, [&s](double lambda) { return double(s(Float(std::lround(lambda)))); },
        [](double lambda, double xyz[3]) {
            const Float l = Float(lambda);
            xyz[0] = Spectra::X()(l);
            xyz[1] = Spectra::Y()(l);
            xyz[2] = Spectra::Z()(l);
        });
    for (const std::string &w : wavelength_table::CoverageWarnings(
             coverage, "this light", hostTable->grid.front(), hostTable->grid.back(),
             tableDescription))
        Warning(loc, "%s", w);
}

}  // namespace pbrt
