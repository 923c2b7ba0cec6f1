"""Turbulence synthesis along the line (paper section 2.2; Chen & Letchford 2004; Chay et al. 2006).

A zero-mean, unit-variance, stationary Gaussian field u(x, t) is synthesised at every
global FE node (still-air x = ``system.node_x0``) by the spectral representation
method (Shinozuka & Deodatis 1991; Deodatis 1996) evaluated with the FFT, then
modulated by a(x, t) = I V_m(x, t) (downburst) or I V_ref (synoptic) (Chay et al. 2006).

Conventions: one-sided spectra in [1/Hz] normalised by the variance; frequencies f in
[Hz]; a field array has shape (n_steps, n_nodes).

- Spectrum: von Karman (1948), n S(n) / sigma^2 = 4 x / (1 + 70.8 x^2)^(5/6), x = n L_u / V.
- Coherence: Davenport (1961/1986), gamma(n, dx) = exp(-C n dx / V), C = ``coherence_decay``.
- V = V_ref (one mean speed for the whole field); L_u from :func:`length_scale`.

Discretisation: the record of n_steps samples at dt is one period of an FFT of
length M = n_steps; bin k (f_k = k / (M dt), k = 1 .. ceil(M/2) - 1) carries the
spectrum integrated over [f_k - df/2, f_k + df/2] (closed form, incomplete beta
function); the variance below df/2 is added to bin 1 and the bins are scaled so that
they sum to exactly 1 (unit variance: the variance above the highest bin, about 1 %
at dt = 0.05 s, is redistributed proportionally; see ``docs/wind.md``).

Cross-correlation: at each frequency the coherence matrix of the nodes is factored
C = L L^T and the node coefficients are B_j = A_k sum_m L_jm exp(i phi_mk) with
independent uniform phases phi (Deodatis 1996).  For equally spaced nodes
C_jm = rho^|j-m| with rho = exp(-C f dx / V) (Kac-Murdock-Szego matrix), whose
Cholesky factor is closed form (L_j0 = rho^j, L_jm = rho^(j-m) sqrt(1 - rho^2)): applying
it is the AR(1) recursion y_j = rho y_(j-1) + sqrt(1 - rho^2) xi_j, O(N) per frequency
and vectorised over frequencies.  Ordered points at any spacing (a line section of unequal
spans) use the same recursion with a coefficient per gap, rho_j = exp(-C f ds_j / V)
(:func:`markov_apply`): exponential coherence along ordered points is Markov, so the
coherence of nodes j < m is the product of the gap coefficients, exp(-C f (x_m - x_j) / V),
exactly the Davenport coherence at the separation measured along the line.  The dense
Cholesky per frequency (:func:`general_apply`, eigen-decomposition fallback) remains for
unordered points and as the reference.  On a section the points are the nodes' stations
(distance along the line); across an angle tower the straight plan distance is shorter, and
the error this makes in the coherence is measured in docs/wind.md ("Sections").

Randomness: realization r uses ``numpy.random.Generator(PCG64(SeedSequence(seed).spawn(r + 1)[r]))``
only, so its field is bit-identical whatever else is generated and in any process.
Nothing here prints.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import fft as sfft
from scipy.linalg import LinAlgError, cholesky, eigh
from scipy.special import beta as beta_fn
from scipy.special import betainc

from .. import kernel
from ..case import Case
from ..errors import Cancelled, CaseError
from ..system import LineSystem
from .mean import mean_normal_at_nodes, mean_speed_at_nodes

__all__ = [
    "VON_KARMAN_A",
    "SpectralGrid",
    "davenport_coherence",
    "fft_input",
    "fluctuating_velocity",
    "gap_coherence",
    "gap_rows",
    "general_apply",
    "kms_apply",
    "length_scale",
    "markov_apply",
    "markov_quadratic_form",
    "mean_normal_at_nodes",
    "mean_speed_at_nodes",
    "modulation",
    "random_phases",
    "realization_rng",
    "spectral_grid",
    "synthesize",
    "unit_field",
    "von_karman_cumulative",
    "von_karman_psd",
]

VON_KARMAN_A = 70.8  # von Karman (1948) longitudinal spectrum constant
SYNOPTIC_L_UV = 52.0  # [m] ASCE 74 (2010), open terrain (paper section 2.2)
L_UV_OVER_L_U = 0.3  # paper section 2.2: L_u = L_uv / 0.3


# ------------------------------------------------------------------------- model functions
def length_scale(case: Case) -> float:
    """von Karman length scale L_u [m]: ``wind.length_scale``, else synoptic L_uv/0.3 = 52/0.3 m
    (ASCE 74 open terrain, paper section 2.2), downburst D_j (Chay et al. 2006, paper section 2.2)."""
    if case.wind.length_scale is not None:
        return float(case.wind.length_scale)
    if case.wind.type == "downburst":
        if case.wind.downburst is None:  # pragma: no cover - guarded by the case loader
            raise CaseError("missing table [wind.downburst]", key="wind.downburst")
        return float(case.wind.downburst.jet_diameter)  # Chay et al. (2006): L_u = D_j
    return SYNOPTIC_L_UV / L_UV_OVER_L_U  # paper section 2.2: L_u = L_uv / 0.3, L_uv = 52 m (ASCE 74)


def von_karman_psd(f: np.ndarray | float, length_scale: float, v_mean: float) -> np.ndarray:
    """One-sided von Karman spectrum S(f)/sigma^2 [1/Hz] at f [Hz]; L_u [m], V [m/s]."""
    x = np.asarray(f, dtype=float) * length_scale / v_mean
    # von Karman (1948): n S(n)/sigma^2 = 4 x / (1 + 70.8 x^2)^(5/6), x = n L_u / V
    return 4.0 * (length_scale / v_mean) / (1.0 + VON_KARMAN_A * x * x) ** (5.0 / 6.0)


def von_karman_cumulative(f: np.ndarray | float, length_scale: float, v_mean: float) -> np.ndarray:
    """Variance fraction below f [Hz]: int_0^f S(f')/sigma^2 df' [-] (closed form).

    int_0^x 4 (1 + a s^2)^(-5/6) ds = (2/sqrt(a)) B(1/2, 1/3) I_w(1/2, 1/3), w = a x^2 / (1 + a x^2)
    (substitution w = a s^2/(1 + a s^2); I the regularised incomplete beta function).
    The limit f -> inf is 0.99986 (the 70.8 constant rounds the exact von Karman value).
    """
    x = np.asarray(f, dtype=float) * length_scale / v_mean
    a = VON_KARMAN_A
    ax2 = a * x * x
    w = np.where(np.isinf(ax2), 1.0, ax2 / (1.0 + np.where(np.isinf(ax2), 0.0, ax2)))
    return (2.0 / math.sqrt(a)) * beta_fn(0.5, 1.0 / 3.0) * betainc(0.5, 1.0 / 3.0, w)


def davenport_coherence(f: np.ndarray | float, dx: np.ndarray | float, decay: float, v_mean: float) -> np.ndarray:
    """Davenport coherence [-] at f [Hz] and separation dx [m] (broadcast); C [-], V [m/s]."""
    # Davenport (1961; 1986): gamma = exp(-C n |dx| / V)
    return np.exp(-decay * np.asarray(f, dtype=float) * np.abs(np.asarray(dx, dtype=float)) / v_mean)


# ------------------------------------------------------------------------- discretisation
@dataclass(frozen=True, eq=False)
class SpectralGrid:
    """Frequency discretisation of one record.

    Attributes:
        n_steps: samples in the record; dt: [s] time step; n_fft: FFT length (= n_steps, or the
            next 5-smooth length with ``fft_length = "fast"``; the first n_steps samples are used).
        df: [Hz] frequency step 1/(n_fft dt).
        freq: [Hz] simulated frequencies f_k = k df, k = 1 .. n_freq, shape (n_freq,).
        amplitude: [-] cosine amplitude sqrt(2 P_k) of each bin (sum P_k = 1), shape (n_freq,).
        low_fraction: [-] von Karman variance below df/2, carried by the first bin.
        high_fraction: [-] von Karman variance above the last bin edge (n_freq + 1/2) df,
            removed by scaling all bins up by 1/(1 - high_fraction).
    """

    n_steps: int
    dt: float
    n_fft: int
    df: float
    freq: np.ndarray
    amplitude: np.ndarray
    low_fraction: float
    high_fraction: float

    @property
    def n_freq(self) -> int:
        return int(self.freq.size)


@lru_cache(maxsize=32)
def spectral_grid(n_steps: int, dt: float, length_scale: float, v_mean: float, fast: bool = False) -> SpectralGrid:
    """Bins and amplitudes for ``n_steps`` samples at ``dt`` [s] (cached; arrays read-only).

    Bin k carries P_k = int over [f_k - df/2, f_k + df/2] of S(f)/sigma^2 df (exact, closed
    form); bin 1 also carries the variance below df/2 (a record of length T cannot hold it
    otherwise); all bins are divided by the variance below the last edge so sum P_k = 1.
    """
    if n_steps < 4:
        raise CaseError(f"record of {n_steps} samples is too short: expected at least 4 time steps",
                        key="analysis.duration")
    if not (dt > 0 and math.isfinite(dt)):
        raise CaseError(f"time step {dt!r} is not allowed: expected a positive number", key="analysis.time_step")
    # the transform as long as the record (the paper cases), or with ``fast`` the next length
    # >= n_steps whose prime factors are 2, 3 and 5 only (scipy.fft.next_fast_len, real
    # transforms): a record of 12,001 samples (= 11 x 1091) takes pocketfft's Bluestein
    # algorithm, ≈ 7x slower than 12,000; the first n_steps samples of the periodic synthesis
    # are used (docs/wind.md, "Synthesis length")
    n_fft = sfft.next_fast_len(int(n_steps), real=True) if fast else int(n_steps)
    df = 1.0 / (n_fft * dt)
    n_freq = (n_fft - 1) // 2  # k = 1 .. ceil(M/2) - 1: no DC, no Nyquist term
    edges = (np.arange(n_freq + 1, dtype=float) + 0.5) * df
    cum = von_karman_cumulative(edges, length_scale, v_mean)
    total = float(von_karman_cumulative(np.inf, length_scale, v_mean))
    power = np.diff(cum)  # exact band integral of the von Karman spectrum per bin
    power[0] += cum[0]  # variance below df/2 goes to the lowest simulated frequency
    power = power / cum[-1]  # unit variance of the discrete process (docs/wind.md)
    amplitude = np.sqrt(2.0 * power)  # variance of A cos(.) is A^2/2 = P_k
    freq = np.arange(1, n_freq + 1, dtype=float) * df
    freq.setflags(write=False)
    amplitude.setflags(write=False)
    return SpectralGrid(int(n_steps), float(dt), n_fft, df, freq, amplitude,
                        low_fraction=float(cum[0] / total), high_fraction=float(1.0 - cum[-1] / total))


def realization_rng(seed: int, realization: int) -> np.random.Generator:
    """The generator of realization r (0-based): ``SeedSequence(seed).spawn(r + 1)[r]``.

    Equal to ``SeedSequence(seed, spawn_key=(r,))``, which is what is built (O(1)).
    """
    if realization < 0:
        raise CaseError(f"realization {realization} is not allowed: expected an index >= 0")
    ss = np.random.SeedSequence(int(seed), spawn_key=(int(realization),))
    return np.random.Generator(np.random.PCG64(ss))


def random_phases(seed: int, realization: int, n_nodes: int, n_freq: int) -> np.ndarray:
    """Independent phases phi_mk uniform on [0, 2 pi) [rad], shape (n_nodes, n_freq)."""
    return realization_rng(seed, realization).random((n_nodes, n_freq)) * (2.0 * math.pi)


def kms_apply(rho: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """y = L xi with L the Cholesky factor of the KMS matrix rho^|j-m|, per frequency.

    rho [-] shape (n_freq,) in [0, 1]; xi shape (n_nodes, n_freq) (complex) -> y same shape.
    L_j0 = rho^j, L_jm = rho^(j-m) sqrt(1 - rho^2) (1 <= m <= j), i.e. the AR(1) recursion
    y_0 = xi_0, y_j = rho y_(j-1) + sqrt(1 - rho^2) xi_j (Kac, Murdock & Szego 1953).
    """
    rho = np.asarray(rho, dtype=float)
    s = np.sqrt(np.maximum(1.0 - rho * rho, 0.0))
    y = np.empty_like(xi)
    y[0] = xi[0]
    prev = y[0]
    for j in range(1, xi.shape[0]):
        # closed-form KMS Cholesky factor (docs/wind.md, derivation): AR(1) recursion along the nodes
        prev = rho * prev + s * xi[j]
        y[j] = prev
    return y


def markov_apply(x: np.ndarray, freq: np.ndarray, xi: np.ndarray, decay: float, v_mean: float) -> np.ndarray:
    """y_k = L_k xi_k with L_k the Cholesky factor of exp(-C f_k |x_j - x_m| / V) for ordered x.

    x [m] shape (n_nodes,), non-decreasing (any spacing); freq [Hz] (n_freq,); xi (n_nodes, n_freq)
    complex -> y same shape.  Exponential coherence along ordered points is Markov: with the gap
    coefficients rho_j = exp(-C f (x_j - x_(j-1)) / V) the recursion y_0 = xi_0,
    y_j = rho_j y_(j-1) + sqrt(1 - rho_j^2) xi_j gives unit variance and
    E[y_j y_m*] = prod_(j<i<=m) rho_i = exp(-C f (x_m - x_j) / V) (Davenport 1961), i.e. the
    Cholesky factor of the coherence matrix (the KMS factor of :func:`kms_apply` generalised to
    unequal gaps).  O(N) per frequency; a coefficient row per distinct gap is computed once.
    """
    rows, row = gap_rows(x, freq, decay, v_mean)
    s = np.sqrt(np.maximum(1.0 - rows * rows, 0.0))  # the innovation weight of every row
    y = np.empty_like(xi)
    y[0] = xi[0]
    prev = y[0]
    for j in range(1, xi.shape[0]):
        g = row[j - 1]
        # AR(1) step with the gap's coefficient (Markov property of exp(-a |dx|))
        prev = rows[g] * prev + s[g] * xi[j]
        y[j] = prev
    return y


def gap_rows(x: np.ndarray, freq: np.ndarray, decay: float, v_mean: float) -> tuple[np.ndarray, np.ndarray]:
    """Davenport (1961) coherence of neighbours rho = exp(-C f ds / V) [-] for every distinct gap ds
    of ordered points x [m] (n_nodes,) at f [Hz] (n_freq,): rows (n_rows, n_freq) and the row of
    every gap (n_nodes - 1,) (int64).  The Markov recursion's coefficients (:func:`markov_apply`,
    the compiled ``kernel.coherent_spectrum``); raises ValueError for unordered x."""
    gaps, row = np.unique(np.diff(np.asarray(x, dtype=float)), return_inverse=True)
    if gaps.size and gaps[0] < 0:
        raise ValueError("the Markov path needs ordered (non-decreasing) x")
    rows = davenport_coherence(np.asarray(freq, dtype=float)[None, :], gaps[:, None], decay, v_mean)
    return rows, row.astype(np.int64)


def fft_input(y: np.ndarray, amplitude: np.ndarray, m: int) -> np.ndarray:
    """The inverse FFT's input of :func:`synthesize` from the correlated phasors y (n_nodes, n_freq):
    (n_nodes, m // 2 + 1) complex, column k = (m/2) A_k y_k for k = 1 .. n_freq, zero elsewhere."""
    spec = np.zeros((y.shape[0], m // 2 + 1), dtype=complex)
    # Deodatis (1996) spectral sum by FFT: irfft gives (1/M)(X_k e^{..} + conj) = A_k cos(..) for X_k = (M/2) A_k e^{i psi}
    spec[:, 1:y.shape[1] + 1] = (0.5 * m) * (amplitude[None, :] * y)
    return spec


def gap_coherence(x: np.ndarray, freq: np.ndarray, decay: float, v_mean: float) -> np.ndarray:
    """Davenport coherence of neighbouring points rho_j = exp(-C f (x_j - x_(j-1)) / V) [-] for
    ordered x [m] (n_nodes,) at f [Hz] (n_f,), shape (n_nodes - 1, n_f) (Davenport 1961)."""
    gaps = np.diff(np.asarray(x, dtype=float))
    return davenport_coherence(np.asarray(freq, dtype=float)[None, :], gaps[:, None], decay, v_mean)


def markov_quadratic_form(w: np.ndarray, rho_gaps: np.ndarray) -> np.ndarray:
    """w^H Coh w [-] for the Markov coherence Coh_jm = prod of the gap coefficients between j and m
    (Davenport coherence at separations along ordered points, any spacing), O(N) per frequency.

    w (..., N, n_f) complex (node axis second to last, frequency last); rho_gaps (N - 1, n_f) from
    :func:`gap_coherence`.  Returns (..., n_f) real.  With h_j = sum_(i<j) Coh_ij w_i the recursion
    h_j = rho_j (h_(j-1) + w_(j-1)) holds because Coh_ij = Coh_i,j-1 rho_j (Markov property), and
    w^H Coh w = sum |w_j|^2 + 2 Re sum_j conj(w_j) h_j.  Equal gaps: the KMS form of the spectral
    check (core/spectral.py ``_quad_kms_nodes``) -- this is its unequal-spacing generalisation.
    """
    h = np.zeros(w.shape[:-2] + w.shape[-1:], dtype=complex)
    total = np.sum(w.real**2 + w.imag**2, axis=-2)
    cross = np.zeros(total.shape)
    for j in range(1, w.shape[-2]):
        h += w[..., j - 1, :]
        h *= rho_gaps[j - 1]  # h_j = rho_j (h_(j-1) + w_(j-1))
        cross += w[..., j, :].real * h.real + w[..., j, :].imag * h.imag
    return total + 2.0 * cross


def _factor(c: np.ndarray) -> np.ndarray:
    """A factor L with L L^T = c: lower Cholesky, or Q sqrt(Lambda) from the eigen-decomposition
    (negative round-off eigenvalues clipped) when c is not numerically positive definite."""
    try:
        return cholesky(c, lower=True, check_finite=False)
    except LinAlgError:
        lam, q = eigh(c, check_finite=False)
        return q * np.sqrt(np.clip(lam, 0.0, None))[None, :]


def general_apply(x: np.ndarray, freq: np.ndarray, xi: np.ndarray, decay: float, v_mean: float) -> np.ndarray:
    """y_k = L_k xi_k with L_k a factor of the Davenport coherence matrix at each frequency.

    x [m] shape (n_nodes,) (any spacing); freq [Hz] (n_freq,); xi (n_nodes, n_freq) complex.
    Dense Cholesky per frequency, eigen fallback where the matrix is not numerically
    positive definite.  O(N^3) per frequency: the reference path for uneven spacing and
    the baseline of ``bench/bench_wind.py``.
    """
    x = np.asarray(x, dtype=float)
    dx = np.abs(x[:, None] - x[None, :])
    y = np.empty_like(xi)
    rhs = np.empty((x.size, 2))
    for k, f in enumerate(np.asarray(freq, dtype=float)):
        lower = _factor(davenport_coherence(f, dx, decay, v_mean))
        rhs[:, 0], rhs[:, 1] = xi[:, k].real, xi[:, k].imag  # real factor: two real right-hand sides
        out = lower @ rhs
        y[:, k] = out[:, 0] + 1j * out[:, 1]
    return y


def uniform_spacing(x: np.ndarray) -> float | None:
    """[m] the spacing of equally spaced increasing x, else None: the rule that picks the KMS path
    (:mod:`linecheck.core.wind.wires` uses it too, so its wire 0 takes the same path)."""
    d = np.diff(x)
    if d.size == 0:
        return 0.0
    if d[0] > 0 and np.allclose(d, d[0], rtol=1e-9, atol=0.0):
        return float(d[0])
    return None


@dataclass(frozen=True, eq=False)
class UnitPhases:
    """The random phases of one realization [rad] (n_nodes, n_freq) and, when the compiled kernel
    computed them, their unit phasors (cos, sin) as its spectrum pass reads them (else None)."""

    phases: np.ndarray
    phasors: tuple[np.ndarray, np.ndarray] | None


def synthesize(x: np.ndarray, grid: SpectralGrid, phases: np.ndarray | UnitPhases, decay: float,
               v_mean: float, method: str = "auto", lead: int = 0) -> np.ndarray:
    """Unit-variance field at points x [m] for given phases [rad]: shape (lead + n_steps, n_nodes).

    phases shape (n_nodes, n_freq) (or :class:`UnitPhases` with their phasors computed).
    ``method``: "kms" (equal spacing required), "markov" (ordered x at any spacing), "general"
    (dense factor per frequency) or "auto" (KMS when x is equally spaced, else Markov when x is
    non-decreasing, else general).
    u_j(t_n) = sum_k A_k Re[(L_k e^(i phi_k))_j e^(i 2 pi f_k t_n)] (Deodatis 1996), by inverse FFT.
    ``lead`` samples before t_0 are the synthesis' periodic continuation (the sum is periodic
    with the transform's length n_fft dt): samples n_fft - lead .. n_fft - 1, wrapped as often as
    needed -- so the record from t_0 on is the same whatever the lead (common random numbers).
    """
    given = phases
    if isinstance(phases, UnitPhases):
        phases, given = phases.phases, (phases.phasors if phases.phasors is not None else phases.phases)
    x = np.asarray(x, dtype=float)
    n_nodes = x.size
    if phases.shape != (n_nodes, grid.n_freq):
        raise ValueError(f"phases shape {phases.shape} != {(n_nodes, grid.n_freq)}")
    spacing = uniform_spacing(x)
    if method == "auto":
        method = "kms" if spacing is not None else ("markov" if np.all(np.diff(x) >= 0) else "general")
    m = grid.n_fft
    spec = None
    if method == "kms":
        if spacing is None:
            raise ValueError("the KMS path needs equally spaced, increasing x")
        rho = davenport_coherence(grid.freq, spacing, decay, v_mean)  # coherence of neighbours: C_jk = rho^|j-k|
        # the phasors, the recursion and the scaling below in one compiled pass when the kernel
        # piece ``spectrum`` is on (checked at load)
        spec = kernel.coherent_spectrum(given, rho[None, :], np.zeros(max(n_nodes - 1, 0), dtype=np.int64),
                                        grid.amplitude, m)
        if spec is None:
            y = kms_apply(rho, np.exp(1j * phases))
    elif method == "markov":
        spec = kernel.coherent_spectrum(given, *gap_rows(x, grid.freq, decay, v_mean), grid.amplitude, m)
        if spec is None:
            y = markov_apply(x, grid.freq, np.exp(1j * phases), decay, v_mean)
    elif method == "general":
        y = general_apply(x, grid.freq, np.exp(1j * phases), decay, v_mean)
    else:
        raise ValueError(f"unknown method {method!r}")
    if spec is None:
        spec = fft_input(y, grid.amplitude, m)
    # one contiguous transform per node (pocketfft gives each 1-D transform the same bits whatever
    # the layout; along the contiguous axis it is ~25 % faster than along axis 0)
    full = sfft.irfft(spec, n=m, axis=1)
    if lead == 0:
        return np.ascontiguousarray(full[:, : grid.n_steps].T)
    return np.ascontiguousarray(np.take(full, np.arange(-lead, grid.n_steps), axis=1, mode="wrap").T)


# ------------------------------------------------------------------------- case-level API
def unit_field(case: Case, system: LineSystem, n_steps: int, dt: float, realization: int, lead: int = 0) -> np.ndarray:
    """Zero-mean, unit-variance turbulence u(x, t) [-] at every global FE node.

    n_steps samples at dt [s] of the analysed record, after ``lead`` samples of lead-in (a
    burn-in: the synthesis' periodic continuation, :func:`synthesize`); realization: 0-based
    index.  Returns shape (lead + n_steps, n_nodes).  Bit-identical for the same case, seed,
    n_steps, dt and realization; the analysed samples do not depend on ``lead``.
    Points: the nodes' still-air x (equal-span form) or stations, the distance along the line
    (section form: the Markov path; see :func:`markov_apply`).  The coherence uses
    the one speed V_ref whatever the profile (docs/wind.md, "Sections").
    """
    x = system.node_station if system.is_section else system.node_x0
    v = float(case.wind.v_ref)
    if not v > 0:
        raise CaseError("value 0.0 is not allowed for turbulence synthesis: expected v_ref > 0",
                        file=str(case.source) if case.source else None, key="wind.v_ref")
    grid = spectral_grid(int(n_steps), float(dt), length_scale(case), v, case.wind.fft_length == "fast")
    return synthesize(x, grid, unit_phases(case.analysis.seed, realization, x.size, grid.n_freq),
                      case.wind.coherence_decay, v, lead=lead)


_phase_memo: dict[tuple, UnitPhases] = {}


def unit_phases(seed: int, realization: int, n_nodes: int, n_freq: int) -> UnitPhases:
    """:func:`random_phases` and, with the compiled kernel loaded, their unit phasors, remembered
    per process like the unit fields (:data:`UNIT_FIELD_MEMO_BYTES`, least recently used first
    out).  They depend on the seed, the realization, the node count and the grid only: the
    positions of a one-storm scan, whose unit fields differ (V_ref at p changes the spectrum and
    coherence), share them (the sines and cosines were ≈ 0.1 s of a ten-realization
    position), and so do cases of a batch with the same seed, nodes and record.  The same bits
    as computing them afresh (deterministic)."""
    key = (int(seed), int(realization), int(n_nodes), int(n_freq))
    got = _memo_get(_phase_memo, key)
    if got is not None:
        return got
    phases = random_phases(seed, realization, n_nodes, n_freq)
    out = UnitPhases(phases, kernel.phasors(phases))
    if out.phasors is None:  # the numpy path: its complex exponential is not kept
        return out
    for arr in (phases, *out.phasors):
        arr.setflags(write=False)
    if 3 * phases.nbytes <= UNIT_FIELD_MEMO_BYTES / 8:
        _memo_put(_phase_memo, key, out, lambda p: 3 * p.phases.nbytes, UNIT_FIELD_MEMO_BYTES / 2)
    return out


def modulation(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """a(x, t) [m/s] = I V_m(x, t) (downburst, speed magnitude at the nodes) or I V_ref (synoptic).

    Shape (n_steps, n_nodes) for a downburst, (1, 1) for synoptic (broadcasts).  Chay et al. (2006).
    Synoptic with a power-law profile: sigma_u = I V_ref at every height (I is the intensity at
    the reference height; the surface-layer sigma_u is about constant with height, sigma_u ~ 2.5 u*,
    Burton et al., Wind Energy Handbook 2001, sec. 2.6.3 after ESDU 1985; docs/wind.md).
    """
    i = case.wind.turbulence_intensity
    # Chay et al. (2006), paper section 2.2: a = I V_m(x, t) (downburst), I V_ref (synoptic)
    if case.wind.type == "synoptic":
        return np.full((1, 1), i * case.wind.v_ref)
    return i * mean_speed_at_nodes(case, system, time)


def record_axis(time: np.ndarray) -> tuple[int, float]:
    """(n_steps, dt [s]) of an equally spaced time axis [s], dt to 12 significant digits (a
    :class:`CaseError` otherwise); the many-wire synthesis uses the same rule (the same grid)."""
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or t.size < 4:
        raise CaseError(f"time axis of {t.size} instants is not allowed: expected at least 4 equally spaced instants")
    d = np.diff(t)
    dt = float((t[-1] - t[0]) / (t.size - 1))
    if not dt > 0 or not np.allclose(d, dt, rtol=1e-6, atol=1e-9 * max(1.0, abs(t[-1]))):
        raise CaseError("time axis is not allowed: expected equally spaced, increasing instants")
    # t0 + dt * arange(n) recovers dt only to round-off: keep 12 significant digits so the same
    # time step always gives the same spectral grid (and bit-identical fields)
    return t.size, float(f"{dt:.12g}")


def fluctuating_velocity(case: Case, system: LineSystem, time: np.ndarray, realizations: Sequence[int],
                         a: np.ndarray | None = None, lead: int = 0, cancel=None) -> np.ndarray:
    """Fluctuating along-wind velocity a(x, t) u_r(x, t) [m/s] at the global FE nodes.

    time [s] equally spaced, shape (n_steps,); realizations: 0-based indices; ``a`` [m/s]: the
    :func:`modulation` over ``time`` when the caller has it already (a run's chunks share it).
    ``lead``: the first samples of ``time`` that precede the analysed record (a burn-in); the
    turbulence is synthesized on the analysed record and continued periodically into the lead,
    so realization k's turbulence at a given time of the analysed record does not depend on the
    burn-in's length, nor on anything else that does not define the turbulence: two runs that
    differ in drag, tension or damping compare with common random numbers (docs/wind.md).
    ``cancel``: an event (``is_set()``) checked before each realization (Cancelled when set).
    Returns shape (n_real, n_steps, n_nodes).
    """
    n_steps, dt = record_axis(time)
    if not 0 <= lead < n_steps - 3:
        raise ValueError(f"lead of {lead} samples does not fit a record of {n_steps}")
    if a is None:
        a = modulation(case, system, np.asarray(time, dtype=float))
    reals = list(realizations)
    out = np.empty((len(reals), n_steps, system.n_nodes))
    for i, r in enumerate(reals):
        if cancel is not None and cancel.is_set():
            raise Cancelled("run cancelled")
        out[i] = _unit_field_memo(case, system, n_steps - lead, dt, int(r), int(lead))
        out[i] *= a
    return out


#: [bytes] unit fields kept per process for reuse (scans); the environment variable
#: LINECHECK_UNIT_FIELD_MEMO overrides it (0: off; the bench scripts time fresh runs with it)
UNIT_FIELD_MEMO_BYTES = float(os.environ.get("LINECHECK_UNIT_FIELD_MEMO", "256e6"))
_memo: dict[tuple, np.ndarray] = {}
_memo_lock = threading.Lock()


def _unit_field_memo(case: Case, system: LineSystem, n_steps: int, dt: float, realization: int,
                     lead: int = 0) -> np.ndarray:
    """:func:`unit_field`, remembered per process (read-only, least recently used first out,
    at most :data:`UNIT_FIELD_MEMO_BYTES`).  The unit field depends only on the node positions,
    V_ref, L_u, the coherence decay, the seed, the realization and the record grid, not on the
    running mean: a critical-downburst scan's positions share it, and a repeated
    run reuses it.  The same bits as computing it afresh (it is deterministic)."""
    x = system.node_station if system.is_section else system.node_x0
    key = (x.tobytes(), bool(system.is_section), float(case.wind.v_ref), float(length_scale(case)),
           float(case.wind.coherence_decay), int(case.analysis.seed), realization, n_steps, dt, case.wind.fft_length,
           lead)
    got = _memo_get(_memo, key)
    if got is not None:
        return got
    u = unit_field(case, system, n_steps, dt, realization, lead)
    if u.nbytes <= UNIT_FIELD_MEMO_BYTES / 4:
        u.setflags(write=False)
        _memo_put(_memo, key, u, lambda v: v.nbytes, UNIT_FIELD_MEMO_BYTES)
    return u


def _memo_get(memo: dict, key: tuple):
    """A per-process memo's value for ``key`` (made the most recently used), or None."""
    with _memo_lock:
        got = memo.pop(key, None)
        if got is not None:
            memo[key] = got  # most recently used last
        return got


def _memo_put(memo: dict, key: tuple, value, nbytes: Callable, limit: float) -> None:
    """Keep ``value`` under ``key``, dropping the least recently used entries while the memo's
    ``nbytes`` total exceeds ``limit`` [bytes]."""
    with _memo_lock:
        memo[key] = value
        while sum(nbytes(v) for v in memo.values()) > limit:
            memo.pop(next(iter(memo)))


# ---- the compiled kernel's piece ``spectrum`` (linecheck.core.kernel): its load check

def _spectrum_check(fns) -> float:
    """The compiled synthesis spectrum (``fns.phasors``, ``fns.coherent_spectrum``) against the
    numpy forms: equal gaps (the KMS recursion, :func:`kms_apply`) and unequal ones (the Markov
    recursion, :func:`markov_apply`, a coefficient row per gap); the largest relative difference."""
    rng = np.random.default_rng(23)
    n_nodes, n_freq = 9, 301
    phases = rng.random((n_nodes, n_freq)) * (2.0 * np.pi)
    freq = np.arange(1, n_freq + 1) * 0.01
    amp = rng.random(n_freq)
    m = 2 * n_freq + 2
    x = np.cumsum(np.r_[0.0, rng.choice([30.0, 12.5], n_nodes - 1)])
    rows, gap = gap_rows(x, freq, 10.0, 40.0)
    cases = [(markov_apply(x, freq, np.exp(1j * phases), 10.0, 40.0), rows, gap),
             (kms_apply(rows[0], np.exp(1j * phases)), rows[:1], np.zeros(n_nodes - 1, dtype=np.int64))]
    pairs = []
    for y, r, g in cases:
        ref = fft_input(y, amp, m)
        got = np.zeros_like(ref)
        xr, xi = np.empty_like(phases), np.empty_like(phases)
        fns.phasors(phases, xr, xi)
        fns.coherent_spectrum(xr, xi, r, np.sqrt(np.maximum(1.0 - r * r, 0.0)), g, amp, 0.5 * m, got)
        pairs.append((ref.view(float), got.view(float)))
    return kernel.worst_difference(pairs)


kernel.register_check("spectrum", _spectrum_check)
