// Textures: functions of the surface point that give a spectrum or a float.
//
// Supported "Texture" classes (pbrt-v4 names and parameters):
//   "constant"      value
//   "checkerboard"  tex1, tex2, dimension (2 or 3), and the uv mapping parameters
//   "scale"         tex, scale
//   "mix"           tex1, tex2, amount
//   "imagemap"      filename, encoding, invert, scale, wrap (repeat, black, clamp), filter
//                   (bilinear lookup, pbrt-v4's default; other filters fall back to it
//                   with a warning)
// The uv mapping: "mapping" "uv" with uscale, vscale, udelta, vdelta. Other texture classes
// ("bilerp", "dots", "fbm", "ptex", ...) and mappings are reported as errors.
// The checkerboard is evaluated at the point (pbrt-v4 box-filters it over the ray's
// footprint; the difference is confined to a sub-pixel band along the checker edges).
#pragma once

#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pbrt {

class ParameterDictionary;
class RGBColorSpace;
struct FileLoc;

// What a texture is evaluated at.
struct TextureEvalContext {
    Point3f p;
    Point2f uv;
};

// How an RGB or spectrum value is turned into a spectrum: reflectances stay in [0, 1],
// unbounded values (indices of refraction) may exceed 1, illuminants include the colour
// space's illuminant (pbrt-v4's SpectrumType).
enum class SpectrumType { Albedo, Unbounded, Illuminant };

class FloatTexture {
  public:
    virtual ~FloatTexture() = default;
    virtual Float Evaluate(const TextureEvalContext &ctx) const = 0;
    // The value if the texture is constant (lets materials skip evaluation).
    virtual bool IsConstant(Float *value) const { return false; }
};
using FloatTextureHandle = std::shared_ptr<const FloatTexture>;

class SpectrumTexture {
  public:
    virtual ~SpectrumTexture() = default;
    virtual SampledSpectrum Evaluate(const TextureEvalContext &ctx,
                                     const SampledWavelengths &lambda) const = 0;
    // The spectrum if the texture is constant.
    virtual SpectrumHandle Constant() const { return nullptr; }
};
using SpectrumTextureHandle = std::shared_ptr<const SpectrumTexture>;

FloatTextureHandle MakeConstantFloatTexture(Float v);
SpectrumTextureHandle MakeConstantSpectrumTexture(SpectrumHandle s);

// The uv mapping of pbrt-v4: st = (su u + du, sv v + dv).
struct UVMapping {
    Float su = 1, sv = 1, du = 0, dv = 0;
    Point2f Map(const TextureEvalContext &ctx) const {
        return {su * ctx.uv.x + du, sv * ctx.uv.y + dv};
    }
};

FloatTextureHandle MakeCheckerboardFloatTexture(UVMapping map, int dimension,
                                                FloatTextureHandle tex1, FloatTextureHandle tex2);
SpectrumTextureHandle MakeCheckerboardSpectrumTexture(UVMapping map, int dimension,
                                                      SpectrumTextureHandle tex1,
                                                      SpectrumTextureHandle tex2);
FloatTextureHandle MakeScaleFloatTexture(FloatTextureHandle tex, FloatTextureHandle scale);
SpectrumTextureHandle MakeScaleSpectrumTexture(SpectrumTextureHandle tex, FloatTextureHandle scale);
FloatTextureHandle MakeMixFloatTexture(FloatTextureHandle tex1, FloatTextureHandle tex2,
                                       FloatTextureHandle amount);
SpectrumTextureHandle MakeMixSpectrumTexture(SpectrumTextureHandle tex1, SpectrumTextureHandle tex2,
                                             FloatTextureHandle amount);

// An image for "imagemap" textures: linear values, row 0 at the top, 1 or 3 channels
// (alpha dropped), shared by the textures that use the same file and encoding.
struct TextureImage {
    int width = 0, height = 0, channels = 0;
    std::vector<float> pixels;
    enum class Wrap { Repeat, Black, Clamp } wrap = Wrap::Repeat;
    // Texel (x, y) channel c with the wrap mode applied (x, y may be outside the image).
    float Texel(int x, int y, int c) const {
        ptrdiff_t o = TexelOffset(x, y);
        return o < 0 ? 0.f : pixels[size_t(o) + c];
    }
    // Index of texel (x, y)'s first channel in pixels after wrapping; -1 where the wrap mode
    // makes it black.
    ptrdiff_t TexelOffset(int x, int y) const;
    // Bilinear interpolation at st in [0,1]^2, t = 0 at the bottom row (pbrt-v4's image
    // lookup: texel centres at half-integers).
    void Bilerp(Point2f st, float out[3]) const;
};
// Reads a texture image; encoding is "sRGB", "linear" or "gamma G" (pbrt-v4's names;
// 8-bit formats default to sRGB and float formats to linear).
std::shared_ptr<const TextureImage> LoadTextureImage(const std::string &path,
                                                     const std::string &encoding,
                                                     TextureImage::Wrap wrap);

FloatTextureHandle MakeImageFloatTexture(UVMapping map, std::shared_ptr<const TextureImage> image,
                                         Float scale, bool invert);
SpectrumTextureHandle MakeImageSpectrumTexture(UVMapping map, std::shared_ptr<const TextureImage> image,
                                               Float scale, bool invert, SpectrumType type,
                                               const RGBColorSpace *colorSpace);

// How a material's or texture's parameters become textures (implemented by the scene
// builder, which knows the named textures and the current colour space). Both return
// nullptr when the parameter is absent and there is no default.
struct TextureResolver {
    std::function<SpectrumTextureHandle(const std::string &name, SpectrumHandle def, SpectrumType)>
        spectrum;
    std::function<FloatTextureHandle(const std::string &name, std::optional<Float> def)> floats;
};

// The images of "imagemap" textures, loaded once per file, encoding and wrap mode.
using TextureImageCache = std::map<std::string, std::shared_ptr<const TextureImage>>;

// What a "Texture" directive defines: a float texture, or a spectrum texture made twice, as
// reflectance (clamped to [0, 1]) and unbounded; the material parameter that uses one picks
// the flavour (as pbrt-v4 does).
struct TextureDefinition {
    FloatTextureHandle floatTexture;
    SpectrumTextureHandle albedo, unbounded;
};

// Creates the texture of class texname ("constant", "checkerboard", ...; see the top of
// this file) named name, of type "float" or "spectrum" (checked by the caller). Texture-
// valued parameters come from textures (for a spectrum texture, from the flavour being
// made); RGB values are in colorSpace; relative image file names are resolved against the
// scene file. Throws PbrtError at loc or at the parameter for what is not supported.
TextureDefinition CreateTexture(const std::string &name, const std::string &type,
                                const std::string &texname, const ParameterDictionary &params,
                                const TextureResolver &textures, const RGBColorSpace &colorSpace,
                                TextureImageCache *images, const FileLoc &loc);

// Whether the 2D (dimension 2, from st) or 3D (from p) checkerboard picks tex1 at ctx.
bool CheckerboardPicksFirst(const UVMapping &map, int dimension, const TextureEvalContext &ctx);

}  // namespace pbrt
