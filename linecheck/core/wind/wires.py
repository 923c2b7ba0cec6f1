"""One turbulence field for every wire of a line (phases, bundles, ground wires).

The single-wire synthesis (:mod:`.turbulence`) gives the unit field u(x, t) of one wire's nodes
with the Davenport coherence along the line.  Here n_w wires share one field: their nodes sit at
the same stations x (the same towers, the same mesh) and each wire w is offset across the line by
(y_w, z_w) [m] (y horizontal, square to the line; z up; e.g. its attachment point in the tower
frame -- only differences matter).  The coherence of node j of wire a and node m of wire b is

    gamma(f) = exp(-f (C_x |x_j - x_m| + C_y |y_a - y_b| + C_z |z_a - z_b|) / V)

the product of the along-line Davenport coherence (Davenport 1961; C_x = ``coherence_decay``) and
exponential coherences across the line and in height with their own decay constants (Davenport
1961; Simiu & Scanlan 1996, sec. 2.3: C_y = 16, C_z = 10 as defaults, docs/wind.md "Many wires").
V = V_ref, one speed for the whole field as in the single-wire synthesis.  With ``combine="root"``
the wires' term is Simiu & Scanlan's sqrt(C_y^2 dy^2 + C_z^2 dz^2) instead of C_y |dy| + C_z |dz|
(equal for a separation along one axis; higher coherence for a diagonal one).  The across-line
separation y is along the mean wind when the wind blows square to the line; the model applies
the same real (zero-phase) exponential coherence to it (docs/wind.md "Many wires").

Factorisation.  Ordered wire-major, the coherence matrix of all n_w N points at frequency f is the
Kronecker product Gamma_w(f) (x) Gamma_x(f) of the wires' n_w x n_w matrix and the nodes' N x N
matrix, so L = L_w (x) L_x is a factor (L L^T = Gamma) and L xi = (L_w (x) I)(I (x) L_x) xi: each
wire's phasors go through the O(N) Markov recursion along x (the single-wire spectrum, unchanged),
then every node's n_w values are mixed by the small lower factor L_w(f).  Cost per frequency
O(n_w N) for the recursions and O(n_w^2 N) for the mixing; the n_w N x n_w N matrix is never formed.

Wire 0 is the single-wire field bit for bit: L_w is lower triangular with L_w[0] = (1, 0, ..., 0),
so wire 0's spectrum is not touched, and its phases are those of ``turbulence.unit_phases``.  Wire
w >= 1 draws its phases from child w of the realization's seed sequence
(``SeedSequence(seed, spawn_key=(r, w))``), independent of wire 0's stream.  Wire a's field depends
only on wires 0 .. a (their offsets and phases): appending a wire changes none of the others.
Wires at the same point (equal offsets) get the same field exactly (the first one's); nearly or
fully coherent wires (Gamma_w semidefinite) are factored by a Cholesky that gives zero columns
for zero pivots (:func:`semidefinite_cholesky`).

Work per realization (docs/performance.md "Every wire in one wind"): the spectral grid, L_w, the
along-line coefficients and a buffer of the points' spectra are made once per call and shared by
its realizations (the same values as made afresh); each distinct point's spectrum is written into
the buffer, the buffer is mixed in place (the piece ``mixing`` of the compiled kernel, or
:func:`mix_wires_numpy`: the same products summed in the same order), and each inverse FFT is
copied straight into the result.  The inverse FFTs (one per point, as the single-wire synthesis
has one) are most of the cost.

Layout: wire-major, a unit field of shape (n_w, n_steps, n_nodes) (``field[w]`` is the array the
single-wire code gives for that wire); velocities (n_w, n_real, n_steps, n_nodes).
Nothing here prints.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from .. import kernel
from ..case import Case
from ..errors import Cancelled, CaseError
from ..system import LineSystem
from . import turbulence as tb

__all__ = [
    "COMBINATIONS",
    "DECAY_Y",
    "DECAY_Z",
    "PIVOT_TOL",
    "CrossCoherence",
    "fluctuating_velocity_wires",
    "mix_wires_numpy",
    "semidefinite_cholesky",
    "synthesize_wires",
    "unit_field_wires",
    "wire_coherence",
    "wire_factor",
    "wire_phases",
    "wire_rng",
]

#: [-] decay constant of the coherence for horizontal separation across the line, C_y
#: (Simiu & Scanlan 1996, sec. 2.3, after Vellozzi & Cohen 1968; docs/wind.md "Many wires")
DECAY_Y = 16.0
#: [-] decay constant of the coherence for vertical separation, C_z (same source)
DECAY_Z = 10.0
#: how the across and vertical separations combine: "sum" exp(-f (C_y |dy| + C_z |dz|) / V) (a
#: product of one exponential per direction) or "root" exp(-f sqrt(C_y^2 dy^2 + C_z^2 dz^2) / V)
#: (Simiu & Scanlan 1996, sec. 2.3, their form); equal for a separation along one axis only
COMBINATIONS = ("sum", "root")
#: [-] a Cholesky pivot (a conditional variance, the diagonal being 1) at or below this is zero:
#: the wire is then fully explained by the wires before it at that frequency
PIVOT_TOL = 1e-12


# ------------------------------------------------------------------------- the wires' factor
def _offsets(offsets: np.ndarray) -> np.ndarray:
    off = np.asarray(offsets, dtype=float)
    if off.ndim != 2 or off.shape[1] != 2 or off.shape[0] < 1:
        raise ValueError(f"wire offsets of shape {off.shape}: expected (n_wires, 2) = (y, z) [m]")
    if not np.all(np.isfinite(off)):
        raise ValueError("wire offsets must be finite")
    return off


@dataclass(frozen=True)
class CrossCoherence:
    """The coherence of the wires across the line and in height (docs/wind.md "Many wires").

    decay_y, decay_z: [-] C_y, C_z >= 0 (0: fully coherent in that direction); combine: one of
    :data:`COMBINATIONS`."""

    decay_y: float = DECAY_Y
    decay_z: float = DECAY_Z
    combine: str = "sum"

    def __post_init__(self):
        if not (self.decay_y >= 0 and self.decay_z >= 0 and math.isfinite(self.decay_y + self.decay_z)):
            raise ValueError(f"coherence decay constants must be finite and >= 0: got C_y={self.decay_y}, "
                             f"C_z={self.decay_z}")
        if self.combine not in COMBINATIONS:
            raise ValueError(f"combine {self.combine!r}: expected one of {COMBINATIONS}")


def wire_coherence(freq: np.ndarray, offsets: np.ndarray, v_mean: float,
                   cross: CrossCoherence | None = None) -> np.ndarray:
    """Coherence of the wires' points [-] at f [Hz] (n_freq,): shape (n_w, n_w, n_freq).

    offsets [m] (n_w, 2) = (y, z); V [m/s]; ``cross`` the constants (default :class:`CrossCoherence`).
    "sum": Gamma_ab = exp(-f (C_y |y_a - y_b| + C_z |z_a - z_b|) / V), the product of two exponential
    coherences with one constant per direction (Davenport 1961); "root": exp(-f sqrt(C_y^2 dy^2 +
    C_z^2 dz^2) / V) (Simiu & Scanlan 1996, sec. 2.3).  Both are positive semidefinite (a product of
    two exponential kernels, Schur product theorem; an exponential kernel of a scaled distance).
    """
    cross = CrossCoherence() if cross is None else cross
    off = _offsets(offsets)
    dy = np.abs(off[:, None, 0] - off[None, :, 0])
    dz = np.abs(off[:, None, 1] - off[None, :, 1])
    if cross.combine == "sum":
        reach = cross.decay_y * dy + cross.decay_z * dz  # [m] C_y |dy| + C_z |dz| (Davenport 1961)
    else:
        reach = np.hypot(cross.decay_y * dy, cross.decay_z * dz)  # [m] Simiu & Scanlan (1996), sec. 2.3
    # exponential coherence exp(-f reach / V) (Davenport 1961)
    return np.exp(-reach[:, :, None] * np.asarray(freq, dtype=float)[None, None, :] / v_mean)


def semidefinite_cholesky(c: np.ndarray, tol: float = PIVOT_TOL) -> np.ndarray:
    """Lower factor L with L L^T = c of symmetric positive semidefinite matrices, one per frequency.

    c shape (n, n, n_freq) (matrix first, frequency last) -> L same shape, lower triangular in the
    first two axes.  Column-by-column Cholesky (Golub & Van Loan 2013, sec. 4.2) in which a pivot
    d_j = c_jj - sum_(k<j) L_jk^2 <= ``tol`` gives a zero column (L_jj = 0 and L_ij = 0 below): for a
    semidefinite matrix the Schur complement's column is then zero too, so nothing is lost.  Fully
    coherent points (c all ones) give L[:, 0] = 1 and zero columns elsewhere, i.e. identical fields.
    """
    c = np.asarray(c, dtype=float)
    n = c.shape[0]
    low = np.zeros_like(c)
    for j in range(n):
        d = c[j, j] - np.sum(low[j, :j] ** 2, axis=0)
        keep = d > tol
        low[j, j] = np.sqrt(np.where(keep, d, 0.0))
        for i in range(j + 1, n):
            num = c[i, j] - np.sum(low[i, :j] * low[j, :j], axis=0)
            np.divide(num, low[j, j], out=low[i, j], where=keep)  # zero where the pivot is zero
    return low


def wire_factor(freq: np.ndarray, offsets: np.ndarray, v_mean: float,
                cross: CrossCoherence | None = None) -> np.ndarray:
    """The lower factor L_w(f) of :func:`wire_coherence` [-], shape (n_w, n_w, n_freq).

    Row 0 is (1, 0, ..., 0) at every frequency (wire 0 is the single-wire field)."""
    return semidefinite_cholesky(wire_coherence(freq, offsets, v_mean, cross))


def _distinct_points(off: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first wire at each distinct offset, in order of appearance (n_p,), and each wire's point
    index (n_w,): wires at equal offsets share one point, hence one field, exactly."""
    first: list[int] = []
    point = np.empty(off.shape[0], dtype=np.int64)
    for w in range(off.shape[0]):
        same = [p for p, f in enumerate(first) if np.array_equal(off[f], off[w])]
        if same:
            point[w] = same[0]
        else:
            point[w] = len(first)
            first.append(w)
    return np.asarray(first, dtype=np.int64), point


