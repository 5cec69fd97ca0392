// Pixel reconstruction filters with filter importance sampling: a camera ray's film
// position is drawn from the filter's own distribution around the pixel centre, so each
// sample carries the weight f(p) / pdf(p) and only touches its own pixel.
//
//   "box"      (xradius, yradius = 0.5)           f = 1 inside the radius
//   "triangle" (xradius, yradius = 2)             f = max(0, rx - |x|) max(0, ry - |y|)
//   "gaussian" (xradius, yradius = 1.5, sigma 0.5) f = (g(x) - g(rx)) (g(y) - g(ry)), g the
//                                                  normal density (pbrt-v4's definition)
// All three are separable and non-negative and are sampled exactly, so the weight is the
// filter's integral, the same for every sample.
#pragma once

#include <pbrt/util/vecmath.h>

#include <string>

namespace pbrt {

class ParameterDictionary;

struct FilterSample {
    Point2f p;     // offset from the pixel centre, in pixels
    Float weight;  // f(p) / pdf(p)
};

class Filter {
  public:
    enum class Type { Box, Triangle, Gaussian };

    static Filter Box(Vector2f radius) { return Filter(Type::Box, radius, 0); }
    static Filter Triangle(Vector2f radius) { return Filter(Type::Triangle, radius, 0); }
    static Filter Gaussian(Vector2f radius, Float sigma) { return Filter(Type::Gaussian, radius, sigma); }
    // From a PixelFilter directive; throws PbrtError for unsupported filters.
    static Filter Create(const std::string &name, const ParameterDictionary &params,
                         const FileLoc &loc);

    Type GetType() const { return type; }
    Vector2f Radius() const { return radius; }
    std::string Description() const;

    Float Evaluate(Point2f p) const;
    Float Integral() const { return integral; }
    // The sample/pdf/invert triple of the normalized filter f / Integral().
    FilterSample Sample(Point2f u) const;
    Float PDF(Point2f p) const;
    Point2f InvertSample(Point2f p) const;

  private:
    Filter(Type type, Vector2f radius, Float sigma);
    Float Evaluate1D(Float x, Float r) const;
    Float Integral1D(Float r) const;
    Float Sample1D(Float u, Float r) const;
    Float PDF1D(Float x, Float r) const;
    Float Invert1D(Float x, Float r) const;

    Type type = Type::Box;
    Vector2f radius{0.5f, 0.5f};
    Float sigma = 0.5f;
    Float integral = 1;  // computed once: it is every sample's weight
};

}  // namespace pbrt
