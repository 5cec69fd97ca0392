#!/usr/bin/env python3
"""Apply the wavelength-pdf patch to an upstream pbrt-v4 checkout, in place.

    python3 integrations/pbrt-v4/apply.py UPSTREAM_DIR [--check]

The patched pbrt-v4 takes ``--wavelength-pdf TABLE.csv`` and ``--wavelength-pdf-defensive S``,
and ``--wavelength-sampling emission`` with ``--emission-weight W`` (a table built from the
scene's own lamps), in its CPU integrators and its wavefront integrator (CPU and GPU); without
them it renders what upstream renders. The edits are listed in ``edits.py``: each replaces an exact snippet
(an anchor) of upstream pbrt-v4 (commit 5f7a6068).

Every anchor is checked before anything is written. When one is missing (another pbrt-v4
version), the tool names the file and the anchor and exits with status 2, leaving the tree
untouched. A tree that is already patched is recognized (exit 0, nothing rewritten except
new files whose content changed); a tree with only some edits applied is refused. Files are
written through temporary files and renamed; if a write fails, the files already replaced
are restored.

``--check`` only reports the tree's state (status 0: patched, 1: unpatched, 2: neither).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from edits import CHECKS, EDITS, MARKER, NEW_FILES, UPSTREAM_COMMIT  # noqa: E402


class PatchError(Exception):
    """The tree does not fit the patch (the message names the file and the anchor)."""


def _show(anchor: str) -> str:
    lines = anchor.strip("\n").splitlines()
    text = "\n".join("    | " + line for line in lines[:6])
    return text + ("\n    | ..." if len(lines) > 6 else "")


def plan(root: Path) -> tuple[str, dict[Path, tuple[str, str]]]:
    """The tree's state ("unpatched" or "patched") and {file: (old text, new text)}.

    Raises PatchError when an anchor (or a checked snippet) is missing or the tree is
    partly patched. Reads only.
    """
    if not (root / "src" / "pbrt").is_dir():
        raise PatchError(f"{root}: not a pbrt-v4 checkout (no src/pbrt/)")
    texts: dict[Path, str] = {}

    def read(rel: str) -> str:
        path = root / rel
        if path not in texts:
            try:
                texts[path] = path.read_text(encoding="utf-8")
            except FileNotFoundError:
                raise PatchError(f"{path}: file not found (pbrt-v4 {UPSTREAM_COMMIT} has it)") from None
            except (OSError, UnicodeDecodeError) as e:
                raise PatchError(f"{path}: cannot read: {e}") from None
        return texts[path]

    for c in CHECKS:
        if c.anchor not in read(c.path):
            raise PatchError(f"{root / c.path}: anchor not found ({c.why}):\n{_show(c.anchor)}")

    new: dict[Path, str] = {}
    applied, pending = [], []
    for e in EDITS:
        path = root / e.path
        text = new.get(path, read(e.path))
        n_done, n_todo = text.count(e.replacement), text.count(e.anchor)
        if n_done == e.count:
            applied.append(e)
        elif n_todo == e.count:
            pending.append(e)
            new[path] = text.replace(e.anchor, e.replacement)
        else:
            found = f"found {n_todo}" if n_done == 0 else f"found {n_todo}, {n_done} already patched"
            raise PatchError(
                f"{path}: anchor not found (expected {e.count} occurrence"
                f"{'s' if e.count > 1 else ''}, {found}):\n{_show(e.anchor)}")
    if applied and pending:
        names = sorted({str(root / e.path) for e in pending})
        raise PatchError("the tree is partly patched; these edits are missing:\n    "
                         + "\n    ".join(names) + "\nstart again from a clean upstream checkout")
    state = "patched" if applied else "unpatched"
    # Any stray marker in an unpatched tree means someone edited it by hand.
    if state == "unpatched":
        for path, text in texts.items():
            if MARKER in text:
                raise PatchError(f"{path}: holds '{MARKER}' text but not the patch's edits")

    changes = {path: (texts[path], text) for path, text in new.items()}
    for rel, src in NEW_FILES.items():
        dest = root / rel
        content = src.read_text(encoding="utf-8")
        old = dest.read_text(encoding="utf-8") if dest.exists() else None
        if state == "unpatched" and old is not None:
            raise PatchError(f"{dest}: already exists in an unpatched tree")
        if old != content:
            changes[dest] = (old, content)
    return state, changes


def write(changes: dict[Path, tuple[str | None, str]]) -> None:
    """Write every file, or none: on an error, restore the files already written."""
    done: list[tuple[Path, str | None]] = []
    try:
        for path, (old, text) in changes.items():
            tmp = path.with_name(path.name + ".wavelength-pdf.tmp")
            tmp.write_text(text, encoding="utf-8")
            if path.exists():
                os.chmod(tmp, path.stat().st_mode & 0o7777)
            os.replace(tmp, path)
            done.append((path, old))
    except OSError:
        for path, old in reversed(done):
            if old is None:
                path.unlink(missing_ok=True)
            else:
                path.write_text(old, encoding="utf-8")
        for path in changes:
            path.with_name(path.name + ".wavelength-pdf.tmp").unlink(missing_ok=True)
        raise


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("upstream", type=Path, help="the pbrt-v4 checkout to patch in place")
    parser.add_argument("--check", action="store_true", help="only report the tree's state")
    args = parser.parse_args(argv)
    root = args.upstream.resolve()
    try:
        state, changes = plan(root)
    except PatchError as e:
        print(f"apply.py: {e}\napply.py: nothing was changed "
              f"(the patch is written for pbrt-v4 {UPSTREAM_COMMIT})", file=sys.stderr)
        return 2
    if args.check:
        print(f"{root}: {state}")
        return 0 if state == "patched" else 1
    if state == "patched" and not changes:
        print(f"{root}: already patched, nothing to do")
        return 0
    try:
        write(changes)
    except OSError as e:
        print(f"apply.py: {e}\napply.py: nothing was changed", file=sys.stderr)
        return 2
    what = "updated the patch's new files" if state == "patched" else "patched"
    print(f"{root}: {what} ({len(changes)} files: "
          + ", ".join(str(p.relative_to(root)) for p in changes) + ")")
    return 0


if __name__ == "__main__":
    sys.exit(main())
