"""Executables kept on disk (wavelength_pdf.aot): a function loaded from the cache gives
bit-identical results to the plain jitted one, the signature separates shapes and static
arguments, and a damaged file is replaced instead of failing."""

import time

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from wavelength_pdf import aot
from wavelength_pdf.budget import Budget
from wavelength_pdf.precision import float64


def _f(x, arr, scale, name):
    y = jnp.sin(x) * arr["w"] + scale
    return jnp.cumsum(y) if name == "cumsum" else jnp.sort(y)


@pytest.fixture(autouse=True)
def _restore():
    before = aot._dir
    yield
    aot._dir = before


@pytest.fixture
def cache_dir(tmp_path):
    aot.enable(tmp_path)
    return tmp_path


def _fresh():
    return aot.disk_jit(_f, static_argnames=("name",))


@float64
def test_loaded_executable_gives_identical_results(cache_dir):
    x = jnp.linspace(0.0, 3.0, 17)
    arr = {"w": jnp.linspace(1.0, 2.0, 17)}
    plain = np.asarray(jax.jit(_f, static_argnames=("name",))(x, arr, 0.5, "cumsum"))
    first = _fresh()
    got1 = np.asarray(first(x, arr, 0.5, "cumsum"))  # compiles and writes
    files = list(cache_dir.glob("f-*.pkl"))
    assert len(files) == 1
    second = _fresh()  # a new process would start like this: nothing in memory
    got2 = np.asarray(second(x, arr, 0.5, name="cumsum"))  # keyword or position: same
    assert len(list(cache_dir.glob("f-*.pkl"))) == 1
    np.testing.assert_array_equal(got1, plain)
    np.testing.assert_array_equal(got2, plain)
    # Another static argument and another shape are other executables.
    np.testing.assert_array_equal(np.asarray(second(x, arr, 0.5, "sort")),
                                  np.asarray(jax.jit(_f, static_argnames=("name",))(x, arr, 0.5, "sort")))
    second(x[:5], {"w": arr["w"][:5]}, 0.5, "sort")
    assert len(list(cache_dir.glob("f-*.pkl"))) == 3


@float64
def test_clear_memory_drops_the_executables_and_the_next_call_loads_them(cache_dir):
    x = jnp.linspace(0.0, 3.0, 11)
    arr = {"w": jnp.linspace(1.0, 2.0, 11)}
    f = _fresh()
    want = np.asarray(f(x, arr, 0.5, "cumsum"))
    assert f in aot._instances and len(f._compiled) == 1
    aot.clear_memory()
    assert not f._compiled
    np.testing.assert_array_equal(np.asarray(f(x, arr, 0.5, "cumsum")), want)
    assert len(f._compiled) == 1 and len(list(cache_dir.glob("f-*.pkl"))) == 1


@float64
def test_damaged_file_is_replaced(cache_dir):
    x = jnp.linspace(0.0, 1.0, 8)
    arr = {"w": jnp.ones(8)}
    want = np.asarray(_fresh()(x, arr, 1.0, "cumsum"))
    (path,) = cache_dir.glob("f-*.pkl")
    path.write_bytes(b"not an executable")
    np.testing.assert_array_equal(np.asarray(_fresh()(x, arr, 1.0, "cumsum")), want)
    assert path.is_file() and path.read_bytes() != b"not an executable"


@float64
def test_traced_arguments_and_no_cache_fall_back_to_jit(tmp_path):
    aot.enable(None)
    x = jnp.linspace(0.0, 1.0, 8)
    arr = {"w": jnp.ones(8)}
    f = _fresh()
    np.testing.assert_array_equal(np.asarray(f(x, arr, 1.0, "cumsum")),
                                  np.asarray(jnp.cumsum(jnp.sin(x) + 1.0)))
    aot.enable(tmp_path)
    g = jax.grad(lambda s: jnp.sum(f(x, arr, s, "cumsum")))(1.0)  # s is a tracer
    assert float(g) == pytest.approx(36.0)
    assert not list(tmp_path.glob("f-*.pkl"))


@pytest.mark.parametrize("on_disk", [True, False])
@float64
def test_bound_executable_equals_the_call(on_disk, tmp_path):
    """``bind`` gives the executable of one signature, called with the non-static arguments
    alone: the same numbers as calling the function, on other values of that signature."""
    aot.enable(tmp_path if on_disk else None)
    f = _fresh()
    arr = {"w": jnp.linspace(1.0, 2.0, 9)}
    exe = f.bind(jnp.zeros(9), arr, 0.5, name="sort")
    for k in range(3):
        x = jnp.linspace(0.0, 1.0 + k, 9)
        np.testing.assert_array_equal(np.asarray(exe(x, arr, 0.25 * k)),
                                      np.asarray(f(x, arr, 0.25 * k, "sort")))
    assert len(list(tmp_path.glob("f-*.pkl"))) == (1 if on_disk else 0)


