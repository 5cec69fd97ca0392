"""A pixel's spread (``transfer.spread``): the covariance of the spectra its samples see.

- the filter's shares of a pixel's samples sum to 1, are symmetric about its centre, and a box
  of radius 0.5 gives each of its own sub-pixels the same share;
- from two renders of sub-pixels, the spread of a pixel split between two spectra is
  w (1 - w) D D' (w the share on one side), and the renders' independent noise does not
  bias it (its mean over many pixels converges to the noiseless value);
- in the prediction (``predict.pixel_de2``) a spread of one spectrum, r t t', is the
  incoherence r; an edge between two spectra of the same luminance, which the incoherence
  cannot see, adds the unstratified noise of their difference; the objective's weights
  (``predict.pixel_weights``) give the same mean;
- the scene's pixel filter is read, with pbrt-v4's defaults;
- rendered, the spread is each path's own (one seed at two wavelength seeds): it sees the
  patches' edges of a ColorChecker, and the red and green light a white floor gets off two
  walls, which a seed pair of sub-pixel means does not;
- between a pixel's cells (what ``pbrt --wavelength-net`` stratifies): cells of equal filter
  weight for three filters; the corrected spread between cells is unbiased by the random
  paths within them (an edge down the middle: 0.25 D D' across x, nothing across y alone);
  as measured, the levels nest, each level's part is a covariance within noise and the parts
  sum to the spread; cells of nothing, or too few samples to stratify, change no prediction;
  an edge between halves is left with C(u)'s covariance within 2^(m-2) strata.
"""
from __future__ import annotations

import numpy as np
import pytest

from wavelength_pdf import predict as P, stratified
from wavelength_pdf.evaluation import transfer
from wavelength_pdf.exr import read_spectral
from wavelength_pdf.spectra import load_spectrum

CENTRES = np.arange(390.0, 780.0, 20.0)


@pytest.mark.parametrize("kind,radius", [("gaussian", 1.5), ("box", 0.5), ("triangle", 2.0)])
def test_filter_shares_sum_to_one_and_are_symmetric(kind, radius):
    w = transfer.filter_shares(6, 4, kind, radius)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    # Pixel 2 (centre 2.5 px, sub-pixels 8-11) sees its row mirrored about its centre.
    row = w[2]
    np.testing.assert_allclose(row[10 - 6:10 + 6], row[10 - 6:10 + 6][::-1], atol=1e-15)
    if kind == "box":
        np.testing.assert_allclose(w[2, 8:12], 0.25)
        assert w[2, :8].sum() == 0 and w[2, 12:].sum() == 0


def test_filter_shares_refuse_negative_lobed_filters():
    with pytest.raises(ValueError, match="mitchell"):
        transfer.filter_shares(4, 4, "mitchell", 2.0)


def _halves(h, w, k, T1, T2, column):
    """Sub-pixel spectra (h k, w k, B): T1 left of sub-pixel ``column``, T2 from it on."""
    img = np.empty((h * k, w * k, T1.size))
    img[:, :column] = T1
    img[:, column:] = T2
    return img


def test_spread_of_an_edge_is_the_two_spectra_difference():
    rng = np.random.default_rng(5)
    B, h, w, k = 5, 3, 4, 4
    T1, T2 = rng.uniform(0.2, 1.0, B), rng.uniform(0.2, 1.0, B)
    img = _halves(h, w, k, T1, T2, 6)  # the edge inside pixel 1 (sub-pixels 4-7)
    sy, sx = transfer.filter_shares(h, k, "box", 0.5), transfer.filter_shares(w, k, "box", 0.5)
    S = transfer.spread_of(img, img, sy, sx)
    D = T1 - T2
    np.testing.assert_allclose(S[1, 1], 0.25 * D[:, None] * D[None, :], atol=1e-12)  # half on each side
    np.testing.assert_allclose(S[:, 0], 0.0, atol=1e-12)  # one spectrum: no spread
    np.testing.assert_allclose(S[:, 3], 0.0, atol=1e-12)


