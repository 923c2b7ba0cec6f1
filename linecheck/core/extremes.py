"""Summaries of per-realization statistics: moments, fractiles, Gumbel fits, confidence
intervals and the three-state "dynamic analysis" flag (docs/method.md, "Statistics over realizations").

Input everywhere is an array of per-realization (or per window x realization) values
``values`` of shape (n, ...) -- axis 0 the sample; outputs have shape ``values.shape[1:]``.
NaN (an undefined gust factor) propagates: a column with a NaN summarises to NaN.

Choices (docs/method.md, "Statistics over realizations"):

- Standard error of the mean: std / sqrt(n), std with ddof = 1.
- Fractiles: linear interpolation between order statistics (numpy's default, Hyndman & Fan
  1996 definition 7).
- Gumbel (extreme value type I) fit of peaks by the method of moments (Gumbel 1958):
  scale beta = sqrt(6) s / pi, location u = mean - gamma beta (gamma = Euler's constant).
  With the 10-50 samples of a run the moment estimators are closed-form, never fail to
  converge and are nearly as efficient as maximum likelihood (relative efficiency of the
  location ~ 0.95; Lowery & Nash 1970), and they keep the fitted mean equal to the sample mean.
- Goodness of fit: probability-plot correlation coefficient (Filliben 1975) of the sorted
  sample against Gumbel reduced variates at Gringorten (1963) plotting positions
  p_i = (i - 0.44) / (n + 0.12).
- Design value at non-exceedance probability p: x_p = u - beta ln(-ln p) (Gumbel CDF
  F(x) = exp(-exp(-(x - u)/beta)) inverted).
- Confidence interval of a mean (GF_Dy, GF_QS, Cont_R): normal theory with Student's t,
  mean +- t_{0.975, n-1} se (the realizations are independent and identically distributed;
  the coverage is checked on synthetic Gaussian records in tests/core/test_extremes.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

EULER_GAMMA = 0.5772156649015329  # Euler-Mascheroni constant (Gumbel mean = u + gamma beta)
CI_LEVEL = 0.95
FRACTILES = (5.0, 50.0, 95.0)
CONT_R_THRESHOLD = 0.10  # paper Sec. 5: dynamic analysis recommended where Cont_R > 10 %
# No flag where the wind-induced peak is below this share of the still-air load of the tower
# (magnitude of its (R_x, R_y, R_z) still-air reaction): such a reaction does not govern the design.
MIN_WIND_SHARE = 0.05


@dataclass(frozen=True)
class Summary:
    """Moments and fractiles over axis 0; every field has shape ``values.shape[1:]``.

    mean, std (ddof = 1; 0 for one sample), se = std / sqrt(n), p05, p50, p95 in the unit of
    the values; n the sample count.
    """

    mean: np.ndarray
    std: np.ndarray
    se: np.ndarray
    p05: np.ndarray
    p50: np.ndarray
    p95: np.ndarray
    n: int


@dataclass(frozen=True)
class GumbelFit:
    """Gumbel (EV-I) fit of peaks; fields of shape ``values.shape[1:]``.

    location u and scale beta in the unit of the values, ppcc [-] the probability-plot
    correlation (NaN for fewer than 3 samples or a constant sample), design the value at the
    non-exceedance probability ``fractile``.
    """

    location: np.ndarray
    scale: np.ndarray
    ppcc: np.ndarray
    design: np.ndarray
    fractile: float


def summarise(values: np.ndarray) -> Summary:
    """Mean, std, standard error and 5/50/95 % fractiles over axis 0 of ``values`` (n, ...)."""
    v = np.asarray(values, dtype=float)
    n = v.shape[0]
    mean = v.mean(axis=0)
    std = v.std(axis=0, ddof=1) if n > 1 else np.zeros(v.shape[1:])
    se = std / np.sqrt(n)
    p = np.percentile(v, FRACTILES, axis=0)
    return Summary(mean, std, se, p[0], p[1], p[2], n)


def gumbel_quantile(location: np.ndarray, scale: np.ndarray, p: float) -> np.ndarray:
    """x_p of the Gumbel distribution: u - beta ln(-ln p) (inverse of exp(-exp(-(x-u)/beta)))."""
    return location - scale * np.log(-np.log(p))


def gumbel_fit(values: np.ndarray, fractile: float = 0.5) -> GumbelFit:
    """Method-of-moments Gumbel fit of peaks ``values`` (n, ...) and the design value at ``fractile``.

    beta = sqrt(6) s / pi, u = mean - gamma beta (Gumbel 1958, moments of the EV-I law).
    """
    if not 0.0 < fractile < 1.0:
        raise ValueError(f"fractile {fractile!r} must be in (0, 1)")
    v = np.asarray(values, dtype=float)
    n = v.shape[0]
    mean = v.mean(axis=0)
    s = v.std(axis=0, ddof=1) if n > 1 else np.zeros(v.shape[1:])
    beta = np.sqrt(6.0) * s / np.pi
    u = mean - EULER_GAMMA * beta
    return GumbelFit(u, beta, ppcc_gumbel(v), gumbel_quantile(u, beta, fractile), float(fractile))


def ppcc_gumbel(values: np.ndarray) -> np.ndarray:
    """Probability-plot correlation coefficient against the Gumbel law (Filliben 1975), Gringorten
    plotting positions (Gringorten 1963); NaN for n < 3 or a constant column."""
    v = np.asarray(values, dtype=float)
    n = v.shape[0]
    if n < 3:
        return np.full(v.shape[1:], np.nan)
    pp = (np.arange(1, n + 1) - 0.44) / (n + 0.12)
    y = -np.log(-np.log(pp))
    y = (y - y.mean()) / np.sqrt(((y - y.mean()) ** 2).sum())
    x = np.sort(v, axis=0)
    xc = x - x.mean(axis=0)
    norm = np.sqrt((xc**2).sum(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.tensordot(y, xc, axes=(0, 0)) / norm
    return np.where(norm > 0, r, np.nan)


def confidence_interval(summary: Summary, level: float = CI_LEVEL) -> tuple[np.ndarray, np.ndarray]:
    """Normal-theory interval of the mean: mean -+ t_{(1+level)/2, n-1} se (Student 1908).

    One sample: (NaN, NaN) -- no interval without a spread estimate.
    """
    n = summary.n
    if n < 2:
        nan = np.full(np.shape(summary.mean), np.nan)
        return nan, nan.copy()
    from scipy import stats as _sps  # here, not at import: scipy.stats costs ~0.4 s of start-up

    t = float(_sps.t.ppf(0.5 * (1.0 + level), n - 1))
    return summary.mean - t * summary.se, summary.mean + t * summary.se


def dynamic_analysis_flag(
    cont_r_low: np.ndarray,
    cont_r_high: np.ndarray,
    gf_defined: np.ndarray,
    wind_peak: np.ndarray,
    still_air: np.ndarray,
) -> np.ndarray:
    """Three-state flag per reaction: "recommended", "inconclusive" or None (object array).

    Args:
        cont_r_low, cont_r_high: [-] 95 % interval of Cont_R, shape (..., 3).
        gf_defined: whether GF_Dy is defined (mean not negligible), shape (..., 3).
        wind_peak: [N] mean wind-induced peak, shape (..., 3).
        still_air: [N] still-air reactions, shape (..., 3); the share is taken of the
            magnitude of the (R_x, R_y, R_z) vector at the tower.

    "recommended" when the lower bound exceeds :data:`CONT_R_THRESHOLD`, "inconclusive" when the
    interval straddles it (pass (-inf, inf) when there is no interval, one realization), None otherwise and wherever GF is undefined or the wind-induced peak
    is below :data:`MIN_WIND_SHARE` of the still-air reaction.
    """
    low, high = np.asarray(cont_r_low, float), np.asarray(cont_r_high, float)
    sa = np.linalg.norm(np.asarray(still_air, float), axis=-1, keepdims=True)
    relevant = np.asarray(gf_defined, bool) & (np.asarray(wind_peak, float) >= MIN_WIND_SHARE * sa)
    out = np.full(low.shape, None, dtype=object)
    out[relevant & (low > CONT_R_THRESHOLD)] = "recommended"
    straddle = relevant & ~(low > CONT_R_THRESHOLD) & (high > CONT_R_THRESHOLD)
    out[straddle] = "inconclusive"
    return out
