#include <pbrt/util/spectrum.h>

#if defined(PBRT_HAS_LIBMVEC) && defined(__AVX2__) && defined(__x86_64__)
#define PBRT_VECTOR_LOG
#include <immintrin.h>
// glibc's libmvec: log of four doubles (the AVX2 variant, in the x86-64 vector ABI's name).
extern "C" __m256d _ZGVdN4v_log(__m256d);
#endif

#include <pbrt/util/cie_data.h>
#include <pbrt/util/file.h>
#include <pbrt/util/color.h>
#include <pbrt/util/wavelength_densities.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sstream>

namespace pbrt {

namespace {

std::string FormatFloat(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// pbrt-v4's InnerProduct (a sum at every nanometre over 360..830), accumulated in double.
double InnerProductDouble(const Spectrum &f, const Spectrum &g) {
    double sum = 0;
    for (int lambda = int(Lambda_min); lambda <= int(Lambda_max); ++lambda)
        sum += double(f(Float(lambda))) * double(g(Float(lambda)));
    return sum;
}

// A PbrtError prefixed with the location, when there is one.
PbrtError SpectrumError(const FileLoc *loc, const std::string &msg) {
    return loc ? PbrtError(*loc, msg) : PbrtError(msg);
}

}  // namespace

// ---- SampledSpectrum ---------------------------------------------------------------------

Float SampledSpectrum::y(const SampledWavelengths &lambda) const {
    SampledSpectrum ys = Spectra::Y().Sample(lambda);
    return SafeDiv(ys * *this, lambda.PDF()).Average() / CIE_Y_integral;
}

XYZ SampledSpectrum::ToXYZ(const SampledWavelengths &lambda) const {
    SampledSpectrum pdf = lambda.PDF();
    auto component = [&](const DenselySampledSpectrum &cmf) {
        return SafeDiv(cmf.Sample(lambda) * *this, pdf).Average() / CIE_Y_integral;
    };
    return XYZ(component(Spectra::X()), component(Spectra::Y()), component(Spectra::Z()));
}

SampledSpectrum SafeDiv(const SampledSpectrum &a, const SampledSpectrum &b) {
    SampledSpectrum r;
    for (int i = 0; i < NSpectrumSamples; ++i) r[i] = b[i] != 0 ? a[i] / b[i] : 0;
    return r;
}

SampledSpectrum Sqrt(const SampledSpectrum &s) {
    SampledSpectrum r;
    for (int i = 0; i < NSpectrumSamples; ++i) r[i] = std::sqrt(s[i]);
    return r;
}

SampledSpectrum Exp(const SampledSpectrum &s) {
    SampledSpectrum r;
    for (int i = 0; i < NSpectrumSamples; ++i) r[i] = std::exp(s[i]);
    return r;
}

SampledSpectrum Pow(const SampledSpectrum &s, Float e) {
    SampledSpectrum r;
    for (int i = 0; i < NSpectrumSamples; ++i) r[i] = std::pow(s[i], e);
    return r;
}

SampledSpectrum Clamp(const SampledSpectrum &s, Float low, Float high) {
    SampledSpectrum r;
    for (int i = 0; i < NSpectrumSamples; ++i) r[i] = std::clamp(s[i], low, high);
    return r;
}

SampledSpectrum ClampZero(const SampledSpectrum &s) {
    SampledSpectrum r;
    for (int i = 0; i < NSpectrumSamples; ++i) r[i] = std::max<Float>(0, s[i]);
    return r;
}

SampledSpectrum Lerp(Float t, const SampledSpectrum &a, const SampledSpectrum &b) {
    return (1 - t) * a + t * b;
}

// ---- SampledWavelengths ------------------------------------------------------------------

namespace {
// (u + i / n) mod 1 for the stratified wavelengths of one path.
Float StratumOffset(Float u, int i) {
    Float up = u + Float(i) / NSpectrumSamples;
    if (up >= 1) up -= 1;
    return up;
}
}  // namespace

SampledWavelengths SampledWavelengths::SampleVisible(Float u) {
    SampledWavelengths w;
    double ratio[NSpectrumSamples];
    for (int i = 0; i < NSpectrumSamples; ++i) {
        double t = VisibleWavelengthsTanh(StratumOffset(u, i));
        ratio[i] = VisibleWavelengthsAtanhRatio(t);
        // VisibleWavelengthsPDF(lambda) without its cosh: sech^2(A (lambda - C)) = 1 - t^2
        // with t = tanh(A (lambda - C)), the value the sampler inverted. The same density up
        // to the float rounding of lambda (relative 1e-6 at most).
        w.pdf[i] = VisibleWavelengthsPDFFromTanh(t);
    }
    // The four logarithms of SampleVisibleWavelengths in one call of glibc's vector maths
    // library where there is one (within its 4 ulp of libm's: the same floats but for
    // rare last-bit roundings), one by one elsewhere.
#ifdef PBRT_VECTOR_LOG
    static_assert(NSpectrumSamples == 4, "one AVX2 register of doubles");
    double logs[NSpectrumSamples];
    _mm256_storeu_pd(logs, _ZGVdN4v_log(_mm256_loadu_pd(ratio)));
    for (int i = 0; i < NSpectrumSamples; ++i) w.lambda[i] = VisibleWavelengthFromLogRatio(logs[i]);
#else
    for (int i = 0; i < NSpectrumSamples; ++i) w.lambda[i] = VisibleWavelengthFromLogRatio(std::log(ratio[i]));
#endif
    return w;
}

SampledWavelengths SampledWavelengths::SampleUniform(Float u, Float lmin, Float lmax) {
    if (!(std::isfinite(lmin) && std::isfinite(lmax) && lmin > 0 && lmin < lmax))
        throw PbrtError("uniform wavelength sampling needs 0 < min < max, got [" +
                        FormatFloat(lmin) + ", " + FormatFloat(lmax) + "] nm");
    SampledWavelengths w;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        w.lambda[i] = SampleUniformWavelengths(StratumOffset(u, i), lmin, lmax);
        w.pdf[i] = 1 / (lmax - lmin);
    }
    return w;
}

SampledWavelengths SampledWavelengths::FromArrays(const Float lambda[NSpectrumSamples],
                                                  const Float pdf[NSpectrumSamples]) {
    SampledWavelengths w;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        w.lambda[i] = lambda[i];
        w.pdf[i] = pdf[i];
    }
    return w;
}

