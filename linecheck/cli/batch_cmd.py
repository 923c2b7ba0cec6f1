"""`batch` and `scan` commands: many cases / many downburst configurations, in parallel.

Both parse options, build an executor (:func:`linecheck.batch.make_executor`:
sequential, local process pool or Dask) and delegate to :mod:`linecheck.batch`;
this module only draws progress and tables.  Exit codes: 0 ok, 1 a case failed,
2 usage errors (bad option, unwritable output), 130 interrupted.
"""

from __future__ import annotations

import glob
import threading
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..core.errors import CaseError, printable
from ..core.extremes import (
    CONT_R_THRESHOLD as CONT_R_FLAG,  # Cont_R flag, paper Sect. 5 (one definition)
)
from ..core.names import REACTIONS
from ..io.display import STAT_ROWS, kn, kn_text
from ..io.document import RunDocument, SanityCheckRow
from .common import CaseArg, app, console, err_console, error_line, handle_errors, path_value, read_case
from .export_cmd import (
    EngineerOpt,
    LineOpt,
    ProjectOpt,
    RevisionOpt,
    TitleOpt,
    title_block,
)
from .limits import MaxMemoryOpt, apply_max_memory
from .scan_progress import ScanDisplay
from .signals import sigterm_cancels
from .stats_view import MaxRealOpt, UntilOpt, parse_until

JobsOpt = Annotated[int | None, typer.Option(
    "--jobs", "-j", help="Local worker processes (default: the number of cores; 1 runs in this process).",
    min=1, show_default=False)]
SchedulerOpt = Annotated[str | None, typer.Option(
    "--scheduler", help="Run on a Dask distributed cluster at this address (tcp://HOST:PORT); "
                        "needs pip install 'linecheck\\[dask]'.", show_default=False)]
ConnectTimeoutOpt = Annotated[float, typer.Option(
    "--connect-timeout", help="With --scheduler: seconds allowed for the connection and the scheduler's handshake "
                              "(each step; an unreachable or silent address exits 2).", min=0.001, max=3600.0)]
BatchExcelOpt = Annotated[Path | None, typer.Option(
    "--excel", help="Also write the Excel design sheet (.xlsx) of all cases to this file.", show_default=False,
    parser=path_value)]
BatchTemplateOpt = Annotated[Path | None, typer.Option(
    "--template", help="Excel template with the title-block defined names.", show_default=False, parser=path_value)]
BatchForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing Excel file.")]
JsonDirOpt = Annotated[Path | None, typer.Option(
    "--json-dir", help="Folder of the per-case JSON results (default: results/ next to --excel, else ./results).",
    show_default=False, parser=path_value)]
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


def _check_outputs(jobs: list[Any], plan: Any, excel: Path | None, template: Path | None, out_dir: Path) -> None:
    """Refuse (exit 2, before any work) a workbook or a per-case JSON result that would overwrite
    an input of the batch: a case file, its tower table or field file, the template."""
    from ..io.outputs import case_inputs, check_outputs

    inputs: list[tuple[str, Any]] = [("template", template)]
    outputs: list[tuple[str, Any]] = [("--excel", excel)]
    seen: set[Path] = set()
    for job in jobs:
        path = Path(getattr(job, "path", job))
        if path not in seen:
            seen.add(path)
            try:
                inputs += case_inputs(read_case(path))
            except CaseError:  # a bad case fails alone in the batch, with its message
                inputs.append(("case file", path))
        name = getattr(job, "json_name", None) or f"{path.stem}.json"
        outputs.append((f"result {name} in --json-dir", out_dir / name))
    for path in plan or ():  # --models: one combined <stem>.json per case file besides the runs
        outputs.append((f"result {path.stem}.json in --json-dir", out_dir / f"{path.stem}.json"))
    outs = list(dict.fromkeys(outputs))  # a --models case's own run and its combined document share a name
    check_outputs(outs, inputs)


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


def _write_excel(docs: list[Any], excel: Path, force: bool, template: Path | None,
                 title: dict[str, str] | None = None) -> None:
    try:
        from ..excel.writer import write_workbook
    except ImportError:
        raise CaseError("Excel output is not available in this installation (linecheck.excel missing)") from None
    kwargs: dict[str, Any] = {"force": force, "title": title or None}
    if template is not None:
        kwargs["template"] = template
    write_workbook(docs, excel, **kwargs)


