#include <pbrt/bumpmap.h>

namespace pbrt {

BumpedFrame BumpMap(const FloatTexture &displacement, const SurfaceInteraction &si) {
    const Normal3f n = si.ns;
    // The shading tangents: the parametric ones on flat-shaded surfaces; with interpolated
    // normals, unit tangents orthogonal to the shading normal (pbrt-v4's triangle shading
    // geometry: ss = dp/du projected, ts = n x ss).
    Vector3f ss = si.dpdu, ts = si.dpdv;
    if (Dot(si.n, si.ns) < 1 - 1e-6f || LengthSquared(ts) == 0) {
        ss = si.dpdu - n * Dot(si.dpdu, n);
        if (LengthSquared(ss) == 0) {
            CoordinateSystem(Vector3f(n), &ss, &ts);
        } else {
            ss = Normalize(ss);
            ts = Cross(Vector3f(n), ss);
        }
    }

    // Forward differences of the displacement along u and v.
    const Float du = kBumpDelta, dv = kBumpDelta;
    TextureEvalContext ctx{si.p, si.uv};
    Float d0 = displacement.Evaluate(ctx);
    TextureEvalContext cu{si.p + du * ss, Point2f(si.uv.x + du, si.uv.y)};
    TextureEvalContext cv{si.p + dv * ts, Point2f(si.uv.x, si.uv.y + dv)};
    Float dU = displacement.Evaluate(cu), dV = displacement.Evaluate(cv);

    Vector3f dpdu = ss + (dU - d0) / du * Vector3f(n);
    Vector3f dpdv = ts + (dV - d0) / dv * Vector3f(n);
    Vector3f c = Cross(dpdu, dpdv);
    if (!(LengthSquared(c) > 0) || c.HasNaN()) return {si.ns, si.dpdu};
    Normal3f nb = Normalize(Normal3f(c));
    // The side of the geometric normal (pbrt-v4: the bumped normal is not authoritative).
    nb = FaceForward(nb, si.n);
    return {nb, dpdu};
}

}  // namespace pbrt