# ------------------------------------------------------------------------- randomness
def wire_rng(seed: int, realization: int, wire: int) -> np.random.Generator:
    """The generator of wire w >= 1 in realization r: child w of the realization's seed sequence,
    ``SeedSequence(seed, spawn_key=(r, w))`` (= ``SeedSequence(seed, spawn_key=(r,)).spawn(w + 1)[w]``).
    Wire 0 uses the realization's own stream (``turbulence.realization_rng``); child 0 is unused."""
    if realization < 0:
        raise CaseError(f"realization {realization} is not allowed: expected an index >= 0")
    if wire < 1:
        raise ValueError(f"wire {wire}: wire 0 draws from turbulence.realization_rng")
    ss = np.random.SeedSequence(int(seed), spawn_key=(int(realization), int(wire)))
    return np.random.Generator(np.random.PCG64(ss))


def wire_phases(seed: int, realization: int, wires: Sequence[int], n_nodes: int, n_freq: int) -> list[tb.UnitPhases]:
    """The random phases [rad] (n_nodes, n_freq) of the given wires, as :class:`turbulence.UnitPhases`
    (with the compiled kernel's phasors when it is on).  Wire 0: ``turbulence.unit_phases`` (the
    single-wire phases, memo included); wire w >= 1: uniform on [0, 2 pi) from :func:`wire_rng`."""
    out = []
    for w in wires:
        if w == 0:
            out.append(tb.unit_phases(seed, realization, n_nodes, n_freq))
            continue
        phases = wire_rng(seed, realization, int(w)).random((n_nodes, n_freq)) * (2.0 * math.pi)
        out.append(tb.UnitPhases(phases, kernel.phasors(phases)))
    return out