def _clock(seconds: float) -> str:
    s = int(round(max(0.0, seconds)))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def _count(done: float, total: int) -> str:
    return f"{done:.1f}/{total}" if done != int(done) else f"{int(done)}/{total}"


class _Rate:
    """Elapsed time and ETA of a batch from its events (realizations done in this run)."""

    def __init__(self) -> None:
        self.t0 = time.monotonic()
        self.start_done: float | None = None  # realizations already done (resume) when the batch started

    def elapsed(self) -> float:
        return time.monotonic() - self.t0

    def eta(self, done: float, total: int) -> str:
        base = self.start_done or 0.0
        ran = done - base
        if ran <= 0 or total <= done:
            return "--:--:--" if total > done else _clock(0)
        return _clock(self.elapsed() * (total - done) / ran)

    def summary(self, ev: Any) -> str:
        pct = 100.0 * ev.overall_done / ev.overall_total if ev.overall_total else 100.0
        return (f"cases {ev.cases_done}/{ev.cases_total}, realizations {_count(ev.overall_done, ev.overall_total)} "
                f"({pct:.0f} %), elapsed {_clock(self.elapsed())}, ETA {self.eta(ev.overall_done, ev.overall_total)}")


class BatchDisplay:
    """Progress for :class:`linecheck.batch.BatchEvent`.

    In a terminal (rich): one overall bar (cases and realizations done / total, elapsed,
    ETA) and one bar per running case, both moving while chunks run (tasks report at
    least once per realization).  Piped (CI, logs): plain lines -- one per finished,
    failed or skipped case, and a progress line when a whole realization more is done,
    at most every ``interval`` seconds (0: every realization).
    """

    def __init__(self, *, interval: float = 5.0, live: bool | None = None, console: Any = None) -> None:
        self.console = console if console is not None else err_console
        self.live = self.console.is_terminal if live is None else live
        self.interval = interval
        self.rate = _Rate()
        self.last_line = float("-inf")
        self.last_whole = 0
        self.bars = Progress(
            TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[count]}"),
            TimeElapsedColumn(), TextColumn("{task.fields[eta]}"), console=self.console, transient=True,
            disable=not self.live,
        )
        self.overall: TaskID | None = None
        self.cases: dict[int, TaskID] = {}

    def __enter__(self) -> BatchDisplay:
        self.bars.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bars.__exit__(*exc)

    def _count(self, done: float, total: int) -> str:
        return _count(done, total)

    def _overall_count(self, ev: Any) -> str:
        return f"{ev.cases_done}/{ev.cases_total} cases, {self._count(ev.overall_done, ev.overall_total)} realizations"

    def _line(self, text: str) -> None:
        self.console.print(printable(text), highlight=False, soft_wrap=True, markup=False, emoji=False)
        self.last_line = time.monotonic()

    def __call__(self, ev: Any) -> None:
        if ev.kind == "start":
            self.rate = _Rate()
            self.rate.start_done = ev.overall_done
            self.last_whole = int(ev.overall_done)
        if self.live:
            self._live(ev)
        else:
            self._plain(ev)

    def _plain(self, ev: Any) -> None:
        if ev.kind == "start":
            self._line(f"batch: {ev.cases_total} case(s), {ev.overall_total} realizations on {ev.message}")
        elif ev.kind in ("case_done", "case_failed", "case_skipped"):
            word = {"case_done": "done", "case_failed": "failed", "case_skipped": "skipped"}[ev.kind]
            extra = f": {ev.message}" if ev.kind == "case_failed" else ""
            self._line(f"{word:<8}{ev.name}{extra}  [{self.rate.summary(ev)}]")
            self.last_whole = int(ev.overall_done)
        elif ev.kind == "case_warning":
            self._line(f"warning: {ev.name}: {ev.message}")
        elif ev.kind == "case_progress":
            whole = int(ev.overall_done)
            if whole > self.last_whole and time.monotonic() - self.last_line >= self.interval:
                self.last_whole = whole
                self._line(f"progress: {self.rate.summary(ev)}")

    def _live(self, ev: Any) -> None:
        b = self.bars
        if ev.kind == "start":
            self.overall = b.add_task(f"[bold]batch[/] on {escape(ev.message)}", total=max(ev.overall_total, 1),
                                      count=self._overall_count(ev), eta="")
            return
        if self.overall is not None:
            b.update(self.overall, completed=ev.overall_done, count=self._overall_count(ev),
                     eta=f"ETA {self.rate.eta(ev.overall_done, ev.overall_total)}")
        if ev.kind == "case_warning":
            b.console.print(f"[yellow]warning:[/] {escape(printable(f'{ev.name}: {ev.message}'))}", highlight=False,
                            soft_wrap=True)
        if ev.kind in ("case_start", "case_progress") and ev.case not in self.cases:
            self.cases[ev.case] = b.add_task(f"  {escape(ev.name)}", total=max(ev.total, 1),
                                             count=self._count(ev.done, ev.total), eta="")
        if ev.kind == "case_progress" and ev.case in self.cases:
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
                b.console.print(f"[red]failed[/]  {escape(printable(f'{ev.name}: {ev.message}'))}", highlight=False,
                                soft_wrap=True)


