#include <pbrt/util/transform.h>

#include <cmath>
#include <cstdio>

namespace pbrt {

SquareMatrix4 SquareMatrix4::FromRowMajor(const Float v[16]) {
    SquareMatrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = v[i * 4 + j];
    return r;
}

bool SquareMatrix4::IsIdentity() const {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (m[i][j] != (i == j ? 1 : 0)) return false;
    return true;
}

bool SquareMatrix4::operator==(const SquareMatrix4 &o) const {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (m[i][j] != o.m[i][j]) return false;
    return true;
}

SquareMatrix4 SquareMatrix4::operator*(const SquareMatrix4 &o) const {
    SquareMatrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += double(m[i][k]) * o.m[k][j];
            r.m[i][j] = Float(s);
        }
    return r;
}

SquareMatrix4 SquareMatrix4::Transposed() const {
    SquareMatrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
    return r;
}

double SquareMatrix4::Determinant3x3() const {
    return double(m[0][0]) * (double(m[1][1]) * m[2][2] - double(m[1][2]) * m[2][1]) -
           double(m[0][1]) * (double(m[1][0]) * m[2][2] - double(m[1][2]) * m[2][0]) +
           double(m[0][2]) * (double(m[1][0]) * m[2][1] - double(m[1][1]) * m[2][0]);
}

bool SquareMatrix4::Inverse(SquareMatrix4 *inv) const {
    // Gauss-Jordan elimination with partial pivoting, in double.
    double a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            a[i][j] = m[i][j];
            a[i][j + 4] = (i == j) ? 1 : 0;
        }
    for (int col = 0; col < 4; ++col) {
        int pivot = col;
        for (int r = col + 1; r < 4; ++r)
            if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
        if (a[pivot][col] == 0 || !std::isfinite(a[pivot][col])) return false;
        if (pivot != col)
            for (int j = 0; j < 8; ++j) std::swap(a[pivot][j], a[col][j]);
        double s = 1 / a[col][col];
        for (int j = 0; j < 8; ++j) a[col][j] *= s;
        for (int r = 0; r < 4; ++r) {
            if (r == col || a[r][col] == 0) continue;
            double f = a[r][col];
            for (int j = 0; j < 8; ++j) a[r][j] -= f * a[col][j];
        }
    }
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) inv->m[i][j] = Float(a[i][j + 4]);
    return true;
}

Transform::Transform(const SquareMatrix4 &m) : m(m) {
    if (!m.Inverse(&mInv)) throw PbrtError("singular transformation matrix " + ToString());
}

Bounds3f Transform::ApplyBounds(const Bounds3f &b) const {
    Bounds3f r;
    if (b.IsEmpty()) return r;
    for (int c = 0; c < 8; ++c) {
        Point3f p((c & 1) ? b.pMax.x : b.pMin.x, (c & 2) ? b.pMax.y : b.pMin.y,
                  (c & 4) ? b.pMax.z : b.pMin.z);
        r = Union(r, ApplyPoint(p));
    }
    return r;
}

std::string Transform::ToString() const {
    std::string s = "[";
    char buf[64];
    for (int i = 0; i < 4; ++i) {
        s += (i ? " [" : "[");
        for (int j = 0; j < 4; ++j) {
            std::snprintf(buf, sizeof(buf), j ? " %g" : "%g", m.m[i][j]);
            s += buf;
        }
        s += "]";
    }
    return s + "]";
}

Transform TransformFromColumnMajor(const Float v[16]) {
    // The file lists columns; our matrix is indexed [row][col].
    return Transform(SquareMatrix4::FromRowMajor(v).Transposed());
}

Transform Translate(const Vector3f &d) {
    SquareMatrix4 m, mInv;
    m.m[0][3] = d.x; m.m[1][3] = d.y; m.m[2][3] = d.z;
    mInv.m[0][3] = -d.x; mInv.m[1][3] = -d.y; mInv.m[2][3] = -d.z;
    return Transform(m, mInv);
}

Transform Scale(Float x, Float y, Float z) {
    if (x == 0 || y == 0 || z == 0)
        throw PbrtError("Scale with a zero factor makes the transformation singular");
    SquareMatrix4 m, mInv;
    m.m[0][0] = x; m.m[1][1] = y; m.m[2][2] = z;
    mInv.m[0][0] = 1 / x; mInv.m[1][1] = 1 / y; mInv.m[2][2] = 1 / z;
    return Transform(m, mInv);
}

Transform Rotate(Float thetaDegrees, const Vector3f &axis) {
    if (LengthSquared(axis) == 0) throw PbrtError("Rotate about a zero-length axis");
    Vector3f a = Normalize(axis);
    double theta = double(thetaDegrees) * 3.14159265358979323846 / 180;
    double s = std::sin(theta), c = std::cos(theta);
    // Rodrigues' rotation formula: R = c I + s [a]_x + (1 - c) a a^T.
    SquareMatrix4 m;
    m.m[0][0] = Float(a.x * a.x + (1 - a.x * a.x) * c);
    m.m[0][1] = Float(a.x * a.y * (1 - c) - a.z * s);
    m.m[0][2] = Float(a.x * a.z * (1 - c) + a.y * s);
    m.m[1][0] = Float(a.x * a.y * (1 - c) + a.z * s);
    m.m[1][1] = Float(a.y * a.y + (1 - a.y * a.y) * c);
    m.m[1][2] = Float(a.y * a.z * (1 - c) - a.x * s);
    m.m[2][0] = Float(a.x * a.z * (1 - c) - a.y * s);
    m.m[2][1] = Float(a.y * a.z * (1 - c) + a.x * s);
    m.m[2][2] = Float(a.z * a.z + (1 - a.z * a.z) * c);
    // A rotation's inverse is its transpose.
    return Transform(m, m.Transposed());
}

Transform LookAt(const Point3f &pos, const Point3f &look, const Vector3f &up) {
    if (LengthSquared(look - pos) == 0)
        throw PbrtError("LookAt: the eye and the look-at point coincide");
    if (LengthSquared(up) == 0) throw PbrtError("LookAt: zero-length up vector");
    Vector3f dir = Normalize(look - pos);
    Vector3f upn = Normalize(up);
    if (Length(Cross(upn, dir)) < 1e-6f)
        throw PbrtError("LookAt: the up vector is parallel to the viewing direction");
    Vector3f right = Normalize(Cross(upn, dir));
    Vector3f newUp = Cross(dir, right);
    // worldFromCamera has columns right, newUp, dir and pos; LookAt returns its inverse.
    SquareMatrix4 worldFromCamera;
    for (int i = 0; i < 3; ++i) {
        worldFromCamera.m[i][0] = right[i];
        worldFromCamera.m[i][1] = newUp[i];
        worldFromCamera.m[i][2] = dir[i];
        worldFromCamera.m[i][3] = pos[i];
    }
    SquareMatrix4 cameraFromWorld;
    if (!worldFromCamera.Inverse(&cameraFromWorld))
        throw PbrtError("LookAt: degenerate viewing frame");
    return Transform(cameraFromWorld, worldFromCamera);
}

}  // namespace pbrt
