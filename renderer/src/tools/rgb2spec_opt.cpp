// rgb2spec_opt: computes the RGB-to-spectrum coefficient table of one colour space at
// build time (cmake/rgb2spec.cmake runs it once per named colour space).
//
// Method: Jakob and Hanika 2019, "A Low-Dimensional Function Space for Efficient Spectral
// Upsampling" (Computer Graphics Forum 38(2)). A reflectance is the sigmoid of a quadratic,
// s(lambda) = S(c0 t^2 + c1 t + c2), S(x) = 1/2 + x / (2 sqrt(1 + x^2)), with the
// normalized wavelength t = (lambda - 595) / 235 in [-1, 1]. For each RGB on a grid the
// three coefficients are found by Gauss-Newton iterations that drive the CIELAB difference
// (CIE 1976) between the target and the colour of s lit by the colour space's illuminant to
// zero. The grid is Jakob and Hanika 2019's (and pbrt-v4's): for each largest component l, its value z
// on kRes smoothstep(smoothstep) nodes and the other two components' ratios to it on kRes
// even steps; neighbouring solutions along z seed each other, starting from z node kRes/5.
//
// Colours are integrated exactly as the renderer integrates them: sums over lambda = 360,
// 361, ..., 830 nm of the CIE 1931 matching functions times the normalized illuminant times
// s (InnerProduct in spectrum.cpp), so an RGB round-trips through the renderer's spectrum.
//
// Why hand-written: no packaged library computes these tables, and the project must make
// them itself rather than ship pbrt-v4's.
//
// Usage: rgb2spec_opt <colour space> <output.cpp> [--threads N]

#include <pbrt/util/color.h>
#include <pbrt/util/spectrum.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace pbrt {

// The library's colour spaces refer to the tables this tool writes. The tool runs before
// they exist, so here they are absent (RGBColorSpace works without a table).
const RGBToSpectrumTable *RGBToSpectrumTable_srgb() { return nullptr; }
const RGBToSpectrumTable *RGBToSpectrumTable_dci_p3() { return nullptr; }
const RGBToSpectrumTable *RGBToSpectrumTable_rec2020() { return nullptr; }
const RGBToSpectrumTable *RGBToSpectrumTable_aces2065_1() { return nullptr; }

namespace {

constexpr int kRes = RGBToSpectrumTable::kRes;

// The colorimetry of one colour space, as the optimizer needs it.
struct Problem {
    std::vector<double> t, t2;      // normalized wavelength per 1 nm sample
    std::vector<double> w[3];       // cmf_c(lambda) * illuminant(lambda) / sum(ybar * illuminant)
    double white[3];                // XYZ of the perfect reflector (Y = 1)
    ColorMatrix3 xyzFromRGB;
};

Problem MakeProblem(const RGBColorSpace &cs) {
    Problem p;
    const Spectrum &illum = cs.Illuminant();
    const DenselySampledSpectrum *cmf[3] = {&Spectra::X(), &Spectra::Y(), &Spectra::Z()};
    double norm = 0;
    for (int lambda = int(Lambda_min); lambda <= int(Lambda_max); ++lambda)
        norm += double(Spectra::Y()(Float(lambda))) * double(illum(Float(lambda)));
    for (int lambda = int(Lambda_min); lambda <= int(Lambda_max); ++lambda) {
        double t = (lambda - RGBSigmoidPolynomial::kCenter) / RGBSigmoidPolynomial::kHalfWidth;
        p.t.push_back(t);
        p.t2.push_back(t * t);
        for (int c = 0; c < 3; ++c)
            p.w[c].push_back(double((*cmf[c])(Float(lambda))) * double(illum(Float(lambda))) / norm);
    }
    for (int c = 0; c < 3; ++c) {
        p.white[c] = 0;
        for (double v : p.w[c]) p.white[c] += v;
    }
    p.xyzFromRGB = cs.XYZFromRGB;
    return p;
}

// CIE 1976 L*a*b* of an XYZ relative to the white, and its Jacobian d(Lab)/d(XYZ).
void XYZToLab(const double xyz[3], const double white[3], double lab[3], double dlab[3][3]) {
    const double delta = 6.0 / 29.0, delta3 = delta * delta * delta;
    double f[3], df[3];
    for (int c = 0; c < 3; ++c) {
        double v = xyz[c] / white[c];
        if (v > delta3) {
            f[c] = std::cbrt(v);
            df[c] = 1 / (3 * f[c] * f[c] * white[c]);
        } else {
            f[c] = v / (3 * delta * delta) + 4.0 / 29.0;
            df[c] = 1 / (3 * delta * delta * white[c]);
        }
    }
    lab[0] = 116 * f[1] - 16;
    lab[1] = 500 * (f[0] - f[1]);
    lab[2] = 200 * (f[1] - f[2]);
    if (dlab) {
        const double D[3][3] = {{0, 116, 0}, {500, -500, 0}, {0, 200, -200}};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) dlab[i][j] = D[i][j] * df[j];
    }
}

