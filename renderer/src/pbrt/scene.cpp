#include <pbrt/scene.h>

#include <pbrt/emission.h>
#include <pbrt/parser.h>
#include <pbrt/util/color.h>
#include <pbrt/util/output_path.h>
#include <pbrt/util/paramdict.h>
#include <pbrt/wavelength_coverage.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cmath>
#include <functional>
#include <map>
#include <set>

namespace pbrt {

bool Scene::Unoccluded(const Ray &ray, uint32_t skipSphere) const {
    if (!hasInterfaces) return !accel->Occluded(ray, skipSphere);
    // Walk through "interface" surfaces, which have no substance.
    Point3f target = ray(ray.tMax);
    Ray r = ray;
    SurfaceInteraction si;
    for (int i = 0; i < 256; ++i) {
        if (!accel->Intersect(r, &si)) return true;
        if (si.material >= 0) return false;
        Point3f o = si.OffsetRayOrigin(target - si.p);
        r = Ray(o, target - o, 1);
        if (Dot(r.d, ray.d) <= 0) return true;
    }
    return false;
}

namespace {

// Parameters that cannot change the picture: reported as ignored, not as errors.
const std::set<std::string> kHarmlessParameters = {"nsamples", "samples"};

std::string ParamName(const ParsedParameter &p) { return "\"" + p.type + " " + p.name + "\""; }

std::string PointText(const Point3f &p) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "(%g, %g, %g)", double(p.x), double(p.y), double(p.z));
    return buf;
}

// An object instance must stay where the ray tracer can intersect it (design §5.5), as every
// shape must: an affine, finite transformation that keeps the object's bounds within
// +-kMaxRenderCoordinate. Beyond, Embree's single-precision tests overflow and the instance
// silently vanishes; a projective transformation would be dropped to its affine part.
void CheckInstanceRange(const std::string &name, const Transform &renderFromInstance,
                        const Bounds3f &objectBounds, const FileLoc &loc) {
    const SquareMatrix4 &m = renderFromInstance.Matrix();
    const std::string what = "ObjectInstance \"" + name + "\": ";
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (!std::isfinite(m.m[r][c])) throw PbrtError(loc, what + "its transformation is not finite");
    if (m.m[3][0] != 0 || m.m[3][1] != 0 || m.m[3][2] != 0 || m.m[3][3] != 1)
        throw PbrtError(loc, what + "its transformation is projective; instances take affine "
                                    "transformations only (last row 0 0 0 1)");
    if (objectBounds.IsEmpty()) return;
    for (int c = 0; c < 8; ++c) {
        const Point3f corner = objectBounds.Corner(c);
        const Point3f w = renderFromInstance.ApplyPoint(corner);
        if (!WithinRenderRange(w))
            throw PbrtError(loc, what + "the object reaches " + PointText(w) + " after the "
                                        "instance's transformation, beyond the +-1e12 the ray "
                                        "tracer can intersect (it would vanish from the image)");
    }
}

// The other way round: Embree intersects an instance in the object's own space, carrying
// every ray there with the inverse transformation. A transformation that shrinks the object
// enormously takes the rays of the rest of the scene (its extent: the geometry and the
// camera) beyond the same range, or beyond what Embree accepts as a ray at all (it aborts).
void CheckInstanceRays(const std::string &name, const Transform &renderFromInstance,
                       const Bounds3f &sceneExtent, const FileLoc &loc) {
    if (sceneExtent.IsEmpty()) return;
    const Transform instanceFromRender = Inverse(renderFromInstance);
    // Directions too (Embree checks them like origins): a ray's direction is at most as long
    // as the scene is wide (shadow rays are not normalized), at least 1.
    const SquareMatrix4 &inv = instanceFromRender.Matrix();
    double gain = 0;  // the largest growth of a direction component (max row sum)
    for (int r = 0; r < 3; ++r)
        gain = std::max(gain, double(std::abs(inv.m[r][0])) + std::abs(inv.m[r][1]) + std::abs(inv.m[r][2]));
    const double length = std::max(1.0, double(Length(sceneExtent.Diagonal())));
    if (!(gain * length <= kMaxRenderCoordinate)) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), "ray directions up to %g long (the scene's width) grow to %g",
                      length, gain * length);
        throw PbrtError(loc, "ObjectInstance \"" + name + "\": its transformation shrinks the object "
                             "so much that " + buf + " in the object's own space, beyond the "
                             "+-1e12 the ray tracer can intersect");
    }
    for (int c = 0; c < 8; ++c) {
        const Point3f corner = sceneExtent.Corner(c);
        const Point3f w = instanceFromRender.ApplyPoint(corner);
        if (!WithinRenderRange(w))
            throw PbrtError(loc, "ObjectInstance \"" + name + "\": its transformation shrinks the "
                                 "object so much that rays from the rest of the scene (which "
                                 "reaches " + PointText(corner) + ") lie at " + PointText(w) +
                                 " in the object's own space, beyond the +-1e12 the ray tracer "
                                 "can intersect");
    }
}

