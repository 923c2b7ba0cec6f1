"""Every wire on the tower in one correlated wind: steps 2-3 of each wire, the reactions at every
attachment and the tower's totals from the summed histories (:func:`run_wires`).

Each wire of a case with ``[[wires]]`` is run as its single-wire case
(:func:`~linecheck.core.case_wires.wire_case`): one :class:`~.run.RunPlan` per wire (step 1, the
linear models, damping and burn-in of that wire), and per chunk of realizations the same steps 2-3
as a single-wire run (:func:`~.run.chunk_response`, :func:`~.run.chunk_statistics`).  What the wires
share is the wind:

* **One turbulence field.**  Per chunk the field of every wire is synthesized once
  (:func:`~linecheck.core.wind.wires.fluctuating_velocity_wires`, docs/wind.md "Many wires: one
  correlated field"), with the Davenport coherence along the line and exponential coherences
  across it and in height (C_y = ``wind.coherence_decay_y``, C_z = ``wind.coherence_decay_z``,
  the "sum" combination).  The wires' offsets (y, z) [m] are their attachments on the tower of
  interest: y the attachment's y in the tower frame, z the wire's still-air clamp height (z - v
  at a suspension attachment, z at a strain one: :func:`~linecheck.core.case_wires.clamp_height`),
  one offset per wire for the whole line (the Kronecker model's assumption).  The field's
  stations are the first wire's nodes; the other wires' nodes lie within a few cm of them (the
  nodes divide each span's unstretched length, so their stations move with the sag;
  :attr:`WiresRun.station_spread`).
* **Each wire its own modulation and burn-in.**  The unit field is synthesized with the largest
  burn-in lead of the wires; wire w takes the tail that its own burn-in needs and is modulated by
  its own a = I V_m(x, t) (``RunPlan.a_turb``).  The burn-in is the analysed record's periodic
  continuation, so the analysed record's turbulence is the same whatever the lead (common random
  numbers, docs/wind.md): wire 0 is the single-wire run's turbulence bit for bit, and so is any
  wire at wire 0's point (the field copies it), which makes its attachment's statistics those of
  the single-wire run bit for bit.

Frames and signs.  Reactions are the forces of the wire on the tower, in each tower's own frame
(docs/method.md "Line sections": x along the tower's mean heading, y = x turned +90 deg in plan,
z DOWN), each acting at its attachment point (0, y, z) (z UP above the tower's ground).  The
tower's totals are their resultant F = (F_x, F_y, F_z) and their moment M = (M_x, M_y, M_z) about
the tower's base, M = sum r x F with z up, as :mod:`linecheck.core.tower_totals` defines them
(:data:`~linecheck.core.tower_totals.TOTALS`; the static totals' convention, docs/wires.md).

Every history is summed before its statistics: M(t) + B(t) + R(t) of the total is the sum of the
attachments' (the same for each moment), so the wires' correlation is in the totals' peaks, r.m.s.
and gust factors (paper Eqs 15-17 as :func:`~linecheck.core.results.compute_statistics`).  A
total's peak is at most the sum of its attachments' peaks (the triangle inequality, per
realization); :meth:`WiresRun.peak_sum` gives that sum and :meth:`WiresRun.peak_largest` the
largest attachment's, so the designer sees what the correlation saves.  Eq. 17's normalising
force of a total force is the wires' sum of g*_yp L_x; the moments have none (NaN).

Load trees (:class:`LoadTrees`): for each tower and each governing total (:data:`GOVERNING`) --
max |F_y| (transverse), max |F_x| (longitudinal), max |M_x| (overturning), max |M_z| (torsion),
min F_z (the least downward force: uplift) -- the instant it is reached in each sample (a realization, or
a peak window), the total there and every attachment's R_x, R_y, R_z at that instant, all with the
still-air reactions (the loads a tower design applies).

Memory.  A chunk holds the field of every wire over the record, one wire's steps 2-3 at a time,
the totals' B and R and (for the load trees) each wire's B + R at every tower: realizations per
chunk as :func:`~linecheck.core.budget.realization_chunk` counts them with these added
(:func:`wires_chunk`).  Nothing here prints.
"""

from __future__ import annotations

import contextlib
import threading
from dataclasses import dataclass

import numpy as np

