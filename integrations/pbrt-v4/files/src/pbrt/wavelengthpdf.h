// wavelengthpdf.h -- `--wavelength-pdf TABLE.csv` for pbrt-v4 (added by the wavelength-pdf
// patch, integrations/pbrt-v4/ of the spectral wavelength-table toolkit; Apache-2.0).
//
// Camera paths draw their four wavelengths from a wavelength table instead of the film's
// density: lambda_k = F_k^-1(u) for the table's four densities, one u per path, each carrying
// the mixture density (1/4) sum_k p_k(lambda_k) (the balance heuristic, design §1). The
// table lives in one flat array (wavelength_table::Pack) that the CPU and, in GPU builds,
// the device read through a TableView held in a global (a __constant__ on the device).
//
// Only the files that sample wavelengths or terminate secondary wavelengths include this
// header, so that applying the patch recompiles few files. Without --wavelength-pdf (and
// without --wavelength-sampling emission, which builds such a table from the scene's lights)
// every function here does exactly what upstream pbrt-v4 does.
#ifndef PBRT_WAVELENGTHPDF_H
#define PBRT_WAVELENGTHPDF_H

#include <pbrt/pbrt.h>

#include <pbrt/util/hash.h>
#include <pbrt/util/pstd.h>
#include <pbrt/util/spectrum.h>
#include <pbrt/util/vecmath.h>

#define WAVELENGTH_TABLE_HOST_DEVICE PBRT_CPU_GPU
#include <pbrt/wavelength_table.h>

#include <cstring>
#include <string>
#include <type_traits>

namespace pbrt {

static_assert(NSpectrumSamples == wavelength_table::kNumDensities,
              "--wavelength-pdf needs NSpectrumSamples == 4 (one table density per wavelength)");

// What the samplers read: whether a table is in use, and the table's arrays.
struct WavelengthTableState {
    bool active = false;
    wavelength_table::TableView view = {};
};

extern WavelengthTableState WavelengthTableCPU;
#if defined(PBRT_BUILD_GPU_RENDERER) && defined(__CUDACC__)
extern __constant__ WavelengthTableState WavelengthTableGPU;
#endif

PBRT_CPU_GPU inline const WavelengthTableState &GetWavelengthTable() {
#if defined(PBRT_IS_GPU_CODE)
    return WavelengthTableGPU;
#else
    return WavelengthTableCPU;
#endif
}

// Reads and validates the table (design §2; a bad table prints "pbrt: FILE:LINE: reason"
// and exits with status 1), mixes in the defensive share (the text of
// --wavelength-pdf-defensive, empty for none), and makes it visible to the CPU and, with
// --gpu, to the device. An empty path leaves upstream's sampling in place.
// `sampling` is --wavelength-sampling ("", "visible" or "emission") and `emissionWeight`
// --emission-weight ("", "spd", "luminance" or "xyz"); "emission" asks for the table that
// InitEmissionWavelengthTable builds once the lights exist. Bad combinations exit with 1.
void InitWavelengthTable(const std::string &path, const std::string &defensiveShare,
                         const std::string &sampling, const std::string &emissionWeight);

// Warns (once per light directive) where the table's mixture density is zero but the light
// of `lightName` with `params` emits: an interior gap, or more than 1e-4 of its luminance
// (1e-3 of X, Y or Z) outside the table's range. A no-op without a table.
class ParameterDictionary;
void WarnUnsampledEmission(const std::string &lightName, const ParameterDictionary &params,
                           const FileLoc *loc);

// --wavelength-sampling emission (design §1.7): the scene's emitted spectral power
// Phi(lambda) = sum over lights of Light::Phi (upstream's light power), times the weight,
// cut into four equal-mass densities (wavelength_table::EqualMassTable) and sampled as a
// --wavelength-pdf table is. Upstream's lights hold their spectra at whole nanometres
// (DenselySampledSpectrum: the value of the nearest nm), so Phi is taken at 360, 361, ...,
// 830 nm and the table is that step function (0.002 nm hand-overs at the half-nanometres).
// Lights whose emission is an RGB image (image infinite, portal, projection and image area
// lights) count as their colour space's illuminant times their power, measured once at four
// wavelengths (Phi over every nanometre would read the whole image 118 times).
//
// The Note* functions remember where each light was defined (for error messages) while the
// scene is parsed and its lights created; all of them are no-ops without
// --wavelength-sampling emission.
class Light;
void NoteLightSource(const std::string &lightName, const ParameterDictionary &params,
                     const FileLoc *loc);                    // in BasicScene::AddLight order
void NoteLightSourceCreated(size_t index, const Light &light);  // the index-th AddLight's light
void NoteAreaLight(const Light &light, const ParameterDictionary &params, const FileLoc *loc);
// Builds the table from the lights (after Light::Preprocess, which infinite lights need) and
// installs it for the CPU and the GPU. A light whose power is not finite (a blackbody of
// 0 K, an overflowing scale) or a scene whose lights emit nothing between 360 and 830 nm
// prints "pbrt: FILE:LINE:COL: reason" naming the light and exits with status 1; a scene
// without lights keeps upstream's sampling (with a warning).
void InitEmissionWavelengthTable(const Light *lights, size_t count);

// SampledWavelengths keeps lambda and pdf private and has no factory for arbitrary pdfs;
// this struct has its layout (util/spectrum.h: `pstd::array<Float, NSpectrumSamples> lambda,
// pdf;`, checked by the patch tool), and InitWavelengthTable checks the round trip once.
struct SampledWavelengthsLayout {
    pstd::array<Float, NSpectrumSamples> lambda, pdf;
};
static_assert(sizeof(SampledWavelengthsLayout) == sizeof(SampledWavelengths) &&
                  std::is_trivially_copyable_v<SampledWavelengths> &&
                  std::is_standard_layout_v<SampledWavelengths>,
              "SampledWavelengths no longer has the layout this patch relies on");

PBRT_CPU_GPU inline SampledWavelengths ToSampledWavelengths(const SampledWavelengthsLayout &l) {
    SampledWavelengths swl;
    std::memcpy(static_cast<void *>(&swl), &l, sizeof(swl));
    return swl;
}

PBRT_CPU_GPU inline SampledWavelengthsLayout FromSampledWavelengths(const SampledWavelengths &s) {
    SampledWavelengthsLayout l;
    std::memcpy(&l, static_cast<const void *>(&s), sizeof(l));
    return l;
}

// Four wavelengths from one u: lambda_k = F_k^-1(u), pdf = the mixture density there.
PBRT_CPU_GPU inline SampledWavelengths SampleTableWavelengths(Float u) {
    double lambda[NSpectrumSamples], pdf[NSpectrumSamples];
    wavelength_table::kernel::SampleFour(GetWavelengthTable().view, double(u), lambda, pdf);
    SampledWavelengthsLayout l;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        l.lambda[i] = Float(lambda[i]);
        l.pdf[i] = Float(pdf[i]);
    }
    return ToSampledWavelengths(l);
}