// Residual (Lab of the sigmoid spectrum minus the target Lab) and its Jacobian with respect
// to the coefficients.
void Residual(const Problem &p, const double c[3], const double targetLab[3], double r[3],
              double J[3][3]) {
    // One pass over the wavelengths with scalar accumulators (so the loop vectorizes):
    // XYZ_m = sum_k w_m S(x_k), dXYZ_m/dc_i = sum_k w_m S'(x_k) t_k^(2-i).
    const double *t = p.t.data(), *t2 = p.t2.data();
    const double *wx = p.w[0].data(), *wy = p.w[1].data(), *wz = p.w[2].data();
    double X = 0, Y = 0, Z = 0, X0 = 0, X1 = 0, X2 = 0, Y0 = 0, Y1 = 0, Y2 = 0, Z0 = 0, Z1 = 0, Z2 = 0;
    const size_t n = p.t.size();
    for (size_t k = 0; k < n; ++k) {
        double x = c[0] * t2[k] + c[1] * t[k] + c[2];
        double inv = 1 / std::sqrt(1 + x * x);
        double s = 0.5 + 0.5 * x * inv;     // S(x)
        double ds = 0.5 * inv * inv * inv;  // S'(x)
        double dx = wx[k] * ds, dy = wy[k] * ds, dz = wz[k] * ds;
        X += wx[k] * s;
        Y += wy[k] * s;
        Z += wz[k] * s;
        X0 += dx * t2[k]; X1 += dx * t[k]; X2 += dx;
        Y0 += dy * t2[k]; Y1 += dy * t[k]; Y2 += dy;
        Z0 += dz * t2[k]; Z1 += dz * t[k]; Z2 += dz;
    }
    double xyz[3] = {X, Y, Z};
    double dxyz[3][3] = {{X0, X1, X2}, {Y0, Y1, Y2}, {Z0, Z1, Z2}};
    double lab[3], dlab[3][3];
    XYZToLab(xyz, p.white, lab, dlab);
    for (int i = 0; i < 3; ++i) {
        r[i] = lab[i] - targetLab[i];
        for (int j = 0; j < 3; ++j)
            J[i][j] = dlab[i][0] * dxyz[0][j] + dlab[i][1] * dxyz[1][j] + dlab[i][2] * dxyz[2][j];
    }
}

// Solves A x = b (3x3) by Gaussian elimination with partial pivoting; false if singular.
bool Solve3(double A[3][3], double b[3], double x[3]) {
    int perm[3] = {0, 1, 2};
    for (int col = 0; col < 3; ++col) {
        int best = col;
        for (int row = col + 1; row < 3; ++row)
            if (std::abs(A[perm[row]][col]) > std::abs(A[perm[best]][col])) best = row;
        std::swap(perm[col], perm[best]);
        double pivot = A[perm[col]][col];
        if (!(std::abs(pivot) > 1e-300)) return false;
        for (int row = col + 1; row < 3; ++row) {
            double f = A[perm[row]][col] / pivot;
            for (int k = col; k < 3; ++k) A[perm[row]][k] -= f * A[perm[col]][k];
            b[perm[row]] -= f * b[perm[col]];
        }
    }
    for (int col = 2; col >= 0; --col) {
        double sum = b[perm[col]];
        for (int k = col + 1; k < 3; ++k) sum -= A[perm[col]][k] * x[k];
        x[col] = sum / A[perm[col]][col];
    }
    return std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]);
}

double Norm(const double r[3]) { return std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]); }

