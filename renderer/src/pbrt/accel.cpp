#include <pbrt/accel.h>

#include <pbrt/flat_triangles.h>

#include <embree3/rtcore.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace pbrt {

namespace {

void EmbreeErrorCallback(void *, RTCError code, const char *str) {
    // Errors at build time become exceptions in Commit/Add*; here we only remember them.
    (void)code;
    Warning(std::string("Embree: ") + (str ? str : "unknown error"));
}

struct Record {
    enum class Kind { Mesh, Sphere, Instance } kind;
    int index;        // mesh, sphere, or instance index (for Instance: into instances)
    int material;
    int lightOffset;
};

struct Object {
    RTCScene scene = nullptr;
    std::vector<std::shared_ptr<TriangleMesh>> meshes;
    std::vector<std::unique_ptr<Sphere>> spheres;
    std::vector<Record> records;  // indexed by Embree geometry ID
    bool committed = false;
};

struct Instance {
    int object;
    Transform renderFromInstance;
};

// --- Sphere user-geometry callbacks --------------------------------------------------------
// Render-space bounds of a sphere, padded a little: they must contain every point the
// intersection test can return.
Bounds3f SphereBounds(const Sphere &s) {
    Bounds3f b = s.renderFromObject.ApplyBounds(s.ObjectBounds());
    Vector3f pad = (Abs(b.pMin) + Abs(b.pMax)) * 1e-6f;
    return Bounds3f(b.pMin - pad, b.pMax + pad);
}

void SphereBoundsFunc(const RTCBoundsFunctionArguments *args) {
    Bounds3f b = SphereBounds(*static_cast<const Sphere *>(args->geometryUserPtr));
    args->bounds_o->lower_x = b.pMin.x;
    args->bounds_o->lower_y = b.pMin.y;
    args->bounds_o->lower_z = b.pMin.z;
    args->bounds_o->upper_x = b.pMax.x;
    args->bounds_o->upper_y = b.pMax.y;
    args->bounds_o->upper_z = b.pMax.z;
}

// The sphere's hit t in (tMin, tMax) along the render-space ray o + t d, if any: every sphere
// query (Embree's callbacks and the flat test) goes through here.
bool HitsSphere(const Sphere &s, const Point3f &o, const Vector3f &d, Float tMin, Float tMax, Float *t) {
    return s.IntersectObject(s.objectFromRender.ApplyPoint(o), s.objectFromRender.ApplyVector(d), tMax, t) &&
           *t > tMin;
}

// Whether an occlusion query skips sphere s (Accelerator::Occluded's skipSphere).
bool Skips(const Sphere &s, uint32_t skipSphere) { return s.id != 0 && s.id == skipSphere; }

void SphereIntersectFunc(const RTCIntersectFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    const Sphere *s = static_cast<const Sphere *>(args->geometryUserPtr);
    RTCRayHit *rh = reinterpret_cast<RTCRayHit *>(args->rayhit);
    Float t;
    if (!HitsSphere(*s, Point3f(rh->ray.org_x, rh->ray.org_y, rh->ray.org_z),
                    Vector3f(rh->ray.dir_x, rh->ray.dir_y, rh->ray.dir_z), rh->ray.tnear, rh->ray.tfar, &t))
        return;
    rh->ray.tfar = t;
    rh->hit.u = rh->hit.v = 0;
    rh->hit.Ng_x = rh->hit.Ng_y = 0;
    rh->hit.Ng_z = 1;
    rh->hit.primID = args->primID;
    rh->hit.geomID = args->geomID;
    rh->hit.instID[0] = args->context->instID[0];
}

// The context of every occlusion query: Embree hands it to the callbacks unchanged, so it
// carries the sphere the query skips (Accelerator::Occluded).
struct OccludedContext {
    RTCIntersectContext embree;  // first: Embree's pointer to it is a pointer to this
    uint32_t skipSphere = 0;
};

void SphereOccludedFunc(const RTCOccludedFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    const Sphere *s = static_cast<const Sphere *>(args->geometryUserPtr);
    if (Skips(*s, reinterpret_cast<const OccludedContext *>(args->context)->skipSphere)) return;
    RTCRay *r = reinterpret_cast<RTCRay *>(args->ray);
    Float t;
    if (HitsSphere(*s, Point3f(r->org_x, r->org_y, r->org_z), Vector3f(r->dir_x, r->dir_y, r->dir_z), r->tnear,
                   r->tfar, &t))
        r->tfar = -Infinity;
}

// Where a ray hit, whichever way it was found: Embree's geometry and primitive IDs (the
// instance's ID, or RTC_INVALID_GEOMETRY_ID), Embree's barycentrics of a triangle, and t.
struct HitRecord {
    unsigned geomID, primID, instID;
    Float u, v, t;
};

// A sphere of a small scene: tested when the ray crosses its bounds.
struct FlatSphere {
    const Sphere *sphere;
    Bounds3f bounds;
    unsigned geomID;
};

// Whether the ray o + t d crosses box b for some t in [0, tMax] (conservatively).
bool CrossesBounds(const Bounds3f &b, const Point3f &o, const Vector3f &d, Float tMax) {
    Float t0 = 0, t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        Float inv = 1 / d[a];
        Float tn = (b.pMin[a] - o[a]) * inv, tf = (b.pMax[a] - o[a]) * inv;
        if (tn > tf) std::swap(tn, tf);
        t0 = std::max(t0, tn);  // NaN (a zero direction on the box's face) is ignored
        t1 = std::min(t1, tf * (1 + 4e-7f));
        if (t0 > t1) return false;
    }
    return true;
}

}  // namespace

