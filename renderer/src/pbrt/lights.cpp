#include <pbrt/lights.h>

#include <pbrt/util/color.h>
#include <pbrt/util/paramdict.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace pbrt {

namespace {

Float SmoothStep(Float x, Float a, Float b) {
    if (a == b) return x < a ? 0 : 1;
    Float t = Clamp((x - a) / (b - a), 0, 1);
    return t * t * (3 - 2 * t);
}

// Integral of s against xbar + ybar + zbar: positive for anything emitting in 360..830 nm.
Float SpectralWeight(const Spectrum &s) {
    return InnerProduct(Spectra::X(), s) + InnerProduct(Spectra::Y(), s) + InnerProduct(Spectra::Z(), s);
}

// pbrt-v4's 1-nit normalization: divide by the spectrum's luminance integral.
Float PhotometricNormalization(const Spectrum &s, const FileLoc &loc) {
    Float y = SpectrumToPhotometric(s);
    if (!(y > 0) || !std::isfinite(y))
        throw PbrtError(loc, "emission spectrum has no luminance (it is zero over the visible range), "
                             "so it cannot be normalized to 1 nit");
    return 1 / y;
}

// The transform whose columns are a frame's axes: local +z -> dir.
Transform FromLocalFrame(const Vector3f &dir) {
    Frame f = Frame::FromZ(dir);
    SquareMatrix4 m;
    for (int i = 0; i < 3; ++i) {
        m.m[i][0] = f.x[i];
        m.m[i][1] = f.y[i];
        m.m[i][2] = f.z[i];
    }
    return Transform(m, m.Transposed());
}

}  // namespace

IndexedPiecewiseLinearSpectrum::IndexedPiecewiseLinearSpectrum(const PiecewiseLinearSpectrum &s)
    : lambdas(s.Lambdas()), values(s.Values()) {
    lambda0 = std::floor(lambdas.front());
    size_t nb = size_t(std::ceil(lambdas.back()) - lambda0) + 2;
    bucketStart.resize(nb);
    for (size_t b = 0; b < nb; ++b) {
        // A safe place to start scanning for lambdas in bucket b: one bucket earlier.
        Float lo = lambda0 + Float(b) - 1;
        bucketStart[b] = uint32_t(std::upper_bound(lambdas.begin(), lambdas.end(), lo) - lambdas.begin());
    }
    if (lambdas.size() >= 2) {
        Float step = lambdas[1] - lambdas[0];
        bool even = step > 0;
        for (size_t i = 0; even && i < lambdas.size(); ++i)
            even = std::abs(lambdas[i] - (lambdas[0] + Float(i) * step)) <= 1e-3f * step;
        if (even) uniformStep = step;
    }
}

Float IndexedPiecewiseLinearSpectrum::operator()(Float lambda) const {
    // The same result as PiecewiseLinearSpectrum::operator(), without a binary search.
    if (!(lambda >= lambdas.front() && lambda <= lambdas.back())) return 0;
    size_t i, n = lambdas.size();
    if (uniformStep > 0) {
        // Evenly spaced nodes (the usual tabulation): the node is where the arithmetic says,
        // give or take one for rounding, which the two loops settle.
        i = std::min(size_t((lambda - lambdas.front()) / uniformStep) + 1, n);
        while (i > 0 && lambdas[i - 1] > lambda) --i;
    } else {
        size_t b = std::min(size_t(lambda - lambda0), bucketStart.size() - 1);
        i = bucketStart[b];
    }
    while (i < n && lambdas[i] <= lambda) ++i;  // first node above lambda
    if (i >= n) return values.back();
    if (i == 0) return values.front();
    --i;
    Float t = (lambda - lambdas[i]) / (lambdas[i + 1] - lambdas[i]);
    return (1 - t) * values[i] + t * values[i + 1];
}

SampledSpectrum IndexedPiecewiseLinearSpectrum::Sample(const SampledWavelengths &lambda) const {
    SampledSpectrum s;
    for (int i = 0; i < NSpectrumSamples; ++i) s[i] = (*this)(lambda[i]);
    return s;
}

Float IndexedPiecewiseLinearSpectrum::MaxValue() const {
    return *std::max_element(values.begin(), values.end());
}

std::string IndexedPiecewiseLinearSpectrum::ToString() const {
    return "[ IndexedPiecewiseLinearSpectrum " + std::to_string(lambdas.size()) + " samples ]";
}

const char *EmissionParameterName(const std::string &directive, const std::string &type) {
    const bool pointLike =
        type == "point" || type == "spot" || type == "goniometric" || type == "projection";
    return directive == "LightSource" && pointLike ? "I" : "L";
}

