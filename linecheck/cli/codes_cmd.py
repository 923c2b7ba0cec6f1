"""`codes` command: the design codes' conductor wind loads beside linecheck's peaks."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from ..io.atomic import check_target
from ..io.display import kn_text
from ..io.document import CodeCheckRecord
from ..io.outputs import case_inputs, check_outputs
from .common import CaseArg, JsonOpt, app, console, handle_errors, read_case
from .progress import progress_bar


def codes_table(codes: dict[str, CodeCheckRecord], title: str) -> Table:
    """Rich table of a typed ``codes`` block (kN at display): the code load's two parts (wind, angle;
    :data:`~linecheck.core.codes.CODES_COMPARED`), the code load, linecheck's peak, ratio, verdict."""
    t = Table(title=title, title_justify="left")
    for col in ("code", "verified", "tower", "wind kN", "angle kN", "code load kN", "linecheck peak kN", "ratio",
                "verdict"):
        t.add_column(col, justify="left" if col in ("code", "verdict") else "right")

    for name, block in codes.items():
        for k, tower in enumerate(block.towers):
            ry = tower.reactions["Ry"]
            t.add_row(name if k == 0 else "", ("yes" if block.verified else "no") if k == 0 else "",
                      str(tower.index), kn_text(ry.wind_load), kn_text(ry.angle_load), kn_text(ry.code_load),
                      kn_text(ry.linecheck_peak), "-" if ry.ratio is None else f"{ry.ratio:.3f}", ry.verdict)
    return t


def print_codes_notes(codes: dict[str, CodeCheckRecord]) -> None:
    for name, block in codes.items():
        console.print(f"[dim]{name} ({block.edition}): {block.note}[/]", highlight=False)


@app.command()
@handle_errors
def codes(
    case_file: CaseArg,
    json_out: JsonOpt = None,
    loads_only: Annotated[bool, typer.Option("--loads-only", help="Only the code loads: do not run the case.")] = False,
) -> None:
    """Design-code conductor wind loads (ASCE 74, IEC 60826, EN 50341-1, AS/NZS 7000) beside linecheck's peaks."""
    from .. import service  # here, not at import: the service loads the numerical core (start-up time)
    from ..io.jsonout import codes_document, codes_to_dict, with_provenance, write_json

    case = read_case(case_file)
    check_outputs([("--json", json_out)], case_inputs(case))
    if json_out is not None:
        check_target(json_out, what="JSON")
    loads = service.code_loads(case)  # validity limits first: a bad value fails before the run (exit 2)
    run = None
    if not loads_only and any(x.load_per_length is not None for x in loads):  # nothing to compare: no run
        with progress_bar() as cb:
            run = service.run_case(case, spectral_check=False, progress=cb)
    res = service.codes_analysis(case, run)
    doc = {"case": case.name, "units": "SI", "peak": res.peak, "compared": res.compared, "codes": codes_to_dict(res)}
    typed = codes_document(res)
    console.print(codes_table(typed, f"{case.name}: transverse load on Ry (wind + angle), design codes vs linecheck "
                                            f"(v_ref {case.wind.v_ref:g} m/s, terrain \"{case.codes.terrain}\")"))
    print_codes_notes(typed)
    console.print("[dim]" + res.compared + ".[/]", highlight=False)
    console.print("[dim]linecheck peak: " + res.peak + ". Unverified codes are shown, not judged (docs/codes.md).[/]",
                  highlight=False)
    if json_out is not None:
        write_json(json_out, with_provenance(doc))
        console.print(f"wrote {json_out}")