def test_spread_is_unbiased_by_the_renders_noise():
    rng = np.random.default_rng(6)
    B, h, w, k = 4, 40, 40, 4
    T1, T2 = rng.uniform(0.2, 1.0, B), rng.uniform(0.2, 1.0, B)
    clean = np.concatenate([_halves(h, 1, k, T1, T2, 2)] * w, axis=1)  # every pixel split in half
    sy, sx = transfer.filter_shares(h, k, "gaussian", 1.5), transfer.filter_shares(w, k, "gaussian", 1.5)
    want = transfer.spread_of(clean, clean, sy, sx)
    noisy = [clean * rng.gamma(4.0, 0.25, clean.shape) for _ in range(2)]  # mean 1, 50 % noise
    got = transfer.spread_of(*noisy, sy, sx)
    same = transfer.spread_of(noisy[0], noisy[0], sy, sx)  # a render with itself counts its noise
    inner = (slice(4, -4), slice(4, -4))
    err = np.abs(got[inner].mean(axis=(0, 1)) - want[inner].mean(axis=(0, 1))).max()
    assert err < 0.05 * np.abs(want[inner].mean(axis=(0, 1))).max()
    assert np.trace(same[inner].mean(axis=(0, 1))) > 1.5 * np.trace(want[inner].mean(axis=(0, 1)))


@pytest.fixture(scope="module")
def fl2_basis():
    fl2 = load_spectrum("cie:FL2", 380.0, 780.0)
    table = stratified.stratified_table(fl2, "xyz", 380.0, 780.0)
    return P.path_colours(table, fl2, P.hat_basis(CENTRES, 380.0, 780.0), points=2 ** 12)


def test_a_spread_of_one_spectrum_is_the_incoherence(fl2_basis):
    t = np.stack([np.ones(CENTRES.size), 0.2 + 0.6 * (CENTRES > 550.0)])
    r = np.array([0.5, 3.0])
    S = r[:, None, None] * t[:, :, None] * t[:, None, :]
    np.testing.assert_allclose(P.pixel_de2(fl2_basis, t, 16, spread=S),
                               P.pixel_de2(fl2_basis, t, 16, incoherence=r), rtol=1e-9)
    W = P.pixel_weights(fl2_basis.target, t, 16, spread=S)
    np.testing.assert_allclose(W, P.pixel_weights(fl2_basis.target, t, 16, incoherence=r), rtol=1e-9, atol=1e-300)
    with pytest.raises(ValueError, match="spread"):
        P.pixel_de2(fl2_basis, t, 16, spread=S[:, :3, :3])


def test_an_edge_of_equal_luminance_adds_what_the_incoherence_cannot_see(fl2_basis):
    """Half the samples see a reddish, half a bluish spectrum of the same luminance: the
    pixel's luminance does not vary (r = 0), its spectra do."""
    red = 0.2 + 0.7 * (CENTRES > 580.0)
    blue = 0.2 + 0.7 * (CENTRES < 500.0)
    blue *= (red @ fl2_basis.target[:, 1]) / (blue @ fl2_basis.target[:, 1])
    t = 0.5 * (red + blue)[None, :]
    D = red - blue
    S = 0.25 * (D[:, None] * D[None, :])[None]
    coherent = P.pixel_de2(fl2_basis, t, 16)
    edge = P.pixel_de2(fl2_basis, t, 16, spread=S)
    M = P.basis_covariance(fl2_basis, 16, "independent")
    cov = np.einsum("b,bicj,c->ij", D, M, D) / 4 + np.einsum("b,bicj,c->ij", t[0], P.basis_covariance(fl2_basis, 16), t[0])
    np.testing.assert_allclose(edge, P.lab_quadratic(t @ fl2_basis.target, cov[None]), rtol=1e-9)
    assert edge[0] > 2 * coherent[0]


