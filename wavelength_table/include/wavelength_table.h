// wavelength_table.h -- sample the wavelengths of a spectral path from a tabulated table.
//
// A table holds kNumDensities = 4 densities p_0..p_3 over one strictly increasing grid of
// nodes lambda_0 < ... < lambda_M [nm] (design §1). Each p_k is piecewise linear between
// its node values, zero outside [lambda_0, lambda_M], and integrates to 1 by the trapezoid
// rule, so its CDF F_k is piecewise quadratic. A path draws ONE u and gets four wavelengths
// lambda_k = F_k^-1(u); the estimator divides f(lambda_j) by the mixture density
// (1/4) sum_k p_k(lambda_j) (the balance heuristic over the four densities).
//
// Header only, standard library only, C++17. Every density routine comes as a triple:
// Sample (exact inverse CDF), Pdf, Invert (the CDF). The functions in namespace kernel work
// on raw arrays and are plain arithmetic, so a GPU renderer can call them on device copies
// of the arrays (Pack / ViewPacked; define WAVELENGTH_TABLE_HOST_DEVICE as
// `__host__ __device__`).
//
// File layouts (design §2), both read by LoadTable / ParseTable:
//   - commented CSV: lines starting with '#' are comments, then the header
//     `lambda_nm,pdf0,pdf1,pdf2,pdf3`, then one row per node;
//   - headerless "4 x 81": four rows of 81 densities at 380, 385, ..., 780 nm.
// Blank lines and '#' lines are skipped in both; a row may end with one trailing comma.
// A line ends at LF, CR LF or a lone CR; any other control character is an error; fields are
// trimmed of spaces and tabs; numbers are ASCII (design §2). A table file must be a regular
// file of at most 64 MiB (design §2.3). Each density is renormalized exactly: one whose
// largest value lies outside [2^-64, 2^64] is first scaled by a power of two (§2.3).
// Bad input throws TableError("FILE:LINE: reason"); "FILE: reason" when no line applies
// (a missing file, or a table built in memory with MakeTable).
//
// The same rules, with the same conventions at the edges (which segment u = F_k(node)
// selects, u = 0 and u = 1 map to the ends of the support), are implemented in Python by
// python/wavelength_pdf/sampling.py; wavelength_table/tests/data/vectors*.csv pin the two together.

#ifndef WAVELENGTH_TABLE_H
#define WAVELENGTH_TABLE_H

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <istream>
#include <limits>
#include <locale>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#define WAVELENGTH_TABLE_POSIX 1
#endif

#ifndef WAVELENGTH_TABLE_HOST_DEVICE
#define WAVELENGTH_TABLE_HOST_DEVICE
#endif

namespace wavelength_table {

// Number of densities in a table = wavelengths per path (design §1).
constexpr int kNumDensities = 4;
// Column header of the commented CSV layout (design §2).
constexpr const char *kHeader = "lambda_nm,pdf0,pdf1,pdf2,pdf3";
// Grid of the headerless layout: 81 nodes, 380..780 nm in 5 nm steps (design §2).
constexpr int kWideNodes = 81;
constexpr double kWideFirst = 380.0, kWideStep = 5.0;
// The largest table file a reader accepts (design §2.3): far above any real table (0.1 nm
// steps over 360..830 nm take ~0.5 MB), low enough that a wrong file cannot exhaust memory.
constexpr std::size_t kMaxTableBytes = std::size_t(64) << 20;

// A validated table: pdf[k] integrates to 1 by the trapezoid rule over grid, cdf[k][i] is
// F_k(grid[i]) with cdf[k].front() == 0 and cdf[k].back() == 1 exactly.
struct Table {
    std::vector<double> grid;                            // nm, strictly increasing, >= 2 nodes
    std::array<std::vector<double>, kNumDensities> pdf;  // 1/nm at the nodes, >= 0
    std::array<std::vector<double>, kNumDensities> cdf;  // at the nodes
    std::string source;                                  // file name (or the name given)
};

// Invalid table: the message reads "FILE:LINE: reason" (or "FILE: reason" when line is 0).
class TableError : public std::runtime_error {
  public:
    TableError(const std::string &file, int line, const std::string &reason)
        : std::runtime_error(Format(file, line, reason)), file_(file), line_(line),
          reason_(reason) {}
    const std::string &file() const { return file_; }
    int line() const { return line_; }
    const std::string &reason() const { return reason_; }