struct Accelerator::Impl {
    RTCDevice device = nullptr;
    std::vector<Object> objects;
    std::vector<Instance> instances;
    int flatMaxTriangles = 0;

    // A small scene (no instances, at most flatMaxTriangles triangles and a few spheres) is
    // traced without Embree: every triangle and sphere is tested (flat_triangles.h says why).
    bool flat = false;
    FlatTriangles flatTriangles;
    std::vector<std::pair<unsigned, unsigned>> flatIDs;  // (geomID, primID) per flat triangle
    std::vector<FlatSphere> flatSpheres;

    void MakeFlat();
    bool FlatIntersect(const Ray &ray, HitRecord *h) const;
    bool FlatOccluded(const Ray &ray, uint32_t skipSphere) const;

    RTCScene NewScene() {
        RTCScene s = rtcNewScene(device);
        rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
        return s;
    }
    void Check(const char *what) {
        RTCError e = rtcGetDeviceError(device);
        if (e != RTC_ERROR_NONE) throw PbrtError(std::string("Embree error while ") + what +
                                                 " (code " + std::to_string(int(e)) + ")");
    }
};

Accelerator::Accelerator(int flatMaxTriangles) : impl(new Impl) {
    impl->flatMaxTriangles = flatMaxTriangles;
    impl->device = rtcNewDevice(nullptr);
    if (!impl->device) throw PbrtError("could not create the Embree device");
    rtcSetDeviceErrorFunction(impl->device, EmbreeErrorCallback, nullptr);
    impl->objects.emplace_back();
    impl->objects[0].scene = impl->NewScene();
}

Accelerator::~Accelerator() {
    for (Object &o : impl->objects)
        if (o.scene) rtcReleaseScene(o.scene);
    if (impl->device) rtcReleaseDevice(impl->device);
}

int Accelerator::NewObject() {
    impl->objects.emplace_back();
    impl->objects.back().scene = impl->NewScene();
    return int(impl->objects.size()) - 1;
}

bool Accelerator::ObjectIsEmpty(int object) const { return impl->objects[object].records.empty(); }

Bounds3f Accelerator::ObjectBounds(int object) {
    Object &obj = impl->objects[object];
    if (obj.records.empty()) return Bounds3f();
    if (!obj.committed) {
        rtcCommitScene(obj.scene);
        impl->Check("building an object instance's BVH");
        obj.committed = true;
    }
    RTCBounds b;
    rtcGetSceneBounds(obj.scene, &b);
    if (!(b.lower_x <= b.upper_x)) return Bounds3f();
    return Bounds3f(Point3f(b.lower_x, b.lower_y, b.lower_z), Point3f(b.upper_x, b.upper_y, b.upper_z));
}

void Accelerator::AddMesh(int object, std::shared_ptr<TriangleMesh> mesh, int material,
                          int lightOffset) {
    Object &obj = impl->objects[object];
    RTCGeometry g = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree's own buffers (they carry the padding Embree's SIMD loads need).
    float *v = static_cast<float *>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh->p.size()));
    for (size_t i = 0; i < mesh->p.size(); ++i) {
        v[3 * i] = mesh->p[i].x;
        v[3 * i + 1] = mesh->p[i].y;
        v[3 * i + 2] = mesh->p[i].z;
    }
    unsigned *idx = static_cast<unsigned *>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh->NumTriangles()));
    std::memcpy(idx, mesh->indices.data(), mesh->indices.size() * sizeof(unsigned));
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(obj.scene, g);
    rtcReleaseGeometry(g);
    impl->Check("adding a triangle mesh");
    if (id != obj.records.size()) throw PbrtError("internal error: unexpected Embree geometry ID");
    mesh->PrecomputeFaceNormals();
    obj.records.push_back({Record::Kind::Mesh, int(obj.meshes.size()), material, lightOffset});
    obj.meshes.push_back(std::move(mesh));
}