# ------------------------------------------------------------------------- synthesis
def _resolve(x: np.ndarray, method: str) -> tuple[str, float | None]:
    spacing = tb.uniform_spacing(x)  # turbulence.synthesize's rule: wire 0 takes its path
    if method == "auto":
        method = "kms" if spacing is not None else ("markov" if np.all(np.diff(x) >= 0) else "general")
    if method not in ("kms", "markov", "general"):
        raise ValueError(f"unknown method {method!r}")
    if method == "kms" and spacing is None:
        raise ValueError("the KMS path needs equally spaced, increasing x")
    return method, spacing


def mix_wires_numpy(spec: np.ndarray, low: np.ndarray, k0: int) -> None:
    """(L_w (x) I) y per frequency, in place: the numpy form of ``kernel.mix_wires`` (piece ``mixing``).

    spec (n_p, n_nodes, n_bins) complex, C-ordered: each distinct point's single-wire spectrum;
    low [-] (n_p, n_p, n_freq) the lower factor L_w(f) (:func:`wire_factor`).  Bins k0 .. k0 +
    n_freq - 1 of point p >= 1 become sum_(q <= p) L_w[p, q](f) times point q's raw bins (a real
    factor on the real and imaginary parts, summed from zero over q in order); point 0 and the
    other bins are not touched.  Points in descending order, so that the raw spectra of the
    points before p are still there when p is mixed."""
    n_p, n_nodes = spec.shape[:2]
    n_freq = low.shape[2]
    k = slice(k0, k0 + n_freq)
    pairs = spec.view(float).reshape(n_p, n_nodes, -1, 2)
    acc, term = np.empty((n_nodes, n_freq, 2)), np.empty((n_nodes, n_freq, 2))
    for p in range(n_p - 1, 0, -1):
        acc[...] = 0.0
        for q in range(p + 1):
            # point p's value = sum_(q<=p) L_w[p, q](f) times point q's (the Kronecker factor's rows)
            np.multiply(low[p, q][None, :, None], pairs[q, :, k], out=term)
            acc += term
        pairs[p, :, k] = acc


