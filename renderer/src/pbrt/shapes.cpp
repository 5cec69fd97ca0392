#include <pbrt/shapes.h>

#include <pbrt/parser.h>
#include <pbrt/util/paramdict.h>
#include <pbrt/util/ply.h>

#include <atomic>
#include <cmath>
#include <cstdio>

namespace pbrt {

namespace {
// Relative error bound of a reconstructed hit point (Embree's single-precision
// barycentrics and our interpolation), with a safety factor.
constexpr Float kPointErrorScale = 2e-6f;
}  // namespace

bool WithinRenderRange(const Point3f &p) {
    for (Float c : {p.x, p.y, p.z})
        if (!(std::abs(c) <= kMaxRenderCoordinate)) return false;  // also false for NaN
    return true;
}

namespace {
std::string PointString(const Point3f &p) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "(%g, %g, %g)", double(p.x), double(p.y), double(p.z));
    return buf;
}
}  // namespace

// --- Triangle meshes -------------------------------------------------------------------
Float TriangleMesh::Area(size_t tri) const {
    auto v = Vertices(tri);
    return 0.5f * Length(Cross(v[1] - v[0], v[2] - v[0]));
}

Bounds3f TriangleMesh::Bounds() const {
    Bounds3f b;
    for (const Point3f &q : p) b = Union(b, q);
    return b;
}

void TriangleMesh::PrecomputeFaceNormals() {
    faceNormals.clear();
    std::vector<Normal3f> normals(NumTriangles());
    for (size_t t = 0; t < normals.size(); ++t) normals[t] = ComputeGeometricNormal(t);
    faceNormals = std::move(normals);
}

Normal3f TriangleMesh::ComputeGeometricNormal(size_t tri) const {
    auto v = Vertices(tri);
    Vector3f c = Cross(v[0] - v[2], v[1] - v[2]);
    Float len = Length(c);
    Normal3f n = len > 0 ? c / len : Normal3f(0, 0, 1);
    if (reverseOrientation ^ transformSwapsHandedness) n = -n;
    return n;
}

void TriangleMesh::SurfacePoint(size_t tri, Float b1, Float b2, Point3f *pOut, Vector3f *pError,
                                Normal3f *nOut) const {
    // Every line as in Interaction below, so that both give the same numbers.
    uint32_t i0 = indices[3 * tri], i1 = indices[3 * tri + 1], i2 = indices[3 * tri + 2];
    const Point3f &p0 = p[i0], &p1 = p[i1], &p2 = p[i2];
    Float b0 = 1 - b1 - b2;
    *pOut = p0 * b0 + p1 * b1 + p2 * b2;
    Float m = MaxComponent(Abs(p0 * b0) + Abs(p1 * b1) + Abs(p2 * b2)) * kPointErrorScale;
    *pError = Vector3f(m, m, m);
    *nOut = GeometricNormal(tri);
    if (!n.empty()) {
        Normal3f ns = n[i0] * b0 + n[i1] * b1 + n[i2] * b2;
        if (LengthSquared(ns) > 0) *nOut = FaceForward(*nOut, Normalize(ns));
    }
}

