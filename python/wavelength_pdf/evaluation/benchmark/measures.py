"""Error measures that a noisy reference cannot distort (design §6.7).

For two images A and B of one sampler at one spp rendered with independent seeds, E[(A - B)^2]
is twice one image's variance: squared-error measures from such a seed pair need no reference
at all. For an unbiased sampler that variance is its whole mean squared error.

- ``mse``: mean over pixels and channels of (A - B)^2 / 2, linear RGB;
- ``relmse``: the same divided per pixel and channel by T^2 + (0.01 mean T)^2 (T the reference,
  only as a scale);
- ``de2``: mean over pixels of CIEDE2000(A, B)^2 / 2: to first order in the noise the mean
  squared CIEDE2000 of one image against the exact one (CIEDE2000 is locally a quadratic form);
- ``chroma2``: the same for the Lab chroma plane, ((a*_A - a*_B)^2 + (b*_A - b*_B)^2) / 2.

Against a reference T (the published measure): ``de`` is the mean CIEDE2000 of A and of B
against T. CIEDE2000 is not linear in the noise, so ``de`` ratios are compressed relative to
the squared ones: each figure says which measure it is. The reference's own noise is measured
from two halves H1, H2 of its chunks: ``truth_de`` = mean CIEDE2000(H1, H2) / 2 estimates T's own
mean error (each half has twice T's variance, so |H1 - H2| is about twice |T - exact|), and
``truth_de2`` = mean CIEDE2000(H1, H2)^2 / 4 its mean squared error; ``de2_ref`` = mean
CIEDE2000(A, T)^2 - truth_de2 is the squared error against T with T's noise subtracted, which
must agree with ``de2`` (a check of both).

Every measure is taken over the pixels the scene lights (:func:`lit_pixels`): emitters seen
directly (pixels brighter than 5 times the median) are left out. Their pixels show the lamp's
spectrum unattenuated, far above the display's white, where a picture clips them; their noise
is heavy-tailed (a rare hit of a line worth a thousand ordinary samples) and would decide every
mean on its own. ``de_all`` is the published measure as published, the mean CIEDE2000 against T
over every pixel.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wavelength_pdf.evaluation.metrics import rgb_to_lab

#: The squared measures (additive in independent noise: floor + spectral part).
SQUARED = ("mse", "relmse", "de2", "chroma2")
#: Every measure, in report order.
MEASURES = (*SQUARED, "de", "de2_ref", "de_all")


def _delta_e(lab1: np.ndarray, lab2: np.ndarray) -> np.ndarray:
    import colour

    return np.asarray(colour.delta_E(lab1, lab2, method="CIE 2000"), dtype=np.float64)


def _check(*images: np.ndarray) -> None:
    shapes = {np.shape(im) for im in images}
    if len(shapes) != 1:
        raise ValueError(f"images of different shapes {sorted(shapes)}")
    for im in images:
        if not np.all(np.isfinite(im)):
            raise ValueError("image has NaN or infinite pixels")


@dataclass(frozen=True)
class Truth:
    """The reference and its own noise, from two halves of its chunks."""

    image: np.ndarray
    lab: np.ndarray
    de: float
    de2: float

    #: The pixels every measure uses (:func:`lit_pixels`).
    mask: np.ndarray

    @staticmethod
    def of(image: np.ndarray, half1: np.ndarray, half2: np.ndarray) -> "Truth":
        _check(image, half1, half2)
        mask = lit_pixels(image)
        d = _delta_e(rgb_to_lab(half1), rgb_to_lab(half2))[mask]
        return Truth(np.asarray(image, np.float64), rgb_to_lab(image), float(d.mean() / 2.0),
                     float(np.mean(d * d) / 4.0), mask)


def pair(a: np.ndarray, b: np.ndarray, truth: Truth) -> dict[str, float]:
    """Every measure of one sampler at one spp from its seed pair ``a``, ``b`` (linear RGB)."""
    _check(a, b, truth.image)
    m = truth.mask
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    lab_a, lab_b = rgb_to_lab(a), rgb_to_lab(b)
    de_all = (_delta_e(lab_a, truth.lab).mean() + _delta_e(lab_b, truth.lab).mean()) / 2.0
    a, b, t, lab_a, lab_b, lab_t = a[m], b[m], truth.image[m], lab_a[m], lab_b[m], truth.lab[m]
    d2 = (a - b) ** 2 / 2.0
    scale = (0.01 * t.mean(axis=0)) ** 2
    de_ab = _delta_e(lab_a, lab_b)
    de_a, de_b = _delta_e(lab_a, lab_t), _delta_e(lab_b, lab_t)
    return {
        "mse": float(d2.mean()),
        "relmse": float(np.mean(d2 / (t * t + scale))),
        "de2": float(np.mean(de_ab ** 2) / 2.0),
        "chroma2": float(np.mean(np.sum((lab_a[..., 1:] - lab_b[..., 1:]) ** 2, axis=-1)) / 2.0),
        "de": float((de_a.mean() + de_b.mean()) / 2.0),
        "de2_ref": float((np.mean(de_a ** 2) + np.mean(de_b ** 2)) / 2.0 - truth.de2),
        "de_all": float(de_all),
    }


def pair_se(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None) -> float:
    """Relative standard error of ``mse`` over the pixels (taken as independent)."""
    d2 = ((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2).mean(axis=-1)
    d2 = d2[mask] if mask is not None else d2.ravel()
    m = d2.mean()
    return float(d2.std(ddof=1) / np.sqrt(d2.size) / m) if m > 0 and d2.size > 1 else float("nan")


def lit_pixels(truth: np.ndarray, factor: float = 5.0) -> np.ndarray:
    """Mask (h, w) of the pixels the bias check uses: all but those brighter than ``factor``
    times the median (emitters seen directly: they show the lamp's spectrum unattenuated, so
    their noise is heavy-tailed, a rare hit of a line worth a thousand ordinary samples, and
    two seeds say nothing reliable about it)."""
    y = np.asarray(truth, np.float64) @ np.array([0.2126, 0.7152, 0.0722])
    med = np.median(y)
    return y <= factor * med if med > 0 else np.ones(y.shape, bool)


def bias_z(a: np.ndarray, b: np.ndarray, truth: np.ndarray, truth_halves=None,
           mask: np.ndarray | None = None) -> np.ndarray:
    """Per channel: how many standard errors the mean of (a + b) / 2 over the image (the
    ``mask``'s pixels) lies from the reference's mean. The pair's own variance estimate (pixels
    taken as independent, as they are: every pixel has its own scramble or random stream) is
    the noise; ``truth_halves`` (two independent halves of the reference) add the reference's."""
    m = np.ones(np.shape(a)[:2], bool) if mask is None else np.asarray(mask, bool)
    a = np.asarray(a, np.float64)[m]
    b = np.asarray(b, np.float64)[m]
    t = np.asarray(truth, np.float64)[m]
    n = a.shape[0]
    # Var(mean of (a+b)/2) = (1/n^2) sum_pixels Var((a+b)/2) = (1/n^2) sum (a-b)^2/4 in expectation.
    var = np.sum((a - b) ** 2, axis=0) / 4.0 / n ** 2
    if truth_halves is not None:
        var = var + mean_variance(*(np.asarray(h, np.float64)[m] for h in truth_halves))
    diff = (a + b).mean(axis=0) / 2.0 - t.mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(var > 0, diff / np.sqrt(var), np.where(diff == 0, 0.0, np.inf))


