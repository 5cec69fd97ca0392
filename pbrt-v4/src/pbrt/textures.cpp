#include <pbrt/textures.h>

#include <pbrt/util/color.h>
#include <pbrt/util/image.h>

#include <algorithm>
#include <cmath>

namespace pbrt {

namespace {

class ConstantFloatTex : public FloatTexture {
  public:
    explicit ConstantFloatTex(Float v) : v(v) {}
    Float Evaluate(const TextureEvalContext &) const override { return v; }
    bool IsConstant(Float *value) const override { *value = v; return true; }
  private:
    Float v;
};

class ConstantSpectrumTex : public SpectrumTexture {
  public:
    explicit ConstantSpectrumTex(SpectrumHandle s) : s(std::move(s)) {}
    SampledSpectrum Evaluate(const TextureEvalContext &, const SampledWavelengths &lambda) const override {
        return s->Sample(lambda);
    }
    SpectrumHandle Constant() const override { return s; }
  private:
    SpectrumHandle s;
};

template <typename Base, typename Handle>
class Checkerboard : public Base {
  public:
    Checkerboard(UVMapping map, int dim, Handle t1, Handle t2)
        : map(map), dim(dim), t1(std::move(t1)), t2(std::move(t2)) {}
    template <typename... Args>
    auto Eval(const TextureEvalContext &ctx, const Args &...args) const {
        return CheckerboardPicksFirst(map, dim, ctx) ? t1->Evaluate(ctx, args...) : t2->Evaluate(ctx, args...);
    }
  protected:
    UVMapping map;
    int dim;
    Handle t1, t2;
};

class CheckerboardFloat : public Checkerboard<FloatTexture, FloatTextureHandle> {
  public:
    using Checkerboard::Checkerboard;
    Float Evaluate(const TextureEvalContext &ctx) const override { return Eval(ctx); }
};

class CheckerboardSpectrum : public Checkerboard<SpectrumTexture, SpectrumTextureHandle> {
  public:
    using Checkerboard::Checkerboard;
    SampledSpectrum Evaluate(const TextureEvalContext &ctx, const SampledWavelengths &l) const override {
        return Eval(ctx, l);
    }
};

class ScaleFloat : public FloatTexture {
  public:
    ScaleFloat(FloatTextureHandle t, FloatTextureHandle s) : t(std::move(t)), s(std::move(s)) {}
    Float Evaluate(const TextureEvalContext &ctx) const override {
        Float sc = s->Evaluate(ctx);
        return sc == 0 ? 0 : sc * t->Evaluate(ctx);
    }
  private:
    FloatTextureHandle t, s;
};

class ScaleSpectrum : public SpectrumTexture {
  public:
    ScaleSpectrum(SpectrumTextureHandle t, FloatTextureHandle s) : t(std::move(t)), s(std::move(s)) {}
    SampledSpectrum Evaluate(const TextureEvalContext &ctx, const SampledWavelengths &l) const override {
        Float sc = s->Evaluate(ctx);
        return sc == 0 ? SampledSpectrum(0) : t->Evaluate(ctx, l) * sc;
    }
  private:
    SpectrumTextureHandle t;
    FloatTextureHandle s;
};

class MixFloat : public FloatTexture {
  public:
    MixFloat(FloatTextureHandle a, FloatTextureHandle b, FloatTextureHandle amt)
        : a(std::move(a)), b(std::move(b)), amt(std::move(amt)) {}
    Float Evaluate(const TextureEvalContext &ctx) const override {
        Float t = amt->Evaluate(ctx);
        Float va = t != 1 ? a->Evaluate(ctx) : 0, vb = t != 0 ? b->Evaluate(ctx) : 0;
        return (1 - t) * va + t * vb;
    }
  private:
    FloatTextureHandle a, b, amt;
};

class MixSpectrum : public SpectrumTexture {
  public:
    MixSpectrum(SpectrumTextureHandle a, SpectrumTextureHandle b, FloatTextureHandle amt)
        : a(std::move(a)), b(std::move(b)), amt(std::move(amt)) {}
    SampledSpectrum Evaluate(const TextureEvalContext &ctx, const SampledWavelengths &l) const override {
        Float t = amt->Evaluate(ctx);
        SampledSpectrum r(0);
        if (t != 1) r += a->Evaluate(ctx, l) * (1 - t);
        if (t != 0) r += b->Evaluate(ctx, l) * t;
        return r;
    }
  private:
    SpectrumTextureHandle a, b;
    FloatTextureHandle amt;
};

class ImageFloat : public FloatTexture {
  public:
    ImageFloat(UVMapping map, std::shared_ptr<const TextureImage> img, Float scale, bool invert)
        : map(map), img(std::move(img)), scale(scale), invert(invert) {}
    Float Evaluate(const TextureEvalContext &ctx) const override {
        float v[3];
        img->Bilerp(map.Map(ctx), v);
        // Several channels: their average.
        Float x = img->channels == 1 ? v[0] : (v[0] + v[1] + v[2]) / 3;
        x *= scale;
        return invert ? std::max<Float>(0, 1 - x) : x;
    }
  private:
    UVMapping map;
    std::shared_ptr<const TextureImage> img;
    Float scale;
    bool invert;
};

class ImageSpectrum : public SpectrumTexture {
  public:
    ImageSpectrum(UVMapping map, std::shared_ptr<const TextureImage> img, Float scale, bool invert,
                  SpectrumType type, const RGBColorSpace *cs)
        : map(map), img(std::move(img)), scale(scale), invert(invert), type(type), cs(cs) {}
    SampledSpectrum Evaluate(const TextureEvalContext &ctx, const SampledWavelengths &lambda) const override {
        float v[3];
        img->Bilerp(map.Map(ctx), v);
        RGB rgb(v[0] * scale, v[1] * scale, v[2] * scale);
        if (invert) rgb = RGB(1, 1, 1) - rgb;
        rgb = ClampZero(rgb);
        // One-channel images are a constant spectrum; RGB goes through the colour space.
        if (img->channels == 1) return SampledSpectrum(type == SpectrumType::Albedo ? std::min<Float>(rgb.r, 1) : rgb.r);
        switch (type) {
        case SpectrumType::Albedo:
            return RGBAlbedoSpectrum(*cs, RGB(std::min<Float>(rgb.r, 1), std::min<Float>(rgb.g, 1),
                                              std::min<Float>(rgb.b, 1))).Sample(lambda);
        case SpectrumType::Unbounded: return RGBUnboundedSpectrum(*cs, rgb).Sample(lambda);
        case SpectrumType::Illuminant: return RGBIlluminantSpectrum(*cs, rgb).Sample(lambda);
        }
        return SampledSpectrum(0);
    }
  private:
    UVMapping map;
    std::shared_ptr<const TextureImage> img;
    Float scale;
    bool invert;
    SpectrumType type;
    const RGBColorSpace *cs;
};

}  // namespace

float TextureImage::Texel(int x, int y, int c) const {
    switch (wrap) {
    case Wrap::Repeat:
        x = ((x % width) + width) % width;
        y = ((y % height) + height) % height;
        break;
    case Wrap::Clamp:
        x = Clamp(x, 0, width - 1);
        y = Clamp(y, 0, height - 1);
        break;
    case Wrap::Black:
        if (x < 0 || x >= width || y < 0 || y >= height) return 0;
        break;
    }
    return pixels[(size_t(y) * width + x) * channels + c];
}

void TextureImage::Bilerp(Point2f st, float out[3]) const {
    // t = 0 is the bottom of the image; row 0 is its top.
    Float x = st.x * width - 0.5f, y = (1 - st.y) * height - 0.5f;
    int xi = int(std::floor(x)), yi = int(std::floor(y));
    Float dx = x - xi, dy = y - yi;
    for (int c = 0; c < 3; ++c) {
        int cc = channels == 1 ? 0 : c;
        out[c] = (1 - dx) * (1 - dy) * Texel(xi, yi, cc) + dx * (1 - dy) * Texel(xi + 1, yi, cc) +
                 (1 - dx) * dy * Texel(xi, yi + 1, cc) + dx * dy * Texel(xi + 1, yi + 1, cc);
    }
}

std::shared_ptr<const TextureImage> LoadTextureImage(const std::string &path, const std::string &encoding,
                                                     TextureImage::Wrap wrap) {
    bool srgb = encoding == "sRGB";
    Float gamma = 1;
    if (encoding.rfind("gamma ", 0) == 0) {
        try {
            gamma = std::stof(encoding.substr(6));
        } catch (...) {
            gamma = -1;
        }
        if (!(gamma > 0)) throw PbrtError(path + ": bad texture encoding \"" + encoding + "\"");
    } else if (!srgb && encoding != "linear") {
        throw PbrtError(path + ": unknown texture encoding \"" + encoding + "\" (sRGB, linear or gamma G)");
    }
    Image img = ReadImage(path, srgb);
    auto t = std::make_shared<TextureImage>();
    t->width = img.width;
    t->height = img.height;
    t->wrap = wrap;
    // Keep one channel (Y) or three (RGB); drop alpha.
    t->channels = img.channels >= 3 ? 3 : 1;
    t->pixels.resize(size_t(img.width) * img.height * t->channels);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < t->channels; ++c) {
                float v = img.Get(x, y, c);
                if (gamma != 1) v = std::pow(std::max(0.f, v), gamma);
                t->pixels[(size_t(y) * img.width + x) * t->channels + c] = v;
            }
    if (t->width <= 0 || t->height <= 0) throw PbrtError(path + ": empty texture image");
    return t;
}