  private:
    static std::string Format(const std::string &file, int line, const std::string &reason) {
        if (line > 0)
            return file + ":" + std::to_string(line) + ": " + reason;
        return file + ": " + reason;
    }
    std::string file_;
    int line_;
    std::string reason_;
};

// Pointers to the arrays of a table (of a Table, or of a packed copy in GPU memory);
// trivially copyable, so it can be passed to a kernel.
struct TableView {
    const double *grid;
    const double *pdf[kNumDensities];
    const double *cdf[kNumDensities];
    int n;  // nodes
};

// ---------------------------------------------------------------------------------------
// Kernels on raw arrays: one density with n >= 2 nodes (grid, normalized pdf, cdf).
// ---------------------------------------------------------------------------------------
namespace kernel {

// Largest i in [0, n-1] with x[i] <= v (0 if v < x[0] or v is NaN); x is non-decreasing.
// A hand-written search instead of std::upper_bound so that it also compiles as device code,
// and branch-free (the step is a conditional move, Khuong and Morin 2017): the comparisons
// of a sampled wavelength are unpredictable, so a branching search mispredicts about every
// other step, and a table of several hundred nodes would cost noticeably more per path than
// one of 81.
WAVELENGTH_TABLE_HOST_DEVICE inline int LastNotAbove(const double *x, int n, double v) {
    // invariant: the answer lies in [base, base + len - 1], and x[base] <= v unless base = 0
    int base = 0, len = n;
    while (len > 1) {
        const int half = len / 2;
        base = (x[base + half] <= v) ? base + half : base;
        len -= half;
    }
    return base;
}

// lambda = F^-1(u), exact for the piecewise-linear density; *segment receives the i with
// grid[i] <= lambda <= grid[i + 1] (so the caller can evaluate densities there directly).
WAVELENGTH_TABLE_HOST_DEVICE inline double SampleSegment(const double *grid, const double *pdf,
                                                         const double *cdf, int n, double u,
                                                         int *segment) {
    // Clamp u to [0, 1] (NaN counts as 0).
    if (!(u > 0.0))
        u = 0.0;
    else if (u > 1.0)
        u = 1.0;
    // The segment holding u: the last node with F <= u skips zero-probability segments to
    // the left of u; at the top (u = 1) step back over zero-probability segments so that u
    // never lands in a zero tail.
    int i = LastNotAbove(cdf, n, u);
    if (i > n - 2)
        i = n - 2;
    while (i > 0 && !(cdf[i + 1] > cdf[i]))
        --i;
    *segment = i;
    // Inside the segment the CDF is quadratic. Measured from the end where the density is
    // smaller, the offset t solves a t^2 / 2 + q t - r = 0 with q >= 0 the density at that
    // end, a >= 0 the slope away from it and r >= 0 the probability between that end and u.
    // The root is taken as t = 2 r / (q + sqrt(q^2 + 2 a r)): every term is >= 0, so nothing
    // cancels; it tends to r / q as a -> 0 and to sqrt(2 r / a) as q -> 0. (Solving from the
    // larger end instead would subtract nearly equal numbers where the density approaches 0.)
    const double h = grid[i + 1] - grid[i];
    const double p0 = pdf[i], p1 = pdf[i + 1];
    const bool fromLeft = p1 >= p0;
    const double q = fromLeft ? p0 : p1;
    const double a = (fromLeft ? p1 - p0 : p0 - p1) / h;
    const double r = fromLeft ? u - cdf[i] : cdf[i + 1] - u;
    if (!(r > 0.0))
        return fromLeft ? grid[i] : grid[i + 1];
    const double den = q + std::sqrt(q * q + 2.0 * a * r);
    double t = den > 0.0 ? 2.0 * r / den : 0.0;
    t = t > h ? h : t;
    // Inside the segment even where the arithmetic is lost to rounding (densities near the
    // smallest doubles, on a grid spanning 1e308 nm, once gave 0 nm): a no-op otherwise.
    const double x = fromLeft ? grid[i] + t : grid[i + 1] - t;
    return x < grid[i] ? grid[i] : (x > grid[i + 1] ? grid[i + 1] : x);
}

// lambda = F^-1(u), exact for the piecewise-linear density.
WAVELENGTH_TABLE_HOST_DEVICE inline double Sample(const double *grid, const double *pdf,
                                                  const double *cdf, int n, double u) {
    int segment;
    return SampleSegment(grid, pdf, cdf, n, u, &segment);
}

// p(lambda): linear between nodes, 0 outside [grid[0], grid[n-1]].
WAVELENGTH_TABLE_HOST_DEVICE inline double Pdf(const double *grid, const double *pdf, int n,
                                               double lambda) {
    if (!(lambda >= grid[0] && lambda <= grid[n - 1]))
        return 0.0;
    int i = LastNotAbove(grid, n, lambda);
    if (i > n - 2)
        i = n - 2;
    const double a = (lambda - grid[i]) / (grid[i + 1] - grid[i]);
    return pdf[i] + a * (pdf[i + 1] - pdf[i]);
}

// F(lambda): the u that Sample maps to lambda (where p > 0); 0 left of the grid, 1 right.
WAVELENGTH_TABLE_HOST_DEVICE inline double Invert(const double *grid, const double *pdf,
                                                  const double *cdf, int n, double lambda) {
    if (!(lambda > grid[0]))
        return 0.0;  // also NaN
    if (lambda >= grid[n - 1])
        return 1.0;
    int i = LastNotAbove(grid, n, lambda);
    if (i > n - 2)
        i = n - 2;
    // Exact area of the trapezoid under the linear density from grid[i] to lambda.
    const double t = lambda - grid[i];
    const double pl = pdf[i] + (pdf[i + 1] - pdf[i]) * (t / (grid[i + 1] - grid[i]));
    const double F = cdf[i] + 0.5 * t * (pdf[i] + pl);
    return F < 0.0 ? 0.0 : (F > 1.0 ? 1.0 : F);
}

// (1/4) sum_k p_k(lambda).
WAVELENGTH_TABLE_HOST_DEVICE inline double MixturePdf(const TableView &v, double lambda) {
    double sum = 0.0;
    for (int k = 0; k < kNumDensities; ++k)
        sum += Pdf(v.grid, v.pdf[k], v.n, lambda);
    return sum / kNumDensities;
}

// The four wavelengths of a path from one u and their mixture densities. All densities share
// the grid, so the segment found while sampling lambda_j serves to evaluate the four
// densities at lambda_j: four binary searches per path in all.
WAVELENGTH_TABLE_HOST_DEVICE inline void SampleFour(const TableView &v, double u,
                                                    double lambda[kNumDensities],
                                                    double pdf[kNumDensities]) {
    int segment[kNumDensities];
    for (int k = 0; k < kNumDensities; ++k)
        lambda[k] = SampleSegment(v.grid, v.pdf[k], v.cdf[k], v.n, u, &segment[k]);
    for (int j = 0; j < kNumDensities; ++j) {
        const int i = segment[j];
        const double a = (lambda[j] - v.grid[i]) / (v.grid[i + 1] - v.grid[i]);
        double sum = 0.0;
        for (int k = 0; k < kNumDensities; ++k)
            sum += v.pdf[k][i] + a * (v.pdf[k][i + 1] - v.pdf[k][i]);
        pdf[j] = sum / kNumDensities;
    }
}

}  // namespace kernel

// A view of the arrays of `t` (valid while `t` lives).
inline TableView View(const Table &t) {
    TableView v;
    v.grid = t.grid.data();
    for (int k = 0; k < kNumDensities; ++k) {
        v.pdf[k] = t.pdf[k].data();
        v.cdf[k] = t.cdf[k].data();
    }
    v.n = static_cast<int>(t.grid.size());
    return v;
}

// ---------------------------------------------------------------------------------------
// Sampling a table (k = 0..3 picks the density).
// ---------------------------------------------------------------------------------------

// lambda = F_k^-1(u) [nm]; u = 0 maps to the left end of p_k's support, u = 1 to its right.
inline double Sample(const Table &t, int k, double u) {
    return kernel::Sample(t.grid.data(), t.pdf[k].data(), t.cdf[k].data(),
                          static_cast<int>(t.grid.size()), u);
}

// p_k(lambda) [1/nm].
inline double Pdf(const Table &t, int k, double lambda) {
    return kernel::Pdf(t.grid.data(), t.pdf[k].data(), static_cast<int>(t.grid.size()), lambda);
}

// F_k(lambda) in [0, 1].
inline double Invert(const Table &t, int k, double lambda) {
    return kernel::Invert(t.grid.data(), t.pdf[k].data(), t.cdf[k].data(),
                          static_cast<int>(t.grid.size()), lambda);
}

// (1/4) sum_k p_k(lambda) [1/nm]: the density a renderer divides by when it averages the
// four wavelengths of a path (design §1).
inline double MixturePdf(const Table &t, double lambda) {
    double sum = 0.0;
    for (int k = 0; k < kNumDensities; ++k)
        sum += Pdf(t, k, lambda);
    return sum / kNumDensities;
}

// The four wavelengths of one path from ONE u: lambda[k] = F_k^-1(u), pdf[j] =
// MixturePdf(lambda[j]). pdf[j] > 0 except on a set of u of measure zero (u = 0 or 1 at
// an end of the support where the densities vanish); a renderer counts such a sample as 0.
inline void SampleFour(const Table &t, double u, double lambda[kNumDensities],
                       double pdf[kNumDensities]) {
    kernel::SampleFour(View(t), u, lambda, pdf);
}

// ---------------------------------------------------------------------------------------
// Building and validating tables.
// ---------------------------------------------------------------------------------------
namespace detail {

// v with `digits` significant digits (%g style), in the classic locale.
inline std::string FormatDigits(double v, int digits) {
    std::ostringstream os;
    os.imbue(std::locale::classic());
    os.precision(digits);
    os << v;
    return os.str();
}

// The shortest text that reads back as v (like Python's repr), for values in messages.
inline std::string FormatNumber(double v) {
    for (int digits = 6; digits < 17; ++digits) {
        const std::string s = FormatDigits(v, digits);
        std::istringstream is(s);
        is.imbue(std::locale::classic());
        double back = 0.0;
        if (is >> back && back == v)
            return s;
    }
    return FormatDigits(v, 17);
}

// The IEEE 754 bits of a double, and back.
inline std::uint64_t Bits(double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
}
inline double FromBits(std::uint64_t b) {
    double v;
    std::memcpy(&v, &b, sizeof v);
    return v;
}
constexpr std::uint64_t kMagnitude = ~(std::uint64_t(1) << 63);
constexpr std::uint64_t kFraction = (std::uint64_t(1) << 52) - 1;

// An integer in the order of the finite double v (+0 and -0 equal, subnormals included),
// from its bits: a renderer built to treat subnormal numbers as zero (-ffast-math and the
// like set the FPU's DAZ/FTZ flags) would otherwise call 0 and 5e-324 equal.
inline std::int64_t OrderKey(double v) {
    const std::uint64_t b = Bits(v);
    const std::int64_t magnitude = static_cast<std::int64_t>(b & kMagnitude);
    return (b >> 63) ? -magnitude : magnitude;
}

// Scales the values of one density (finite, >= 0) by a power of two to a largest value in
// [0.5, 1) when their largest value lies outside [2^-64, 2^64], and reads every value then
// below 2^-1022 (a subnormal number, under 2^-958 of the largest) as 0 (design §2.3). On the
// bits, with integers only: exact, and the same whatever the FPU does with subnormal numbers
// (the Python reader, wavelength_pdf.table, does the same).
inline void ScaleExactly(std::vector<double> &v) {
    // value = sig * 2^e exactly, sig < 2^53, and the bit length of sig
    auto decompose = [](std::uint64_t b, std::uint64_t *sig, int *e, int *length) {
        const int biased = static_cast<int>(b >> 52);
        *sig = biased > 0 ? (b & kFraction) | (std::uint64_t(1) << 52) : (b & kFraction);
        *e = biased > 0 ? biased - 1075 : -1074;
        *length = 0;
        for (std::uint64_t s = *sig; s != 0; s >>= 1)
            ++*length;
    };
    std::uint64_t peakBits = 0;  // the bits of non-negative doubles are in their order
    for (double x : v)
        peakBits = std::max(peakBits, Bits(x) & kMagnitude);
    if (peakBits == 0)
        return;
    std::uint64_t sig;
    int e, length;
    decompose(peakBits, &sig, &e, &length);
    const int peakTop = e + length - 1;  // the peak lies in [2^top, 2^(top + 1))
    const bool powerOfTwo = sig == std::uint64_t(1) << (length - 1);
    const bool inside = (peakTop >= -64 && peakTop < 64) || (peakTop == 64 && powerOfTwo);
    const int shift = inside ? 0 : -(peakTop + 1);
    for (double &x : v) {
        const std::uint64_t b = Bits(x) & kMagnitude;
        decompose(b, &sig, &e, &length);
        const int top = e + length - 1 + shift;
        if (b == 0 || top < -1022) {
            x = 0.0;
            continue;
        }
        const std::uint64_t mantissa = (sig << (53 - length)) & kFraction;
        x = FromBits((static_cast<std::uint64_t>(top + 1023) << 52) | mantissa);
    }
}

// Lines of the file that hold each node and each value (0 when the table is not from a file).
struct SourceLines {
    std::vector<int> node;                                // line of grid[i]
    std::array<std::vector<int>, kNumDensities> value;   // line of values[k][i]
};

// Validate, renormalize (trapezoid rule) and build the CDFs.
inline Table Build(std::vector<double> grid, std::array<std::vector<double>, kNumDensities> values,
                   const std::string &name, const SourceLines &lines) {
    auto nodeLine = [&](std::size_t i) { return i < lines.node.size() ? lines.node[i] : 0; };
    auto valueLine = [&](int k, std::size_t i) {
        return i < lines.value[k].size() ? lines.value[k][i] : 0;
    };
    const std::size_t n = grid.size();
    if (n < 2)
        throw TableError(name, nodeLine(0),
                         "a table needs at least 2 grid nodes, got " + std::to_string(n));
    for (int k = 0; k < kNumDensities; ++k)
        if (values[k].size() != n)
            throw TableError(name, 0, "pdf" + std::to_string(k) + " has " +
                                          std::to_string(values[k].size()) +
                                          " values, the grid has " + std::to_string(n));
    // Numbers: the wavelengths, then each density in turn (the order of the Python reader,
    // wavelength_pdf.table, so that both name the same problem first).
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(grid[i]))
            throw TableError(name, nodeLine(i),
                             "wavelength is " + FormatNumber(grid[i]) + " (must be finite)");
    for (int k = 0; k < kNumDensities; ++k) {
        for (std::size_t i = 0; i < n; ++i) {
            const double v = values[k][i];
            if (std::isfinite(v) && v >= 0)
                continue;
            // The message only for a bad value (formatting costs microseconds a value, which
            // a table built in memory at scene load would pay for every node).
            const std::string what = "pdf" + std::to_string(k) + " is ";
            const std::string where = " at " + FormatDigits(grid[i], 6) + " nm";
            if (std::isnan(v))
                throw TableError(name, valueLine(k, i), what + "NaN" + where);
            if (std::isinf(v))
                throw TableError(name, valueLine(k, i), what + "infinite" + where);
            if (std::signbit(v) && (Bits(v) & kMagnitude) != 0)  // -0 is 0
                throw TableError(name, valueLine(k, i),
                                 what + "negative (" + FormatNumber(v) + ")" + where);
        }
    }
    for (std::size_t i = 1; i < n; ++i)
        if (!(OrderKey(grid[i]) > OrderKey(grid[i - 1])))
            throw TableError(name, nodeLine(i),
                             "grid is not strictly increasing (" + FormatNumber(grid[i - 1]) +
                                 " then " + FormatNumber(grid[i]) + " nm)");
    // Integrate each density (trapezoid rule, exact for piecewise-linear densities),
    // then divide the node values and the cumulative sums by the total. A density whose
    // largest value lies outside [2^-64, 2^64] is first scaled by a power of two to a largest
    // value in [0.5, 1), and values then below 2^-1022 are read as 0 (ScaleExactly): summed
    // as they are, subnormal values lose their digits (a table of 5e-324 everywhere
    // integrated to 1.16 after renormalizing) and huge ones overflow. The renormalization
    // is then exact to rounding, or the table is refused (design §2.3); a table written
    // normalized is not scaled and reads back bit for bit.
    Table t;
    t.grid = std::move(grid);
    t.source = name;
    for (int k = 0; k < kNumDensities; ++k) {
        const std::string pk = "pdf" + std::to_string(k);
        std::vector<double> &v = values[k];
        ScaleExactly(v);
        // -0 is 0 (ScaleExactly leaves a density without a non-zero magnitude as it is).
        if (std::all_of(v.begin(), v.end(), [](double x) { return (Bits(x) & kMagnitude) == 0; }))
            throw TableError(name, valueLine(k, 0), pk + " is zero everywhere");
        // One operation per statement: no fused multiply-add, so the CDF has the same bits
        // as the Python sampler's (the test vectors rely on it where the CDF is flat).
        std::vector<double> cum(n, 0.0);
        for (std::size_t i = 0; i + 1 < n; ++i) {
            const double width = t.grid[i + 1] - t.grid[i];
            const double mean = 0.5 * (v[i] + v[i + 1]);
            const double area = mean * width;
            cum[i + 1] = cum[i] + area;
        }
        const double total = cum[n - 1];
        if (!std::isfinite(total))
            throw TableError(name, valueLine(k, 0),
                             pk + " integrates to infinity (the grid is too wide)");
        // Every value is 0 or at least 2^-1022, so areas that underflow change a mass of at
        // least 2^-900 by less than 1e-100 of it (only a grid narrower than ~1e-250 nm makes
        // a smaller one); no value / total overflows either (< 2^965).
        if (!(total >= std::ldexp(1.0, -900)))
            throw TableError(name, valueLine(k, 0),
                             pk + " cannot be normalized exactly (the grid is too narrow)");
        t.pdf[k].resize(n);
        t.cdf[k].resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            t.pdf[k][i] = v[i] / total;
            t.cdf[k][i] = cum[i] / total;  // x / x == 1 exactly, so cdf.back() == 1
        }
    }
    return t;
}