def test_the_scene_pixel_filter_is_read(tmp_path):
    scene = tmp_path / "s.pbrt"
    scene.write_text('PixelFilter "box" "float xradius" [ 0.75 ]\nWorldBegin\n')
    assert transfer.pixel_filter(scene) == ("box", 0.75, 0.5, 0.5)
    scene.write_text('PixelFilter "gaussian" "float sigma" 0.4\nWorldBegin\n')
    assert transfer.pixel_filter(scene) == ("gaussian", 1.5, 1.5, 0.4)
    scene.write_text("WorldBegin\n")
    assert transfer.pixel_filter(scene) == ("gaussian", 1.5, 1.5, 0.5)
    scene.write_text('\nPixelFilter "mitchell"\nWorldBegin\n')
    with pytest.raises(ValueError, match=r"s\.pbrt:2.*mitchell.*not modelled"):
        transfer.pixel_filter(scene)
    scene.write_text('PixelFilter "box" "float xradius" [ "wide" ]\nWorldBegin\n')
    with pytest.raises(ValueError, match=r"s\.pbrt:1.*xradius.*not a number"):
        transfer.pixel_filter(scene)


def test_a_rendered_colorchecker_spreads_at_its_patches_edges(tmp_path, pbrt):
    """Rendered: the ColorChecker at 64 x 48 under the flat lamp. Inside a patch every path
    sees one spectrum shape, only its magnitude varies (the spread is r t t'); at a patch's edge
    the paths see two. So the spread's part across the pixel's own spectrum, relative to it, is
    far larger at the edges than inside, where the wavelength noise cancels between the two
    renders."""
    from repo_paths import REPO

    scene = REPO / "scenes" / "benchmark" / "colorchecker" / "scene.pbrt"
    tr = transfer.of_file(scene, tmp_path, (64, 48), pbrt, spp=512, with_spread=True)
    assert tr.spread.shape == (tr.t.shape[0], tr.t.shape[1], tr.t.shape[1])
    img = np.zeros(tr.mask.shape + (tr.t.shape[1],))
    img[tr.mask] = tr.t
    norm = np.linalg.norm(img, axis=2)
    step = np.zeros(tr.mask.shape)
    for axis in (0, 1):
        for shift in (1, -1):
            d = np.linalg.norm(img - np.roll(img, shift, axis=axis), axis=2)
            step = np.maximum(step, d)
    step = (step / np.maximum(norm, 1e-12))[tr.mask]
    u = tr.t / np.maximum(np.linalg.norm(tr.t, axis=1, keepdims=True), 1e-300)
    across = np.eye(u.shape[1])[None] - u[:, :, None] * u[:, None, :]  # projects t out
    rel = np.einsum("pij,pjk,pki->p", across, tr.spread, across) / np.maximum(norm[tr.mask] ** 2, 1e-12)
    edge, inside = rel[step > 0.5], rel[step < 0.05]
    assert edge.size > 50 and inside.size > 50
    assert edge.mean() > 10 * abs(inside.mean())


def test_negative_share_of_analytic_spreads():
    """A covariance has none; -S all of it; diag(2, -2, 0) half; a zero spread none to speak of (nan)."""
    rng = np.random.default_rng(3)
    X = rng.normal(size=(5, 4, 6))
    S = X @ np.swapaxes(X, -1, -2)  # (5, 4, 4), positive semidefinite
    np.testing.assert_allclose(transfer.negative_share(S), 0.0, atol=1e-12)
    np.testing.assert_allclose(transfer.negative_share(-S), 1.0)
    assert transfer.negative_share(np.diag([2.0, -2.0, 0.0])) == pytest.approx(0.5)
    assert np.isnan(transfer.negative_share(np.zeros((3, 3))))
    # Pooled: the sum over pixels, so a large pixel outweighs a small one.
    mixed = np.stack([np.diag([3.0, 1.0]), np.diag([1.0, -1.0])])  # masses 4 and 2, negative 0 and 1
    assert transfer.negative_share(mixed, pooled=True) == pytest.approx(1 / 6)
    assert np.isnan(transfer.negative_share(np.zeros((2, 3, 3)), pooled=True))


