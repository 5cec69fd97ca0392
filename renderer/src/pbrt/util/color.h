// Colour: RGB and XYZ triples, RGB colour spaces (primaries + illuminant, pbrt-v4's
// construction, PBR book 4th ed. section 4.6.3), and the RGB-to-spectrum lookup table of
// Jakob and Hanika 2019 ("A Low-Dimensional Function Space for Efficient Spectral
// Upsampling", Computer Graphics Forum 38(2)) that the RGB spectra in spectrum.h use.
// The tables are computed at build time by src/tools/rgb2spec_opt.cpp (cmake/rgb2spec.cmake).
#pragma once

#include <pbrt/pbrt.h>
#include <pbrt/util/spectrum.h>

#include <algorithm>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace pbrt {

// A linear RGB triple in some colour space.
struct RGB {
    Float r = 0, g = 0, b = 0;
    RGB() = default;
    RGB(Float r, Float g, Float b) : r(r), g(g), b(b) {}

    Float operator[](int c) const { return c == 0 ? r : (c == 1 ? g : b); }
    Float &operator[](int c) { return c == 0 ? r : (c == 1 ? g : b); }

    RGB &operator+=(const RGB &o) { r += o.r; g += o.g; b += o.b; return *this; }
    RGB &operator-=(const RGB &o) { r -= o.r; g -= o.g; b -= o.b; return *this; }
    RGB &operator*=(const RGB &o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
    RGB &operator/=(const RGB &o) { r /= o.r; g /= o.g; b /= o.b; return *this; }
    RGB &operator*=(Float a) { r *= a; g *= a; b *= a; return *this; }
    RGB &operator/=(Float a) { r /= a; g /= a; b /= a; return *this; }
    RGB operator+(const RGB &o) const { RGB t = *this; return t += o; }
    RGB operator-(const RGB &o) const { RGB t = *this; return t -= o; }
    RGB operator*(const RGB &o) const { RGB t = *this; return t *= o; }
    RGB operator/(const RGB &o) const { RGB t = *this; return t /= o; }
    RGB operator*(Float a) const { RGB t = *this; return t *= a; }
    RGB operator/(Float a) const { RGB t = *this; return t /= a; }
    RGB operator-() const { return RGB(-r, -g, -b); }
    bool operator==(const RGB &o) const { return r == o.r && g == o.g && b == o.b; }
    bool operator!=(const RGB &o) const { return !(*this == o); }

    Float Average() const { return (r + g + b) / 3; }
    Float MaxComponentValue() const { return std::max({r, g, b}); }
    Float MinComponentValue() const { return std::min({r, g, b}); }
    std::string ToString() const;
};
inline RGB operator*(Float a, const RGB &c) { return c * a; }
inline RGB ClampZero(const RGB &c) {
    return RGB(std::max<Float>(0, c.r), std::max<Float>(0, c.g), std::max<Float>(0, c.b));
}

// A CIE 1931 chromaticity (x, y).
struct Chromaticity {
    Float x = 0, y = 0;
};

// CIE 1931 tristimulus values.
struct XYZ {
    Float X = 0, Y = 0, Z = 0;
    XYZ() = default;
    XYZ(Float X, Float Y, Float Z) : X(X), Y(Y), Z(Z) {}

    Float operator[](int c) const { return c == 0 ? X : (c == 1 ? Y : Z); }
    XYZ operator+(const XYZ &o) const { return XYZ(X + o.X, Y + o.Y, Z + o.Z); }
    XYZ operator*(Float a) const { return XYZ(a * X, a * Y, a * Z); }
    XYZ operator/(Float a) const { return XYZ(X / a, Y / a, Z / a); }

    // Chromaticity x = X / (X + Y + Z), y = Y / (X + Y + Z); (0, 0) for black.
    Chromaticity xy() const;
    // The XYZ with chromaticity xy and luminance Y.
    static XYZ FromxyY(Chromaticity xy, Float Y = 1);
    std::string ToString() const;
};

// A 3x3 matrix for colour conversions, kept in double precision.
struct ColorMatrix3 {
    double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