// Without leading and trailing spaces and tabs (the only white space of a table, design §2).
inline std::string Trim(const std::string &s) {
    const char *ws = " \t";
    const std::size_t a = s.find_first_not_of(ws);
    if (a == std::string::npos)
        return std::string();
    return s.substr(a, s.find_last_not_of(ws) - a + 1);
}

// Comma-separated fields, trimmed; one trailing empty field (a trailing comma) is dropped.
inline std::vector<std::string> SplitFields(const std::string &line) {
    std::vector<std::string> fields;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = line.find(',', start);
        fields.push_back(Trim(line.substr(start, comma == std::string::npos
                                                     ? std::string::npos
                                                     : comma - start)));
        if (comma == std::string::npos)
            break;
        start = comma + 1;
    }
    if (fields.size() > 1 && fields.back().empty())
        fields.pop_back();
    return fields;
}

// One line without its terminator: "\n", "\r\n" and a lone "\r" end a line, and nothing else
// does (design §2; the Python reader splits lines by the same rule, not by str.splitlines(),
// which also splits at form feeds, NEL and U+2028).
inline bool GetLine(std::istream &in, std::string &line) {
    line.clear();
    std::istream::int_type c = in.get();
    if (c == std::istream::traits_type::eof())
        return false;
    for (; c != std::istream::traits_type::eof(); c = in.get()) {
        if (c == '\n')
            break;
        if (c == '\r') {
            if (in.peek() == '\n')
                in.get();
            break;
        }
        line.push_back(static_cast<char>(c));
    }
    return true;
}