void Accelerator::AddSphere(int object, const Sphere &sphere, int material, int lightOffset) {
    Object &obj = impl->objects[object];
    obj.spheres.push_back(std::make_unique<Sphere>(sphere));
    RTCGeometry g = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, obj.spheres.back().get());
    rtcSetGeometryBoundsFunction(g, SphereBoundsFunc, nullptr);
    rtcSetGeometryIntersectFunction(g, SphereIntersectFunc);
    rtcSetGeometryOccludedFunction(g, SphereOccludedFunc);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(obj.scene, g);
    rtcReleaseGeometry(g);
    impl->Check("adding a sphere");
    if (id != obj.records.size()) throw PbrtError("internal error: unexpected Embree geometry ID");
    obj.records.push_back({Record::Kind::Sphere, int(obj.spheres.size()) - 1, material, lightOffset});
}

void Accelerator::AddInstance(int object, const Transform &renderFromInstance) {
    Object &obj = impl->objects[object];
    if (obj.records.empty()) return;
    if (!obj.committed) {
        rtcCommitScene(obj.scene);
        impl->Check("building an object instance's BVH");
        obj.committed = true;
    }
    Object &top = impl->objects[0];
    RTCGeometry g = rtcNewGeometry(impl->device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, obj.scene);
    // 3x4 column-major: the three columns of the linear part, then the translation.
    const SquareMatrix4 &m = renderFromInstance.Matrix();
    float xfm[12];
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) xfm[c * 3 + r] = m.m[r][c];
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(top.scene, g);
    rtcReleaseGeometry(g);
    impl->Check("adding an object instance");
    if (id != top.records.size()) throw PbrtError("internal error: unexpected Embree geometry ID");
    top.records.push_back({Record::Kind::Instance, int(impl->instances.size()), -1, -1});
    impl->instances.push_back({object, renderFromInstance});
}

void Accelerator::Commit() {
    rtcCommitScene(impl->objects[0].scene);
    impl->Check("building the BVH");
    RTCBounds b;
    rtcGetSceneBounds(impl->objects[0].scene, &b);
    bounds = Bounds3f();
    if (b.lower_x <= b.upper_x)
        bounds = Bounds3f(Point3f(b.lower_x, b.lower_y, b.lower_z), Point3f(b.upper_x, b.upper_y, b.upper_z));
    impl->MakeFlat();
}

bool Accelerator::TestsEveryShape() const { return impl->flat; }

void Accelerator::Impl::MakeFlat() {
    const Object &top = objects[0];
    size_t triangles = 0;
    for (const Record &r : top.records) {
        if (r.kind == Record::Kind::Instance) return;
        if (r.kind == Record::Kind::Mesh) triangles += top.meshes[r.index]->NumTriangles();
    }
    // Spheres are tested one by one as well (a bounding-box test, then the exact one).
    constexpr size_t kMaxSpheres = 8;
    if (triangles > size_t(flatMaxTriangles) || top.spheres.size() > kMaxSpheres) return;
    for (unsigned g = 0; g < top.records.size(); ++g) {
        const Record &r = top.records[g];
        if (r.kind == Record::Kind::Sphere) {
            flatSpheres.push_back({top.spheres[r.index].get(), SphereBounds(*top.spheres[r.index]), g});
            continue;
        }
        const TriangleMesh &m = *top.meshes[r.index];
        for (size_t i = 0; i < m.NumTriangles(); ++i) {
            auto v = m.Vertices(i);
            flatTriangles.Add(v[0], v[1], v[2]);
            flatIDs.push_back({g, unsigned(i)});
        }
    }
    flat = true;
}

namespace {
// The sphere's hit with t in (0, tMax), after a test of its bounds.
bool HitsFlatSphere(const FlatSphere &fs, const Ray &ray, Float tMax, Float *t) {
    return CrossesBounds(fs.bounds, ray.o, ray.d, tMax) && HitsSphere(*fs.sphere, ray.o, ray.d, 0, tMax, t);
}
}  // namespace

bool Accelerator::Impl::FlatIntersect(const Ray &ray, HitRecord *h) const {
    FlatTriangles::Hit th;
    bool found = flatTriangles.Closest(ray.o, ray.d, ray.tMax, &th);
    if (found)
        *h = {flatIDs[th.index].first, flatIDs[th.index].second, RTC_INVALID_GEOMETRY_ID, th.b1, th.b2, th.t};
    for (const FlatSphere &fs : flatSpheres) {
        Float t;
        if (HitsFlatSphere(fs, ray, found ? h->t : ray.tMax, &t)) {
            *h = {fs.geomID, 0, RTC_INVALID_GEOMETRY_ID, 0, 0, t};
            found = true;
        }
    }
    return found;
}

