"""`linecheck run` of a case with ``[[wires]]``: every wire in one correlated wind
(:func:`linecheck.service.run_wires`), the console report (:mod:`linecheck.cli.wires_view`), the
JSON result, the load-tree CSV (:mod:`linecheck.io.wires_document`) and the Excel design sheet
with its "Totals" and "Load trees" sheets (:mod:`linecheck.excel`); docs/wires.md."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..core.case import Case
from ..core.errors import CaseError
from ..io.atomic import check_target
from ..io.outputs import case_inputs, check_outputs
from .common import console, write_run_outputs
from .limits import warn as limits_warn
from .progress import progress_bar

LoadTreesOpt = Annotated[Path | None, typer.Option(
    "--load-trees", help="A case with [[wires]]: write every tower's load trees (each wire's load at the instant "
                         "each governing total is reached, kN) to this CSV.", show_default=False)]

#: The options of `run` a case with ``[[wires]]`` does not take yet, each with why.
NOT_FOR_WIRES = {
    "--models": "the downburst model spread of several wires is not available yet: run the case under each model",
    "--until": "the adaptive realization count of several wires is not available yet: give --realizations",
    "--full-histories": "a run of several wires records no time histories",
}


def refuse_options(case: Case, given: dict[str, object]) -> None:
    """One :class:`CaseError` line (exit 2, before any work) for the first option of
    :data:`NOT_FOR_WIRES` given (not None and not False) with a case with ``[[wires]]``."""
    for option, value in given.items():
        if value is not None and value is not False:
            raise CaseError(f"a run of a case with several wires writes the console report, --json, --load-trees and "
                            f"--excel; "
                            f"{NOT_FOR_WIRES[option]}", file=str(case.source) if case.source else None, key=option)


def require_wires(case: Case, load_trees: Path | None) -> None:
    """``--load-trees`` of a case without ``[[wires]]``: one :class:`CaseError` line (exit 2)."""
    if load_trees is not None and not case.has_wires:
        raise CaseError("the case has no [[wires]]: load trees are the coincident loads of every wire a tower carries "
                        "(docs/wires.md); describe the tower's wires with [[wires]] and [[tower_types]]",
                        file=str(case.source) if case.source else None, key="--load-trees")


def run_wires_command(case: Case, *, json_out: Path | None, load_trees: Path | None, threads: int,
                      excel: Path | None = None, template: Path | None = None, force: bool = False,
                      title: dict[str, str] | None = None) -> None:
    """`run` of a case with ``[[wires]]``: outputs (and the Excel template) checked first, the
    case's warnings, the run with progress bars (Ctrl-C stops it), the report, then the JSON, the
    CSV and the workbook (``title``: its title block), each atomically with a "wrote" line."""
    from .. import service
    from ..io.provenance import kernel_warning
    from ..io.wires_document import wires_run_document, write_load_trees
    from .wires_view import print_wires_run

    check_outputs([("--json", json_out), ("--load-trees", load_trees), ("--excel", excel)],
                  [*case_inputs(case), ("template", template)])
    if json_out is not None:
        check_target(json_out, what="JSON")
    if load_trees is not None:
        check_target(load_trees, what="CSV")
    if excel is not None:
        from ..excel.writer import check_excel_target

        check_excel_target(excel, force=force, template=template)
    service.warn_case(case, limits_warn)
    kernel_off = kernel_warning()
    if kernel_off:
        limits_warn(kernel_off)
    with progress_bar() as cb:
        res = service.run_wires(case, progress=cb, threads=threads, warn=limits_warn)
    doc = wires_run_document(res)
    print_wires_run(doc)
    write_run_outputs(doc, json_out, excel, template, force, title)
    if load_trees is not None:
        write_load_trees(load_trees, doc)
        console.print(f"wrote {load_trees}")
