"""Files the TUI writes: the edited case (save as) and the exports.  Plain Python, no Textual.

Every write is atomic and replaces an existing file only when ``replace`` is true.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..core.case import Case, case_to_toml, with_value
from ..io.atomic import write_text_atomic
from ..io.document import RunDocument
from .formatting import case_differences


def shipped_case_folders() -> list[Path]:
    """The case folders shipped with linecheck (``cases/`` of the checkout the package runs
    from): ``linecheck batch cases/paper/*.toml`` must find only the shipped cases there."""
    folder = Path(__file__).resolve().parents[2] / "cases"
    return [folder] if folder.is_dir() else []


def in_shipped_folder(path: Path) -> str | None:
    """A warning when ``path`` lies in a shipped case folder, else None."""
    p = Path(path).expanduser().resolve()
    for folder in shipped_case_folders():
        if p.is_relative_to(folder):
            return f"{p.parent} is a shipped case folder (batch cases/paper/*.toml would run this file)"
    return None


def save_as_default(name: str) -> Path:
    """Where "save as" proposes to write an edited case: the working directory, never a shipped
    case folder (the home directory when the working directory is one)."""
    folder = Path.cwd()
    if in_shipped_folder(folder / "x.toml"):
        folder = Path.home()
    return free_path(folder / f"{name}-edited.toml")


def free_path(path: Path) -> Path:
    """``path``, or ``stem-2.ext``, ``stem-3.ext``... the first that does not exist."""
    if not path.exists():
        return path
    n = 2
    while (candidate := path.with_name(f"{path.stem}-{n}{path.suffix}")).exists():
        n += 1
    return candidate


def case_for_saving(case: Case, original: Case | None, path: Path) -> Case:
    """``case`` as it will be written to ``path``.

    Unless the user changed them: the name becomes the file stem (results and sheets of
    the two files stay apart) and the description notes the edits (the old description
    would describe the old values).  Raises :class:`CaseError` like any edit.
    """
    if original is None:
        return case
    out = case
    if out.name == original.name:
        out = with_value(out, "name", path.stem)
    if out.description == original.description:
        edits = [f"{k} = {b}" for k, _a, b in case_differences(original, out) if k not in ("name", "description")]
        if edits:
            note = f"edited from {original.name}: " + ", ".join(edits)
            out = with_value(out, "description", f"{out.description} ({note})" if out.description else note)
    return out


def edit_note(case: Case, original: Case | None) -> str | None:
    """``"edited: wind.v_ref 40 → 30, ..."`` for the value keys of ``case`` that differ from the
    file it was opened from (None when none differ)."""
    if original is None:
        return None
    edits = [f"{k} {a} → {b}" for k, a, b in case_differences(original, case) if k not in ("name", "description")]
    return "edited: " + ", ".join(edits) if edits else None


def doc_for_export(doc: RunDocument, case: Case, original: Case | None) -> RunDocument:
    """The run document as exported (Excel, JSON) from the TUI.

    A case's description is free text written for the values of its file ("Vref = 40 m/s");
    the TUI cannot re-derive it from new values.  So when value keys were edited and the
    description was not, the exported description is marked with the edits
    ("Vref = 40 m/s (edited: wind.v_ref 40 → 30)"); a description the user edited is theirs.
    """
    if original is None or case.description != original.description:
        return doc
    note = edit_note(case, original)
    if note is None:
        return doc
    text = doc.description or ""
    return dataclasses.replace(doc, description=f"{text} ({note})" if text else note)


def save_case(case: Case, path: Path, *, replace: bool) -> Path:
    """Write ``case`` as TOML (units as comments)."""
    return write_text_atomic(path, case_to_toml(case), force=replace, what="case")


def export(kind: str, doc: RunDocument, path: Path, *, replace: bool) -> Path:
    """Write a run document: ``kind`` "xlsx" (the Excel design sheet) or "json"."""
    if kind == "xlsx":
        from ..excel.writer import write_workbook  # lazy: openpyxl only when exporting

        write_workbook([doc], path, force=replace)
        return path
    from ..io.jsonout import write_json

    return write_json(path, doc, force=replace)