// Every parameter nothing looked up is an error (it may change the picture), unless it is
// known to be harmless.
void CheckUnused(const ParameterDictionary &dict, const std::string &what) {
    for (const ParsedParameter *p : dict.Unused()) {
        if (kHarmlessParameters.count(p->name))
            Warning(p->loc, "parameter " + ParamName(*p) + " of " + what + " is ignored");
        else
            throw PbrtError(p->loc, "parameter " + ParamName(*p) + " of " + what +
                                        " is unknown or not supported");
    }
}

ParsedParameterVector Concat(ParsedParameterVector a, const ParsedParameterVector &b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

struct MaterialRef {
    int index = -1;          // anonymous material (Material directive) or default
    std::string name;        // NamedMaterial (any string, "" too: the fuzzer found it)
    FileLoc loc;
    bool named = false;      // set by NamedMaterial: name, not index, says which
};

struct AreaLightDesc {
    std::string name;
    ParsedParameterVector params;
    FileLoc loc;
    const RGBColorSpace *colorSpace = nullptr;
};

struct GraphicsState {
    pbrt::Transform ctm[2];
    int activeTransformBits = 3;
    bool reverseOrientation = false;
    MaterialRef material;
    std::optional<AreaLightDesc> areaLight;
    const RGBColorSpace *colorSpace = nullptr;
    ParsedParameterVector shapeAttributes, lightAttributes, materialAttributes, textureAttributes;
};

struct PendingInstance {
    std::string name;
    pbrt::Transform renderFromInstance;
    FileLoc loc;
};

class SceneBuilder : public ParserTarget {
  public:
    SceneBuilder(Scene *scene, const RenderOptions &opts) : scene(scene), opts(opts) {
        scene->accel = std::make_unique<pbrt::Accelerator>();
        graphicsState.colorSpace = RGBColorSpace::sRGB;
        // pbrt-v4's default material: diffuse with reflectance 0.5.
        auto half = std::make_shared<ConstantSpectrum>(0.5f);
        scene->materials.push_back(DiffuseMaterial{MakeConstantSpectrumTexture(half), nullptr, half});
        scene->materialWhere.push_back("default material");
        scene->materialUsed.push_back(0);
        graphicsState.material.index = 0;
    }

    // --- Transformations -------------------------------------------------------------------
    template <typename F>
    void ForActive(F f) {
        for (int i = 0; i < 2; ++i)
            if (graphicsState.activeTransformBits & (1 << i)) graphicsState.ctm[i] = f(graphicsState.ctm[i]);
    }
    void Identity(FileLoc) override { ForActive([](const pbrt::Transform &) { return pbrt::Transform(); }); }
    void Translate(Float dx, Float dy, Float dz, FileLoc) override {
        ForActive([&](const pbrt::Transform &t) { return t * pbrt::Translate(Vector3f(dx, dy, dz)); });
    }
    void Scale(Float sx, Float sy, Float sz, FileLoc loc) override {
        pbrt::Transform s = Wrap(loc, [&] { return pbrt::Scale(sx, sy, sz); });
        ForActive([&](const pbrt::Transform &t) { return t * s; });
    }
    void Rotate(Float angle, Float ax, Float ay, Float az, FileLoc loc) override {
        pbrt::Transform r = Wrap(loc, [&] { return pbrt::Rotate(angle, Vector3f(ax, ay, az)); });
        ForActive([&](const pbrt::Transform &t) { return t * r; });
    }
    void LookAt(Float ex, Float ey, Float ez, Float lx, Float ly, Float lz, Float ux, Float uy,
                Float uz, FileLoc loc) override {
        pbrt::Transform l = Wrap(loc, [&] {
            return pbrt::LookAt(Point3f(ex, ey, ez), Point3f(lx, ly, lz), Vector3f(ux, uy, uz));
        });
        ForActive([&](const pbrt::Transform &t) { return t * l; });
    }
    void Transform(Float m[16], FileLoc loc) override {
        pbrt::Transform x = Wrap(loc, [&] { return TransformFromColumnMajor(m); });
        ForActive([&](const pbrt::Transform &) { return x; });
    }
    void ConcatTransform(Float m[16], FileLoc loc) override {
        pbrt::Transform x = Wrap(loc, [&] { return TransformFromColumnMajor(m); });
        ForActive([&](const pbrt::Transform &t) { return t * x; });
    }
    void CoordinateSystem(const std::string &name, FileLoc) override {
        namedCoordinateSystems[name] = {graphicsState.ctm[0], graphicsState.ctm[1]};
    }
    void CoordSysTransform(const std::string &name, FileLoc loc) override {
        auto it = namedCoordinateSystems.find(name);
        if (it == namedCoordinateSystems.end())
            throw PbrtError(loc, "CoordSysTransform: unknown coordinate system \"" + name + "\"");
        graphicsState.ctm[0] = it->second.first;
        graphicsState.ctm[1] = it->second.second;
    }
    void ActiveTransformAll(FileLoc) override { graphicsState.activeTransformBits = 3; }
    void ActiveTransformEndTime(FileLoc) override { graphicsState.activeTransformBits = 2; }
    void ActiveTransformStartTime(FileLoc) override { graphicsState.activeTransformBits = 1; }
    void TransformTimes(Float, Float, FileLoc) override {}

    // --- Scene-wide options ---------------------------------------------------------------
    void ColorSpace(const std::string &name, FileLoc loc) override {
        const RGBColorSpace *cs = RGBColorSpace::GetNamed(name);
        if (!cs) throw PbrtError(loc, "unknown color space \"" + name + "\"");
        graphicsState.colorSpace = cs;
    }
    void Option(const std::string &name, const std::string &value, FileLoc loc) override {
        auto boolValue = [&] {
            if (value == "true") return true;
            if (value == "false") return false;
            throw PbrtError(loc, "Option \"" + name + "\": expected true or false, got \"" + value + "\"");
        };
        if (name == "disablepixeljitter") scene->disablePixelJitter = boolValue();
        else if (name == "disablewavelengthjitter") scene->disableWavelengthJitter = boolValue();
        else if (name == "seed") {
            try {
                optionSeed = std::stoll(value);
            } catch (...) {
                throw PbrtError(loc, "Option \"seed\": not an integer: \"" + value + "\"");
            }
        } else if (name == "rendercoordsys" || name == "disabletexturefiltering" ||
                   name == "displacementedgescale" || name == "wavefront" || name == "gpu" ||
                   name == "pixelstats" || name == "msereferenceimage" || name == "msereferenceout" ||
                   name == "recordpixelstatistics") {
            Warning(loc, "Option \"" + name + "\" has no effect here");
        } else if (name == "forcediffuse") {
            if (boolValue()) throw PbrtError(loc, "Option \"forcediffuse\" is not supported");
        } else {
            throw PbrtError(loc, "unknown Option \"" + name + "\"");
        }
    }
    void PixelFilter(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireOptionsBlock("PixelFilter", loc);
        ParameterDictionary dict(std::move(params));
        scene->filter = Filter::Create(name, dict, loc);
        filterLoc = loc;
        CheckUnused(dict, "PixelFilter \"" + name + "\"");
    }
    void Film(const std::string &type, ParsedParameterVector params, FileLoc loc) override {
        RequireOptionsBlock("Film", loc);
        filmDesc = {type, std::move(params), loc, graphicsState.colorSpace};
        // A film that cannot be made (too big for memory, a bad resolution) is refused here,
        // before the world (perhaps huge meshes) is read; EndOfFiles makes it for real.
        ParameterDictionary early(filmDesc->params);
        FilmSettings::Create(type, early, graphicsState.colorSpace, opts, loc);
    }
    void Sampler(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireOptionsBlock("Sampler", loc);
        samplerDesc = {name, std::move(params), loc, nullptr};
    }
    void Accelerator(const std::string &, ParsedParameterVector, FileLoc loc) override {
        RequireOptionsBlock("Accelerator", loc);  // Embree builds its own BVH
    }
    void Integrator(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireOptionsBlock("Integrator", loc);
        integratorDesc = {name, std::move(params), loc, nullptr};
    }
    void Camera(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireOptionsBlock("Camera", loc);
        CheckNoMotion(loc, "Camera");
        cameraDesc = {name, std::move(params), loc, nullptr};
        cameraFromWorld = graphicsState.ctm[0];
        namedCoordinateSystems["camera"] = {Inverse(graphicsState.ctm[0]), Inverse(graphicsState.ctm[1])};
    }
    void MakeNamedMedium(const std::string &name, ParsedParameterVector, FileLoc loc) override {
        throw PbrtError(loc, "MakeNamedMedium \"" + name + "\": participating media are not supported");
    }
    void MediumInterface(const std::string &inside, const std::string &outside, FileLoc loc) override {
        if (!inside.empty() || !outside.empty())
            throw PbrtError(loc, "MediumInterface: participating media are not supported");
    }

    // --- The world ------------------------------------------------------------------------------
    void WorldBegin(FileLoc loc) override {
        if (inWorld) throw PbrtError(loc, "WorldBegin appears twice");
        inWorld = true;
        graphicsState.ctm[0] = graphicsState.ctm[1] = pbrt::Transform();
        graphicsState.activeTransformBits = 3;
        namedCoordinateSystems["world"] = {pbrt::Transform(), pbrt::Transform()};
    }
    void AttributeBegin(FileLoc loc) override {
        RequireWorld("AttributeBegin", loc);
        pushedStates.push_back(graphicsState);
        pushKinds.push_back({'a', loc});
    }
    void AttributeEnd(FileLoc loc) override {
        RequireWorld("AttributeEnd", loc);
        if (pushedStates.empty()) throw PbrtError(loc, "unmatched AttributeEnd");
        if (pushKinds.back().first != 'a')
            throw PbrtError(loc, "AttributeEnd closes the ObjectBegin at " + pushKinds.back().second.ToString());
        graphicsState = std::move(pushedStates.back());
        pushedStates.pop_back();
        pushKinds.pop_back();
    }
    void Attribute(const std::string &target, ParsedParameterVector params, FileLoc loc) override {
        ParsedParameterVector *dst = nullptr;
        if (target == "shape") dst = &graphicsState.shapeAttributes;
        else if (target == "light") dst = &graphicsState.lightAttributes;
        else if (target == "material") dst = &graphicsState.materialAttributes;
        else if (target == "texture") dst = &graphicsState.textureAttributes;
        else if (target == "medium") throw PbrtError(loc, "Attribute \"medium\": media are not supported");
        else throw PbrtError(loc, "Attribute: unknown target \"" + target + "\"");
        dst->insert(dst->end(), params.begin(), params.end());
    }
    void Texture(const std::string &name, const std::string &type, const std::string &texname,
                 ParsedParameterVector params, FileLoc loc) override;
    void Material(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireWorld("Material", loc);
        ParameterDictionary dict(Concat(std::move(params), graphicsState.materialAttributes));
        scene->materials.push_back(MakeMaterial(name, dict, loc));
        scene->materialWhere.push_back(loc.ToString());
        scene->materialUsed.push_back(0);
        graphicsState.material = MaterialRef{int(scene->materials.size()) - 1, "", loc};
    }
    void MakeNamedMaterial(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireWorld("MakeNamedMaterial", loc);
        if (namedMaterials.count(name))
            throw PbrtError(loc, "named material \"" + name + "\" redefined");
        ParameterDictionary dict(Concat(std::move(params), graphicsState.materialAttributes));
        std::string type = dict.GetOneString("type", "");
        scene->materials.push_back(MakeMaterial(type, dict, loc));
        scene->materialWhere.push_back(loc.ToString() + " " + name);
        scene->materialUsed.push_back(0);
        namedMaterials[name] = int(scene->materials.size()) - 1;
    }
    void NamedMaterial(const std::string &name, FileLoc loc) override {
        RequireWorld("NamedMaterial", loc);
        graphicsState.material = MaterialRef{-1, name, loc, true};
    }
    void LightSource(const std::string &name, ParsedParameterVector params, FileLoc loc) override;
    void AreaLightSource(const std::string &name, ParsedParameterVector params, FileLoc loc) override {
        RequireWorld("AreaLightSource", loc);
        if (name != "diffuse")
            throw PbrtError(loc, "AreaLightSource \"" + name + "\" is not supported (only \"diffuse\")");
        graphicsState.areaLight = AreaLightDesc{name, Concat(std::move(params), graphicsState.lightAttributes),
                                                loc, graphicsState.colorSpace};
    }
    void Shape(const std::string &name, ParsedParameterVector params, FileLoc loc) override;
    void ReverseOrientation(FileLoc loc) override {
        RequireWorld("ReverseOrientation", loc);
        graphicsState.reverseOrientation = !graphicsState.reverseOrientation;
    }
    void ObjectBegin(const std::string &name, FileLoc loc) override {
        RequireWorld("ObjectBegin", loc);
        if (currentObject != 0)
            throw PbrtError(loc, "ObjectBegin \"" + name + "\" inside the definition of another object");
        if (objects.count(name)) throw PbrtError(loc, "object \"" + name + "\" redefined");
        pushedStates.push_back(graphicsState);
        pushKinds.push_back({'o', loc});
        currentObject = scene->accel->NewObject();
        objects[name] = currentObject;
    }
    void ObjectEnd(FileLoc loc) override {
        RequireWorld("ObjectEnd", loc);
        if (currentObject == 0 || pushKinds.empty() || pushKinds.back().first != 'o')
            throw PbrtError(loc, "ObjectEnd without a matching ObjectBegin");
        currentObject = 0;
        graphicsState = std::move(pushedStates.back());
        pushedStates.pop_back();
        pushKinds.pop_back();
    }
    void ObjectInstance(const std::string &name, FileLoc loc) override {
        RequireWorld("ObjectInstance", loc);
        if (currentObject != 0)
            throw PbrtError(loc, "ObjectInstance inside an object definition is not supported");
        CheckNoMotion(loc, "ObjectInstance");
        instances.push_back({name, graphicsState.ctm[0], loc});
    }
    void EndOfFiles() override;

  private:
    struct Desc {
        std::string name;
        ParsedParameterVector params;
        FileLoc loc;
        const RGBColorSpace *colorSpace;
    };

    template <typename F>
    static pbrt::Transform Wrap(const FileLoc &loc, F f) {
        try {
            return f();
        } catch (const PbrtError &e) {
            throw PbrtError(loc, e.what());
        }
    }
    void RequireOptionsBlock(const char *what, const FileLoc &loc) const {
        if (inWorld) throw PbrtError(loc, std::string(what) + " is not allowed after WorldBegin");
    }
    void RequireWorld(const char *what, const FileLoc &loc) const {
        if (!inWorld) throw PbrtError(loc, std::string(what) + " is only allowed after WorldBegin");
    }
    void CheckNoMotion(const FileLoc &loc, const char *what) const {
        if (graphicsState.ctm[0] != graphicsState.ctm[1])
            throw PbrtError(loc, std::string(what) + ": motion blur (different start and end "
                                                     "transformations) is not supported");
    }

    // Spectra and textures from parameters.
    SpectrumHandle MakeSpectrum(const ParsedParameter &p, SpectrumType type, const RGBColorSpace &cs) const;
    SpectrumHandle RGBSpectrum(const std::array<Float, 3> &rgb, SpectrumType type,
                               const RGBColorSpace &cs, const FileLoc &loc) const;
    // A spectrum-valued parameter given as rgb, spectrum or blackbody (no textures).
    SpectrumHandle GetSpectrum(const ParameterDictionary &dict, const std::string &name,
                               SpectrumType type, const RGBColorSpace &cs) const;
    TextureResolver Resolver(const ParameterDictionary &dict, const RGBColorSpace &cs) const;
    pbrt::Material MakeMaterial(const std::string &type, const ParameterDictionary &dict,
                                const FileLoc &loc) const {
        // The layered material's random walks are seeded like the sampler (--seed, Option).
        uint64_t seed = opts.seed ? *opts.seed : uint64_t(optionSeed.value_or(0));
        pbrt::Material m = CreateMaterial(type, dict, Resolver(dict, *graphicsState.colorSpace), loc, seed);
        CheckUnused(dict, "material \"" + type + "\"");
        return m;
    }
    int ResolveMaterial(const MaterialRef &ref) const {
        if (!ref.named) return ref.index;
        auto it = namedMaterials.find(ref.name);
        if (it == namedMaterials.end())
            throw PbrtError(ref.loc, "NamedMaterial \"" + ref.name + "\" is not defined");
        return it->second;
    }

    Scene *scene;
    RenderOptions opts;
    GraphicsState graphicsState;
    std::vector<GraphicsState> pushedStates;
    std::vector<std::pair<char, FileLoc>> pushKinds;
    std::map<std::string, std::pair<pbrt::Transform, pbrt::Transform>> namedCoordinateSystems;
    std::map<std::string, int> namedMaterials;
    std::map<std::string, FloatTextureHandle> floatTextures;
    std::map<std::string, SpectrumTextureHandle> albedoTextures, unboundedTextures;
    TextureImageCache textureImages;
    std::map<std::string, int> objects;
    std::vector<PendingInstance> instances;
    int currentObject = 0;
    bool inWorld = false;
    std::optional<long long> optionSeed;
    pbrt::Transform cameraFromWorld;
    FileLoc filterLoc;
    std::optional<Desc> filmDesc, samplerDesc, integratorDesc, cameraDesc;
};

// --- Spectra ----------------------------------------------------------------------------------
SpectrumHandle SceneBuilder::RGBSpectrum(const std::array<Float, 3> &v, SpectrumType type,
                                         const RGBColorSpace &cs, const FileLoc &loc) const {
    RGB rgb(v[0], v[1], v[2]);
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(rgb[c]) || rgb[c] < 0)
            throw PbrtError(loc, "RGB value " + rgb.ToString() + " has a negative or non-finite component");
    switch (type) {
    case SpectrumType::Albedo:
        if (rgb.MaxComponentValue() > 1)
            throw PbrtError(loc, "RGB reflectance " + rgb.ToString() + " has a component > 1");
        return std::make_shared<RGBAlbedoSpectrum>(cs, rgb);
    case SpectrumType::Unbounded: return std::make_shared<RGBUnboundedSpectrum>(cs, rgb);
    case SpectrumType::Illuminant: return std::make_shared<RGBIlluminantSpectrum>(cs, rgb);
    }
    return nullptr;
}

