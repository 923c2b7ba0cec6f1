"""`batch` and `scan` commands: many cases / many downburst configurations, in parallel.

Both parse options, build an executor (:func:`linecheck.batch.make_executor`:
sequential, local process pool or Dask) and delegate to :mod:`linecheck.batch`;
this module only draws progress and tables.  Exit codes: 0 ok, 1 a case failed,
2 usage errors (bad option, unwritable output), 130 interrupted.
"""

from __future__ import annotations

import glob
import threading
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..core.errors import CaseError
from .app import CaseArg, app, console, err_console, handle_errors, read_case
from .limits import MaxMemoryOpt, apply_max_memory
from .stats_view import MaxRealOpt, UntilOpt, parse_until

JobsOpt = Annotated[int | None, typer.Option(
    "--jobs", "-j", help="Local worker processes (default: the number of cores; 1 runs in this process).",
    min=1, show_default=False)]
SchedulerOpt = Annotated[str | None, typer.Option(
    "--scheduler", help="Run on a Dask distributed cluster at this address (tcp://HOST:PORT); "
                        "needs pip install 'linecheck\\[dask]'.", show_default=False)]
BatchExcelOpt = Annotated[Path | None, typer.Option(
    "--excel", help="Also write the Excel design sheet (.xlsx) of all cases to this file.", show_default=False)]
BatchTemplateOpt = Annotated[Path | None, typer.Option(
    "--template", help="Excel template with the title-block defined names.", show_default=False)]
BatchForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing Excel file.")]
JsonDirOpt = Annotated[Path | None, typer.Option(
    "--json-dir", help="Folder of the per-case JSON results (default: results/ next to --excel, else ./results).",
    show_default=False)]
ChunkOpt = Annotated[int | None, typer.Option(
    "--chunk", help="Realizations per task (default 10, fewer when there are fewer realizations than workers); "
                    "results do not depend on it.",
    min=1, show_default=False)]


def expand_cases(paths: list[Path]) -> list[Path]:
    """Expand glob patterns the shell left alone (e.g. on Windows); keep the order, drop repeats."""
    out: list[Path] = []
    seen: set[Path] = set()
    for p in paths:
        s = str(p)
        matches = sorted(glob.glob(s)) if any(ch in s for ch in "*?[") and not p.exists() else [s]
        if not matches:
            raise CaseError("no case file matches this pattern", file=s)
        for m in matches:
            key = Path(m).resolve()
            if key not in seen:
                seen.add(key)
                out.append(Path(m))
    return out


def _check_excel(excel: Path | None, force: bool, template: Path | None) -> None:
    if excel is None:
        return
    try:
        from ..excel.writer import check_excel_target
    except ImportError:
        from ..io.atomic import check_target

        check_target(excel, force=force, what="Excel")
        return
    check_excel_target(excel, force=force, template=template)


def _write_excel(docs: list[dict[str, Any]], excel: Path, force: bool, template: Path | None) -> None:
    try:
        from ..excel.writer import write_workbook
    except ImportError:
        raise CaseError("Excel output is not available in this installation (linecheck.excel missing)") from None
    kwargs: dict[str, Any] = {"force": force}
    if template is not None:
        kwargs["template"] = template
    write_workbook(docs, excel, **kwargs)