bool Accelerator::Impl::FlatOccluded(const Ray &ray, uint32_t skipSphere) const {
    if (flatTriangles.Any(ray.o, ray.d, ray.tMax)) return true;
    for (const FlatSphere &fs : flatSpheres) {
        Float t;
        if (!Skips(*fs.sphere, skipSphere) && HitsFlatSphere(fs, ray, ray.tMax, &t)) return true;
    }
    return false;
}

namespace {
// Embree's limit on ray origins and directions (FLT_LARGE in its RayK::valid(), which
// aborts on a ray outside it): beyond, or NaN, the ray is dropped here instead.
constexpr Float kEmbreeLargest = 1.844e18f;

bool EmbreeAccepts(const Ray &r) {
    for (Float c : {r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z})
        if (!(std::abs(c) <= kEmbreeLargest)) return false;
    return r.tMax >= 0;  // also false for NaN
}

void WarnDroppedRay() {
    Warning("a ray with a non-finite or huge origin or direction was dropped (not traced); "
            "the scene has geometry or lights beyond the ray tracer's range");
}
}  // namespace

bool Accelerator::Intersect(const Ray &ray, SurfaceInteraction *si) const {
    if (!EmbreeAccepts(ray)) {
        WarnDroppedRay();
        return false;
    }
    HitRecord h;
    if (impl->flat) {
        if (!impl->FlatIntersect(ray, &h)) return false;
    } else {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh;
        rh.ray.org_x = ray.o.x; rh.ray.org_y = ray.o.y; rh.ray.org_z = ray.o.z;
        rh.ray.dir_x = ray.d.x; rh.ray.dir_y = ray.d.y; rh.ray.dir_z = ray.d.z;
        rh.ray.tnear = 0;
        rh.ray.tfar = ray.tMax;
        rh.ray.time = 0;
        rh.ray.mask = 0xffffffffu;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(impl->objects[0].scene, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
        h = {rh.hit.geomID, rh.hit.primID, rh.hit.instID[0], rh.hit.u, rh.hit.v, rh.ray.tfar};
    }

    // Find the shape: directly in the top level, or inside an instance.
    const Transform *xf = nullptr;
    const Object *obj = &impl->objects[0];
    if (h.instID != RTC_INVALID_GEOMETRY_ID) {
        const Instance &inst = impl->instances[impl->objects[0].records[h.instID].index];
        xf = &inst.renderFromInstance;
        obj = &impl->objects[inst.object];
    }
    const Record &rec = obj->records[h.geomID];
    Float t = h.t;
    if (rec.kind == Record::Kind::Mesh) {
        obj->meshes[rec.index]->Interaction(h.primID, h.u, h.v, si);
        si->shapeLoc = &obj->meshes[rec.index]->loc;
    } else {
        const Sphere &s = *obj->spheres[rec.index];
        Ray local = xf ? Inverse(*xf).ApplyRay(ray) : ray;
        s.Interaction(s.objectFromRender.ApplyPoint(local(t)), si);
        si->shapeLoc = &s.loc;
    }
    if (xf) {
        // Instance space to world space.
        Point3f p = xf->ApplyPoint(si->p);
        const SquareMatrix4 &m = xf->Matrix();
        Vector3f err;
        for (int i = 0; i < 3; ++i)
            err[i] = std::abs(m.m[i][0]) * si->pError.x + std::abs(m.m[i][1]) * si->pError.y +
                     std::abs(m.m[i][2]) * si->pError.z + 2e-6f * (std::abs(p[i]) + std::abs(m.m[i][3]));
        si->p = p;
        si->pError = err;
        si->n = Normalize(xf->ApplyNormal(si->n));
        si->ns = Normalize(xf->ApplyNormal(si->ns));
        si->dpdu = xf->ApplyVector(si->dpdu);
        si->dpdv = xf->ApplyVector(si->dpdv);
    }
    si->tHit = t;
    si->wo = -Normalize(ray.d);
    si->material = rec.material;
    si->areaLight = rec.lightOffset < 0 ? -1
                    : rec.lightOffset + (rec.kind == Record::Kind::Mesh ? int(h.primID) : 0);
    return true;
}

bool Accelerator::Occluded(const Ray &ray, uint32_t skipSphere) const {
    if (!EmbreeAccepts(ray)) {
        WarnDroppedRay();
        return true;
    }
    if (impl->flat) return impl->FlatOccluded(ray, skipSphere);
    OccludedContext ctx;
    rtcInitIntersectContext(&ctx.embree);
    ctx.skipSphere = skipSphere;
    RTCRay r;
    r.org_x = ray.o.x; r.org_y = ray.o.y; r.org_z = ray.o.z;
    r.dir_x = ray.d.x; r.dir_y = ray.d.y; r.dir_z = ray.d.z;
    r.tnear = 0;
    r.tfar = ray.tMax;
    r.time = 0;
    r.mask = 0xffffffffu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(impl->objects[0].scene, &ctx.embree, &r);
    return r.tfar < 0;
}

}  // namespace pbrt