from ..core import budget, kernel
from ..core.case import Case, clamp_height, wire_case
from ..core.extremes import gumbel_fit, summarise
from ..core.results import ResultSummary, Statistics, StatisticSummary, compute_statistics, summarise_statistics
from ..core.tower_totals import LOAD_CASES, TOTALS, reaction_moments
from ..core.wind.wires import CrossCoherence, fluctuating_velocity_wires
from .burnin import BurnIn
from .concurrency import AnyEvent, map_chunks, short_switch_interval
from .guard import Warn, warn_once
from .record import peak_window_steps
from .run import RunPlan, chunk_response, chunk_statistics, plan_run
from .step1 import Progress, StaticResult
from .wires_static import wire_progress

#: The governing totals of the load trees: load case -> (index of its total in
#: :data:`~linecheck.core.tower_totals.TOTALS`, "abs" or "min"), from
#: :data:`~linecheck.core.tower_totals.LOAD_CASES`.
GOVERNING = {case: (TOTALS.index(total), sense) for case, (total, sense) in LOAD_CASES.items()}
_ONE = np.ones((1, 1))  # the unit modulation: each wire's own is applied to its tail of the field


@dataclass(frozen=True)
class LoadTrees:
    """Coincident attachment loads at the instants the governing totals peak (module docstring).

    Attributes:
        cases: the governing totals, the keys of :data:`GOVERNING`, (n_cases,).
        value: the governing total at its instant, still air included [N or N m],
            (n_samples, n_towers, n_cases).
        time: [s] that instant on the analysed record, (n_samples, n_towers, n_cases).
        loads: every attachment's R_x, R_y, R_z at that instant [N], still air included, tower
            frame (z down), (n_samples, n_towers, n_cases, n_wires, 3).
    """

    cases: tuple[str, ...]
    value: np.ndarray
    time: np.ndarray
    loads: np.ndarray

    def mean(self) -> np.ndarray:
        """[N] the attachments' loads averaged over the samples, (n_towers, n_cases, n_wires, 3)."""
        return self.loads.mean(axis=0)

    def std(self) -> np.ndarray:
        """[N] their sample standard deviation (ddof = 1; 0 for one sample), the mean's shape."""
        if self.loads.shape[0] < 2:
            return np.zeros(self.loads.shape[1:])
        return self.loads.std(axis=0, ddof=1)

    @staticmethod
    def concatenate(parts: list[LoadTrees]) -> LoadTrees:
        """Join the trees of disjoint realization sets (chunks)."""
        return LoadTrees(parts[0].cases, *(np.concatenate([getattr(p, k) for p in parts])
                                           for k in ("value", "time", "loads")))