class BatchDisplay:
    """Rich progress for :class:`linecheck.batch.BatchEvent`: one overall bar, one bar per running case."""

    def __init__(self) -> None:
        self.bars = Progress(
            TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[count]}"),
            TimeElapsedColumn(), console=err_console, transient=True,
        )
        self.overall: TaskID | None = None
        self.cases: dict[int, TaskID] = {}

    def __enter__(self) -> BatchDisplay:
        self.bars.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bars.__exit__(*exc)

    def _count(self, done: float, total: int) -> str:
        return f"{int(done)}/{total}"

    def __call__(self, ev: Any) -> None:
        b = self.bars
        if ev.kind == "start":
            self.overall = b.add_task(f"[bold]batch[/] on {ev.message}", total=max(ev.overall_total, 1),
                                      count=self._count(ev.overall_done, ev.overall_total))
            return
        if self.overall is not None:
            b.update(self.overall, completed=ev.overall_done, count=self._count(ev.overall_done, ev.overall_total))
        if ev.kind == "case_start" and ev.case not in self.cases:
            self.cases[ev.case] = b.add_task(f"  {escape(ev.name)}", total=max(ev.total, 1), count=self._count(ev.done, ev.total))
        elif ev.kind == "case_progress" and ev.case in self.cases:
            b.update(self.cases[ev.case], completed=ev.done, count=self._count(ev.done, ev.total))
        elif ev.kind in ("case_done", "case_failed", "case_skipped"):
            if ev.case in self.cases:
                b.remove_task(self.cases.pop(ev.case))
            if ev.kind == "case_done":
                b.console.print(f"[green]done[/]    {escape(ev.name)}", highlight=False)
            elif ev.kind == "case_skipped":
                b.console.print(f"[cyan]skipped[/] {escape(ev.name)} [dim](saved result matches the case file)[/]",
                                highlight=False)
            else:
                b.console.print(f"[red]failed[/]  {escape(ev.name)}: {escape(ev.message)}", highlight=False, soft_wrap=True)


def _kn(doc: dict[str, Any] | None, reaction: str, stat: str, scale: float = 1e-3, fmt: str = "{:.2f}") -> str:
    try:
        v = doc["reactions"][reaction][stat]["mean"]  # type: ignore[index]
    except (KeyError, TypeError):
        return ""
    return "**" if v is None else fmt.format(v * scale)


def summary_table(report: Any) -> Table:
    """One row per case: status, peak reactions, gust factors, Cont_R, time, JSON or error."""
    t = Table(title="batch summary (tower of interest)", title_justify="left")
    for col, just in (("case", "left"), ("status", "left"), ("n", "right"), ("peak Rx kN", "right"), ("peak Ry kN", "right"),
                      ("GF_Dy Rx", "right"), ("GF_Dy Ry", "right"), ("Cont_R Ry %", "right"), ("time s", "right"),
                      ("result / error", "left")):
        t.add_column(col, justify=just, overflow="fold")
    colours = {"done": "green", "skipped": "cyan", "failed": "red", "cancelled": "yellow", "pending": "yellow"}
    for o in report.outcomes:
        d = o.doc
        t.add_row(
            escape(o.name), f"[{colours.get(o.status, 'white')}]{o.status}[/]",
            str(d.get("realizations", "")) if d else "",
            _kn(d, "Rx", "peak_dynamic"), _kn(d, "Ry", "peak_dynamic"),
            _kn(d, "Rx", "GF_Dy", 1.0, "{:.3f}"), _kn(d, "Ry", "GF_Dy", 1.0, "{:.3f}"),
            _kn(d, "Ry", "Cont_R", 100.0, "{:.1f}"),
            f"{o.elapsed:.1f}" if o.status == "done" else "",
            escape(o.error if o.error else (str(o.json_path) if o.json_path and o.ok else "")),
        )
    return t