SpectrumHandle SceneBuilder::MakeSpectrum(const ParsedParameter &p, SpectrumType type,
                                          const RGBColorSpace &cs) const {
    try {
        if (p.type == "rgb") {
            return RGBSpectrum({Float(p.floats[0]), Float(p.floats[1]), Float(p.floats[2])}, type, cs, p.loc);
        }
        if (p.type == "blackbody") {
            if (!(p.floats[0] > 0)) throw PbrtError(p.loc, "blackbody temperature must be positive");
            return std::make_shared<BlackbodySpectrum>(Float(p.floats[0]));
        }
        if (p.type == "spectrum") {
            if (!p.strings.empty()) {
                // A named spectrum, or a .spd file relative to the scene file.
                if (SpectrumHandle s = GetNamedSpectrum(p.strings[0])) return s;
                return PiecewiseLinearSpectrum::ReadSPD(ResolveFilename(p.strings[0], p.loc));
            }
            std::vector<Float> v(p.floats.begin(), p.floats.end());
            return PiecewiseLinearSpectrum::FromInterleaved(v, false, &p.loc);
        }
    } catch (const PbrtError &e) {
        std::string msg = e.what();
        if (msg.find(p.loc.filename) == std::string::npos || p.loc.filename.empty())
            throw PbrtError(p.loc, "parameter " + ParamName(p) + ": " + msg);
        throw;
    }
    throw PbrtError(p.loc, "parameter " + ParamName(p) + " has type \"" + p.type +
                               "\"; expected rgb, spectrum or blackbody");
}