def _kn(doc: RunDocument | None, reaction: str, stat: str, fmt: str = "{:.2f}") -> str:
    """The realization mean of ``stat`` in its shown unit (statistics table), "" without a result."""
    if doc is None:
        return ""
    v = doc.reactions[reaction][stat].mean
    return "**" if v is None else fmt.format(v * STAT_ROWS[stat].scale)


QUANTITY_TEXT = {"rms_background": "background r.m.s.", "rms_fluctuating": "fluctuating r.m.s."}


def cont_r_flags(doc: RunDocument | None, state: str = "recommended") -> list[str]:
    """Reactions whose ``dynamic_analysis`` flag is ``state`` ("recommended": the 95 % interval
    of Cont_R lies above :data:`CONT_R_FLAG`; "inconclusive": it straddles it)."""
    if doc is None:
        return []
    return [r for r in REACTIONS if doc.reactions[r].dynamic_analysis == state]


def sanity_failures(doc: RunDocument | None) -> list[SanityCheckRow]:
    """The failed items of the time- vs frequency-domain sanity check of a synoptic result."""
    if doc is None or doc.spectral is None:
        return []
    return [i for i in doc.spectral.sanity_check or () if not i.ok]


def _sanity_text(item: SanityCheckRow) -> str:
    return (f"{item.reaction} {QUANTITY_TEXT.get(item.quantity, item.quantity)} "
            f"{kn_text(item.time_domain, '?')} vs {kn_text(item.frequency_domain, '?')} kN "
            f"(allowed difference {kn_text(item.allowed_difference, '?')})")


def _flag_names(doc: RunDocument | None, reactions: list[str], columns: dict[str, str]) -> str:
    """The reactions a Cont_R flag names; one without a Cont_R column carries its value (``Rz 12.3%``)."""
    return " ".join(r if r in columns else f"{r} {_kn(doc, r, 'Cont_R', '{:.1f}')}%" for r in reactions)


def summary_table(report: Any) -> Table:
    """One row per case: status, peak reactions, gust factors, Cont_R, flags, time, JSON or error.

    Flags: ``Cont_R>10% <reactions>`` (dynamic analysis recommended), ``Cont_R~10% <reactions>``
    (inconclusive) and ``t/f check`` (the time- and frequency-domain r.m.s. of a synoptic case
    differ); :func:`summary_notes` explains them.  Rx and Ry have their Cont_R columns,
    highlighted as their flags; a flag on Rz (no column) carries its value, ``Rz 12.3%``.
    """
    t = Table(title="batch summary (tower of interest)", title_justify="left")
    for col, just in (("case", "left"), ("status", "left"), ("n", "right"), ("peak Rx kN", "right"),
                      ("peak Ry kN", "right"), ("GF_Dy Rx", "right"), ("GF_Dy Ry", "right"), ("Cont_R Rx %", "right"),
                      ("Cont_R Ry %", "right"), ("flags", "left"), ("time s", "right"), ("result / error", "left")):
        t.add_column(col, justify=just, overflow="fold")
    colours = {"done": "green", "skipped": "cyan", "failed": "red", "cancelled": "yellow", "pending": "yellow"}
    for o in report.outcomes:
        d = o.doc
        flagged = cont_r_flags(d)
        unsure = cont_r_flags(d, "inconclusive")
        cont = {}
        for r in ("Rx", "Ry"):
            cont[r] = _kn(d, r, "Cont_R", "{:.1f}")
            if r in flagged:
                cont[r] = f"[bold yellow]{cont[r]}[/]"
            elif r in unsure:
                cont[r] = f"[yellow]{cont[r]}[/]"
        flags = []
        if flagged:
            flags.append(f"[bold yellow]Cont_R>10% {_flag_names(d, flagged, cont)}[/]")
        if unsure:
            flags.append(f"[yellow]Cont_R~10% {_flag_names(d, unsure, cont)}[/]")
        if sanity_failures(d):
            flags.append("[bold red]t/f check[/]")
        t.add_row(
            escape(o.name), f"[{colours.get(o.status, 'white')}]{o.status}[/]",
            str(d.realizations) if d else "",
            _kn(d, "Rx", "peak_dynamic"), _kn(d, "Ry", "peak_dynamic"),
            _kn(d, "Rx", "GF_Dy", "{:.3f}"), _kn(d, "Ry", "GF_Dy", "{:.3f}"),
            cont["Rx"], cont["Ry"], " ".join(flags),
            f"{o.elapsed:.1f}" if o.status == "done" else "",
            escape(o.error if o.error else (str(o.json_path) if o.json_path and o.ok else "")),
        )
    return t