@app.command()
@handle_errors
def batch(
    cases: Annotated[list[Path], typer.Argument(help="Case files (TOML); shell globs like cases/paper/*.toml.",
                                                show_default=False)],
    excel: BatchExcelOpt = None,
    json_dir: JsonDirOpt = None,
    jobs: JobsOpt = None,
    scheduler: SchedulerOpt = None,
    resume: Annotated[bool, typer.Option(
        "--resume", help="Skip cases whose saved JSON result matches the case file's content hash.")] = False,
    force: BatchForceOpt = False,
    template: BatchTemplateOpt = None,
    chunk: ChunkOpt = None,
    max_memory: MaxMemoryOpt = None,
    until: UntilOpt = None,
    max_realizations: MaxRealOpt = 1000,
) -> None:
    """Run many cases (all realizations) in parallel, saving each result as it completes."""
    from ..batch import make_executor, run_batch

    apply_max_memory(max_memory)  # each task checks its memory estimate (workers inherit the limit)

    paths = expand_cases(cases)
    target = parse_until(until)
    _check_excel(excel, force, template)
    out_dir = json_dir if json_dir is not None else ((excel.parent if excel is not None else Path.cwd()) / "results")
    cancel = threading.Event()
    with make_executor(jobs, scheduler) as executor, BatchDisplay() as display:
        report = run_batch(paths, executor=executor, json_dir=out_dir, resume=resume, chunk_size=chunk,
                           progress=display, cancel=cancel,
                           until=None if target is None else (target, max_realizations))
    console.print(summary_table(report))
    n_done = sum(o.status == "done" for o in report.outcomes)
    n_skip = sum(o.status == "skipped" for o in report.outcomes)
    console.print(f"{n_done} run, {n_skip} skipped, {len(report.failed)} failed "
                  f"in {report.elapsed:.1f} s on {report.executor}; results in {out_dir}", highlight=False)
    if report.cancelled:
        err_console.print(f"[bold red]interrupted[/]: finished cases are saved in {out_dir}; "
                          "run again with --resume to do the rest", highlight=False)
        raise typer.Exit(130)
    if excel is not None:
        _write_excel(report.docs(), excel, force, template)
        console.print(f"wrote {excel}")
    if report.failed:
        err_console.print(f"[bold red]error:[/] {len(report.failed)} case(s) failed: "
                          + escape(", ".join(o.name for o in report.failed)), highlight=False, soft_wrap=True)
    raise typer.Exit(report.exit_code)


# --------------------------------------------------------------------------- scan
PAPER_CRITICAL = {"Rx": ("Db_x", 1.6, 30.0), "Ry": ("Db_y", 1.2, 0.0)}  # paper Table 2 (El Damatty et al. 2013)


def scan_table(result: Any) -> Table:
    t = Table(title=f"{result.case.name}: critical downburst configurations "
                    f"(tower {result.case.line.tower_of_interest}, step 1)", title_justify="left")
    for col in ("reaction", "R m", "R/D_j", "Θ deg", "D_j m", "max |mean| kN", "at t s", "V_ref at p m/s", "paper"):
        t.add_column(col, justify="right")
    for c in result.criticals(("Rx", "Ry")):
        name, ratio, theta = PAPER_CRITICAL[c.reaction]
        t.add_row(c.reaction, f"{c.distance:.0f}", f"{c.distance_over_dj:.2f}", f"{c.angle:g}", f"{c.jet_diameter:.0f}",
                  f"{c.value / 1e3:.3f}", f"{c.time:.1f}", f"{c.v_ref:.1f}", f"{name}: R = {ratio:g} D_j, Θ = {theta:g}°")
    return t


def dynamic_table(report: Any) -> Table:
    t = Table(title="full analysis at the critical configurations", title_justify="left")
    for col in ("run", "status", "peak Rx kN", "peak Ry kN", "GF_Dy Rx", "GF_Dy Ry", "Cont_R Rx %", "Cont_R Ry %"):
        t.add_column(col, justify="right" if col not in ("run", "status") else "left")
    for o in report.outcomes:
        d = o.doc
        t.add_row(escape(o.name), o.status if not o.error else escape(f"failed: {o.error}"),
                  _kn(d, "Rx", "peak_dynamic"), _kn(d, "Ry", "peak_dynamic"),
                  _kn(d, "Rx", "GF_Dy", 1.0, "{:.3f}"), _kn(d, "Ry", "GF_Dy", 1.0, "{:.3f}"),
                  _kn(d, "Rx", "Cont_R", 100.0, "{:.1f}"), _kn(d, "Ry", "Cont_R", 100.0, "{:.1f}"))
    return t