void SampledWavelengths::TerminateSecondary(Float u) {
    if (terminated) return;
    int k = std::clamp(int(u * NSpectrumSamples), 0, NSpectrumSamples - 1);
    // The kept wavelength is chosen with probability 1/4, so its pdf is divided by 4.
    Float keptLambda = lambda[k], keptPdf = pdf[k] / NSpectrumSamples;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        lambda[i] = keptLambda;
        pdf[i] = (i == k) ? keptPdf : 0;
    }
    terminated = true;
    survivor = k;
}

// ---- Spectrum ----------------------------------------------------------------------------

Spectrum::~Spectrum() = default;

SampledSpectrum Spectrum::Sample(const SampledWavelengths &lambda) const {
    SampledSpectrum s;
    for (int i = 0; i < NSpectrumSamples; ++i) s[i] = (*this)(lambda[i]);
    return s;
}

std::string ConstantSpectrum::ToString() const { return "[ ConstantSpectrum " + FormatFloat(c) + " ]"; }

// ---- DenselySampledSpectrum --------------------------------------------------------------

DenselySampledSpectrum::DenselySampledSpectrum(const Spectrum &s) : values(kNumSamples) {
    for (int i = 0; i < kNumSamples; ++i) values[i] = s(Lambda_min + i);
}

DenselySampledSpectrum::DenselySampledSpectrum(std::vector<Float> v) : values(std::move(v)) {
    if (int(values.size()) != kNumSamples)
        throw PbrtError("DenselySampledSpectrum needs " + std::to_string(kNumSamples) +
                        " values (360..830 nm), got " + std::to_string(values.size()));
}

Float DenselySampledSpectrum::operator()(Float lambda) const {
    // The nearest nanometre (pbrt-v4 rounds the same way: std::lround, halves away from 0).
    int i = Index(lambda);
    return i < 0 ? 0 : values[i];
}

SampledSpectrum DenselySampledSpectrum::Sample(const SampledWavelengths &lambda) const {
    SampledSpectrum s;
    for (int i = 0; i < NSpectrumSamples; ++i) s[i] = (*this)(lambda[i]);
    return s;
}

Float DenselySampledSpectrum::MaxValue() const {
    return *std::max_element(values.begin(), values.end());
}

std::string DenselySampledSpectrum::ToString() const {
    return "[ DenselySampledSpectrum 360..830 nm, max " + FormatFloat(MaxValue()) + " ]";
}

// ---- PiecewiseLinearSpectrum -------------------------------------------------------------

