// Lights, following pbrt-v4's definitions and conventions:
//   "point"     I, scale, power, from
//   "spot"      I, scale, power, from, to, coneangle (30), conedeltaangle (5)
//   "distant"   L, scale, illuminance, from (0 0 0), to (0 0 1)
//   "infinite"  L, scale, illuminance (constant radiance from every direction)
//   area "diffuse"  L, scale, power, twosided: emits on the side of the surface normal
// Every emission spectrum is first normalized to 1 nit (divided by its integral against
// the CIE Y matching function, SpectrumToPhotometric) and then multiplied by "scale"; the
// "power"/"illuminance" parameters rescale to the requested photometric quantity. For area
// lights each triangle is its own light (as in pbrt-v4, so "power" is per triangle).
#pragma once

#include <pbrt/interaction.h>
#include <pbrt/shapes.h>
#include <pbrt/util/sampling.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/util/transform.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pbrt {

class ParameterDictionary;
class RGBColorSpace;

enum class LightType { Point, Spot, Distant, UniformInfinite, DiffuseArea };

// The receiving point of a light sample.
struct LightSampleContext {
    Point3f p;
    Normal3f n;        // geometric normal (zero if not on a surface)
    Vector3f pError;
};

struct LightLiSample {
    SampledSpectrum L;
    Vector3f wi;       // unit direction toward the light
    Float pdf = 0;     // solid angle density (1 for delta lights)
    Point3f pLight;    // the sampled point (far away for distant lights)
    Normal3f nLight;   // its normal (zero for point, spot and distant lights)
    Vector3f pLightError;
    // The id of a sphere whose first point along wi is pLight (cone sampling): the segment to
    // pLight cannot cross that sphere, so its shadow ray need not test it. 0: test everything.
    uint32_t unblockingSphere = 0;
};

class Light {
  public:
    LightType Type() const { return type; }
    bool IsDelta() const { return type == LightType::Point || type == LightType::Spot || type == LightType::Distant; }
    bool IsInfinite() const { return type == LightType::Distant || type == LightType::UniformInfinite; }

    // Needs the scene's bounds (distant and infinite lights).
    void Preprocess(const Bounds3f &sceneBounds);

    // Samples incident radiance at ctx; nullopt when there is none.
    // With a cache, the emission spectrum's values come from (and go to) it.
    std::optional<LightLiSample> SampleLi(const LightSampleContext &ctx, Point2f u,
                                          const SampledWavelengths &lambda,
                                          SampledSpectrumCache *cache = nullptr) const;
    // Solid-angle density with which SampleLi picks direction wi toward the point `hit` on
    // this (area) light.
    Float PDF_Li(const LightSampleContext &ctx, const Vector3f &wi, const SurfaceInteraction &hit) const;
    // Radiance leaving an area light's surface point (normal n) in direction w.
    SampledSpectrum L(const Normal3f &n, const Vector3f &w, const SampledWavelengths &lambda,
                      SampledSpectrumCache *cache = nullptr) const {
        if (!twoSided && Dot(n, w) < 0) return SampledSpectrum(0);
        return (cache ? cache->Get(*spectrum, lambda) : spectrum->Sample(lambda)) * scale;
    }
    // Radiance arriving along a ray that escapes the scene (infinite lights).
    SampledSpectrum Le(const SampledWavelengths &lambda, SampledSpectrumCache *cache = nullptr) const {
        if (type != LightType::UniformInfinite) return SampledSpectrum(0);
        return (cache ? cache->Get(*spectrum, lambda) : spectrum->Sample(lambda)) * scale;
    }
    // Whether the light sampler should pick this light for next-event estimation. The
    // uniform infinite light is left to BSDF sampling (as pbrt-v4's path integrator does).
    bool SampledByNEE() const { return type != LightType::UniformInfinite; }
    // A scalar proportional to the emitted power (weights for light selection):
    // PowerFactor() * scale * the spectrum's integral against xbar + ybar + zbar.
    Float Power() const;
    // The emitted spectral power is Phi(lambda) = PowerFactor() * Scale() * spectrum(lambda)
    // (pbrt-v4's Light::Phi): 4 pi for a point light, 2 pi (1 - (cos start + cos end) / 2)
    // for a spot light, pi r^2 for a distant light and 4 pi^2 r^2 for a uniform infinite
    // light (r the radius of the scene's bounding sphere, after Preprocess), and
    // pi * area (times 2 if two-sided) for a diffuse area light (area in render space).
    double PowerFactor() const;
    // "scale" times the 1-nit normalization (and the "power"/"illuminance" rescaling).
    Float Scale() const { return scale; }
    // The emission spectrum (before "scale") and where the light was defined (the
    // LightSource / AreaLightSource directive; empty if unknown): for the check that the
    // wavelength sampler covers every emitter (wavelength_coverage.h).
    const SpectrumHandle &EmissionSpectrum() const { return spectrum; }
    FileLoc Loc() const { return loc ? *loc : FileLoc{}; }

