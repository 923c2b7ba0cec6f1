"""The per-case result files of a batch: the results folder, file names, the saved
document (reused by ``--resume``) and why a result could not be written.

A case's result is ``<json_dir>/<file stem>.json``: the typed
:func:`~linecheck.io.jsonout.run_document` plus its :class:`BatchSource` (the case file,
its hash and the key changes applied to it), written atomically.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..core.errors import CaseError
from ..io.document import BatchSource, RunDocument


def json_name_for(path: Path) -> str:
    return f"{path.stem}.json"


def results_folder(json_dir: str | Path | None, resume: bool) -> Path | None:
    """The results folder of a batch, created if missing and checked writable (``None``: no files).

    Raises CaseError (exit 2): ``resume`` without a folder, a file in its place, a folder that
    cannot be created or written.
    """
    out_dir = Path(json_dir) if json_dir is not None else None
    if resume and out_dir is None:
        raise CaseError("--resume needs a results folder (--json-dir)")
    if out_dir is not None:
        if out_dir.exists() and not out_dir.is_dir():
            raise CaseError("results folder is a file, expected a folder", file=str(out_dir))
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CaseError(f"cannot create results folder: {exc.strerror}", file=str(out_dir)) from None
        check_writable(out_dir)
    return out_dir


def check_writable(folder: Path) -> None:
    """CaseError (exit 2) unless a file can be created in ``folder`` -- checked before any
    computing by writing and removing a probe file (``os.access`` is wrong for root and for
    read-only mounts)."""
    import os
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".linecheck-probe.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise CaseError(f"results folder is not writable: {exc.strerror or exc}", file=str(folder)) from None
    os.close(fd)
    Path(probe).unlink(missing_ok=True)


def saved_result(json_path: Path, digest: str, changes: Mapping[str, Any] | None = None) -> RunDocument | None:
    """The saved document at ``json_path``, typed, if it carries ``digest`` as its case hash
    (and the same key ``changes``, for runs that alter the file's case); None when it is
    missing, damaged, of another schema version or of another case (it is then run again)."""
    from ..io.document import read_result_file

    try:  # a regular file of bounded size (a FIFO there must not hang), parsable JSON (not 100,000
        doc = read_result_file(json_path)  # nested brackets, not a 5,001-digit integer): else run it again
    except CaseError:
        return None
    try:  # saved by an older linecheck, or damaged: run it again
        typed = RunDocument.from_json(doc, source=str(json_path))
    except CaseError:
        return None
    if typed.batch is None or typed.batch.case_hash != digest:
        return None
    if typed.batch.changes != (json.loads(json.dumps(dict(changes))) if changes else None):
        return None
    return typed


def result_document(result: Any, path: Path, digest: str | None,
                    changes: Mapping[str, Any] | None = None) -> RunDocument:
    """The per-case typed document: the run's plus its :class:`BatchSource` (``"case_file"``,
    ``"case_hash"`` and ``"changes"`` in the JSON)."""
    from dataclasses import replace

    from ..io.jsonout import run_document

    return replace(run_document(result),
                   batch=BatchSource(str(path), digest, {k: v for k, v in changes.items()} if changes else None))


def save_result(json_path: Path, doc: RunDocument) -> None:
    """Write a case's document atomically (:func:`linecheck.io.jsonout.write_json`)."""
    from ..io import jsonout

    jsonout.write_json(json_path, doc)


def write_failure(exc: BaseException) -> str:
    """Why a result could not be written: the operating system's reason (``No space left on
    device``), also when the atomic writer reported it as a one-line CaseError naming the file."""
    cause = exc if isinstance(exc, OSError) else (exc.__cause__ or exc.__context__)
    if isinstance(cause, OSError):
        return cause.strerror or str(cause) or type(cause).__name__
    text = str(exc)
    file = getattr(exc, "file", None)
    return text[len(file) + 2:] if file and text.startswith(f"{file}: ") else text
