#include <pbrt/wavelength_coverage.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

namespace pbrt {

namespace {

// Step of the midpoint rule the fractions are integrated with [nm]: fine enough to see a
// spectrum's narrow lines and the edges of 5 nm table segments (4700 evaluations a light).
constexpr double kStep = 0.1;

std::string Percent(double f) {
    std::ostringstream s;
    s << std::setprecision(3) << 100 * f << "%";
    return s.str();
}

std::string Intervals(const std::vector<std::pair<Float, Float>> &v) {
    std::ostringstream s;
    for (size_t i = 0; i < v.size(); ++i) {
        if (i) s << (i + 1 == v.size() ? " and " : ", ");
        s << "[" << v[i].first << ", " << v[i].second << "]";
    }
    s << " nm";
    return s.str();
}

// Where one emitter's light goes: the tristimulus integrals over 360..830 nm, and the parts
// inside the sampler's zero-density gaps and outside its range.
UnsampledEmission Measure(const Spectrum &s, const std::vector<std::pair<Float, Float>> &gaps,
                          double lo, double hi) {
    UnsampledEmission u;
    double total[3] = {0, 0, 0}, outside[3] = {0, 0, 0}, inGapsY = 0;
    std::vector<bool> gapEmits(gaps.size(), false);
    bool emitsBelow = false, emitsAbove = false;
    const int n = int(std::lround((Lambda_max - Lambda_min) / kStep));
    for (int i = 0; i < n; ++i) {
        const double lambda = Lambda_min + (i + 0.5) * kStep;
        const double e = s(Float(lambda));
        if (!(e > 0)) continue;
        const Float l = Float(lambda);
        const double w[3] = {e * Spectra::X()(l), e * Spectra::Y()(l), e * Spectra::Z()(l)};
        for (int c = 0; c < 3; ++c) total[c] += w[c];
        if (lambda < lo || lambda > hi) {
            (lambda < lo ? emitsBelow : emitsAbove) = true;
            for (int c = 0; c < 3; ++c) outside[c] += w[c];
            continue;
        }
        for (size_t g = 0; g < gaps.size(); ++g)
            if (lambda > gaps[g].first && lambda < gaps[g].second) {
                gapEmits[g] = true;
                inGapsY += w[1];
            }
    }
    for (size_t g = 0; g < gaps.size(); ++g)
        if (gapEmits[g]) u.gaps.push_back(gaps[g]);
    if (emitsBelow) u.outside.emplace_back(Lambda_min, Float(lo));
    if (emitsAbove) u.outside.emplace_back(Float(hi), Lambda_max);
    if (total[1] > 0) {
        u.gapLuminanceFraction = Float(inGapsY / total[1]);
        u.outsideLuminanceFraction = Float(outside[1] / total[1]);
    }
    for (int c = 0; c < 3; ++c)
        if (total[c] > 0)
            u.outsideTristimulusFraction =
                std::max(u.outsideTristimulusFraction, Float(outside[c] / total[c]));
    return u;
}

}  // namespace

std::vector<UnsampledEmission> FindUnsampledEmission(const WavelengthSampler &sampler,
                                                     const std::vector<Light> &lights) {
    std::vector<UnsampledEmission> out;
    if (!sampler.IsTable()) return out;
    const double lo = sampler.MinLambda(), hi = sampler.MaxLambda();
    const std::vector<std::pair<Float, Float>> gaps = sampler.ZeroDensityIntervals();
    // Each distinct (spectrum, directive) once: the triangles of an area light share both.
    std::map<std::pair<const Spectrum *, std::string>, bool> seen;
    for (const Light &light : lights) {
        const Spectrum *s = light.EmissionSpectrum().get();
        if (!s || !(light.Power() > 0)) continue;
        FileLoc loc = light.Loc();
        if (!seen.emplace(std::make_pair(s, loc.ToString()), true).second) continue;
        UnsampledEmission u = Measure(*s, gaps, lo, hi);
        if (u.gaps.empty() && u.outside.empty()) continue;
        u.loc = std::move(loc);
        out.push_back(std::move(u));
    }
    return out;
}

std::vector<std::string> UnsampledEmissionWarnings(const WavelengthSampler &sampler,
                                                   const std::vector<Light> &lights) {
    std::vector<std::string> out;
    for (const UnsampledEmission &u : FindUnsampledEmission(sampler, lights)) {
        const std::string who =
            u.loc.filename.empty() ? "a light" : u.loc.ToString() + ": this light";
        if (!u.gaps.empty()) {
            std::ostringstream m;
            m << "the wavelength sampling density is zero on " << Intervals(u.gaps) << ", where "
              << (u.loc.filename.empty() ? "a light" : "this light") << " emits ("
              << Percent(u.gapLuminanceFraction) << " of its luminance): paths never carry "
              << "those wavelengths, so the image is biased; mix a uniform share into the "
              << "table with --wavelength-pdf-defensive 0.01 [" << sampler.Description() << "]";
            out.push_back(u.loc.filename.empty() ? m.str() : u.loc.ToString() + ": " + m.str());
        }
        if (!u.outside.empty() && (u.outsideLuminanceFraction > kOutsideLuminanceWarnFraction ||
                                   u.outsideTristimulusFraction > kOutsideTristimulusWarnFraction)) {
            std::ostringstream m;
            m << who << " emits on " << Intervals(u.outside) << ", outside the range of the "
              << "wavelength table [" << sampler.MinLambda() << ", " << sampler.MaxLambda()
              << "] nm, where paths never carry wavelengths: the image misses "
              << Percent(u.outsideLuminanceFraction) << " of its luminance (up to "
              << Percent(u.outsideTristimulusFraction) << " of X, Y or Z). "
              << "--wavelength-pdf-defensive only covers the table's range; extend the table's "
              << "grid to 360..830 nm, or compare with images rendered over the same range "
              << "(--wavelength-sampling uniform --wavelength-range " << sampler.MinLambda()
              << " " << sampler.MaxLambda() << ") [" << sampler.Description() << "]";
            out.push_back(m.str());
        }
    }
    return out;
}

}  // namespace pbrt
