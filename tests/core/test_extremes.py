"""Statistics over realizations: moments, Gumbel fits, confidence intervals, the
Cont_R flag, peak windows and --until.

The coverage tests use synthetic Gaussian records with a known spectrum, generated here with
numpy's FFT and independent of linecheck's wind and solver: M = 1, a low-pass background B
(von Karman-shaped spectrum, sigma 0.15) and a narrow-band resonant R (SDOF |H|^2 at 1 Hz,
2 % damping, sigma 0.06), every Fourier coefficient complex Gaussian so the records are
exactly Gaussian with that spectrum.
"""

from __future__ import annotations

import numpy as np
import pytest

from linecheck.core.extremes import (
    CONT_R_THRESHOLD,
    EULER_GAMMA,
    MIN_WIND_SHARE,
    confidence_interval,
    dynamic_analysis_flag,
    gumbel_fit,
    ppcc_gumbel,
    summarise,
)

N_T, DT = 1024, 0.1  # 102.4 s records
FREQ = np.fft.rfftfreq(N_T, DT)


def _psd_background(f):
    return 1.0 / (1.0 + 70.8 * (f / 0.05) ** 2) ** (5 / 6)


def _psd_resonant(f, f0=1.0, zeta=0.02):
    return 1.0 / ((1 - (f / f0) ** 2) ** 2 + (2 * zeta * f / f0) ** 2)


def _gaussian(rng, n, psd, sigma):
    """n records (n, N_T) of a zero-mean Gaussian process of one-sided spectrum shape ``psd``,
    variance sigma^2: x = 2 Re sum_k c_k exp(i 2 pi f_k t), E|c_k|^2 = S_k / (2 sum S)."""
    s = psd(FREQ)
    s[0] = 0.0
    amp = np.sqrt(s / s.sum())
    c = (rng.standard_normal((n, FREQ.size)) + 1j * rng.standard_normal((n, FREQ.size))) * amp / 2.0
    return sigma * np.fft.irfft(c, n=N_T, axis=1) * N_T


def _records(rng, n):
    """Per-record GF_Dy, GF_QS, Cont_R (M = 1, so peak = GF) of n synthetic records."""
    b = _gaussian(rng, n, _psd_background, 0.15)
    r = _gaussian(rng, n, _psd_resonant, 0.06)
    pq = np.abs(1.0 + b).max(axis=1)
    pd = np.abs(1.0 + b + r).max(axis=1)
    return pd, pq, (pd - pq) / pd


@pytest.fixture(scope="module")
def truth():
    """'Known' truth: 10 000 independent records (seed 1).  The standard error of their mean
    GF is sigma/100 ~ 0.001, 1/50 of the n = 10 intervals' half-width (~0.07)."""
    pd, pq, cr = _records(np.random.default_rng(1), 10_000)
    return {"GF_Dy": pd, "GF_QS": pq, "Cont_R": cr}


def test_synthetic_records_have_the_stated_variance():
    x = _gaussian(np.random.default_rng(3), 2000, _psd_background, 0.15)
    # 2000 x 1024 samples, but the low-pass records are strongly correlated: allow 3 %
    assert np.var(x) == pytest.approx(0.15**2, rel=0.03)


def test_confidence_interval_coverage(truth):
    """400 experiments of n = 10 realizations (seed 2): the 95 % interval of the mean of GF_Dy,
    GF_QS and Cont_R contains the true mean in 95 % of them.  Binomial standard error
    sqrt(0.95 x 0.05 / 400) = 0.011; tolerance 3 of them (0.033), which also absorbs the slight
    under-coverage of Student's t on the skewed peak law at n = 10."""
    e, n = 400, 10
    pd, pq, cr = _records(np.random.default_rng(2), e * n)
    for name, v in (("GF_Dy", pd), ("GF_QS", pq), ("Cont_R", cr)):
        mu = truth[name].mean()
        lo, hi = confidence_interval(summarise(v.reshape(e, n).T))
        coverage = np.mean((lo <= mu) & (mu <= hi))
        assert coverage == pytest.approx(0.95, abs=0.033), name
    # a wrong interval fails: +- 1 se covers ~ 65 %, far outside the tolerance
    sm = summarise(pd.reshape(e, n).T)
    narrow = np.mean(np.abs(sm.mean - truth["GF_Dy"].mean()) <= sm.se)
    assert narrow < 0.8