@app.command()
@handle_errors
def scan(
    case_file: CaseArg,
    distance: Annotated[str | None, typer.Option(
        "--distance", help="R values START:STOP:STEP (metres, or with a Dj suffix multiples of D_j) or a list "
                           "(default 0.5:2.5:0.1Dj).", show_default=False)] = None,
    angle: Annotated[str | None, typer.Option(
        "--angle", help="Θ values START:STOP:STEP or a list, degrees (default -80:80:10).", show_default=False)] = None,
    jet_diameter: Annotated[str | None, typer.Option(
        "--jet-diameter", help="D_j values START:STOP:STEP or a list, metres (default: the case's D_j).",
        show_default=False)] = None,
    csv_out: Annotated[Path | None, typer.Option("--csv", help="Write every scan point to this CSV file.",
                                                 show_default=False)] = None,
    hold: Annotated[str, typer.Option(
        "--hold", help="Storm strength over the grid: 'jet' = one storm (V_max of the case's own configuration) "
                       "moved around; 'vref' = the case's V_ref at point p in every configuration.")] = "jet",
    dynamic: Annotated[bool, typer.Option(
        "--dynamic", help="Then run the full three-step analysis at the critical configurations.")] = False,
    json_dir: Annotated[Path | None, typer.Option(
        "--json-dir", help="With --dynamic: save the critical runs' JSON results in this folder.",
        show_default=False)] = None,
    jobs: JobsOpt = None,
    scheduler: SchedulerOpt = None,
    max_memory: MaxMemoryOpt = None,
) -> None:
    """Find the critical downburst configurations: step 1 over a grid of positions and sizes."""
    apply_max_memory(max_memory)  # each step-1 task checks its memory estimate
    from ..batch import ScanGrid, make_executor, run_critical, run_scan, write_scan_csv
    from ..io.atomic import check_target
    from .progress import progress_bar

    case = read_case(case_file)
    grid = ScanGrid.from_options(case, distance, angle, jet_diameter)
    if csv_out is not None:
        check_target(csv_out, what="CSV")
    cancel = threading.Event()
    with make_executor(jobs, scheduler) as executor:
        try:
            with progress_bar() as cb:
                result = run_scan(case_file, grid, executor=executor, hold=hold, progress=cb, cancel=cancel)
        except KeyboardInterrupt:
            cancel.set()
            raise
        console.print(scan_table(result))
        strength = (f"one storm, V_max = {result.v_max:.1f} m/s (the case's own configuration)"
                    if result.hold == "jet" else f"V_ref = {case.wind.v_ref:g} m/s at point p everywhere")
        console.print(f"[dim]{grid.size} configurations in {result.elapsed:.1f} s on {escape(result.executor)}; "
                      f"{strength}; value = wind-induced mean reaction with the largest magnitude over the "
                      "event.[/]", highlight=False)
        if result.n_failed:
            first = next(e for e in result.errors if e)
            err_console.print(f"[yellow]warning:[/] {result.n_failed} configuration(s) failed and were left out, "
                              f"e.g.: {escape(first)}", highlight=False, soft_wrap=True)
        if csv_out is not None:
            write_scan_csv(result, csv_out)
            console.print(f"wrote {csv_out}")
        if not result.criticals():
            raise CaseError("no scan configuration could be analysed", file=str(case_file))
        if dynamic:
            console.print(f"[dim]full analysis at the critical configurations with the case's V_ref = "
                          f"{case.wind.v_ref:g} m/s at point p[/]", highlight=False)
            with BatchDisplay() as display:
                report = run_critical(result, executor=executor, json_dir=json_dir, progress=display, cancel=cancel)
            console.print(dynamic_table(report))
            if report.cancelled:
                raise typer.Exit(130)
            if report.failed:
                raise typer.Exit(1)
