"""`check` and `static` commands."""

from __future__ import annotations

import typer
from rich.markup import escape
from rich.table import Table

from ..core.errors import CaseError, ConvergenceError
from ..core.names import REACTIONS
from ..io.atomic import check_target
from ..io.display import kn
from ..io.outputs import case_inputs, check_outputs
from .common import CaseArg, CasesArg, JsonOpt, app, console, error_line, handle_errors, read_case
from .limits import warn as limits_warn
from .progress import progress_bar


@app.command()
@handle_errors
def check(cases: CasesArg) -> None:
    """Validate case files without running them; every bad file is reported, one line each (exit 2 if any)."""
    from ..analysis.guard import check_case  # the light checks only: the solvers stay unloaded

    failed = 0
    for path in cases:
        try:
            case = read_case(path)
            check_case(case, warn=limits_warn)  # field file, V_ref at p, resource estimate
        except CaseError as err:
            error_line(str(err))
            failed += 1
            continue
        console.print(f"[green]ok[/] {escape(str(path))}  [dim]{escape(case.name)}: {escape(case.description)}[/]",
                      highlight=False)
        if case.line.is_section:
            console.print(f"   section: {escape(section_line(case))}", highlight=False, soft_wrap=True)
            _warn_uplift(case)
    if failed:
        raise typer.Exit(2)


def _warn_uplift(case) -> None:
    """Step 1 of a section (still air and the mean wind) for its uplift: one warning line when a
    suspension insulator would be in compression (:func:`linecheck.analysis.uplift.uplift_warning`;
    with [[wires]] one line per wire with uplift).  The equal-span form has level clamps and
    cannot lift."""
    from ..analysis.step1 import static_result
    from ..analysis.uplift import uplift_warning
    from ..analysis.wires_static import wires_uplift_warnings

    try:
        messages = wires_uplift_warnings(case) if case.has_wires else [uplift_warning(static_result(case))]
    except ConvergenceError as err:
        messages = [f"uplift not checked: step 1 found no equilibrium: {err}"]
    for message in messages:
        if message:
            limits_warn(message)


def section_line(case) -> str:
    """``"13 towers T1-T13, 12 spans, 255-420 m, 2 angle towers; tower of interest 7 (T7)"``."""
    from ..io.section import section_summary, tower_rows

    rows = tower_rows(case.line)
    toi = case.line.tower_of_interest
    return (f"{len(rows)} towers {rows[0].name}-{rows[-1].name}, {section_summary(case.line)}; "
            f"tower of interest {toi} ({rows[toi - 1].name})")


def _at(v, k: int) -> float:
    """Value ``k`` of a static document's entry (a list over the step-1 instants of a downburst)."""
    return float(v[k] if isinstance(v, list) else v)


def static_table(doc: dict, name: str) -> Table:
    """The console table of a step-1 document (:func:`linecheck.io.jsonout.static_to_dict`): the
    same numbers as its JSON, every tower's reactions in its own frame (``heading``: its x axis
    from the global x, sections only).  Downburst: each row is the instant of that tower's
    largest wind-induced |Ry|.  ``weight span``: a suspension tower's R_z / W, ``!`` where its clamp
    is held at its still-air point (uplift)."""
    towers = doc["towers"]
    section = "name" in towers[0]
    table = Table(title=f"{name}: step-1 mean reactions (kN), each tower in its own frame", title_justify="left")
    names = ("name", "station (m)", "heading (deg)") if section else ()
    for col in ("tower", *names, "support", "weight span (m)", *REACTIONS, *(f"{r} wind" for r in REACTIONS)):
        table.add_column(col, justify="left" if col == "name" else "right")
    toi = doc["tower_of_interest"]
    for t in towers:
        ry = t["Ry_wind"]
        k = max(range(len(ry)), key=lambda i: abs(ry[i])) if isinstance(ry, list) else 0
        ident = (escape(t["name"]), f"{t['station']:g}", f"{t['heading']:.1f}") if section else ()
        table.add_row(
            f"{t['index']}{' *' if t['index'] == toi else ''}", *ident, t["support"],
            _weight_span_cell(t.get("uplift"), k),
            *(f"{kn(_at(t[c], k)):.3f}" for c in (*REACTIONS, *(f"{r}_wind" for r in REACTIONS))),
        )
    return table


