#include <pbrt/util/color.h>

#include <cctype>
#include <cmath>
#include <memory>
#include <sstream>

namespace pbrt {

// ---- RGB, XYZ ----------------------------------------------------------------------------

std::string RGB::ToString() const {
    std::ostringstream s;
    s << "(" << r << ", " << g << ", " << b << ")";
    return s.str();
}

Chromaticity XYZ::xy() const {
    Float sum = X + Y + Z;
    if (sum == 0) return {0, 0};
    return {X / sum, Y / sum};
}

XYZ XYZ::FromxyY(Chromaticity xy, Float Y) {
    if (xy.y == 0) return XYZ(0, 0, 0);
    return XYZ(xy.x * Y / xy.y, Y, (1 - xy.x - xy.y) * Y / xy.y);
}

std::string XYZ::ToString() const {
    std::ostringstream s;
    s << "[ X " << X << " Y " << Y << " Z " << Z << " ]";
    return s.str();
}

// ---- ColorMatrix3 ------------------------------------------------------------------------

ColorMatrix3 ColorMatrix3::Diagonal(double a, double b, double c) {
    ColorMatrix3 d;
    d.m[0][0] = a;
    d.m[1][1] = b;
    d.m[2][2] = c;
    return d;
}

ColorMatrix3 ColorMatrix3::operator*(const ColorMatrix3 &o) const {
    ColorMatrix3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j];
    return r;
}

std::optional<ColorMatrix3> ColorMatrix3::Inverse() const {
    // Adjugate divided by the determinant.
    ColorMatrix3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            r.m[i][j] = m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1];
        }
    double det = m[0][0] * r.m[0][0] + m[0][1] * r.m[1][0] + m[0][2] * r.m[2][0];
    double scale = 0;
    for (const auto &row : m)
        for (double v : row) scale = std::max(scale, std::abs(v));
    if (!std::isfinite(det) || std::abs(det) <= 1e-12 * scale * scale * scale) return {};
    for (auto &row : r.m)
        for (double &v : row) v /= det;
    return r;
}

void ColorMatrix3::Apply(double v0, double v1, double v2, double out[3]) const {
    for (int i = 0; i < 3; ++i) out[i] = m[i][0] * v0 + m[i][1] * v1 + m[i][2] * v2;
}

// ---- RGBToSpectrumTable ------------------------------------------------------------------

RGBSigmoidPolynomial RGBToSpectrumTable::operator()(RGB rgb) const {
    // Grey: a constant spectrum, sigmoid(c2) = value, i.e. c2 = (v - 1/2) / sqrt(v (1 - v))
    // (infinite for black and white, which the sigmoid maps to 0 and 1).
    if (rgb.r == rgb.g && rgb.g == rgb.b) {
        double v = rgb.r;
        return {0, 0, Float((v - 0.5) / std::sqrt(v * (1 - v)))};
    }
    // The largest component picks the table; z is its value, x and y the others over z.
    int l = (rgb.r > rgb.g) ? (rgb.r > rgb.b ? 0 : 2) : (rgb.g > rgb.b ? 1 : 2);
    Float z = rgb[l];
    Float x = rgb[(l + 1) % 3] * (kRes - 1) / z, y = rgb[(l + 2) % 3] * (kRes - 1) / z;

    // The cell and the position inside it; z nodes are uneven, x and y even.
    int zi = int(std::upper_bound(zNodes, zNodes + kRes, z) - zNodes) - 1;
    zi = std::clamp(zi, 0, kRes - 2);
    int xi = std::clamp(int(x), 0, kRes - 2), yi = std::clamp(int(y), 0, kRes - 2);
    Float dz = (z - zNodes[zi]) / (zNodes[zi + 1] - zNodes[zi]);
    Float dx = x - xi, dy = y - yi;

    // Trilinear interpolation of each coefficient.
    Float c[3];
    for (int i = 0; i < 3; ++i) {
        auto co = [&](int dzi, int dyi, int dxi) {
            return coeffs[CoeffIndex(l, zi + dzi, yi + dyi, xi + dxi) + i];
        };
        auto lerp = [](Float t, Float a, Float b) { return (1 - t) * a + t * b; };
        c[i] = lerp(dz,
                    lerp(dy, lerp(dx, co(0, 0, 0), co(0, 0, 1)), lerp(dx, co(0, 1, 0), co(0, 1, 1))),
                    lerp(dy, lerp(dx, co(1, 0, 0), co(1, 0, 1)), lerp(dx, co(1, 1, 0), co(1, 1, 1))));
    }
    return {c[0], c[1], c[2]};
}

// ---- RGBColorSpace -----------------------------------------------------------------------