    // --- Construction --------------------------------------------------------------------
    // A non-area light from a LightSource directive; spectrumL is the already-built "L"/"I"
    // spectrum (nullptr: the colour space's illuminant).
    static Light Create(const std::string &name, const ParameterDictionary &params,
                        const Transform &renderFromLight, SpectrumHandle spectrum,
                        const RGBColorSpace &cs, const FileLoc &loc);
    // Area lights for one shape: one per triangle of mesh (or one for the sphere).
    static void CreateArea(const ParameterDictionary &params, SpectrumHandle spectrum,
                           const RGBColorSpace &cs, std::shared_ptr<const TriangleMesh> mesh,
                           const Sphere *sphere, const FileLoc &loc, std::vector<Light> *out);
    // Makes lights whose tabulated spectra have the same nodes and values share one
    // spectrum object: a path's spectrum cache (keyed by object) then evaluates it once for
    // all of them. Scenes often give every lamp its own copy of one table. The values are
    // unchanged.
    static void ShareEqualSpectra(std::vector<Light> &lights);

  private:
    LightType type = LightType::Point;
    SpectrumHandle spectrum;  // emission spectrum (densely sampled), times scale
    Float scale = 1;
    Float spectralWeight = 0; // integral of spectrum * (xbar + ybar + zbar), for Power()
    std::shared_ptr<const FileLoc> loc;  // shared by the triangles of one area light
    // Point and spot lights.
    Transform renderFromLight;
    Point3f position;
    Float cosFalloffStart = 1, cosFalloffEnd = 1;
    // Distant light: unit direction toward the light.
    Vector3f wLight;
    Point3f sceneCenter;
    Float sceneRadius = 0;
    // Area lights.
    bool twoSided = false;
    std::shared_ptr<const TriangleMesh> mesh;
    int triangle = -1;
    std::shared_ptr<const Sphere> sphere;
    Float area = 0;
    Float sphereScale = 1;    // similarity scale of the sphere's transform
};

// A piecewise-linear spectrum evaluated exactly as PiecewiseLinearSpectrum does, but with
// a per-nanometre index into its nodes instead of a binary search (emission spectra are
// evaluated at every light sample). FastLookup wraps piecewise-linear spectra in it and
// returns other spectra unchanged.
class IndexedPiecewiseLinearSpectrum : public Spectrum {
  public:
    explicit IndexedPiecewiseLinearSpectrum(const PiecewiseLinearSpectrum &s);
    Float operator()(Float lambda) const override;
    SampledSpectrum Sample(const SampledWavelengths &lambda) const override;
    Float MaxValue() const override;
    std::string ToString() const override;
    // The nodes (between them the spectrum is linear) and the values there.
    const std::vector<Float> &Lambdas() const { return lambdas; }
    const std::vector<Float> &Values() const { return values; }

  private:
    std::vector<Float> lambdas, values;
    std::vector<uint32_t> bucketStart;
    Float lambda0 = 0;
    Float uniformStep = 0;  // the spacing when the nodes are evenly spaced (else 0)
};
SpectrumHandle FastLookup(SpectrumHandle s);

// The name of the parameter that carries the spectrum of a `directive` ("LightSource" or
// "AreaLightSource") of type `type`, as pbrt-v4's light constructors read it (design §5.4):
// "I" (intensity) for the point-like lights point, spot, goniometric and projection, "L"
// (radiance) for every other light. tests/data/emitter-parameters.csv pins this and the
// Python reader's wavelength_pdf.emitters.emission_parameter alike.
const char *EmissionParameterName(const std::string &directive, const std::string &type);

// Picks lights for next-event estimation with probability proportional to Power().
class LightSampler {
  public:
    LightSampler() = default;
    explicit LightSampler(const std::vector<Light> &lights);
    bool Empty() const { return indices.empty(); }
    // Returns the light index, or -1 if no light can be sampled.
    int Sample(Float u, Float *pmf) const;
    Float PMF(int lightIndex) const { return lightIndex < 0 ? 0 : pmfByLight[lightIndex]; }

  private:
    DiscreteDistribution distrib;
    std::vector<int> indices;       // distribution entry -> light index
    std::vector<Float> pmfByLight;  // light index -> probability
};

}  // namespace pbrt