SpectrumHandle FastLookup(SpectrumHandle s) {
    if (auto pl = std::dynamic_pointer_cast<const PiecewiseLinearSpectrum>(s))
        return std::make_shared<IndexedPiecewiseLinearSpectrum>(*pl);
    return s;
}

void Light::ShareEqualSpectra(std::vector<Light> &lights) {
    // Candidates by node count and end points; equal tables are then compared in full.
    std::map<std::tuple<size_t, Float, Float>, std::vector<SpectrumHandle>> seen;
    const Spectrum *lastIn = nullptr;
    SpectrumHandle lastOut;
    for (Light &l : lights) {
        if (l.spectrum.get() == lastIn) {  // the lights of one shape share their spectrum
            l.spectrum = lastOut;
            continue;
        }
        lastIn = l.spectrum.get();
        if (auto *a = dynamic_cast<const IndexedPiecewiseLinearSpectrum *>(lastIn)) {
            auto &same = seen[{a->Lambdas().size(), a->Lambdas().front(), a->Lambdas().back()}];
            auto it = std::find_if(same.begin(), same.end(), [&](const SpectrumHandle &h) {
                auto *b = static_cast<const IndexedPiecewiseLinearSpectrum *>(h.get());
                return b->Lambdas() == a->Lambdas() && b->Values() == a->Values();
            });
            if (it != same.end()) l.spectrum = *it;
            else same.push_back(l.spectrum);
        }
        lastOut = l.spectrum;
    }
}

void Light::Preprocess(const Bounds3f &b) {
    b.BoundingSphere(&sceneCenter, &sceneRadius);
    if (sceneRadius == 0) sceneRadius = 1;
}

double Light::PowerFactor() const {
    const double pi = 3.14159265358979323846, r2 = double(sceneRadius) * double(sceneRadius);
    switch (type) {
    case LightType::Point: return 4 * pi;
    case LightType::Spot:
        return 2 * pi * ((1 - double(cosFalloffStart)) + (double(cosFalloffStart) - double(cosFalloffEnd)) / 2);
    case LightType::Distant: return pi * r2;
    case LightType::UniformInfinite: return 4 * pi * pi * r2;
    case LightType::DiffuseArea: return pi * double(area) * (twoSided ? 2 : 1);
    }
    return 0;
}

Float Light::Power() const { return Float(PowerFactor() * double(scale) * double(spectralWeight)); }

std::optional<LightLiSample> Light::SampleLi(const LightSampleContext &ctx, Point2f u,
                                             const SampledWavelengths &lambda,
                                             SampledSpectrumCache *cache) const {
    auto emission = [&]() -> SampledSpectrum {
        return cache ? cache->Get(*spectrum, lambda) : spectrum->Sample(lambda);
    };
    LightLiSample ls;
    switch (type) {
    case LightType::Point:
    case LightType::Spot: {
        Vector3f d = position - ctx.p;
        Float d2 = LengthSquared(d);
        if (d2 == 0) return std::nullopt;
        ls.wi = d / std::sqrt(d2);
        Float falloff = 1;
        if (type == LightType::Spot) {
            Vector3f wl = Normalize(Inverse(renderFromLight).ApplyVector(-ls.wi));
            falloff = SmoothStep(wl.z, cosFalloffEnd, cosFalloffStart);
            if (falloff == 0) return std::nullopt;
        }
        ls.L = emission() * (scale * falloff / d2);
        ls.pdf = 1;
        ls.pLight = position;
        return ls;
    }
    case LightType::Distant:
        ls.wi = wLight;
        ls.L = emission() * scale;
        ls.pdf = 1;
        ls.pLight = ctx.p + wLight * (2 * sceneRadius);
        return ls;
    case LightType::UniformInfinite: {
        ls.wi = SampleUniformSphere(u);
        ls.pdf = UniformSpherePDF();
        ls.L = emission() * scale;
        ls.pLight = ctx.p + ls.wi * (2 * sceneRadius);
        return ls;
    }
    case LightType::DiffuseArea: break;
    }

    // Area lights: a point on the shape, converted to a solid-angle density.
    // The point, its error bound and normal go straight into ls.
    if (mesh) {
        auto b = SampleUniformTriangle(u);
        mesh->SurfacePoint(size_t(triangle), b[1], b[2], &ls.pLight, &ls.pLightError, &ls.nLight);
    } else {
        Point3f c = sphere->center;
        Float R = sphere->radius * sphereScale;
        Float dc2 = DistanceSquared(ctx.p, c);
        if (sphere->IsFull() && dc2 > Sqr(R) * 1.0001f) {
            // Outside a full sphere: sample the cone of directions it subtends.
            Float dc = std::sqrt(dc2);
            Float sin2Max = Sqr(R) / dc2;
            Float cosMax = SafeSqrt(1 - sin2Max);
            Float oneMinusCosMax = sin2Max / (1 + cosMax);
            Float oneMinusCos = u.x * oneMinusCosMax;
            Float cosTheta = 1 - oneMinusCos;
            Float sin2Theta = oneMinusCos * (2 - oneMinusCos);
            Float phi = 2 * Pi * u.y;
            Frame f = Frame::FromZ((c - ctx.p) / dc);
            ls.wi = Normalize(f.FromLocal(SphericalDirection(std::sqrt(sin2Theta), cosTheta, phi)));
            Float t = dc * cosTheta - SafeSqrt(Sqr(R) - dc2 * sin2Theta);
            Point3f pObj = sphere->objectFromRender.ApplyPoint(ctx.p + ls.wi * t);
            sphere->SurfacePoint(pObj, &ls.pLight, &ls.pLightError, &ls.nLight);
            ls.unblockingSphere = sphere->id;
            ls.pdf = 1 / (2 * Pi * oneMinusCosMax);
            ls.L = L(ls.nLight, -ls.wi, lambda, cache);
            if (!ls.L.IsNonZero()) return std::nullopt;
            return ls;
        }
        // Inside, or a partial sphere: uniform over its area.
        Float z = Lerp(u.x, sphere->zMin, sphere->zMax);
        Float phi = u.y * sphere->phiMax;
        Float r = SafeSqrt(Sqr(sphere->radius) - Sqr(z));
        sphere->SurfacePoint(Point3f(r * std::cos(phi), r * std::sin(phi), z), &ls.pLight, &ls.pLightError, &ls.nLight);
    }
    Vector3f d = ls.pLight - ctx.p;
    Float d2 = LengthSquared(d);
    if (d2 == 0) return std::nullopt;
    ls.wi = d / std::sqrt(d2);
    Float cosLight = AbsDot(ls.nLight, ls.wi);
    if (cosLight == 0) return std::nullopt;
    ls.pdf = d2 / (area * cosLight);
    ls.L = L(ls.nLight, -ls.wi, lambda, cache);
    if (!ls.L.IsNonZero() || !std::isfinite(ls.pdf)) return std::nullopt;
    return ls;
}

