"""Safe reading of user files: a case file, a tower table, a field file, a saved result.

Only regular files are read (a FIFO, a socket or a link to a device is refused before any read)
and only up to a size cap checked before and while reading; every refusal is a one-line
:class:`~.errors.CaseError` naming the file and what was expected.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import CaseError

MAX_CASE_BYTES = 10 * 2**20  # [bytes] size cap of a TOML case file (docs/case-files.md)
MAX_RESULT_BYTES = 2**30  # [bytes] size cap of a saved JSON result read back (export, batch --resume)


def _size_text(n: int) -> str:
    return f"{n / 2**20:.1f} MB" if n >= 2**20 else f"{n} bytes"


def read_regular_file(path: str | Path, expected: str, max_bytes: int) -> bytes:
    """Bytes of a user file, read only if it is a regular file of at most ``max_bytes``.

    The file is opened without blocking (a FIFO never hangs), checked with ``fstat`` after
    opening (a symlink to /dev/zero or a device is refused before any read), its size is
    checked before reading, and at most ``max_bytes + 1`` bytes are read (a file growing
    while read is still refused).  One-line :class:`CaseError` naming the file otherwise.
    """
    p = Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except FileNotFoundError:
        raise CaseError(f"file not found (expected {expected})", file=str(p)) from None
    except IsADirectoryError:
        raise CaseError(f"is a directory, expected {expected}", file=str(p)) from None
    except OSError as exc:
        raise CaseError(f"cannot read: {exc.strerror}", file=str(p)) from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise CaseError(f"is a directory, expected {expected}", file=str(p))
        if not stat.S_ISREG(st.st_mode):
            raise CaseError(f"is not a regular file (a pipe, socket or device), expected {expected}", file=str(p))
        if st.st_size > max_bytes:
            raise CaseError(f"file size {_size_text(st.st_size)} is too large: expected at most "
                            f"{_size_text(max_bytes)} ({expected})", file=str(p))
        chunks: list[bytes] = []
        left = max_bytes + 1
        while left > 0:
            b = os.read(fd, min(left, 2**20))
            if not b:
                break
            chunks.append(b)
            left -= len(b)
        if left <= 0:
            raise CaseError(f"file grew beyond {_size_text(max_bytes)} while read: expected at most "
                            f"{_size_text(max_bytes)} ({expected})", file=str(p))
        return b"".join(chunks)
    except OSError as exc:
        raise CaseError(f"cannot read: {exc.strerror}", file=str(p)) from None
    finally:
        os.close(fd)


def read_text_file(path: str | Path, expected: str, max_bytes: int = MAX_CASE_BYTES) -> str:
    """UTF-8 text of a user file; one-line :class:`CaseError` naming the file and ``expected``
    (e.g. "a TOML case file") when it is missing, a folder, not a regular file (FIFO, device),
    larger than ``max_bytes``, unreadable or not UTF-8.  A leading UTF-8 byte-order mark (which
    spreadsheets and some editors write) is dropped; the bytes, hence ``case_hash``, are as read."""
    data = read_regular_file(path, expected, max_bytes)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise CaseError(f"not a UTF-8 text file (expected {expected})", file=str(path)) from None