@pytest.mark.parametrize("on_disk", [True, False])
def test_no_compilation_starts_that_would_end_past_the_deadline(on_disk, tmp_path, monkeypatch):
    """A time cap is kept across compilations, which cannot be cut short: under a deadline
    a call that must compile first refuses when less time is left than a compilation takes;
    one already compiled runs whatever the deadline."""
    monkeypatch.setattr(aot, "_dir", tmp_path if on_disk else None)
    monkeypatch.setattr(aot, "_compile_seconds", [])  # none timed yet: the default applies

    def triple_plus_one(x):
        return 3.0 * x + 1.0

    f = aot.disk_jit(triple_plus_one)
    x = jnp.arange(5.0)
    short = Budget(1, time.monotonic() + 0.5 * aot.DEFAULT_COMPILE_SECONDS)
    with pytest.raises(aot.CompileWouldOverrun, match="time cap"):
        f(x, budget=short)
    np.testing.assert_array_equal(np.asarray(f(x)), 3.0 * np.arange(5.0) + 1.0)  # no deadline
    past = Budget(1, time.monotonic() - 1.0)  # already past: nothing new compiles
    np.testing.assert_array_equal(np.asarray(f(x, budget=past)), 3.0 * np.arange(5.0) + 1.0)
    with pytest.raises(aot.CompileWouldOverrun):
        f(jnp.arange(6.0), budget=past)  # another shape: another compilation
    with pytest.raises(aot.CompileWouldOverrun):
        f.bind(jnp.arange(7.0), budget=past)  # binding compiles within the budget too


# --- what the cache folder may hold (design §7) -------------------------------------------

class _Planted:
    """A pickle that, loaded, creates the file ``marker``: what an attacker would plant."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        import pathlib

        return (pathlib.Path.touch, (pathlib.Path(self.marker),))


@float64
def test_planted_file_is_never_unpickled(cache_dir, tmp_path):
    """A file planted where an executable is expected ran its command when it was loaded."""
    import pickle

    x = jnp.linspace(0.0, 1.0, 8)
    arr = {"w": jnp.ones(8)}
    want = np.asarray(_fresh()(x, arr, 1.0, "cumsum"))
    (path,) = cache_dir.glob("f-*.pkl")
    marker = tmp_path / "planted-code-ran"
    path.write_bytes(pickle.dumps(_Planted(marker)))
    assert path.stat().st_mode & 0o077 == 0  # a private file of this user, as the real one
    np.testing.assert_array_equal(np.asarray(_fresh()(x, arr, 1.0, "cumsum")), want)
    assert not marker.exists(), "the planted pickle was loaded"
    # A copy of a genuine entry under another entry's name is refused too (the name is signed).
    genuine = path.read_bytes()
    assert genuine.startswith(aot._MAGIC)
    other = cache_dir / "f-0000000000000000000000000000000000000000.pkl"
    other.write_bytes(genuine)
    other.chmod(0o600)
    with pytest.raises(ValueError, match="not written by this package"):
        aot._unsealed(other, other.name)


@pytest.fixture
def restore_compilation_cache():
    from wavelength_pdf import compile_cache

    saved = (compile_cache._cache_dir, aot._dir, jax.config.jax_compilation_cache_dir)
    compile_cache._cache_dir = None
    yield compile_cache
    compile_cache._cache_dir, aot._dir = saved[0], saved[1]
    jax.config.update("jax_compilation_cache_dir", saved[2])


def test_cache_folder_others_may_write_is_not_used(tmp_path, monkeypatch, restore_compilation_cache):
    compile_cache = restore_compilation_cache
    folder = tmp_path / "shared-cache"
    folder.mkdir()
    folder.chmod(0o777)
    monkeypatch.setenv("WAVELENGTH_PDF_JAX_CACHE", str(folder))
    with pytest.warns(RuntimeWarning, match="others may write in it"):
        assert compile_cache.enable_compilation_cache() is None
    assert aot._dir is None
    assert jax.config.jax_compilation_cache_dir != str(folder)
    assert list(folder.iterdir()) == []
    assert compile_cache.enable_compilation_cache() is None  # one warning: decided once


def test_cache_folder_of_another_user_is_not_used(tmp_path, monkeypatch, restore_compilation_cache):
    import os

    if os.geteuid() != 0:
        pytest.skip("needs root to give a folder to another user")
    compile_cache = restore_compilation_cache
    folder = tmp_path / "their-cache"
    folder.mkdir(mode=0o700)
    os.chown(folder, 65534, 65534)
    monkeypatch.setenv("WAVELENGTH_PDF_JAX_CACHE", str(folder))
    with pytest.warns(RuntimeWarning, match="belongs to another user"):
        assert compile_cache.enable_compilation_cache() is None
    assert aot._dir is None and list(folder.iterdir()) == []
    # aot refuses such a folder by itself too.
    aot.enable(folder)
    assert aot._dir is None