@dataclass(frozen=True, eq=False)
class _Along:
    """The along-line recursion of every wire (the same for all wires and realizations): the
    path (``turbulence.synthesize``'s rule), the neighbours' coherence rows (n_rows, n_freq), the
    row of every gap (n_nodes - 1,) and the innovation weights sqrt(max(1 - rho^2, 0)) of the rows
    (None on the dense "general" path)."""

    method: str
    rows: np.ndarray | None
    gap: np.ndarray | None
    s_rows: np.ndarray | None


def _along(x: np.ndarray, grid: tb.SpectralGrid, decay: float, v_mean: float, method: str) -> _Along:
    method, spacing = _resolve(x, method)
    if method == "kms":
        rows = tb.davenport_coherence(grid.freq, spacing, decay, v_mean)[None, :]  # Davenport (1961), neighbours
        gap = np.zeros(max(x.size - 1, 0), dtype=np.int64)
    elif method == "markov":
        rows, gap = tb.gap_rows(x, grid.freq, decay, v_mean)
    else:
        return _Along(method, None, None, None)
    rows = np.ascontiguousarray(rows, dtype=float)
    # the kernel's innovation weights (kernel.coherent_spectrum computes the same values per call)
    return _Along(method, rows, gap, np.sqrt(np.maximum(1.0 - rows * rows, 0.0)))


