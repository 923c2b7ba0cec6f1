"""Response statistics, gust factors and contributions (paper Eqs 15-17).

Every statistic is computed per realization on the wind-induced response
(total minus still air) and kept as an array of shape (n_real, n_towers, 3),
last axis (R_x, R_y, R_z); :meth:`Statistics.mean` / :meth:`Statistics.std`
summarise over realizations.  Definitions (paper Eqs 15-17):

- mean_max = max_t |M(t)|  (M: step-1 mean reaction, wind-induced)
- rms_background = sqrt(mean_t B^2), rms_resonant = sqrt(mean_t R^2),
  rms_fluctuating = sqrt(mean_t (B + R)^2)
- peak_quasi_static = max_t |M + B|, peak_dynamic = max_t |M + B + R|
  (``*_total``: the same with the still-air reaction added)
- GF_Dy = peak_dynamic / mean_max, GF_QS = peak_quasi_static / mean_max (Eq. 15)
- Cont_M = 1/GF_Dy, Cont_BG = (GF_QS - 1)/GF_Dy, Cont_R = (GF_Dy - GF_QS)/GF_Dy (Eq. 16),
  written as mean_max/peak, (peak_QS - mean_max)/peak, (peak - peak_QS)/peak so that
  they stay defined when the mean vanishes by symmetry (the paper's "**" rows of
  Table 5 still report Cont_R);
- peak_normalised = peak_dynamic / (g*_yp L_x), g*_yp = 1/2 rho C_d V_ref^2 D (Eq. 17).

A reaction whose mean is zero by symmetry, or negligible (mean_max below
:data:`ZERO_MEAN_RTOL` = 1 % of the largest wind-induced mean reaction component
of the case), has GF_Dy = GF_QS = NaN (JSON null): a peak divided by a vanishing
mean carries no design meaning (the paper's "**" entries of Table 5).  Its peaks
and Cont_* are still reported.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from . import kernel
from .extremes import GumbelFit, Summary, confidence_interval, dynamic_analysis_flag, gumbel_fit, summarise

REACTIONS = ("Rx", "Ry", "Rz")
STATISTICS = (
    "mean_max",
    "rms_background",
    "rms_resonant",
    "rms_fluctuating",
    "peak_quasi_static",
    "peak_dynamic",
    "peak_quasi_static_total",
    "peak_dynamic_total",
    "GF_Dy",
    "GF_QS",
    "Cont_M",
    "Cont_BG",
    "Cont_R",
    "peak_normalised",
    "peak_normalised_total",
)
ZERO_MEAN_RTOL = 0.01
#: Peak statistics: summarised with a Gumbel fit and a design value.
PEAK_STATISTICS = (
    "peak_quasi_static",
    "peak_dynamic",
    "peak_quasi_static_total",
    "peak_dynamic_total",
    "peak_normalised",
    "peak_normalised_total",
)
#: Statistics reported with a 95 % confidence interval of their mean.
CI_STATISTICS = ("GF_Dy", "GF_QS", "Cont_R")


@dataclass(frozen=True)
class Statistics:
    """Per-realization statistics; every field has shape (n_samples, n_towers, 3), n_samples =
    n_real x n_windows (realization-major) when peaks are taken per window.

    Forces in [N]; GF and Cont are ratios (Cont as fractions, 0.042 = 4.2 %).
    """

    mean_max: np.ndarray
    rms_background: np.ndarray
    rms_resonant: np.ndarray
    rms_fluctuating: np.ndarray
    peak_quasi_static: np.ndarray
    peak_dynamic: np.ndarray
    peak_quasi_static_total: np.ndarray
    peak_dynamic_total: np.ndarray
    GF_Dy: np.ndarray
    GF_QS: np.ndarray
    Cont_M: np.ndarray
    Cont_BG: np.ndarray
    Cont_R: np.ndarray
    peak_normalised: np.ndarray
    peak_normalised_total: np.ndarray

    def values(self, name: str) -> np.ndarray:
        """The per-realization array of statistic ``name`` (one of :data:`STATISTICS`)."""
        if name not in STATISTICS:
            raise KeyError(name)
        return getattr(self, name)

    def mean(self, name: str) -> np.ndarray:
        """Mean over realizations, shape (n_towers, 3); NaN where undefined."""
        return self.values(name).mean(axis=0)

    def std(self, name: str) -> np.ndarray:
        """Sample standard deviation over realizations (ddof=1; 0 for one realization)."""
        v = self.values(name)
        if v.shape[0] < 2:
            return np.zeros(v.shape[1:])
        return v.std(axis=0, ddof=1)

    @property
    def n_samples(self) -> int:
        """Number of samples (realizations x windows) the statistics are over."""
        return int(self.mean_max.shape[0])

    @staticmethod
    def concatenate(parts: list[Statistics]) -> Statistics:
        """Join statistics of disjoint realization sets (batch/distributed runs)."""
        return Statistics(**{f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(Statistics)})


def compute_statistics(
    mean: np.ndarray,
    background: np.ndarray,
    resonant: np.ndarray,
    still_air: np.ndarray,
    g_yp_L: float | np.ndarray,
    window: int | None = None,
    scale: float | None = None,
) -> Statistics:
    """Statistics of Eqs 15-17 from response histories.

    With ``window`` (samples, ``analysis.peak_window``) every statistic is taken per window
    (:func:`_peak_windows`): n_real x n_w samples, realization-major; ``window`` None or
    >= n_t - 1 steps: the whole record.

    Args:
        mean: [N] wind-induced mean reaction M(t), shape (n_t, n_towers, 3).
        background: [N] B(t), shape (n_real, n_t, n_towers, 3).
        resonant: [N] R(t) = F - B, same shape.
        still_air: [N] still-air reactions, shape (n_towers, 3).
        g_yp_L: [N] normalising force g*_yp L_x (Eq. 17): a number, or one per tower (n_towers,)
            (a section: L_x the mean of the tower's two adjacent spans).
        window: samples per peak window (None: the whole record).
        scale: [N] the largest |M| that decides which gust factors are defined (a mean below
            ``ZERO_MEAN_RTOL`` of it has none); None: max |mean| (pass the whole section's when
            ``mean`` holds some of its towers only).
    """
    scale = max(float(np.abs(mean).max()), 1e-300) if scale is None else scale
    M, background, resonant, mean_max = _peak_windows(mean, background, resonant, window)
    # one compiled pass over the histories with the kernel's piece ``reductions`` (checked at load)
    red = kernel.history_reductions(M, background, resonant, still_air)
    if red is None:  # the piece off: the numpy form
        red = history_reductions(M, background, resonant, still_air)
    rms_b, rms_r, rms_f, pk_qs, pk_dy, pk_qs_t, pk_dy_t = red
    return Statistics(
        mean_max=mean_max,
        rms_background=rms_b,
        rms_resonant=rms_r,
        rms_fluctuating=rms_f,
        peak_quasi_static=pk_qs,
        peak_dynamic=pk_dy,
        peak_quasi_static_total=pk_qs_t,
        peak_dynamic_total=pk_dy_t,
        **_ratios(mean_max, pk_qs, pk_dy, pk_dy_t, mean_max > ZERO_MEAN_RTOL * scale, g_yp_L),
    )


def _peak_windows(mean: np.ndarray, background: np.ndarray, resonant: np.ndarray,
                  window: int | None) -> tuple[np.ndarray, ...]:
    """The histories cut into peak windows: with 0 < ``window`` < n_t - 1, n_w = (n_t - 1) //
    window consecutive windows of ``window`` samples (n_t samples span n_t - 1 steps; a shorter
    remainder at the end is dropped), else the whole record as one.  Returns M [N] (n_samples or
    1, n_s, n_towers, 3), B and R [N] (n_samples, n_s, n_towers, 3) and mean_max = max_t |M| [N]
    (n_samples, n_towers, 3): n_s = window or n_t, n_samples = n_real x n_w, realization-major."""
    n_real, n_t = background.shape[:2]
    if window is not None and 0 < window < n_t - 1:
        n_w = (n_t - 1) // window
        cut = n_w * window
        tail = background.shape[2:]
        background = background[:, :cut].reshape((n_real * n_w, window) + tail)
        resonant = resonant[:, :cut].reshape((n_real * n_w, window) + tail)
        M = np.tile(mean[:cut].reshape((n_w, window) + tail), (n_real,) + (1,) * (1 + len(tail)))
        mean_max = np.abs(M).max(axis=1)
    else:
        M = mean[None]
        mean_max = np.broadcast_to(np.abs(mean).max(axis=0), background.shape[:1] + mean.shape[1:]).copy()
    return M, background, resonant, mean_max


def _ratios(mean_max: np.ndarray, pk_qs: np.ndarray, pk_dy: np.ndarray, pk_dy_t: np.ndarray, defined: np.ndarray,
            g_yp_L: float | np.ndarray) -> dict[str, np.ndarray]:
    """The gust factors GF_Dy, GF_QS [-] (Eq. 15; NaN where not ``defined``), the contributions
    Cont_M, Cont_BG, Cont_R [-] (Eq. 16, as fractions of the peak: NaN where it is 0) and the
    normalised peaks peak_dynamic(_total) / g*_yp L_x [-] (Eq. 17; NaN unless every g_yp_L [N]
    > 0), each (n_samples, n_towers, 3), from the peaks and mean_max [N] of that shape."""
    with np.errstate(divide="ignore", invalid="ignore"):
        gf_dy = np.where(defined, pk_dy / mean_max, np.nan)
        gf_qs = np.where(defined, pk_qs / mean_max, np.nan)
        cont_m = np.where(pk_dy > 0, mean_max / pk_dy, np.nan)
        cont_bg = np.where(pk_dy > 0, (pk_qs - mean_max) / pk_dy, np.nan)
        cont_r = np.where(pk_dy > 0, (pk_dy - pk_qs) / pk_dy, np.nan)
        g = np.asarray(g_yp_L, dtype=float)
        gL = g[:, None] if g.ndim else g_yp_L  # per tower (a section's L_x differs)
        norm = pk_dy / gL if np.all(g > 0) else np.full_like(pk_dy, np.nan)
        norm_t = pk_dy_t / gL if np.all(g > 0) else np.full_like(pk_dy, np.nan)
    return {"GF_Dy": gf_dy, "GF_QS": gf_qs, "Cont_M": cont_m, "Cont_BG": cont_bg, "Cont_R": cont_r,
            "peak_normalised": norm, "peak_normalised_total": norm_t}


def history_reductions(M: np.ndarray, background: np.ndarray, resonant: np.ndarray,
                       still_air: np.ndarray) -> tuple[np.ndarray, ...]:
    """The reductions over time of :func:`compute_statistics` (module docstring), numpy form:
    r.m.s. of B, R and B + R, and the peaks |M + B|, |M + B + R| (also with the still-air reaction
    added).  M (1 or n, n_t, n_towers, 3); background, resonant (n, n_t, n_towers, 3); still_air
    (n_towers, 3) [N].  Returns seven arrays (n, n_towers, 3).  (:func:`linecheck.core.kernel.
    history_reductions` computes them in one compiled pass, within the kernel's tolerance.)"""
    qs = M + background
    dyn = qs + resonant
    rms_b = np.sqrt(np.mean(background**2, axis=1))
    rms_r = np.sqrt(np.mean(resonant**2, axis=1))
    rms_f = np.sqrt(np.mean((background + resonant) ** 2, axis=1))
    pk_qs = np.abs(qs).max(axis=1)
    pk_dy = np.abs(dyn).max(axis=1)
    sa = still_air[None, None]
    pk_qs_t = np.abs(qs + sa).max(axis=1)
    pk_dy_t = np.abs(dyn + sa).max(axis=1)
    return rms_b, rms_r, rms_f, pk_qs, pk_dy, pk_qs_t, pk_dy_t


@dataclass(frozen=True)
class StatisticSummary:
    """Summary of one statistic over samples at every tower; arrays of shape (n_towers, 3).

    ``gumbel`` for :data:`PEAK_STATISTICS`, ``ci`` (low, high) for :data:`CI_STATISTICS`
    (None otherwise); units those of the statistic.
    """

    summary: Summary
    gumbel: GumbelFit | None = None
    ci: tuple[np.ndarray, np.ndarray] | None = None


@dataclass(frozen=True)
class ResultSummary:
    """Every statistic summarised and the three-state Cont_R flag.

    Attributes:
        statistics: name -> :class:`StatisticSummary` for every name of :data:`STATISTICS`.
        dynamic_analysis: object array (n_towers, 3) of "recommended", "inconclusive" or None.
        n_samples: realizations x windows summarised over.
        design_fractile: non-exceedance probability of the Gumbel design values [-].
    """

    statistics: dict[str, StatisticSummary]
    dynamic_analysis: np.ndarray
    n_samples: int
    design_fractile: float


def summarise_statistics(stats: Statistics, still_air: np.ndarray, design_fractile: float = 0.5) -> ResultSummary:
    """Summaries, Gumbel fits of the peaks, 95 % intervals and the Cont_R flag.

    Args:
        stats: per-sample statistics, fields (n_samples, n_towers, 3).
        still_air: [N] still-air reactions, shape (n_towers, 3).
        design_fractile: non-exceedance probability of the design peak (``analysis.design_fractile``).
    """
    out: dict[str, StatisticSummary] = {}
    for name in STATISTICS:
        v = stats.values(name)
        sm = summarise(v)
        gb = gumbel_fit(v, design_fractile) if name in PEAK_STATISTICS else None
        ci = confidence_interval(sm) if name in CI_STATISTICS else None
        out[name] = StatisticSummary(sm, gb, ci)
    low, high = out["Cont_R"].ci
    if stats.n_samples < 2:  # no interval from one sample: the flag can only say "inconclusive"
        low, high = np.full_like(low, -np.inf), np.full_like(high, np.inf)
    gf_defined = np.isfinite(out["GF_Dy"].summary.mean)
    flag = dynamic_analysis_flag(low, high, gf_defined, out["peak_dynamic"].summary.mean, still_air)
    return ResultSummary(out, flag, stats.n_samples, float(design_fractile))


# ---- the compiled kernel's piece ``reductions`` (linecheck.core.kernel): its load check

def _reductions_check(fns) -> float:
    """The compiled reductions over time (``fns.history_reductions``) against
    :func:`history_reductions` (the mean held, and one per sample as with peak windows); the
    largest relative difference."""
    rng = np.random.default_rng(26)
    B, R = rng.standard_normal((2, 3, 257, 2, 3)) * 1e3
    sa = rng.standard_normal((2, 3)) * 1e4
    pairs = []
    for m in (1, 3):
        M = rng.standard_normal((m, 257, 2, 3)) * 1e4
        pairs += list(zip(history_reductions(M, B, R, sa),
                          kernel.reductions_compiled(fns.history_reductions, M, B, R, sa)))
    return kernel.worst_difference(pairs)


kernel.register_check("reductions", _reductions_check)