void TriangleMesh::Interaction(size_t tri, Float b1, Float b2, SurfaceInteraction *si) const {
    uint32_t i0 = indices[3 * tri], i1 = indices[3 * tri + 1], i2 = indices[3 * tri + 2];
    const Point3f &p0 = p[i0], &p1 = p[i1], &p2 = p[i2];
    Float b0 = 1 - b1 - b2;
    si->p = p0 * b0 + p1 * b1 + p2 * b2;
    // Isotropic bound: Embree's float arithmetic mixes the coordinates, so a coordinate that
    // is exactly 0 on every vertex (an axis-aligned plane) still needs an offset.
    Float m = MaxComponent(Abs(p0 * b0) + Abs(p1 * b1) + Abs(p2 * b2)) * kPointErrorScale;
    si->pError = Vector3f(m, m, m);
    si->n = GeometricNormal(tri);

    // Texture coordinates (pbrt's defaults (0,0), (1,0), (1,1) when the mesh has none).
    Point2f uv0(0, 0), uv1(1, 0), uv2(1, 1);
    if (!uv.empty()) {
        uv0 = uv[i0];
        uv1 = uv[i1];
        uv2 = uv[i2];
    }
    si->uv = uv0 * b0 + uv1 * b1 + uv2 * b2;

    // dp/du from the uv parameterization; any tangent if it is degenerate.
    Vector2f duv02 = uv0 - uv2, duv12 = uv1 - uv2;
    Vector3f dp02 = p0 - p2, dp12 = p1 - p2;
    Float det = duv02.x * duv12.y - duv02.y * duv12.x;
    Vector3f dpdu, dpdv;
    if (std::abs(det) > 1e-9f) {
        dpdu = (dp02 * duv12.y - dp12 * duv02.y) / det;
        dpdv = (dp12 * duv02.x - dp02 * duv12.x) / det;
    }
    if (LengthSquared(Cross(dpdu, si->n)) == 0 || LengthSquared(Cross(dpdv, si->n)) == 0)
        CoordinateSystem(si->n, &dpdu, &dpdv);
    si->dpdu = dpdu;
    si->dpdv = dpdv;

    // Shading normal: interpolated N decides the side of the geometric normal.
    si->ns = si->n;
    if (!n.empty()) {
        Normal3f ns = n[i0] * b0 + n[i1] * b1 + n[i2] * b2;
        if (LengthSquared(ns) > 0) {
            si->ns = Normalize(ns);
            si->n = FaceForward(si->n, si->ns);
        }
    }
    si->faceIndex = faceIndices.empty() ? 0 : faceIndices[tri];
}

std::shared_ptr<TriangleMesh> MakeTriangleMesh(const Transform &renderFromObject,
                                               bool reverseOrientation,
                                               std::vector<std::array<Float, 3>> P,
                                               std::vector<int> indices,
                                               std::vector<std::array<Float, 3>> N,
                                               std::vector<std::array<Float, 2>> uv,
                                               std::vector<int> faceIndices,
                                               const FileLoc &loc) {
    if (P.empty()) throw PbrtError(loc, "triangle mesh has no vertices (\"P\")");
    if (indices.empty()) {
        if (P.size() == 3) indices = {0, 1, 2};
        else throw PbrtError(loc, "triangle mesh has no \"indices\" (needed unless there are exactly 3 vertices)");
    }
    if (indices.size() % 3 != 0)
        throw PbrtError(loc, "triangle mesh: the number of \"indices\" (" +
                                 std::to_string(indices.size()) + ") is not a multiple of 3");
    for (int i : indices)
        if (i < 0 || size_t(i) >= P.size())
            throw PbrtError(loc, "triangle mesh: vertex index " + std::to_string(i) +
                                     " is out of range [0, " + std::to_string(P.size()) + ")");
    if (!N.empty() && N.size() != P.size())
        throw PbrtError(loc, "triangle mesh: " + std::to_string(N.size()) + " normals \"N\" for " +
                                 std::to_string(P.size()) + " vertices");
    if (!uv.empty() && uv.size() != P.size())
        throw PbrtError(loc, "triangle mesh: " + std::to_string(uv.size()) + " \"uv\" for " +
                                 std::to_string(P.size()) + " vertices");
    if (!faceIndices.empty() && faceIndices.size() != indices.size() / 3)
        throw PbrtError(loc, "triangle mesh: \"faceIndices\" needs one value per triangle");

    auto mesh = std::make_shared<TriangleMesh>();
    mesh->reverseOrientation = reverseOrientation;
    mesh->transformSwapsHandedness = renderFromObject.SwapsHandedness();
    mesh->loc = loc;
    mesh->p.reserve(P.size());
    for (auto &q : P) {
        Point3f w = renderFromObject.ApplyPoint(Point3f(q[0], q[1], q[2]));
        if (!std::isfinite(w.x) || !std::isfinite(w.y) || !std::isfinite(w.z))
            throw PbrtError(loc, "triangle mesh has a vertex that is not finite");
        if (!WithinRenderRange(w))
            throw PbrtError(loc, "triangle mesh vertex " + std::to_string(mesh->p.size()) +
                                     " lies at " + PointString(w) +
                                     " after its transformation, beyond the +-1e12 the ray "
                                     "tracer can intersect (it would vanish from the image)");
        mesh->p.push_back(w);
    }
    for (auto &nn : N) {
        Normal3f w = renderFromObject.ApplyNormal(Normal3f(nn[0], nn[1], nn[2]));
        if (LengthSquared(w) > 0) w = Normalize(w);
        mesh->n.push_back(reverseOrientation ? -w : w);
    }
    for (auto &t : uv) mesh->uv.emplace_back(t[0], t[1]);
    mesh->indices.assign(indices.begin(), indices.end());
    mesh->faceIndices = std::move(faceIndices);
    return mesh;
}