def summary_notes(report: Any) -> list[str]:
    """Footnotes of :func:`summary_table` for the flags that appear in it (rich markup)."""
    notes = []
    if any(cont_r_flags(o.doc) for o in report.outcomes):
        notes.append(f"[bold yellow]Cont_R>10%[/]: the resonant share of the peak (Cont_R, Eq. 16) of these reactions "
                     f"exceeds {CONT_R_FLAG:.0%} (its 95 % interval lies above): dynamic analysis recommended (a "
                     "quasi-static analysis misses it).")
    if any(cont_r_flags(o.doc, "inconclusive") for o in report.outcomes):
        notes.append(f"[yellow]Cont_R~10%[/]: the 95 % interval of Cont_R straddles {CONT_R_FLAG:.0%}: inconclusive, "
                     "run more realizations (--until 1%).")
    bad = [(o.name, sanity_failures(o.doc)) for o in report.outcomes if sanity_failures(o.doc)]
    if bad:
        notes.append("[bold red]t/f check[/]: time- and frequency-domain r.m.s. differ by more than the sampling "
                     "error of the realizations explains (see the case's sanity check, `linecheck spectral`): "
                     + "; ".join(f"{escape(name)}: " + ", ".join(_sanity_text(i) for i in items)
                                 for name, items in bad) + ".")
    return notes


@app.command()
@handle_errors
def batch(
    cases: Annotated[list[Path], typer.Argument(help="Case files (TOML); shell globs like cases/paper/*.toml.",
                                                show_default=False, parser=path_value)],
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
    project: ProjectOpt = None,
    line: LineOpt = None,
    engineer: EngineerOpt = None,
    revision: RevisionOpt = None,
    title: TitleOpt = None,
    connect_timeout: ConnectTimeoutOpt = 10.0,
    progress_interval: Annotated[float, typer.Option(
        "--progress-interval", help="Output not a terminal (CI, logs): print a progress line at most every this "
                                    "many seconds, when one more realization is done (0: every realization).",
        min=0.0)] = 5.0,
    models: Annotated[str | None, typer.Option(
        "--models", help='Downburst model spread: run every case under "all" built-in running-mean models (or a '
                         'comma list) with the same seeds; <stem>.<model>.json per run, <stem>.json with the '
                         '"models" block and envelope.', show_default=False)] = None,
    until: UntilOpt = None,
    max_realizations: MaxRealOpt = 1000,
) -> None:
    """Run many cases (all realizations) in parallel, saving each result as it completes."""
    apply_max_memory(max_memory)  # each task checks its memory estimate (workers inherit the limit)

    fields = title_block(project, line, engineer, revision, title, excel=excel)
    paths = expand_cases(cases)
    target = parse_until(until)
    paths, plan, out_dir = _plan_batch(paths, models, excel, json_dir, template, force)
    report = _run_batch(paths, out_dir, jobs=jobs, scheduler=scheduler, connect_timeout=connect_timeout,
                        resume=resume, chunk=chunk, progress_interval=progress_interval,
                        until=None if target is None else (target, max_realizations))
    _print_batch_summary(report, out_dir)
    docs = report.docs()
    if plan is not None:
        docs = _write_model_documents(report, plan, out_dir)
    if excel is not None:
        _write_excel(docs, excel, force, template, fields)
        console.print(f"wrote {excel}")
    _report_failures(report, scheduler, out_dir)
    raise typer.Exit(report.exit_code)


