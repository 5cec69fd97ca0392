"""The ``wavelength_table`` texture: a sensor's ``srf`` that samples wavelengths from a table.

Why a texture used as the sensor's ``srf``, not a sensor of its own: every Mitsuba 3 sensor
(perspective, thin lens, radiance meter, ...) asks its ``srf`` texture for the wavelengths of
a path (``Sensor::sample_wavelengths`` returns ``srf.sample_spectrum(si, shifted(u))`` in
every spectral variant, scalar, llvm and cuda alike), so one texture works with all of them
and in XML as in a scene dict; a wrapping sensor would have to forward every other method of
the sensor it wraps. Mitsuba hands the texture the four lanes of ``math::sample_shifted(u)``,
u + j/4 wrapped into [0, 1]; lane 0 is u itself, and the texture uses it for all four lanes
(design §1: one u drives the four densities), so the stratification offsets never reach the
table. The weight it returns is 1 / mixture pdf per lane; the film averages the four lanes,
which makes the balance heuristic.

Properties: ``filename`` (the table, read and validated by ``wavelength_pdf.table``; a bad
table fails scene loading with ``FILE:LINE: reason``) or ``table`` (the name of a table built
in this process by ``wavelength_pdf.mitsuba.emission_srf``: emission sampling, design §1.7),
and ``defensive`` (float in [0, 1], default 0: the uniform share of design §1).

Cost: in the llvm and cuda variants ``sample_spectrum`` runs once, while Dr.Jit traces the
render kernel, and costs nothing per sample. In the scalar variants Mitsuba calls it through
Python once per sample (a few microseconds of interpreter work against a path that costs
about as much in C++): renders take 5-7 times as long as with Mitsuba's default sampling. It
cannot be cut from Python; use ``llvm_ad_spectral`` (same images; it warns once, below).
"""
from __future__ import annotations

from pathlib import Path

import drjit as dr

from wavelength_pdf.mitsuba.sampler import TableSampler
from wavelength_pdf.table import TableError, read_table

#: The plugin name in scene dicts and XML (design §7).
PLUGIN_NAME = "wavelength_table"


def _resolve(filename: str) -> Path:
    """A relative filename the way Mitsuba resolves scene files (the scene's folder first)."""
    import mitsuba

    path = Path(filename)
    if not path.is_absolute():
        try:
            resolver = (mitsuba.file_resolver() if hasattr(mitsuba, "file_resolver")
                        else mitsuba.Thread.thread().file_resolver())  # before Mitsuba 3.6
            path = Path(str(resolver.resolve(filename)))
        except Exception:  # no resolver in this thread: relative to the working directory
            pass
    return path


#: The scalar variants' cost, said once per process.
SCALAR_COST = ("wavelength_table in a scalar variant: Mitsuba calls this Python plugin once per "
               "sample, so renders take 5-7 times as long as with Mitsuba's default sampling; "
               "in llvm_ad_spectral (or cuda_ad_spectral) it runs compiled, at no cost per sample")
_warned_scalar = False


def _warn_scalar_cost() -> None:
    global _warned_scalar
    if not _warned_scalar:
        _warned_scalar = True
        import warnings

        warnings.warn(SCALAR_COST, RuntimeWarning, stacklevel=3)


def texture_class(m):
    """The ``wavelength_table`` texture class for one variant module ``m`` (spectral only)."""
    wavelength_type = type(dr.zeros(m.SurfaceInteraction3f).wavelengths)
    weight_type = getattr(m, "UnpolarizedSpectrum", m.Spectrum)

    class WavelengthTable(m.Texture):
        """Samples a sensor's wavelengths from a table (see the module's docstring)."""

        def __init__(self, props):
            m.Texture.__init__(self, props)
            self.defensive = float(props["defensive"]) if "defensive" in props else 0.0
            if ("filename" in props) == ("table" in props):
                raise TableError(f"{PLUGIN_NAME}: the texture needs a 'filename' (a wavelength "
                                 "table) or a 'table' (from emission_srf), one of the two")
            if "table" in props:
                from wavelength_pdf.mitsuba.emission import registered_table

                self.filename = f"<{props['table']}>"
                table = registered_table(str(props["table"]))
            else:
                self.filename = str(_resolve(str(props["filename"])))
                table = read_table(self.filename)
            self.sampler = TableSampler(table, m, self.defensive)
            if not self.sampler.jit:
                _warn_scalar_cost()

        def sample_spectrum(self, si, sample, active=True):
            u = m.Float64(sample[0])  # lane 0 of math::sample_shifted(u) is u itself
            lam, pdf = self.sampler.sample_four(u)
            if self.sampler.jit:
                w = [m.Float(dr.select(p > 0, dr.rcp(p), 0.0)) for p in pdf]
                wl = [m.Float(x) for x in lam]
            else:  # a zero mixture (u = 0 or 1 at a support's end) counts as 0
                w = [1.0 / p if p > 0 else 0.0 for p in pdf]
                wl = lam
            return wavelength_type(*wl), weight_type(*w)

        def pdf_spectrum(self, si, active=True):
            wl = si.wavelengths
            return weight_type(*[m.Float(self.sampler.pdf(m.Float64(wl[j]))) if self.sampler.jit
                                 else self.sampler.pdf(float(wl[j])) for j in range(4)])

        def eval(self, si, active=True):
            # The response is 1 where the table samples and 0 outside: the table changes how
            # wavelengths are drawn, not what the sensor measures.
            wl = si.wavelengths
            inside = [(wl[j] >= self.sampler.lo) & (wl[j] <= self.sampler.hi) if self.sampler.jit
                      else self.sampler.lo <= wl[j] <= self.sampler.hi for j in range(4)]
            return weight_type(*[dr.select(c, 1.0, 0.0) if self.sampler.jit else float(c) for c in inside])

        def mean(self):
            return 1.0

        def to_string(self):
            return (f"WavelengthTable[filename=\"{self.filename}\", defensive={self.defensive:g}, "
                    f"range=[{self.sampler.lo:g}, {self.sampler.hi:g}] nm, nodes={self.sampler.n}]")

    return WavelengthTable