def _wire_spectrum(x: np.ndarray, grid: tb.SpectralGrid, phases: tb.UnitPhases | np.ndarray, decay: float,
                   v_mean: float, along: _Along, out: np.ndarray) -> None:
    """Fill out (n_nodes, n_fft // 2 + 1) complex (zero outside bins 1 .. n_freq) with one wire's
    inverse-FFT input, exactly as ``turbulence.synthesize`` builds it (the same calls on the same
    values): the along-line factor L_x applied to the unit phasors, scaled by (m/2) A_k
    (Deodatis 1996)."""
    given = phases
    if isinstance(phases, tb.UnitPhases):
        phases, given = phases.phases, (phases.phasors if phases.phasors is not None else phases.phases)
    m = grid.n_fft
    if along.method == "general":
        y = tb.general_apply(x, grid.freq, np.exp(1j * phases), decay, v_mean)
    elif kernel.coherent_spectrum(given, along.rows, along.gap, grid.amplitude, m, s_rows=along.s_rows,
                                  out=out) is not None:
        return
    elif along.method == "kms":
        y = tb.kms_apply(along.rows[0], np.exp(1j * phases))
    else:
        y = tb.markov_apply(x, grid.freq, np.exp(1j * phases), decay, v_mean)
    out[...] = tb.fft_input(y, grid.amplitude, m)


def _to_time(spec: np.ndarray, grid: tb.SpectralGrid, lead: int, out: np.ndarray) -> None:
    """out (lead + n_steps, n_nodes) = the inverse FFT of one wire's spectrum, its first n_steps
    samples after ``lead`` samples of periodic continuation (as ``turbulence.synthesize``: the
    same transform, its samples copied into place without an intermediate array)."""
    m, n = grid.n_fft, grid.n_steps
    full = sfft.irfft(spec, n=m, axis=1)
    if lead > m:  # the continuation wraps more than once
        out[...] = np.take(full, np.arange(-lead, n), axis=1, mode="wrap").T
        return
    out[lead:] = full[:, :n].T
    if lead:
        out[:lead] = full[:, m - lead:].T  # samples m - lead .. m - 1: the period before t_0