def test_the_spread_has_almost_no_negative_variance(tmp_path, pbrt):
    """A pixel's spread is a covariance, positive semidefinite but for noise. Rendered at the
    module's wavelengths per path (``SPREAD_REPEATS``) on the benchmark's ColorChecker
    (32 x 24), the median pixel's negative eigenvalues are a few per cent of its absolute
    eigenvalue mass; at 8 wavelength repeats, each path's spectrum over the buckets so sparse
    that its noise dominates, they are a fifth or more: the indefinite directions a polish
    can lean on."""
    from repo_paths import REPO

    scene = REPO / "scenes" / "benchmark" / "colorchecker" / "scene.pbrt"
    few, enough = (np.nanmedian(transfer.negative_share(transfer.spread(scene, tmp_path, (32, 24), pbrt, repeats=k)))
                   for k in (8, transfer.SPREAD_REPEATS))
    assert enough < 0.03 and few > 0.2, (enough, few)


def test_a_noisy_spread_is_measured_linearly(fl2_basis):
    """A measured spread is noisy and can be indefinite: the prediction is linear in it, so
    noise of mean 0 leaves the mean prediction unbiased (clipping negative variances would not)."""
    rng = np.random.default_rng(7)
    t = np.full((1, CENTRES.size), 0.5)
    D = rng.normal(size=CENTRES.size) * 0.2
    S0 = 0.25 * np.outer(D, D)[None]
    E = rng.normal(size=(CENTRES.size, CENTRES.size)) * 0.05
    E = (E + E.T)[None]  # indefinite
    for metric in ("de2000", "lab"):
        up, down, mid = (P.pixel_de2(fl2_basis, t, 16, metric=metric, spread=S) for S in (S0 + E, S0 - E, S0))
        assert up + down == pytest.approx(2 * mid, rel=1e-9)
        assert up != pytest.approx(mid, rel=1e-3)


# A white floor seen from above, lit by a lamp over it and by what a red wall and a green one
# (or two grey ones) on either side throw back: every pixel sees one surface, but its paths
# reach the lamp directly, off the red wall or off the green one.
WALLS = """LookAt 0 1.5 0  0 0 0  0 0 1
Camera "perspective" "float fov" [20]
Film "rgb" "integer xresolution" [12] "integer yresolution" [12]
Sampler "sobol"
Integrator "path" "integer maxdepth" [3]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "blackbody L" [5000] "float scale" [20]
  Translate 0 2.8 0
  Shape "sphere" "float radius" [0.2]
AttributeEnd
Material "diffuse" "rgb reflectance" [0.8 0.8 0.8]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-1 0 -2  1 0 -2  1 0 2  -1 0 2]
Material "diffuse" "rgb reflectance" [LEFT]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [-1 0 -2  -1 3 -2  -1 3 2  -1 0 2]
Material "diffuse" "rgb reflectance" [RIGHT]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point3 P" [1 0 -2  1 0 2  1 3 2  1 3 -2]
"""


def _red_green(tr, S):
    """Each pixel's spread along red minus green (the buckets above 580 nm less those of
    480-580 nm) with its own spectrum t projected out, relative to |t|^2: one direction, so
    that the noise of the other buckets stays out."""
    c = tr.centres
    d0 = (c > 580).astype(float) - ((c > 480) & (c < 580)).astype(float)
    u = tr.t / np.linalg.norm(tr.t, axis=1, keepdims=True)
    d = d0[None] - (u @ d0)[:, None] * u
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.einsum("pi,pij,pj->p", d, S, d) / np.sum(tr.t ** 2, axis=1)