inline std::string Lower(std::string s) {
    for (char &c : s)
        if (c >= 'A' && c <= 'Z')
            c = static_cast<char>(c - 'A' + 'a');
    return s;
}

// `text` in single quotes for a message, bytes outside printable ASCII written as \xNN (a
// message stays plain text whatever the file holds), at most 40 of them.
inline std::string Quote(const std::string &text) {
    std::string out = "'";
    for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7F) {
            out += static_cast<char>(c);
        } else {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", c);
            out += hex;
        }
    }
    return out + (text.size() > 40 ? "...'" : "'");
}

// The first control character of a line as its code point, or -1 if there is none: C0 other
// than tab, DEL, and C1 (U+0080..U+009F, NEL among them, the UTF-8 bytes C2 80..C2 9F). Any
// of them is an error in a table (design §2): none ends a line or counts as white space.
inline long ControlCharacter(const std::string &line) {
    for (std::size_t i = 0; i < line.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(line[i]);
        if ((c < 0x20 && c != '\t') || c == 0x7F)
            return c;
        if (c == 0xC2 && i + 1 < line.size()) {
            const unsigned char d = static_cast<unsigned char>(line[i + 1]);
            if (d >= 0x80 && d <= 0x9F)
                return d;
        }
    }
    return -1;
}

// Whether `low` (lower case, sign removed) is a number as design §2 writes one: ASCII digits
// with an optional point and exponent (1, 1., .5, 1.5e-3), or nan, inf, infinity.
inline bool IsNumberText(const std::string &low) {
    if (low == "nan" || low == "inf" || low == "infinity")
        return true;
    std::size_t i = 0, digits = 0;
    const auto isDigit = [&](std::size_t j) { return j < low.size() && low[j] >= '0' && low[j] <= '9'; };
    while (isDigit(i))
        ++i, ++digits;
    if (i < low.size() && low[i] == '.') {
        ++i;
        while (isDigit(i))
            ++i, ++digits;
    }
    if (digits == 0)
        return false;
    if (i < low.size() && low[i] == 'e') {
        ++i;
        if (i < low.size() && (low[i] == '+' || low[i] == '-'))
            ++i;
        if (!isDigit(i))
            return false;
        while (isDigit(i))
            ++i;
    }
    return i == low.size();
}

// One number; NaN and infinities are returned as such (Build names them). Parsed with the
// classic locale, so a renderer that switched the C locale still reads "0.5".
inline double ParseNumber(const std::string &token, const std::string &name, int line) {
    std::string low = Lower(token);
    const bool negative = !low.empty() && low[0] == '-';
    if (!low.empty() && (low[0] == '+' || low[0] == '-'))
        low.erase(0, 1);
    if (!IsNumberText(low))
        throw TableError(name, line, "cannot parse number " + Quote(token));
    if (low == "nan")
        return std::nan("");
    if (low == "inf" || low == "infinity")
        return negative ? -std::numeric_limits<double>::infinity()
                        : std::numeric_limits<double>::infinity();
    std::istringstream is(token);
    is.imbue(std::locale::classic());
    double v = 0.0;
    is >> v;
    // A number too large for a double: the stream stores +-max and sets failbit (C++11);
    // return an infinity, which Build rejects by name (as Python's float() would).
    const double big = std::numeric_limits<double>::max();
    if (!token.empty() && is.fail() && (v == big || v == -big) && (is >> std::ws, is.eof()))
        return v > 0 ? std::numeric_limits<double>::infinity()
                     : -std::numeric_limits<double>::infinity();
    if (token.empty() || is.fail() || (is >> std::ws, !is.eof()))
        throw TableError(name, line, "cannot parse number " + Quote(token));
    return v;
}

}  // namespace detail

// A table from node values: validates (no NaN, infinity or negative value, no density zero
// everywhere, a strictly increasing grid of >= 2 nodes), renormalizes each density by the
// trapezoid rule and builds the CDFs. Throws TableError("NAME: reason").
inline Table MakeTable(std::vector<double> grid,
                       std::array<std::vector<double>, kNumDensities> values,
                       const std::string &name) {
    return detail::Build(std::move(grid), std::move(values), name, detail::SourceLines());
}