def _plan_batch(paths: list[Any], models: str | None, excel: Path | None, json_dir: Path | None,
                template: Path | None, force: bool) -> tuple[list[Any], Any, Path]:
    """The jobs (one per case file, or per case and model with --models, and the model plan) and
    the JSON folder, after refusing (exit 2, before any work) outputs that would overwrite inputs."""
    plan = None
    if models is not None:
        from ..batch.models import model_jobs

        paths, plan = model_jobs(paths, models)
    out_dir = json_dir if json_dir is not None else ((excel.parent if excel is not None else Path.cwd()) / "results")
    _check_outputs(paths, plan, excel, template, out_dir)
    _check_excel(excel, force, template)
    return paths, plan, out_dir


def _run_batch(paths: list[Any], out_dir: Path, *, jobs: int | None, scheduler: str | None,
               connect_timeout: float, resume: bool, chunk: int | None, progress_interval: float,
               until: tuple[Any, int] | None) -> Any:
    """The batch on its executor with the progress display; SIGTERM cancels it like Ctrl-C
    (summary, results kept, 130).  The compiled-kernel warning comes first, one line."""
    from ..batch import make_executor, run_batch
    from ..io.provenance import kernel_warning
    from .limits import warn as limits_warn

    kernel_off = kernel_warning()  # compiled pieces off (Numba installed): one line, before the batch
    if kernel_off:
        limits_warn(kernel_off)
    cancel = threading.Event()  # set by SIGTERM too: the batch stops like Ctrl-C (summary, results kept, 130)
    with (sigterm_cancels(cancel), make_executor(jobs, scheduler, connect_timeout) as executor,
          BatchDisplay(interval=progress_interval) as display):
        return run_batch(paths, executor=executor, json_dir=out_dir, resume=resume, chunk_size=chunk,
                         progress=display, cancel=cancel, until=until)


def _print_batch_summary(report: Any, out_dir: Path) -> None:
    """The summary table, its notes and the counts; a full disk (exit 2) or an interruption (exit
    130) stops here, with how to go on."""
    console.print(summary_table(report))
    for note in summary_notes(report):
        console.print(note, highlight=False, soft_wrap=True)
    n_done = sum(o.status == "done" for o in report.outcomes)
    n_skip = sum(o.status == "skipped" for o in report.outcomes)
    console.print(f"{n_done} run, {n_skip} skipped, {len(report.failed)} failed "
                  f"in {report.elapsed:.1f} s on {report.executor}; results in {out_dir}", highlight=False)
    if report.output_error:
        n_saved = sum(o.status == "done" for o in report.outcomes)
        raise CaseError(f"{report.output_error}; the batch stopped, {n_saved} result(s) saved in {out_dir}: "
                        "free space (or fix the folder) and run again with --resume")
    if report.cancelled:
        err_console.print(f"[bold red]interrupted[/]: finished cases are saved in {out_dir}; "
                          "run again with --resume to do the rest", highlight=False)
        raise typer.Exit(130)


def _write_model_documents(report: Any, plan: Any, out_dir: Path) -> list[Any]:
    """--models: one document per case file with the "models" block, saved as <stem>.json; returns
    the documents of the workbook."""
    from ..batch.models import combined_documents
    from ..io.jsonout import write_json

    docs = combined_documents(report, plan)
    spread = [(path, d) for path, d in zip(plan, docs) if isinstance(d, RunDocument) and d.models is not None]
    for path, doc in spread:
        write_json(out_dir / f"{path.stem}.json", doc)
    console.print(f"model spread: {len(spread)} case document(s) with a \"models\" block "
                  f"in {out_dir}",
                  highlight=False)
    return docs


def _report_failures(report: Any, scheduler: str | None, out_dir: Path) -> None:
    """One error line naming the failed cases (and, with a lost Dask scheduler, how to resume)."""
    if report.failed:
        from ..batch.executors import SCHEDULER_LOST

        lost = sum(o.error_kind == SCHEDULER_LOST for o in report.failed)
        hint = (f"; the connection to the Dask scheduler at {scheduler} was lost ({lost} of them): start it again "
                f"and run the same command with --resume (finished cases are saved in {out_dir})") if lost else ""
        error_line(f"{len(report.failed)} case(s) failed: " + ", ".join(o.name for o in report.failed) + hint)