class _Synthesis:
    """What every realization of one field shares: the distinct points, their factor L_w per
    frequency, the along-line coefficients and the buffer of the points' spectra (n_p, n_nodes,
    n_fft // 2 + 1), zero outside the simulated bins (each realization overwrites those)."""

    def __init__(self, x: np.ndarray, off: np.ndarray, grid: tb.SpectralGrid, decay: float, v_mean: float,
                 cross: CrossCoherence | None, method: str) -> None:
        self.x, self.grid, self.decay, self.v_mean = x, grid, decay, v_mean
        self.along = _along(x, grid, decay, v_mean, method)
        self.first, self.point = _distinct_points(off)
        self.low = wire_factor(grid.freq, off[self.first], v_mean, cross)  # (n_p, n_p, n_freq)
        self.spec = np.zeros((self.first.size, x.size, grid.n_fft // 2 + 1), dtype=complex)

    def __call__(self, phases: Sequence[tb.UnitPhases | np.ndarray | None], lead: int, out: np.ndarray) -> None:
        """out (n_w, lead + n_steps, n_nodes) = the field of these phases (one entry per wire;
        only the first wire at each point is read)."""
        x, grid = self.x, self.grid
        for p, w in enumerate(self.first):
            ph = phases[w]
            shape = (ph.phases if isinstance(ph, tb.UnitPhases) else np.asarray(ph)).shape
            if shape != (x.size, grid.n_freq):
                raise ValueError(f"wire {w}: phases shape {shape} != {(x.size, grid.n_freq)}")
            _wire_spectrum(x, grid, ph, self.decay, self.v_mean, self.along, self.spec[p])
        if self.first.size > 1:
            # (L_w (x) I) y: the simulated bins 1 .. n_freq mixed across points (the others are zero)
            kernel.mix_wires(self.spec, self.low, 1)
        for p, w in enumerate(self.first):
            _to_time(self.spec[p], grid, lead, out[w])
        for w in range(out.shape[0]):
            if self.first[self.point[w]] != w:
                out[w] = out[self.first[self.point[w]]]  # the same point: the same field


def synthesize_wires(x: np.ndarray, offsets: np.ndarray, grid: tb.SpectralGrid,
                     phases: Sequence[tb.UnitPhases | np.ndarray], decay: float, v_mean: float,
                     cross: CrossCoherence | None = None, method: str = "auto", lead: int = 0) -> np.ndarray:
    """Unit-variance field of n_w wires at stations x [m]: shape (n_w, lead + n_steps, n_nodes).

    x [m] (n_nodes,), the stations every wire's nodes share; offsets [m] (n_w, 2) = (y, z) across
    the line and up; phases: one per wire, each (n_nodes, n_freq) [rad] or ``UnitPhases`` (the
    entry of a wire at the same point as an earlier wire is not used and may be None);
    C_x = ``decay`` [-]; V [m/s]; ``cross``: C_y, C_z and their combination (default
    :class:`CrossCoherence`); ``method`` and ``lead`` as ``turbulence.synthesize`` (wire 0 is its
    result bit for bit).  Per frequency f_k: y = (L_w(f_k) (x) L_x(f_k)) xi_k, the single-wire
    spectrum of each distinct point mixed across wires by the lower factor L_w (Deodatis 1996;
    docs/wind.md "Many wires").
    """
    x = np.asarray(x, dtype=float)
    off = _offsets(offsets)
    if len(phases) != off.shape[0]:
        raise ValueError(f"{len(phases)} phase arrays for {off.shape[0]} wires")
    out = np.empty((off.shape[0], lead + grid.n_steps, x.size))
    _Synthesis(x, off, grid, decay, v_mean, cross, method)(phases, lead, out)
    return out


# ------------------------------------------------------------------------- case-level API
def _stations(system: LineSystem) -> np.ndarray:
    return system.node_station if system.is_section else system.node_x0


def _setup(case: Case, system: LineSystem, off: np.ndarray, n_steps: int, dt: float,
           cross: CrossCoherence | None) -> _Synthesis:
    """The field's shared part for the case's wind on ``system``'s stations (as ``turbulence.unit_field``)."""
    x = _stations(system)
    v = float(case.wind.v_ref)
    if not v > 0:
        raise CaseError("value 0.0 is not allowed for turbulence synthesis: expected v_ref > 0",
                        file=str(case.source) if case.source else None, key="wind.v_ref")
    grid = tb.spectral_grid(int(n_steps), float(dt), tb.length_scale(case), v, case.wind.fft_length == "fast")
    return _Synthesis(x, off, grid, case.wind.coherence_decay, v, cross, "auto")


def _realization_phases(case: Case, synth: _Synthesis, n_w: int, realization: int) -> list:
    """Realization r's phases of the first wire at each point (None for the others)."""
    phases: list = [None] * n_w
    first = [int(f) for f in synth.first]
    for w, ph in zip(first, wire_phases(case.analysis.seed, realization, first, synth.x.size, synth.grid.n_freq)):
        phases[w] = ph
    return phases


def unit_field_wires(case: Case, system: LineSystem, offsets: np.ndarray, n_steps: int, dt: float,
                     realization: int, lead: int = 0, cross: CrossCoherence | None = None) -> np.ndarray:
    """Zero-mean, unit-variance turbulence of n_w wires [-]: shape (n_w, lead + n_steps, n_nodes).

    ``system``: the mesh every wire shares (its stations, as ``turbulence.unit_field``); offsets
    [m] (n_w, 2) = (y, z); n_steps samples at dt [s] after ``lead`` samples of periodic lead-in;
    realization 0-based; ``cross`` as :func:`synthesize_wires`.  Wire 0 equals
    ``turbulence.unit_field`` bit for bit; the spectrum, L_u, C_x = ``wind.coherence_decay`` and
    V = V_ref are the case's.
    """
    off = _offsets(offsets)
    synth = _setup(case, system, off, n_steps, dt, cross)
    out = np.empty((off.shape[0], lead + synth.grid.n_steps, synth.x.size))
    synth(_realization_phases(case, synth, off.shape[0], realization), lead, out)
    return out


def fluctuating_velocity_wires(case: Case, system: LineSystem, offsets: np.ndarray, time: np.ndarray,
                               realizations: Sequence[int], a: np.ndarray | None = None, lead: int = 0,
                               cancel=None, cross: CrossCoherence | None = None) -> np.ndarray:
    """Fluctuating along-wind velocity a u [m/s] of n_w wires: shape (n_w, n_real, n_steps, n_nodes).

    As ``turbulence.fluctuating_velocity`` (time [s] (n_steps,) with its first ``lead`` samples a
    burn-in continued periodically; ``cancel`` checked before each realization) for the wires at
    ``offsets`` [m] (n_w, 2).  ``a`` [m/s]: the modulation, (n_w, n_steps, n_nodes) for each wire's
    own running mean (downbursts: I V_m at that wire's nodes) or anything that broadcasts to it;
    default ``turbulence.modulation(case, system, time)`` for every wire.  Wire 0 with that
    modulation equals ``turbulence.fluctuating_velocity`` bit for bit.  Each realization's field
    is synthesized in place in the result; the spectral grid, the factors and the spectra's buffer
    are shared by the realizations (the same values as computed afresh).
    """
    n_steps, dt = tb.record_axis(time)
    if not 0 <= lead < n_steps - 3:
        raise ValueError(f"lead of {lead} samples does not fit a record of {n_steps}")
    off = _offsets(offsets)
    if a is None:
        a = tb.modulation(case, system, np.asarray(time, dtype=float))
    a = np.asarray(a, dtype=float)
    if a.ndim == 3 and a.shape[0] not in (1, off.shape[0]):
        raise ValueError(f"modulation of shape {a.shape} for {off.shape[0]} wires")
    per_wire = a.ndim == 3 and a.shape[0] > 1  # else one modulation broadcast to every wire
    if a.ndim == 3 and not per_wire:
        a = a[0]
    unit = not per_wire and a.size == 1 and float(a.reshape(-1)[0]) == 1.0  # u * 1.0 is u: skip the pass
    synth = _setup(case, system, off, n_steps - lead, dt, cross)
    reals = list(realizations)
    out = np.empty((off.shape[0], len(reals), n_steps, system.n_nodes))
    for i, r in enumerate(reals):
        if cancel is not None and cancel.is_set():
            raise Cancelled("run cancelled")
        synth(_realization_phases(case, synth, off.shape[0], int(r)), int(lead), out[:, i])
        if unit:
            continue
        for w in range(off.shape[0]):
            out[w, i] *= a[w] if per_wire else a
    return out


# ---- the compiled kernel's piece ``mixing`` (linecheck.core.kernel): its load check

def _mixing_check(fns) -> float:
    """The compiled mixing (``fns.mix_wires``) against :func:`mix_wires_numpy` on random spectra
    of five points, two of them nearly coincident (zero pivots: zero columns of L_w); the largest
    relative difference."""
    rng = np.random.default_rng(26)
    n_nodes, n_freq = 7, 97
    freq = np.arange(1, n_freq + 1) * 0.02
    off = np.array([[0.0, 0.0], [-6.5, 2.0], [6.5, 2.0], [0.0, 9.0], [0.0, 9.0 + 1e-9]])
    low = wire_factor(freq, off, 30.0)
    spec = np.zeros((off.shape[0], n_nodes, n_freq + 2), dtype=complex)
    spec[:, :, 1:n_freq + 1] = rng.standard_normal((off.shape[0], n_nodes, n_freq)) + 1j * rng.standard_normal(
        (off.shape[0], n_nodes, n_freq))
    ref, got = spec.copy(), spec.copy()
    mix_wires_numpy(ref, low, 1)
    fns.mix_wires(got, low, 1)
    return kernel.worst_difference([(ref.view(float), got.view(float))])


kernel.register_check("mixing", _mixing_check, numpy=mix_wires_numpy)