SpectrumHandle SceneBuilder::GetSpectrum(const ParameterDictionary &dict, const std::string &name,
                                         SpectrumType type, const RGBColorSpace &cs) const {
    if (auto rgb = dict.GetOneRGB(name)) return RGBSpectrum(*rgb, type, cs, dict.Loc(name));
    const ParsedParameter *p = dict.Find(name);
    if (!p) return nullptr;
    return MakeSpectrum(*p, type, cs);
}

TextureResolver SceneBuilder::Resolver(const ParameterDictionary &dict, const RGBColorSpace &cs) const {
    TextureResolver r;
    r.spectrum = [this, &dict, &cs](const std::string &name, SpectrumHandle def,
                                    SpectrumType type) -> SpectrumTextureHandle {
        std::string tex = dict.GetTexture(name);
        if (!tex.empty()) {
            const auto &m = type == SpectrumType::Albedo ? albedoTextures : unboundedTextures;
            auto it = m.find(tex);
            if (it == m.end())
                throw PbrtError(dict.Loc(name), "spectrum texture \"" + tex + "\" is not defined");
            return it->second;
        }
        const ParsedParameter *p = dict.Find(name);
        if (p && p->type == "float") {
            // A float given for a spectrum: a constant spectrum (pbrt-v4 accepts this).
            if (p->floats.size() != 1) throw PbrtError(p->loc, "parameter " + ParamName(*p) + " needs one value");
            return MakeConstantSpectrumTexture(std::make_shared<ConstantSpectrum>(Float(p->floats[0])));
        }
        SpectrumHandle s = GetSpectrum(dict, name, type, cs);
        if (!s) s = def;
        return s ? MakeConstantSpectrumTexture(s) : nullptr;
    };
    r.floats = [this, &dict](const std::string &name, std::optional<Float> def) -> FloatTextureHandle {
        std::string tex = dict.GetTexture(name);
        if (!tex.empty()) {
            auto it = floatTextures.find(tex);
            if (it == floatTextures.end())
                throw PbrtError(dict.Loc(name), "float texture \"" + tex + "\" is not defined");
            return it->second;
        }
        const ParsedParameter *p = dict.Find(name);
        if (p) {
            if (p->type != "float" || p->floats.size() != 1)
                throw PbrtError(p->loc, "parameter " + ParamName(*p) + ": expected one float or a texture");
            return MakeConstantFloatTexture(Float(p->floats[0]));
        }
        return def ? MakeConstantFloatTexture(*def) : nullptr;
    };
    return r;
}