// A table from text in either layout of design §2; `name` is used in error messages.
inline Table ParseTable(std::istream &in, const std::string &name) {
    // Collect the non-comment lines as fields, noting the header.
    struct Row {
        int line;
        std::vector<std::string> fields;
    };
    std::vector<Row> rows;
    int header = 0, lineNo = 0;
    std::string raw;
    while (detail::GetLine(in, raw)) {
        ++lineNo;
        if (lineNo == 1 && raw.compare(0, 3, "\xEF\xBB\xBF") == 0)
            raw.erase(0, 3);  // a UTF-8 byte-order mark
        if (const long c = detail::ControlCharacter(raw); c >= 0) {
            char code[8];
            std::snprintf(code, sizeof code, "%04lX", c);
            throw TableError(name, lineNo,
                             std::string("control character U+") + code +
                                 " is not allowed in a table (design §2)");
        }
        const std::string line = detail::Trim(raw);
        if (line.empty() || line[0] == '#')
            continue;
        std::vector<std::string> fields = detail::SplitFields(line);
        if (rows.empty() && header == 0 && detail::Lower(fields[0]).compare(0, 6, "lambda") == 0) {
            header = lineNo;
            if (fields.size() != 1 + kNumDensities)
                throw TableError(name, lineNo,
                                 "header has " + std::to_string(fields.size()) +
                                     " columns, expected 5 (" + kHeader + ")");
            continue;
        }
        rows.push_back(Row{lineNo, std::move(fields)});
    }
    if (in.bad())
        throw TableError(name, lineNo, "read error");
    if (rows.empty())
        throw TableError(name, header > 0 ? header : std::max(1, lineNo),
                         "no data rows (a table needs at least 2 grid nodes)");

    std::vector<double> grid;
    std::array<std::vector<double>, kNumDensities> values;
    detail::SourceLines lines;

    // The headerless 4 x 81 layout: every row wider than the 5 columns of the CSV layout.
    bool wide = header == 0;
    for (const Row &r : rows)
        wide = wide && r.fields.size() > 1 + kNumDensities;
    if (wide) {
        if (rows.size() != kNumDensities)
            throw TableError(name, rows[std::min<std::size_t>(rows.size(), kNumDensities) - 1].line,
                             std::to_string(rows.size()) + " rows of densities, expected 4 "
                             "(headerless 4 x 81 layout)");
        // Shapes first, then numbers (the Python reader's order).
        for (const Row &r : rows)
            if (r.fields.size() != kWideNodes)
                throw TableError(name, r.line,
                                 std::to_string(r.fields.size()) +
                                     " densities, expected 81 (headerless 4 x 81 layout, "
                                     "380..780 nm)");
        for (int k = 0; k < kNumDensities; ++k) {
            const Row &r = rows[k];
            for (const std::string &f : r.fields)
                values[k].push_back(detail::ParseNumber(f, name, r.line));
            lines.value[k].assign(kWideNodes, r.line);
        }
        for (int i = 0; i < kWideNodes; ++i)
            grid.push_back(kWideFirst + kWideStep * i);
        lines.node.assign(kWideNodes, rows[0].line);
        return detail::Build(std::move(grid), std::move(values), name, lines);
    }

    // The commented CSV layout: lambda_nm, pdf0..pdf3 on every row.
    for (const Row &r : rows)
        if (r.fields.size() != 1 + kNumDensities)
            throw TableError(name, r.line,
                             std::to_string(r.fields.size()) + " columns, expected 5 (" +
                                 kHeader + ")");
    for (const Row &r : rows) {
        grid.push_back(detail::ParseNumber(r.fields[0], name, r.line));
        lines.node.push_back(r.line);
        for (int k = 0; k < kNumDensities; ++k) {
            values[k].push_back(detail::ParseNumber(r.fields[1 + k], name, r.line));
            lines.value[k].push_back(r.line);
        }
    }
    return detail::Build(std::move(grid), std::move(values), name, lines);
}

// The bytes of the table file `path`: it must be a regular file (not a directory, device,
// FIFO or socket) of at most kMaxTableBytes (design §2.3). Throws TableError("PATH: reason").
// On POSIX systems the file is opened without blocking (opening a FIFO to read would wait
// for a writer) and the opened descriptor is checked, so a rename between the check and the
// read cannot slip another file in; at most kMaxTableBytes + 1 bytes are ever read.
inline std::string ReadTableFile(const std::string &path) {
    const std::string tooLarge = "larger than 64 MiB, not a table file";
    const std::string notRegular = "not a regular file (a device, FIFO or socket), not a table file";
    std::string bytes;
#if defined(WAVELENGTH_TABLE_POSIX)
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        if (err == ENOENT || err == ENOTDIR)
            throw TableError(path, 0, "no such file");
        if (err == EISDIR)
            throw TableError(path, 0, "is a directory, not a table file");
        throw TableError(path, 0, std::string("cannot read (") + std::strerror(err) + ")");
    }
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st;
    if (::fstat(fd, &st) != 0)
        throw TableError(path, 0, std::string("cannot read (") + std::strerror(errno) + ")");
    if (S_ISDIR(st.st_mode))
        throw TableError(path, 0, "is a directory, not a table file");
    if (!S_ISREG(st.st_mode))
        throw TableError(path, 0, notRegular);
    if (static_cast<unsigned long long>(st.st_size) > kMaxTableBytes)
        throw TableError(path, 0, tooLarge);
    char chunk[1 << 16];
    while (true) {
        const ssize_t got = ::read(fd, chunk, sizeof chunk);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0)
            throw TableError(path, 0, std::string("cannot read (") + std::strerror(errno) + ")");
        if (got == 0)
            break;
        bytes.append(chunk, static_cast<std::size_t>(got));
        if (bytes.size() > kMaxTableBytes)  // the file grew while it was read
            throw TableError(path, 0, tooLarge);
    }
#else
    // Elsewhere: the same checks on the path, then the read.
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status))
        throw TableError(path, 0, "no such file");
    if (fs::is_directory(status))
        throw TableError(path, 0, "is a directory, not a table file");
    if (!fs::is_regular_file(status))
        throw TableError(path, 0, notRegular);
    if (fs::file_size(path, ec) > kMaxTableBytes)
        throw TableError(path, 0, tooLarge);
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw TableError(path, 0, "cannot read (permission denied?)");
    char chunk[1 << 16];
    while (in.read(chunk, sizeof chunk), in.gcount() > 0) {
        bytes.append(chunk, static_cast<std::size_t>(in.gcount()));
        if (bytes.size() > kMaxTableBytes)
            throw TableError(path, 0, tooLarge);
    }
    if (in.bad())
        throw TableError(path, 0, "cannot read the table file");
#endif
    return bytes;
}

// A table from a file in either layout; errors name the file, the line and the reason.
inline Table LoadTable(const std::string &path) {
    std::istringstream in(ReadTableFile(path));
    return ParseTable(in, path);
}

// ---------------------------------------------------------------------------------------
// A table in one flat array, for memory a GPU can read (the std::vectors of Table cannot
// cross to the device). Layout: grid, pdf[0..3], cdf[0..3], n values each.
// ---------------------------------------------------------------------------------------

// The 9 n doubles of `t` in the packed layout; copy them to device-readable memory.
inline std::vector<double> Pack(const Table &t) {
    std::vector<double> out(t.grid);
    for (int k = 0; k < kNumDensities; ++k)
        out.insert(out.end(), t.pdf[k].begin(), t.pdf[k].end());
    for (int k = 0; k < kNumDensities; ++k)
        out.insert(out.end(), t.cdf[k].begin(), t.cdf[k].end());
    return out;
}

// A view of a packed table of n nodes starting at `packed` (wherever it was copied to).
WAVELENGTH_TABLE_HOST_DEVICE inline TableView ViewPacked(const double *packed, int n) {
    TableView v;
    v.grid = packed;
    for (int k = 0; k < kNumDensities; ++k) {
        v.pdf[k] = packed + (1 + k) * n;
        v.cdf[k] = packed + (1 + kNumDensities + k) * n;
    }
    v.n = n;
    return v;
}


