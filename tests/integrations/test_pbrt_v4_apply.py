"""The patch tool for upstream pbrt-v4 (integrations/pbrt-v4/apply.py), without building pbrt-v4.

On a synthetic tree made of the patch's own anchors, and on a copy of the few upstream files
it edits (../shared/upstream/pbrt-v4, skipped when absent): it patches, recognizes its own
result (idempotent), and refuses a tree with a missing anchor or a partial patch without
changing a byte.
"""
from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "integrations" / "pbrt-v4"
sys.path.insert(0, str(TOOL))
spec = importlib.util.spec_from_file_location("pbrt_v4_apply", TOOL / "apply.py")
apply = importlib.util.module_from_spec(spec)
spec.loader.exec_module(apply)
edits = apply  # CHECKS, EDITS, MARKER, NEW_FILES are imported into apply's namespace


def edited_paths() -> set[str]:
    return {e.path for e in apply.EDITS} | {c.path for c in apply.CHECKS}


def snapshot(root: Path) -> dict[str, tuple[bytes, int]]:
    return {str(p.relative_to(root)): (p.read_bytes(), p.stat().st_mtime_ns)
            for p in sorted(root.rglob("*")) if p.is_file()}


def synthetic_tree(root: Path) -> Path:
    """A tree whose files hold exactly the patch's anchors (each as often as it expects)."""
    parts: dict[str, list[str]] = {}
    for c in apply.CHECKS:
        parts.setdefault(c.path, []).append(c.anchor)
    for e in apply.EDITS:
        parts.setdefault(e.path, []).extend([e.anchor] * e.count)
    for rel, chunks in parts.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("// upstream\n" + "\n// between anchors\n".join(chunks) + "\n// end\n")
    return root


def upstream_copy(shared: Path, root: Path) -> Path:
    upstream = shared / "upstream" / "pbrt-v4"
    if not (upstream / "src" / "pbrt").is_dir():
        pytest.skip("../shared/upstream/pbrt-v4 is not present")
    for rel in edited_paths():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(upstream / rel, root / rel)
    return root


def run(root: Path, *extra: str) -> int:
    return apply.main([str(root), *extra])


def test_patches_then_is_idempotent(tmp_path, capsys):
    root = synthetic_tree(tmp_path / "t")
    assert run(root, "--check") == 1
    assert run(root) == 0
    for e in apply.EDITS:
        assert (root / e.path).read_text().count(e.replacement) == e.count
    for rel, src in apply.NEW_FILES.items():
        assert (root / rel).read_bytes() == src.read_bytes()
    before = snapshot(root)
    capsys.readouterr()
    assert run(root) == 0
    assert "already patched" in capsys.readouterr().out
    assert snapshot(root) == before  # nothing rewritten, not even touched
    assert run(root, "--check") == 0


@pytest.mark.parametrize("index", range(len(apply.EDITS)))
def test_missing_anchor_is_refused_untouched(tmp_path, capsys, index):
    root = synthetic_tree(tmp_path / "t")
    e = apply.EDITS[index]
    path = root / e.path
    # Another pbrt-v4 version: the anchor's first line reads differently.
    first = e.anchor.strip("\n").splitlines()[0]
    path.write_text(path.read_text().replace(first, first + " /* changed upstream */"))
    before = snapshot(root)
    assert run(root) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "anchor not found" in err and first.strip() in err
    assert "nothing was changed" in err
    assert snapshot(root) == before


def test_missing_checked_snippet_is_refused(tmp_path, capsys):
    root = synthetic_tree(tmp_path / "t")
    c = apply.CHECKS[0]
    path = root / c.path
    path.write_text(path.read_text().replace("lambda, pdf;", "pdf, lambda;"))
    before = snapshot(root)
    assert run(root) == 2
    assert str(path) in capsys.readouterr().err
    assert snapshot(root) == before


def test_partly_patched_tree_is_refused(tmp_path, capsys):
    root = synthetic_tree(tmp_path / "t")
    pristine = {rel: (root / rel).read_text() for rel in edited_paths()}
    assert run(root) == 0
    rel = apply.EDITS[-1].path
    (root / rel).write_text(pristine[rel])  # one file back to upstream's text
    before = snapshot(root)
    assert run(root) == 2
    assert "partly patched" in capsys.readouterr().err
    assert snapshot(root) == before


def test_missing_file_is_refused(tmp_path, capsys):
    root = synthetic_tree(tmp_path / "t")
    (root / "src" / "pbrt" / "materials.h").unlink()
    before = snapshot(root)
    assert run(root) == 2
    assert "materials.h: file not found" in capsys.readouterr().err
    assert snapshot(root) == before


@pytest.mark.shared
def test_real_upstream_files(tmp_path, shared, capsys):
    root = upstream_copy(shared, tmp_path / "u")
    assert run(root) == 0
    patched = snapshot(root)
    for e in apply.EDITS:
        assert (root / e.path).read_text().count(e.replacement) == e.count, e.anchor
    assert run(root) == 0
    assert snapshot(root) == patched
    # Without the flag nothing changes: every upstream call the patch wraps is still made.
    integ = (root / "src/pbrt/cpu/integrators.cpp").read_text()
    assert integ.count("SampleCameraWavelengths(") == 5
    assert "lambda.TerminateSecondary();" not in (root / "src/pbrt/materials.h").read_text()