Float Light::PDF_Li(const LightSampleContext &ctx, const Vector3f &wi,
                    const SurfaceInteraction &hit) const {
    if (type == LightType::UniformInfinite) return UniformSpherePDF();
    if (type != LightType::DiffuseArea) return 0;
    if (sphere) {
        Point3f c = sphere->center;
        Float R = sphere->radius * sphereScale;
        Float dc2 = DistanceSquared(ctx.p, c);
        if (sphere->IsFull() && dc2 > Sqr(R) * 1.0001f) {
            Float sin2Max = Sqr(R) / dc2;
            Float cosMax = SafeSqrt(1 - sin2Max);
            return 1 / (2 * Pi * (sin2Max / (1 + cosMax)));
        }
    }
    Float cosLight = AbsDot(hit.n, wi);
    if (cosLight == 0) return 0;
    Float pdf = DistanceSquared(ctx.p, hit.p) / (area * cosLight);
    return std::isfinite(pdf) ? pdf : 0;
}

Light Light::Create(const std::string &name, const ParameterDictionary &params,
                    const Transform &renderFromLight, SpectrumHandle spec,
                    const RGBColorSpace &cs, const FileLoc &loc) {
    Light l;
    if (!spec) spec = cs.IlluminantHandle();
    l.spectrum = FastLookup(spec);
    l.spectralWeight = SpectralWeight(*spec);
    l.loc = std::make_shared<const FileLoc>(loc);
    l.scale = params.GetOneFloat("scale", 1);
    if (!std::isfinite(l.scale) || l.scale < 0) throw PbrtError(params.Loc("scale"), "light \"scale\" must be finite and >= 0");
    auto point3 = [&](const char *n, std::array<Float, 3> def) {
        auto a = params.GetOnePoint3(n, def);
        return Point3f(a[0], a[1], a[2]);
    };
    if (name == "point" || name == "spot") {
        l.type = name == "point" ? LightType::Point : LightType::Spot;
        l.scale *= PhotometricNormalization(*spec, loc);
        Point3f from = point3("from", {0, 0, 0});
        Transform t = Translate(from);
        Float k_e = 4 * Pi;
        if (l.type == LightType::Spot) {
            Point3f to = point3("to", {0, 0, 1});
            if (to == from) throw PbrtError(loc, "spot light: \"from\" and \"to\" coincide");
            t = t * FromLocalFrame(Normalize(to - from));
            Float cone = params.GetOneFloat("coneangle", 30), delta = params.GetOneFloat("conedeltaangle", 5);
            l.cosFalloffEnd = std::cos(Radians(cone));
            l.cosFalloffStart = std::cos(Radians(cone - delta));
            k_e = 2 * Pi * ((1 - l.cosFalloffStart) + (l.cosFalloffStart - l.cosFalloffEnd) / 2);
        }
        Float phi_v = params.GetOneFloat("power", -1);
        if (phi_v > 0) l.scale *= phi_v / k_e;
        l.renderFromLight = renderFromLight * t;
        l.position = l.renderFromLight.ApplyPoint(Point3f(0, 0, 0));
        return l;
    }
    if (name == "distant") {
        l.type = LightType::Distant;
        l.scale *= PhotometricNormalization(*spec, loc);
        Point3f from = point3("from", {0, 0, 0}), to = point3("to", {0, 0, 1});
        Vector3f w = renderFromLight.ApplyVector(from - to);
        if (LengthSquared(w) == 0) throw PbrtError(loc, "distant light: \"from\" and \"to\" coincide");
        l.wLight = Normalize(w);
        Float E_v = params.GetOneFloat("illuminance", -1);
        if (E_v > 0) l.scale *= E_v;
        return l;
    }
    if (name == "infinite") {
        for (const char *p : {"filename", "portal"})
            if (params.Find(p))
                throw PbrtError(params.Loc(p), std::string("infinite light \"") + p +
                                                   "\" (image environment maps) is not supported yet");
        l.type = LightType::UniformInfinite;
        l.scale *= PhotometricNormalization(*spec, loc);
        Float E_v = params.GetOneFloat("illuminance", -1);
        // A constant sky of radiance L gives an upward surface the illuminance pi L.
        if (E_v > 0) l.scale *= E_v / Pi;
        return l;
    }
    throw PbrtError(loc, "LightSource \"" + name +
                             "\" is not supported (supported: point, spot, distant, infinite)");
}