// --- Textures --------------------------------------------------------------------------------
void SceneBuilder::Texture(const std::string &name, const std::string &type,
                           const std::string &texname, ParsedParameterVector params, FileLoc loc) {
    RequireWorld("Texture", loc);
    if (type != "float" && type != "spectrum")
        throw PbrtError(loc, "Texture \"" + name + "\": type must be \"float\" or \"spectrum\", not \"" + type + "\"");
    if ((type == "float" && floatTextures.count(name)) || (type == "spectrum" && albedoTextures.count(name)))
        throw PbrtError(loc, "texture \"" + name + "\" redefined");
    ParameterDictionary dict(Concat(std::move(params), graphicsState.textureAttributes));
    const RGBColorSpace &cs = *graphicsState.colorSpace;
    TextureDefinition t = CreateTexture(name, type, texname, dict, Resolver(dict, cs), cs,
                                        &textureImages, loc);
    CheckUnused(dict, "Texture \"" + name + "\"");
    if (type == "float") {
        floatTextures[name] = t.floatTexture;
    } else {
        albedoTextures[name] = t.albedo;
        unboundedTextures[name] = t.unbounded;
    }
}

// --- Lights ------------------------------------------------------------------------------------
void SceneBuilder::LightSource(const std::string &name, ParsedParameterVector params, FileLoc loc) {
    RequireWorld("LightSource", loc);
    if (currentObject != 0) throw PbrtError(loc, "LightSource inside an object definition is not supported");
    CheckNoMotion(loc, "LightSource");
    ParameterDictionary dict(Concat(std::move(params), graphicsState.lightAttributes));
    const char *specName = EmissionParameterName("LightSource", name);
    SpectrumHandle spec = GetSpectrum(dict, specName, SpectrumType::Illuminant, *graphicsState.colorSpace);
    Light light = Light::Create(name, dict, graphicsState.ctm[0], spec, *graphicsState.colorSpace, loc);
    CheckUnused(dict, "LightSource \"" + name + "\"");
    if (light.IsInfinite() && light.Type() == LightType::UniformInfinite)
        scene->infiniteLights.push_back(int(scene->lights.size()));
    scene->lights.push_back(std::move(light));
}