PiecewiseLinearSpectrum::PiecewiseLinearSpectrum(std::vector<Float> l, std::vector<Float> v)
    : lambdas(std::move(l)), values(std::move(v)) {
    if (lambdas.size() != values.size() || lambdas.empty())
        throw PbrtError("piecewise-linear spectrum needs as many wavelengths as values (>= 1)");
    for (size_t i = 1; i < lambdas.size(); ++i)
        if (!(lambdas[i] > lambdas[i - 1]))
            throw PbrtError("piecewise-linear spectrum wavelengths must increase: " +
                            FormatFloat(lambdas[i - 1]) + " then " + FormatFloat(lambdas[i]));
}

Float PiecewiseLinearSpectrum::operator()(Float lambda) const {
    if (!(lambda >= lambdas.front() && lambda <= lambdas.back())) return 0;
    // The segment [lambdas[i], lambdas[i+1]] that contains lambda.
    size_t i = std::upper_bound(lambdas.begin(), lambdas.end(), lambda) - lambdas.begin();
    if (i >= lambdas.size()) return values.back();
    if (i == 0) return values.front();
    --i;
    Float t = (lambda - lambdas[i]) / (lambdas[i + 1] - lambdas[i]);
    return (1 - t) * values[i] + t * values[i + 1];
}

Float PiecewiseLinearSpectrum::MaxValue() const {
    return *std::max_element(values.begin(), values.end());
}

std::string PiecewiseLinearSpectrum::ToString() const {
    return "[ PiecewiseLinearSpectrum " + std::to_string(lambdas.size()) + " samples, " +
           FormatFloat(lambdas.front()) + ".." + FormatFloat(lambdas.back()) + " nm ]";
}

std::shared_ptr<const PiecewiseLinearSpectrum> PiecewiseLinearSpectrum::FromInterleaved(
    const std::vector<Float> &interleaved, bool normalize, const FileLoc *loc) {
    if (interleaved.empty() || interleaved.size() % 2 != 0)
        throw SpectrumError(loc, "spectrum needs (wavelength, value) pairs, got " +
                                     std::to_string(interleaved.size()) + " numbers");
    std::vector<Float> lambdas, values;
    for (size_t i = 0; i < interleaved.size(); i += 2) {
        Float l = interleaved[i], v = interleaved[i + 1];
        if (!std::isfinite(l) || !std::isfinite(v))
            throw SpectrumError(loc, "spectrum has a non-finite number in pair " +
                                         std::to_string(i / 2 + 1));
        if (!lambdas.empty() && !(l > lambdas.back()))
            throw SpectrumError(loc, "spectrum wavelengths must increase: " +
                                         FormatFloat(lambdas.back()) + " then " + FormatFloat(l));
        lambdas.push_back(l);
        values.push_back(v);
    }
    // pbrt-v4 extends samples that stop short of the visible range with their end values
    // (to Lambda_min - 1 and Lambda_max + 1 nm).
    if (lambdas.front() > Lambda_min) {
        lambdas.insert(lambdas.begin(), Lambda_min - 1);
        values.insert(values.begin(), values.front());
    }
    if (lambdas.back() < Lambda_max) {
        lambdas.push_back(Lambda_max + 1);
        values.push_back(values.back());
    }
    auto spec = std::make_shared<PiecewiseLinearSpectrum>(std::move(lambdas), std::move(values));
    if (normalize) {
        // Scale to a luminance of 1: InnerProduct with ybar equal to CIE_Y_integral.
        double y = InnerProductDouble(*spec, Spectra::Y());
        if (!(y > 0))
            throw SpectrumError(loc, "cannot normalize a spectrum whose luminance is " +
                                         FormatFloat(y) + " (zero over 360..830 nm?)");
        for (Float &v : spec->values) v = Float(v * (CIE_Y_integral / y));
    }
    return spec;
}

