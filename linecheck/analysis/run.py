"""Steps 2-3 of the method and the statistics of paper Eqs 15-17 (``run_case``, ``run_tower``).

A run is planned once (:func:`plan_run`: the resource guard, step 1, the linear models and their
damping, the burn-in, the record and its mean wind, all frozen in a :class:`RunPlan`), then its
realizations are integrated in chunks that fit in memory (:func:`run_chunk`, on threads with the
compiled step loop) and the chunks are assembled into one result (:func:`assemble`).  Every
realization's turbulence, Newmark columns and statistics are its own, so neither the chunking
nor the threads change a bit.  Nothing here prints.
"""

from __future__ import annotations

import contextlib
import dataclasses
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core import budget, kernel
from ..core.case import Case
from ..core.crossflow import NodeWind
from ..core.dynamics import DynamicResponse, integrate
from ..core.errors import Cancelled
from ..core.line_damping import reference_state_index, structural_omega1
from ..core.loads import fluctuating_loads
from ..core.model import LinearModel, build_models
from ..core.results import Statistics, compute_statistics
from ..core.system import LineSystem
from .burnin import NO_BURN_IN, BurnIn, synoptic_burn_in
from .concurrency import AnyEvent, map_chunks, run_threads, short_switch_interval
from .guard import Warn, check_budget
from .linear import SynopticModel, damping_matrices, synoptic_model
from .record import (
    interpolated_models,
    mean_reactions,
    peak_window_steps,
    record_cross_wind,
    record_time,
    record_wind,
    state_of_step,
    with_burn_in,
)
from .spectral_check import SpectralResult, spectral_analysis
from .step1 import Progress, StaticResult, static_result
from .uplift import require_tension
from .windows import windowed

if TYPE_CHECKING:  # names of annotations only
    from ..core.results import ResultSummary
    from .until import UntilInfo


@dataclass(frozen=True)
class RunResult:
    """Steps 1-3 of a case and the statistics of Eqs 15-17.

    Attributes:
        case, system, static: the case and its step-1 result.
        realizations: realization indices run (seeds spawned per index), shape (n_real,).
        time: [s] record time grid, shape (n_steps,).
        mean: [N] wind-induced mean reaction M(t) at every tower, shape (n_steps, n_towers, 3).
        background, resonant: [N] B(t), R(t) at the tower of interest, shape (n_real, n_steps, 3).
        stats: statistics per realization at every tower (:class:`Statistics`).
        spectral: frequency-domain check (synoptic cases; None for downbursts).
        burn_in: the discarded start of the record and whether it suffices.
        until: the adaptive stop of :func:`~linecheck.analysis.until.run_until` (None for a fixed count).
    """

    case: Case
    system: LineSystem
    static: StaticResult
    realizations: np.ndarray
    time: np.ndarray
    mean: np.ndarray
    background: np.ndarray
    resonant: np.ndarray
    stats: Statistics
    spectral: SpectralResult | None = None
    burn_in: BurnIn | None = None
    until: UntilInfo | None = None

    @property
    def tower_index(self) -> int:
        """0-based index of the tower of interest."""
        return self.case.line.tower_of_interest - 1

    @property
    def still_air(self) -> np.ndarray:
        """[N] still-air reactions at every tower, shape (n_towers, 3)."""
        return self.static.mean.still_air.reactions

    @property
    def windows(self) -> int:
        """Peak windows per realization (1 without ``analysis.peak_window``)."""
        return self.stats.n_samples // max(int(self.realizations.size), 1)

    def summary(self) -> ResultSummary:
        """Statistics summarised over realizations x windows: moments, fractiles, Gumbel fits of
        the peaks, 95 % intervals, the Cont_R flag."""
        from ..core.results import summarise_statistics

        return summarise_statistics(self.stats, self.still_air, self.case.analysis.design_fractile)


@dataclass(frozen=True)
class TowerRun:
    """Steps 1-3 reduced to the reactions of the tower of interest (:func:`run_tower`).

    Attributes:
        static: the case's step-1 result (every tower).
        stats: statistics per realization at the tower of interest alone: every array of
            :class:`Statistics` has a tower axis of length 1, (n_real, 1, 3).
    """

    static: StaticResult
    stats: Statistics