# --------------------------------------------------------------------------- scan
PAPER_CRITICAL = {"Rx": ("Db_x", 1.6, 30.0), "Ry": ("Db_y", 1.2, 0.0)}  # paper Table 2 (El Damatty et al. 2013)


def models_scan_table(results: list[Any]) -> Table:
    """Critical configuration per downburst model."""
    t = Table(title="critical configuration per downburst model", title_justify="left")
    for col in ("model", "reaction", "R m", "R/D_j", "Θ deg", "D_j m", "max |mean| kN", "at t s"):
        t.add_column(col, justify="right" if col not in ("model", "reaction") else "left")
    for res in results:
        for c in res.criticals(("Rx", "Ry")):
            t.add_row(res.model or "", c.reaction, f"{c.distance:.0f}", f"{c.distance_over_dj:.2f}", f"{c.angle:g}",
                      f"{c.jet_diameter:.0f}", f"{kn(c.value):.3f}", f"{c.time:.1f}")
    return t


def scan_table(result: Any) -> Table:
    model = escape(f" [{result.model}]") if getattr(result, "model", None) else ""
    t = Table(title=f"{result.case.name}{model}: critical downburst configurations "
                    f"(tower {result.case.line.tower_of_interest}, step 1)", title_justify="left")
    for col in ("reaction", "R m", "R/D_j", "Θ deg", "D_j m", "max |mean| kN", "at t s", "V_ref at p m/s", "paper"):
        t.add_column(col, justify="right")
    for c in result.criticals(("Rx", "Ry")):
        name, ratio, theta = PAPER_CRITICAL[c.reaction]
        t.add_row(c.reaction, f"{c.distance:.0f}", f"{c.distance_over_dj:.2f}", f"{c.angle:g}", f"{c.jet_diameter:.0f}",
                  f"{kn(c.value):.3f}", f"{c.time:.1f}", f"{c.v_ref:.1f}", f"{name}: R = {ratio:g} D_j, Θ = {theta:g}°")
    return t


def peak_scan_table(result: Any) -> Table:
    """Critical configurations by the expected dynamic peak beside those by the mean."""
    t = Table(title=f"critical configurations by the expected dynamic peak |M + B + R| "
                    f"(mean of {result.dynamic_realizations} realization(s) per position) and by the mean, "
                    "at the scanned storm (V_ref at p): they rank the positions, the design values follow",
              title_justify="left")
    for col in ("reaction", "ranked by", "R m", "R/D_j", "Θ deg", "D_j m", "value kN", "V_ref at p m/s",
                "same position"):
        t.add_column(col, justify="right" if col not in ("reaction", "ranked by", "same position") else "left")
    for r in ("Rx", "Ry"):
        cm, cp = result.critical(r, "mean"), result.critical(r, "peak")
        for by, c in (("peak", cp), ("mean", cm)):
            if c is None:
                continue
            same = "yes" if (cm is not None and cp is not None and cm.index == cp.index) else "no"
            label = "expected peak" if by == "peak" else "max |mean|"
            t.add_row(r, label, f"{c.distance:.0f}", f"{c.distance_over_dj:.2f}", f"{c.angle:g}", f"{c.jet_diameter:.0f}",
                      f"{kn(c.value):.3f}", f"{c.v_ref:.1f}", same)
    return t


#: The caption of :func:`dynamic_table`: which of the scan's numbers is the design value.
DESIGN_CAPTION = ("design for the \"design peak\" columns: the full analysis at the case's V_ref at point p. "
                  "\"scan peak\" is the expected peak that ranked the position, with the storm of the scan "
                  "(V_ref at p of that position, --hold) and {k} realization(s): a ranking, not a design value.")