// Gauss-Newton from the coefficients in c (updated in place), with step halving when a full
// step does not reduce the residual. Stops at the tolerance, or when the residual stalls
// (targets outside the colours a reflectance can reach have no exact solution). Returns the
// final CIELAB difference.
double GaussNewton(const Problem &p, const double targetLab[3], double c[3]) {
    const int kMaxIterations = 48, kMaxHalvings = 12, kMaxStalls = 3;
    const double kTolerance = 1e-6;  // CIELAB units
    // Coefficients stay within +-kMaxCoefficient: enough for a transition narrower than
    // 0.1 nm, or a reflectance below 1e-8 (black has no finite solution), while the renderer's
    // single-precision evaluation stays accurate. Out-of-reach targets would diverge.
    const double kMaxCoefficient = 1e4;
    double r[3], J[3][3];
    Residual(p, c, targetLab, r, J);
    double err = Norm(r);
    int stalls = 0;
    for (int it = 0; it < kMaxIterations && err > kTolerance && stalls < kMaxStalls; ++it) {
        double A[3][3], b[3], step[3];
        for (int i = 0; i < 3; ++i) {
            b[i] = -r[i];
            for (int j = 0; j < 3; ++j) A[i][j] = J[i][j];
        }
        if (!Solve3(A, b, step)) break;
        bool improved = false;
        double alpha = 1;
        for (int h = 0; h < kMaxHalvings && !improved; ++h, alpha *= 0.5) {
            double cn[3];
            for (int m = 0; m < 3; ++m)
                cn[m] = std::clamp(c[m] + alpha * step[m], -kMaxCoefficient, kMaxCoefficient);
            double rn[3], Jn[3][3];
            Residual(p, cn, targetLab, rn, Jn);
            double errn = Norm(rn);
            if (errn < err) {
                // A step that gains less than 0.1% counts as a stall.
                stalls = (errn > 0.999 * err) ? stalls + 1 : 0;
                std::copy(cn, cn + 3, c);
                std::copy(rn, rn + 3, r);
                for (int i = 0; i < 3; ++i) std::copy(Jn[i], Jn[i] + 3, J[i]);
                err = errn;
                improved = true;
            }
        }
        if (!improved) break;
    }
    return err;
}

struct Stats {
    double maxError = 0;
    long notConverged = 0;  // CIELAB difference above 1e-3
    int worst[4] = {0, 0, 0, 0};
};

// All z for one (l, y index j, x index i) column of the grid, written into coeffs.
void SolveColumn(const Problem &p, int l, int j, int i, std::vector<float> &coeffs, Stats &stats) {
    auto solveAt = [&](int k, double c[3]) {
        double z = RGBToSpectrumTable::ZNode(k);
        double x = double(i) / (kRes - 1), y = double(j) / (kRes - 1);
        double rgb[3];
        rgb[l] = z;
        rgb[(l + 1) % 3] = x * z;
        rgb[(l + 2) % 3] = y * z;
        double xyz[3], lab[3];
        p.xyzFromRGB.Apply(rgb[0], rgb[1], rgb[2], xyz);
        XYZToLab(xyz, p.white, lab, nullptr);
        double err = GaussNewton(p, lab, c);
        // Black (z = 0) has no finite solution; its coefficients only need to be very dark.
        if (k > 0 && err > stats.maxError) {
            stats.maxError = err;
            stats.worst[0] = l; stats.worst[1] = k; stats.worst[2] = j; stats.worst[3] = i;
        }
        if (k > 0 && err > 1e-3) ++stats.notConverged;
        size_t idx = RGBToSpectrumTable::CoeffIndex(l, k, j, i);
        for (int m = 0; m < 3; ++m) coeffs[idx + m] = float(c[m]);
    };
    // March up from z node kRes/5, then down from it. Each solve starts from the linear
    // extrapolation (in z) of the two previous solutions, or the previous one.
    auto march = [&](int from, int to, int dir, const double *seed, const double *seed2, int k2) {
        double prev[3], prev2[3], c[3];
        std::copy(seed, seed + 3, prev);
        bool havePrev2 = seed2 != nullptr;
        if (havePrev2) std::copy(seed2, seed2 + 3, prev2);
        int kPrev = from - dir, kPrev2 = k2;
        for (int k = from; k != to; k += dir) {
            std::copy(prev, prev + 3, c);
            if (havePrev2) {
                double f = (RGBToSpectrumTable::ZNode(k) - RGBToSpectrumTable::ZNode(kPrev)) /
                           (RGBToSpectrumTable::ZNode(kPrev) - RGBToSpectrumTable::ZNode(kPrev2));
                for (int m = 0; m < 3; ++m) c[m] += f * (prev[m] - prev2[m]);
            }
            solveAt(k, c);
            std::copy(prev, prev + 3, prev2);
            std::copy(c, c + 3, prev);
            havePrev2 = true;
            kPrev2 = kPrev;
            kPrev = k;
        }
    };
    const int start = kRes / 5;
    const double zero[3] = {0, 0, 0};
    march(start, kRes, +1, zero, nullptr, 0);
    double atStart[3], aboveStart[3];
    for (int m = 0; m < 3; ++m) {
        atStart[m] = coeffs[RGBToSpectrumTable::CoeffIndex(l, start, j, i) + m];
        aboveStart[m] = coeffs[RGBToSpectrumTable::CoeffIndex(l, start + 1, j, i) + m];
    }
    march(start - 1, -1, -1, atStart, aboveStart, start + 1);
}

std::string Identifier(const std::string &space) {
    std::string id;
    for (char ch : space) id += std::isalnum((unsigned char)ch) ? ch : '_';
    return id;
}

