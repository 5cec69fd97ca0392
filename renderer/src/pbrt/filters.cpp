#include <pbrt/filters.h>

#include <pbrt/util/paramdict.h>
#include <pbrt/util/sampling.h>

#include <cmath>

namespace pbrt {

Filter::Filter(Type type, Vector2f radius, Float sigma) : type(type), radius(radius), sigma(sigma) {
    if (!(radius.x > 0) || !(radius.y > 0))
        throw PbrtError("filter radius must be positive");
    if (type == Type::Gaussian && !(sigma > 0)) throw PbrtError("gaussian filter sigma must be positive");
    // Each sample's weight is the filter's integral (see Sample): it must be a finite number.
    integral = Integral1D(radius.x) * Integral1D(radius.y);
    if (!std::isfinite(radius.x) || !std::isfinite(radius.y) || !std::isfinite(integral) ||
        !(integral > 0))
        throw PbrtError("filter radius " + std::to_string(radius.x) + " x " +
                        std::to_string(radius.y) + " is too large (the filter's integral, " +
                        "every sample's weight, overflows)");
}

Filter Filter::Create(const std::string &name, const ParameterDictionary &params,
                      const FileLoc &loc) {
    // Defaults are pbrt-v4's.
    auto radii = [&](Float def) {
        return Vector2f(params.GetOneFloat("xradius", def), params.GetOneFloat("yradius", def));
    };
    try {
        if (name == "box") return Box(radii(0.5f));
        if (name == "triangle") return Triangle(radii(2));
        if (name == "gaussian") {
            Vector2f r = radii(1.5f);
            return Gaussian(r, params.GetOneFloat("sigma", 0.5f));
        }
    } catch (const PbrtError &e) {
        throw PbrtError(loc, std::string("PixelFilter \"") + name + "\": " + e.what());
    }
    throw PbrtError(loc, "PixelFilter \"" + name +
                             "\" is not supported (supported: box, triangle, gaussian)");
}

std::string Filter::Description() const {
    std::string r = std::to_string(radius.x) + " x " + std::to_string(radius.y);
    switch (type) {
    case Type::Box: return "box " + r;
    case Type::Triangle: return "triangle " + r;
    case Type::Gaussian: return "gaussian " + r + " sigma " + std::to_string(sigma);
    }
    return "?";
}

Float Filter::Evaluate1D(Float x, Float r) const {
    switch (type) {
    case Type::Box: return std::abs(x) <= r ? 1 : 0;
    case Type::Triangle: return std::max<Float>(0, r - std::abs(x));
    case Type::Gaussian: return ShiftedGaussian(x, sigma, r);
    }
    return 0;
}

Float Filter::Integral1D(Float r) const {
    switch (type) {
    case Type::Box: return 2 * r;
    case Type::Triangle: return r * r;
    case Type::Gaussian: return ShiftedGaussianIntegral(sigma, r);
    }
    return 0;
}

Float Filter::Sample1D(Float u, Float r) const {
    switch (type) {
    case Type::Box: return Lerp(u, -r, r);
    case Type::Triangle: return SampleTent(u, r);
    case Type::Gaussian: return SampleShiftedGaussian(u, sigma, r);
    }
    return 0;
}

Float Filter::PDF1D(Float x, Float r) const {
    switch (type) {
    case Type::Box: return std::abs(x) <= r ? 1 / (2 * r) : 0;
    case Type::Triangle: return TentPDF(x, r);
    case Type::Gaussian: return ShiftedGaussianPDF(x, sigma, r);
    }
    return 0;
}

Float Filter::Invert1D(Float x, Float r) const {
    switch (type) {
    case Type::Box: return Clamp((x + r) / (2 * r), 0, OneMinusEpsilon);
    case Type::Triangle: return InvertTentSample(x, r);
    case Type::Gaussian: return InvertShiftedGaussianSample(x, sigma, r);
    }
    return 0;
}

Float Filter::Evaluate(Point2f p) const { return Evaluate1D(p.x, radius.x) * Evaluate1D(p.y, radius.y); }
FilterSample Filter::Sample(Point2f u) const {
    // Exact sampling of a separable, non-negative filter: weight = f / pdf = integral.
    return {Point2f(Sample1D(u.x, radius.x), Sample1D(u.y, radius.y)), Integral()};
}
Float Filter::PDF(Point2f p) const { return PDF1D(p.x, radius.x) * PDF1D(p.y, radius.y); }
Point2f Filter::InvertSample(Point2f p) const {
    return {Invert1D(p.x, radius.x), Invert1D(p.y, radius.y)};
}

}  // namespace pbrt