def dynamic_table(report: Any, result: Any = None, v_ref: float | None = None) -> Table:
    """The full analysis at the critical configurations of a dynamic scan: the design peaks (the
    case's ``v_ref`` at point p) beside the scan's expected peak that ranked each position and
    the V_ref at p it was ranked at (``result``: the :class:`~linecheck.batch.ScanResult`)."""
    from ..batch.scan import critical_groups

    at = f" at the case's V_ref = {v_ref:g} m/s at point p" if v_ref is not None else ""
    t = Table(title=f"design values: full analysis at the critical configurations{at}", title_justify="left")
    groups = critical_groups(result) if result is not None else []
    scan_cols = ("scan peak kN", "scan V_ref at p m/s") if groups else ()
    for col in ("run", "status", *scan_cols, "design peak Rx kN", "design peak Ry kN", "V_ref at p m/s",
                "GF_Dy Rx", "GF_Dy Ry", "Cont_R Rx %", "Cont_R Ry %"):
        t.add_column(col, justify="right" if col not in ("run", "status", "scan peak kN") else "left")
    for k, o in enumerate(report.outcomes):
        d = o.doc
        scan = ()
        if groups:
            crits = groups[k][1] if k < len(groups) else []
            scan = (", ".join(f"{c.reaction} {kn(abs(c.value)):.3f}" for c in crits),
                    ", ".join(sorted({f"{c.v_ref:.1f}" for c in crits})))
        vr = "" if d is None or d.v_ref is None else f"{d.v_ref:g}"
        t.add_row(escape(o.name), o.status if not o.error else escape(f"failed: {o.error}"), *scan,
                  _kn(d, "Rx", "peak_dynamic"), _kn(d, "Ry", "peak_dynamic"), vr,
                  _kn(d, "Rx", "GF_Dy", "{:.3f}"), _kn(d, "Ry", "GF_Dy", "{:.3f}"),
                  _kn(d, "Rx", "Cont_R", "{:.1f}"), _kn(d, "Ry", "Cont_R", "{:.1f}"))
    if groups:
        t.caption = DESIGN_CAPTION.format(k=result.dynamic_realizations)
        t.caption_justify = "left"
    return t


def _scan_each_model(case_file: Path, case: Any, grid: Any, names: tuple[str | None, ...], *, hold: str,
                     csv_out: Path | None, dynamic: bool, json_dir: Path | None, jobs: int | None,
                     scheduler: str | None, connect_timeout: float = 10.0, dynamic_realizations: int = 3,
                     progress_interval: float = 5.0) -> None:
    """The scan under each downburst model of ``names`` (None: the case's own model; ``scan
    --models`` gives several), then the critical position per model.  The resource guard's
    warning (a long scan, memory) is printed once, before the first model's scan."""
    from ..batch import make_executor, run_critical, run_scan, write_scan_csv
    from .limits import warn as limits_warn

    cancel = threading.Event()  # set by SIGTERM too: the scan stops like Ctrl-C
    with sigterm_cancels(cancel), make_executor(jobs, scheduler, connect_timeout) as executor:
        summary = []
        for k, model in enumerate(names):
            what = "scan" + (f" [{model}]" if model else "") + (" --dynamic" if dynamic else "")
            try:
                with ScanDisplay(f"{what} on {executor.describe()}", interval=progress_interval) as cb:
                    result = run_scan(case_file, grid, executor=executor, hold=hold, progress=cb, cancel=cancel,
                                      model=model, dynamic_realizations=dynamic_realizations if dynamic else 0,
                                      warn=limits_warn if k == 0 else None)
            except KeyboardInterrupt:
                cancel.set()
                raise
            console.print(scan_table(result))
            if result.dynamic is not None:
                console.print(peak_scan_table(result))
            strength = (f"one storm, V_max = {result.v_max:.1f} m/s (the case's own configuration)"
                        if result.hold == "jet" else f"V_ref = {case.wind.v_ref:g} m/s at point p everywhere")
            console.print(f"[dim]{grid.size} configurations in {result.elapsed:.1f} s on {escape(result.executor)}; "
                          f"{strength}; value = wind-induced mean reaction with the largest magnitude over the "
                          "event.[/]", highlight=False)
            if result.n_failed:
                first = next(e for e in result.errors if e)
                error_line(f"{result.n_failed} configuration(s) failed and were left out, e.g.: {first}",
                           label="warning", style="yellow")
            if csv_out is not None:
                target = csv_out if model is None else csv_out.with_name(f"{csv_out.stem}.{model}{csv_out.suffix}")
                write_scan_csv(result, target)
                console.print(f"wrote {target}")
            if not result.criticals():
                raise CaseError("no scan configuration could be analysed", file=str(case_file))
            summary.append(result)
            if dynamic:
                console.print(f"[dim]full analysis at the critical configurations of the expected dynamic peak "
                              f"with the case's V_ref = {case.wind.v_ref:g} m/s at point p[/]", highlight=False)
                with BatchDisplay() as display:
                    report = run_critical(result, executor=executor, json_dir=json_dir, progress=display, cancel=cancel)
                console.print(dynamic_table(report, result, case.wind.v_ref))
                if report.cancelled:
                    raise typer.Exit(130)
                if report.failed:
                    raise typer.Exit(1)
        if len(summary) > 1:
            console.print(models_scan_table(summary))