def _weight_span_cell(u: dict | None, k: int) -> str:
    """A tower's weight span [m] at instant ``k`` of a step-1 document, ``!`` when its clamp is held
    (uplift); ``-`` at a strain tower."""
    if u is None:
        return "-"
    held = u["held"][k] if isinstance(u["held"], list) else u["held"]
    return f"{_at(u['weight_span'], k):.1f}{' !' if held else ''}"


@app.command()
@handle_errors
def static(case_file: CaseArg, json_out: JsonOpt = None) -> None:
    """Step 1: non-linear static analysis under the (running-)mean wind (with [[wires]]: every attachment and the tower totals)."""
    from .. import service
    from ..io.display import UPLIFT_CONSEQUENCE, tower_frame_caption, uplift_static_lines
    from ..io.jsonout import static_to_dict, write_json

    case = read_case(case_file)
    check_outputs([("--json", json_out)], case_inputs(case))
    if json_out is not None:
        check_target(json_out, what="JSON")
    if case.has_wires:
        _static_wires(case, json_out)
        return
    with progress_bar() as cb:
        res = service.static_analysis(case, progress=cb, warn=limits_warn)
    doc = static_to_dict(res)
    m = res.mean
    console.print(static_table(doc, case.name))
    console.print(f"[dim]* tower of interest (line.tower_of_interest = {case.line.tower_of_interest}); Rx, Ry, Rz total "
                  "reactions (conductor weight included), \"wind\" their wind-induced part (still air subtracted); "
                  f"{escape(tower_frame_caption(straight=res.system.straight_in_plan))}; weight span: a "
                  "suspension tower's Rz / W, the conductor length whose weight it carries.[/]", highlight=False)
    lifted = uplift_static_lines(doc)
    for line in lifted:
        console.print(f"[bold yellow]{escape(line)}[/]", highlight=False, soft_wrap=True)
    if lifted:
        console.print(f"[yellow]! {escape(UPLIFT_CONSEQUENCE)}.[/]", highlight=False, soft_wrap=True)
    series = case.wind.type == "downburst"
    tens = ", ".join(f"{kn(h):.2f}" for h in (m.tension.max(axis=0) if series else m.tension[0]))
    console.print(f"span tensions H (kN{', largest over the event' if series else ''}): {tens}   "
                  f"still air: {kn(m.still_air.tension[0]):.2f}   "
                  + (f"H0 at clipping-in: {kn(res.system.tension_nominal):.2f}" if res.system.is_section
                     else f"nominal T0: {kn(res.system.tension_nominal):.2f}"))
    if case.wind.type == "downburst":
        console.print(f"[dim]{m.time.size} mean states over t = {m.time[0]:.0f} to {m.time[-1]:.0f} s; "
                      "rows show the instant of peak wind-induced Ry at each tower.[/]")
    if json_out is not None:
        write_json(json_out, doc)
        console.print(f"wrote {json_out}")


def _static_wires(case, json_out) -> None:
    """`static` of a case with [[wires]]: step 1 of every wire, each attachment's reactions and the
    tower totals (:func:`linecheck.service.wires_static_analysis`)."""
    from .. import service
    from ..io.jsonout import wires_static_to_dict, write_json
    from .wires_view import print_wires_static

    with progress_bar() as cb:
        res = service.wires_static_analysis(case, progress=cb, warn=limits_warn)
    doc = wires_static_to_dict(res)
    print_wires_static(doc, straight=res.wires[0].system.straight_in_plan)
    if json_out is not None:
        write_json(json_out, doc)
        console.print(f"wrote {json_out}")