def test_the_spread_is_each_paths_own_and_sees_light_off_coloured_walls(tmp_path, pbrt):
    """The floor's sub-pixels all have the same mean spectrum, so a seed pair's spread (each
    factor a sub-pixel's mean) sees little across the pixel's spectrum; the spread of one seed
    at two wavelength seeds (each factor one path's own) sees the red and the green light, and
    nothing with grey walls."""
    walls = {"coloured": ("0.8 0.05 0.05", "0.05 0.8 0.05"), "grey": ("0.3 0.3 0.3", "0.3 0.3 0.3")}
    got = {}
    for name, (left, right) in walls.items():
        scene = tmp_path / f"{name}.pbrt"
        scene.write_text(WALLS.replace("LEFT", left).replace("RIGHT", right))
        tr = transfer.of_file(scene, tmp_path / name, None, pbrt, spp=256, with_spread=True)
        assert tr.t.shape[0] == 144  # every pixel sees the lit floor
        got[name] = _red_green(tr, tr.spread).mean()
        if name == "coloured":
            copy = tmp_path / name / "spread" / "scene.pbrt"
            a, b = (read_spectral(transfer.render(copy, pbrt, 1, seed=s, repeats=8, name=f"seed{s}.exr"))[1]
                    for s in (1, 2))
            sh = transfer.filter_shares(12, transfer.SPREAD_FACTOR)
            got["seed pair"] = _red_green(tr, transfer.spread_of(a, b, sh, sh)[tr.mask] * tr.scale ** 2).mean()
    assert got["coloured"] > 20 * abs(got["grey"]), got
    assert got["coloured"] > 20 * abs(got["seed pair"]), got


def test_a_scene_copied_by_several_at_once_is_whole_and_leaves_no_draft(tmp_path):
    """Two processes may copy one scene into one folder at once (the benchmark's tables made in
    parallel): every copy returns, the copy is the one a lone copy writes, and no draft is left."""
    from concurrent.futures import ThreadPoolExecutor

    scene = tmp_path / "s.pbrt"
    scene.write_text(WALLS.replace("LEFT", "0.8 0.05 0.05").replace("RIGHT", "0.05 0.8 0.05"))
    alone = transfer.copy_scene(scene, tmp_path / "alone", (12, 12)).read_text()
    with ThreadPoolExecutor(8) as pool:
        copies = list(pool.map(lambda _: transfer.copy_scene(scene, tmp_path / "shared", (12, 12)), range(32)))
    assert {c.read_text() for c in copies} == {alone}
    assert sorted(p.name for p in (tmp_path / "shared").iterdir()) == ["scene.pbrt"]


# --- The spread between a pixel's cells (pbrt --wavelength-net stratifies it) ---------------

@pytest.mark.parametrize("kind,radius", [("gaussian", 1.5), ("box", 0.5), ("triangle", 2.0)])
@pytest.mark.parametrize("g", [2, 4])
def test_cell_shares_cut_each_pixel_into_cells_of_equal_weight(kind, radius, g):
    shares = transfer.filter_shares(5, 8, kind, radius)
    cells = transfer.cell_shares(shares, g)
    np.testing.assert_allclose(cells.reshape(5, g, -1).sum(axis=1), shares)  # each sub-pixel in one cell
    mass = cells.sum(axis=1).reshape(5, g)
    # Within one sub-pixel's share of 1 / g (a sub-pixel goes whole to one cell); exact for the box.
    assert np.abs(mass - 1.0 / g).max() <= (1e-12 if kind == "box" else shares.max())
    order = np.argmax(cells.reshape(5, g, -1) > 0, axis=2)  # cells fill from the left
    assert np.all(np.diff(order, axis=1) > 0)


def _paths(rng, h, w, k, spectrum_of_column, path_sd):
    """Two renders (h k, w k, B) of the same paths at independent wavelengths: each sub-pixel's
    path sees its column's spectrum times a random magnitude of ``path_sd`` (shared by both
    renders), each render adds its own multiplicative wavelength noise (mean 1)."""
    clean = np.stack([spectrum_of_column(c % k) for c in range(w * k)])[None].repeat(h * k, axis=0)
    paths = clean * rng.normal(1.0, path_sd, clean.shape[:2])[..., None]
    return [paths * rng.gamma(4.0, 0.25, paths.shape) for _ in range(2)]