def mean_variance(half1: np.ndarray, half2: np.ndarray) -> np.ndarray:
    """Variance of an image's per-channel mean over pixels, for the image (h1 + h2) / 2 made of
    two independent halves: sum over pixels of (h1 - h2)^2 / 4, over n^2 (pixels independent)."""
    d = (np.asarray(half1, np.float64) - np.asarray(half2, np.float64)).reshape(-1, np.shape(half1)[-1])
    return np.sum(d * d, axis=0) / 4.0 / d.shape[0] ** 2


def removed_share(e_sampler: float, e_uniform: float, e_floor: float) -> float:
    """The share of the spectral error above the floor that a sampler removes, relative to
    stratified uniform sampling: 1 - (E_s - E_floor) / (E_uniform - E_floor) (1: all of it)."""
    removable = e_uniform - e_floor
    if not removable > 0:
        return float("nan")
    return 1.0 - (e_sampler - e_floor) / removable


def share_above_floor(table, simple, floor) -> tuple[float, float]:
    """The table's error above the floor over a simple sampler's, (mean T - mean F) /
    (mean S - mean F), and its standard error, from K independent seed pairs' measures of each
    (sequences of K values, pair k of each rendered with the same seeds): the jackknife over
    the pairs (leave one pair out of all three means), which needs no model of how a pair's
    measure varies (se nan for one pair). NaN where the simple sampler is not above the
    floor."""
    t, s, f = (np.asarray(x, np.float64) for x in (table, simple, floor))
    k = t.size
    if not (t.shape == s.shape == f.shape == (k,)) or k == 0:
        raise ValueError(f"share_above_floor: {t.shape}, {s.shape}, {f.shape} pairs' measures")

    def share(tm, sm, fm):
        return (tm - fm) / (sm - fm) if sm > fm else float("nan")

    whole = share(t.mean(), s.mean(), f.mean())
    if k < 2 or not np.isfinite(whole):
        return whole, float("nan")
    drop = [(x.sum() - x) / (k - 1) for x in (t, s, f)]
    loo = np.array([share(*(d[i] for d in drop)) for i in range(k)])
    return whole, float(np.sqrt((k - 1) / k * np.sum((loo - loo.mean()) ** 2)))


def equal_time_ratio(e_a: float, t_a: float, e_b: float, t_b: float, slope: float = 1.0) -> float:
    """Error of A over error of B at equal CPU time, from errors at equal spp and CPU seconds
    per image: a squared error that falls as spp^-slope (1 for independent samples) at A's
    time per sample t_a reaches, in B's time, e_a (t_a / t_b)^slope."""
    if not (e_b > 0 and t_b > 0 and t_a > 0):
        return float("nan")
    return e_a * (t_a / t_b) ** slope / e_b
