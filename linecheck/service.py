"""Service layer: the one function per job that every front end calls.

CLI, TUI, Excel export and batch runners call these functions and nothing
deeper.  They take a validated :class:`~linecheck.core.case.Case`, report
progress through a callback ``progress(stage, done, total)`` and stop when the
``cancel`` event is set (raising :class:`~linecheck.core.errors.Cancelled`).
This module imports only the numerical core (numpy/scipy) and never prints.
"""

from __future__ import annotations

import contextlib
import dataclasses
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .analysis.guard import check_budget, check_case, warn_case  # noqa: F401 - the front ends' entry points
from .core import budget, kernel
from .core.case import Case
from .core.codes import CODES_PEAK  # what ``linecheck_peak`` is: one text for every front end
from .core.damping import (
    aerodynamic_damping,
    aerodynamic_damping_stack,
    stiffness_proportional,
    stiffness_proportional_stack,
)
from .core.dynamics import DynamicResponse, integrate
from .core.errors import Cancelled
from .core.model import build_model, build_models
from .core.results import Statistics, compute_statistics
from .core.static import MeanStates, drag_intensity, solve_mean_states
from .core.system import LineSystem
from .core.wind.mean import MeanWind, mean_wind

if TYPE_CHECKING:  # names of annotations only
    from .core.modes import Modes
    from .core.results import ResultSummary
    from .core.spectral import DavenportEstimate, SpectralEstimate

Progress = Callable[[str, int, int], None]
Warn = Callable[[str], None]


@dataclass(frozen=True)
class StaticResult:
    """Step-1 result of a case: the mean wind used and the mean states."""

    case: Case
    system: LineSystem
    wind: MeanWind
    mean: MeanStates


def mean_state_times(case: Case) -> np.ndarray:
    """Instants of the step-1 mean states [s] (synoptic: one state at t = 0)."""
    if case.wind.type == "synoptic":
        return np.zeros(1)
    from .core.wind.mean import event_window  # downburst only

    t0, t1 = event_window(case)
    return np.linspace(t0, t1, case.analysis.mean_states)


def turbulence_variance_ratio(case: Case, normal: np.ndarray, longitudinal: np.ndarray) -> np.ndarray:
    """sigma^2 / |V|^2 [-]: variance of the along-wind turbulence over the squared running-mean
    speed, same shape as ``normal`` [m/s] (0 where |V| = 0).

    Downburst: sigma = I |V_m| (Chay et al. 2006), so the ratio is I^2; synoptic: sigma = I V_ref
    on a span of mean speed |V| (I^2 unless ``span_speeds`` differ from v_ref).
    """
    i = case.wind.turbulence_intensity
    if case.wind.type == "downburst":
        return np.full(np.shape(normal), i * i)
    speed2 = normal**2 + longitudinal**2
    sig2 = (i * case.wind.v_ref) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(speed2 > 0, sig2 / np.where(speed2 > 0, speed2, 1.0), 0.0)


def mean_loads(case: Case, wind: MeanWind) -> np.ndarray:
    """Transverse mean load per unit length [N/m], shape (n_t, n_spans, ne+1) (paper Eq. 1).

    ``drag = "quadratic"``: the mean of the drag on the total wind, 1/2 rho C_d D V_n|V_n|
    (1 + sigma^2/|V|^2), i.e. the paper's Eq. 1 times (1 + I^2) (docs/method.md "Quadratic drag").
    """
    line = case.line
    g = drag_intensity(wind.normal, case.wind.air_density, line.drag_coefficient, line.diameter)
    if case.analysis.drag == "quadratic":
        g = g * (1.0 + turbulence_variance_ratio(case, wind.normal, wind.longitudinal))
    return g


def static_analysis(
    case: Case,
    *,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    warn: Warn | None = None,
) -> StaticResult:
    """Step 1 of the method: non-linear static analysis under the running-mean wind.

    ``warn(message)`` receives the case's warnings (:func:`warn_case`) and resource warnings
    (:func:`check_budget`)."""
    warn_case(case, warn)
    check_budget(case, "static", warn=warn)
    return _static_analysis(case, progress=progress, cancel=cancel)


def _static_analysis(case: Case, *, progress: Progress | None = None,
                     cancel: threading.Event | None = None) -> StaticResult:
    system = LineSystem(case.line)
    wind = mean_wind(case, system, mean_state_times(case))
    gy = mean_loads(case, wind)
    cb = None if progress is None else (lambda d, n: progress("step 1: mean states", d, n))
    mean = solve_mean_states(system, wind.time, gy, progress=cb, cancel=cancel)
    return StaticResult(case, system, wind, mean)


def to_global_nodes(system: LineSystem, span_local: np.ndarray) -> np.ndarray:
    """Span-local node values (..., n_spans, ne+1) to global nodes (..., n_nodes).

    A tower node shared by two spans takes the mean of both sides.
    """
    head = span_local[..., :, :-1].reshape(span_local.shape[:-2] + (-1,))
    out = np.concatenate([head, span_local[..., -1:, -1]], axis=-1)
    if system.n_spans > 1:
        out[..., system.tower_nodes[1:-1]] = 0.5 * (span_local[..., :-1, -1] + span_local[..., 1:, 0])
    return out


def record_time(case: Case) -> np.ndarray:
    """Time grid of steps 2-3 [s], shape (n_steps,): synoptic 0..duration, downburst the event window."""
    from .core.wind.point import record_times

    return record_times(case)


def peak_window_steps(case: Case) -> int | None:
    """Samples per peak window (``analysis.peak_window`` / time step), None for the whole record."""
    w = case.analysis.peak_window
    return None if w is None else max(1, int(round(w / case.analysis.time_step)))


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
        burn_in: the discarded start of the record and whether it suffices (issue 10).
        until: the adaptive stop of :func:`run_until` (None for a fixed count).
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
        """Statistics summarised over realizations x windows (issue 18): moments, fractiles,
        Gumbel fits of the peaks, 95 % intervals, the Cont_R flag."""
        from .core.results import summarise_statistics

        return summarise_statistics(self.stats, self.still_air, self.case.analysis.design_fractile)


def reference_state_index(case: Case, mean: MeanStates) -> int:
    """Mean state used for single-state quantities (modes, structural damping calibration):
    synoptic 0; downburst the instant of the largest wind-induced mean reaction at the tower."""
    j = case.line.tower_of_interest - 1
    return int(np.argmax(np.abs(mean.reactions_wind[:, j, :]).max(axis=1)))


def damping_matrices(case: Case, st: StaticResult, models: list, states: list[int] | None = None,
                     omega1: float | None = None) -> np.ndarray:
    """Damping of mean states [N s/m], upper band storage, shape (len(models), 6, n_dof).

    ``models[i]`` is the model of mean state ``states[i]`` (default: all states in order).
    Aerodynamic (``analysis.damping``) plus stiffness-proportional structural damping
    calibrated at the lowest mode of the reference mean state (docs/method.md, damping), or
    at ``omega1`` [rad/s] when given (a window of a long line keeps the whole line's).
    """

    system, mean = st.system, st.mean
    states = list(range(len(models))) if states is None else list(states)
    vn = to_global_nodes(system, st.wind.normal)  # (n_k, n_nodes)
    C = aerodynamic_damping_stack(case, models, vn[states], mean.nodes[states])  # all states in one pass
    zs = case.analysis.structural_ratio
    if zs > 0:
        if omega1 is None:
            k_ref = reference_state_index(case, mean)
            ref = models[states.index(k_ref)] if k_ref in states else build_model(system, mean.state(k_ref))
            omega1 = structural_omega1(ref)
        C = C + stiffness_proportional_stack(models, zs, omega1)
    return C


def structural_omega1(ref) -> float:
    """[rad/s] the lowest natural circular frequency of the reference state's model ``ref``, at
    which the structural damping is calibrated (:func:`~linecheck.core.modes.natural_modes`:
    dense up to 600 DOFs, sparse Lanczos above)."""
    from .core.modes import natural_modes

    return 2 * np.pi * float(natural_modes(ref, 1).frequencies_hz[0])


BURN_IN_DECAY = np.log(100.0)  # transient amplitude down to 1 %: t = ln(100) / (zeta omega)
BURN_IN_MAX_FACTOR = 10.0  # derived burn-in capped at this multiple of the analysed duration
SIGNIFICANT_FRACTION = 0.01  # a mode matters if it adds > 1 % of the largest background r.m.s.


@dataclass(frozen=True)
class BurnIn:
    """Discarded start of a synoptic record (issue 10).

    Attributes:
        seconds: [s] burn-in used; required: [s] time for the transient of the least-damped
        significant mode to decay to 1 % (inf if undamped); mode_hz [Hz], zeta [-]: that mode;
        sufficient: whether the analysed record is stationary for every significant mode;
        source: where ``seconds`` comes from.
    """

    seconds: float
    required: float
    mode_hz: float
    zeta: float
    sufficient: bool
    source: str


@dataclass(frozen=True)
class SynopticModel:
    """The linearised synoptic mean state shared by the time and frequency domains."""

    model: object
    damping: np.ndarray
    load_per_v: np.ndarray
    modes: object