def test_the_spread_between_cells_is_unbiased_by_the_paths_within_them():
    rng = np.random.default_rng(8)
    B, h, w, k = 4, 30, 30, 8
    T1, T2 = rng.uniform(0.2, 1.0, B), rng.uniform(0.2, 1.0, B)
    sy, sx = transfer.filter_shares(h, k, "box", 0.5), transfer.filter_shares(w, k, "box", 0.5)
    # Every pixel's left half sees T1, its right half T2 (an edge down its middle), each path
    # varying by 30 % more: between cells cut along x lies the edge's spread, 0.25 D D', alone;
    # between cells cut along y alone, nothing.
    a, b = _paths(rng, h, w, k, lambda c: T1 if c < k // 2 else T2, 0.3)
    S = transfer.spread_of(a, b, sy, sx)
    D = T1 - T2
    edge = 0.25 * D[:, None] * D[None, :]
    scale = np.abs(edge).max()
    for cells, want in (((2, 2), edge), ((4, 4), edge), ((1, 2), edge), ((1, 8), edge), ((2, 1), 0 * edge)):
        got = transfer.cell_spread_of(a, b, sy, sx, cells, S, correct=True).mean(axis=(0, 1))
        np.testing.assert_allclose(got, want, atol=0.05 * scale, err_msg=str(cells))
    assert np.trace(S.mean(axis=(0, 1))) > 1.5 * np.trace(edge)  # the paths' own spread is more
    # One spectrum, the paths varying alone: nothing between cells, though each cell's mean of
    # 16 paths is itself noisy (uncorrected, it counts 1/16 of the paths' spread less the pixel
    # mean's 1/64).
    a, b = _paths(rng, h, w, k, lambda c: T1, 0.3)
    S = transfer.spread_of(a, b, sy, sx)
    total = np.trace(S.mean(axis=(0, 1)))
    assert abs(np.trace(transfer.cell_spread_of(a, b, sy, sx, (2, 2), S, correct=True).mean(axis=(0, 1)))) \
        < 0.01 * total
    raw = transfer.cell_spread_of(a, b, sy, sx, (2, 2), S)  # as measured: with the paths' noise
    assert np.trace(raw.mean(axis=(0, 1))) > 0.03 * total


def test_the_levels_of_the_spread_as_measured_are_covariances():
    """As measured the cells nest, so each level's part of the spread (its inclusion-exclusion
    over the coarser levels) is a covariance in expectation and the whole spread their sum,
    here for an edge fixed on the sub-pixel grid (a diagonal one in every pixel, finer than
    any cell) under wavelength noise alone."""
    rng = np.random.default_rng(9)
    B, h, w, k = 3, 24, 24, 8
    T1, T2 = rng.uniform(0.2, 1.0, B), rng.uniform(0.2, 1.0, B)
    yy, xx = np.mgrid[0:h * k, 0:w * k]
    clean = np.where(((xx % k) + (yy % k) < k - 1)[..., None], T1, T2)
    a, b = (clean * rng.gamma(16.0, 1 / 16.0, clean.shape) for _ in range(2))
    sy, sx = transfer.filter_shares(h, k, "gaussian", 1.5), transfer.filter_shares(w, k, "gaussian", 1.5)
    S = transfer.spread_of(a, b, sy, sx)
    L = transfer.NET_LEVEL

    def mean_level(i, j):
        if (i, j) == (0, 0) or i < 0 or j < 0:
            return np.zeros((B, B))
        if (i, j) == (L, L):
            return S.mean(axis=(0, 1))
        return transfer.cell_spread_of(a, b, sy, sx, (2 ** i, 2 ** j), S).mean(axis=(0, 1))

    V = {(i, j): mean_level(i, j) for i in range(-1, L + 1) for j in range(-1, L + 1)}
    parts = [V[i, j] - V[i - 1, j] - V[i, j - 1] + V[i - 1, j - 1]
             for i in range(L + 1) for j in range(L + 1) if (i, j) != (0, 0)]
    scale = np.trace(S.mean(axis=(0, 1)))
    assert min(np.linalg.eigvalsh(0.5 * (q + q.T)).min() for q in parts) > -0.02 * scale  # noise only
    assert max(np.trace(q) for q in parts) > 0.1 * scale  # and the edge is somewhere
    np.testing.assert_allclose(sum(parts), S.mean(axis=(0, 1)), atol=1e-12 * scale)


def _edge_pixel(fl2_basis):
    """A pixel whose left half sees a reddish spectrum, its right half a bluish one: its mean
    t, spread S and the difference D."""
    red = 0.2 + 0.7 * (CENTRES > 580.0)
    blue = 0.2 + 0.7 * (CENTRES < 500.0)
    t = 0.5 * (red + blue)[None, :]
    D = red - blue
    return t, 0.25 * (D[:, None] * D[None, :])[None], D


def _levels(S, between):
    """The cells of :func:`transfer.net_cells` with ``between(i, j)`` of the spread ``S``."""
    return tuple(((i, j), between(i, j) * S) for i, j in transfer.net_cells())


def test_cells_of_nothing_or_too_few_samples_change_nothing(fl2_basis):
    t, S, _ = _edge_pixel(fl2_basis)
    plain = P.pixel_de2(fl2_basis, t, 64, spread=S)
    none = _levels(S, lambda i, j: 0.0)
    np.testing.assert_allclose(P.pixel_de2(fl2_basis, t, 64, spread=S, cells=none), plain, rtol=1e-12)
    # At 4 spp (m = 2) a cell of two halves holds 2 samples: the net stratifies none of the spread.
    edge = _levels(S, lambda i, j: float(j >= 1))
    np.testing.assert_allclose(P.pixel_de2(fl2_basis, t, 4, spread=S, cells=edge),
                               P.pixel_de2(fl2_basis, t, 4, spread=S), rtol=1e-12)
    with pytest.raises(ValueError, match="spread"):
        P.pixel_de2(fl2_basis, t, 64, cells=none)
    with pytest.raises(ValueError, match="low-discrepancy"):
        P.pixel_de2(fl2_basis, t, 64, "independent", spread=S, cells=none)
    with pytest.raises(ValueError, match="every level"):
        P.pixel_de2(fl2_basis, t, 64, spread=S, cells=none[:-1])


@pytest.mark.parametrize("spp", [16, 64])
def test_an_edge_between_cells_is_stratified_with_the_net(fl2_basis, spp):
    """An edge down the pixel's middle is the spread between its halves along x, level (0, 1):
    a (1, m, 3)-net integrates it times any function of u constant on 2^(m - 2) strata, so
    what is left is C(u)'s covariance within those strata, over N."""
    t, S, D = _edge_pixel(fl2_basis)
    with_net = P.pixel_de2(fl2_basis, t, spp, spread=S, cells=_levels(S, lambda i, j: float(j >= 1)))
    n = spp // 4
    cov = ((n / spp) * np.einsum("b,bicj,c->ij", D, P.basis_covariance(fl2_basis, n), D) / 4
           + np.einsum("b,bicj,c->ij", t[0], P.basis_covariance(fl2_basis, spp), t[0]))
    np.testing.assert_allclose(with_net, P.lab_quadratic(t @ fl2_basis.target, cov[None]), rtol=1e-9)
    # Far less than unstratified, and the less the more samples a half holds.
    assert with_net[0] < {16: 0.5, 64: 0.2}[spp] * P.pixel_de2(fl2_basis, t, spp, spread=S)[0]
    # Cut across y as well (2 x 2 cells, level (1, 1)), a cell's strata are half as many: more.
    square = P.pixel_de2(fl2_basis, t, spp, spread=S, cells=_levels(S, lambda i, j: float(i >= 1 and j >= 1)))
    assert square[0] > with_net[0]