@dataclass(frozen=True)
class WiresRun:
    """Steps 1-3 of every wire in one correlated wind (:func:`run_wires`).

    Attributes:
        case: the case (with ``[[wires]]``); wires: the wires' names in the case's order
            (attachment j of every tower is wire j's), (n_w,).
        realizations: indices run, (n_real,); time: [s] the analysed record, (n_keep,).
        static, burn_in: each wire's step-1 result and burn-in, (n_w,).
        offsets: [m] the wires' (y, z) in the coherence of the field, (n_w, 2).
        arms: [m] each attachment's (y_a, z_a) in its tower's frame (z up), (n_towers, n_w, 2).
        attachments: each wire's reaction statistics at every tower (its attachment): R_x, R_y,
            R_z as a single-wire run's :class:`~linecheck.core.results.Statistics`,
            (n_samples, n_towers, 3) each, (n_w,).
        attachment_moments: each attachment's own share of the tower's moments (M_x, M_y, M_z
            of its reaction, :func:`tower_moments`) [N m], the same statistics, (n_w,).
        still_air: [N] each wire's still-air reactions, tower frame, (n_w, n_towers, 3).
        forces, moments: the totals' statistics from the summed histories: (F_x, F_y, F_z) [N]
            and (M_x, M_y, M_z) [N m], (n_samples, n_towers, 3) each.
        totals_still_air: the totals' still-air values [N, N m], (n_towers, 6) in :data:`TOTALS`
            order.
        load_trees: the coincident loads at the governing totals' instants (:class:`LoadTrees`).
        station_spread: [m] the largest distance of a wire's node station from the first
            wire's (the field's stations).
    """

    case: Case
    wires: tuple[str, ...]
    realizations: np.ndarray
    time: np.ndarray
    static: tuple[StaticResult, ...]
    burn_in: tuple[BurnIn, ...]
    offsets: np.ndarray
    arms: np.ndarray
    attachments: tuple[Statistics, ...]
    attachment_moments: tuple[Statistics, ...]
    still_air: np.ndarray
    forces: Statistics
    moments: Statistics
    totals_still_air: np.ndarray
    load_trees: LoadTrees
    station_spread: float

    def totals(self, name: str) -> np.ndarray:
        """Statistic ``name`` of the six totals, (n_samples, n_towers, 6) in :data:`TOTALS` order."""
        return np.concatenate([self.forces.values(name), self.moments.values(name)], axis=-1)

    def attachment_totals(self, name: str) -> np.ndarray:
        """Statistic ``name`` of every attachment's share of the six totals (its R_x, R_y, R_z and
        its moments), (n_w, n_samples, n_towers, 6)."""
        return np.stack([np.concatenate([f.values(name), m.values(name)], axis=-1)
                         for f, m in zip(self.attachments, self.attachment_moments)])

    def peak_sum(self, name: str = "peak_dynamic") -> np.ndarray:
        """The sum over attachments of their peaks ``name`` (one of the peak statistics), per
        sample: (n_samples, n_towers, 6); the totals' own peak (:meth:`totals`) is at most this."""
        return self.attachment_totals(name).sum(axis=0)

    def peak_largest(self, name: str = "peak_dynamic") -> np.ndarray:
        """The largest attachment's peak ``name`` per sample, (n_samples, n_towers, 6)."""
        return self.attachment_totals(name).max(axis=0)

    def bounds_summary(self, name: str = "peak_dynamic") -> tuple[StatisticSummary, StatisticSummary]:
        """:meth:`peak_sum` and :meth:`peak_largest` summarised over the samples like a peak
        statistic (mean, std, fractiles and the Gumbel fit with its design value at
        ``analysis.design_fractile``), arrays (n_towers, 6) in :data:`~linecheck.core.tower_totals.TOTALS` order."""
        p = self.case.analysis.design_fractile
        return tuple(StatisticSummary(summarise(v), gumbel_fit(v, p))  # type: ignore[return-value]
                     for v in (self.peak_sum(name), self.peak_largest(name)))

    def attachment_summary(self, wire: int) -> ResultSummary:
        """Wire ``wire``'s (0-based) reactions summarised as a single-wire run's."""
        return summarise_statistics(self.attachments[wire], self.still_air[wire], self.case.analysis.design_fractile)

    def totals_summary(self) -> tuple[ResultSummary, ResultSummary]:
        """The total forces' and moments' statistics summarised (moments, fractiles, Gumbel fits
        and design values of the peaks, intervals, the Cont_R flag)."""
        p = self.case.analysis.design_fractile
        return (summarise_statistics(self.forces, self.totals_still_air[:, :3], p),
                summarise_statistics(self.moments, self.totals_still_air[:, 3:], p))


@dataclass(frozen=True)
class _Wires:
    """What the chunks of :func:`run_wires` share: the wires' plans, the field's lead, offsets and
    coherence, the attachments' arms, the totals' means, still-air values and g_yp L."""

    plans: tuple[RunPlan, ...]
    time: np.ndarray  # [s] the record of the wire with the longest burn-in
    lead: int  # its burn-in steps
    offsets: np.ndarray
    cross: CrossCoherence
    arms: np.ndarray  # (n_towers, n_w, 2)
    mean_moments: tuple[np.ndarray, ...]  # each wire's M(t) moments (n_keep, n_towers, 3)
    still_moments: tuple[np.ndarray, ...]  # each wire's still-air moments (n_towers, 3)
    mean_totals: np.ndarray  # (n_keep, n_towers, 6)
    still_totals: np.ndarray  # (n_towers, 6)
    gL: np.ndarray | float  # [N] the forces' sum of g_yp L
    window: int | None
    chunk: int