bool WriteTable(const std::string &path, const std::string &space, const std::vector<float> &coeffs,
                const Stats &stats) {
    std::string tmp = path + ".tmp";
    FILE *f = std::fopen(tmp.c_str(), "w");
    if (!f) return false;
    std::string id = Identifier(space);
    std::fprintf(f,
                 "// GENERATED at build time by src/tools/rgb2spec_opt.cpp for colour space \"%s\";\n"
                 "// do not edit. Sigmoid-polynomial coefficients (Jakob and Hanika 2019), %d^3 grid\n"
                 "// per largest component; largest CIELAB error of a solved grid point: %.3g.\n"
                 "#include <pbrt/util/color.h>\n\nnamespace pbrt {\nnamespace {\n\n",
                 space.c_str(), kRes, stats.maxError);
    std::fprintf(f, "const float zNodes[%d] = {\n", kRes);
    for (int k = 0; k < kRes; ++k)
        std::fprintf(f, "%.9g,%s", float(RGBToSpectrumTable::ZNode(k)), k % 8 == 7 ? "\n" : " ");
    std::fprintf(f, "};\n\nconst float coeffs[%zu] = {\n", coeffs.size());
    for (float c : coeffs)
        if (!std::isfinite(c)) {
            std::fclose(f);
            std::remove(tmp.c_str());
            std::fprintf(stderr, "rgb2spec_opt: non-finite coefficient (a bug)\n");
            return false;
        }
    for (size_t n = 0; n < coeffs.size(); ++n)
        std::fprintf(f, "%.9g,%s", coeffs[n], n % 9 == 8 ? "\n" : " ");
    std::fprintf(f,
                 "};\n\n}  // namespace\n\n"
                 "const RGBToSpectrumTable *RGBToSpectrumTable_%s() {\n"
                 "    static const RGBToSpectrumTable table(zNodes, coeffs);\n"
                 "    return &table;\n}\n\n}  // namespace pbrt\n",
                 id.c_str());
    bool ok = std::fclose(f) == 0;
    return ok && std::rename(tmp.c_str(), path.c_str()) == 0;
}

int Main(int argc, char **argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: rgb2spec_opt <colour space> <output.cpp> [--threads N]\n");
        return 1;
    }
    std::string space = argv[1], out = argv[2];
    int nThreads = int(std::max(1u, std::thread::hardware_concurrency()));
    for (int a = 3; a < argc; ++a) {
        if (std::string(argv[a]) == "--threads" && a + 1 < argc) nThreads = std::max(1, std::atoi(argv[++a]));
        else {
            std::fprintf(stderr, "rgb2spec_opt: unknown argument '%s'\n", argv[a]);
            return 1;
        }
    }
    const RGBColorSpace *cs = RGBColorSpace::GetNamed(space);
    if (!cs) {
        std::fprintf(stderr, "rgb2spec_opt: unknown colour space '%s'\n", space.c_str());
        return 1;
    }
    auto t0 = std::chrono::steady_clock::now();
    Problem p = MakeProblem(*cs);
    std::vector<float> coeffs(RGBToSpectrumTable::kNumCoefficients);

    // Threads take (l, j) rows of the grid from a shared counter.
    std::atomic<int> next{0};
    std::mutex statsMutex;
    Stats total;
    std::vector<std::thread> threads;
    for (int t = 0; t < nThreads; ++t)
        threads.emplace_back([&] {
            Stats local;
            for (int task; (task = next++) < 3 * kRes;)
                for (int i = 0; i < kRes; ++i) SolveColumn(p, task / kRes, task % kRes, i, coeffs, local);
            std::lock_guard<std::mutex> lock(statsMutex);
            total.notConverged += local.notConverged;
            if (local.maxError > total.maxError) {
                total.maxError = local.maxError;
                std::copy(local.worst, local.worst + 4, total.worst);
            }
        });
    for (auto &th : threads) th.join();

    if (!WriteTable(out, space, coeffs, total)) {
        std::fprintf(stderr, "rgb2spec_opt: cannot write '%s'\n", out.c_str());
        return 1;
    }
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("rgb2spec_opt: %s: %d^3 x 3 grid in %.1f s (%d threads); largest CIELAB error %.3g "
                "(l=%d z=%d y=%d x=%d), %ld grid points above 1e-3 (outside the reachable colours)\n",
                space.c_str(), kRes, seconds, nThreads, total.maxError, total.worst[0], total.worst[1],
                total.worst[2], total.worst[3], total.notConverged);
    return 0;
}

}  // namespace
}  // namespace pbrt

int main(int argc, char **argv) {
    try {
        return pbrt::Main(argc, argv);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "rgb2spec_opt: %s\n", e.what());
        return 1;
    }
}
