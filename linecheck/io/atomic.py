"""Atomic output: write to a temporary file in the target folder, then rename.

A failure (disk full, permission, cancel) never leaves a half-written file at
the destination.  An existing destination is replaced only when ``force`` is
true.

What the output path names decides how it is written (:func:`output_kind`):

- a new name or a regular file: temporary file in the same folder, renamed over it;
- a symbolic link to a regular file: the link is followed and its *target* is replaced
  atomically (temporary file in the target's folder), so the link stays a link;
- a character device or a FIFO (``/dev/null``, a terminal, a named pipe): the output is
  built completely in a temporary file first, then copied to it (never replaced by a file);
  a FIFO that no process reads is refused (nothing hangs);
- a dangling symbolic link, a link loop, a block device or a socket: refused, one line.
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
                    and getattr(os, "getuid", lambda: st.st_uid)() == st.st_uid):  # noqa: B023 - called at once, in this iteration
                tmp.unlink()
                removed.append(tmp)
    return removed


#: How an output path is written (:func:`output_kind`): a regular file (or a new name), or a
#: character device / FIFO written through.
FILE, DEVICE = "file", "device"


def output_kind(path: str | Path, what: str = "output") -> tuple[str, Path]:
    """``(kind, target)`` of an output path: ``(FILE, path)`` for a new name or a regular file,
    ``(FILE, resolved target)`` for a symbolic link to a regular file, ``(DEVICE, path)`` for a
    character device or a FIFO; :class:`CaseError` (one line) for a folder, a dangling link, a
    link loop, a block device or a socket."""
    p = Path(path)
    try:
        st = os.stat(p)  # follows symbolic links
    except FileNotFoundError:
        if os.path.islink(p):
            try:
                dest = os.readlink(p)
            except OSError:
                dest = "?"
            raise CaseError(f"{what} path is a symbolic link to {dest}, which does not exist: remove the link "
                            "or give the path of a file to write", file=str(p)) from None
        return FILE, p
    except NotADirectoryError:
        raise CaseError(f"folder {p.parent} is not writable: part of it is a file, not a folder",
                        file=str(p)) from None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise CaseError(f"{what} path is a loop of symbolic links: expected a file name", file=str(p)) from None
        raise CaseError(f"cannot use {what} path: {exc.strerror or exc}", file=str(p)) from None
    mode = st.st_mode
    if stat.S_ISDIR(mode):
        raise CaseError(f"{what} path is a directory, expected a file name", file=str(p))
    if stat.S_ISCHR(mode) or stat.S_ISFIFO(mode):
        return DEVICE, p
    if not stat.S_ISREG(mode):
        kind = "a block device" if stat.S_ISBLK(mode) else ("a socket" if stat.S_ISSOCK(mode) else "not a regular file")
        raise CaseError(f"{what} path is {kind}: expected a file name (or a character device or FIFO)",
                        file=str(p))
    return FILE, (Path(os.path.realpath(p)) if os.path.islink(p) else p)


def check_target(path: str | Path, *, force: bool = True, what: str = "output") -> Path:
    """Validate an output path before any work is done (clear one-line errors).

    A symbolic link is checked at its target (its folder must be writable); a character device
    or FIFO needs no folder and no ``force`` (it is written through, nothing is replaced).
    """
    p = Path(path)
    if not str(path):
        raise CaseError(f"{what} path is empty: expected a file name")
    kind, target = output_kind(p, what)
    if kind == DEVICE:
        return p
    if target.exists() and not force:
        raise CaseError(f"{what} file exists; use --force to replace it", file=str(p))
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.exists():
        raise CaseError(f"folder {parent} does not exist", file=str(p))
    if not os.access(parent, os.W_OK):
        raise CaseError(f"folder {parent} is not writable", file=str(p))
    return p


@contextlib.contextmanager
def atomic_path(path: str | Path, *, force: bool = True, what: str = "output") -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it over ``path`` on success.

    A symbolic link is followed: its target is replaced, the link stays.  A character device or
    a FIFO gets the finished temporary file's bytes written through to it (the temporary file is
    then in the system's temporary folder).  An ``OSError`` while writing or renaming (a full
    disk, ENOSPC; a quota; an I/O error) becomes a one-line :class:`CaseError` (exit 2) naming
    the file; the temporary file is removed and an existing ``path`` is left as it was.
    """
    p = check_target(path, force=force, what=what)
    kind, target = output_kind(p, what)
    if kind == FILE:
        clean_stale_temporaries(target)
    folder = (target.parent if str(target.parent) else Path(".")) if kind == FILE else None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise CaseError(_os_message(what, exc), file=str(p)) from None
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if kind == DEVICE:
            _write_through(tmp_path, p, what)
            return
        # mkstemp creates 0600; give the output the permissions a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)
        if target.exists() and not force:
            raise CaseError(f"{what} file appeared while writing; use --force to replace it", file=str(p))
        try:
            os.replace(tmp_path, target)
        except PermissionError:
            raise CaseError(f"cannot replace {what} file (is it open in another program?)", file=str(p)) from None
    except OSError as exc:
        raise CaseError(_os_message(what, exc), file=str(p)) from None
    finally:
        with contextlib.suppress(OSError):
            tmp_path.unlink()


def _write_through(tmp: Path, device: Path, what: str) -> None:
    """Copy the finished output ``tmp`` to a character device or FIFO ``device`` (no file is
    created or replaced).  A FIFO without a reader is refused instead of waiting for one."""
    flags = os.O_WRONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(device, flags)
    except OSError as exc:
        if exc.errno == errno.ENXIO:
            raise CaseError("no process is reading this FIFO: start the reader first (nothing was written)",
                            file=str(device)) from None
        raise
    try:
        st = os.fstat(fd)
        if not (stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode)):  # replaced since it was checked
            raise CaseError(f"{what} path is no longer a device or FIFO: nothing was written", file=str(device))
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        with open(tmp, "rb") as src:
            while chunk := src.read(1 << 20):
                view = memoryview(chunk)
                while view:
                    view = view[os.write(fd, view):]
    finally:
        os.close(fd)


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