def run_wires(case: Case, *, realizations: list[int] | np.ndarray | None = None, progress: Progress | None = None,
              cancel: threading.Event | None = None, threads: int = 1, warn: Warn | None = None) -> WiresRun:
    """Steps 1-3 of every wire of ``case`` (a case with ``[[wires]]``) in one correlated wind, the
    statistics of each attachment's reactions and of the tower's totals from the summed histories,
    and the load trees (module docstring).

    Args:
        realizations: which realizations (0-based; default all ``analysis.realizations``).
        progress: ``progress(stage, done, total)`` (step 1 of each wire, its stage naming the
            wire, then "wind" per chunk and "steps 2-3: dynamics" over every wire's steps).
        cancel: when set the run stops with ``Cancelled``.
        threads: chunks of realizations run at once on threads (with the compiled step loop, which
            runs without the GIL; else one), each chunk then at most 1/threads of the chunks'
            memory.  Every realization's arithmetic is its own and the wires are summed in their
            order, so the result is bit-identical whatever ``threads`` and the chunking.
        warn: ``warn(message)`` receives the resource warnings of each wire's run (its
            single-wire case's :func:`~linecheck.analysis.guard.check_budget`), each distinct
            one once; above the memory limit a wire's run is refused before its work
            (:class:`~linecheck.core.errors.CaseError`).  The case's own warnings
            (:func:`~linecheck.analysis.guard.warn_case`) are the caller's.
    Raises ValueError for a case without wires or wires whose meshes differ in size or frames.
    """
    if not case.has_wires:
        raise ValueError(f"case {case.name!r} has no [[wires]]: run it with run_case")
    names = tuple(w.name for w in case.wires)
    once = warn_once(warn)
    plans = tuple(plan_run(wire_case(case, w), realizations=realizations, interpolate_states=False,
                           spectral_check=False, progress=wire_progress(progress, w), cancel=cancel, warn=once,
                           threads=1, tower_only=False) for w in names)
    threads = max(1, int(threads)) if threads > 1 and kernel.use("newmark") else 1
    ctx = _context(case, plans, threads)
    stop = AnyEvent(cancel)  # the user's cancel, or a failed sibling chunk
    real = plans[0].realizations
    n_chunks = -(-real.size // ctx.chunk)
    reports = _Reports(progress, n_chunks, [p.time.size for p in plans])
    switch = short_switch_interval() if threads > 1 else contextlib.nullcontext()  # GIL hand-offs
    with switch:
        parts = map_chunks(lambda ci: _run_chunk(ctx, real[ci * ctx.chunk:(ci + 1) * ctx.chunk], stop, reports, ci),
                           n_chunks, threads, stop)
    return _assemble(case, names, ctx, parts)


class _Reports:
    """The progress of the chunks, one call at a time whichever thread reports: the field
    ("wind", chunks done) and steps 2-3 (steps summed over chunks and wires)."""

    def __init__(self, progress: Progress | None, n_chunks: int, steps: list[int]) -> None:
        self.progress, self.n_chunks = progress, n_chunks
        self.total = n_chunks * sum(steps)
        self.lock = threading.Lock()
        self.winds, self.done = 0, [[0] * len(steps) for _ in range(n_chunks)]

    def wind_done(self) -> None:
        if self.progress is not None:
            with self.lock:
                self.winds += 1
                self.progress("wind", self.winds, self.n_chunks)

    def steps(self, ci: int, w: int):
        """The step callback of wire ``w`` in chunk ``ci`` (None without a progress callback)."""
        if self.progress is None:
            return None

        def cb(d: int, n: int) -> None:
            with self.lock:
                self.done[ci][w] = d
                self.progress("steps 2-3: dynamics", sum(map(sum, self.done)), self.total)

        return cb


def _context(case: Case, plans: tuple[RunPlan, ...], threads: int) -> _Wires:
    """The chunks' shared data (:class:`_Wires`), after checking that the wires' meshes agree."""
    systems = [p.static.system for p in plans]
    s0 = systems[0]
    for name, s, p in zip((w.name for w in case.wires), systems, plans):
        if s.n_nodes != s0.n_nodes or s.n_towers != s0.n_towers or p.keep.sum() != plans[0].keep.sum():
            raise ValueError(f"wire {name!r}: {s.n_nodes} nodes, {s.n_towers} towers, {int(p.keep.sum())} steps; "
                             f"the first wire has {s0.n_nodes}, {s0.n_towers}, {int(plans[0].keep.sum())}")
        if not np.allclose(s.tower_headings, s0.tower_headings, rtol=0.0, atol=1e-9):
            raise ValueError(f"wire {name!r}: its tower frames differ from the first wire's")
    j = case.line.tower_of_interest - 1
    ins = case.line.insulator_length
    here = case.tower_type(case.line.towers[j].type)
    offsets = np.array([[here.attachment(w.name).y, clamp_height(here.attachment(w.name), ins)]
                        for w in case.wires])
    arms = np.array([[(t.attachment(w.name).y, t.attachment(w.name).z) for w in case.wires]
                     for t in (case.tower_type(tw.type) for tw in case.line.towers)])
    mean_m = tuple(reaction_moments(p.mean, arms[:, w, 0], arms[:, w, 1]) for w, p in enumerate(plans))
    still_m = tuple(reaction_moments(p.still_air, arms[:, w, 0], arms[:, w, 1]) for w, p in enumerate(plans))
    mean_t = np.concatenate([sum(p.mean for p in plans), sum(mean_m)], axis=-1)
    still_t = np.concatenate([sum(p.still_air for p in plans), sum(still_m)], axis=-1)
    longest = int(np.argmax([p.lead for p in plans]))
    cross = CrossCoherence(case.wind.coherence_decay_y, case.wind.coherence_decay_z)
    return _Wires(plans, plans[longest].time, plans[longest].lead, offsets, cross, arms, mean_m, still_m, mean_t,
                  still_t, sum(p.gL for p in plans), peak_window_steps(case), wires_chunk(plans, threads))


def wires_chunk(plans: tuple[RunPlan, ...] | list[RunPlan], threads: int = 1) -> int:
    """Realizations per chunk of :func:`run_wires` [-]: whole-record arrays per step and
    realization of about n_w n_nodes (the field) + 3 n_nodes + 24 n_towers (one wire's steps
    2-3, as :func:`~linecheck.core.budget.realization_chunk`) + 12 n_towers (the totals' B and R)
    + 3 n_w n_towers (each wire's B + R for the load trees) doubles, within
    :data:`~linecheck.core.budget.RUN_CHUNK_BYTES` shared by the ``threads`` chunks in flight;
    at most the realizations run, and with threads at most their share."""
    s = plans[0].static.system
    n_w, n_steps, n_real = len(plans), max(p.time.size for p in plans), int(plans[0].realizations.size)
    per = n_steps * budget.F8 * (n_w * s.n_nodes + 3 * s.n_nodes + 36 * s.n_towers + 3 * n_w * s.n_towers)
    chunk = max(1, min(n_real, int(budget.RUN_CHUNK_BYTES / threads // per)))
    return min(chunk, -(-n_real // threads))


def _run_chunk(ctx: _Wires, rc: np.ndarray, stop: AnyEvent, reports: _Reports, ci: int) -> tuple:
    """Steps 2-3 of realizations ``rc`` (chunk ``ci``) for every wire in one field.  Returns each
    wire's statistics and moment statistics, the totals' force and moment statistics and the load
    trees."""
    p0 = ctx.plans[0]
    # (n_w, n_c, lead + n_keep, n_nodes): the unit field with the longest burn-in (a = 1)
    v = fluctuating_velocity_wires(p0.case, p0.static.system, ctx.offsets, ctx.time, list(rc), a=_ONE,
                                   lead=ctx.lead, cancel=stop, cross=ctx.cross)
    reports.wind_done()
    n_keep, n_towers = ctx.mean_totals.shape[:2]
    fb, fr, mb, mr = (np.zeros((len(rc), n_keep, n_towers, 3)) for _ in range(4))
    stats, mstats, hist = [], [], []
    for w, plan in enumerate(ctx.plans):
        vw = v[w, :, ctx.lead - plan.lead:]  # this wire's burn-in and the analysed record
        vw *= plan.a_turb  # a = I V_m(x, t) of this wire (as turbulence.fluctuating_velocity)
        B, R = chunk_response(plan, [np.ascontiguousarray(vw)], stop, steps=reports.steps(ci, w))
        del vw
        stats.append(chunk_statistics(plan, B, R))
        y, z = ctx.arms[:, w, 0], ctx.arms[:, w, 1]
        mB, mR = reaction_moments(B, y, z), reaction_moments(R, y, z)
        mstats.append(compute_statistics(ctx.mean_moments[w], mB, mR, ctx.still_moments[w], 0.0, window=ctx.window))
        fb += B
        fr += R
        mb += mB
        mr += mR
        B += R
        hist.append(B)
        del R, mB, mR
    del v
    forces = compute_statistics(ctx.mean_totals[..., :3], fb, fr, ctx.still_totals[:, :3], ctx.gL, window=ctx.window)
    moments = compute_statistics(ctx.mean_totals[..., 3:], mb, mr, ctx.still_totals[:, 3:], 0.0, window=ctx.window)
    fb += fr
    mb += mr
    del fr, mr
    trees = _load_trees(ctx, fb, mb, hist)
    return stats, mstats, forces, moments, trees


def _windows(n_t: int, window: int | None) -> tuple[int, int]:
    """(windows per realization, samples per window) as the statistics cut them
    (:func:`~linecheck.core.results.compute_statistics`): n_w = (n_t - 1) // window windows of
    ``window`` samples when 0 < window < n_t - 1, else the whole record as one."""
    if window is not None and 0 < window < n_t - 1:
        return (n_t - 1) // window, window
    return 1, n_t


def _load_trees(ctx: _Wires, forces: np.ndarray, moments: np.ndarray, hist: list[np.ndarray]) -> LoadTrees:
    """The load trees of a chunk from the totals' B + R histories [N, N m] (n_c, n_keep, n_towers,
    3) each and each wire's B + R [N] (same shape): in every sample (realization x peak window)
    the instant each governing total (still air and mean added) is reached, its value and every
    attachment's reaction there (still air and mean added)."""
    n_c, n_keep, n_towers = forces.shape[:3]
    n_win, span = _windows(n_keep, ctx.window)
    n_s, names = n_c * n_win, tuple(GOVERNING)
    value, at = np.empty((n_s, n_towers, len(names))), np.empty((n_s, n_towers, len(names)), dtype=np.int64)
    for c, (k, sense) in enumerate(GOVERNING.values()):
        part = forces if k < 3 else moments
        x = part[..., k % 3] + ctx.mean_totals[None, :, :, k] + ctx.still_totals[None, None, :, k]
        x = x[:, :n_win * span].reshape(n_s, span, n_towers)  # realization-major samples
        i = np.argmin(x, axis=1) if sense == "min" else np.argmax(np.abs(x), axis=1)
        value[:, :, c] = np.take_along_axis(x, i[:, None, :], axis=1)[:, 0]
        at[:, :, c] = i + (np.arange(n_s) % n_win * span)[:, None]  # the step on the analysed record
    r = np.repeat(np.arange(n_c), n_win)[:, None, None]  # each sample's realization
    j = np.arange(n_towers)[None, :, None]
    loads = np.empty((n_s, n_towers, len(names), len(hist), 3))
    for w, (h, plan) in enumerate(zip(hist, ctx.plans)):
        loads[:, :, :, w] = h[r, at, j] + plan.mean[at, j] + plan.still_air[None, :, None]
    return LoadTrees(names, value, ctx.plans[0].time[ctx.plans[0].keep][at], loads)


def _assemble(case: Case, names: tuple[str, ...], ctx: _Wires, parts: list) -> WiresRun:
    """One :class:`WiresRun` from the chunks' results in order."""
    stats, mstats, forces, moments, trees = zip(*parts)

    def join(xs):
        return xs[0] if len(xs) == 1 else Statistics.concatenate(list(xs))

    plans = ctx.plans
    s0 = plans[0].static.system
    spread = max(float(np.abs(p.static.system.node_station - s0.node_station).max()) for p in plans)
    return WiresRun(
        case=case, wires=names, realizations=plans[0].realizations, time=plans[0].time[plans[0].keep],
        static=tuple(p.static for p in plans), burn_in=tuple(p.burn_in for p in plans), offsets=ctx.offsets,
        arms=ctx.arms, attachments=tuple(join([s[w] for s in stats]) for w in range(len(plans))),
        attachment_moments=tuple(join([s[w] for s in mstats]) for w in range(len(plans))),
        still_air=np.stack([p.still_air for p in plans]), forces=join(forces), moments=join(moments),
        totals_still_air=ctx.still_totals,
        load_trees=trees[0] if len(trees) == 1 else LoadTrees.concatenate(list(trees)),
        station_spread=spread,
    )