// ---------------------------------------------------------------------------------------
// Support: the fix for zero densities.
// ---------------------------------------------------------------------------------------

// (1 - share) p_k + share * uniform over [grid.front(), grid.back()] for every k: a mixture
// with a positive density everywhere on the grid (the defensive mixture of design §1).
// share in [0, 1].
inline Table WithDefensiveMixture(const Table &t, double share) {
    if (!(share >= 0.0 && share <= 1.0))
        throw TableError(t.source, 0,
                         "defensive share must be in [0, 1], got " + detail::FormatNumber(share));
    const double uniform = 1.0 / (t.grid.back() - t.grid.front());
    std::array<std::vector<double>, kNumDensities> values;
    for (int k = 0; k < kNumDensities; ++k) {
        values[k].resize(t.grid.size());
        for (std::size_t i = 0; i < t.grid.size(); ++i)
            values[k][i] = (1.0 - share) * t.pdf[k][i] + share * uniform;
    }
    return MakeTable(t.grid, std::move(values), t.source);
}

// The intervals [a, b] (nm, a < b, merged, increasing) inside the grid's range where the
// mixture density is zero: wherever all four densities vanish at two neighbouring nodes.
// Isolated zeros (a single node) have measure zero and are not listed. Outside
// [grid.front(), grid.back()] the mixture is zero too; a renderer checks that range itself.
inline std::vector<std::pair<double, double>> ZeroMixtureIntervals(const Table &t) {
    const std::size_t n = t.grid.size();
    auto zeroAt = [&](std::size_t i) {
        for (int k = 0; k < kNumDensities; ++k)
            if (t.pdf[k][i] > 0.0)
                return false;
        return true;
    };
    std::vector<std::pair<double, double>> out;
    for (std::size_t i = 0; i + 1 < n; ++i) {
        if (!(zeroAt(i) && zeroAt(i + 1)))
            continue;
        if (!out.empty() && out.back().second == t.grid[i])
            out.back().second = t.grid[i + 1];
        else
            out.emplace_back(t.grid[i], t.grid[i + 1]);
    }
    return out;
}

// ---------------------------------------------------------------------------------------
// Coverage: emission a table never samples (design §1.5).
// ---------------------------------------------------------------------------------------
//
// A path carries only wavelengths where the mixture density is positive; where a light emits
// but the mixture is zero, that light is missing from the image however many samples are
// taken. Two places can hide such emission: a gap inside the table's range (the defensive
// mixture removes it) and the range outside [lambda_0, lambda_M] (only a wider grid helps).
// The measure, the thresholds and the warnings live here so that every renderer built on
// this header warns by one rule; wavelength_pdf.coverage is the optimizer's `show`.

// Coverage is measured over the colour-matching functions' range [nm], by the midpoint rule
// with this step: it sees a spectrum's 1 nm lines and the edges of 5 nm table segments.
constexpr double kCoverageFirstNm = 360.0, kCoverageLastNm = 830.0, kCoverageStepNm = 0.1;
// Emission outside the table's range below these fractions is not worth a warning: a table on
// the default 380..780 nm grid misses about 1e-5 of the luminance of a lamp with a flat floor
// (the CMFs are tiny at the ends); 1e-3 of a tristimulus value is about 0.1 CIEDE2000.
constexpr double kOutsideLuminanceWarnFraction = 1e-4;
constexpr double kOutsideTristimulusWarnFraction = 1e-3;

// Where one emitter's light falls that a table does not sample. Fractions are of the
// emitter's tristimulus integrals over kCoverageFirstNm..kCoverageLastNm.
struct Coverage {
    std::vector<std::pair<double, double>> gaps;     // zero-mixture stretches [nm] where it emits
    double gapLuminanceFraction = 0;                 // of its luminance (Y) inside them
    std::vector<std::pair<double, double>> outside;  // parts of the CMF range outside the grid
    double outsideLuminanceFraction = 0;             // of its luminance (Y) there
    double outsideTristimulusFraction = 0;           // the largest over X, Y and Z there
};

// The coverage of an emitter by a table whose grid spans [lo, hi] with zero-mixture intervals
// `gaps` (ZeroMixtureIntervals). `emission(lambda)` is the emitter's spectrum and
// `cmfs(lambda, xyz)` stores the colour-matching functions in xyz[3]: the renderer's own, so
// that the header needs neither.
template <typename Emission, typename Cmfs>
Coverage MeasureCoverage(const std::vector<std::pair<double, double>> &gaps, double lo,
                         double hi, const Emission &emission, const Cmfs &cmfs) {
    Coverage c;
    double total[3] = {0, 0, 0}, outside[3] = {0, 0, 0}, inGapsY = 0;
    std::vector<bool> gapEmits(gaps.size(), false);
    bool emitsBelow = false, emitsAbove = false;
    const long n = std::lround((kCoverageLastNm - kCoverageFirstNm) / kCoverageStepNm);
    for (long i = 0; i < n; ++i) {
        const double lambda = kCoverageFirstNm + (double(i) + 0.5) * kCoverageStepNm;
        const double e = emission(lambda);
        if (!(e > 0))
            continue;
        double xyz[3];
        cmfs(lambda, xyz);
        const double w[3] = {e * xyz[0], e * xyz[1], e * xyz[2]};
        for (int j = 0; j < 3; ++j)
            total[j] += w[j];
        if (lambda < lo || lambda > hi) {
            (lambda < lo ? emitsBelow : emitsAbove) = true;
            for (int j = 0; j < 3; ++j)
                outside[j] += w[j];
            continue;
        }
        for (std::size_t g = 0; g < gaps.size(); ++g)
            if (lambda > gaps[g].first && lambda < gaps[g].second) {
                gapEmits[g] = true;
                inGapsY += w[1];
            }
    }
    for (std::size_t g = 0; g < gaps.size(); ++g)
        if (gapEmits[g])
            c.gaps.push_back(gaps[g]);
    if (emitsBelow)
        c.outside.emplace_back(kCoverageFirstNm, lo);
    if (emitsAbove)
        c.outside.emplace_back(hi, kCoverageLastNm);
    if (total[1] > 0) {
        c.gapLuminanceFraction = inGapsY / total[1];
        c.outsideLuminanceFraction = outside[1] / total[1];
    }
    for (int j = 0; j < 3; ++j)
        if (total[j] > 0)
            c.outsideTristimulusFraction = std::max(c.outsideTristimulusFraction, outside[j] / total[j]);
    return c;
}

// The same for a table (its grid's range and its zero-mixture intervals).
template <typename Emission, typename Cmfs>
Coverage MeasureCoverage(const Table &t, const Emission &emission, const Cmfs &cmfs) {
    return MeasureCoverage(ZeroMixtureIntervals(t), t.grid.front(), t.grid.back(), emission, cmfs);
}

