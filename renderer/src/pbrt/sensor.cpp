#include <pbrt/sensor.h>

namespace pbrt {

FilmSensor::FilmSensor(const RGBColorSpace *outputSpace, Float imagingRatio)
    : outputSpace(outputSpace), imagingRatio(imagingRatio) {
    if (!outputSpace) throw PbrtError("film sensor needs an output colour space");
}

XYZ FilmSensor::ToXYZ(const SampledSpectrum &L, const SampledWavelengths &lambda) const {
    // The Monte Carlo estimate of the integral of each matching function times L.
    SampledSpectrum Lw = SafeDiv(L, lambda.PDF());
    // The three matching functions share one table index per wavelength (the values of
    // Spectra::X().Sample(lambda) and so on).
    const DenselySampledSpectrum &X = Spectra::X(), &Y = Spectra::Y(), &Z = Spectra::Z();
    SampledSpectrum x, y, z;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        int k = DenselySampledSpectrum::Index(lambda[i]);
        if (k >= 0) {
            x[i] = X.At(k);
            y[i] = Y.At(k);
            z[i] = Z.At(k);
        }
    }
    return XYZ((x * Lw).Average(), (y * Lw).Average(), (z * Lw).Average()) * imagingRatio;
}

RGB FilmSensor::ToOutputRGB(const SampledSpectrum &L, const SampledWavelengths &lambda) const {
    return outputSpace->ToRGB(ToXYZ(L, lambda));
}

}  // namespace pbrt
