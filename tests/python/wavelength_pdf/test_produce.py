"""wavelength_pdf.produce: output paths are checked before any optimization starts."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from wavelength_pdf import cli, produce
from wavelength_pdf.produce import OutputPathError, check_output_path


def test_writable_paths_pass_and_leave_nothing_behind(tmp_path):
    check_output_path(tmp_path / "t.csv")
    check_output_path(tmp_path / "new" / "sub" / "t.csv")  # directories are created later
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("bad, reason", [
    ("", "empty output file name"),
    ("/proc/t.csv", "cannot create a file in /proc"),
    ("/proc/no/such/t.csv", "cannot create a file in /proc"),
])
def test_unwritable_paths_are_refused(bad, reason):
    if bad.startswith("/proc") and not Path("/proc/self").exists():
        pytest.skip("no /proc on this system")
    with pytest.raises(OutputPathError, match=reason):
        check_output_path(Path(bad) if bad else bad)


def test_a_directory_or_a_file_as_directory_is_refused(tmp_path):
    with pytest.raises(OutputPathError, match="is a directory"):
        check_output_path(tmp_path)
    (tmp_path / "f").write_text("x")
    with pytest.raises(OutputPathError, match="is not a directory"):
        check_output_path(tmp_path / "f" / "t.csv")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere the bits forbid")
def test_read_only_directory_is_refused(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(OutputPathError, match="cannot create"):
            check_output_path(ro / "t.csv")
    finally:
        ro.chmod(0o700)


@pytest.mark.parametrize("out", ["/proc/t.csv", ""])
def test_optimize_refuses_a_bad_output_before_optimizing(monkeypatch, capsys, out):
    import wavelength_pdf.optimize as optimize

    def must_not_run(*args, **kwargs):
        raise AssertionError("the optimizer ran before the output path was checked")

    monkeypatch.setattr(optimize, "optimize_spectrum", must_not_run)
    status = cli.main(["optimize", "cie:A", "-o", out, "--quiet"])
    assert status == cli.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert ("cannot create a file in /proc" in err) if out else ("empty output path" in err), err
    assert not Path("A.csv").exists()


@pytest.mark.parametrize("value", ["-1", "0", "nan", "inf", "-inf", "x"])
def test_max_seconds_must_be_a_positive_finite_number(capsys, value):
    with pytest.raises(SystemExit) as e:
        cli.main(["optimize", "cie:A", "-o", "x.csv", "--max-seconds", value])
    assert e.value.code == 2
    assert "--max-seconds" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["0", "-3", "two"])
def test_batch_jobs_must_be_at_least_one(tmp_path, capsys, value):
    with pytest.raises(SystemExit) as e:
        cli.main(["batch", str(tmp_path), "-o", str(tmp_path / "out"), "--jobs", value])
    assert e.value.code == 2
    assert "--jobs" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_accepted_limits_still_parse():
    args = cli.build_parser().parse_args(["optimize", "cie:A", "-o", "x.csv", "--max-seconds", "2.5"])
    assert args.max_seconds == 2.5
    args = cli.build_parser().parse_args(["batch", "d", "-o", "o", "--jobs", "3"])
    assert args.jobs == 3
    assert produce.check_output_path is check_output_path