// --- Shapes ------------------------------------------------------------------------------------
void SceneBuilder::Shape(const std::string &name, ParsedParameterVector params, FileLoc loc) {
    RequireWorld("Shape", loc);
    CheckNoMotion(loc, "Shape");
    ParameterDictionary dict(Concat(std::move(params), graphicsState.shapeAttributes));
    ShapeSet shapes = CreateShapes(name, dict, graphicsState.ctm[0], graphicsState.reverseOrientation, loc);
    CheckUnused(dict, "Shape \"" + name + "\"");

    int material = ResolveMaterial(graphicsState.material);
    scene->materialUsed[size_t(material)] = 1;
    if (std::holds_alternative<InterfaceMaterial>(scene->materials[material])) {
        material = -1;
        scene->hasInterfaces = true;
    }

    // Emission: one area light per triangle / sphere.
    std::optional<ParameterDictionary> lightDict;
    SpectrumHandle L;
    if (graphicsState.areaLight) {
        if (currentObject != 0) {
            Warning(loc, "area lights are not supported inside object instances (as in pbrt-v4); "
                         "the shape does not emit");
        } else {
            const AreaLightDesc &al = *graphicsState.areaLight;
            lightDict.emplace(al.params);
            L = GetSpectrum(*lightDict, EmissionParameterName("AreaLightSource", al.name),
                            SpectrumType::Illuminant, *al.colorSpace);
        }
    }
    auto addLights = [&](std::shared_ptr<const TriangleMesh> mesh, const Sphere *sphere) {
        if (!lightDict) return -1;
        int offset = int(scene->lights.size());
        Light::CreateArea(*lightDict, L, *graphicsState.areaLight->colorSpace, mesh, sphere,
                          graphicsState.areaLight->loc, &scene->lights);
        return offset;
    };
    for (auto &mesh : shapes.meshes) {
        if (mesh->NumTriangles() == 0) continue;
        int lightOffset = addLights(mesh, nullptr);
        scene->accel->AddMesh(currentObject, mesh, material, lightOffset);
    }
    for (const Sphere &s : shapes.spheres) {
        int lightOffset = addLights(nullptr, &s);
        scene->accel->AddSphere(currentObject, s, material, lightOffset);
    }
    if (lightDict) CheckUnused(*lightDict, "AreaLightSource \"diffuse\"");
}