// --- Spheres ------------------------------------------------------------------------------
Sphere::Sphere(const Transform &renderFromObject, bool reverseOrientation, Float radius,
               Float zmin, Float zmax, Float phiMaxDegrees)
    : renderFromObject(renderFromObject), objectFromRender(Inverse(renderFromObject)),
      radius(radius), reverseOrientation(reverseOrientation) {
    static std::atomic<uint32_t> nextId{1};
    id = nextId++;
    center = renderFromObject.ApplyPoint(Point3f(0, 0, 0));
    errorRadius = radius * Length(renderFromObject.ApplyVector(Vector3f(1, 0, 0)));
    zMin = Clamp(std::min(zmin, zmax), -radius, radius);
    zMax = Clamp(std::max(zmin, zmax), -radius, radius);
    thetaZMin = std::acos(Clamp(zMin / radius, -1, 1));
    thetaZMax = std::acos(Clamp(zMax / radius, -1, 1));
    phiMax = Radians(Clamp(phiMaxDegrees, 0, 360));
}

Bounds3f Sphere::ObjectBounds() const {
    return Bounds3f(Point3f(-radius, -radius, zMin), Point3f(radius, radius, zMax));
}

bool Sphere::IntersectObject(const Point3f &of, const Vector3f &df, Float tMax, Float *tHit) const {
    double ox = of.x, oy = of.y, oz = of.z, dx = df.x, dy = df.y, dz = df.z;
    double a = dx * dx + dy * dy + dz * dz;
    double b = 2 * (dx * ox + dy * oy + dz * oz);
    double c = ox * ox + oy * oy + oz * oz - double(radius) * radius;
    // Discriminant as 4a (r^2 - |o - (o.d/|d|^2) d|^2), which loses less precision.
    double proj = (dx * ox + dy * oy + dz * oz) / a;
    double fx = ox - proj * dx, fy = oy - proj * dy, fz = oz - proj * dz;
    double disc = 4 * a * (double(radius) * radius - (fx * fx + fy * fy + fz * fz));
    if (disc < 0) return false;
    double root = std::sqrt(disc);
    double q = (b < 0) ? -0.5 * (b - root) : -0.5 * (b + root);
    double t0 = q / a, t1 = c / q;
    if (t0 > t1) std::swap(t0, t1);
    for (double t : {t0, t1}) {
        if (!(t > 0) || !(t < tMax)) continue;
        double px = ox + t * dx, py = oy + t * dy, pz = oz + t * dz;
        if (!IsFull()) {
            double phi = std::atan2(py, px);
            if (phi < 0) phi += 2 * 3.14159265358979323846;
            if ((zMin > -radius && pz < zMin) || (zMax < radius && pz > zMax) || phi > phiMax)
                continue;
        }
        *tHit = Float(t);
        return true;
    }
    return false;
}

Point3f Sphere::SurfacePoint(const Point3f &pObjIn, Point3f *p, Vector3f *pError, Normal3f *n) const {
    // Project onto the surface (off the poles, where phi is undefined).
    Point3f pObj = pObjIn * (radius / Length(pObjIn));
    if (pObj.x == 0 && pObj.y == 0) pObj.x = 1e-5f * radius;
    *p = renderFromObject.ApplyPoint(pObj);
    *n = Normalize(renderFromObject.ApplyNormal(pObj));
    if (reverseOrientation) *n = -*n;
    Float rs = errorRadius;
    *pError = (Abs(*p) + Vector3f(rs, rs, rs)) * kPointErrorScale;
    return pObj;
}