// The warnings for one emitter (design §1.5), none when it is covered: emission in a gap
// always, emission outside the range above the thresholds. `light` names it in the text
// ("this light" after the caller's FILE:LINE:COL, else "a light"); `lo`, `hi` are the
// table's range, `table` its description for the end of the text; `otherFix`, when not
// empty, is offered after "extend the table's grid" (a renderer's own option).
inline std::vector<std::string> CoverageWarnings(const Coverage &c, const std::string &light,
                                                 double lo, double hi, const std::string &table,
                                                 const std::string &otherFix = "") {
    auto stream = [] {
        std::ostringstream s;
        s.imbue(std::locale::classic());
        return s;
    };
    auto percent = [&](double f) {
        std::ostringstream s = stream();
        s << std::setprecision(3) << 100 * f << "%";
        return s.str();
    };
    auto intervals = [&](const std::vector<std::pair<double, double>> &v) {
        std::ostringstream s = stream();
        for (std::size_t i = 0; i < v.size(); ++i) {
            if (i)
                s << (i + 1 == v.size() ? " and " : ", ");
            s << "[" << v[i].first << ", " << v[i].second << "]";
        }
        s << " nm";
        return s.str();
    };
    std::vector<std::string> out;
    if (!c.gaps.empty()) {
        std::ostringstream m = stream();
        m << "the wavelength sampling density is zero on " << intervals(c.gaps) << ", where "
          << light << " emits (" << percent(c.gapLuminanceFraction) << " of its luminance): "
          << "paths never carry those wavelengths, so the image is biased; mix a uniform share "
          << "into the table with --wavelength-pdf-defensive 0.01 [" << table << "]";
        out.push_back(m.str());
    }
    if (!c.outside.empty() && (c.outsideLuminanceFraction > kOutsideLuminanceWarnFraction ||
                               c.outsideTristimulusFraction > kOutsideTristimulusWarnFraction)) {
        std::ostringstream m = stream();
        m << light << " emits on " << intervals(c.outside) << ", outside the range of the "
          << "wavelength table [" << lo << ", " << hi << "] nm, where paths never carry "
          << "wavelengths: the image misses " << percent(c.outsideLuminanceFraction)
          << " of its luminance (up to " << percent(c.outsideTristimulusFraction)
          << " of X, Y or Z). --wavelength-pdf-defensive only covers the table's range; extend "
          << "the table's grid to 360..830 nm" << (otherFix.empty() ? "" : ", or " + otherFix)
          << " [" << table << "]";
        out.push_back(m.str());
    }
    return out;
}

// ---------------------------------------------------------------------------------------
// Stratified tables without an optimizer: four equal-mass bands of a weight (design §1.7).
// ---------------------------------------------------------------------------------------

// Width of the step over which a density hands over to the next at a cut [nm].
constexpr double kCutWidthNm = 0.01;

namespace detail {

// numpy.interp(x, xp, fp, left, right) for strictly increasing xp (the same arithmetic, so
// that a table built here has the bits of the Python reference's wherever the compiler keeps
// the operations apart).
inline double Interp(const std::vector<double> &xp, const std::vector<double> &fp, double x,
                     double left, double right) {
    const std::size_t n = xp.size();
    if (x < xp.front())
        return left;
    if (x > xp.back())
        return right;
    const std::size_t j = std::size_t(std::upper_bound(xp.begin(), xp.end(), x) - xp.begin()) - 1;
    if (j + 1 >= n || xp[j] == x)
        return fp[j];
    const double dy = fp[j + 1] - fp[j];
    const double dx = xp[j + 1] - xp[j];
    const double slope = dy / dx;
    const double t = x - xp[j];
    const double rise = slope * t;
    return rise + fp[j];
}

// Trapezoid-rule integral of v over x, summed left to right.
inline double Trapezoid(const std::vector<double> &x, const std::vector<double> &v) {
    double sum = 0.0;
    for (std::size_t i = 0; i + 1 < x.size(); ++i) {
        const double s = v[i + 1] + v[i];
        const double mean = 0.5 * s;
        const double width = x[i + 1] - x[i];
        const double area = mean * width;
        sum = sum + area;
    }
    return sum;
}

// g(a) = Q(a) + q(a) d(a) / 2 inside segment i at offset s from x[i] (design §1.7): the
// mass of q up to a plus the half of the hand-over step that stays with the band before
// the cut. One operation per statement, in the Python reference's order.
inline double CutMass(double massI, double q0, double slope, double h, double s) {
    const double halfSlope = 0.5 * slope;
    const double a = halfSlope * s;
    const double b = q0 + a;
    const double integral = b * s;
    const double left = massI + integral;
    const double rise = slope * s;
    const double qs = q0 + rise;
    const double rest = h - s;
    const double halfRest = 0.5 * rest;
    const double d = kCutWidthNm < halfRest ? kCutWidthNm : halfRest;
    const double stepMass = qs * d;
    const double half = stepMass / 2.0;
    return left + half;
}

}  // namespace detail

