"""The compile cache seen by a user (design §7): the first run's progress
line says it compiles once and how long that takes, with no estimate of the time left until
evaluations run; the cache's place and size are in --help; ``cache info|clear|warm``."""
from __future__ import annotations

import io
import os
import subprocess
import sys
import time

import pytest

from wavelength_pdf import compile_cache, progress
from wavelength_pdf.cli import build_parser, main


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "jax"
    monkeypatch.setenv("WAVELENGTH_PDF_JAX_CACHE", str(folder))
    return folder


def _fill(folder, tag="00000000"):
    """A cache as JAX and the package leave it, plus a file of the user's that is not the cache's."""
    (folder / "executables").mkdir(parents=True)
    (folder / "jit__objective-abc-cache").write_bytes(b"x" * 1000)
    (folder / "jit__objective-abc-atime").write_bytes(b"t" * 8)
    (folder / "executables" / f"penalized_in-{tag}-0123.pkl").write_bytes(b"p" * 2000)
    (folder / "executables" / "key").write_bytes(b"k" * 32)
    (folder / "notes.txt").write_text("mine")
    (folder / "executables" / "README").write_text("mine too")


def test_place_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("WAVELENGTH_PDF_JAX_CACHE", "off")
    assert compile_cache.cache_dir() is None
    assert "off" in compile_cache.info().describe()
    monkeypatch.delenv("WAVELENGTH_PDF_JAX_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert compile_cache.cache_dir() == tmp_path / "wavelength-pdf" / "jax"


def test_info_counts_only_the_caches_files_and_clear_deletes_only_them(cache):
    _fill(cache)
    got = compile_cache.info()
    assert (got.path, got.files, got.bytes) == (cache, 4, 1000 + 8 + 2000 + 32)
    assert not got.warm  # the tag is not this installation's
    text = got.describe()
    assert str(cache) in text and "3.0 kB" in text and "cache clear" in text and "cold" in text
    assert compile_cache.clear() == (4, 3040)
    assert sorted(p.name for p in cache.rglob("*")) == ["README", "executables", "notes.txt"]
    assert compile_cache.info().files == 0


def test_clear_does_not_follow_symbolic_links(cache, tmp_path):
    _fill(cache)
    outside = tmp_path / "precious-cache"
    outside.write_text("keep")
    (cache / "link-cache").symlink_to(outside)
    compile_cache.clear()
    assert outside.read_text() == "keep" and (cache / "link-cache").is_symlink()


def test_warm_is_this_installations_tag(cache):
    from wavelength_pdf import aot

    _fill(cache)
    assert not compile_cache.is_warm()
    (cache / "executables" / f"to_P-{aot.environment_tag(x64=True)}-feed.pkl").write_bytes(b"")
    assert compile_cache.is_warm()
    assert "loading the compiled optimizer" in progress.preparing_message()


def test_first_run_says_it_compiles_once_and_how_long(cache):
    msg = progress.preparing_message()
    assert "compiling the optimizer once" in msg and compile_cache.FIRST_COMPILE in msg and str(cache) in msg


def test_no_estimate_of_time_left_until_evaluations_run():
    """A 35 s compilation then one evaluation used to read as hours left: the estimate now
    counts from the first evaluation, and the plain log says first what is going on."""
    out = io.StringIO()
    p = progress.OptimizationProgress("lamp", 1000, stream=out, interval=0.0,
                                      preparing="compiling the optimizer once (usually 30-60 s)")
    p.start -= 35.0  # the compilation
    p(1, 5.0)
    first = p.first[0]
    p.first = (first - 1.0, 1)  # then 100 evaluations in a second
    p(101, 1.0)
    p.close()
    lines = out.getvalue().splitlines()
    assert lines[0] == "lamp: compiling the optimizer once (usually 30-60 s)"
    assert "s left" not in lines[1]  # one evaluation: no rate yet
    left = float(lines[2].split("at most ")[1].split(" s left")[0])
    assert 5 <= left <= 15, lines  # 899 evaluations at 100 a second, not (36 s / 101) x 899


def test_the_bar_on_a_terminal_shows_no_eta_while_compiling():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    out = Tty()
    p = progress.OptimizationProgress("lamp", 1000, stream=out, preparing="compiling the optimizer once")
    p.bar.refresh()
    before = out.getvalue()
    assert "compiling the optimizer once" in before and "?" not in before and "<" not in before
    p(5, 1.0)
    assert p.bar.bar_format is None and p.bar.n == 5
    p.close()


def test_help_says_where_the_cache_is_and_how_big(cache, capsys):
    _fill(cache)
    for argv in (["--help"], ["optimize", "--help"], ["cache", "--help"]):
        with pytest.raises(SystemExit):
            build_parser().parse_args(argv)
        text = " ".join(capsys.readouterr().out.split())
        assert str(cache) in text and "4 files, 3.0 kB now" in text, argv
        assert "cache clear" in text and "cache warm" in text and "WAVELENGTH_PDF_JAX_CACHE" in text


def test_cache_command_info_and_clear(cache, capsys):
    _fill(cache)
    assert main(["cache"]) == 0 and str(cache) in capsys.readouterr().out
    assert main(["cache", "clear"]) == 0
    assert "deleted 4 files" in capsys.readouterr().out
    assert compile_cache.info().files == 0


@pytest.mark.slow
def test_warm_fills_the_cache_and_the_next_run_starts_at_once(cache):
    """``cache warm`` compiles for the default grid; an optimize on that grid afterwards
    reads compiled code and reports evaluations within seconds."""
    env = {**os.environ, "WAVELENGTH_PDF_JAX_CACHE": str(cache)}
    run = subprocess.run([sys.executable, "-m", "wavelength_pdf", "cache", "warm", "--max-evals", "5"],
                         capture_output=True, text=True, env=env, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "holds compiled code for this installation" in run.stdout
    t = time.monotonic()
    run = subprocess.run([sys.executable, "-m", "wavelength_pdf", "optimize", "cie:D65", "-o",
                          str(cache.parent / "d65.csv"), "--max-evals", "5"],
                         capture_output=True, text=True, env=env, timeout=900)
    assert run.returncode in (0, 1), run.stderr[-2000:]
    assert "loading the compiled optimizer" in run.stderr
    assert time.monotonic() - t < 40, "the warmed cache was not used"


def test_executables_carry_the_tag_that_is_warm_looks_for(tmp_path):
    """The optimizer runs in float64: the executables it keeps are named with the float64
    tag, the one :func:`compile_cache.is_warm` looks for, whatever mode asked first."""
    import jax
    import jax.numpy as jnp

    from wavelength_pdf import aot

    assert aot.environment_tag(x64=True) != aot.environment_tag(x64=False)
    aot.enable(tmp_path / "executables")
    try:
        assert jax.config.jax_enable_x64  # as tests/conftest.py sets it, and the optimizer runs
        f = aot.disk_jit(lambda x: x * 2.0)
        f(jnp.ones(3))
        (path,) = (tmp_path / "executables").glob("*.pkl")
        assert f"-{aot.environment_tag(x64=True)}-" in path.name
        assert compile_cache.is_warm(tmp_path)
    finally:
        aot.enable(None)
