"""Resource guard: estimated peak memory and run time of a job, checked before it starts.

Nothing here allocates the arrays it sizes: every count is arithmetic on the case, so an
absurd case (``time_step = 1e-9``, ``realizations = 1e9``, 200 spans x 200 elements) is
refused in microseconds with a :class:`CaseError` (exit 2) that quotes the estimate.

Limits: memory above ``max_memory`` is refused; above half of it, or a run
time above :data:`WARN_SECONDS`, a warning is returned to the caller (the core never
prints).  ``max_memory`` comes from the environment variable ``LINECHECK_MAX_MEMORY``
(e.g. ``8GB``, ``512MB``, ``0.5TB`` or a number of bytes; the CLI option
``--max-memory`` sets it, so local batch workers inherit it), default
:data:`DEFAULT_FRACTION` of the physical memory.

The coefficients are ROUGH: array counts read off the code (service.run_case, the wind
synthesis, the banded Newmark solver, the dense condensation of model.condensed) and
per-item costs calibrated from a few runs of the paper cases on a 2-core x86-64 machine
(docs/performance.md, "resource guard").  They aim at the right order of magnitude (a
factor of about 2 either way), which is what a guard needs; they do not predict timings.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass

from .case import Case
from .errors import CaseError

DEFAULT_FRACTION = 0.75  # default memory limit: this fraction of the physical memory
WARN_FRACTION = 0.5  # warn above this fraction of the memory limit
WARN_SECONDS = 600.0  # [s] warn when a job is estimated to take longer than this
ENV_MAX_MEMORY = "LINECHECK_MAX_MEMORY"

F8 = 8.0  # [bytes] float64
# --- memory, counted arrays (calibrated roughly with bench/bench_budget.py)
REC_ARRAYS = 4.0  # per realization x step x node: velocity v, loads, f_i temporary, response slices
STEP_ARRAYS = 8.0  # per step x node: mean wind components, speed, cos, per_v, synthesis FFT buffers
STATE_BYTES_PER_DOF = 20 * F8  # per mean state x DOF: band K, M, C, factors, static state arrays
STATE_OVERHEAD = 3e3  # [bytes] per mean state: Python objects of a model
DENSE_ARRAYS = 7.0  # per DOF^2: K, M, C dense, the map S, three condensed products (model.condensed)
BASE_BYTES = 100e6  # [bytes] interpreter, numpy, scipy
# --- time [s], calibrated roughly with bench/bench_budget.py (2-core x86-64, shared)
T_FIXED = 1.0  # set-up
T_STEP = 2e-5  # per step (Python-level loop of the Newmark integrator, all realizations at once)
T_NEWMARK = 2.5e-7  # per realization x step x DOF (banded solves and updates)
T_SYNTH = 3e-7  # per realization x step x node (phases, KMS recursion, inverse FFT)
T_STATE0 = 1.5e-3  # per mean state (model, damping, factorisation)
T_STATE = 5e-5  # per mean state x DOF (Newton iterations of step 1)
T_DENSE = 1.5e-9  # per DOF^3 (dense eigensolvers of the condensed model)
T_SPECTRAL = 2e-9  # per frequency-grid point x node^2 (random-vibration quadrature)
SPECTRAL_POINTS = 2000  # frequency-grid points of the spectral check (order of magnitude)
# --- time of one downburst scan position [s] (a warm worker: step 1 without the job's set-up, and the
# tower of interest's steps 2-3; six-span and single-span paper lines, 2-core x86-64, with and
# without the compiled kernel: 1.9e-6 and 0.6e-6 per state x DOF, 1.6e-7 and 2.3e-7 per r x step x node)
T_SCAN_STATE = 2e-6  # per mean state x DOF of a position's step 1
T_SCAN_REALIZATION = 2e-7  # per realization x step x node of a position's steps 2-3 (--dynamic)
WINDOW_SPANS = 20  # lines longer than this: burn-in and check on windows of about this many spans


@dataclass(frozen=True)
class Estimate:
    """Estimated peak memory [bytes] and time [s] of one job, with the sizes behind them."""

    job: str
    memory: float
    seconds: float
    n_steps: int
    n_nodes: int
    n_dof: int
    realizations: int
    mean_states: int
    dominant: str  # what drives the memory
    points: int = 0  # scan: grid positions (the memory is one position's, held by each worker)
    workers: int = 1  # scan: tasks at once (the time is the wall time on that many)

    def text(self) -> str:
        sizes = [f"{self.n_dof} DOF", f"{self.mean_states} mean state(s)"]
        if self.n_steps:
            sizes[1:1] = [f"{self.realizations} realization(s)"] if self.job == "run" else []
            sizes.insert(0, f"{self.n_steps} steps")
        if self.points:
            per = f" x {self.realizations} realization(s)" if self.realizations else ""
            sizes.insert(0, f"{self.points} positions{per} on {self.workers} worker(s)")
        return (f"{self.job} needs about {fmt_bytes(self.memory)} of memory and {fmt_seconds(self.seconds)} "
                f"({self.dominant}; {', '.join(sizes)})")


def fmt_bytes(n: float) -> str:
    for unit, size in (("PB", 1e15), ("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n / 1e3:.3g} kB"


def fmt_seconds(s: float) -> str:
    if s >= 86400 * 365:
        return f"{s / (86400 * 365):.3g} years"
    if s >= 86400:
        return f"{s / 86400:.3g} days"
    if s >= 3600:
        return f"{s / 3600:.3g} h"
    if s >= 60:
        return f"{s / 60:.3g} min"
    return f"{s:.2g} s"


_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([kKmMgGtT]?)(i?)[bB]?\s*$")


def parse_size(text: str, *, key: str = "--max-memory") -> float:
    """``"8GB"``, ``"512 MB"``, ``"1.5TiB"``, ``"1e9"`` -> bytes (CaseError naming ``key`` otherwise)."""
    m = _SIZE.match(str(text))
    if not m:
        raise CaseError(f"value {text!r} is not allowed: expected a size such as 8GB, 512MB or a number of bytes",
                        key=key)
    base = 1024.0 if m.group(3) else 1000.0
    value = float(m.group(1)) * base ** " KMGT".index(m.group(2).upper() or " ")
    if not (value > 0 and math.isfinite(value)):
        raise CaseError(f"value {text!r} is not allowed: expected a positive size", key=key)
    return value


def physical_memory() -> float | None:
    """Physical memory [bytes], or None where the platform does not say."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def memory_limit() -> tuple[float, str]:
    """The memory limit [bytes] and where it comes from."""
    env = os.environ.get(ENV_MAX_MEMORY)
    if env:
        return parse_size(env, key=ENV_MAX_MEMORY), f"{ENV_MAX_MEMORY} / --max-memory"
    phys = physical_memory()
    if phys is None:
        return math.inf, "no limit (physical memory unknown)"
    return DEFAULT_FRACTION * phys, f"default {DEFAULT_FRACTION:.0%} of the physical memory"