void Sphere::Interaction(const Point3f &pObjIn, SurfaceInteraction *si) const {
    // The point, then (u, v) = (phi / phiMax, theta fraction) and the derivatives.
    Normal3f n;
    Point3f pObj = SurfacePoint(pObjIn, &si->p, &si->pError, &n);
    Float phi = std::atan2(pObj.y, pObj.x);
    if (phi < 0) phi += 2 * Pi;
    Float theta = SafeACos(pObj.z / radius);
    si->uv = Point2f(phi / phiMax, (theta - thetaZMin) / (thetaZMax - thetaZMin));
    si->n = si->ns = n;
    si->dpdu = renderFromObject.ApplyVector(Vector3f(-phiMax * pObj.y, phiMax * pObj.x, 0));
    // dp/dv = (thetaMax - thetaMin) (z cos(phi), z sin(phi), -r sin(theta)).
    Float zr = std::sqrt(Sqr(pObj.x) + Sqr(pObj.y));
    Float cosPhi = zr > 0 ? pObj.x / zr : 1, sinPhi = zr > 0 ? pObj.y / zr : 0;
    si->dpdv = renderFromObject.ApplyVector(
        (thetaZMax - thetaZMin) * Vector3f(pObj.z * cosPhi, pObj.z * sinPhi, -radius * std::sin(theta)));
    if (LengthSquared(Cross(si->dpdu, n)) == 0 || LengthSquared(Cross(si->dpdv, n)) == 0)
        CoordinateSystem(n, &si->dpdu, &si->dpdv);
    si->faceIndex = 0;
}

Float Sphere::SimilarityScale() const {
    Vector3f c[3] = {renderFromObject.ApplyVector({1, 0, 0}), renderFromObject.ApplyVector({0, 1, 0}),
                     renderFromObject.ApplyVector({0, 0, 1})};
    Float s = Length(c[0]);
    for (int i = 0; i < 3; ++i) {
        if (std::abs(Length(c[i]) - s) > 1e-4f * s) return 0;
        for (int j = i + 1; j < 3; ++j)
            if (std::abs(Dot(c[i], c[j])) > 1e-4f * s * s) return 0;
    }
    return s;
}

// --- Creation from a Shape directive ------------------------------------------------------
namespace {

// Bilinear patches (v00, v10, v01, v11) become two triangles each, with their own vertices
// so that patches without "uv" get their per-patch default parameterization.
std::shared_ptr<TriangleMesh> BilinearToTriangles(const ParameterDictionary &params,
                                                  const Transform &renderFromObject,
                                                  bool reverseOrientation, const FileLoc &loc) {
    auto P = params.GetPoint3Array("P");
    auto idx = params.GetIntArray("indices");
    auto N = params.GetNormal3Array("N");
    auto uv = params.GetPoint2Array("uv");
    auto faceIndices = params.GetIntArray("faceIndices");
    if (idx.empty() && P.size() == 4) idx = {0, 1, 2, 3};
    if (P.empty() || idx.empty() || idx.size() % 4 != 0)
        throw PbrtError(loc, "bilinearmesh needs \"P\" and \"indices\" (four per patch)");
    if ((!N.empty() && N.size() != P.size()) || (!uv.empty() && uv.size() != P.size()))
        throw PbrtError(loc, "bilinearmesh: \"N\" and \"uv\" need one value per vertex");
    for (int i : idx)
        if (i < 0 || size_t(i) >= P.size())
            throw PbrtError(loc, "bilinearmesh: vertex index " + std::to_string(i) + " out of range");
    std::vector<std::array<Float, 3>> P2, N2;
    std::vector<std::array<Float, 2>> uv2;
    std::vector<int> tri, face2;
    const std::array<Float, 2> defUV[4] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    bool warnedPlanar = false;
    for (size_t patch = 0; patch < idx.size() / 4; ++patch) {
        int base = int(P2.size());
        for (int k = 0; k < 4; ++k) {
            int v = idx[4 * patch + k];
            P2.push_back(P[v]);
            if (!N.empty()) N2.push_back(N[v]);
            uv2.push_back(uv.empty() ? defUV[k] : uv[v]);
        }
        // Patch corners: 0 = (0,0), 1 = (1,0), 2 = (0,1), 3 = (1,1).
        for (int k : {0, 1, 3, 0, 3, 2}) tri.push_back(base + k);
        if (!faceIndices.empty()) {
            face2.push_back(faceIndices[patch % faceIndices.size()]);
            face2.push_back(faceIndices[patch % faceIndices.size()]);
        }
        auto at = [&](int k) { return Point3f(P2[base + k][0], P2[base + k][1], P2[base + k][2]); };
        Vector3f nrm = Cross(at(1) - at(0), at(2) - at(0));
        Float off = std::abs(Dot(at(3) - at(0), nrm)) / std::max<Float>(Length(nrm), 1e-30f);
        if (!warnedPlanar && off > 1e-3f * Length(at(3) - at(0))) {
            Warning(loc, "bilinearmesh: non-planar patches are rendered as two triangles each");
            warnedPlanar = true;
        }
    }
    return MakeTriangleMesh(renderFromObject, reverseOrientation, P2, tri, N2, uv2, face2, loc);
}

}  // namespace

