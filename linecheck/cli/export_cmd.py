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
from ..core.extremes import CONT_R_THRESHOLD
from .common import app, console, handle_errors, path_value

ExcelOpt = Annotated[Path | None, typer.Option(
    "--excel", help="Also write the Excel design sheet (.xlsx) to this file.", show_default=False, parser=path_value)]
TemplateOpt = Annotated[Path | None, typer.Option(
    "--template", help="Excel template with the title-block defined names (default templates/design_sheet.xlsx).",
    show_default=False, parser=path_value)]
ForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing Excel file.")]
ThresholdOpt = Annotated[float, typer.Option(
    "--cont-r-threshold",
    help="Flag Cont_R above this fraction as 'dynamic analysis recommended' (0.10 = 10 %).")]
# ---- the title block: one option set shared by `export`, `run --excel` and `batch --excel`
_PANEL = "Excel title block"
ProjectOpt = Annotated[str | None, typer.Option(
    "--project", help="Title block: project.", show_default=False, rich_help_panel=_PANEL)]
LineOpt = Annotated[str | None, typer.Option(
    "--line", help="Title block: line.", show_default=False, rich_help_panel=_PANEL)]
EngineerOpt = Annotated[str | None, typer.Option(
    "--engineer", help="Title block: engineer.", show_default=False, rich_help_panel=_PANEL)]
RevisionOpt = Annotated[str | None, typer.Option(
    "--revision", help="Title block: revision.", show_default=False, rich_help_panel=_PANEL)]
TitleOpt = Annotated[list[str] | None, typer.Option(
    "--title",
    help="Any title-block field as KEY=VALUE (project, line, section, engineer, checked_by, date, revision, "
         "units_note); repeat for several.", show_default=False, rich_help_panel=_PANEL)]

#: Title-block fields (the defined names of the design-sheet template, linecheck.excel.template.TITLE_NAMES;
#: repeated here so that the CLI checks them before any work without importing openpyxl).
TITLE_FIELDS = ("project", "line", "section", "engineer", "checked_by", "date", "revision", "units_note")


def parse_title(items: list[str] | None) -> dict[str, str]:
    """``["project=Line 7", ...]`` -> ``{"project": "Line 7"}`` (CaseError on a malformed item or unknown key)."""
    out: dict[str, str] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise CaseError(f"value '{item}' is not allowed: expected KEY=VALUE, e.g. project=\"Line 7\"",
                            key="--title")
        if key.strip() not in TITLE_FIELDS:
            raise CaseError(f"unknown title field '{key.strip()}': expected one of " + ", ".join(TITLE_FIELDS),
                            key="--title")
        out[key.strip()] = value.strip()
    return out


def title_block(project: str | None, line: str | None, engineer: str | None, revision: str | None,
                title: list[str] | None, *, excel: Path | None = Path("x.xlsx")) -> dict[str, str]:
    """The title-block values of the shared options (``--project`` ... win over the same ``--title`` key).

    Checked before any work; ``excel=None`` (``run``/``batch`` without ``--excel``) with a title
    option given is an error, since nothing would show it.
    """
    fields = parse_title(title)
    for key, value in (("project", project), ("line", line), ("engineer", engineer), ("revision", revision)):
        if value is not None:
            fields[key] = value
    if fields and excel is None:
        raise CaseError("title-block options (--project, --line, --engineer, --revision, --title) fill the Excel "
                        "design sheet: add --excel FILE.xlsx")
    return fields


@app.command()
@handle_errors
def export(
    results: Annotated[list[Path], typer.Argument(
        help="Saved run results (JSON of `linecheck run --json` or of a batch).", show_default=False,
        parser=path_value)],
    excel: Annotated[Path, typer.Option("--excel", help="Excel design sheet (.xlsx) to write.", show_default=False,
                                        parser=path_value)],
    template: TemplateOpt = None,
    force: ForceOpt = False,
    cont_r_threshold: ThresholdOpt = CONT_R_THRESHOLD,
    project: ProjectOpt = None,
    line: LineOpt = None,
    engineer: EngineerOpt = None,
    revision: RevisionOpt = None,
    title: TitleOpt = None,
) -> None:
    """Write the Excel design sheet of saved run results (summary, peaks, one sheet per case)."""
    from ..excel.writer import check_excel_target, load_result_docs, write_workbook
    from ..io.outputs import check_outputs

    fields = title_block(project, line, engineer, revision, title)
    check_outputs([("--excel", excel)], [*(("result file", r) for r in results), ("template", template)])
    check_excel_target(excel, force=force, template=template)
    docs = load_result_docs(results)
    write_workbook(docs, excel, template=template, force=force, cont_r_threshold=cont_r_threshold,
                   title=fields or None)
    n = len(docs)
    console.print(f"wrote {excel} ({n} case{'s' if n != 1 else ''})")