// Four densities that cut the weight q into bands of equal mass (design §1.7; the Python
// reference is wavelength_pdf.stratified.equal_mass_table, pinned to this by the test
// vectors wavelength_table/tests/data/equal-mass-*.csv).
//
// x: nodes [nm], finite and strictly increasing, at least 2; q: the weight at the nodes,
// finite and >= 0, linear between them, with a positive integral. Only q's shape matters:
// it is scaled to a peak of 1, and values below 1e-300 of the peak count as 0.
//
// The table's grid is x plus, at each cut a_k (k = 1..3), the nodes a_k and a_k + d_k with
// d_k = min(0.01 nm, half the gap to the next node of x) (shortened to half the distance to
// the next cut when two cuts are closer than that). Density k is q on its band
// [a_k + d_k, a_{k+1}] (band 0 starts at x.front(), band 3 ends at x.back()) and 0 at every
// other node; density k - 1 falls to 0 over [a_k, a_k + d_k] while density k rises. The cuts
// solve g(a_k) = k M / 4, g(a) = Q(a) + q(a) d(a) / 2 (Q the integral of q up to a, M its
// total), so every density carries M / 4 before normalizing, and the mixture
// (1/4) sum_k p_k equals q / M wherever q is linear between the nodes: the table
// importance-samples q and stratifies it into four bands driven by one u. A band without
// mass (a cut on a jump of g) takes q itself.
//
// Throws TableError("NAME: reason") for fewer than 2 nodes or a q of another length, nodes
// that are not finite or not strictly increasing, a negative or non-finite q, or a q
// without mass.
inline Table EqualMassTable(const std::vector<double> &x, const std::vector<double> &qIn,
                            const std::string &name = "equal-mass table") {
    const std::size_t n = x.size();
    if (n < 2 || qIn.size() != n)
        throw TableError(name, 0,
                         "need at least 2 nodes and one weight per node (got " +
                             std::to_string(n) + " nodes and " + std::to_string(qIn.size()) +
                             " weights)");
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(x[i]) || (i > 0 && !(x[i] > x[i - 1])))
            throw TableError(name, 0,
                             "nodes must be finite and strictly increasing (node " +
                                 std::to_string(i) + " is " + detail::FormatNumber(x[i]) +
                                 " nm)");
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(qIn[i]) || qIn[i] < 0)
            throw TableError(name, 0,
                             "the weight must be finite and non-negative (it is " +
                                 detail::FormatNumber(qIn[i]) + " at " +
                                 detail::FormatNumber(x[i]) + " nm)");
    // Scaled to a peak of 1; values below 1e-300 of it read as 0 (design §3.3): a density
    // normalized from them would underflow to 0 where q is not 0.
    std::vector<double> q(qIn);
    const double peak = *std::max_element(q.begin(), q.end());
    if (peak > 0)
        for (double &v : q) {
            v = v / peak;
            if (v < 1e-300)
                v = 0.0;
        }
    std::vector<double> h(n - 1), mass(n, 0.0);
    for (std::size_t i = 0; i + 1 < n; ++i) {
        h[i] = x[i + 1] - x[i];
        const double s = q[i + 1] + q[i];
        const double mean = 0.5 * s;
        const double seg = mean * h[i];
        mass[i + 1] = mass[i] + seg;
    }
    const double total = mass[n - 1];
    if (!(total > 0) || !std::isfinite(total))
        throw TableError(name, 0,
                         "the weight has no mass over " + detail::FormatDigits(x.front(), 6) +
                             "-" + detail::FormatDigits(x.back(), 6) + " nm");

    // The cuts: g jumps up at a node and increases inside a segment, so the segment is found
    // among the node masses and the cut by bisection in it (a target in a jump: the node).
    std::array<double, kNumDensities - 1> cuts{};
    for (int k = 1; k < kNumDensities; ++k) {
        const double scaled = total * double(k);
        const double t = scaled / double(kNumDensities);
        std::size_t i = std::size_t(std::upper_bound(mass.begin(), mass.end(), t) - mass.begin());
        i = i == 0 ? 0 : i - 1;
        if (i > n - 2)
            i = n - 2;
        const double halfGap = 0.5 * h[i];
        const double d0 = kCutWidthNm < halfGap ? kCutWidthNm : halfGap;
        const double stepMass = q[i] * d0;
        const double gRight = mass[i] + stepMass / 2.0;  // g just right of x[i]
        if (t <= gRight) {
            cuts[k - 1] = x[i];
            continue;
        }
        const double dq = q[i + 1] - q[i];
        const double slope = dq / h[i];
        double lo = 0.0, hi = h[i];
        while (true) {
            const double sum = lo + hi;
            const double s = 0.5 * sum;
            if (s <= lo || s >= hi)
                break;
            if (detail::CutMass(mass[i], q[i], slope, h[i], s) < t)
                lo = s;
            else
                hi = s;
        }
        cuts[k - 1] = x[i] + hi;
    }
    // Where each band starts: after the hand-over step at its cut.
    std::array<double, kNumDensities> starts{}, ends{};
    starts[0] = x.front();
    for (int k = 0; k < kNumDensities - 1; ++k) {
        const double a = cuts[k];
        const std::size_t j = std::size_t(std::upper_bound(x.begin(), x.end(), a) - x.begin());
        double d = 0.0;
        if (j < n) {
            const double half = 0.5 * (x[j] - a);
            d = kCutWidthNm < half ? kCutWidthNm : half;
        }
        if (k + 1 < kNumDensities - 1 && cuts[k + 1] > a) {
            const double half = 0.5 * (cuts[k + 1] - a);
            d = d < half ? d : half;
        }
        starts[k + 1] = a + d > a ? a + d : a;
        ends[k] = a;
    }
    ends[kNumDensities - 1] = x.back();

    std::vector<double> grid(x);
    grid.insert(grid.end(), cuts.begin(), cuts.end());
    grid.insert(grid.end(), starts.begin(), starts.end());
    std::sort(grid.begin(), grid.end());
    grid.erase(std::unique(grid.begin(), grid.end()), grid.end());
    std::vector<double> qg(grid.size());
    for (std::size_t i = 0; i < grid.size(); ++i)
        qg[i] = detail::Interp(x, q, grid[i], q.front(), q.back());
    std::array<std::vector<double>, kNumDensities> values;
    for (int k = 0; k < kNumDensities; ++k) {
        std::vector<double> p(grid.size(), 0.0);
        for (std::size_t i = 0; i < grid.size(); ++i)
            if (grid[i] >= starts[k] && grid[i] <= ends[k])
                p[i] = qg[i];
        // A band without mass takes q itself (MakeTable normalizes every density).
        values[k] = detail::Trapezoid(grid, p) > 0 ? std::move(p) : qg;
    }
    return MakeTable(std::move(grid), std::move(values), name);
}

// The nodes and values of q = s * w on [lo, hi] (wavelength_pdf.stratified.weighted_spectrum):
// the union of lo, hi, the spectrum's nodes and the weight's nodes inside [lo, hi], with s and w
// each linear between their own nodes and 0 outside them. An empty weight means w = 1 (and
// adds no nodes): the spectrum alone, exactly. Throws TableError(name, ...) for a range that
// is not finite with lo < hi, or nodes that are not strictly increasing.
struct WeightedNodes {
    std::vector<double> x, q;
};
inline WeightedNodes WeightedSpectrum(const std::vector<double> &spectrumNodes,
                                      const std::vector<double> &spectrumValues,
                                      const std::vector<double> &weightNodes,
                                      const std::vector<double> &weightValues, double lo,
                                      double hi, const std::string &name = "spectrum") {
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi))
        throw TableError(name, 0,
                         "the range must be finite with lo < hi, got " + detail::FormatNumber(lo) +
                             "-" + detail::FormatNumber(hi) + " nm");
    if (spectrumNodes.empty())
        throw TableError(name, 0, "spectrum: no nodes");
    auto check = [&](const std::vector<double> &nodes, const std::vector<double> &values,
                     const char *what) {
        if (nodes.size() != values.size())
            throw TableError(name, 0, std::string(what) + ": need one value per node");
        for (std::size_t i = 0; i < nodes.size(); ++i)
            if (!std::isfinite(nodes[i]) || (i > 0 && !(nodes[i] > nodes[i - 1])))
                throw TableError(name, 0,
                                 std::string(what) + ": nodes must be finite and strictly increasing");
    };
    check(spectrumNodes, spectrumValues, "spectrum");
    check(weightNodes, weightValues, "weight");
    WeightedNodes out;
    out.x = {lo, hi};
    for (double v : spectrumNodes)
        if (v >= lo && v <= hi)
            out.x.push_back(v);
    for (double v : weightNodes)
        if (v >= lo && v <= hi)
            out.x.push_back(v);
    std::sort(out.x.begin(), out.x.end());
    out.x.erase(std::unique(out.x.begin(), out.x.end()), out.x.end());
    out.q.resize(out.x.size());
    for (std::size_t i = 0; i < out.x.size(); ++i) {
        double v = detail::Interp(spectrumNodes, spectrumValues, out.x[i], 0.0, 0.0);
        if (!weightNodes.empty())
            v = v * detail::Interp(weightNodes, weightValues, out.x[i], 0.0, 0.0);
        out.q[i] = v;
    }
    return out;
}

// Stratified sampling of a spectrum times a weight on [lo, hi] as a table:
// EqualMassTable of WeightedSpectrum (wavelength_pdf.stratified.stratified_table). With the
// spectrum alone (empty weight) it is stratified sampling of the lamp; with the luminance
// curve or xbar + ybar + zbar as the weight, of its luminance or its tristimulus sum.
inline Table StratifiedTable(const std::vector<double> &spectrumNodes,
                             const std::vector<double> &spectrumValues,
                             const std::vector<double> &weightNodes,
                             const std::vector<double> &weightValues, double lo, double hi,
                             const std::string &name = "spectrum") {
    const WeightedNodes w =
        WeightedSpectrum(spectrumNodes, spectrumValues, weightNodes, weightValues, lo, hi, name);
    return EqualMassTable(w.x, w.q, name);
}

}  // namespace wavelength_table

#endif  // WAVELENGTH_TABLE_H