@app.command()
@handle_errors
def scan(
    case_file: CaseArg,
    distance: Annotated[str | None, typer.Option(
        "--distance", help="R values START:STOP:STEP or a list, each with its unit: m (metres) or Dj (multiples "
                           "of D_j), after every number or once after the last (720m, 1.2Dj,1.6Dj, 0.5:2.5:0.1Dj; "
                           "default 0.5:2.5:0.1Dj). A bare number is refused.", show_default=False)] = None,
    angle: Annotated[str | None, typer.Option(
        "--angle", help="Θ values START:STOP:STEP or a list, degrees (default -80:80:10).", show_default=False)] = None,
    jet_diameter: Annotated[str | None, typer.Option(
        "--jet-diameter", help="D_j values START:STOP:STEP or a list in m, the unit after every number or once "
                               "after the last (600m, 600:900:100m; default: the case's D_j).",
        show_default=False)] = None,
    csv_out: Annotated[Path | None, typer.Option("--csv", help="Write every scan point to this CSV file.",
                                                 show_default=False, parser=path_value)] = None,
    hold: Annotated[str, typer.Option(
        "--hold", help="Storm strength over the grid: 'jet' = one storm (V_max of the case's own configuration) "
                       "moved around; 'vref' = the case's V_ref at point p in every configuration.")] = "jet",
    dynamic: Annotated[bool, typer.Option(
        "--dynamic", help="Rank every position by the expected dynamic peak |M+B+R| (steps 1-3 with "
                          "--dynamic-realizations realizations each), report the critical positions for the peak "
                          "and for the mean, then run the full analysis at the peak-critical ones.")] = False,
    dynamic_realizations: Annotated[int, typer.Option(
        "--dynamic-realizations", min=1, max=1000,
        help="With --dynamic: realizations per position for the expected peak (their mean).")] = 3,
    json_dir: Annotated[Path | None, typer.Option(
        "--json-dir", help="With --dynamic: save the critical runs' JSON results in this folder.",
        show_default=False, parser=path_value)] = None,
    jobs: JobsOpt = None,
    scheduler: SchedulerOpt = None,
    max_memory: MaxMemoryOpt = None,
    connect_timeout: ConnectTimeoutOpt = 10.0,
    models: Annotated[str | None, typer.Option(
        "--models", help='Scan under "all" built-in downburst running-mean models (or a comma list) and report '
                         "the critical position per model.", show_default=False)] = None,
    progress_interval: Annotated[float, typer.Option(
        "--progress-interval", help="Output not a terminal (CI, logs): print a progress line at most every this "
                                    "many seconds, when more positions are done (0: at every report).",
        min=0.0)] = 5.0,
) -> None:
    """Find the critical downburst configurations: step 1 over a grid of positions and sizes."""
    apply_max_memory(max_memory)  # each step-1 task checks its memory estimate
    from ..batch import ScanGrid
    from ..io.atomic import check_target

    case = read_case(case_file)
    grid = ScanGrid.from_options(case, distance, angle, jet_diameter)
    from .. import service
    from ..io.outputs import case_inputs, check_outputs

    names = service.parse_models(case, models) if models is not None else (None,)  # None: the case's own model
    if csv_out is not None:  # --models: one CSV per model, <stem>.<model>.csv
        check_outputs([(f"--csv ({m})" if m else "--csv", csv_out if m is None else
                        csv_out.with_name(f"{csv_out.stem}.{m}{csv_out.suffix}")) for m in names], case_inputs(case))
        check_target(csv_out, what="CSV")
    _scan_each_model(case_file, case, grid, names, hold=hold, csv_out=csv_out, dynamic=dynamic, json_dir=json_dir,
                     jobs=jobs, scheduler=scheduler, connect_timeout=connect_timeout,
                     dynamic_realizations=dynamic_realizations, progress_interval=progress_interval)
