"""Reading input files: regular files only, with a cap on their size (design §2.3, §3.3).

A path named as a table, a spectrum, a reflectance file or a scene can be anything: a
device that never ends (``/dev/zero``), a FIFO whose reader blocks until someone writes, a
directory. Such a file is refused before a byte is read: it is opened without blocking
(``O_NONBLOCK``: opening a FIFO for reading would otherwise wait for a writer), and the
*opened* descriptor must be a regular file (``fstat``; checking the path first and opening
it afterwards would race with a rename). A regular file larger than the cap is refused
too, and at most cap + 1 bytes are ever read (the file may grow while it is read).

The messages are those of the C++ readers (``wavelength_table::ReadTableFile`` and pbrt's
``ReadRegularFile``) for the same files: ``PATH: reason``.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

__all__ = ["MAX_INPUT_BYTES", "InputFileError", "read_regular_file", "read_input_bytes",
           "read_input_text"]

#: The size cap of tables (design §2.3), spectra (§3.3) and reflectance files (§3.4): far
#: above any real one (a table at 0.1 nm steps over 360-830 nm is ~0.5 MB).
MAX_INPUT_BYTES = 64 << 20


class InputFileError(ValueError):
    """A file that is not read: ``path`` and ``reason``; the message reads ``PATH: reason``."""

    def __init__(self, path: Path, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path, self.reason = path, reason


def read_regular_file(path: str | os.PathLike, what: str,
                      max_bytes: int | None = MAX_INPUT_BYTES) -> bytes:
    """The bytes of the regular file ``path``, at most ``max_bytes`` of them (None: no cap);
    ``what`` names the kind of file in messages ("table", "spectrum", ...).

    Raises
    ------
    InputFileError
        Missing, a directory, not a regular file, larger than the cap, or unreadable.
    """
    path = Path(path)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except (FileNotFoundError, NotADirectoryError):
        raise InputFileError(path, "no such file") from None
    except IsADirectoryError:
        raise InputFileError(path, f"is a directory, not a {what} file") from None
    except OSError as e:
        raise InputFileError(path, f"cannot read ({e.strerror})") from None
    too_large = f"larger than {(max_bytes or 0) >> 20} MiB, not a {what} file"
    # The descriptor's kind first: a file object cannot even be made of a directory's.
    st = os.fstat(fd)
    reason = ""
    if stat.S_ISDIR(st.st_mode):
        reason = f"is a directory, not a {what} file"
    elif not stat.S_ISREG(st.st_mode):
        reason = f"not a regular file (a device, FIFO or socket), not a {what} file"
    elif max_bytes is not None and st.st_size > max_bytes:
        reason = too_large
    if reason:
        os.close(fd)
        raise InputFileError(path, reason)
    with os.fdopen(fd, "rb") as fh:
        try:
            data = fh.read() if max_bytes is None else fh.read(max_bytes + 1)
        except OSError as e:
            raise InputFileError(path, f"cannot read ({e.strerror})") from None
    if max_bytes is not None and len(data) > max_bytes:  # it grew while it was read
        raise InputFileError(path, too_large)
    return data


def read_input_bytes(path: str | os.PathLike, what: str, error: type[Exception],
                     max_bytes: int | None = MAX_INPUT_BYTES) -> bytes:
    """:func:`read_regular_file`, raising ``error("PATH: reason")`` instead (the reader's own
    error type: TableError, SpectrumError)."""
    try:
        return read_regular_file(path, what, max_bytes)
    except InputFileError as e:
        raise error(str(e)) from None


def read_input_text(path: str | os.PathLike, what: str, error: type[Exception],
                    max_bytes: int | None = MAX_INPUT_BYTES) -> str:
    """:func:`read_input_bytes` decoded as UTF-8 (a byte-order mark skipped, bytes that are
    not UTF-8 replaced by U+FFFD, so that they fail as text, not as a decoding error)."""
    return read_input_bytes(path, what, error, max_bytes).decode("utf-8-sig", errors="replace")
