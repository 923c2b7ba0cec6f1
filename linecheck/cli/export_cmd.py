"""`export` command: Excel design sheets from saved run results (no re-run).

The option aliases here (:data:`ExcelOpt`, :data:`TemplateOpt`, :data:`ForceOpt`) are
shared by ``run --excel`` and ``batch --excel``.  openpyxl is imported only when a
workbook is written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..core.errors import CaseError
from .app import app, console, handle_errors

ExcelOpt = Annotated[Path | None, typer.Option(
    "--excel", help="Also write the Excel design sheet (.xlsx) to this file.", show_default=False)]
TemplateOpt = Annotated[Path | None, typer.Option(
    "--template", help="Excel template with the title-block defined names (default templates/design_sheet.xlsx).",
    show_default=False)]
ForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing Excel file.")]
ThresholdOpt = Annotated[float, typer.Option(
    "--cont-r-threshold",
    help="Flag Cont_R above this fraction as 'dynamic analysis recommended' (0.10 = 10 %).")]
TitleOpt = Annotated[list[str] | None, typer.Option(
    "--title",
    help="Title-block field KEY=VALUE (project, line, section, engineer, checked_by, date, revision, "
         "units_note); repeat for several.", show_default=False)]


def parse_title(items: list[str] | None) -> dict[str, str]:
    """``["project=Line 7", ...]`` -> ``{"project": "Line 7"}`` (CaseError on a malformed item)."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise CaseError(f"value '{item}' is not allowed: expected KEY=VALUE, e.g. project=\"Line 7\"",
                            key="--title")
        out[key.strip()] = value.strip()
    return out


@app.command()
@handle_errors
def export(
    results: Annotated[list[Path], typer.Argument(
        help="Saved run results (JSON of `linecheck run --json` or of a batch).", show_default=False)],
    excel: Annotated[Path, typer.Option("--excel", help="Excel design sheet (.xlsx) to write.", show_default=False)],
    template: TemplateOpt = None,
    force: ForceOpt = False,
    cont_r_threshold: ThresholdOpt = 0.10,
    title: TitleOpt = None,
) -> None:
    """Write the Excel design sheet of saved run results (summary, peaks, one sheet per case)."""
    from ..excel.writer import check_excel_target, load_result_docs, write_workbook

    fields = parse_title(title)
    check_excel_target(excel, force=force, template=template)
    docs = load_result_docs(results)
    write_workbook(docs, excel, template=template, force=force, cont_r_threshold=cont_r_threshold,
                   title=fields or None)
    n = len(docs)
    console.print(f"wrote {excel} ({n} case{'s' if n != 1 else ''})")