@dataclass(frozen=True)
class RunPlan:
    """Everything the realization chunks of a run share, fixed before the first chunk starts.

    Attributes:
        case, static: the case and its step-1 result; realizations: indices run, (n_real,).
        time: [s] the record with the burn-in, (n_steps,); keep: the analysed steps (after the
            burn-in), bool (n_steps,); burn_in: the burn-in.
        models: linear models of the mean states (paper Eqs 7-9, 13; with ``tower_only`` their
            reaction map G keeps the tower of interest's rows); damping: [N s/m] theirs, upper
            band storage (n_k, 6, n_dof); nearest: the mean state of each step, (n_steps,);
            model_at: the reference scheme's model_at(n) (None: nearest states);
            second_order: the second-order tension operators (None: linear).
        mean: [N] M(t) over the kept steps, (n_keep, n_towers', 3); still_air: [N] the still-air
            reactions, (n_towers', 3); gL: [N] Eq. 17's g_yp L per tower (or one value);
            scale: the statistics' max |M| (defined gust factors; None: from ``mean``);
            towers: the towers whose reactions are computed.
        vn, vl: [m/s] running-mean normal and longitudinal speeds at the nodes, (n_steps, n_nodes)
            (vl None: zero); a_turb: [m/s] the turbulence's modulation I V_m(x, t).
        cross: the cross-flow form's wind over the record (:class:`~linecheck.core.crossflow.NodeWind`;
            None: the horizontal-normal form).
        load_dirs: load directions of the free nodes, (n_free, 3) (None: straight line, y; a
            section: the node normals; the cross-flow form: its directions); threads: chunks at
            once; concurrent: whether threads are used
            (the compiled step loop); chunk: realizations per chunk.
        synoptic: the synoptic mean state's model (None: downburst or long line); windows: a
            long line's window models, shared by the burn-in and the check; spectral_check:
            run the frequency-domain check; tower_only: :func:`run_tower`.
    """

    case: Case
    static: StaticResult
    realizations: np.ndarray
    time: np.ndarray
    keep: np.ndarray
    burn_in: BurnIn
    models: list[LinearModel]
    damping: np.ndarray
    nearest: np.ndarray
    model_at: Callable | None
    second_order: list | None
    mean: np.ndarray
    still_air: np.ndarray
    gL: np.ndarray | float
    scale: float | None
    towers: slice
    vn: np.ndarray
    vl: np.ndarray | None
    a_turb: np.ndarray
    cross: NodeWind | None
    load_dirs: np.ndarray | None
    threads: int
    concurrent: bool
    chunk: int
    synoptic: SynopticModel | None
    windows: dict
    spectral_check: bool
    tower_only: bool

    @property
    def lead(self) -> int:
        """Steps of the burn-in, which precede the analysed record."""
        return int(np.argmax(self.keep))

    @property
    def n_chunks(self) -> int:
        """Chunks of :attr:`chunk` realizations."""
        return -(-self.realizations.size // self.chunk)


def run_tower(case: Case, *, realizations: list[int] | np.ndarray | None = None,
              cancel: threading.Event | None = None) -> TowerRun:
    """:func:`run_case` (no frequency-domain check, one thread) computing the dynamic
    reactions of the tower of interest only: a scan ranks positions by them, and the
    other towers' reactions, statistics and frame rotations cost ≈ 15 % of a six-span downburst
    position (measured 1.34 → 1.13 s).  Each reaction is the same arithmetic as in
    :func:`run_case` (every reaction is a sum of its own, in a fixed order), so the statistics
    are bit-identical to ``run_case(...).stats`` at that tower (tested)."""
    plan = plan_run(case, realizations=realizations, interpolate_states=False, spectral_check=False,
                    progress=None, cancel=cancel, warn=None, threads=1, tower_only=True)
    return assemble(plan, *execute(plan, progress=None, cancel=cancel))


def run_case(
    case: Case,
    *,
    realizations: list[int] | np.ndarray | None = None,
    interpolate_states: bool = False,
    spectral_check: bool = True,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    warn: Warn | None = None,
    threads: int = 1,
) -> RunResult:
    """Steps 1-3 of the method for ``case`` and the statistics of Eqs 15-17.

    Args:
        realizations: which realizations to run (default all ``analysis.realizations``);
            realization r always gets the same turbulence, whatever else is run with it.
        interpolate_states: reference scheme: interpolate the step-1 state linearly in time
            and rebuild and factorise the model at every step, instead of holding the
            nearest of the ``analysis.mean_states`` states (slow; validation only).
        spectral_check: run the frequency-domain check of a synoptic case (estimates 1 and 2,
            :func:`~linecheck.analysis.spectral_check.spectral_analysis`); its cost grows faster
            than the number of spans, the time-domain steps' only linearly (docs/performance.md).
        progress: ``progress(stage, done, total)``.
        cancel: a :class:`threading.Event`; when set the run stops with ``Cancelled``.
        warn: ``warn(message)`` receives resource warnings; above the memory limit the run
            is refused before any work (:func:`~linecheck.analysis.guard.check_budget`, CaseError).
        threads: realization chunks integrated at once in threads (the wind synthesis, steps
            2-3 and statistics of a chunk; step 1 runs once before them), and with more than
            one the frequency-domain check runs beside them on a thread of its own.  Every
            realization's arithmetic is its own, so the result is bit-identical whatever
            ``threads``; fewer threads are used where the chunks in flight would exceed the
            memory limit (:func:`~linecheck.analysis.concurrency.run_threads`), one without the
            compiled step loop (the numpy loop holds the GIL).  Batch and scan workers are
            processes and keep 1.
    """
    plan = plan_run(case, realizations=realizations, interpolate_states=interpolate_states,
                    spectral_check=spectral_check, progress=progress, cancel=cancel, warn=warn, threads=threads,
                    tower_only=False)
    return assemble(plan, *execute(plan, progress=progress, cancel=cancel))


def _guard(case: Case, n_real: int, threads: int, spectral_check: bool, warn: Warn | None,
           burn_in: float | None = None) -> int:
    """The resource guard of a run (:func:`~linecheck.analysis.guard.check_budget`) at the
    threads memory allows (:func:`~linecheck.analysis.concurrency.run_threads`); returns them."""
    threads = run_threads(case, n_real, threads, burn_in=burn_in, spectral_check=spectral_check)
    check_budget(case, "run", warn=warn, realizations=n_real, burn_in=burn_in,
                 spectral_check=spectral_check, threads=threads)
    return threads


def _linearise(case: Case, st: StaticResult) -> tuple[list[LinearModel], np.ndarray, SynopticModel | None,
                                                       BurnIn, dict]:
    """The linear models of the mean states (paper Eqs 7-9, 13), their damping, the synoptic
    model (None: downburst or long line), the burn-in and a long line's window-model memo."""
    mean = st.mean
    models = build_models(st.system, [mean.state(k) for k in range(mean.time.size)])  # one vectorised pass
    synoptic = case.wind.type == "synoptic"
    windows: dict = {}  # long lines: window models shared by the burn-in and the check
    if synoptic and case.analysis.structural_ratio > 0:
        # the structural-damping calibration, computed once for the record's models, the synoptic
        # model of the burn-in and the check (the same state's model) and a long line's windows
        windows["omega1"] = structural_omega1(models[reference_state_index(case, mean)])
    damping = damping_matrices(case, st, models, omega1=windows.get("omega1"))
    # complex modes with eigenvectors: the burn-in tells significant modes apart with them and
    # the frequency-domain check sums them (modal superposition)
    sm = synoptic_model(case, st, omega1=windows.get("omega1")) if synoptic and not windowed(case) else None
    burn = synoptic_burn_in(case, st, sm, windows) if synoptic else NO_BURN_IN
    return models, damping, sm, burn, windows


def _second_order(case: Case, st: StaticResult, models: list[LinearModel]) -> list | None:
    """The second-order tension operators of the mean states' models (None: linear tension)."""
    if case.analysis.tension != "second-order":
        return None
    from ..core.second_order import second_order_operator

    return [second_order_operator(m, st.mean.state(k)) for k, m in enumerate(models)]


def _tower_rows(j: int, models: list[LinearModel], second: list | None):
    """The models' reaction map G and the second-order forms reduced to tower ``j``'s three rows
    (each reaction is a sum of its own: the same bits)."""
    rows = slice(3 * j, 3 * j + 3)
    models = [dataclasses.replace(m, G=m.G[rows]) for m in models]
    if second is not None:
        second = [dataclasses.replace(so, A=np.ascontiguousarray(so.A[:, rows]),
                                      W=np.ascontiguousarray(so.W[:, rows])) for so in second]
    return models, second


def plan_run(case: Case, *, realizations, interpolate_states: bool, spectral_check: bool, progress: Progress | None,
             cancel: threading.Event | None, warn: Warn | None, threads: int, tower_only: bool) -> RunPlan:
    """The :class:`RunPlan` of :func:`run_case` (``tower_only`` False) or :func:`run_tower`: the
    resource guard first, before any allocation (even the realizations' indices: 8 GB for -n 1e9),
    then step 1, the linear models, the burn-in and the record (guarded again when the burn-in
    lengthens it)."""
    n_real = int(case.analysis.realizations if realizations is None else len(realizations))
    asked = max(1, int(threads))
    warned: list[str] = []
    threads = _guard(case, n_real, threads, spectral_check, lambda m: (warned.append(m), warn(m) if warn else None))
    real = np.arange(n_real) if realizations is None else np.asarray(realizations, dtype=int)
    st = static_result(case, progress=progress, cancel=cancel)
    require_tension(st)  # the models linearise about the mean states: every insulator hanging
    system, mean = st.system, st.mean
    models, damping, sm, burn, windows = _linearise(case, st)
    t = analysed = record_time(case)
    if burn.seconds > 0:  # the derived burn-in lengthens the record: check the budget again
        threads = _guard(case, int(real.size), threads, spectral_check, None if warned else warn, burn.seconds)
        t = with_burn_in(case, t, burn.seconds)
    keep = np.arange(t.size) >= t.size - analysed.size  # the analysed record (after the burn-in)
    nearest, bracket, weights = state_of_step(mean.time, t)
    if cancel is not None and cancel.is_set():
        raise Cancelled("run cancelled")
    M = mean_reactions(system, mean, t)  # the step-1 reactions interpolated to the record grid
    gL = case.g_yp * system.eq17_lengths if system.is_section else case.g_yp_L  # Eq. 17 per tower
    still_air = system.to_tower_frames(mean.still_air.reactions)
    vn, vl, a_turb = record_wind(case, st, t)  # a_turb: the turbulence's I V_m(x, t), shared by the chunks
    second = _second_order(case, st, models)
    towers, scale = slice(None), None  # the towers whose reactions steps 2-3 compute; the whole section's max |M|
    if tower_only:  # the tower of interest's reactions alone
        j = case.line.tower_of_interest - 1
        scale = max(float(np.abs(M[keep]).max()), 1e-300)
        towers = slice(j, j + 1)
        M, still_air, gL = M[:, towers], still_air[towers], gL[towers] if np.ndim(gL) else gL
        models, second = _tower_rows(j, models, second)
    cross = record_cross_wind(case, st, t, vn, vl)  # a section in cross-flow: every node's load direction
    load_dirs = None if system.straight_in_plan else system.node_normals[models[0].dofs.free_nodes]
    if cross is not None:
        load_dirs = cross.directions[models[0].dofs.free_nodes]
    model_at = interpolated_models(case, st, bracket, weights) if interpolate_states else None
    # realization threads only with the compiled step loop, which runs without the GIL (the numpy
    # step loop holds the GIL between its small calls: threads lose time)
    concurrent = asked > 1 and kernel.use("newmark")
    threads = threads if concurrent else 1
    chunk = budget.realization_chunk(case, t.size, threads)  # chunks that fit in memory (long lines)
    if threads > 1:
        chunk = min(chunk, -(-real.size // threads))
    return RunPlan(case, st, real, t, keep, burn, models, damping, nearest, model_at, second, M[keep], still_air,
                   gL, scale, towers, vn, vl, a_turb, cross, load_dirs, threads, concurrent, chunk, sm, windows,
                   spectral_check and case.wind.type == "synoptic", tower_only)


class _ChunkProgress:
    """The chunks' progress reports, one call at a time whichever thread reports: the wind
    synthesis (chunks done) and steps 2-3 (steps summed over the chunks)."""

    def __init__(self, progress: Progress | None, n_chunks: int) -> None:
        self.progress, self.n_chunks = progress, n_chunks
        self.lock = threading.Lock()
        self.winds_done, self.steps_done = 0, [0] * n_chunks

    def report(self, stage: str, done: int, total: int) -> None:
        if self.progress is not None:
            with self.lock:
                self.progress(stage, done, total)

    def wind_done(self) -> None:
        with self.lock:
            self.winds_done += 1
        self.report("wind", self.winds_done, self.n_chunks)

    def steps(self, ci: int) -> Callable[[int, int], None] | None:
        """The step callback of chunk ``ci`` (None without a progress callback)."""
        if self.progress is None:
            return None

        def cb(d: int, n: int) -> None:
            self.steps_done[ci] = d
            self.report("steps 2-3: dynamics", sum(self.steps_done), self.n_chunks * n)

        return cb


def chunk_velocity(plan: RunPlan, realizations: np.ndarray, stop: AnyEvent | threading.Event | None) -> np.ndarray:
    """The fluctuating along-wind velocity [m/s] of ``realizations`` (0-based) over the plan's
    record, (n, n_steps, n_nodes): the burn-in's :attr:`RunPlan.lead` steps lead the analysed
    record (common random numbers: the analysed turbulence does not depend on the burn-in's
    length, docs/wind.md).  ``stop`` is checked before each realization."""
    from ..core.wind.turbulence import fluctuating_velocity

    return fluctuating_velocity(plan.case, plan.static.system, plan.time, list(realizations), plan.a_turb,
                                lead=plan.lead, cancel=stop)


def chunk_response(plan: RunPlan, v: list[np.ndarray], stop: AnyEvent | threading.Event,
                   loads_done: Callable[[], None] | None = None,
                   steps: Callable[[int, int], None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Steps 2-3 of a chunk given its turbulence: the fluctuating loads (paper Eq. 5), the Newmark
    integration and the quasi-static background (Eqs 6, 14).  Returns B(t), R(t) [N] at every
    computed tower (:attr:`RunPlan.towers`) in its own frame over the kept steps, (n, n_keep,
    n_towers', 3) each.

    ``v``: a one-item list holding the chunk's velocity [m/s], (n, n_steps, n_nodes) over the
    plan's record; it is emptied, so the velocity is freed once the loads are built (when the
    caller holds no other reference).  ``loads_done()`` is called once the loads are built,
    ``steps(done, total)`` reports the integration; ``stop`` set: Cancelled."""
    case, system, t, towers = plan.case, plan.static.system, plan.time, plan.towers
    loads, direct = fluctuating_loads(case, system, plan.models[0], t, v.pop(), plan.vn, plan.vl, plan.cross)
    direct = direct.reshape(direct.shape[:2] + (-1, 3))[:, :, towers].reshape(direct.shape[:2] + (-1,))
    if loads_done is not None:
        loads_done()
    if stop.is_set():
        raise Cancelled("run cancelled")
    resp = integrate(plan.models, plan.damping, plan.nearest, loads, case.analysis.time_step, direct=direct,
                     model_at=plan.model_at, second_order=plan.second_order, second_order_start=plan.lead,
                     progress=steps, cancel=stop, load_dirs=plan.load_dirs)
    del loads, direct
    # every reaction from here on in its tower's own frame (a straight line: the global frame)
    resp = DynamicResponse(system.to_tower_frames(resp.fluctuating, towers),
                           system.to_tower_frames(resp.background, towers))
    return resp.background[:, plan.keep], resp.resonant[:, plan.keep]


def chunk_statistics(plan: RunPlan, background: np.ndarray, resonant: np.ndarray) -> Statistics:
    """The statistics of Eqs 15-17 of a chunk's B(t), R(t) [N] (:func:`chunk_response`, (n, n_keep,
    n_towers', 3)) with the plan's mean, still-air reactions, g_yp L and peak window."""
    return compute_statistics(plan.mean, background, resonant, plan.still_air, plan.gL,
                              window=peak_window_steps(plan.case), scale=plan.scale)


def run_chunk(plan: RunPlan, ci: int, stop: AnyEvent, reports: _ChunkProgress):
    """Chunk ``ci`` of a run: its realizations' turbulence (:func:`chunk_velocity`), steps 2-3
    (:func:`chunk_response`) and statistics (Eqs 15-17).  Returns the statistics and B(t), R(t)
    [N] at the tower of interest over the kept steps, (n_chunk_real, n_keep, 3) each."""
    rc = plan.realizations[ci * plan.chunk:(ci + 1) * plan.chunk]
    reports.report("wind", reports.winds_done, plan.n_chunks)
    Bk, Rk = chunk_response(plan, [chunk_velocity(plan, rc, stop)], stop, reports.wind_done, reports.steps(ci))
    jr = 0 if plan.tower_only else plan.case.line.tower_of_interest - 1  # the tower of interest among the computed
    return chunk_statistics(plan, Bk, Rk), Bk[:, :, jr, :].copy(), Rk[:, :, jr, :].copy()


def execute(plan: RunPlan, *, progress: Progress | None, cancel: threading.Event | None):
    """The chunks of ``plan`` on its threads, and with threads the frequency-domain check beside
    them on a thread of its own (it needs only step 1 and the burn-in's models).  Returns the
    chunks' results in order and the check's result (None: not run beside the chunks)."""
    stop = AnyEvent(cancel)  # the user's cancel, or a failed sibling chunk
    reports = _ChunkProgress(progress, plan.n_chunks)
    check_pool = check = None
    switch = short_switch_interval() if plan.concurrent else contextlib.nullcontext()  # GIL hand-offs
    with switch:
        try:
            if plan.spectral_check and plan.concurrent:
                from concurrent.futures import ThreadPoolExecutor

                check_pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="linecheck-check")
                check = check_pool.submit(spectral_analysis, plan.case, static=plan.static, synoptic=plan.synoptic,
                                          windows=plan.windows)
            parts = map_chunks(lambda ci: run_chunk(plan, ci, stop, reports), plan.n_chunks, plan.threads, stop)
            spectral = check.result() if check is not None else None
        finally:
            if check_pool is not None:
                check_pool.shutdown(wait=False, cancel_futures=True)  # a failed run does not wait for it
    return parts, spectral


def assemble(plan: RunPlan, parts: list, spectral: SpectralResult | None) -> RunResult | TowerRun:
    """One result from the chunks' ``parts`` in order; the frequency-domain check run here when it
    did not run beside the chunks (``spectral`` None)."""
    parts_stats, parts_B, parts_R = (list(p) for p in zip(*parts))
    one = len(parts) == 1
    stats = parts_stats[0] if one else Statistics.concatenate(parts_stats)
    if plan.tower_only:
        return TowerRun(static=plan.static, stats=stats)
    if spectral is None and plan.spectral_check:
        spectral = spectral_analysis(plan.case, static=plan.static, synoptic=plan.synoptic, windows=plan.windows)
    st = plan.static
    return RunResult(
        case=plan.case, system=st.system, static=st, realizations=plan.realizations, time=plan.time[plan.keep],
        mean=plan.mean, background=parts_B[0] if one else np.concatenate(parts_B),
        resonant=parts_R[0] if one else np.concatenate(parts_R), stats=stats, spectral=spectral, burn_in=plan.burn_in,
    )