    static ColorMatrix3 Diagonal(double a, double b, double c);
    ColorMatrix3 operator*(const ColorMatrix3 &o) const;
    // Inverse, or nothing when (nearly) singular.
    std::optional<ColorMatrix3> Inverse() const;
    // Matrix times the column vector (v0, v1, v2).
    void Apply(double v0, double v1, double v2, double out[3]) const;
};

// The sigmoid-polynomial coefficients for RGBs in [0, 1]^3 of one colour space, tabulated
// as Jakob and Hanika 2019 (and pbrt-v4) lay them out: for the index l of the largest
// component, its value z = rgb[l] and the ratios x = rgb[(l+1)%3] / z, y = rgb[(l+2)%3] / z,
// a kRes^3 grid over (z, y, x); z sits on nodes zNode(k) = smoothstep(smoothstep(k/(kRes-1)))
// that crowd near black and white. Lookups interpolate the coefficients trilinearly.
class RGBToSpectrumTable {
  public:
    static constexpr int kRes = 64;
    static constexpr std::size_t kNumCoefficients = std::size_t(3) * kRes * kRes * kRes * 3;

    // zNodes: kRes values; coeffs: kNumCoefficients values laid out by CoeffIndex.
    RGBToSpectrumTable(const float *zNodes, const float *coeffs) : zNodes(zNodes), coeffs(coeffs) {}

    // rgb must lie in [0, 1]^3.
    RGBSigmoidPolynomial operator()(RGB rgb) const;

    static double ZNode(int k) {
        auto smoothstep = [](double x) { return x * x * (3 - 2 * x); };
        return smoothstep(smoothstep(double(k) / (kRes - 1)));
    }
    // Offset of the three coefficients (c0, c1, c2) of grid point (l, zi, yi, xi).
    static std::size_t CoeffIndex(int l, int zi, int yi, int xi) {
        return 3 * (((std::size_t(l) * kRes + zi) * kRes + yi) * kRes + xi);
    }

  private:
    const float *zNodes, *coeffs;
};

// An RGB colour space: primaries and a white illuminant. As in pbrt-v4, the white point is
// the chromaticity of the illuminant spectrum (not a rounded nominal value) and RGB (1,1,1)
// maps to that white with Y = 1.
class RGBColorSpace {
  public:
    // table may be null (then RGB spectra cannot be made in this space).
    RGBColorSpace(std::string name, Chromaticity r, Chromaticity g, Chromaticity b,
                  SpectrumHandle illuminant, const RGBToSpectrumTable *table);

    RGB ToRGB(const XYZ &xyz) const;
    XYZ ToXYZ(const RGB &rgb) const;
    Float Luminance(const RGB &rgb) const { return ToXYZ(rgb).Y; }
    // Sigmoid-polynomial coefficients of an RGB in [0, 1]^3 (table lookup).
    RGBSigmoidPolynomial ToRGBCoeffs(const RGB &rgb) const;
    bool HasSpectrumTable() const { return table != nullptr; }

    // The illuminant, normalized to luminance 1 and densely sampled.
    const Spectrum &Illuminant() const { return *illuminant; }
    const SpectrumHandle &IlluminantHandle() const { return illuminant; }
    const std::string &Name() const { return name; }
    Chromaticity r, g, b, w;
    ColorMatrix3 XYZFromRGB, RGBFromXYZ;

    // pbrt-v4's named colour spaces (primaries: IEC 61966-2-1 / ITU-R BT.709; DCI-P3 primaries
    // with the D65 white, as pbrt-v4 defines "dci-p3"; ITU-R BT.2020; SMPTE ST 2065-1 with the
    // ACES white).
    static const RGBColorSpace *sRGB, *DCI_P3, *Rec2020, *ACES2065_1;
    // "srgb", "dci-p3", "rec2020", "aces2065-1" (case-insensitive); nullptr if unknown.
    static const RGBColorSpace *GetNamed(const std::string &name);
    static std::vector<std::string> Names();

  private:
    std::string name;
    SpectrumHandle illuminant;
    const RGBToSpectrumTable *table;
};

// The matrix taking RGB in `from` to RGB in `to` (through XYZ; no chromatic adaptation).
ColorMatrix3 ConvertRGBColorSpace(const RGBColorSpace &from, const RGBColorSpace &to);

// The coefficient tables, defined in the files cmake/rgb2spec.cmake generates at build time
// (${CMAKE_BINARY_DIR}/rgbspectrum_<space>.cpp); the generator itself defines them as null.
const RGBToSpectrumTable *RGBToSpectrumTable_srgb();
const RGBToSpectrumTable *RGBToSpectrumTable_dci_p3();
const RGBToSpectrumTable *RGBToSpectrumTable_rec2020();
const RGBToSpectrumTable *RGBToSpectrumTable_aces2065_1();

}  // namespace pbrt