def synoptic_model(case: Case, st: StaticResult, *, vectors: bool = True, omega1: float | None = None) -> SynopticModel:
    """Model, damping, load per unit turbulence (Eq. 5) and complex modes of the synoptic state
    (with eigenvectors when ``vectors``: the burn-in and the modal superposition of the
    frequency-domain check need them); ``omega1`` [rad/s]: see :func:`damping_matrices`."""
    from .core.spectral import complex_modes

    system = st.system
    model = build_model(system, st.mean.state(0))
    damping = damping_matrices(case, st, [model], omega1=omega1)[0]
    vn = to_global_nodes(system, st.wind.normal)[0]
    line, wind = case.line, case.wind
    a = wind.air_density * line.drag_coefficient * line.diameter * model.tributary * vn  # Eq. 5 per unit v
    if system.is_section or wind.direction != 0.0:
        # the normal component of the along-wind fluctuation, v cos(phi), as the time domain
        # (fluctuating_loads; issue 17): cos(phi) = |V_n| / |V|
        vl = record_mean_wind(case, st, np.zeros(1))[1][0]
        speed = np.hypot(vn, vl)
        a = a * np.where(speed > 0, np.abs(vn) / np.where(speed > 0, speed, 1.0), 1.0)
    f_top = 0.75 / case.analysis.time_step
    modes = complex_modes(model, damping, max_hz=f_top, vectors=vectors)
    return SynopticModel(model, damping, a, modes)


def burn_in(case: Case, sm: SynopticModel) -> BurnIn:
    """Burn-in of a synoptic run from the least-damped significant complex mode (issue 10)."""
    from .core.spectral import modal_contributions
    from .core.wind.turbulence import length_scale

    duration = case.analysis.duration if case.analysis.duration is not None else 600.0
    f_top = 0.5 / case.analysis.time_step
    # the paper's damping gets no burn-in, and its verdict counts every mode in the band
    if sm.modes.right is not None and case.analysis.damping != "paper":
        mc = modal_contributions(
            sm.model, sm.modes, sm.load_per_v, case.line.tower_of_interest - 1,
            sigma=case.wind.turbulence_intensity * case.wind.v_ref, length_scale=length_scale(case),
            v_mean=case.wind.v_ref, coherence_decay=case.wind.coherence_decay, max_hz=f_top,
        )
        freq, zeta, rate_all = mc.frequencies_hz, mc.damping_ratio, mc.decay_rate
        sig = np.flatnonzero(mc.significant(SIGNIFICANT_FRACTION))
    else:  # paper damping (or no eigenvectors): every mode in the band counts (conservative)
        cm = sm.modes
        freq, zeta, rate_all = cm.frequencies_hz, cm.damping_ratio, -cm.poles.real
        sig = np.flatnonzero(freq <= f_top)
    if sig.size == 0:
        required, f1, z1 = 0.0, float("nan"), float("nan")
    else:
        i = sig[np.argmin(rate_all[sig])]
        rate = rate_all[i]
        required = float(BURN_IN_DECAY / rate) if rate > 0 else float("inf")
        f1, z1 = float(freq[i]), float(zeta[i])
    if case.analysis.burn_in is not None:
        used, src = float(case.analysis.burn_in), "analysis.burn_in"
    elif case.analysis.damping == "paper":
        used, src = 0.0, "none with damping = \"paper\" (the paper's method)"
    else:
        used, src = min(required, BURN_IN_MAX_FACTOR * duration), "derived from the least-damped significant mode"
    return BurnIn(float(used), required, f1, z1, bool(used >= required), src)


# ---- long lines: the synoptic burn-in and the frequency-domain check on windows (issue 20)
CHECK_WINDOW_MIN_SPANS = budget.WINDOW_SPANS  # lines with more spans (20): burn-in and check on windows around the tower of interest
CHECK_WINDOW_HALVES = (6, 8, 10, 12, 16, 20, 24, 32, 48, 64, 96, 128)  # spans each side, tried in turn
BURN_IN_WINDOW_HALF = 8  # the burn-in of a long line: the modes of the 16-span window
CHECK_WINDOW_RTOL = 0.005  # accept a window when the estimate moved by less than this from the previous one


@dataclass(frozen=True)
class CheckWindow:
    """The part of a long line on which the frequency-domain check ran (issue 20).

    Attributes:
        spans: spans of the window; first_tower: 0-based index (in the whole line) of its
            first tower; estimated_error: [-] per reaction (R_x, R_y, R_z), the relative change
            of the estimate (largest of the dynamic peak and the fluctuating r.m.s.) from the
            previous, smaller window -- the run-time error estimate of the reduction, shape (3,);
        windows: spans of every window tried, in order.
    """

    spans: int
    first_tower: int
    estimated_error: np.ndarray
    windows: tuple[int, ...]


def windowed(case: Case) -> bool:
    """True when the synoptic burn-in and check of ``case`` run on windows (a line of more than
    :data:`CHECK_WINDOW_MIN_SPANS` spans; docs/method.md "Long lines")."""
    return case.wind.type == "synoptic" and case.line.spans > CHECK_WINDOW_MIN_SPANS


def window_case(case: Case, system: LineSystem, half: int) -> tuple[Case, int, bool] | None:
    """The sub-line of ``half`` spans each side of the tower of interest (clipped at the strain
    towers that bound its strain section), cut at strain towers, with everything else as in
    ``case``; the index of its first tower in the whole line; and whether it is exact (the whole
    strain section: strain towers are pinned, so the rest of the line does not move it).  None
    when the window is the whole line.

    The cut ends hold the conductor at its clipped-in clamp points (a strain tower); a section
    window is re-framed on its own first span (stations from 0, the wind direction turned by
    that span's heading, the reference height pinned to the whole line's), so every node keeps
    its height, its plan position relative to the tower of interest and its wind."""
    from .core.wind.mean import reference_height

    line, wind = case.line, case.wind
    j = line.tower_of_interest - 1
    strain = [i for i, sp in enumerate(line.supports) if sp == "strain"]  # the two ends at least
    lo, hi = max(i for i in strain if i < max(j, 1)), min(i for i in strain if i > min(j, line.n_towers - 2))
    if j in (0, line.n_towers - 1):  # an end tower: its one strain section
        lo, hi = (0, hi) if j == 0 else (lo, j)
    a, b = max(lo, j - half), min(hi, j + half)
    if a == 0 and b == line.n_towers - 1:
        return None
    sup = ("strain",) + tuple(line.supports[a + 1:b]) + ("strain",)
    if wind.span_speeds is not None:
        wind = dataclasses.replace(wind, span_speeds=tuple(wind.span_speeds[a:b]))
    if line.is_section:
        s0 = line.towers[a].station
        tw = [dataclasses.replace(t, station=t.station - s0) for t in line.towers[a:b + 1]]
        for k in (0, -1):
            tw[k] = dataclasses.replace(tw[k], support="strain", angle=0.0, insulator_length=None)
        new = dataclasses.replace(line, spans=b - a, supports=sup, tower_of_interest=j - a + 1, towers=tuple(tw))
        d = wind.direction + float(np.degrees(system.span_headings[a]))  # global frame: x along the first span
        wind = dataclasses.replace(wind, direction=(d + 180.0) % 360.0 - 180.0, reference_height=reference_height(case))
    else:
        new = dataclasses.replace(line, spans=b - a, supports=sup, tower_of_interest=j - a + 1)
    return dataclasses.replace(case, line=new, wind=wind), a, (a, b) == (lo, hi)


def _window_models(case: Case, st: StaticResult, half: int, cache: dict | None):
    """(window case, its static result, its synoptic model, first tower, exact) of ``half``, or
    None for the whole line (:func:`window_case`); memoised in ``cache``."""
    cache = {} if cache is None else cache
    if half in cache:
        return cache[half]
    w = window_case(case, st.system, half)
    out = None
    if w is not None:
        wc, a, exact = w
        wst = _static_analysis(wc)
        if "omega1" not in cache:  # structural damping: calibrated on the whole line, as the time domain
            cache["omega1"] = (structural_omega1(build_model(st.system, st.mean.state(0)))
                               if case.analysis.structural_ratio > 0 else None)
        out = (wc, wst, synoptic_model(wc, wst, omega1=cache["omega1"]), a, exact)
    cache[half] = out
    return out


def synoptic_burn_in(case: Case, st: StaticResult, sm: SynopticModel | None = None,
                     cache: dict | None = None) -> BurnIn:
    """:func:`burn_in` of a synoptic case; a long line's (:func:`windowed`) from the modes of the
    window of :data:`BURN_IN_WINDOW_HALF` spans each side of the tower of interest (the modes
    that matter there), never from a dense eigenproblem of the whole line."""
    if windowed(case):
        w = _window_models(case, st, BURN_IN_WINDOW_HALF, cache)
        if w is not None:
            wc, _, wsm, _, _ = w
            b = burn_in(wc, wsm)
            if case.analysis.burn_in is None and case.analysis.damping != "paper":
                b = dataclasses.replace(b, source=f"{b.source}, in the {wc.line.spans}-span window around the tower of interest")
            return b
    return burn_in(case, sm if sm is not None else synoptic_model(case, st))


