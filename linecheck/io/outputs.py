"""Output paths checked against a command's inputs and against each other, before any work.

An output that is one of the command's inputs (the case file, its tower table ``towers_file``,
its running-mean field file, a result being exported, an Excel template) would be replaced by
the output; one path given for two outputs (``--json out.xlsx --excel out.xlsx``) would get
one output, then the other.  Both are refused with one line (:class:`CaseError`, exit 2) before
anything is computed or written.  Paths are compared resolved (``os.path.realpath``: relative
names, ``..`` and symbolic links) and, where both exist, as files (``os.path.samefile``: hard
links).  A character device or FIFO (``/dev/null``) may take several outputs: nothing is
replaced there (:mod:`linecheck.io.atomic`).
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..core.errors import CaseError

#: ``(what, path)``: what the path is to the command ("--json", "case file", ...); None: not given.
Named = tuple[str, "str | Path | None"]


def same_file(a: str | Path, b: str | Path) -> bool:
    """Whether ``a`` and ``b`` name the same file: the same resolved path, or (both existing)
    the same device and inode."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def _is_device(path: str | Path) -> bool:
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


def case_inputs(case: Any) -> list[tuple[str, Path]]:
    """The files a case reads: the case file itself, its tower table (``line.towers_file``,
    relative to the case file) and its running-mean field (``wind.downburst.field``)."""
    items: list[tuple[str, Path]] = []
    source = getattr(case, "source", None)
    if source is not None:
        items.append(("case file", Path(source)))
    towers = getattr(case.line, "towers_file", None)
    if towers:
        p = Path(towers)
        if not p.is_absolute() and source is not None:
            p = Path(source).parent / p
        items.append(("tower table (line.towers_file)", p))
    db = getattr(case.wind, "downburst", None)
    if db is not None and getattr(db, "field_path", None) is not None:
        items.append(("field file (wind.downburst.field)", Path(db.field_path)))
    return items


def check_outputs(outputs: Iterable[Named], inputs: Iterable[Named] = ()) -> None:
    """Refuse (one-line :class:`CaseError`) an output that is one of ``inputs`` or that another
    output already names.  ``outputs``/``inputs``: ``(what, path)`` pairs, ``path`` None when
    the option was not given."""
    outs = [(what, Path(p)) for what, p in outputs if p is not None and str(p)]
    ins = [(what, Path(p)) for what, p in inputs if p is not None and str(p)]
    for i, (what, p) in enumerate(outs):
        for what_in, q in ins:
            if same_file(p, q):
                raise CaseError(f"{what} would overwrite the {what_in}, an input of this command: give the output "
                                "another file name (nothing was written)", file=str(p))
        if _is_device(p):
            continue
        for what_before, p_before in outs[:i]:
            if same_file(p, p_before):
                raise CaseError(f"the same file is given for {what_before} and {what}: give each output its own "
                                "file (nothing was written)", file=str(p))