FloatTextureHandle MakeImageFloatTexture(UVMapping map, std::shared_ptr<const TextureImage> image,
                                         Float scale, bool invert) {
    return std::make_shared<ImageFloat>(map, std::move(image), scale, invert);
}
SpectrumTextureHandle MakeImageSpectrumTexture(UVMapping map, std::shared_ptr<const TextureImage> image,
                                               Float scale, bool invert, SpectrumType type,
                                               const RGBColorSpace *cs) {
    return std::make_shared<ImageSpectrum>(map, std::move(image), scale, invert, type, cs);
}

bool CheckerboardPicksFirst(const UVMapping &map, int dimension, const TextureEvalContext &ctx) {
    if (dimension == 3) {
        long s = long(std::floor(ctx.p.x)) + long(std::floor(ctx.p.y)) + long(std::floor(ctx.p.z));
        return s % 2 == 0;
    }
    Point2f st = map.Map(ctx);
    long s = long(std::floor(st.x)) + long(std::floor(st.y));
    return s % 2 == 0;
}

FloatTextureHandle MakeConstantFloatTexture(Float v) { return std::make_shared<ConstantFloatTex>(v); }
SpectrumTextureHandle MakeConstantSpectrumTexture(SpectrumHandle s) {
    return std::make_shared<ConstantSpectrumTex>(std::move(s));
}
FloatTextureHandle MakeCheckerboardFloatTexture(UVMapping map, int dim, FloatTextureHandle t1,
                                                FloatTextureHandle t2) {
    return std::make_shared<CheckerboardFloat>(map, dim, std::move(t1), std::move(t2));
}
SpectrumTextureHandle MakeCheckerboardSpectrumTexture(UVMapping map, int dim, SpectrumTextureHandle t1,
                                                      SpectrumTextureHandle t2) {
    return std::make_shared<CheckerboardSpectrum>(map, dim, std::move(t1), std::move(t2));
}
FloatTextureHandle MakeScaleFloatTexture(FloatTextureHandle t, FloatTextureHandle s) {
    return std::make_shared<ScaleFloat>(std::move(t), std::move(s));
}
SpectrumTextureHandle MakeScaleSpectrumTexture(SpectrumTextureHandle t, FloatTextureHandle s) {
    return std::make_shared<ScaleSpectrum>(std::move(t), std::move(s));
}
FloatTextureHandle MakeMixFloatTexture(FloatTextureHandle a, FloatTextureHandle b, FloatTextureHandle amt) {
    return std::make_shared<MixFloat>(std::move(a), std::move(b), std::move(amt));
}
SpectrumTextureHandle MakeMixSpectrumTexture(SpectrumTextureHandle a, SpectrumTextureHandle b,
                                             FloatTextureHandle amt) {
    return std::make_shared<MixSpectrum>(std::move(a), std::move(b), std::move(amt));
}

}  // namespace pbrt