void Light::CreateArea(const ParameterDictionary &params, SpectrumHandle spec,
                       const RGBColorSpace &cs, std::shared_ptr<const TriangleMesh> mesh,
                       const Sphere *sphere, const FileLoc &loc, std::vector<Light> *out) {
    if (params.Find("filename"))
        throw PbrtError(params.Loc("filename"), "image-textured area lights (\"filename\") are not supported yet");
    if (!spec) spec = cs.IlluminantHandle();
    Light base;
    base.type = LightType::DiffuseArea;
    base.spectrum = FastLookup(spec);
    base.spectralWeight = SpectralWeight(*spec);
    base.loc = std::make_shared<const FileLoc>(loc);
    base.twoSided = params.GetOneBool("twosided", false);
    base.scale = params.GetOneFloat("scale", 1);
    if (!std::isfinite(base.scale) || base.scale < 0)
        throw PbrtError(params.Loc("scale"), "area light \"scale\" must be finite and >= 0");
    base.scale *= PhotometricNormalization(*spec, loc);
    Float phi_v = params.GetOneFloat("power", -1);
    auto finish = [&](Light l) {
        if (phi_v > 0) {
            Float k_e = (l.twoSided ? 2 : 1) * l.area * Pi;
            l.scale *= phi_v / k_e;
        }
        out->push_back(std::move(l));
    };
    if (mesh) {
        for (size_t i = 0; i < mesh->NumTriangles(); ++i) {
            Light l = base;
            l.mesh = mesh;
            l.triangle = int(i);
            l.area = mesh->Area(i);
            finish(std::move(l));
        }
    } else if (sphere) {
        Light l = base;
        l.sphereScale = sphere->SimilarityScale();
        if (l.sphereScale == 0)
            throw PbrtError(loc, "sphere area lights under a non-uniform scale are not supported");
        l.sphere = std::make_shared<Sphere>(*sphere);
        l.area = sphere->Area() * Sqr(l.sphereScale);
        finish(std::move(l));
    }
}

LightSampler::LightSampler(const std::vector<Light> &lights) {
    std::vector<Float> w;
    pmfByLight.assign(lights.size(), 0);
    for (size_t i = 0; i < lights.size(); ++i) {
        Float p = lights[i].SampledByNEE() ? lights[i].Power() : 0;
        if (p > 0 && std::isfinite(p)) {
            indices.push_back(int(i));
            w.push_back(p);
        }
    }
    if (indices.empty()) return;
    distrib = DiscreteDistribution(w);
    for (size_t k = 0; k < indices.size(); ++k) pmfByLight[indices[k]] = distrib.PMF(int(k));
}

int LightSampler::Sample(Float u, Float *pmf) const {
    if (indices.empty()) {
        *pmf = 0;
        return -1;
    }
    int k = distrib.Sample(u, pmf);
    return indices[k];
}

}  // namespace pbrt