// --- End: everything that needs the whole scene -------------------------------------------
void SceneBuilder::EndOfFiles() {
    if (!pushedStates.empty())
        throw PbrtError(pushKinds.back().second, "AttributeBegin/ObjectBegin without a matching end");
    // Object instances.
    for (const PendingInstance &inst : instances) {
        auto it = objects.find(inst.name);
        if (it == objects.end()) throw PbrtError(inst.loc, "ObjectInstance: object \"" + inst.name + "\" is not defined");
        if (!scene->accel->ObjectIsEmpty(it->second))
            CheckInstanceRange(inst.name, inst.renderFromInstance, scene->accel->ObjectBounds(it->second),
                               inst.loc);
        scene->accel->AddInstance(it->second, inst.renderFromInstance);
    }
    scene->accel->Commit();
    {
        // Where rays can start: the geometry, and the camera.
        const Bounds3f extent = Union(scene->accel->Bounds(),
                                      Inverse(cameraFromWorld).ApplyPoint(Point3f(0, 0, 0)));
        for (const PendingInstance &inst : instances)
            if (!scene->accel->ObjectIsEmpty(objects.at(inst.name)))
                CheckInstanceRays(inst.name, inst.renderFromInstance, extent, inst.loc);
    }

    // Film, camera, sampler, integrator (pbrt-v4 defaults when a directive is absent).
    Desc film = filmDesc ? *filmDesc : Desc{"rgb", {}, FileLoc{}, graphicsState.colorSpace};
    ParameterDictionary filmDict(film.params);
    FilmSettings fs = FilmSettings::Create(film.name, filmDict, film.colorSpace ? film.colorSpace : RGBColorSpace::sRGB,
                                           opts, film.loc);
    CheckUnused(filmDict, "Film \"" + film.name + "\"");
    if (opts.outfile.empty() && opts.emissionSpectrum.empty() && opts.materialReflectances.empty() &&
        opts.emissionTable.empty() && opts.guidingSpectraDir.empty()) {
        try {
            CheckOutputImagePath(fs.filename);
        } catch (const PbrtError &e) {
            throw PbrtError(filmDict.Find("filename") ? filmDict.Loc("filename") : film.loc,
                            std::string("Film \"filename\": ") + e.what());
        }
    }

    Desc cam = cameraDesc ? *cameraDesc : Desc{"perspective", {}, FileLoc{}, nullptr};
    ParameterDictionary camDict(cam.params);
    scene->camera = std::make_unique<pbrt::Camera>(
        pbrt::Camera::Create(cam.name, camDict, cameraFromWorld, fs.fullResolution, cam.loc));
    CheckUnused(camDict, "Camera \"" + cam.name + "\"");
    // No non-finite camera ray may reach the ray tracer: checked here, before rendering.
    // (At the Camera statement; at the PixelFilter's when the scene has no Camera.)
    scene->camera->CheckRays(scene->filter.Radius(), cameraDesc ? cam.loc : filterLoc);
    scene->film = std::make_unique<RGBFilm>(fs, scene->camera->ExposureTime());

    Desc samp = samplerDesc ? *samplerDesc : Desc{"zsobol", {}, FileLoc{}, nullptr};
    ParameterDictionary sampDict(samp.params);
    scene->sampler = pbrt::Sampler::Create(samp.name, sampDict, optionSeed ? uint64_t(*optionSeed) : 0,
                                           opts.seed, opts.spp, samp.loc, fs.fullResolution, opts.quick);
    CheckUnused(sampDict, "Sampler \"" + samp.name + "\"");

    // pbrt-v4's default integrator is "volpath", which we render as "path" (no media).
    Desc integ = integratorDesc ? *integratorDesc : Desc{"path", {}, FileLoc{}, nullptr};
    ParameterDictionary integDict(integ.params);
    scene->integrator = IntegratorSettings::Create(integ.name, integDict, integ.loc);
    CheckUnused(integDict, "Integrator \"" + integ.name + "\"");
    if (opts.maxDepth) scene->integrator.maxDepth = *opts.maxDepth;

    // Wavelength sampling (a table, design §1, or a built-in sampler, design §5.2).
    if (!opts.wavelengthTable.empty())
        scene->wavelengths = WavelengthSampler::FromTable(opts.wavelengthTable, opts.defensiveShare);
    else if (opts.wavelengthSampling == "visible") scene->wavelengths = WavelengthSampler::Visible();
    else if (opts.wavelengthSampling == "uniform")
        scene->wavelengths = WavelengthSampler::Uniform(opts.lambdaMin, opts.lambdaMax);
    else if (opts.wavelengthSampling != "emission")
        throw PbrtError("unknown wavelength sampling \"" + opts.wavelengthSampling + "\"");

    // Lights that need the scene bounds, and the light sampler.
    Light::ShareEqualSpectra(scene->lights);
    for (Light &l : scene->lights) l.Preprocess(scene->accel->Bounds());
    scene->lightSampler = LightSampler(scene->lights);
    const bool emission = opts.wavelengthSampling == "emission" || opts.wavelengthGuiding;
    if (scene->lights.empty())
        Warning(opts.wavelengthGuiding
                    ? "the scene has no lights; the image will be black (--wavelength-guiding "
                      "has no emission to sample: visible sampling instead)"
                : opts.wavelengthSampling == "emission"
                    ? "the scene has no lights; the image will be black (--wavelength-sampling "
                      "emission has no emission to sample: visible sampling instead)"
                    : "the scene has no lights; the image will be black");
    // Emission sampling (design §1.7, §5.2): a table from the lights' power, which needs the
    // scene's bounds (infinite lights); a light that makes it impossible stops pbrt here.
    if (emission && !scene->lights.empty()) {
        EmissionTable t = SceneEmissionTable(*scene, opts.emissionWeight);
        scene->wavelengths = WavelengthSampler::FromEmission(t.table, t.weight, t.seconds);
    }
    // design §1: a light emitting where the sampling density is zero biases the image.
    for (const std::string &w : UnsampledEmissionWarnings(scene->wavelengths, scene->lights)) Warning(w);
}

std::unique_ptr<Scene> Build(const RenderOptions &opts, const std::function<void(ParserTarget *)> &parse) {
    auto scene = std::make_unique<Scene>();
    SceneBuilder builder(scene.get(), opts);
    parse(&builder);
    scene->disablePixelJitter |= opts.disablePixelJitter;
    scene->disableWavelengthJitter |= opts.disableWavelengthJitter;
    scene->wavelengthNet = opts.wavelengthNet;
    scene->wavelengthSeed = opts.wavelengthSeed;
    Verbose("loaded the scene: " + std::to_string(scene->lights.size()) + " lights");
    return scene;
}

}  // namespace

std::unique_ptr<Scene> LoadScene(const std::vector<std::string> &files, const RenderOptions &opts) {
    return Build(opts, [&](ParserTarget *t) { ParseFiles(t, files); });
}

std::unique_ptr<Scene> LoadSceneFromString(const std::string &text, const RenderOptions &opts,
                                           const std::string &name) {
    return Build(opts, [&](ParserTarget *t) { ParseString(t, text, name); });
}

}  // namespace pbrt