@pytest.mark.parametrize("p", [0.5, 0.9])
def test_gumbel_design_value_coverage(truth, p):
    """Fits to n = 50 peaks (80 experiments, seed 4): the design value at non-exceedance p is not
    exceeded by a fraction p of the 10 000 independent peaks.  Sampling: each experiment's
    fraction has sd ~ 0.05, so the mean of 80 ~ 0.006; the truth's own error sqrt(p(1-p)/1e4) <=
    0.005; the Gumbel law is the Poisson-limit shape of a Gaussian maximum (Davenport 1964), not
    exact at nu T ~ 100 crossings (measured bias ~ -0.015 at p = 0.5).  Tolerance 0.03."""
    pd, _, _ = _records(np.random.default_rng(4), 80 * 50)
    g = gumbel_fit(pd.reshape(80, 50).T, p)
    ref = np.sort(truth["GF_Dy"])
    coverage = np.searchsorted(ref, g.design) / ref.size
    assert coverage.mean() == pytest.approx(p, abs=0.03)
    assert np.all(g.ppcc > 0.9)


def test_gumbel_moments_recover_the_law():
    """Samples of a known Gumbel law (u = 3, beta = 0.5): moment estimates, the median and the
    ppcc.  5000 x 4 samples: sd of the scale estimate ~ 1.1 beta / sqrt(n) ~ 0.008 -> rel 5 %."""
    rng = np.random.default_rng(5)
    x = rng.gumbel(3.0, 0.5, size=(5000, 4))
    g = gumbel_fit(x, 0.5)
    np.testing.assert_allclose(g.scale, 0.5, rtol=0.05)
    np.testing.assert_allclose(g.location, 3.0, atol=0.03)
    np.testing.assert_allclose(g.design, 3.0 - 0.5 * np.log(np.log(2.0)), atol=0.03)  # median u + 0.3665 beta
    assert np.all(g.ppcc > 0.99)
    # closed forms on a tiny sample: beta = sqrt(6) s / pi, u = mean - gamma beta
    y = np.array([1.0, 2.0, 4.0])
    g = gumbel_fit(y, 0.9)
    beta = np.sqrt(6) * np.std(y, ddof=1) / np.pi
    assert float(g.scale) == pytest.approx(beta)
    assert float(g.location) == pytest.approx(y.mean() - EULER_GAMMA * beta)
    assert float(g.design) == pytest.approx(float(g.location) - beta * np.log(-np.log(0.9)))


def test_ppcc_low_for_a_bimodal_sample():
    x = np.r_[np.zeros(10), np.ones(10)]
    assert float(ppcc_gumbel(x)) < 0.95
    assert np.isnan(ppcc_gumbel(np.ones(5)))


def test_summary_numbers():
    v = np.array([1.0, 2.0, 3.0, 10.0])
    s = summarise(v)
    assert float(s.mean) == 4.0
    assert float(s.std) == pytest.approx(np.sqrt(((v - 4) ** 2).sum() / 3))
    assert float(s.se) == pytest.approx(float(s.std) / 2)
    assert float(s.p50) == 2.5
    assert float(s.p05) == pytest.approx(1.15)  # 1 + 0.05 x 3 x (2 - 1)
    lo, hi = confidence_interval(s)
    t = 3.182446305284263  # t_{0.975, 3}
    assert float(hi - lo) == pytest.approx(2 * t * float(s.se))


