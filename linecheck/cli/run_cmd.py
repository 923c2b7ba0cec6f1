"""`run` and `modes` commands."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from ..core.case import Case
from ..core.extremes import CONT_R_THRESHOLD as CONT_R_FLAG  # Cont_R flag, paper Sect. 5 (one definition)
from ..core.names import REACTIONS
from ..io.atomic import check_target
from ..io.display import STAT_ROWS, SUMMARY_STATS, number_text, stat_text, uplift_run_text
from ..io.document import RunDocument, StatDef
from ..io.outputs import case_inputs, check_outputs
from .common import CaseArg, JsonOpt, app, console, handle_errors, read_case, write_run_outputs
from .export_cmd import (
    EngineerOpt,
    ExcelOpt,
    ForceOpt,
    LineOpt,
    ProjectOpt,
    RevisionOpt,
    TemplateOpt,
    TitleOpt,
    title_block,
)
from .limits import MaxMemoryOpt, apply_max_memory
from .limits import warn as limits_warn
from .progress import progress_bar
from .stats_view import MaxRealOpt, UntilOpt, design_table, parse_until
from .stats_view import notes as stats_notes
from .wires_cmd import LoadTreesOpt, refuse_options, require_wires, run_wires_command

ModelsOpt = Annotated[str | None, typer.Option(
    "--models", help='Downburst model spread: run the case under "all" built-in running-mean models '
                     '(or a comma list, e.g. holmes-oliver,ring-jet) with the same turbulence seeds; '
                     'adds a "models" block and the envelope.', show_default=False)]
RealOpt = Annotated[int | None, typer.Option("--realizations", "-n", help="Number of realizations (overrides the case).", min=1)]
SeedOpt = Annotated[int | None, typer.Option("--seed", help="Random seed (overrides the case).", min=0)]


def override(case: Case, realizations: int | None, seed: int | None) -> Case:
    """The case with CLI overrides of [analysis] applied, validated like the file."""
    from ..core.case import with_options

    return with_options(case, {"--realizations": ("analysis.realizations", realizations),
                               "--seed": ("analysis.seed", seed)})


def console_header(st: StatDef, width: int = 7) -> str:
    """Column header of the console table from the statistics table's short label and unit, in
    lines of at most ``width`` characters, so that the table with its ``± std`` lines fits a
    120-column terminal; :data:`TABLE_LEGEND` explains them."""
    lines: list[str] = []
    for word in st.short.split():
        if lines and len(lines[-1]) + 1 + len(word) <= width:
            lines[-1] += " " + word
        else:
            lines.append(word)
    if st.display_unit != "-":
        lines.append(st.display_unit)
    return "\n".join(lines)


#: Reactions whose Cont_R is flagged (the paper's Table 5 reactions, as in the Excel Summary; Rz's
#: wind-induced part is small beside the conductor weight, its Cont_R is not a design signal).
FLAGGED_REACTIONS = ("Rx", "Ry")
TABLE_LEGEND = (
    "mean M: largest wind-induced mean; rms B, rms R: background and resonant r.m.s.; peak QS = M+B (quasi-static), "
    "peak Dy = M+B+R (dynamic); GF ** : mean zero by symmetry (or < 1 % of the largest mean); Cont_R: share of "
    "the peak that a quasi-static analysis misses; peak / g*yp Lx: peak Dy / (g*yp L_x) (Eq. 17).")


def results_table(doc: RunDocument) -> Table:
    """Rich table of the statistics at the tower of interest (kN, %); a Cont_R above 10 % in bold red.
    Cells: ``mean`` over ``± std`` (two lines, when there are several realizations), ``**`` when undefined."""
    n = doc.realizations
    t = Table(title=f"{doc.case}: reactions at tower {doc.tower_of_interest} "
                    f"({doc.wind}, V_ref = {doc.v_ref:g} m/s, {n} realization{'s' if n > 1 else ''})",
              title_justify="left")
    t.add_column("", justify="right", no_wrap=True)
    for st in SUMMARY_STATS:
        t.add_column(console_header(st), justify="right", no_wrap=True)
    for r in REACTIONS:
        cells = []
        for st in SUMMARY_STATS:
            text = escape(stat_text(doc.reactions[r][st.name], st, n, sep="\n±"))
            if st.name == "Cont_R" and cont_r_flagged(doc, r):
                text = f"[bold red]{text}[/]"
            cells.append(text)
        t.add_row(r, *cells)
    return t


def cont_r_flagged(doc: RunDocument, reaction: str) -> bool:
    """Whether ``reaction`` (Rx, Ry only) has the flag "recommended": the 95 % interval of its
    Cont_R lies above :data:`CONT_R_FLAG` (docs/method.md)."""
    return reaction in FLAGGED_REACTIONS and doc.reactions[reaction].dynamic_analysis == "recommended"


def print_legend(doc: RunDocument) -> None:
    """The legend of :func:`results_table`, and the Cont_R flag when a reaction has it."""
    console.print(f"[dim]{TABLE_LEGEND}[/]", highlight=False)
    flagged = [r for r in FLAGGED_REACTIONS if cont_r_flagged(doc, r)]
    if flagged:
        console.print(f"[bold red]Cont_R above {100 * CONT_R_FLAG:.0f} %[/] ({', '.join(flagged)}, in red; its 95 % interval "
                      "lies above): dynamic analysis recommended, the resonant part is a significant share of the "
                      "peak (paper Sect. 5).",
                      highlight=False)


def burn_in_note(doc: RunDocument) -> str | None:
    """One line on a synoptic record that is not stationary: what it means and what to do.

    ``None`` when the burn-in is sufficient (or the run is not synoptic).
    """
    b = doc.burn_in
    if b is None or doc.wind != "synoptic" or b.sufficient:
        return None
    need = "never (undamped)" if b.required is None else f"{b.required:,.0f} s"
    mode = f"the {b.mode_hz:.3f} Hz mode (zeta {b.zeta:.2g}) would need a burn-in of {need}"
    if doc.damping == "paper" and b.seconds == 0:
        return (f"[yellow]note:[/] damping = \"paper\" leaves the {b.mode_hz:.3f} Hz mode almost undamped "
                f"(zeta {b.zeta:.2g}; stationary only after a burn-in of {need}): as in the paper, its resonant "
                "part comes from a record starting at rest, below the stationary level the frequency-domain check "
                "assumes; for a design value use damping = \"quasi-steady\" (docs/method.md, Damping).")
    return (f"[yellow]note:[/] record not stationary: {mode}, {b.seconds:,.0f} s used ({b.source}); its "
            "resonant part is below its stationary level: raise analysis.duration (the derived burn-in is capped "
            "at 10 x duration) or analysis.burn_in, or set analysis.structural_damping (docs/method.md, Damping).")


def models_table(doc: RunDocument) -> Table:
    """Rich table of the model spread: one row per model and the envelope."""
    n = doc.realizations
    keys = ("mean_max", "peak_dynamic", "GF_Dy", "GF_QS", "peak_normalised")
    t = Table(title=f"{doc.case}: downburst model spread at tower {doc.tower_of_interest}", title_justify="left")
    t.add_column("model", justify="left", no_wrap=True)
    for r in ("Rx", "Ry"):
        for k in keys:
            st = STAT_ROWS[k]
            t.add_column(f"{r} {st.label}" + (f" {st.display_unit}" if st.display_unit != "-" else ""), justify="right")
    for name, blk in (doc.models or {}).items():
        t.add_row(name, *(stat_text(blk[r][k], STAT_ROWS[k], n) for r in ("Rx", "Ry") for k in keys))
    env = doc.models_envelope or {}
    cells = []
    for r in ("Rx", "Ry"):
        for k in keys:
            e = env[r][k]
            cells.append("" if e.value is None else f"{number_text(e.value, STAT_ROWS[k])} ({e.model})")
    t.add_row("[bold]envelope[/]", *cells)
    return t


def print_burn_in(doc: RunDocument) -> None:
    """Say how much of a synoptic record was discarded, and when it is not enough: one line."""
    b = doc.burn_in
    if b is None or doc.wind != "synoptic":
        return
    note = burn_in_note(doc)
    if note is not None:
        console.print(note, highlight=False, soft_wrap=True)
    else:
        console.print(f"[dim]burn-in {b.seconds:.0f} s discarded ({b.source}); statistics from a stationary "
                      f"response (slowest significant mode {b.mode_hz:.3f} Hz, zeta {b.zeta:.3g}).[/]",
                      highlight=False)


@app.command()
@handle_errors
def run(
    case_file: CaseArg,
    json_out: JsonOpt = None,
    realizations: RealOpt = None,
    seed: SeedOpt = None,
    full_histories: Annotated[bool, typer.Option("--full-histories", help="Keep full-resolution time histories in the outputs.")] = False,
    excel: ExcelOpt = None,
    template: TemplateOpt = None,
    force: ForceOpt = False,
    no_check: Annotated[bool, typer.Option("--no-check", help="Skip the frequency-domain sanity check of a synoptic case (long lines: its cost grows faster than the number of spans).")] = False,
    max_memory: MaxMemoryOpt = None,
    project: ProjectOpt = None,
    line: LineOpt = None,
    engineer: EngineerOpt = None,
    revision: RevisionOpt = None,
    title: TitleOpt = None,
    models: ModelsOpt = None,
    until: UntilOpt = None,
    max_realizations: MaxRealOpt = 1000,
    jobs: Annotated[int | None, typer.Option(
        "--jobs", "-j", min=1, show_default=False,
        help="Threads integrating realizations at once (default: the number of cores; the results are the "
             "same bits whatever the number).")] = None,
    load_trees: LoadTreesOpt = None,
) -> None:
    """Steps 1-3: mean, background and resonant reactions, gust factors and contributions (with [[wires]]: every
    wire in one correlated wind, each attachment, the tower totals and load trees)."""
    from .. import service  # here, not at import: the service loads the numerical core (start-up time)
    from ..batch.executors import default_jobs

    fields = title_block(project, line, engineer, revision, title, excel=excel)
    apply_max_memory(max_memory)
    threads = default_jobs() if jobs is None else jobs
    case = override(read_case(case_file), realizations, seed)
    require_wires(case, load_trees)
    if case.has_wires:
        refuse_options(case, {"--models": models, "--until": until, "--full-histories": full_histories})
        run_wires_command(case, json_out=json_out, load_trees=load_trees, threads=threads, excel=excel,
                          template=template, force=force, title=fields)
        return
    target = parse_until(until)
    _check_run_outputs(case, json_out, excel, template, force)
    names = service.parse_models(case, models) if models is not None else ()
    res, spread = _analyse(case, names, target, max_realizations=max_realizations, no_check=no_check,
                           threads=threads)
    doc = _run_document(res, spread, names, full_histories)
    _print_run(doc, case, names, no_check)
    write_run_outputs(doc, json_out, excel, template, force, fields)


def _check_run_outputs(case: Case, json_out: Path | None, excel: Path | None, template: Path | None,
                       force: bool) -> None:
    """Refuse (exit 2, before any work) an output that would overwrite an input or an existing file."""
    check_outputs([("--json", json_out), ("--excel", excel)], [*case_inputs(case), ("template", template)])
    if json_out is not None:
        check_target(json_out, what="JSON")
    if excel is not None:
        from ..excel.writer import check_excel_target

        check_excel_target(excel, force=force, template=template)


def _analyse(case: Case, names: tuple[str, ...], target: Any, *, max_realizations: int, no_check: bool,
             threads: int) -> tuple[Any, dict | None]:
    """The analysis with a progress bar: under each model of ``names`` (the result of the case's own
    model, or the first, and the spread), to the ``target`` accuracy (--until), or as the case says.
    Warnings on the case and the compiled kernel come first, once."""
    from .. import service
    from ..io.provenance import kernel_warning

    service.warn_case(case, limits_warn)  # values probably mistyped (a weight in kg/m): once, before the work
    kernel_off = kernel_warning()  # compiled pieces off (Numba installed): one line, before the work
    if kernel_off:
        limits_warn(kernel_off)
    spread = None
    with progress_bar() as cb:
        if names:
            spread = service.run_models(case, names, progress=cb, spectral_check=not no_check, warn=limits_warn,
                                        threads=threads)
            own = case.wind.downburst.model_name
            res = spread[own] if own in spread else next(iter(spread.values()))
        elif target is not None:
            res = service.run_until(case, target, max_realizations=max_realizations, progress=cb,
                                    spectral_check=not no_check, warn=limits_warn, threads=threads)
        else:
            res = service.run_case(case, progress=cb, spectral_check=not no_check, warn=limits_warn,
                                   threads=threads)
    return res, spread


def _run_document(res: Any, spread: dict | None, names: tuple[str, ...], full_histories: bool) -> RunDocument:
    """The result document, with the "models" block of a model spread."""
    from ..io.jsonout import run_document

    doc = run_document(res, full_histories=full_histories)
    if names:
        from ..io.jsonout import model_reactions, with_models

        doc = with_models(doc, res.case.wind.downburst.model_name, model_reactions(spread))
    return doc


def _print_run(doc: RunDocument, case: Case, names: tuple[str, ...], no_check: bool) -> None:
    """The console report: statistics, design values, notes, legend, model spread, burn-in and sanity check."""
    console.print(results_table(doc))
    console.print(design_table(doc))
    for note in stats_notes(doc):
        console.print(f"[dim]{note}[/]", highlight=False)
    print_legend(doc)
    uplift = uplift_run_text(doc)
    if uplift is not None:
        console.print(f"[dim]{escape(uplift)}[/]", highlight=False)
    if names:
        console.print(models_table(doc))
    from .spectral_cmd import print_sanity

    print_burn_in(doc)
    print_sanity(doc, explained=burn_in_note(doc) is not None)
    if no_check and case.wind.type == "synoptic":
        console.print("[dim]frequency-domain check skipped (--no-check): no \"spectral\" block, no sanity check.[/]")



@app.command()
@handle_errors
def modes(
    case_file: CaseArg,
    json_out: JsonOpt = None,
    count: Annotated[int, typer.Option("--count", help="Number of modes.", min=1, max=500)] = 20,
    shapes: Annotated[bool, typer.Option("--shapes", help="Include mode shapes in the JSON.")] = False,
) -> None:
    """Natural frequencies (and mode shapes) of the still-air and mean states."""
    from .. import service
    from ..io.jsonout import modes_to_dict, write_json

    case = read_case(case_file)
    check_outputs([("--json", json_out)], case_inputs(case))
    if json_out is not None:
        check_target(json_out, what="JSON")
    res = service.modes_analysis(case, n_modes=count, warn=limits_warn)
    console.print(modes_table(res))
    console.print(f"[dim]damped (Hz), damping ratio: the complex mode of the mean state with damping = "
                  f"\"{case.analysis.damping}\" (structural {case.analysis.structural_ratio:g}) whose shape matches "
                  "the row's mean-state mode (MAC: mass-weighted modal assurance criterion, 1 = the same shape); "
                  "still air and mean state: each state's modes in order of frequency, the same number not "
                  "necessarily the same shape; red: damping ratio below 0.5 %.[/]")
    if case.wind.type == "downburst":
        console.print(f"[dim]mean state at t = {res.mean_time:.1f} s (largest mean reaction at the tower of interest)[/]")
    if json_out is not None:
        write_json(json_out, modes_to_dict(case, res, shapes=shapes))
        console.print(f"wrote {json_out}")


def modes_table(res) -> Table:
    """The ``modes`` table: per row the still-air and the mean-state mode of that rank, and the
    damped mode paired with the mean-state one by shape (``ModesResult.paired_*``), not by rank."""
    import numpy as np

    t = Table(title=f"{res.case.name}: natural frequencies (Hz)", title_justify="left")
    for c in ("mode", "still air", "direction", "mean state", "direction", "damped (Hz)", "damping ratio", "MAC"):
        t.add_column(c, justify="right")
    dirs = "xyz"
    ds, dm = res.still_air.dominant_direction(), res.mean.dominant_direction()
    for i in range(res.still_air.frequencies_hz.size):
        damped = ("", "", "")
        if res.paired_hz is not None and i < res.paired_hz.size and np.isfinite(res.paired_hz[i]):
            z = res.paired_ratio[i]
            style = "[bold red]" if z < 0.005 else ""
            damped = (f"{res.paired_hz[i]:.4f}", f"{style}{z:.3g}{'[/]' if style else ''}", f"{res.paired_mac[i]:.2f}")
        t.add_row(str(i + 1), f"{res.still_air.frequencies_hz[i]:.4f}", dirs[ds[i]],
                  f"{res.mean.frequencies_hz[i]:.4f}", dirs[dm[i]], *damped)
    return t