std::shared_ptr<const PiecewiseLinearSpectrum> PiecewiseLinearSpectrum::ReadSPD(
    const std::string &path, bool normalize) {
    // A regular file of at most 64 MiB (design §3.3): a device or FIFO named as a spectrum
    // is refused before a byte is read.
    std::istringstream in;
    try {
        in.str(ReadRegularFile(path, "spectrum", kMaxSpectrumFileBytes));
    } catch (const FileReadError &e) {
        throw PbrtError(path + ": " + e.what());
    }
    // Read every number, remembering where it came from for error messages.
    std::vector<Float> numbers;
    std::vector<FileLoc> where;
    std::string line;
    for (int lineNo = 1; std::getline(in, line); ++lineNo) {
        size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        size_t pos = 0;
        while (true) {
            pos = line.find_first_not_of(" \t\r\f\v,", pos);
            if (pos == std::string::npos) break;
            size_t end = line.find_first_of(" \t\r\f\v,", pos);
            std::string token = line.substr(pos, end == std::string::npos ? end : end - pos);
            FileLoc loc{path, lineNo, int(pos) + 1};
            char *stop = nullptr;
            double v = std::strtod(token.c_str(), &stop);
            if (stop == token.c_str() || *stop != '\0')
                throw PbrtError(loc, "not a number: '" + token + "'");
            if (!std::isfinite(v)) throw PbrtError(loc, "non-finite number: '" + token + "'");
            numbers.push_back(Float(v));
            where.push_back(loc);
            if (end == std::string::npos) break;
            pos = end;
        }
    }
    if (numbers.empty()) throw PbrtError(path + ": spectrum file has no numbers");
    if (numbers.size() % 2 != 0)
        throw PbrtError(where.back(), "spectrum file has an odd number of values (" +
                                          std::to_string(numbers.size()) +
                                          "); expected wavelength/value pairs");
    for (size_t i = 2; i < numbers.size(); i += 2)
        if (!(numbers[i] > numbers[i - 2]))
            throw PbrtError(where[i], "wavelengths must increase: " + FormatFloat(numbers[i - 2]) +
                                          " then " + FormatFloat(numbers[i]));
    FileLoc fileLoc{path, where.front().line, 1};
    return FromInterleaved(numbers, normalize, &fileLoc);
}

// ---- Blackbody ---------------------------------------------------------------------------

Float Blackbody(Float lambda, Float T) {
    if (T <= 0) return 0;
    // CODATA 2018 exact SI values: speed of light, Planck and Boltzmann constants.
    const double c = 299792458., h = 6.62607015e-34, kb = 1.380649e-23;
    double l = double(lambda) * 1e-9;  // nm -> m
    double Le = (2 * h * c * c) / (std::pow(l, 5) * std::expm1((h * c) / (l * kb * T)));
    return Float(Le);
}

BlackbodySpectrum::BlackbodySpectrum(Float T) : T(T) {
    if (!(T > 0) || !std::isfinite(T))
        throw PbrtError("blackbody temperature must be positive, got " + FormatFloat(T) + " K");
    // Wien's displacement law: the peak is at b / T, b = 2.897771955e-3 m K (CODATA 2018).
    Float lambdaMax = Float(2.897771955e-3 / T * 1e9);
    normalizationFactor = 1 / Blackbody(lambdaMax, T);
}

Float BlackbodySpectrum::operator()(Float lambda) const {
    return Blackbody(lambda, T) * normalizationFactor;
}

std::string BlackbodySpectrum::ToString() const {
    return "[ BlackbodySpectrum " + FormatFloat(T) + " K ]";
}

// ---- RGB spectra -------------------------------------------------------------------------

Float RGBSigmoidPolynomial::MaxValue() const {
    // The sigmoid increases, so the maximum is where the quadratic is largest on [-1, 1]:
    // at an end, or at the vertex t = -c1 / (2 c0) when it is a maximum inside.
    auto x = [&](double t) { return (c0 * t + c1) * t + c2; };
    double best = std::max(x(-1), x(1));
    if (c0 < 0) {
        double tv = -double(c1) / (2 * double(c0));
        if (tv > -1 && tv < 1) best = std::max(best, x(tv));
    }
    return Sigmoid(Float(best));
}

namespace {
void CheckRGB(const RGB &rgb, bool atMostOne, const char *what) {
    for (int c = 0; c < 3; ++c) {
        if (std::isnan(rgb[c]) || rgb[c] < 0 || (atMostOne && rgb[c] > 1))
            throw PbrtError(std::string(what) + " RGB " + rgb.ToString() +
                            (atMostOne ? " must lie in [0, 1]" : " must be non-negative"));
    }
}

// pbrt-v4's split of an unbounded RGB into scale * (RGB of max component 1/2).
void SplitUnbounded(const RGBColorSpace &cs, const RGB &rgb, Float *scale, RGBSigmoidPolynomial *rsp) {
    Float m = rgb.MaxComponentValue();
    *scale = 2 * m;
    *rsp = cs.ToRGBCoeffs(*scale != 0 ? rgb / *scale : RGB(0, 0, 0));
}
}  // namespace

RGBAlbedoSpectrum::RGBAlbedoSpectrum(const RGBColorSpace &cs, RGB rgb) {
    CheckRGB(rgb, true, "reflectance");
    rsp = cs.ToRGBCoeffs(rgb);
}