ShapeSet CreateShapes(const std::string &name, const ParameterDictionary &params,
                      const Transform &renderFromObject, bool reverseOrientation,
                      const FileLoc &loc) {
    ShapeSet set;
    // "alpha": only the constant 1 (opaque; the default) and 0 (invisible) are supported.
    if (const ParsedParameter *alpha = params.Find("alpha")) {
        if (alpha->type == "float" && alpha->floats.size() == 1 &&
            (alpha->floats[0] == 1 || alpha->floats[0] == 0)) {
            if (alpha->floats[0] == 0) return set;
        } else {
            throw PbrtError(alpha->loc, "shape \"alpha\" other than the constants 0 and 1 is not supported");
        }
    }
    if (name == "trianglemesh") {
        params.GetVector3Array("S");  // shading tangents: only matter for anisotropic BSDFs
        set.meshes.push_back(MakeTriangleMesh(
            renderFromObject, reverseOrientation, params.GetPoint3Array("P"),
            params.GetIntArray("indices"), params.GetNormal3Array("N"), params.GetPoint2Array("uv"),
            params.GetIntArray("faceIndices"), loc));
    } else if (name == "plymesh") {
        std::string filename = params.GetOneString("filename", "");
        if (filename.empty()) throw PbrtError(loc, "plymesh needs a \"filename\"");
        if (params.Find("displacement"))
            throw PbrtError(params.Loc("displacement"), "plymesh \"displacement\" is not supported");
        params.GetOneFloat("edgelength", 1);  // only used with displacement
        // PLY errors name the Shape statement too ("scene.pbrt:12:7: "mesh.ply": ...").
        PlyMesh ply;
        try {
            ply = ReadPly(ResolveFilename(filename, params.Loc("filename")));
        } catch (const PbrtError &e) {
            throw PbrtError(params.Loc("filename"), e.what());
        }
        set.meshes.push_back(MakeTriangleMesh(renderFromObject, reverseOrientation,
                                              std::move(ply.P), std::move(ply.indices),
                                              std::move(ply.N), std::move(ply.uv),
                                              std::move(ply.faceIndices), params.Loc("filename")));
    } else if (name == "bilinearmesh") {
        set.meshes.push_back(BilinearToTriangles(params, renderFromObject, reverseOrientation, loc));
    } else if (name == "sphere") {
        Float radius = params.GetOneFloat("radius", 1);
        if (!(radius > 0)) throw PbrtError(params.Loc("radius"), "sphere radius must be positive");
        Float zmin = params.GetOneFloat("zmin", -radius), zmax = params.GetOneFloat("zmax", radius);
        Float phimax = params.GetOneFloat("phimax", 360);
        Sphere s(renderFromObject, reverseOrientation, radius, zmin, zmax, phimax);
        if (!(s.zMax > s.zMin) || !(s.phiMax > 0))
            throw PbrtError(loc, "sphere: empty z or phi range");
        // The corners of its bounds in render space must be within the ray tracer's range.
        Bounds3f ob = s.ObjectBounds();
        for (int c = 0; c < 8; ++c) {
            Point3f w = renderFromObject.ApplyPoint(ob.Corner(c));
            if (!WithinRenderRange(w))
                throw PbrtError(loc, "sphere of radius " + std::to_string(radius) +
                                         " reaches " + PointString(w) +
                                         " after its transformation, beyond the +-1e12 the "
                                         "ray tracer can intersect (it would vanish from the "
                                         "image)");
        }
        s.loc = loc;
        set.spheres.push_back(s);
    } else {
        throw PbrtError(loc, "Shape \"" + name +
                                 "\" is not supported (supported: trianglemesh, plymesh, "
                                 "bilinearmesh, sphere)");
    }
    return set;
}

}  // namespace pbrt