def _state_of_step(mean_times: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest mean state at each step, and the bracketing state k and weight toward k+1."""
    if mean_times.size == 1:
        zero = np.zeros(t.size, dtype=int)
        return zero, zero, np.zeros(t.size)
    k = np.clip(np.searchsorted(mean_times, t, side="right") - 1, 0, mean_times.size - 2)
    w = np.clip((t - mean_times[k]) / (mean_times[k + 1] - mean_times[k]), 0.0, 1.0)
    nearest = np.where(w > 0.5, k + 1, k)
    return nearest, k, w


def _interpolated_models(case: Case, st: StaticResult, bracket: np.ndarray, weights: np.ndarray):
    """model_at(n) for the reference scheme: the step-1 state interpolated linearly in time."""
    from .core.static import StaticState

    mean, system = st.mean, st.system
    vn_all = to_global_nodes(system, st.wind.normal)
    n_k = mean.time.size
    zs = case.analysis.structural_ratio
    w1 = 1.0
    if zs > 0:  # calibrated once, at the reference state (as in damping_matrices)
        w1 = structural_omega1(build_model(system, mean.state(reference_state_index(case, mean))))

    def model_at(n: int):
        k0 = int(bracket[n])
        k1 = min(k0 + 1, n_k - 1)
        w = float(weights[n])

        def lerp(a):
            return (1 - w) * a[k0] + w * a[k1]

        state = StaticState(lerp(mean.displacement), lerp(mean.reactions), lerp(mean.tension),
                            lerp(mean.insulator_force), lerp(mean.nodes), lerp(mean.element_tension), 0, 0.0)
        model = build_model(system, state)
        vn = (1 - w) * vn_all[k0] + w * vn_all[k1]
        c = aerodynamic_damping(case, model, vn, state.nodes)
        if zs > 0:
            c = c + stiffness_proportional(model, zs, w1)
        return model, c

    return model_at


def record_mean_wind(case: Case, st: StaticResult, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Running-mean normal and longitudinal speeds [m/s] at the global nodes over the record
    ``t``, shape (n_steps, n_nodes) each (synoptic: the step-1 wind held, longitudinal None)."""
    system = st.system
    if case.wind.type == "synoptic":
        vn = np.broadcast_to(to_global_nodes(system, st.wind.normal)[0], (t.size, system.n_nodes))
        if not system.is_section and case.wind.direction == 0.0:
            return vn, None  # the paper's wind: normal to the line, cos(phi) = 1
        from .core.wind.mean import mean_components_at_nodes

        # oblique wind (issue 17): the longitudinal component gives cos(phi) = |V_n|/|V| of the fluctuation
        vl = np.broadcast_to(mean_components_at_nodes(case, system, t[:1])[1][0], (t.size, system.n_nodes))
        return vn, vl
    mw = mean_wind(case, system, t)
    return to_global_nodes(system, mw.normal), to_global_nodes(system, mw.longitudinal)


def record_wind(case: Case, st: StaticResult, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """:func:`record_mean_wind` (vn, vl) and the turbulence's modulation a = I V_m(x, t) [m/s]
    (:func:`~linecheck.core.wind.turbulence.modulation`, (n_steps, n_nodes) or (1, 1)) over the
    record ``t``.  The equal-span downburst evaluates its field once, at the distinct stations of
    the span nodes and the global nodes together (the two sets differ in the last bit at some
    nodes), instead of once for each (issue 20: ≈ 0.07 s of a six-span run); the field is
    evaluated point by point, so the values are the same bits (tested)."""
    from .core.wind.mean import equal_span_downburst_both
    from .core.wind.turbulence import modulation

    system = st.system
    if case.wind.type != "downburst" or system.is_section:
        vn, vl = record_mean_wind(case, st, t)
        return vn, vl, modulation(case, system, t)
    vx_s, vy_s, vx_n, vy_n = equal_span_downburst_both(case, system, t)
    # as record_mean_wind (via mean_wind) and modulation (via mean_speed_at_nodes)
    return (to_global_nodes(system, vy_s), to_global_nodes(system, vx_s),
            case.wind.turbulence_intensity * np.hypot(vx_n, vy_n))


def fluctuating_loads(case: Case, system: LineSystem, model, t: np.ndarray, v: np.ndarray, vn: np.ndarray,
                      vl: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fluctuating transverse nodal loads of steps 2-3 from the along-wind turbulence.

    Args:
        v: [m/s] along-wind turbulence, shape (n_real, n_steps, n_nodes).
        vn: [m/s] running-mean normal speed at the nodes, (n_steps, n_nodes);
        vl: [m/s] running-mean longitudinal speed (downburst; None: zero, cos(phi) = 1).
    Returns:
        loads [N] on the free nodes, (n_steps, n_real, n_free); direct [N] reactions of the loads
        at pinned nodes, (n_steps, n_real, 3 n_towers).

    ``drag = "linear"``: rho C_d D L_i V_n v_n (paper Eq. 5), v_n = v cos(phi) the normal component
    of the fluctuation.  ``"quadratic"`` adds the zero-mean rest of the drag on the total wind,
    1/2 rho C_d D L_i V_n|V_n|/|V|^2 (v^2 - sigma^2) (docs/method.md "Quadratic drag"; its mean
    sigma^2 is in step 1, :func:`mean_loads`).
    """
    line, wind = case.line, case.wind
    shape = vn.shape  # (n_steps, n_nodes)
    # a synoptic record holds its mean (rows broadcast, stride 0): the per-node factors below are
    # elementwise, so they are computed on one row and viewed over the record (the same values;
    # ≈ 20 ms less per chunk with the quadratic drag)
    held = vn.ndim == 2 and vn.strides[0] == 0 and (vl is None or vl.strides[0] == 0)
    if held:
        vn = vn[:1]
        vl = None if vl is None else vl[:1]
    if vl is None:
        cos_n = np.ones_like(vn)
    else:
        speed = np.hypot(vn, vl)
        with np.errstate(invalid="ignore", divide="ignore"):
            cos_n = np.where(speed > 0, np.abs(vn) / np.where(speed > 0, speed, 1.0), 1.0)
    coef = wind.air_density * line.drag_coefficient * line.diameter
    # Eq. 5 per unit v, normal component of the fluctuation: v cos(phi), phi the angle of
    # the mean wind to the normal of the line
    per_v = coef * model.tributary[None, :] * (vn * cos_n)  # (n_steps, n_nodes)
    quad = case.analysis.drag == "quadratic"
    if quad:
        vl0 = np.zeros_like(vn) if vl is None else vl
        ratio = turbulence_variance_ratio(case, vn, vl0)  # sigma^2/|V|^2
        speed2 = vn**2 + vl0**2
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(speed2 > 0, 1.0 / np.where(speed2 > 0, speed2, 1.0), 0.0)
        # 1/2 rho C_d D L V_n|V_n| / |V|^2 per unit (v^2 - sigma^2); sigma^2 = ratio |V|^2
        per_q = 0.5 * coef * model.tributary[None, :] * vn * np.abs(vn) * inv
        sig2 = ratio * speed2
    if held:  # writeable views, as the materialised factors (np.broadcast_to's are read-only: another
        # array type, i.e. another specialisation of the compiled drag)
        def over_record(a: np.ndarray) -> np.ndarray:
            return np.lib.stride_tricks.as_strided(a, shape=shape, strides=(0, a.strides[1]))

        per_v = over_record(per_v)
        if quad:
            per_q, sig2 = over_record(per_q), over_record(sig2)
    free = model.dofs.free_nodes
    pinned = system.tower_nodes[~system.suspension]
    n_real = v.shape[0]
    loads = np.empty((t.size, n_real, free.size))
    direct = np.zeros((t.size, n_real, 3 * system.n_towers))
    # the free nodes are usually one run (all but the strain towers' nodes): a slice, no gathers
    run = free.size and np.array_equal(free, np.arange(free[0], free[0] + free.size))
    sel = slice(int(free[0]), int(free[0]) + free.size) if run else free
    pv, pv_p = per_v[:, sel], per_v[:, pinned]
    if quad:
        pq, s2 = per_q[:, sel], sig2[:, sel]  # (n_steps, n_nodes), as per_v
        pq_p, s2_p = per_q[:, pinned], sig2[:, pinned]
    # the same elementwise products as on every node, written straight into the loads (one
    # compiled pass with the kernel's piece ``loads``)
    kernel.drag_loads(pv, pq if quad else None, s2 if quad else None, v, sel, loads)
    for i in range(n_real if pinned.size else 0):
        vp = v[i][:, pinned]
        f_i = pv_p * vp  # (n_steps, n_pinned)
        if quad:
            f_i += pq_p * (vp * vp - s2_p)
        # loads at pinned nodes go straight into their supports (R_y; a section: along the node normal)
        if system.straight_in_plan:
            direct[:, i, 3 * np.flatnonzero(~system.suspension) + 1] = f_i
        else:
            b = system.node_normals[pinned]
            direct[:, i, 3 * np.flatnonzero(~system.suspension)] = f_i * b[:, 0]
            direct[:, i, 3 * np.flatnonzero(~system.suspension) + 1] = f_i * b[:, 1]
    return loads, direct


class _AnyEvent:
    """Set when the caller's cancel event is set or :meth:`set` was called (a failed chunk stops
    its siblings); duck-types the ``is_set`` of :class:`threading.Event` for the core loops."""

    def __init__(self, cancel: threading.Event | None) -> None:
        self._cancel, self._own = cancel, threading.Event()

    def set(self) -> None:
        self._own.set()

    def is_set(self) -> bool:
        return self._own.is_set() or (self._cancel is not None and self._cancel.is_set())


def _map_chunks(fn, n: int, threads: int, stop: _AnyEvent) -> list:
    """[fn(0), ..., fn(n - 1)] in order, on up to ``threads`` threads.  The first failure sets
    ``stop`` (the other chunks end at their next cancellation check) and is raised once every
    started chunk has ended; a chunk stopped that way raises Cancelled, which is not reported."""
    if threads <= 1 or n <= 1:
        return [fn(i) for i in range(n)]
    from concurrent.futures import ThreadPoolExecutor

    out: list = [None] * n
    errors: list[tuple[int, BaseException]] = []

    def one(i: int) -> None:
        if stop.is_set():
            return
        try:
            out[i] = fn(i)
        except BaseException as exc:
            errors.append((i, exc))
            stop.set()

    ex = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="linecheck-chunk")
    try:
        list(ex.map(one, range(n)))
    except BaseException:  # e.g. Ctrl-C in the calling thread: the chunks stop at their next check
        stop.set()
        raise
    finally:
        ex.shutdown(wait=True, cancel_futures=True)
    if errors:
        real = [e for e in errors if not isinstance(e[1], Cancelled)]
        raise min(real or errors, key=lambda e: e[0])[1]
    if any(o is None for o in out):  # cancelled before that chunk started
        raise Cancelled("run cancelled")
    return out


#: [s] the interpreter's thread switch interval while a run's threads work (default 5 ms): the
#: chunks and the check alternate between GIL-free compiled work and short Python stretches,
#: and a thread that wants the GIL back waited up to the whole interval (measured, 60 spans:
#: two threads 4.3-5.3 s at 5 ms, 3.8-3.9 s at 1 ms, against 4.4-5.8 s on one thread)
SWITCH_INTERVAL = 0.001
_switch_lock = threading.Lock()
_switch_users = [0, 0.0]  # runs inside _short_switch_interval, the interval before the first


@contextlib.contextmanager
def _short_switch_interval():
    """:data:`SWITCH_INTERVAL` while at least one threaded run is inside; the previous interval
    restored when the last one leaves."""
    import sys

    with _switch_lock:
        if _switch_users[0] == 0:
            _switch_users[1] = sys.getswitchinterval()
            sys.setswitchinterval(min(SWITCH_INTERVAL, _switch_users[1]))
        _switch_users[0] += 1
    try:
        yield
    finally:
        with _switch_lock:
            _switch_users[0] -= 1
            if _switch_users[0] == 0:
                sys.setswitchinterval(_switch_users[1])


def run_threads(case: Case, n_real: int, threads: int, *, burn_in: float | None = None,
                spectral_check: bool = True) -> int:
    """Threads for ``run_case``: at most ``threads`` and one per realization, and no more than
    keep the estimated memory (:func:`linecheck.core.budget.estimate`) within the limit; 1 when
    even that does not fit (``check_budget`` then refuses the run with its message)."""
    k = max(1, min(int(threads), int(n_real)))
    limit, _ = budget.memory_limit()
    while k > 1 and budget.estimate(case, "run", realizations=n_real, burn_in=burn_in,
                                    spectral_check=spectral_check, threads=k).memory > limit:
        k -= 1
    return k


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


def run_tower(case: Case, *, realizations: list[int] | np.ndarray | None = None,
              cancel: threading.Event | None = None) -> TowerRun:
    """:func:`run_case` (no frequency-domain check, one thread) computing the dynamic
    reactions of the tower of interest only: a scan ranks positions by them (issue 20), and the
    other towers' reactions, statistics and frame rotations cost ≈ 15 % of a six-span downburst
    position (measured 1.34 → 1.13 s).  Each reaction is the same arithmetic as in
    :func:`run_case` (every reaction is a sum of its own, in a fixed order), so the statistics
    are bit-identical to ``run_case(...).stats`` at that tower (tested)."""
    return _run(case, realizations=realizations, interpolate_states=False, spectral_check=False,
                progress=None, cancel=cancel, warn=None, threads=1, tower_only=True)


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
            :func:`spectral_analysis`); its cost grows faster than the number of spans, the
            time-domain steps' only linearly (docs/performance.md).
        progress: ``progress(stage, done, total)``.
        cancel: a :class:`threading.Event`; when set the run stops with ``Cancelled``.
        warn: ``warn(message)`` receives resource warnings; above the memory limit the run
            is refused before any work (:func:`check_budget`, CaseError).
        threads: realization chunks integrated at once in threads (the wind synthesis, steps
            2-3 and statistics of a chunk; step 1 runs once before them), and with more than
            one the frequency-domain check runs beside them on a thread of its own.  Every
            realization's arithmetic is its own, so the result is bit-identical whatever
            ``threads``; fewer threads are used where the chunks in flight would exceed the
            memory limit (:func:`run_threads`), one without the compiled step loop (the numpy
            loop holds the GIL).  Batch and scan workers are processes and keep 1.
    """
    return _run(case, realizations=realizations, interpolate_states=interpolate_states,
                spectral_check=spectral_check, progress=progress, cancel=cancel, warn=warn, threads=threads,
                tower_only=False)


def _run(case: Case, *, realizations, interpolate_states: bool, spectral_check: bool, progress: Progress | None,
         cancel: threading.Event | None, warn: Warn | None, threads: int, tower_only: bool):
    """:func:`run_case` (``tower_only`` False) or :func:`run_tower`: with ``tower_only`` the linear
    models' reaction map G keeps the tower of interest's three rows, so steps 2-3 and the
    statistics compute its reactions alone."""
    from .core.wind.turbulence import fluctuating_velocity

    # the resource guard first, before any allocation (even the realizations' indices: 8 GB for -n 1e9)
    n_real = int(case.analysis.realizations if realizations is None else len(realizations))
    asked = max(1, int(threads))
    threads = run_threads(case, n_real, threads, spectral_check=spectral_check)
    warned: list[str] = []
    check_budget(case, "run", warn=lambda m: (warned.append(m), warn(m) if warn else None),
                 realizations=n_real, spectral_check=spectral_check, threads=threads)
    real = np.arange(n_real) if realizations is None else np.asarray(realizations, dtype=int)
    st = _static_analysis(case, progress=progress, cancel=cancel)
    system, mean = st.system, st.mean
    t = record_time(case)
    dt = case.analysis.time_step
    wind = case.wind

    def check_cancel() -> None:
        if cancel is not None and cancel.is_set():
            raise Cancelled("run cancelled")

    # ---- linear models at the mean states (paper Eqs 7-9, 13)
    models = build_models(system, [mean.state(k) for k in range(mean.time.size)])  # one vectorised pass
    synoptic = wind.type == "synoptic"
    windows: dict = {}  # long lines: window models shared by the burn-in and the check (issue 20)
    if synoptic and case.analysis.structural_ratio > 0:
        # the structural-damping calibration, computed once for the record's models, the synoptic
        # model of the burn-in and the check (the same state's model) and a long line's windows
        windows["omega1"] = structural_omega1(models[reference_state_index(case, mean)])
    damping = damping_matrices(case, st, models, omega1=windows.get("omega1"))
    # complex modes with eigenvectors: the burn-in tells significant modes apart with them
    # (issue 10) and the frequency-domain check sums them (modal superposition)
    sm = synoptic_model(case, st, omega1=windows.get("omega1")) if synoptic and not windowed(case) else None
    burn = synoptic_burn_in(case, st, sm, windows) if synoptic else BurnIn(
        0.0, 0.0, float("nan"), float("nan"), True, "none: a downburst starts from a weak running mean")
    if burn.seconds > 0:  # the derived burn-in lengthens the record: check the budget again
        threads = run_threads(case, int(real.size), threads, burn_in=burn.seconds, spectral_check=spectral_check)
        check_budget(case, "run", warn=None if warned else warn, realizations=int(real.size),
                     burn_in=burn.seconds, spectral_check=spectral_check, threads=threads)
        t = t[0] - dt * np.round(burn.seconds / dt) + dt * np.arange(t.size + int(np.round(burn.seconds / dt)))
    keep = t >= t[0] + burn.seconds - 1e-9  # the analysed record (after the burn-in)
    state_of_step, bracket, weights = _state_of_step(mean.time, t)
    check_cancel()

    # ---- mean M(t): step-1 reactions interpolated to the record grid (wind-induced)
    rw = system.to_tower_frames(mean.reactions_wind)  # (n_k, n_towers, 3)
    if mean.time.size == 1:
        M = np.broadcast_to(rw[0], (t.size,) + rw.shape[1:]).copy()
    else:
        flat = rw.reshape(rw.shape[0], -1)
        M = np.stack([np.interp(t, mean.time, flat[:, i]) for i in range(flat.shape[1])], axis=1).reshape(
            (t.size,) + rw.shape[1:])
    gL = case.g_yp * system.eq17_lengths if system.is_section else case.g_yp_L  # Eq. 17 per tower (issue 17)
    j = case.line.tower_of_interest - 1
    still_air = system.to_tower_frames(mean.still_air.reactions)
    vn, vl, a_turb = record_wind(case, st, t)  # a_turb: the turbulence's I V_m(x, t), shared by the chunks
    second = None
    if case.analysis.tension == "second-order":
        from .core.second_order import second_order_operator

        second = [second_order_operator(m, mean.state(k)) for k, m in enumerate(models)]
    towers = slice(None)  # the towers whose reactions steps 2-3 compute
    scale = None  # the statistics' max |M| (defined gust factors): the whole section's
    if tower_only:  # the tower of interest's reactions alone (each is a sum of its own: same bits)
        scale = max(float(np.abs(M[keep]).max()), 1e-300)
        towers, rows = slice(j, j + 1), slice(3 * j, 3 * j + 3)
        M, still_air = M[:, towers], still_air[towers]
        gL = gL[towers] if np.ndim(gL) else gL
        models = [dataclasses.replace(m, G=m.G[rows]) for m in models]  # its rows of G
        if second is not None:  # and columns of the second-order forms
            second = [dataclasses.replace(so, A=np.ascontiguousarray(so.A[:, rows]),
                                          W=np.ascontiguousarray(so.W[:, rows])) for so in second]
    load_dirs = None if system.straight_in_plan else system.node_normals[models[0].dofs.free_nodes]
    model_at = _interpolated_models(case, st, bracket, weights) if interpolate_states else None

    # realization threads only with the compiled step loop, which runs without the GIL
    concurrent = asked > 1 and kernel.use("newmark")
    if not concurrent:
        threads = 1  # the numpy step loop holds the GIL between its small calls: threads lose time
    # the frequency-domain check needs only step 1 and the burn-in's models: with threads to
    # spare it runs beside the realizations (issue 20: a long line's windows take seconds)
    check_pool = check = None
    switch = _short_switch_interval() if concurrent else contextlib.nullcontext()  # GIL hand-offs
    # ---- realizations in chunks that fit in memory (issue 20: long lines), ``threads`` of them at
    # once: every realization's turbulence, Newmark columns and statistics are its own, so
    # neither the chunking nor the threads change a bit
    chunk = budget.realization_chunk(case, t.size, threads)
    if threads > 1:
        chunk = min(chunk, -(-real.size // threads))
    M_keep, window = M[keep], peak_window_steps(case)
    n_chunks = -(-real.size // chunk)
    stop = _AnyEvent(cancel)  # the user's cancel, or a failed sibling chunk
    lock = threading.Lock()
    winds_done, steps_done = [0], [0] * n_chunks

    def report(stage: str, done: int, total: int) -> None:
        if progress is not None:
            with lock:  # one call at a time, whichever thread reports
                progress(stage, done, total)

    def run_chunk(ci: int):
        rc = real[ci * chunk:(ci + 1) * chunk]
        # ---- fluctuating load F_w = rho C_d D L_e V_m v (paper Eq. 5), normal components
        report("wind", winds_done[0], n_chunks)
        v = fluctuating_velocity(case, system, t, list(rc), a_turb)  # (n_real, n_steps, n_nodes), along-wind
        loads, direct = fluctuating_loads(case, system, models[0], t, v, vn, vl)
        direct = direct.reshape(direct.shape[:2] + (-1, 3))[:, :, towers].reshape(direct.shape[:2] + (-1,))
        with lock:
            winds_done[0] += 1
        report("wind", winds_done[0], n_chunks)
        if stop.is_set():
            raise Cancelled("run cancelled")
        del v

        def cb(d: int, n: int) -> None:
            steps_done[ci] = d
            report("steps 2-3: dynamics", sum(steps_done), n_chunks * n)

        resp = integrate(models, damping, state_of_step, loads, dt, direct=direct, model_at=model_at,
                         second_order=second, second_order_start=int(np.argmax(keep)),
                         progress=None if progress is None else cb, cancel=stop, load_dirs=load_dirs)
        del loads, direct
        # every reaction from here on in its tower's own frame (issue 17; a straight line: the global frame)
        resp = DynamicResponse(system.to_tower_frames(resp.fluctuating, towers),
                               system.to_tower_frames(resp.background, towers))
        Bk, Rk = resp.background[:, keep], resp.resonant[:, keep]
        del resp
        jr = 0 if tower_only else j  # the tower of interest among the computed reactions
        return (compute_statistics(M_keep, Bk, Rk, still_air, gL, window=window, scale=scale),
                Bk[:, :, jr, :].copy(), Rk[:, :, jr, :].copy())

    with switch:
        try:
            if synoptic and spectral_check and concurrent:
                from concurrent.futures import ThreadPoolExecutor

                check_pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="linecheck-check")
                check = check_pool.submit(spectral_analysis, case, static=st, synoptic=sm, windows=windows)
            parts = _map_chunks(run_chunk, n_chunks, threads, stop)
            spectral = check.result() if check is not None else None
        finally:
            if check_pool is not None:
                check_pool.shutdown(wait=False, cancel_futures=True)  # a failed run does not wait for it
    parts_stats, parts_B, parts_R = (list(p) for p in zip(*parts))
    stats = parts_stats[0] if n_chunks == 1 else Statistics.concatenate(parts_stats)
    if tower_only:
        return TowerRun(static=st, stats=stats)
    if check is None:
        spectral = (spectral_analysis(case, static=st, synoptic=sm, windows=windows)
                    if synoptic and spectral_check else None)
    return RunResult(
        case=case, system=system, static=st, realizations=real, time=t[keep], mean=M_keep,
        background=parts_B[0] if n_chunks == 1 else np.concatenate(parts_B),
        resonant=parts_R[0] if n_chunks == 1 else np.concatenate(parts_R), stats=stats,
        spectral=spectral, burn_in=burn,
    )




@dataclass(frozen=True)
class UntilInfo:
    """Adaptive realization count (issue 18, ``--until``).

    target, achieved: [-] relative standard errors (0.01 = 1 %); achieved is the largest
    se/|mean| of GF_Dy and of peak_dynamic over the reactions at the tower of interest whose
    GF_Dy is defined; reached: achieved <= target; max_realizations: the cap.
    """

    target: float
    achieved: float
    reached: bool
    max_realizations: int


def relative_standard_error(res: RunResult) -> float:
    """Largest se/|mean| of GF_Dy and peak_dynamic at the tower of interest over the reactions whose
    GF_Dy is defined (a reaction with a vanishing mean has no gust factor to converge) [-]."""
    from .core.extremes import summarise

    j = res.tower_index
    gf = summarise(res.stats.GF_Dy[:, j])
    pk = summarise(res.stats.peak_dynamic[:, j])
    if gf.n < 2:
        return float("inf")
    ok = np.isfinite(gf.mean)
    if not ok.any():
        ok = pk.mean > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.concatenate([(gf.se / np.abs(gf.mean))[ok & np.isfinite(gf.mean)], (pk.se / np.abs(pk.mean))[ok]])
    return float(rel.max()) if rel.size else 0.0


def join_runs(parts: list[RunResult]) -> RunResult:
    """One result from runs of consecutive disjoint realization sets of one case, in order
    (realization r always has the same turbulence, so this is bit-identical to one run)."""
    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    return dataclasses.replace(
        first,
        realizations=np.concatenate([p.realizations for p in parts]),
        background=np.concatenate([p.background for p in parts], axis=0),
        resonant=np.concatenate([p.resonant for p in parts], axis=0),
        stats=Statistics.concatenate([p.stats for p in parts]),
    )


UNTIL_OVERSHOOT = 1.1  # next count: 10 % above the n (se ~ 1/sqrt(n)) predicts, to stop in few chunks
UNTIL_MAX_CHUNK = 50  # realizations added per chunk at most: bounds a chunk's memory (resource guard)


def run_until(
    case: Case,
    target: float,
    *,
    max_realizations: int = 1000,
    interpolate_states: bool = False,
    spectral_check: bool = True,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    warn: Warn | None = None,
    threads: int = 1,
) -> RunResult:
    """Add realizations in chunks until :func:`relative_standard_error` <= ``target`` [-] or
    ``max_realizations`` have run (issue 18).

    Starts with ``analysis.realizations`` (at most the cap); each next count is the one the
    1/sqrt(n) law predicts, times :data:`UNTIL_OVERSHOOT`, adding at most
    :data:`UNTIL_MAX_CHUNK` realizations per chunk.  Realization r always gets the same
    turbulence, so the result is bit-identical to ``run_case`` with the same count.
    """
    if not target > 0:
        raise ValueError(f"target {target!r} must be > 0")
    n = max(2, min(case.analysis.realizations, max_realizations))
    parts = [run_case(case, realizations=range(n), interpolate_states=interpolate_states,
                      spectral_check=spectral_check, progress=progress, cancel=cancel, warn=warn, threads=threads)]
    while True:
        res = join_runs(parts)
        achieved = relative_standard_error(res)
        done = res.realizations.size
        if achieved <= target or done >= max_realizations:
            return dataclasses.replace(res, until=UntilInfo(float(target), achieved, bool(achieved <= target),
                                                            int(max_realizations)))
        want = done * (achieved / target) ** 2 * UNTIL_OVERSHOOT if np.isfinite(achieved) else 2 * done
        nxt = int(min(max_realizations, done + UNTIL_MAX_CHUNK, max(done + 1, int(np.ceil(want)))))
        parts.append(run_case(case, realizations=np.arange(done, nxt), interpolate_states=interpolate_states,
                              spectral_check=False, progress=progress, cancel=cancel, warn=warn, threads=threads))


@dataclass(frozen=True)
class ModesResult:
    """Natural modes of the still-air state and of the mean state.

    ``mean_time`` [s] is the instant of the mean state used: synoptic 0; downburst the
    step-1 instant of the largest wind-induced mean reaction at the tower of interest.
    """

    case: Case
    still_air: Modes
    mean: Modes
    mean_time: float
    damped: object = None  # ComplexModes of the mean state with the case's damping
    #: per undamped mean-state mode, its damped counterpart (:func:`~linecheck.core.modes.pair_by_shape`):
    #: frequency [Hz], damping ratio [-] and MAC [-] of the paired complex mode (NaN where none)
    paired_hz: np.ndarray | None = None
    paired_ratio: np.ndarray | None = None
    paired_mac: np.ndarray | None = None


def modes_analysis(case: Case, *, n_modes: int = 20, warn: Warn | None = None) -> ModesResult:
    """Natural frequencies and mode shapes of the still-air and the mean state."""
    from .core.modes import natural_modes, pair_by_shape

    warn_case(case, warn)
    check_budget(case, "modes", warn=warn)
    st = _static_analysis(case)
    system, mean = st.system, st.mean
    j = case.line.tower_of_interest - 1
    k = int(np.argmax(np.abs(mean.reactions_wind[:, j, :]).max(axis=1)))
    from .core.spectral import complex_modes

    still = natural_modes(build_model(system, mean.still_air), n_modes)
    model = build_model(system, mean.state(k))
    at_mean = natural_modes(model, n_modes)
    cm = complex_modes(model, damping_matrices(case, st, [model], states=[k])[0], vectors=True)
    index, mac = pair_by_shape(at_mean, model, cm.right, cm.S)  # the damped counterpart of each mode
    ok = index >= 0
    paired_hz, paired_ratio = np.full(index.size, np.nan), np.full(index.size, np.nan)
    paired_hz[ok], paired_ratio[ok] = cm.frequencies_hz[index[ok]], cm.damping_ratio[index[ok]]
    n = min(n_modes, cm.poles.size)
    damped = dataclasses.replace(cm, frequencies_hz=cm.frequencies_hz[:n], damping_ratio=cm.damping_ratio[:n],
                                 poles=cm.poles[:n], right=None, left=None, S=None, mass=None, expansion=None,
                                 norm=None)
    return ModesResult(case, still, at_mean, float(mean.time[k]), damped, paired_hz, paired_ratio, mac)


@dataclass(frozen=True)
class WindField:
    """The wind of one realization of a run at every conductor node (``linecheck wind --field``;
    public NPZ layout in docs/wind.md).

    Attributes:
        t: [s] the analysed record's equally spaced instants, burn-in included, shape (n_t,).
        burn_in: [s] the discarded start of ``t`` (0 for downbursts and ``damping = "paper"``).
        x_node: [m] still-air node positions (x along the line, z up), shape (n_nodes, 3);
            nodes in line order, tower nodes once (n_spans * elements_per_span + 1).  Section form:
            ``LineSystem.node_xyz0`` (x along the first span, y to its left, z up, global frame).
        u_mean: [m/s] running-mean wind velocity (x, y, z) at each node, (n_t, n_nodes, 3)
            (section form: the full vector in the global frame, synoptic V(z)(sin d, cos d, 0)).
        u_turb: [m/s] turbulent wind velocity (x, y, z): the along-wind fluctuation v along the
            running mean's direction, (n_t, n_nodes, 3).
        v_along: [m/s] the along-wind fluctuation v itself (signed), (n_t, n_nodes).
        realization: 1-based; seed: the case's seed.
    """

    case: Case
    t: np.ndarray
    burn_in: float
    x_node: np.ndarray
    u_mean: np.ndarray
    u_turb: np.ndarray
    v_along: np.ndarray
    realization: int
    seed: int

    def to_npz_dict(self) -> dict[str, np.ndarray]:
        """Arrays of the public NPZ layout (docs/wind.md)."""
        return {
            "t": self.t, "burn_in": np.float64(self.burn_in), "x_node": self.x_node,
            "u_mean": self.u_mean, "u_turb": self.u_turb, "v_along": self.v_along,
            "realization": np.int64(self.realization), "seed": np.int64(self.seed),
            "case": np.str_(self.case.name), "units": np.str_(
                "SI: s, m, m/s; global frame: x along the first span, y to its left, z up" if self.case.line.is_section
                else "SI: s, m, m/s; x along the line, y transverse, z up"),
        }


def record_grid(case: Case, st: StaticResult | None = None) -> tuple[np.ndarray, float]:
    """Instants of steps 2-3 [s] with the burn-in exactly as :func:`run_case` builds them, and
    the burn-in [s]."""
    st = static_analysis(case) if st is None else st
    t = record_time(case)
    dt = case.analysis.time_step
    burn = 0.0
    if case.wind.type == "synoptic":
        burn = synoptic_burn_in(case, st).seconds
    if burn > 0:
        t = t[0] - dt * np.round(burn / dt) + dt * np.arange(t.size + int(np.round(burn / dt)))
    return t, float(burn)


def wind_field(case: Case, *, realization: int = 0) -> WindField:
    """The running mean and turbulence of ``realization`` (0-based) at every conductor node and
    step of the record :func:`run_case` analyses (burn-in included): the same calls, so the same
    field bit for bit (issue 16).  u_turb = v (V_x, V_y, 0)/|V| (Eq. 5's normal component is its
    y component); no vertical wind (z components zero)."""
    from .core.errors import CaseError
    from .core.wind.turbulence import fluctuating_velocity

    if not 0 <= realization < case.analysis.realizations:
        raise CaseError(f"realization {realization + 1} is out of range: expected 1 to {case.analysis.realizations} "
                        "(analysis.realizations)")
    st = static_analysis(case)
    system = st.system
    t, burn = record_grid(case, st)
    if _wind_vectors(case, system):
        # issue 17: full vectors in the global frame at the still-air node positions (section form)
        from .core.wind.mean import mean_vector_at_nodes

        v = fluctuating_velocity(case, system, t, [realization])[0]
        u_mean = np.broadcast_to(mean_vector_at_nodes(case, system, t[:1] if case.wind.type == "synoptic" else t),
                                 (t.size, system.n_nodes, 3)).copy()
        speed = np.hypot(u_mean[..., 0], u_mean[..., 1])
        normal = system.node_normals[None, :, :]  # direction of the fluctuation where |V| = 0
        with np.errstate(invalid="ignore", divide="ignore"):
            unit = np.where(speed[..., None] > 0, u_mean / np.where(speed > 0, speed, 1.0)[..., None], normal)
        u_turb = v[..., None] * unit
        x_node = system.node_xyz0.copy()
        return WindField(case, t, burn, x_node, u_mean, u_turb, v, realization + 1, case.analysis.seed)
    vn, vl = record_mean_wind(case, st, t)
    vl = np.zeros_like(vn) if vl is None else vl
    v = fluctuating_velocity(case, system, t, [realization])[0]
    zero = np.zeros_like(vn)
    u_mean = np.stack([vl, vn, zero], axis=-1)
    speed = np.hypot(vn, vl)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit_n = np.where(speed > 0, vn / np.where(speed > 0, speed, 1.0), 1.0)
        unit_l = np.where(speed > 0, vl / np.where(speed > 0, speed, 1.0), 0.0)
    u_turb = np.stack([v * unit_l, v * unit_n, zero], axis=-1)
    x_node = st.mean.still_air.nodes.copy()
    return WindField(case, t, burn, x_node, u_mean, u_turb, v, realization + 1, case.analysis.seed)


def _wind_vectors(case: Case, system: LineSystem) -> bool:
    """True when the wind field is built from full mean-wind vectors (a section, or a synoptic
    wind with a direction or profile); False keeps the equal-span form's original arrays."""
    w = case.wind
    return system.is_section or (w.type == "synoptic" and (w.direction != 0.0 or w.profile_exponent != 0.0
                                                           or w.reference_height is not None))


def read_wind_field(path) -> dict[str, np.ndarray]:
    """The arrays of a ``linecheck wind --field`` NPZ file (docs/wind.md)."""
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def loads_from_field(case: Case, field: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Fluctuating loads of steps 2-3 (:func:`fluctuating_loads`) from a wind field's arrays
    (``WindField.to_npz_dict`` or :func:`read_wind_field`): loads [N] (n_t, 1, n_free) and the
    direct reactions [N] (n_t, 1, 3 n_towers)."""
    st = static_analysis(case)
    model = build_model(st.system, st.mean.state(0))
    u = field["u_mean"]
    if _wind_vectors(case, st.system):
        # issue 17: normal component along each node's horizontal normal (span normal; tower nodes:
        # the tower frame's y) and the along-line rest, for cos(phi) = |V_n|/|V|
        n, e = st.system.node_normals, st.system.node_frames[:, :, 0]
        vn = u[..., 0] * n[None, :, 0] + u[..., 1] * n[None, :, 1]
        vl = u[..., 0] * e[None, :, 0] + u[..., 1] * e[None, :, 1]
        return fluctuating_loads(case, st.system, model, field["t"], field["v_along"][None], vn, vl)
    vl = None if case.wind.type == "synoptic" else u[:, :, 0]
    return fluctuating_loads(case, st.system, model, field["t"], field["v_along"][None], u[:, :, 1], vl)


@dataclass(frozen=True)
class WindAtP:
    """Wind at the FE node nearest point p (paper Fig. 3).

    Attributes:
        time: [s] shape (n_steps,); mean: [m/s] running-mean speed (magnitude);
        total: [m/s] mean + turbulence of ``realization``; x: [m] abscissa of the node used.
    """

    case: Case
    time: np.ndarray
    mean: np.ndarray
    total: np.ndarray
    x: float
    realization: int


def wind_at_p(case: Case, *, realization: int = 0, warn: Warn | None = None) -> WindAtP:
    """Running-mean and total wind speed at point p over the record (paper Fig. 3)."""
    from .core.wind.point import point_series

    check_budget(case, "wind", warn=warn)

    p = point_series(case, realization)
    return WindAtP(case, p.time, p.mean_speed, p.total, p.node_x, realization)


@dataclass(frozen=True)
class SpectralResult:
    """Frequency-domain check of a synoptic case (issue 5).

    ``exact``: estimate 1 (linear random vibration of the step-1 model), reactions
    (R_x, R_y, R_z) at the tower of interest; ``davenport``: estimate 2 for the
    transverse reaction (closed form) and whether it is within 15 % of estimate 1;
    ``window``: for a long line, the window estimate 1 ran on and its estimated error
    (None: the whole line).
    """

    case: Case
    exact: SpectralEstimate
    davenport: DavenportEstimate
    davenport_applicable: bool
    davenport_note: str
    window: CheckWindow | None = None


DAVENPORT_TOLERANCE = 0.15  # issue 5: estimate 2 shown only where within 15 % of estimate 1


def spectral_analysis(case: Case, *, static: StaticResult | None = None,
                      synoptic: SynopticModel | None = None, warn: Warn | None = None,
                      windows: dict | None = None) -> SpectralResult:
    """Frequency-domain estimates for a synoptic case (same model and damping as the time domain).

    A long line (:func:`windowed`) gets estimate 1 on windows of ``CHECK_WINDOW_HALVES`` spans
    each side of the tower of interest, widened until the estimate moves by less than
    :data:`CHECK_WINDOW_RTOL` (the last change is reported as the estimated error) or the
    window is the whole line; the mean reaction is always the whole line's step 1.
    ``windows``: memo of the window models shared with :func:`synoptic_burn_in`."""
    from .core.errors import CaseError
    from .core.spectral import davenport_gust_factor, random_vibration
    from .core.wind.turbulence import length_scale

    if case.wind.type != "synoptic":
        raise CaseError("the frequency-domain check is for synoptic cases only (a downburst is non-stationary)",
                        file=str(case.source) if case.source else None, key="wind.type")
    if static is None:
        check_budget(case, "spectral", warn=warn)
    st = static if static is not None else _static_analysis(case)
    mean = st.mean
    line, wind = case.line, case.wind
    t = record_time(case)
    j = case.line.tower_of_interest - 1
    rw = st.system.to_tower_frames(mean.reactions_wind)  # each tower's own frame (issue 17)
    mean_r = rw[0, j]
    from .core.results import ZERO_MEAN_RTOL

    tol = ZERO_MEAN_RTOL * float(np.abs(rw[0]).max())
    L_u = length_scale(case)

    def estimate(m: SynopticModel, tower: int):
        return random_vibration(
            m.model, m.damping, m.load_per_v, mean_r, tower, modes=m.modes, sigma=wind.turbulence_intensity * wind.v_ref,
            length_scale=L_u, v_mean=wind.v_ref, coherence_decay=wind.coherence_decay, duration=float(t[-1] - t[0]),
            band=(1e-5, 0.5 / case.analysis.time_step), zero_mean_tol=tol,
        )

    window = None
    if not windowed(case):
        exact = estimate(synoptic if synoptic is not None else synoptic_model(case, st), j)  # the time domain's model
    else:
        windows = {} if windows is None else windows
        prev, tried = None, []
        for half in CHECK_WINDOW_HALVES:
            w = _window_models(case, st, half, windows)
            if w is None:  # the window reached the whole line: the exact estimate
                exact = estimate(synoptic if synoptic is not None else synoptic_model(case, st), j)
                window = None
                break
            wc, _, wsm, a, whole_section = w
            exact = estimate(wsm, j - a)
            tried.append(wc.line.spans)
            if whole_section:  # the strain section of the tower of interest: exact
                window = CheckWindow(wc.line.spans, a, np.zeros(3), tuple(tried))
                break
            if prev is not None:
                err = np.maximum(_relative_change(exact.peak_dynamic, prev.peak_dynamic),
                                 _relative_change(exact.rms_fluctuating, prev.rms_fluctuating))
                window = CheckWindow(wc.line.spans, a, err, tuple(tried))
                if float(err.max()) <= CHECK_WINDOW_RTOL:
                    break
            prev = exact
    reason = closed_form_not_applicable(case, st.system)
    if reason:
        from .core.spectral import DavenportEstimate

        nan = float("nan")
        return SpectralResult(case, exact, DavenportEstimate(*([nan] * 9)), False, f"not applicable: {reason}", window)
    H = float(mean.tension[0].mean())
    mu = line.mass_per_length
    span = st.system.common_span_length  # the closed form is for equal spans
    f1 = np.sqrt(H / mu) / (2 * span)  # taut-string fundamental (Irvine 1981 Eq. 3.21)
    dav = davenport_gust_factor(
        span=span, v_mean=wind.v_ref, intensity=wind.turbulence_intensity, length_scale=L_u,
        coherence_decay=wind.coherence_decay, f1=f1, mass_per_length=mu, air_density=wind.air_density,
        drag_coefficient=line.drag_coefficient, diameter=line.diameter, duration=float(t[-1] - t[0]),
        height=line.height,
    )
    ref = exact.GF_Dy[1]
    if not np.isfinite(ref):
        ok, note = False, "transverse mean is zero: no gust factor to compare"
    else:
        diff = abs(dav.GF_Dy - ref) / ref
        ok = diff <= DAVENPORT_TOLERANCE
        note = (f"within {100 * diff:.0f} % of the exact estimate" if ok else
                f"differs by {100 * diff:.0f} % from the exact estimate (> 15 %): the closed form's uniform "
                "influence line and single mode do not represent this system; use estimate 1")
    return SpectralResult(case, exact, dav, ok, note, window)


def _relative_change(new: np.ndarray, old: np.ndarray) -> np.ndarray:
    """|new - old| / |new| per component, a component below 1e-6 of the largest scaled by the largest [-]."""
    scale = np.maximum(np.abs(new), 1e-6 * float(np.abs(new).max()) + 1e-300)
    return np.abs(new - old) / scale


def closed_form_not_applicable(case: Case, system: LineSystem) -> str:
    """Why the Davenport/Castanheta closed form (estimate 2) does not apply to this case, or ""
    when it does: it assumes one straight row of equal, level spans, a uniform wind normal to
    the line and one mean speed (issue 17)."""
    if not system.is_section:
        if case.wind.direction != 0.0 or case.wind.profile_exponent != 0.0:
            return "the closed form assumes a uniform wind normal to the line (direction 0, no profile)"
        return ""
    if not system.equal_spans:
        return "the spans of this section are unequal (the closed form is for one span length)"
    if np.any(system.tower_angles):
        return "the section has angle towers (the closed form is for a straight line)"
    if np.ptp(system.clamp_points[:, 2]) > 0.0:
        return "the section has inclined spans (the closed form is for level spans)"
    if case.wind.direction != 0.0 or case.wind.profile_exponent != 0.0:
        return "the closed form assumes a uniform wind normal to the line (direction 0, no profile)"
    return ""


@dataclass(frozen=True)
class SanityItem:
    """One time- vs frequency-domain comparison (issue 5 "sanity check")."""

    reaction: str
    quantity: str
    time_domain: float
    time_domain_std: float
    frequency_domain: float
    allowed: float
    ok: bool


SANITY_QUANTITIES = ("rms_background", "rms_fluctuating")
NUMERICAL_TOLERANCE = 0.03  # frequency-grid and estimator bias allowance, relative


def sanity_check(res: RunResult) -> list[SanityItem]:
    """Compare the time-domain r.m.s. with estimate 1 at the tower of interest.

    A difference is flagged when it exceeds what sampling explains: three standard
    errors of the realization mean (std / sqrt(N)) plus a 3 % numerical allowance.
    Components whose r.m.s. is below 1 % of the largest are skipped.
    """
    if res.spectral is None:
        return []
    from .core.results import REACTIONS

    j = res.tower_index
    n = res.stats.n_samples
    ex = res.spectral.exact
    items = []
    scale = float(np.max(ex.rms_fluctuating))
    for q in SANITY_QUANTITIES:
        td = res.stats.mean(q)[j]
        sd = res.stats.std(q)[j]
        fd = getattr(ex, q)
        for c, r in enumerate(REACTIONS):
            if fd[c] < 0.01 * scale:
                continue
            allowed = 3.0 * sd[c] / np.sqrt(max(n, 1)) + NUMERICAL_TOLERANCE * fd[c]
            items.append(SanityItem(r, q, float(td[c]), float(sd[c]), float(fd[c]), float(allowed),
                                    bool(abs(td[c] - fd[c]) <= allowed)))
    return items


# --------------------------------------------------------------------------- design codes (issue 19)
@dataclass(frozen=True)
class ReactionCheck:
    """One reaction against one code: loads [N], ratio = linecheck_peak / code_load [-]."""

    code_load: float | None
    linecheck_peak: float | None
    ratio: float | None
    verdict: str


@dataclass(frozen=True)
class TowerCheck:
    """A tower's checks; ``reactions`` maps a reaction name ("Ry") to its check."""

    index: int  # 1-based
    reactions: dict


@dataclass(frozen=True)
class CodeCheck:
    """One code's conductor wind load at every tower of the section, beside linecheck's peaks.

    ``load_per_length`` [N/m] on the wind span at ``v_ref`` (None: no provision or outside the
    code's validity, see ``note``); ``towers`` per tower (1-based ``index``).
    """

    code: str
    edition: str
    verified: bool
    provision: str
    load_per_length: float | None
    inputs: dict
    note: str
    towers: tuple


@dataclass(frozen=True)
class CodesResult:
    """The four codes side by side (docs/codes.md); ``peak`` says what ``linecheck_peak`` is."""

    case: Case
    checks: tuple
    peak: str


def design_peaks(run: RunResult, component: int) -> np.ndarray:
    """[N] linecheck's design peak of one reaction component at every tower, shape (n_towers,):
    the Gumbel design value of ``peak_dynamic`` at ``analysis.design_fractile`` (issue 18), or
    the mean over realizations where the fit is undefined (one realization)."""
    pk = run.summary().statistics["peak_dynamic"]
    mean = pk.summary.mean[:, component]
    if pk.gumbel is None:
        return mean
    design = pk.gumbel.design[:, component]
    return np.where(np.isfinite(design), design, mean)


def code_loads(case: Case, *, strict: bool = True) -> list:
    """Each code's :class:`~linecheck.core.codes.CodeLoad` for ``case``: at the case's mean speed at
    the conductor height ``line.height``, v_ref (z/z_ref)^alpha (the case's own profile).

    ``strict``: a value outside a code's validity raises :class:`CaseError`; otherwise the
    code is reported with no load and the message in its note.
    """
    from .core import codes as C
    from .core.errors import CaseError

    line, wind, cc = case.line, case.wind, case.codes
    src = str(case.source) if case.source else None
    if wind.type == "downburst":
        return [C.downburst_load(code) for code in C.CODES]
    # the codes' wind span: the section's common span (equal spans); a section of unequal spans:
    # Eq. 17's L_x at the tower of interest (docs/codes.md "Sections")
    system = LineSystem(line)
    span = system.common_span_length if system.equal_spans else system.span_lengths_at_tower(line.tower_of_interest - 1)
    # the case's 10-minute mean at the codes' height h: v_ref carried from its reference height by
    # the case's own power law (wind.profile_exponent), as steps 1-3 load the wire
    from .core.wind.mean import profile_factor

    v_h = float(wind.v_ref * profile_factor(case, np.array(line.height)))
    args = (v_h, line.height, span, line.diameter, line.drag_coefficient)
    calls = {
        "ASCE74": lambda: C.asce74_wire_load(*args, cc.asce74_exposure or C.TERRAIN_MAP["ASCE74"][cc.terrain],
                                             source=src),
        "IEC60826": lambda: C.iec60826_conductor_load(
            *args, cc.iec60826_terrain or C.TERRAIN_MAP["IEC60826"][cc.terrain], source=src),
        "EN50341": lambda: C.en50341_conductor_load(*args, cc.en50341_terrain or C.TERRAIN_MAP["EN50341"][cc.terrain],
                                                    source=src),
        "ASNZS7000": lambda: C.asnzs7000_conductor_load(*args, turbulence_intensity=wind.turbulence_intensity,
                                                        source=src),
    }
    out = []
    for code in C.CODES:
        try:
            out.append(calls[code]())
        except CaseError as err:
            if strict:
                raise
            out.append(C.CodeLoad(code, C.EDITIONS[code], False, "synoptic", None, {}, f"not applied: {err}"))
    return out


def codes_analysis(case: Case, run: RunResult | None = None, *, strict: bool = True) -> CodesResult:
    """Design-code conductor wind loads beside linecheck's peaks, per tower (issue 19).

    Ry at tower j: code load = sum over the adjacent spans of w(v_n) L_n / 2, w the code's
    load per length scaled by (v_n / v_ref)^2 for per-span synoptic speeds.  ``run``: the run
    whose peaks are compared (None: the code loads only).  Verdict "code covers" when
    linecheck's peak is at most the code load, else "code exceeded by x %"; unverified codes
    get no verdict.
    """
    import math

    line, wind = case.line, case.wind
    n_spans = line.spans
    speeds = np.asarray(wind.span_speeds if wind.span_speeds is not None else [wind.v_ref] * n_spans, dtype=float)
    scale = (speeds / wind.v_ref) ** 2 if wind.v_ref > 0 else np.ones(n_spans)
    system = LineSystem(line)
    if system.is_section or wind.direction != 0.0:
        # the wind's normal component on every span, cos(d + h_i) (issue 17; docs/codes.md "Sections")
        scale = scale * np.cos(np.radians(wind.direction) + system.span_headings) ** 2
    half = 0.5 * system.span_lengths * scale  # [m] equivalent half spans at v_ref
    eq_span = np.zeros(n_spans + 1)
    eq_span[:-1] += half
    eq_span[1:] += half
    peaks = design_peaks(run, 1) if run is not None else None  # (n_towers,) Ry, issue 18 design value
    checks = []
    for load in code_loads(case, strict=strict):
        towers = []
        for j in range(n_spans + 1):
            peak = float(peaks[j]) if peaks is not None else None
            if load.load_per_length is None:
                verdict = {"none": "no provision", "not established": "provision not established"}.get(
                    load.provision, "outside the code's validity")
                rc = ReactionCheck(None, peak, None, verdict)
            else:
                F = float(load.load_per_length * eq_span[j])
                ratio = peak / F if (peak is not None and F > 0) else None
                if ratio is None:
                    verdict = "no linecheck run"
                elif not load.verified:
                    verdict = "unverified: not judged"
                elif ratio <= 1.0:
                    verdict = "code covers"
                else:
                    verdict = f"code exceeded by {100 * (ratio - 1):.0f} %"
                if ratio is not None and not math.isfinite(ratio):
                    ratio = None
                rc = ReactionCheck(F, peak, ratio, verdict)
            towers.append(TowerCheck(j + 1, {"Ry": rc}))
        checks.append(CodeCheck(load.code, load.edition, load.verified, load.provision, load.load_per_length,
                                dict(load.inputs), load.note, tuple(towers)))
    return CodesResult(case, tuple(checks), CODES_PEAK)


# ------------------------------------------------------------------ model spread (issue 15)
#: Downburst running-mean models that need no user data; "table" joins them when the case names a field.
BUILTIN_DOWNBURST_MODELS = ("holmes-oliver", "ring-jet")


def spread_models(case: Case) -> tuple[str, ...]:
    """The models a ``--models all`` run uses for ``case``: every built-in downburst model, plus
    "table" when the case names a field file; () for a synoptic case."""
    if case.wind.type != "downburst" or case.wind.downburst is None:
        return ()
    extra = ("table",) if case.wind.downburst.field is not None else ()
    return BUILTIN_DOWNBURST_MODELS + extra


def model_changes(case: Case, model: str) -> dict:
    """Case key changes that put ``case`` under downburst model ``model``: the key ``model`` and
    the removal of the other models' keys (t1/t_f, jet_velocity, field); {} if already so."""
    from .core.errors import CaseError

    db = case.wind.downburst
    if db is None:
        raise CaseError("has no [wind.downburst] table: a model spread needs a downburst case", key="wind.type")
    if db.model_name == model:
        return {}
    changes: dict = {"wind.downburst.model": model}
    if model != "table":
        changes["wind.downburst.field"] = None
    if model not in ("ring-jet", "ring-jet-inviscid"):  # the ring models read jet_velocity
        changes["wind.downburst.jet_velocity"] = None
    if model != "holmes-oliver":
        changes["wind.downburst.t1"] = None
        changes["wind.downburst.t_f"] = None
    return changes


def case_with_model(case: Case, model: str) -> Case:
    """``case`` under downburst model ``model`` (:func:`model_changes`); geometry, V_ref,
    translation, analysis settings and seeds kept."""
    from .core.case import with_values

    changes = model_changes(case, model)
    return with_values(case, changes) if changes else case


def parse_models(case: Case, text: str) -> tuple[str, ...]:
    """The models of a ``--models`` option: "all" (:func:`spread_models`) or a comma list."""
    from .core.case import DOWNBURST_MODELS
    from .core.errors import CaseError

    if case.wind.type != "downburst":
        raise CaseError("is not a downburst case: --models needs type = \"downburst\"",
                        file=str(case.source) if case.source else None, key="wind.type")
    if text.strip() == "all":
        return spread_models(case)
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    for n in names:
        if n not in DOWNBURST_MODELS:
            raise CaseError(f'--models: value "{n}" is not allowed: expected "all" or a comma list of '
                            + ", ".join(f'"{m}"' for m in DOWNBURST_MODELS))
    if not names:
        raise CaseError('--models: empty: expected "all" or a comma list of model names')
    return names


def run_models(case: Case, models: tuple[str, ...] | list[str] | None = None, **kwargs) -> dict[str, RunResult]:
    """Run ``case`` under each downburst model (default :func:`spread_models`) with the same
    analysis settings and turbulence seeds; ``kwargs`` go to :func:`run_case`.  Returns the
    results keyed by model name, in the order given."""
    from .core.errors import CaseError

    names = tuple(models) if models is not None else spread_models(case)
    if not names:
        raise CaseError("is not a downburst case: the model spread (--models) needs type = \"downburst\"",
                        file=str(case.source) if case.source else None, key="wind.type")
    return {m: run_case(case_with_model(case, m), **kwargs) for m in names}