RGBColorSpace::RGBColorSpace(std::string name, Chromaticity r, Chromaticity g, Chromaticity b,
                             SpectrumHandle illum, const RGBToSpectrumTable *table)
    : r(r), g(g), b(b), name(std::move(name)), table(table) {
    if (!illum) throw PbrtError("colour space \"" + this->name + "\" has no illuminant");
    illuminant = std::make_shared<DenselySampledSpectrum>(*illum);
    // The white point is the chromaticity of the illuminant.
    XYZ W = SpectrumToXYZ(*illuminant);
    w = W.xy();
    // Columns: the XYZ of each primary at Y = 1, then scaled so that RGB (1, 1, 1) is the
    // white with Y = 1.
    XYZ R = XYZ::FromxyY(r), G = XYZ::FromxyY(g), B = XYZ::FromxyY(b);
    ColorMatrix3 primaries;
    for (int i = 0; i < 3; ++i) {
        primaries.m[i][0] = R[i];
        primaries.m[i][1] = G[i];
        primaries.m[i][2] = B[i];
    }
    std::optional<ColorMatrix3> inv = primaries.Inverse();
    if (!inv) throw PbrtError("colour space \"" + this->name + "\": degenerate primaries");
    XYZ white = XYZ::FromxyY(w, 1);
    double C[3];
    inv->Apply(white.X, white.Y, white.Z, C);
    XYZFromRGB = primaries * ColorMatrix3::Diagonal(C[0], C[1], C[2]);
    std::optional<ColorMatrix3> back = XYZFromRGB.Inverse();
    if (!back) throw PbrtError("colour space \"" + this->name + "\": singular RGB-to-XYZ matrix");
    RGBFromXYZ = *back;
}

RGB RGBColorSpace::ToRGB(const XYZ &xyz) const {
    double out[3];
    RGBFromXYZ.Apply(xyz.X, xyz.Y, xyz.Z, out);
    return RGB(Float(out[0]), Float(out[1]), Float(out[2]));
}

XYZ RGBColorSpace::ToXYZ(const RGB &rgb) const {
    double out[3];
    XYZFromRGB.Apply(rgb.r, rgb.g, rgb.b, out);
    return XYZ(Float(out[0]), Float(out[1]), Float(out[2]));
}

RGBSigmoidPolynomial RGBColorSpace::ToRGBCoeffs(const RGB &rgb) const {
    if (!table)
        throw PbrtError("colour space \"" + name + "\" has no RGB-to-spectrum table");
    for (int c = 0; c < 3; ++c)
        if (!(rgb[c] >= 0 && rgb[c] <= 1))
            throw PbrtError("RGB " + rgb.ToString() + " outside [0, 1] in the spectrum table lookup");
    return (*table)(rgb);
}

namespace {
struct NamedSpace {
    const char *name;
    Chromaticity r, g, b;
    const char *illuminant;
    const RGBToSpectrumTable *(*table)();
};

// pbrt-v4's named colour spaces.
const NamedSpace kNamedSpaces[] = {
    // IEC 61966-2-1 (ITU-R BT.709 primaries), D65.
    {"srgb", {0.64f, 0.33f}, {0.30f, 0.60f}, {0.15f, 0.06f}, "stdillum-D65", RGBToSpectrumTable_srgb},
    // SMPTE RP 431-2 (DCI-P3) primaries with the D65 white, as pbrt-v4 defines "dci-p3".
    {"dci-p3", {0.680f, 0.320f}, {0.265f, 0.690f}, {0.150f, 0.060f}, "stdillum-D65",
     RGBToSpectrumTable_dci_p3},
    // ITU-R BT.2020, D65.
    {"rec2020", {0.708f, 0.292f}, {0.170f, 0.797f}, {0.131f, 0.046f}, "stdillum-D65",
     RGBToSpectrumTable_rec2020},
    // SMPTE ST 2065-1 (ACES AP0 primaries), ACES white.
    {"aces2065-1", {0.7347f, 0.2653f}, {0.0f, 1.0f}, {0.0001f, -0.0770f}, "illum-acesD60",
     RGBToSpectrumTable_aces2065_1},
};
constexpr int kNumNamedSpaces = sizeof(kNamedSpaces) / sizeof(kNamedSpaces[0]);

const std::vector<std::unique_ptr<RGBColorSpace>> &NamedSpaces() {
    static const std::vector<std::unique_ptr<RGBColorSpace>> spaces = [] {
        std::vector<std::unique_ptr<RGBColorSpace>> v;
        for (const NamedSpace &s : kNamedSpaces)
            v.push_back(std::make_unique<RGBColorSpace>(s.name, s.r, s.g, s.b,
                                                        GetNamedSpectrum(s.illuminant), s.table()));
        return v;
    }();
    return spaces;
}
}  // namespace

const RGBColorSpace *RGBColorSpace::GetNamed(const std::string &n) {
    std::string lower;
    for (char c : n) lower += char(std::tolower((unsigned char)c));
    const auto &spaces = NamedSpaces();
    for (int i = 0; i < kNumNamedSpaces; ++i)
        if (lower == kNamedSpaces[i].name) return spaces[i].get();
    return nullptr;
}

std::vector<std::string> RGBColorSpace::Names() {
    std::vector<std::string> names;
    for (const NamedSpace &s : kNamedSpaces) names.push_back(s.name);
    return names;
}

const RGBColorSpace *RGBColorSpace::sRGB = RGBColorSpace::GetNamed("srgb");
const RGBColorSpace *RGBColorSpace::DCI_P3 = RGBColorSpace::GetNamed("dci-p3");
const RGBColorSpace *RGBColorSpace::Rec2020 = RGBColorSpace::GetNamed("rec2020");
const RGBColorSpace *RGBColorSpace::ACES2065_1 = RGBColorSpace::GetNamed("aces2065-1");

ColorMatrix3 ConvertRGBColorSpace(const RGBColorSpace &from, const RGBColorSpace &to) {
    return to.RGBFromXYZ * from.XYZFromRGB;
}

}  // namespace pbrt