def test_flag_three_states():
    sa = np.array([[0.0, 0.0, 10_000.0]])  # still air 10 kN, vertical only
    low = np.array([[0.12, 0.05, 0.12]])
    high = np.array([[0.20, 0.15, 0.20]])
    peak = np.array([[5000.0, 5000.0, 0.9 * MIN_WIND_SHARE * 10_000.0]])
    flags = dynamic_analysis_flag(low, high, np.array([[True, True, True]]), peak, sa)
    assert flags.tolist() == [["recommended", "inconclusive", None]]  # Rz: below the share
    flags = dynamic_analysis_flag(low, high, np.array([[False, True, True]]), peak, sa)
    assert flags[0, 0] is None  # GF undefined
    flags = dynamic_analysis_flag(low - 0.1, high - 0.05, np.ones((1, 3), bool), 2 * peak, sa)
    assert flags.tolist() == [["inconclusive", None, "inconclusive"]]  # Ry: upper bound exactly 10 %
    assert CONT_R_THRESHOLD == 0.10


def test_flag_state_at_another_threshold():
    """export --cont-r-threshold: the three-state rule recomputed from the interval in the JSON."""
    from types import SimpleNamespace

    from linecheck.io.display import flag_state
    from linecheck.io.document import ReactionResult, StatValue, StillAir

    def value(mean=None, ci=None):
        return StatValue(mean, None, None, None, None, None, ci=ci)

    def block(lo, hi, gf=1.3, peak=2000.0, state="x"):
        return ReactionResult({"Cont_R": value(ci=(lo, hi)), "GF_Dy": value(gf), "peak_dynamic": value(peak)}, state)

    reactions = {"Rx": block(0.06, 0.09), "Ry": block(0.03, 0.07), "Rz": block(0.06, 0.09, peak=2400.0)}
    doc = SimpleNamespace(reactions=reactions,  # |still air| 50 kN
                          still_air=StillAir({"Rx": 30_000.0, "Ry": 0.0, "Rz": 40_000.0}, [], None, 1.0))
    assert flag_state(doc, "Rx") == "x"  # 10 %: the document's own state
    assert flag_state(doc, "Rx", 0.05) is None  # peak 2 kN < 5 % of 50 kN
    assert flag_state(doc, "Rz", 0.05) is None  # 2.4 kN < 2.5 kN
    doc.still_air = StillAir({"Rx": 0.0, "Ry": 0.0, "Rz": 10_000.0}, [], None, 1.0)
    assert flag_state(doc, "Rx", 0.05) == "recommended"
    assert flag_state(doc, "Ry", 0.05) == "inconclusive"
    assert flag_state(doc, "Ry", 0.08) is None


def test_how_to_read_notes_only_when_they_apply():
    from types import SimpleNamespace

    from linecheck.io.display import HOW_TO_READ_GF_BELOW_1, HOW_TO_READ_NEGATIVE_CONT_BG, how_to_read
    from linecheck.io.document import ReactionResult, StatValue

    def means(**kw):
        return ReactionResult({k: StatValue(m, None, None, None, None, None) for k, m in kw.items()}, None)

    def doc(gf, bg):
        return SimpleNamespace(reactions={"Rx": means(GF_Dy=1.2, GF_QS=gf, Cont_BG=bg),
                                          "Ry": means(GF_Dy=None, GF_QS=None, Cont_BG=0.1)})

    assert how_to_read(doc(1.1, 0.05)) == []
    assert how_to_read(doc(0.94, -0.04)) == [HOW_TO_READ_GF_BELOW_1, HOW_TO_READ_NEGATIVE_CONT_BG]
    assert how_to_read(doc(0.99, 0.01)) == [HOW_TO_READ_GF_BELOW_1]

    # a negative Cont_R is explained too: the dynamic peak below the quasi-static one
    from linecheck.io.display import HOW_TO_READ_NEGATIVE_CONT_R

    neg_r = SimpleNamespace(reactions={"Rx": means(GF_Dy=1.1, GF_QS=1.2, Cont_BG=0.1, Cont_R=-0.08)})
    assert how_to_read(neg_r) == [HOW_TO_READ_NEGATIVE_CONT_R]
    assert "GF_Dy < GF_QS" in HOW_TO_READ_NEGATIVE_CONT_R and "damping" in HOW_TO_READ_NEGATIVE_CONT_R
    pos_r = SimpleNamespace(reactions={"Rx": means(GF_Dy=1.3, GF_QS=1.2, Cont_BG=0.1, Cont_R=0.08)})
    assert how_to_read(pos_r) == []
