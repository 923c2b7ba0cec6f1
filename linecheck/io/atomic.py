"""Atomic output: write to a temporary file in the target folder, then rename.

A failure (disk full, permission, cancel) never leaves a half-written file at
the destination.  An existing destination is replaced only when ``force`` is
true.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import stat
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from ..core.errors import CaseError


# Temporary files of a killed writer (SIGKILL, power loss) stay behind as ".NAME.XXXX.tmp";
# the next write of NAME removes those older than this process (a live writer in another
# process that started earlier is racing for the same file anyway).
_PROCESS_START = time.time()


def clean_stale_temporaries(path: str | Path) -> list[Path]:
    """Remove ``.NAME.*.tmp`` files left next to ``path`` by writers that died (returns them)."""
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    removed = []
    try:
        candidates = list(parent.glob(f".{glob.escape(p.name)}.*.tmp"))
    except OSError:
        return removed
    for tmp in candidates:
        with contextlib.suppress(OSError):
            st = tmp.lstat()
            if (stat.S_ISREG(st.st_mode) and st.st_mtime < _PROCESS_START
                    and getattr(os, "getuid", lambda: st.st_uid)() == st.st_uid):
                tmp.unlink()
                removed.append(tmp)
    return removed


def check_target(path: str | Path, *, force: bool = True, what: str = "output") -> Path:
    """Validate an output path before any work is done (clear one-line errors)."""
    p = Path(path)
    if p.exists() and p.is_dir():
        raise CaseError(f"{what} path is a directory, expected a file name", file=str(p))
    if p.exists() and not force:
        raise CaseError(f"{what} file exists; use --force to replace it", file=str(p))
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.exists():
        raise CaseError(f"folder {parent} does not exist", file=str(p))
    if not os.access(parent, os.W_OK):
        raise CaseError(f"folder {parent} is not writable", file=str(p))
    return p


@contextlib.contextmanager
def atomic_path(path: str | Path, *, force: bool = True, what: str = "output") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it over ``path`` on success.

    An ``OSError`` while writing or renaming (a full disk, ENOSPC; a quota; an I/O error)
    becomes a one-line :class:`CaseError` (exit 2) naming the file; the temporary file is
    removed and an existing ``path`` is left as it was.
    """
    p = check_target(path, force=force, what=what)
    clean_stale_temporaries(p)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent if str(p.parent) else ".")
    except OSError as exc:
        raise CaseError(_os_message(what, exc), file=str(p)) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        # mkstemp creates 0600; give the output the permissions a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)
        if p.exists() and not force:
            raise CaseError(f"{what} file appeared while writing; use --force to replace it", file=str(p))
        try:
            os.replace(tmp_path, p)
        except PermissionError:
            raise CaseError(f"cannot replace {what} file (is it open in another program?)", file=str(p)) from None
    except OSError as exc:
        raise CaseError(_os_message(what, exc), file=str(p)) from None
    finally:
        with contextlib.suppress(OSError):
            tmp_path.unlink()


def _os_message(what: str, exc: OSError) -> str:
    """One line for an operating-system error while writing an output file."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    if exc.errno == errno.ENOSPC:
        reason = "no space left on device; free some space and run again (nothing was written)"
    elif exc.errno == errno.EDQUOT:
        reason = "disk quota exceeded; free some space and run again (nothing was written)"
    return f"cannot write {what} file: {reason}"


def write_atomic(path: str | Path, writer: Callable[[Path], None], *, force: bool = True, what: str = "output") -> Path:
    """Call ``writer(tmp_path)`` and move the result to ``path`` atomically."""
    with atomic_path(path, force=force, what=what) as tmp:
        writer(tmp)
    return Path(path)


def write_text_atomic(path: str | Path, text: str, *, force: bool = True, what: str = "output") -> Path:
    return write_atomic(path, lambda t: t.write_text(text, encoding="utf-8"), force=force, what=what)
