// 4x4 homogeneous transforms with their inverses, following pbrt's conventions:
// matrices act on column vectors (p' = M p), the scene file's "Transform"/"ConcatTransform"
// arrays list the matrix column by column (the translation is in elements 12..14), and
// each directive post-multiplies the current transform (CTM = CTM * T).
#pragma once

#include <pbrt/ray.h>
#include <pbrt/util/vecmath.h>

#include <string>

namespace pbrt {

struct SquareMatrix4 {
    Float m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    SquareMatrix4() = default;
    // Row-major values: m[row][col] = v[row * 4 + col].
    static SquareMatrix4 FromRowMajor(const Float v[16]);
    bool IsIdentity() const;
    bool operator==(const SquareMatrix4 &o) const;
    SquareMatrix4 operator*(const SquareMatrix4 &o) const;
    SquareMatrix4 Transposed() const;
    // The inverse, or false when the matrix is singular.
    bool Inverse(SquareMatrix4 *inv) const;
    double Determinant3x3() const;
};

class Transform {
  public:
    Transform() = default;
    // Throws PbrtError when m is singular.
    explicit Transform(const SquareMatrix4 &m);
    Transform(const SquareMatrix4 &m, const SquareMatrix4 &mInv) : m(m), mInv(mInv) {}

    const SquareMatrix4 &Matrix() const { return m; }
    const SquareMatrix4 &InverseMatrix() const { return mInv; }
    bool IsIdentity() const { return m.IsIdentity(); }
    bool operator==(const Transform &o) const { return m == o.m; }
    bool operator!=(const Transform &o) const { return !(m == o.m); }
    Transform operator*(const Transform &o) const { return Transform(m * o.m, o.mInv * mInv); }
    friend Transform Inverse(const Transform &t) { return Transform(t.mInv, t.m); }

    // A transform with a negative-determinant upper 3x3 turns right-handed frames into
    // left-handed ones (and flips the orientation of cross products).
    bool SwapsHandedness() const { return m.Determinant3x3() < 0; }

    Point3f ApplyPoint(const Point3f &p) const {
        Float x = m.m[0][0] * p.x + m.m[0][1] * p.y + m.m[0][2] * p.z + m.m[0][3];
        Float y = m.m[1][0] * p.x + m.m[1][1] * p.y + m.m[1][2] * p.z + m.m[1][3];
        Float z = m.m[2][0] * p.x + m.m[2][1] * p.y + m.m[2][2] * p.z + m.m[2][3];
        Float w = m.m[3][0] * p.x + m.m[3][1] * p.y + m.m[3][2] * p.z + m.m[3][3];
        return w == 1 ? Point3f(x, y, z) : Point3f(x, y, z) / w;
    }
    Vector3f ApplyVector(const Vector3f &v) const {
        return {m.m[0][0] * v.x + m.m[0][1] * v.y + m.m[0][2] * v.z,
                m.m[1][0] * v.x + m.m[1][1] * v.y + m.m[1][2] * v.z,
                m.m[2][0] * v.x + m.m[2][1] * v.y + m.m[2][2] * v.z};
    }
    // Normals transform with the inverse transpose (not normalized here).
    Normal3f ApplyNormal(const Normal3f &n) const {
        return {mInv.m[0][0] * n.x + mInv.m[1][0] * n.y + mInv.m[2][0] * n.z,
                mInv.m[0][1] * n.x + mInv.m[1][1] * n.y + mInv.m[2][1] * n.z,
                mInv.m[0][2] * n.x + mInv.m[1][2] * n.y + mInv.m[2][2] * n.z};
    }
    Ray ApplyRay(const Ray &r) const { return Ray(ApplyPoint(r.o), ApplyVector(r.d), r.tMax); }
    Bounds3f ApplyBounds(const Bounds3f &b) const;

    std::string ToString() const;

  private:
    SquareMatrix4 m, mInv;
};

// The pbrt scene-file matrix: 16 values, column by column (pbrt's "Transform" directive).
Transform TransformFromColumnMajor(const Float v[16]);
Transform Translate(const Vector3f &delta);
Transform Scale(Float x, Float y, Float z);
// Rotation by theta degrees about axis (right-hand rule in a right-handed frame).
Transform Rotate(Float thetaDegrees, const Vector3f &axis);
// pbrt's LookAt: the camera-from-world transform of a camera at pos looking at look with
// the given up vector; camera space has +z forward, +y up and +x = Cross(up, forward).
// Throws PbrtError when up is parallel to the viewing direction or pos == look.
Transform LookAt(const Point3f &pos, const Point3f &look, const Vector3f &up);

}  // namespace pbrt
