"""Excel design sheets from run result documents.

Input: typed result documents (:class:`~linecheck.io.document.RunDocument`, or
:class:`~linecheck.io.document.FailedRun` for a case of a batch that failed); their JSON
(saved ``.json`` files) is read through ``RunDocument.from_json``, so every number in the
workbook is the number of the JSON it came from and old files fail with a clear message.  ``run --excel``,
``batch --excel`` and ``export`` all go through :func:`write_workbook`.

Cell values (never formulas, openpyxl writes no cached values):

- forces: kN = JSON N / 1000;
- Cont_M, Cont_BG, Cont_R: the JSON fraction itself, shown with a percent format
  (0.042 shows as 4.20 %);
- GF_Dy, GF_QS, peak_normalised: as in the JSON; a GF that is null (mean zero by
  symmetry or negligible) is the text ``**`` as in the paper's Table 5.

openpyxl stores numbers with 16 significant digits, so a cell equals its JSON value to
that precision (Excel shows 15).

Sheets: "Summary" (paper Table 5 layout, one row per case and reaction Rx, Ry;
``reactions=`` adds Rz), "Peaks" (Fig. 13), one sheet per case (inputs, still-air state, step-1 mean state,
statistics, contributions, all towers, spectral check when present, and charts:
Figs B1-B12, 7 and 12); with runs of several wires also "Totals" and "Load trees"
(:mod:`linecheck.excel.wires_sheets`).  Time histories are thinned for the charts keeping every
block's extremes, unless the result was saved with ``--full-histories``.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from openpyxl import Workbook

from ..core.errors import CaseError
from ..core.extremes import CONT_R_THRESHOLD
from ..io.atomic import atomic_path, check_target
from ..io.document import FailedRun, RunDocument, load_document, read_result_file
from . import template as tpl
from .case_sheet import write_case
from .cells import (
    CHART_POINTS,
    FLAG_NOTE,
    GF_UNDEFINED,
    REACTIONS,
    SUMMARY_REACTIONS,
    sheet_name,
    stat_cell,
)
from .charts import chart_indices
from .summary import write_peaks, write_summary
from .wires_sheets import totals_note, wires_docs, write_load_trees, write_totals


# =========================================================================== public API
def check_excel_target(path: str | Path, *, force: bool = False, template: str | Path | None = None) -> Path:
    """Check an Excel output path (and template) before any work is done.

    Raises :class:`CaseError` (one line) for a wrong suffix, an existing file without
    ``force``, a missing or unwritable folder, a file open in another program, or a
    bad template.
    """
    p = Path(path)
    if p.suffix.lower() != ".xlsx":
        raise CaseError(f"Excel output must be an .xlsx file name, got '{p.suffix or p.name}'", file=str(p))
    check_target(p, force=force, what="Excel")
    for lock in (p.parent / f"~${p.name}", p.parent / f".~lock.{p.name}#"):
        if lock.exists():
            raise CaseError(f"Excel file is open in another program (lock file {lock.name}); close it and retry",
                            file=str(p))
    if template is not None:
        tpl.check_template(template)
    return p


def write_workbook(
    docs: Sequence[dict[str, Any]],
    path: str | Path,
    *,
    template: Path | None = None,
    force: bool = False,
    cont_r_threshold: float = CONT_R_THRESHOLD,
    title: dict | None = None,
    chart_points: int = CHART_POINTS,
    reactions: Sequence[str] = SUMMARY_REACTIONS,
) -> Path:
    """Write the design-sheet workbook of ``docs`` to ``path`` atomically.

    Args:
        docs: run result documents (:class:`RunDocument`, or their JSON); a failed case
            may be given as a :class:`FailedRun` (or ``{"case": name, "error": message}``)
            and is listed in the summary with its error.
        path: ``.xlsx`` file; an existing file is replaced only with ``force``.
        template: workbook with the title-block defined names (default
            ``templates/design_sheet.xlsx``).
        cont_r_threshold: Cont_R (fraction) above which a row is flagged
            "dynamic analysis recommended".
        title: title-block values by defined name (project, line, section, engineer,
            checked_by, date, revision, units_note).
        chart_points: about how many samples of each thinned time history go to the
            charts (results saved with ``--full-histories`` are written in full).
        reactions: reactions with a row in the Summary and a bar in Peaks (default Rx, Ry
            as the paper's Table 5; the case sheets always show Rx, Ry, Rz).

    Returns the path written.  Raises :class:`CaseError` for bad input or an
    unwritable/locked/existing target; nothing is left half-written.
    """
    p = check_excel_target(path, force=force)
    if isinstance(cont_r_threshold, bool) or not isinstance(cont_r_threshold, (int, float)) \
            or not 0.0 < float(cont_r_threshold) < 1.0:
        raise CaseError(f"value {cont_r_threshold!r} is not allowed: expected a fraction between 0 and 1 "
                        "(0.10 = 10 %)", key="--cont-r-threshold")
    reactions = tuple(reactions)
    if not reactions or any(r not in REACTIONS for r in reactions):
        raise CaseError(f"reactions {list(reactions)} not allowed: expected some of Rx, Ry, Rz", key="reactions")
    docs = [validate_doc(doc, f"result {i + 1}") for i, doc in enumerate(docs)]
    if not docs:
        raise CaseError("no results to write", file=str(p))
    values = tpl.title_values(title)
    wb = tpl.load_template(template)
    build_workbook(wb, docs, values, float(cont_r_threshold), max(int(chart_points), 16), reactions)
    # The zip is built in memory and written with one plain write: a full disk then fails on
    # that write (a clean OSError, mapped to one line below), never inside zipfile, whose
    # half-closed archive would print a ZipFile.__del__ traceback at exit.
    buffer = io.BytesIO()
    wb.save(buffer)
    try:
        with atomic_path(p, force=force, what="Excel") as tmp:
            with open(tmp, "wb") as fh:
                fh.write(buffer.getbuffer())
            _set_mode(tmp, p)
    except OSError as exc:
        raise CaseError(f"cannot write Excel file: {exc.strerror or exc}", file=str(p)) from None
    return p


def _set_mode(tmp: Path, target: Path) -> None:
    """Give the temporary file the mode of the file it replaces (new file: 0666 less the umask)."""
    try:
        mode = target.stat().st_mode & 0o777
    except FileNotFoundError:
        mode = 0o666 & ~_umask()
    os.chmod(tmp, mode)


def _umask() -> int:
    """The process umask, read without changing it where the system allows (threads: TUI export)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    umask = os.umask(0o022)
    os.umask(umask)
    return umask


def validate_doc(doc: Any, source: str) -> RunDocument | FailedRun:
    """The typed document of ``doc`` (a :class:`RunDocument`, a :class:`FailedRun`, or their JSON:
    a run result or ``{"case", "error"}``); :class:`CaseError` naming ``source`` otherwise."""
    if isinstance(doc, (RunDocument, FailedRun)):
        return doc
    if not isinstance(doc, dict):
        raise CaseError("not a linecheck run result (expected a JSON object from `linecheck run --json`)",
                        file=source)
    if "error" in doc:
        if not isinstance(doc.get("case"), str):
            raise CaseError("failed-case entry needs a \"case\" name beside its \"error\"", file=source)
        return load_document(doc, source=source)
    if "reactions" not in doc and "towers" in doc and "spans" in doc:
        raise CaseError("is a step-1 (static) result: export needs run results (`linecheck run --json`)",
                        file=source)
    return load_document(doc, source=source)  # schema version and layout


def load_result_docs(paths: Iterable[str | Path]) -> list[RunDocument | FailedRun]:
    """Read saved run results (one JSON object, or a list of them, per file) as typed documents."""
    docs: list[RunDocument | FailedRun] = []
    for path in paths:
        p = Path(path)
        data = read_result_file(p)  # one line naming the file for anything unreadable
        items = data if isinstance(data, list) else [data]
        for k, doc in enumerate(items):
            docs.append(validate_doc(doc, str(p) if len(items) == 1 else f"{p}[{k}]"))
    if not docs:
        raise CaseError("no results to export (empty list)")
    return docs


# =========================================================================== workbook
def build_workbook(wb: Workbook, docs: list[RunDocument | FailedRun], title: dict[str, Any], threshold: float,
                   chart_points: int = CHART_POINTS, reactions: Sequence[str] = SUMMARY_REACTIONS) -> None:
    """Fill a loaded template with the summary, peaks and case sheets (in place)."""
    tpl.ensure_styles(wb)
    tpl.fill_title(wb, title)
    anchor = tpl.destination(wb, tpl.SUMMARY_ANCHOR)
    if anchor is not None:
        summary, cell = anchor
        start = summary[cell]
        top, left = start.row, start.column
    else:
        summary = wb["Summary"] if "Summary" in wb.sheetnames else wb.create_sheet("Summary", 0)
        top, left = (summary.max_row + 2 if summary.max_row > 1 or summary["A1"].value is not None else 1), 1
    taken = {n.lower() for n in wb.sheetnames}
    names = [None if isinstance(d, FailedRun) else sheet_name(d.case, taken) for d in docs]
    ok = [(d, n) for d, n in zip(docs, names) if n is not None]
    peaks_name = "Peaks" if "peaks" not in {n.lower() for n in wb.sheetnames} else sheet_name("Peaks (linecheck)", taken)
    wired = wires_docs(ok)  # runs of several wires: their Totals and Load trees sheets
    wire_sheets = (sheet_name("Totals", taken), sheet_name("Load trees", taken)) if wired else None
    write_summary(summary, docs, names, threshold, top, left, reactions,
                  notes=[totals_note(d, wire_sheets) for d, _ in wired] if wire_sheets else ())
    if ok:
        write_peaks(wb.create_sheet(peaks_name), ok, summary, reactions)
    header_text = str(title.get("project") or "")
    for d, name in ok:
        ws = wb.create_sheet(name)
        write_case(ws, d, threshold, chart_points, summary, header_text, reactions, wire_sheets)
    after = peaks_name
    if any(d.codes for d, _ in ok):  # design codes
        from .codes_sheet import write_codes

        at = wb.sheetnames.index(peaks_name) + 1 if peaks_name in wb.sheetnames else None
        after = sheet_name("Codes", taken)
        write_codes(wb.create_sheet(after, at), [d for d, _ in ok], summary)
    if wire_sheets is not None:
        at = wb.sheetnames.index(after) + 1
        write_totals(wb.create_sheet(wire_sheets[0], at), wired, summary, wire_sheets[1])
        write_load_trees(wb.create_sheet(wire_sheets[1], at + 1), wired, summary, header_text)
    wb.active = wb.sheetnames.index(summary.title)


__all__ = [
    "CHART_POINTS",
    "FLAG_NOTE",
    "GF_UNDEFINED",
    "SUMMARY_REACTIONS",
    "build_workbook",
    "chart_indices",
    "check_excel_target",
    "load_result_docs",
    "sheet_name",
    "stat_cell",
    "validate_doc",
    "write_workbook",
]
