#include <pbrt/wavelength_coverage.h>

#include <map>
#include <sstream>

namespace pbrt {

std::vector<UnsampledEmission> FindUnsampledEmission(const WavelengthSampler &sampler,
                                                     const std::vector<Light> &lights) {
    std::vector<UnsampledEmission> out;
    if (!sampler.IsTable()) return out;
    const double lo = sampler.MinLambda(), hi = sampler.MaxLambda();
    std::vector<std::pair<double, double>> gaps;
    for (auto [a, b] : sampler.ZeroDensityIntervals()) gaps.emplace_back(a, b);
    auto cmfs = [](double lambda, double xyz[3]) {
        const Float l = Float(lambda);
        xyz[0] = Spectra::X()(l);
        xyz[1] = Spectra::Y()(l);
        xyz[2] = Spectra::Z()(l);
    };
    // Each distinct (spectrum, directive) once: the triangles of an area light share both.
    std::map<std::pair<const Spectrum *, std::string>, bool> seen;
    for (const Light &light : lights) {
        const Spectrum *s = light.EmissionSpectrum().get();
        if (!s || !(light.Power() > 0)) continue;
        FileLoc loc = light.Loc();
        if (!seen.emplace(std::make_pair(s, loc.ToString()), true).second) continue;
        UnsampledEmission u;
        static_cast<wavelength_table::Coverage &>(u) = wavelength_table::MeasureCoverage(
            gaps, lo, hi, [s](double lambda) { return double((*s)(Float(lambda))); }, cmfs);
        if (u.gaps.empty() && u.outside.empty()) continue;
        u.loc = std::move(loc);
        out.push_back(std::move(u));
    }
    return out;
}

std::vector<std::string> UnsampledEmissionWarnings(const WavelengthSampler &sampler,
                                                   const std::vector<Light> &lights) {
    std::vector<std::string> out;
    std::ostringstream uniform;
    uniform << "compare with images rendered over the same range (--wavelength-sampling uniform "
            << "--wavelength-range " << sampler.MinLambda() << " " << sampler.MaxLambda() << ")";
    for (const UnsampledEmission &u : FindUnsampledEmission(sampler, lights)) {
        const bool known = !u.loc.filename.empty();
        for (const std::string &w : wavelength_table::CoverageWarnings(
                 u, known ? "this light" : "a light", sampler.MinLambda(), sampler.MaxLambda(),
                 sampler.Description(), uniform.str()))
            out.push_back(known ? u.loc.ToString() + ": " + w : w);
    }
    return out;
}

}  // namespace pbrt