// The wavelengths of a camera path: the table's when one is given, else the film's own.
template <typename FilmT>
PBRT_CPU_GPU inline SampledWavelengths SampleCameraWavelengths(const FilmT &film, Float u) {
    if (GetWavelengthTable().active)
        return SampleTableWavelengths(u);
    return film.SampleWavelengths(u);
}

// Whether the secondary wavelengths were terminated: upstream's test (slots 1..3 have
// pdf 0), or, with a table, at most one slot with a non-zero pdf (the kept one).
PBRT_CPU_GPU inline bool SecondaryWavelengthsTerminated(const SampledWavelengths &lambda) {
    if (!GetWavelengthTable().active)
        return lambda.SecondaryTerminated();
    SampledSpectrum pdf = lambda.PDF();
    int nonZero = 0;
    for (int i = 0; i < NSpectrumSamples; ++i)
        nonZero += pdf[i] != 0;
    return nonZero <= 1;
}

// The slot that survived termination (0 without a table, where upstream keeps slot 0).
PBRT_CPU_GPU inline int KeptWavelengthSlot(const SampledWavelengths &lambda) {
    SampledSpectrum pdf = lambda.PDF();
    for (int i = 0; i < NSpectrumSamples; ++i)
        if (pdf[i] != 0)
            return i;
    return 0;
}

// Keep slot `kept` alone, weighted by NSpectrumSamples: its pdf is divided by 4, the others
// become 0, and every slot's wavelength becomes the kept one, so code that reads lambda[0]
// after termination (the dielectrics' eta) sees the kept wavelength, while the spectra
// carried so far stay aligned with their slots. Already terminated: unchanged.
PBRT_CPU_GPU inline void TerminateSecondaryWavelengthsAt(SampledWavelengths &lambda, int kept) {
    if (!GetWavelengthTable().active) {
        lambda.TerminateSecondary();
        return;
    }
    if (SecondaryWavelengthsTerminated(lambda))
        return;
    SampledWavelengthsLayout l = FromSampledWavelengths(lambda);
    const Float keptLambda = l.lambda[kept], keptPdf = l.pdf[kept] / NSpectrumSamples;
    for (int i = 0; i < NSpectrumSamples; ++i) {
        l.lambda[i] = keptLambda;
        l.pdf[i] = i == kept ? keptPdf : Float(0);
    }
    lambda = ToSampledWavelengths(l);
}

// The dispersion rule (design §1): where upstream calls lambda.TerminateSecondary(), keep
// one of the four wavelengths chosen uniformly with a fresh random number and weight it by
// 4. Always keeping slot 0, as upstream does, is only right when all four wavelengths share
// one marginal density; a table's lambda_0 follows p_0 alone. The random number is a hash
// of the scattering point, the outgoing direction and the four wavelengths, as upstream's
// MixMaterial chooses its material (the material code has no sampler, on the GPU neither).
// Without a table this is upstream's TerminateSecondary().
PBRT_CPU_GPU inline void TerminateSecondaryWavelengths(SampledWavelengths &lambda, Point3f p,
                                                       Vector3f w) {
    if (!GetWavelengthTable().active) {
        lambda.TerminateSecondary();
        return;
    }
    if (SecondaryWavelengthsTerminated(lambda))
        return;
    const Float u = HashFloat(p, w, lambda[0], lambda[1], lambda[2], lambda[3]);
    const int kept = int(u * NSpectrumSamples);
    TerminateSecondaryWavelengthsAt(lambda, kept < NSpectrumSamples ? kept : NSpectrumSamples - 1);
}

}  // namespace pbrt

#endif  // PBRT_WAVELENGTHPDF_H
