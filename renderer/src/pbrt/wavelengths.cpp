#include <pbrt/wavelengths.h>

#include <pbrt/util/hash.h>

#include <wavelength_table.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace pbrt {

std::string VisibleWavelengthSampler::Description() const {
    return "visible (pbrt-v4: density ~ sech^2(0.0072 (lambda - 538)) on 360..830 nm, 4 stratified)";
}

std::string UniformWavelengthSampler::Description() const {
    std::ostringstream s;
    s << "uniform on " << lmin << ".." << lmax << " nm, 4 stratified";
    return s.str();
}

// ---- Table-driven sampling -----------------------------------------------------------
static_assert(NSpectrumSamples == wavelength_table::kNumDensities,
              "a wavelength table holds one density per wavelength of a path");

SampledWavelengths TableWavelengthSampler::Sample(Float u) const {
    double lambda[NSpectrumSamples], pdf[NSpectrumSamples];
    wavelength_table::SampleFour(*table, u, lambda, pdf);
    // The table is kept in double precision; the path carries Float.
    Float l[NSpectrumSamples], p[NSpectrumSamples];
    for (int i = 0; i < NSpectrumSamples; ++i) {
        l[i] = Float(lambda[i]);
        p[i] = Float(pdf[i]);
    }
    return SampledWavelengths::FromArrays(l, p);
}

Float TableWavelengthSampler::PDF(Float lambda) const {
    return Float(wavelength_table::MixturePdf(*table, lambda));
}

Float TableWavelengthSampler::MinLambda() const { return Float(table->grid.front()); }
Float TableWavelengthSampler::MaxLambda() const { return Float(table->grid.back()); }

std::string TableWavelengthSampler::Description() const {
    std::ostringstream s;
    if (!guided.empty()) {
        s << "guided table " << guided << " (" << table->grid.size() << " nodes, "
          << table->grid.front() << ".." << table->grid.back() << " nm)";
        return s.str();
    }
    if (!emissionWeight.empty()) {
        s << "emission (the scene's emitted power"
          << (emissionWeight == "luminance" ? " times ybar"
              : emissionWeight == "xyz"     ? " times xbar + ybar + zbar"
                                            : "")
          << " in four equal-mass bands: " << table->grid.size() << " nodes, "
          << table->grid.front() << ".." << table->grid.back() << " nm, built in "
          << std::setprecision(3) << buildSeconds * 1e3 << " ms)";
        return s.str();
    }
    s << "table " << table->source << " (" << table->grid.size() << " nodes, "
      << table->grid.front() << ".." << table->grid.back() << " nm";
    if (share > 0) s << ", defensive share " << share;
    s << ")";
    return s.str();
}

WavelengthSampler WavelengthSampler::FromTable(const std::string &path, Float defensiveShare) {
    if (!(defensiveShare >= 0 && defensiveShare <= 1)) {
        std::ostringstream s;
        s << "the defensive share must be in [0, 1], got " << defensiveShare;
        throw PbrtError(s.str());
    }
    try {
        // The bytes are read once, hashed for the image's provenance and parsed, so the
        // hash is of exactly the table rendered with. ReadTableFile takes regular files of
        // at most 64 MiB only (design §2.3): a device or a FIFO is refused without a read.
        const std::string bytes = wavelength_table::ReadTableFile(path);
        std::istringstream text(bytes);
        wavelength_table::Table t = wavelength_table::ParseTable(text, path);
        if (defensiveShare > 0) t = wavelength_table::WithDefensiveMixture(t, defensiveShare);
        TableWavelengthSampler sampler;
        sampler.table = std::make_shared<const wavelength_table::Table>(std::move(t));
        sampler.share = defensiveShare;
        sampler.file = path;
        sampler.sha256 = SHA256Hex(bytes);
        return WavelengthSampler(std::move(sampler));
    } catch (const wavelength_table::TableError &e) {
        // Already "FILE:LINE: reason" (or "FILE: reason" for a missing file).
        throw PbrtError(e.what());
    }
}

WavelengthSampler WavelengthSampler::FromEmission(std::shared_ptr<const wavelength_table::Table> table,
                                                  const std::string &weight, double buildSeconds) {
    TableWavelengthSampler t;
    t.table = std::move(table);
    t.emissionWeight = weight;
    t.buildSeconds = buildSeconds;
    return WavelengthSampler(std::move(t));
}

WavelengthSampler WavelengthSampler::FromGuided(std::shared_ptr<const wavelength_table::Table> table,
                                                const std::string &label) {
    TableWavelengthSampler t;
    t.table = std::move(table);
    t.guided = label;
    return WavelengthSampler(std::move(t));
}

WavelengthSampler WavelengthSampler::Visible() { return WavelengthSampler(VisibleWavelengthSampler{}); }

WavelengthSampler WavelengthSampler::Uniform(Float lmin, Float lmax) {
    if (!(std::isfinite(lmin) && std::isfinite(lmax) && lmin > 0 && lmin < lmax)) {
        std::ostringstream s;
        s << "uniform wavelength sampling needs 0 < min < max, got [" << lmin << ", " << lmax << "] nm";
        throw PbrtError(s.str());
    }
    return WavelengthSampler(UniformWavelengthSampler{lmin, lmax});
}

SampledWavelengths WavelengthSampler::Sample(Float u) const {
    return std::visit([u](const auto &s) { return s.Sample(u); }, impl);
}

Float WavelengthSampler::PDF(Float lambda) const {
    return std::visit([lambda](const auto &s) { return s.PDF(lambda); }, impl);
}

std::string WavelengthSampler::Description() const {
    return std::visit([](const auto &s) { return s.Description(); }, impl);
}

Float WavelengthSampler::MinLambda() const {
    return std::visit([](const auto &s) { return s.MinLambda(); }, impl);
}

Float WavelengthSampler::MaxLambda() const {
    return std::visit([](const auto &s) { return s.MaxLambda(); }, impl);
}

bool WavelengthSampler::IsTable() const {
    return std::holds_alternative<TableWavelengthSampler>(impl);
}

std::string WavelengthSampler::Name() const {
    if (std::holds_alternative<VisibleWavelengthSampler>(impl)) return "visible";
    if (std::holds_alternative<UniformWavelengthSampler>(impl)) return "uniform";
    const TableWavelengthSampler &t = std::get<TableWavelengthSampler>(impl);
    if (!t.guided.empty()) return "guided";
    return t.emissionWeight.empty() ? "table" : "emission";
}

std::vector<std::pair<Float, Float>> WavelengthSampler::ZeroDensityIntervals() const {
    std::vector<std::pair<Float, Float>> out;
    if (const auto *t = std::get_if<TableWavelengthSampler>(&impl))
        for (auto [a, b] : wavelength_table::ZeroMixtureIntervals(*t->table))
            out.emplace_back(Float(a), Float(b));
    return out;
}

}  // namespace pbrt