SampledSpectrum RGBAlbedoSpectrum::Sample(const SampledWavelengths &lambda) const {
    return rsp.Sample(lambda);
}

SampledSpectrum RGBUnboundedSpectrum::Sample(const SampledWavelengths &lambda) const {
    return rsp.Sample(lambda) * scale;
}

std::string RGBAlbedoSpectrum::ToString() const {
    return "[ RGBAlbedoSpectrum c = " + FormatFloat(rsp.c0) + " " + FormatFloat(rsp.c1) + " " +
           FormatFloat(rsp.c2) + " ]";
}

RGBUnboundedSpectrum::RGBUnboundedSpectrum(const RGBColorSpace &cs, RGB rgb) {
    CheckRGB(rgb, false, "unbounded");
    SplitUnbounded(cs, rgb, &scale, &rsp);
}

std::string RGBUnboundedSpectrum::ToString() const {
    return "[ RGBUnboundedSpectrum scale " + FormatFloat(scale) + " ]";
}

RGBIlluminantSpectrum::RGBIlluminantSpectrum(const RGBColorSpace &cs, RGB rgb)
    : illuminant(cs.IlluminantHandle()) {
    CheckRGB(rgb, false, "illuminant");
    SplitUnbounded(cs, rgb, &scale, &rsp);
}

SampledSpectrum RGBIlluminantSpectrum::Sample(const SampledWavelengths &lambda) const {
    return rsp.Sample(lambda) * scale * illuminant->Sample(lambda);
}

std::string RGBIlluminantSpectrum::ToString() const {
    return "[ RGBIlluminantSpectrum scale " + FormatFloat(scale) + " illuminant " +
           illuminant->ToString() + " ]";
}

// ---- CIE matching functions and named spectra ---------------------------------------------

namespace {
const DenselySampledSpectrum &MakeCMF(const double *table) {
    static_assert(DenselySampledSpectrum::kNumSamples == cie::kNumSamples, "CIE data range");
    std::vector<Float> v(table, table + cie::kNumSamples);
    return *new DenselySampledSpectrum(std::move(v));  // lives for the whole program
}

const std::map<std::string, SpectrumHandle> &NamedSpectra() {
    static const std::map<std::string, SpectrumHandle> spectra = [] {
        std::map<std::string, SpectrumHandle> m;
        // Illuminants: piecewise linear over their published samples, normalized to
        // luminance 1 (pbrt-v4 builds them the same way).
        for (int i = 0; i < cie::kNumIlluminants; ++i) {
            const cie::Table &t = cie::kIlluminants[i];
            std::vector<Float> interleaved;
            for (int j = 0; j < t.count; ++j) {
                interleaved.push_back(Float(t.lambdaFirst + j * t.lambdaStep));
                interleaved.push_back(Float(t.values[j]));
            }
            m[t.name] = PiecewiseLinearSpectrum::FromInterleaved(interleaved, true);
        }
        return m;
    }();
    return spectra;
}
}  // namespace

namespace Spectra {
const DenselySampledSpectrum &X() {
    static const DenselySampledSpectrum &x = MakeCMF(cie::CIE_X);
    return x;
}
const DenselySampledSpectrum &Y() {
    static const DenselySampledSpectrum &y = MakeCMF(cie::CIE_Y);
    return y;
}
const DenselySampledSpectrum &Z() {
    static const DenselySampledSpectrum &z = MakeCMF(cie::CIE_Z);
    return z;
}
}  // namespace Spectra

SpectrumHandle GetNamedSpectrum(const std::string &name) {
    const auto &spectra = NamedSpectra();
    auto it = spectra.find(name);
    return it == spectra.end() ? nullptr : it->second;
}

std::vector<std::string> NamedSpectrumNames() {
    std::vector<std::string> names;
    for (const auto &[name, s] : NamedSpectra()) names.push_back(name);
    return names;
}

Float InnerProduct(const Spectrum &f, const Spectrum &g) { return Float(InnerProductDouble(f, g)); }

Float SpectrumToPhotometric(const Spectrum &s) {
    if (auto *rgbIllum = dynamic_cast<const RGBIlluminantSpectrum *>(&s))
        return InnerProduct(rgbIllum->Illuminant(), Spectra::Y());
    return InnerProduct(s, Spectra::Y());
}

XYZ SpectrumToXYZ(const Spectrum &s) {
    return XYZ(InnerProduct(Spectra::X(), s), InnerProduct(Spectra::Y(), s),
               InnerProduct(Spectra::Z(), s)) /
           CIE_Y_integral;
}

}  // namespace pbrt