# --------------------------------------------------------------------------- sizes
def _sizes(case: Case) -> tuple[int, int, int]:
    """(n_nodes, n_dof, n_towers) of the FE model, arithmetically (no arrays built)."""
    line = case.line
    n_nodes = line.spans * line.elements_per_span + 1
    n_strain = sum(1 for s in line.supports if s == "strain")  # pinned: their 3 DOF are not solved for
    return n_nodes, 3 * (n_nodes - n_strain), line.spans + 1


def record_steps(case: Case, burn_in: float = 0.0) -> int:
    """Steps of the analysed record plus a burn-in [s] (arithmetic twin of wind.point.record_times)."""
    from .wind.mean import event_window

    t0, t1 = event_window(case)
    dt = case.analysis.time_step
    return int(math.floor((t1 - t0 + burn_in) / dt + 1e-9)) + 1


RUN_CHUNK_BYTES = 1.0e9  # [bytes] realizations of one run are integrated in chunks of about this size


def realization_chunk(case: Case, n_steps: int, threads: int = 1) -> int:
    """Realizations integrated together [-] (``service.run_case``): all of them unless their
    whole-record arrays (turbulence, loads and work arrays per node, reaction histories per
    tower: about 3 n_nodes + 24 n_towers doubles per step and realization) exceed
    :data:`RUN_CHUNK_BYTES` shared by the ``threads`` chunks in flight at once."""
    n_nodes, _, n_towers = _sizes(case)
    per = float(n_steps) * F8 * (3 * n_nodes + 24 * n_towers)
    return max(1, int(RUN_CHUNK_BYTES / max(1, int(threads)) // per))


def _dense(n_dof: int) -> tuple[float, float]:
    return DENSE_ARRAYS * n_dof**2 * F8, T_DENSE * float(n_dof) ** 3


def estimate(case: Case, job: str = "run", *, realizations: int | None = None, burn_in: float | None = None,
             spectral_check: bool = True, threads: int = 1) -> Estimate:
    """Estimate peak memory and time of ``job`` for ``case``.

    job: ``run`` (steps 1-3; ``realizations`` held at once, default all), ``static``
    (step 1), ``modes``, ``spectral`` (frequency-domain check), ``wind`` (point p, one
    realization).  burn_in [s]: the synoptic burn-in once known (default
    ``analysis.burn_in`` or 0).  threads: realization chunks of a run integrated at once
    (``service.run_case``); the time is the single-thread work (the wall time is shorter).
    """
    a = case.analysis
    n_nodes, n_dof, n_towers = _sizes(case)
    n_real = a.realizations if realizations is None else int(realizations)
    synoptic = case.wind.type == "synoptic"
    n_k = 1 if synoptic else a.mean_states
    b = burn_in if burn_in is not None else (a.burn_in or 0.0)
    n_steps = record_steps(case, b) if job in ("run", "wind", "spectral") else 0
    parts: dict[str, float] = {"interpreter": BASE_BYTES}
    secs = T_FIXED
    # step 1 (every job but wind): mean states
    if job != "wind":
        parts["mean states"] = n_k * (STATE_BYTES_PER_DOF * n_dof + STATE_OVERHEAD)
        secs += n_k * (T_STATE0 + T_STATE * n_dof)
    # dense condensation: synoptic runs (burn-in, spectral), modes, structural-damping calibration
    # (above 600 DOFs the calibration is sparse); a long synoptic line's burn-in and check run on
    # windows of at most about WINDOW_SPANS spans (long lines, service.CHECK_WINDOW_*)
    windowed = synoptic and case.line.spans > WINDOW_SPANS and job != "modes"
    n_dense = min(n_dof, 3 * (WINDOW_SPANS * case.line.elements_per_span - 1)) if windowed else n_dof
    dense_needed = (job == "spectral" or (job == "modes" and n_dof <= 600)  # above: sparse Lanczos
                    or (job == "run" and (synoptic or (a.structural_ratio > 0 and n_dof <= 600))))
    if dense_needed:
        mem, t = _dense(n_dense)
        parts["dense matrices"] = mem
        secs += t * (3.0 if windowed else 1.0)  # two or three windows
    if job == "run":
        k = max(1, min(int(threads), n_real))
        held = min(n_real, k * realization_chunk(case, n_steps, k))  # realizations in memory at once
        # the chunk's whole-record arrays, plus what the result keeps of every realization: B and R
        # at the tower of interest (6 doubles per step) and 15 statistics per tower and reaction
        parts["time histories"] = (REC_ARRAYS * F8 * float(held) * n_steps * n_nodes + STEP_ARRAYS * F8 * n_steps * n_nodes
                                   + 6 * F8 * float(n_real) * n_steps + 45 * F8 * float(n_real) * n_towers)
        secs += n_steps * T_STEP + float(n_real) * n_steps * (T_NEWMARK * n_dof + T_SYNTH * n_nodes)
    if job == "wind":
        parts["time histories"] = STEP_ARRAYS * F8 * n_steps * n_nodes
        secs += n_steps * T_SYNTH * n_nodes
    if job in ("run", "wind"):
        parts["turbulence memo"] = memo_bytes(1 if job == "wind" else n_real, n_steps, n_nodes)
    if job == "spectral" or (job == "run" and synoptic and spectral_check):
        n_check = n_dense // 3 if windowed else n_nodes
        secs += T_SPECTRAL * SPECTRAL_POINTS * float(n_check) ** 2 * (3.0 if windowed else 1.0)
    memory = sum(parts.values())
    dominant = max(parts, key=parts.get)
    return Estimate(job, memory, secs, n_steps, n_nodes, n_dof, n_real, n_k, dominant)


def estimate_scan(case: Case, points: int, *, dynamic_realizations: int = 0, workers: int = 1) -> Estimate:
    """Estimate of a downburst scan (``linecheck scan``): step 1 at each of ``points`` positions
    and, with ``dynamic_realizations`` = k > 0 (``--dynamic``), steps 2-3 of realizations 0..k-1
    at the tower of interest.  memory: one position's job (each worker holds one at a time);
    seconds: the wall time with ``workers`` tasks at once, from the per-position costs
    :data:`T_SCAN_STATE` and :data:`T_SCAN_REALIZATION` (a scan's positions run warm: no set-up)."""
    a = case.analysis
    n_nodes, n_dof, _ = _sizes(case)
    k = max(0, int(dynamic_realizations))
    one = estimate(case, "run", realizations=k, spectral_check=False) if k else estimate(case, "static")
    n_k = 1 if case.wind.type == "synoptic" else a.mean_states
    per_point = n_k * T_SCAN_STATE * n_dof + k * float(one.n_steps) * T_SCAN_REALIZATION * n_nodes
    w = max(1, int(workers))
    seconds = T_FIXED + int(points) * per_point / min(w, max(1, int(points)))
    return Estimate("scan", one.memory, seconds, one.n_steps, n_nodes, n_dof, k, one.mean_states, one.dominant,
                    points=int(points), workers=w)


def memo_bytes(n_real: int, n_steps: int, n_nodes: int) -> float:
    """[bytes] What the process keeps of ``n_real`` realizations' turbulence for reuse
    (:mod:`linecheck.core.wind.turbulence`'s per-process memos): unit fields
    (n_steps x n_nodes) of at most a quarter of ``UNIT_FIELD_MEMO_BYTES`` each, up to it in all,
    and the random phases with their phasors (3 x n_nodes x n_freq, n_freq ≈ n_steps / 2) of at
    most an eighth each, up to half of it.  An upper bound: the phasors are kept only when the
    compiled kernel is loaded."""
    from .wind.turbulence import UNIT_FIELD_MEMO_BYTES as cap

    field = F8 * float(n_steps) * n_nodes
    phases = 3 * F8 * float(n_steps // 2) * n_nodes
    kept = min(cap, n_real * field) if field <= cap / 4 else 0.0
    return kept + (min(cap / 2, n_real * phases) if phases <= cap / 8 else 0.0)


def check(est: Estimate, case: Case, warn: Callable[[str], None] | None = None) -> Estimate:
    """Refuse ``est`` above the memory limit (CaseError, exit 2); warn above the lower thresholds."""
    limit, source = memory_limit()
    file = str(case.source) if case.source else None
    if est.memory > limit:
        raise CaseError(f"{est.text()}: above the memory limit of {fmt_bytes(limit)} ({source}); reduce "
                        "time_step, duration, realizations, mean_states or elements_per_span, or raise the limit "
                        "with --max-memory SIZE or LINECHECK_MAX_MEMORY=SIZE", file=file)
    if warn is not None:
        if est.memory > WARN_FRACTION * limit:
            warn(f"{est.text()}: more than {WARN_FRACTION:.0%} of the memory limit of {fmt_bytes(limit)}")
        elif est.seconds > WARN_SECONDS:
            warn(f"{est.text()}: a long job; cancel with Ctrl-C")
    return est


def guard(case: Case, job: str = "run", warn: Callable[[str], None] | None = None, **kwargs) -> Estimate:
    """:func:`estimate` then :func:`check`."""
    return check(estimate(case, job, **kwargs), case, warn)
