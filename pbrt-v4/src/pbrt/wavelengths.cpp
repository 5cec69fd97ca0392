#include <pbrt/wavelengths.h>

#include <sstream>

namespace pbrt {

std::string VisibleWavelengthSampler::Description() const {
    return "visible (pbrt-v4: density ~ sech^2(0.0072 (lambda - 538)) on 360..830 nm, 4 stratified)";
}

std::string UniformWavelengthSampler::Description() const {
    std::ostringstream s;
    s << "uniform on " << lmin << ".." << lmax << " nm, 4 stratified";
    return s.str();
}

WavelengthSampler WavelengthSampler::Visible() { return WavelengthSampler(VisibleWavelengthSampler{}); }

WavelengthSampler WavelengthSampler::Uniform(Float lmin, Float lmax) {
    if (!(std::isfinite(lmin) && std::isfinite(lmax) && lmin > 0 && lmin < lmax)) {
        std::ostringstream s;
        s << "uniform wavelength sampling needs 0 < min < max, got [" << lmin << ", " << lmax << "] nm";
        throw PbrtError(s.str());
    }
    return WavelengthSampler(UniformWavelengthSampler{lmin, lmax});
}

SampledWavelengths WavelengthSampler::Sample(Float u) const {
    return std::visit([u](const auto &s) { return s.Sample(u); }, impl);
}

Float WavelengthSampler::PDF(Float lambda) const {
    return std::visit([lambda](const auto &s) { return s.PDF(lambda); }, impl);
}

std::string WavelengthSampler::Description() const {
    return std::visit([](const auto &s) { return s.Description(); }, impl);
}

Float WavelengthSampler::MinLambda() const {
    return std::visit([](const auto &s) { return s.MinLambda(); }, impl);
}

Float WavelengthSampler::MaxLambda() const {
    return std::visit([](const auto &s) { return s.MaxLambda(); }, impl);
}

}  // namespace pbrt
