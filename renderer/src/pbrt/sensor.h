// The film's sensor: turns the radiance a path carries at its four wavelengths into RGB in
// the film's colour space. This is pbrt-v4's "cie1931" sensor (its default for the "rgb"
// film): the XYZ matching functions as the sensor's responses, so
//     XYZ = imagingRatio * ( (xbar * L / pdf).Average(), (ybar * L / pdf).Average(),
//                            (zbar * L / pdf).Average() )
// with the raw CMF values (no division by CIE_Y_integral): an emitter normalized to 1 nit
// and multiplied by its "scale" appears with Y = scale. The XYZ then goes to the output
// colour space's RGB. Entries with pdf = 0 (terminated wavelengths) contribute 0.
#pragma once

#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>

namespace pbrt {

class FilmSensor {
  public:
    // imagingRatio is pbrt-v4's exposure factor (exposure time * ISO / 100; 1 by default).
    explicit FilmSensor(const RGBColorSpace *outputSpace, Float imagingRatio = 1);

    XYZ ToXYZ(const SampledSpectrum &L, const SampledWavelengths &lambda) const;
    RGB ToOutputRGB(const SampledSpectrum &L, const SampledWavelengths &lambda) const;

    const RGBColorSpace *OutputSpace() const { return outputSpace; }
    Float ImagingRatio() const { return imagingRatio; }

  private:
    const RGBColorSpace *outputSpace;
    Float imagingRatio;
};

}  // namespace pbrt
