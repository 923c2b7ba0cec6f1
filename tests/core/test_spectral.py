"""Frequency-domain estimates against the time domain and closed forms (docs/method.md,
"Frequency-domain check")."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy.integrate import dblquad

from linecheck import service
from linecheck.core.case import load_case
from linecheck.core.spectral import _quad_kms, joint_acceptance_uniform, peak_factor

from ..conftest import CASES

QUANTITIES = ("rms_background", "rms_resonant", "rms_fluctuating")


def synoptic(name: str, **analysis):
    case = load_case(CASES / "paper" / f"{name}.toml")
    analysis.setdefault("damping", "quasi-steady")
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


def gaussian_mean_gust_factor(f: np.ndarray, S: np.ndarray, mean: float, T: float, dt: float,
                              records: int = 400, seed: int = 7) -> float:
    """Mean over Gaussian records of max_t |M + x(t)| / |M|, x with the one-sided spectrum S(f).

    Independent of Davenport's formula: x is synthesised by the spectral representation on
    the FFT grid k/T, each bin carrying the variance of S over [f_k - 1/2T, f_k + 1/2T]
    (cumulative trapezoid on the estimate's own grid, so narrow peaks keep their area)."""
    n = int(round(T / dt))
    fk = np.fft.rfftfreq(n, dt)[1:]
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (S[1:] + S[:-1]) * np.diff(f))])
    edges = np.concatenate([fk - 0.5 / T, [fk[-1] + 0.5 / T]])
    var = np.diff(np.interp(edges, f, cum))
    rng = np.random.default_rng(seed)
    X = np.zeros((records, n // 2 + 1), complex)
    X[:, 1:] = 0.5 * np.sqrt(2.0 * var) * np.exp(2j * np.pi * rng.random((records, fk.size))) * n
    x = np.fft.irfft(X, n, axis=1)
    return float(np.mean(np.abs(mean + x).max(axis=1)) / abs(mean))


def compare(name: str) -> None:
    """Time domain (20 realizations of 600 s after the burn-in) against estimate 1.

    Tolerances: the issue's 5 % on r.m.s.  The sampling error of a 20-realization mean of
    an r.m.s. is std/sqrt(20) <= 1.6 % here (std over realizations <= 7 %), the frequency
    grid adds < 1 %.

    Gust factors, twice.  (1) Against the mean peak of Gaussian records with estimate 1's own
    spectra (:func:`gaussian_mean_gust_factor`): the like-for-like comparison of the two
    methods, within the issue's 5 %.  (2) Against estimate 1's GF with Davenport's asymptotic
    peak factor (the issue's formula), which overestimates the mean 600-s maximum of these
    low-frequency-dominated responses: a pure Gaussian process with a span's background
    spectrum shows a 5-15 % bias (:func:`test_davenport_peak_factor_bias_on_a_gaussian_process`)
    and the six-span transverse background up to 22 % on GF - 1, so the time-domain GF - 1 lies
    0.75-1.02 x Davenport's (docs/validation.md).
    """
    case = synoptic(name, realizations=20)
    res = service.run_case(case)
    assert res.burn_in.sufficient
    j = res.tower_index
    ex = res.spectral.exact
    scale = float(np.max(ex.rms_fluctuating))
    for q in QUANTITIES:
        td, fd = res.stats.mean(q)[j], getattr(ex, q)
        for c in range(3):
            if fd[c] > 0.01 * scale:
                assert td[c] == pytest.approx(fd[c], rel=0.05), (q, c, td[c], fd[c])
    T = float(res.time[-1] - res.time[0]) + case.analysis.time_step
    for q, psd in (("GF_QS", ex.psd_background), ("GF_Dy", ex.psd_fluctuating)):
        td, fd = res.stats.mean(q)[j], getattr(ex, q)
        for c in range(2):
            if np.isfinite(fd[c]):
                gauss = gaussian_mean_gust_factor(ex.frequencies, psd[:, c], ex.mean[c], T, case.analysis.time_step)
                assert td[c] == pytest.approx(gauss, rel=0.05), (q, c, td[c], gauss)
                # gust-factor excess over 1 carries Davenport's bias: compare GF - 1
                assert 0.75 * (fd[c] - 1) <= td[c] - 1 <= 1.02 * (fd[c] - 1), (q, c, td[c], fd[c])
    # the run's own sanity check agrees
    assert all(item.ok for item in service.sanity_check(res))


@pytest.mark.parametrize("name", ["case09-single", "case10-single"])
def test_time_vs_frequency_domain_single_span(name):
    compare(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["case09-six", "case10-six"])
def test_time_vs_frequency_domain_six_spans(name):
    compare(name)


def test_davenport_closed_form_close_to_exact_for_single_span_ry():
    for name in ("case09-single", "case10-single"):
        sp = service.spectral_analysis(synoptic(name))
        assert sp.davenport_applicable
        assert sp.davenport.GF_Dy == pytest.approx(sp.exact.GF_Dy[1], rel=0.15)


def test_joint_acceptance_closed_form():
    """|J|^2 = 2/eta - 2(1 - e^-eta)/eta^2 equals the double integral of exp(-eta |s - s'|)."""
    for eta in (0.1, 1.0, 7.5):
        num, _ = dblquad(lambda a, b: np.exp(-eta * abs(a - b)), 0, 1, 0, 1)  # noqa: B023 - called at once, in this iteration
        assert joint_acceptance_uniform(eta) == pytest.approx(num, rel=1e-6)  # dblquad accuracy at the |s - s'| kink
    assert joint_acceptance_uniform(1e-9) == pytest.approx(1.0)


def test_kms_quadratic_form_matches_dense():
    rng = np.random.default_rng(5)
    w = rng.standard_normal((4, 2, 13)) + 1j * rng.standard_normal((4, 2, 13))
    rho = np.array([0.0, 0.3, 0.9, 0.999])
    for k in range(4):
        idx = np.arange(13)
        coh = rho[k] ** np.abs(idx[:, None] - idx[None, :])
        dense = np.einsum("ri,ij,rj->r", w[k].conj(), coh, w[k]).real
        np.testing.assert_allclose(_quad_kms(w, rho)[k], dense, rtol=1e-12)


def test_peak_factor_values():
    # Davenport (1964): g(nu T = 1000) = sqrt(2 ln 1000) + 0.5772 / sqrt(2 ln 1000) = 3.8830
    assert float(peak_factor(1.0, 1000.0)) == pytest.approx(3.71692 + 0.57722 / 3.71692, rel=1e-4)


def test_spectral_command_writes_json(tmp_path):
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    out = tmp_path / "s.json"
    r = CliRunner().invoke(app, ["spectral", str(CASES / "paper" / "case10-single.toml"), "--json", str(out)])
    assert r.exit_code == 0, r.output
    doc = json.loads(out.read_text())
    assert set(doc["exact"]) == {"Rx", "Ry", "Rz"}
    for key in ("mean", "rms_background", "rms_resonant", "peak_dynamic", "GF_Dy", "GF_QS", "Cont_R"):
        assert key in doc["exact"]["Ry"]
    assert doc["davenport"]["applicable"] is True and doc["davenport"]["GF_Dy"] > 1
    r = CliRunner().invoke(app, ["spectral", str(CASES / "paper" / "case01-single.toml")])
    assert r.exit_code == 2 and "synoptic cases only" in r.output


def test_davenport_peak_factor_bias_on_a_gaussian_process():
    """Independent of linecheck's solver: a stationary Gaussian process with the spectrum of a
    span's background reaction (von Karman x uniform joint acceptance, 20 m/s, 300 m) has a
    mean 600-s maximum 5-15 % below Davenport's expected peak (400 FFT records, seed 1; the
    standard error of the mean maximum is 0.7 %)."""
    from linecheck.core.wind.turbulence import von_karman_psd

    L, V, C, span, T, dt = 173.33, 20.0, 10.0, 300.0, 600.0, 0.05
    n = int(T / dt)
    f = np.fft.rfftfreq(n, dt)[1:]
    S = von_karman_psd(f, L, V) * joint_acceptance_uniform(C * f * span / V)
    df = f[1] - f[0]
    m0, m2 = np.sum(S) * df, np.sum(S * f**2) * df
    g = float(peak_factor(np.sqrt(m2 / m0), T))
    rng = np.random.default_rng(1)
    X = np.zeros((400, n // 2 + 1), complex)
    X[:, 1:] = np.sqrt(S * df / 2) * np.exp(1j * rng.uniform(0, 2 * np.pi, (400, f.size))) * n
    peaks = np.fft.irfft(X, n, axis=1).max(axis=1) / np.sqrt(m0)
    assert 0.85 * g < peaks.mean() < 0.95 * g


def test_run_no_check_skips_the_frequency_domain_and_changes_nothing_else(tmp_path):
    """``linecheck run --no-check``: no "spectral" block, the time-domain results identical."""
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    src = (CASES / "paper" / "case10-single.toml").read_text()
    case_file = tmp_path / "short.toml"
    case_file.write_text(src.replace("duration = 600.0", "duration = 60.0").replace("realizations = 10", "realizations = 2"))
    docs = {}
    for flag in ([], ["--no-check"]):
        out = tmp_path / f"r{len(flag)}.json"
        r = CliRunner().invoke(app, ["run", str(case_file), "--json", str(out), *flag])
        assert r.exit_code == 0, r.output
        docs[len(flag)] = json.loads(out.read_text())
    assert "spectral" in docs[0] and "spectral" not in docs[1]
    assert docs[0]["reactions"] == docs[1]["reactions"]
