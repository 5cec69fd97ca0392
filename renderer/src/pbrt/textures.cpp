#include <pbrt/textures.h>

#include <pbrt/parser.h>
#include <pbrt/util/color.h>
#include <pbrt/util/image.h>
#include <pbrt/util/paramdict.h>

#include <algorithm>
#include <cctype>
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

ptrdiff_t TextureImage::TexelOffset(int x, int y) const {
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
        if (x < 0 || x >= width || y < 0 || y >= height) return -1;
        break;
    }
    return (ptrdiff_t(y) * width + x) * channels;
}

void TextureImage::Bilerp(Point2f st, float out[3]) const {
    // t = 0 is the bottom of the image; row 0 is its top.
    Float x = st.x * width - 0.5f, y = (1 - st.y) * height - 0.5f;
    int xi = int(std::floor(x)), yi = int(std::floor(y));
    Float dx = x - xi, dy = y - yi;
    // The four texels wrapped once each (not once per channel: the wrap's integer divisions
    // were most of a lookup's time), then the weights in the order of the formula
    // (1 - dx)(1 - dy) T00 + dx (1 - dy) T10 + (1 - dx) dy T01 + dx dy T11.
    const ptrdiff_t o[4] = {TexelOffset(xi, yi), TexelOffset(xi + 1, yi), TexelOffset(xi, yi + 1),
                            TexelOffset(xi + 1, yi + 1)};
    const Float w[4] = {(1 - dx) * (1 - dy), dx * (1 - dy), (1 - dx) * dy, dx * dy};
    for (int c = 0; c < 3; ++c) {
        int cc = channels == 1 ? 0 : c;
        Float t[4];
        for (int k = 0; k < 4; ++k) t[k] = o[k] < 0 ? 0.f : pixels[size_t(o[k]) + cc];
        out[c] = w[0] * t[0] + w[1] * t[1] + w[2] * t[2] + w[3] * t[3];
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

// --- The factory -------------------------------------------------------------------------------
TextureDefinition CreateTexture(const std::string &name, const std::string &type,
                                const std::string &texname, const ParameterDictionary &dict,
                                const TextureResolver &textures, const RGBColorSpace &colorSpace,
                                TextureImageCache *images, const FileLoc &loc) {
    // The uv mapping shared by the 2D textures.
    auto mapping = [&] {
        std::string m = dict.GetOneString("mapping", "uv");
        if (m != "uv") throw PbrtError(dict.Loc("mapping"), "texture mapping \"" + m + "\" is not supported (only uv)");
        return UVMapping{dict.GetOneFloat("uscale", 1), dict.GetOneFloat("vscale", 1),
                         dict.GetOneFloat("udelta", 0), dict.GetOneFloat("vdelta", 0)};
    };
    auto dimension = [&] {
        int d = dict.GetOneInt("dimension", 2);
        if (d != 2 && d != 3) throw PbrtError(dict.Loc("dimension"), "checkerboard dimension must be 2 or 3");
        return d;
    };
    auto unsupported = [&] {
        throw PbrtError(loc, "texture class \"" + texname +
                                 "\" is not supported yet (supported: constant, checkerboard, scale, mix, imagemap)");
    };
    // "imagemap": the image (cached per file, encoding and wrap mode) and its parameters.
    std::shared_ptr<const TextureImage> image;
    Float imageScale = 1;
    bool imageInvert = false;
    if (texname == "imagemap") {
        std::string filename = dict.GetOneString("filename", "");
        if (filename.empty()) throw PbrtError(loc, "imagemap texture \"" + name + "\" needs a \"filename\"");
        std::string path = ResolveFilename(filename, dict.Loc("filename"));
        std::string ext = path.substr(path.find_last_of('.') == std::string::npos ? path.size() : path.find_last_of('.'));
        for (char &c : ext) c = char(std::tolower((unsigned char)c));
        bool floatFormat = ext == ".exr" || ext == ".hdr" || ext == ".pfm";
        std::string encoding = dict.GetOneString("encoding", floatFormat ? "linear" : "sRGB");
        std::string wrapName = dict.GetOneString("wrap", "repeat");
        TextureImage::Wrap wrap;
        if (wrapName == "repeat") wrap = TextureImage::Wrap::Repeat;
        else if (wrapName == "black") wrap = TextureImage::Wrap::Black;
        else if (wrapName == "clamp") wrap = TextureImage::Wrap::Clamp;
        else throw PbrtError(dict.Loc("wrap"), "texture wrap mode \"" + wrapName + "\" is not supported");
        std::string filter = dict.GetOneString("filter", "bilinear");
        if (filter != "bilinear" && filter != "point")
            Warning(dict.Loc("filter"), "texture filter \"" + filter + "\" is rendered as \"bilinear\"");
        dict.GetOneFloat("maxanisotropy", 8);
        imageScale = dict.GetOneFloat("scale", 1);
        imageInvert = dict.GetOneBool("invert", false);
        std::string key = path + "|" + encoding + "|" + wrapName;
        auto it = images->find(key);
        if (it == images->end()) {
            try {
                it = images->emplace(key, LoadTextureImage(path, encoding, wrap)).first;
            } catch (const PbrtError &e) {
                throw PbrtError(dict.Loc("filename"), e.what());
            }
        }
        image = it->second;
    }

    if (type == "float") {
        FloatTextureHandle t;
        if (texname == "constant") t = MakeConstantFloatTexture(dict.GetOneFloat("value", 1));
        else if (texname == "checkerboard") {
            UVMapping m = mapping();
            int d = dimension();
            t = MakeCheckerboardFloatTexture(m, d, textures.floats("tex1", 1), textures.floats("tex2", 0));
        } else if (texname == "scale") t = MakeScaleFloatTexture(textures.floats("tex", 1), textures.floats("scale", 1));
        else if (texname == "mix")
            t = MakeMixFloatTexture(textures.floats("tex1", 0), textures.floats("tex2", 1), textures.floats("amount", 0.5f));
        else if (texname == "imagemap") t = MakeImageFloatTexture(mapping(), image, imageScale, imageInvert);
        else unsupported();
        return {t, nullptr, nullptr};
    }
    // Spectrum textures are made twice, as reflectance (clamped to [0, 1]) and unbounded,
    // and the material parameter that uses one picks the flavour (as pbrt-v4 does).
    TextureDefinition result;
    for (SpectrumType st : {SpectrumType::Albedo, SpectrumType::Unbounded}) {
        // Re-resolve parameters for this flavour; nested textures come from the same flavour.
        TextureResolver r;
        r.floats = textures.floats;
        r.spectrum = [&](const std::string &n, SpectrumHandle def, SpectrumType) {
            return textures.spectrum(n, def, st);
        };
        auto one = std::make_shared<ConstantSpectrum>(1.f), zero = std::make_shared<ConstantSpectrum>(0.f);
        SpectrumTextureHandle t;
        if (texname == "constant") t = r.spectrum("value", one, st);
        else if (texname == "checkerboard") {
            UVMapping m = mapping();
            int d = dimension();
            t = MakeCheckerboardSpectrumTexture(m, d, r.spectrum("tex1", one, st), r.spectrum("tex2", zero, st));
        } else if (texname == "scale") t = MakeScaleSpectrumTexture(r.spectrum("tex", one, st), r.floats("scale", 1));
        else if (texname == "mix")
            t = MakeMixSpectrumTexture(r.spectrum("tex1", zero, st), r.spectrum("tex2", one, st), r.floats("amount", 0.5f));
        else if (texname == "imagemap")
            t = MakeImageSpectrumTexture(mapping(), image, imageScale, imageInvert, st, &colorSpace);
        else unsupported();
        (st == SpectrumType::Albedo ? result.albedo : result.unbounded) = t;
    }
    return result;
}

}  // namespace pbrt
