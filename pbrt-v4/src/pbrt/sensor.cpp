#include <pbrt/sensor.h>

namespace pbrt {

FilmSensor::FilmSensor(const RGBColorSpace *outputSpace, Float imagingRatio)
    : outputSpace(outputSpace), imagingRatio(imagingRatio) {
    if (!outputSpace) throw PbrtError("film sensor needs an output colour space");
}

XYZ FilmSensor::ToXYZ(const SampledSpectrum &L, const SampledWavelengths &lambda) const {
    // The Monte Carlo estimate of the integral of each matching function times L.
    SampledSpectrum Lw = SafeDiv(L, lambda.PDF());
    return XYZ((Spectra::X().Sample(lambda) * Lw).Average(),
               (Spectra::Y().Sample(lambda) * Lw).Average(),
               (Spectra::Z().Sample(lambda) * Lw).Average()) *
           imagingRatio;
}

RGB FilmSensor::ToOutputRGB(const SampledSpectrum &L, const SampledWavelengths &lambda) const {
    return outputSpace->ToRGB(ToXYZ(L, lambda));
}

}  // namespace pbrt
