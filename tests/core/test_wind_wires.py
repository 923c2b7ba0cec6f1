"""One turbulence field for every wire (linecheck/core/wind/wires.py; docs/wind.md "Many wires").

Wire 0 is today's single-wire synthesis bit for bit; wires at one point share one field exactly;
the synthesized cross-spectrum of two wires' nodes matches the target coherence
exp(-f (C_x |dx| + C_y |dy| + C_z |dz|) / V) within a sampling error derived below.  The
references are built here from the formulas (dense matrices, scipy's Cholesky), not from the
code under test.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import cholesky

from linecheck.core.case import load_case
from linecheck.core.errors import Cancelled
from linecheck.core.system import LineSystem
from linecheck.core.wind import turbulence as tb
from linecheck.core.wind import wires as ww

from ..conftest import CASES

PAPER = CASES / "paper" / "case09-six.toml"  # synoptic, six equal spans (KMS path)
SECTION = CASES / "examples" / "section-12span.toml"  # unequal spans (Markov path)
OFFSETS = np.array([[0.0, 0.0], [-6.5, 2.0], [6.5, 2.0], [0.0, 9.0]])  # [m] (y, z) of four wires


@pytest.fixture(params=["numpy", "auto"])
def kernel_mode(request, monkeypatch):
    """The numpy forms, and the compiled kernel where Numba is installed."""
    monkeypatch.setenv("LINECHECK_KERNEL", request.param)
    return request.param


# --------------------------------------------------------------------------- wire 0 is today's field
@pytest.mark.parametrize("points", ["equal", "unequal", "unordered"])
@pytest.mark.parametrize("lead", [0, 37])
def test_wire_0_is_the_single_wire_synthesis_bit_for_bit(points, lead, kernel_mode):
    x = {"equal": np.arange(9) * 12.5,
         "unequal": np.cumsum(np.r_[0.0, [12.5, 30.0, 30.0, 7.5, 12.5]]),
         "unordered": np.array([0.0, 40.0, 12.5, 30.0, 55.0])}[points]
    grid = tb.spectral_grid(600, 0.1, 173.3, 30.0)
    phases = ww.wire_phases(11, 2, range(4), x.size, grid.n_freq)
    u = ww.synthesize_wires(x, OFFSETS, grid, phases, 10.0, 30.0, lead=lead)
    assert u.shape == (4, lead + 600, x.size)
    ref = tb.synthesize(x, grid, tb.unit_phases(11, 2, x.size, grid.n_freq), 10.0, 30.0, lead=lead)
    assert np.array_equal(u[0], ref)
    assert not np.allclose(u[1], u[0])


@pytest.mark.parametrize("path", [PAPER, SECTION])
def test_case_level_wire_0_equals_unit_field_and_fluctuating_velocity(path, kernel_mode):
    case = load_case(path)
    system = LineSystem(case.line)
    u = ww.unit_field_wires(case, system, OFFSETS, 500, 0.05, 4, lead=25)
    assert np.array_equal(u[0], tb.unit_field(case, system, 500, 0.05, 4, lead=25))
    t = np.arange(-25, 500) * 0.05
    v = ww.fluctuating_velocity_wires(case, system, OFFSETS, t, [1, 4], lead=25)
    assert v.shape == (4, 2, t.size, system.n_nodes)
    assert np.array_equal(v[0], tb.fluctuating_velocity(case, system, t, [1, 4], lead=25))
    # the analysed record does not depend on the lead (common random numbers), for every wire
    assert np.array_equal(ww.unit_field_wires(case, system, OFFSETS, 500, 0.05, 4), u[:, 25:])


def test_one_wire_is_exactly_today_wherever_it_is():
    case = load_case(PAPER)
    system = LineSystem(case.line)
    ref = tb.unit_field(case, system, 400, 0.05, 0)
    for off in ([[0.0, 0.0]], [[3.0, 40.0]]):
        u = ww.unit_field_wires(case, system, np.array(off), 400, 0.05, 0)
        assert u.shape == (1, 400, system.n_nodes)
        assert np.array_equal(u[0], ref)


def test_a_per_wire_modulation_scales_each_wire_and_cancel_stops():
    case = load_case(PAPER)
    system = LineSystem(case.line)
    t = np.arange(300) * 0.05
    a = np.stack([np.full((t.size, system.n_nodes), s) for s in (1.0, 2.0, 3.0, 4.0)])
    v = ww.fluctuating_velocity_wires(case, system, OFFSETS, t, [0], a=a)
    u = ww.unit_field_wires(case, system, OFFSETS, t.size, 0.05, 0)
    for w in range(4):
        assert np.array_equal(v[w, 0], u[w] * (w + 1.0))

    class _Set:
        def is_set(self):
            return True

    with pytest.raises(Cancelled):
        ww.fluctuating_velocity_wires(case, system, OFFSETS, t, [0], cancel=_Set())


def test_realizations_are_the_same_bits_whatever_the_chunk_and_the_lead_wraps(kernel_mode):
    """The realizations of one call share the spectra's buffer and the factors: each realization's
    field is still its own (any chunking, any order); a lead longer than the transform wraps the
    periodic continuation more than once (np.take's "wrap", as turbulence.synthesize)."""
    case = load_case(SECTION)
    system = LineSystem(case.line)
    off = np.vstack([OFFSETS, OFFSETS[2:3]])  # a fifth wire at the third one's point
    t = np.arange(-30, 400) * 0.05
    both = ww.fluctuating_velocity_wires(case, system, off, t, [3, 1], lead=30)
    for i, r in enumerate((3, 1)):
        assert np.array_equal(both[:, i], ww.fluctuating_velocity_wires(case, system, off, t, [r], lead=30)[:, 0])
    assert np.array_equal(both[4], both[2])
    long = ww.unit_field_wires(case, system, OFFSETS, 300, 0.05, 2, lead=700)  # 700 > n_fft = 300
    ref = ww.unit_field_wires(case, system, OFFSETS, 300, 0.05, 2)
    assert np.array_equal(long, ref[:, np.arange(-700, 300) % 300])
    assert np.array_equal(long[0], tb.unit_field(case, system, 300, 0.05, 2, lead=700))


def test_unit_modulation_leaves_the_unit_field():
    """a = 1 (what run_wires passes before each wire's own modulation) is the unit field itself,
    and a scalar modulation the unit field times it, bit for bit."""
    case = load_case(PAPER)
    system = LineSystem(case.line)
    t = np.arange(300) * 0.05
    u = ww.unit_field_wires(case, system, OFFSETS, t.size, 0.05, 5)
    assert np.array_equal(ww.fluctuating_velocity_wires(case, system, OFFSETS, t, [5], a=np.ones((1, 1)))[:, 0], u)
    assert np.array_equal(ww.fluctuating_velocity_wires(case, system, OFFSETS, t, [5], a=np.full((1, 1), 3.5))[:, 0],
                          u * 3.5)


# --------------------------------------------------------------------------- the mixing across wires
def _raw_spectra(n_p: int, n_nodes: int, n_freq: int, seed: int = 7) -> np.ndarray:
    rng = np.random.default_rng(seed)
    spec = np.zeros((n_p, n_nodes, n_freq + 2), dtype=complex)
    spec[:, :, 1:n_freq + 1] = rng.standard_normal((n_p, n_nodes, n_freq)) + 1j * rng.standard_normal(
        (n_p, n_nodes, n_freq))
    return spec


def test_mixing_is_the_kronecker_factor_applied_per_frequency():
    """mix_wires_numpy: point p's bins = sum_(q<=p) L_w[p, q](f) times point q's raw bins (the
    (L_w (x) I) product written as a dense matrix per frequency here), the other bins untouched."""
    f = np.arange(1, 41) * 0.03
    low = ww.wire_factor(f, OFFSETS, 25.0)
    raw = _raw_spectra(4, 5, f.size)
    got = raw.copy()
    ww.mix_wires_numpy(got, low, 1)
    ref = np.einsum("pqk,qjk->pjk", low, raw[:, :, 1:f.size + 1])
    assert np.allclose(got[:, :, 1:f.size + 1], ref, rtol=0, atol=1e-14)
    assert np.array_equal(got[0], raw[0]) and not got[:, :, [0, f.size + 1]].any()


def test_compiled_mixing_agrees_with_numpy_and_is_on_where_numba_is(monkeypatch):
    """The piece ``mixing`` (kernel.mix_wires): on where Numba is installed (its load check
    passed), within kernel.RTOL of mix_wires_numpy, semidefinite factors (zero columns) included."""
    from linecheck.core import kernel

    monkeypatch.setenv("LINECHECK_KERNEL", "auto")
    if not kernel.installed():
        pytest.skip("Numba (linecheck[fast]) not installed")
    assert kernel.use("mixing"), [p.reason for p in kernel.status() if p.name == "mixing"]
    f = np.arange(1, 61) * 0.02
    for off in (OFFSETS, np.array([[0.0, 0.0], [0.0, 0.0], [1e-9, 3.0], [0.0, 3.0]])):
        low = ww.wire_factor(f, off, 30.0)
        raw = _raw_spectra(off.shape[0], 6, f.size, seed=11)
        ref, got = raw.copy(), raw.copy()
        ww.mix_wires_numpy(ref, low, 1)
        kernel.mix_wires(got, low, 1)
        assert kernel.relative_difference(ref.view(float), got.view(float)) <= kernel.RTOL


# --------------------------------------------------------------------------- randomness
def test_extra_wires_draw_from_spawned_children_of_the_realization():
    ss = np.random.SeedSequence(5, spawn_key=(3,)).spawn(3)[2]
    assert np.array_equal(ww.wire_rng(5, 3, 2).random(8), np.random.Generator(np.random.PCG64(ss)).random(8))
    p = ww.wire_phases(5, 3, [0, 1, 2], 4, 50)
    assert np.array_equal(p[0].phases, tb.random_phases(5, 3, 4, 50))  # wire 0: the single-wire stream
    assert not np.allclose(p[1].phases, p[2].phases)
    assert not np.allclose(p[1].phases, tb.random_phases(5, 4, 4, 50))  # not another realization's


def test_appending_a_wire_changes_none_of_the_others():
    x = np.arange(7) * 20.0
    grid = tb.spectral_grid(256, 0.1, 173.3, 30.0)
    three = ww.synthesize_wires(x, OFFSETS[:3], grid, ww.wire_phases(1, 0, range(3), 7, grid.n_freq), 10.0, 30.0)
    four = ww.synthesize_wires(x, OFFSETS, grid, ww.wire_phases(1, 0, range(4), 7, grid.n_freq), 10.0, 30.0)
    assert np.array_equal(four[:3], three)


# --------------------------------------------------------------------------- coincident and coherent wires
def test_wires_at_one_point_get_identical_fields():
    x = np.arange(9) * 12.5
    grid = tb.spectral_grid(400, 0.1, 173.3, 30.0)
    off = np.array([[0.0, 0.0], [4.0, 3.0], [0.0, 0.0], [4.0, 3.0], [-0.0, 0.0]])
    u = ww.synthesize_wires(x, off, grid, ww.wire_phases(2, 1, range(5), x.size, grid.n_freq), 10.0, 30.0)
    assert np.array_equal(u[2], u[0]) and np.array_equal(u[4], u[0]) and np.array_equal(u[3], u[1])
    assert not np.allclose(u[1], u[0])


def test_fully_coherent_wires_all_equal_the_single_wire_field():
    """C_y = C_z = 0: Gamma_w is all ones (rank 1); the semidefinite factor's zero columns give
    every wire wire 0's field exactly, wherever the wires are."""
    case = load_case(SECTION)
    system = LineSystem(case.line)
    ref = tb.unit_field(case, system, 300, 0.05, 2)
    u = ww.unit_field_wires(case, system, OFFSETS, 300, 0.05, 2, cross=ww.CrossCoherence(0.0, 0.0))
    for w in range(4):
        assert np.array_equal(u[w], ref)
    low = ww.wire_factor(np.array([0.1, 1.0]), OFFSETS, 30.0, ww.CrossCoherence(0.0, 0.0))
    assert np.array_equal(low[:, 0], np.ones((4, 2))) and not low[:, 1:].any()


def test_nearly_coincident_wires_are_nearly_equal_and_finite():
    x = np.arange(5) * 25.0
    grid = tb.spectral_grid(400, 0.1, 173.3, 30.0)
    off = np.array([[0.0, 0.0], [1e-9, 0.0], [0.0, 1e-7]])
    u = ww.synthesize_wires(x, off, grid, ww.wire_phases(2, 1, range(3), x.size, grid.n_freq), 10.0, 30.0)
    assert np.all(np.isfinite(u))
    assert np.max(np.abs(u[1] - u[0])) < 1e-3 and np.max(np.abs(u[2] - u[0])) < 1e-2


def test_semidefinite_cholesky_matches_scipy_and_reproduces_rank_deficient_matrices():
    rng = np.random.default_rng(3)
    b = rng.normal(size=(5, 5))
    pd = b @ b.T + 5 * np.eye(5)
    low = ww.semidefinite_cholesky(pd[:, :, None])[:, :, 0]
    assert np.allclose(low, cholesky(pd, lower=True), rtol=0, atol=1e-13)
    r = rng.normal(size=(5, 2))
    psd = r @ r.T  # rank 2
    psd = psd[[0, 1, 0, 2, 3]][:, [0, 1, 0, 2, 3]]  # a repeated point too
    low = ww.semidefinite_cholesky(psd[:, :, None])[:, :, 0]
    assert np.allclose(low @ low.T, psd, rtol=0, atol=1e-10)
    assert np.array_equal(np.triu(low, 1), np.zeros((5, 5)))


@pytest.mark.parametrize("combine", ww.COMBINATIONS)
def test_wire_factor_reproduces_the_target_coherence(combine):
    f = np.array([0.01, 0.1, 0.5, 2.0])
    cross = ww.CrossCoherence(16.0, 10.0, combine)
    low = ww.wire_factor(f, OFFSETS, 25.0, cross)
    assert low.shape == (4, 4, f.size)  # the small n_w x n_w factor per frequency, nothing bigger
    dy = np.abs(OFFSETS[:, None, 0] - OFFSETS[None, :, 0])
    dz = np.abs(OFFSETS[:, None, 1] - OFFSETS[None, :, 1])
    reach = 16 * dy + 10 * dz if combine == "sum" else np.sqrt((16 * dy) ** 2 + (10 * dz) ** 2)
    for k, fk in enumerate(f):
        target = np.exp(-fk * reach / 25.0)
        assert np.allclose(low[:, :, k] @ low[:, :, k].T, target, rtol=0, atol=1e-13)
        assert np.array_equal(low[0, :, k], np.eye(4)[0])


def test_ordered_points_never_take_the_dense_path(monkeypatch):
    """Cost O(n_w^2 N) per frequency: ordered stations go through the O(N) recursion, never the
    dense N x N factor (nor an n_w N x n_w N one, which the module has no code for)."""
    def _dense(*_a, **_k):
        raise AssertionError("dense factor used")

    monkeypatch.setattr(tb, "general_apply", _dense)
    grid = tb.spectral_grid(200, 0.1, 173.3, 30.0)
    for x in (np.arange(6) * 10.0, np.array([0.0, 10.0, 25.0, 30.0, 50.0, 51.0])):
        ww.synthesize_wires(x, OFFSETS, grid, ww.wire_phases(0, 0, range(4), x.size, grid.n_freq), 10.0, 30.0)


# --------------------------------------------------------------------------- the cross-spectrum
# Sampling error.  The record is one FFT period (lead 0, fft_length "record"), so the FFT of a
# synthesized record returns its bins exactly: Y_k = (M/2) A_k y_k, and y_k = (L_k xi_k) with
# xi_pk = exp(i phi_pk), the phases independent and uniform.  For nodes P = (wire a, node j) and
# Q = (wire b, node m) let alpha, beta be their rows of L (real; unit norm; alpha.beta = gamma).
# The sample c_k = Re(y_P conj(y_Q)) = sum_p alpha_p beta_p + sum_(p<q) (alpha_p beta_q +
# alpha_q beta_p) cos(phi_p - phi_q): its mean is gamma (|xi| = 1), and the cosines of distinct
# pairs are uncorrelated with variance 1/2, so
#     Var c_k = (1/2) sum_(p<q) (alpha_p beta_q + alpha_q beta_p)^2 = (1/2) (1 + gamma^2 - 2 sum_p alpha_p^2 beta_p^2)
# (expand the square over all p != q).  With L = L_w (x) L_x the last sum factors as
# (sum_q L_w[a,q]^2 L_w[b,q]^2) (sum_i L_x[j,i]^2 L_x[m,i]^2).  Bins and realizations are independent
# (independent phases), so the mean of c_k - gamma_k over n samples of a band has standard error
# sqrt(sum Var c_k) / n, and the test allows 4 of them.
N_STEPS, DT, V, L_U, C_X = 2048, 0.1, 20.0, 173.3, 10.0
X = np.array([0.0, 12.5, 30.0, 42.5])  # unequal gaps: the Markov path
N_REAL = 200
BANDS = [(0.01, 0.05), (0.05, 0.15), (0.15, 0.4), (0.4, 1.0)]  # [Hz]
PAIRS = [(0, 0, 1, 0), (1, 0, 3, 0), (0, 1, 3, 1), (1, 2, 2, 2), (0, 0, 3, 2), (2, 1, 1, 3), (3, 1, 3, 1)]  # (a, j, b, m)


def _reach(cross: ww.CrossCoherence) -> np.ndarray:
    dy = np.abs(OFFSETS[:, None, 0] - OFFSETS[None, :, 0])
    dz = np.abs(OFFSETS[:, None, 1] - OFFSETS[None, :, 1])
    if cross.combine == "sum":
        return cross.decay_y * dy + cross.decay_z * dz
    return np.hypot(cross.decay_y * dy, cross.decay_z * dz)


@pytest.fixture(scope="module", params=ww.COMBINATIONS)
def ensemble(request):
    cross = ww.CrossCoherence(16.0, 10.0, request.param)
    grid = tb.spectral_grid(N_STEPS, DT, L_U, V)
    scale = (0.5 * grid.n_fft * grid.amplitude)[None, :, None]
    y = np.empty((N_REAL, OFFSETS.shape[0], grid.n_freq, X.size), dtype=complex)
    for r in range(N_REAL):
        u = ww.synthesize_wires(X, OFFSETS, grid, ww.wire_phases(2024, r, range(4), X.size, grid.n_freq),
                                C_X, V, cross)
        y[r] = np.fft.rfft(u, axis=1)[:, 1:grid.n_freq + 1, :] / scale
    return cross, grid, y


def _rows(f: float, cross: ww.CrossCoherence) -> tuple[np.ndarray, np.ndarray]:
    """Reference Cholesky factors of the wires' and the nodes' coherence at f (scipy, dense)."""
    lw = cholesky(np.exp(-f * _reach(cross) / V), lower=True)
    lx = cholesky(np.exp(-C_X * f * np.abs(X[:, None] - X[None, :]) / V), lower=True)
    return lw, lx


@pytest.mark.parametrize("pair", PAIRS)
def test_cross_spectrum_matches_the_target_coherence_within_four_standard_errors(ensemble, pair):
    cross, grid, y = ensemble
    a, j, b, m = pair
    reach = C_X * abs(X[j] - X[m]) + _reach(cross)[a, b]  # [m] C_x |dx| + the wires' term
    for lo, hi in BANDS:
        k = np.nonzero((grid.freq >= lo) & (grid.freq < hi))[0]
        target = np.exp(-grid.freq[k] * reach / V)  # gamma_k
        c = (y[:, a, k, j] * np.conj(y[:, b, k, m])).real  # (N_REAL, n_k) samples of Re(y_P conj y_Q)
        var = np.empty(k.size)
        for i, f in enumerate(grid.freq[k]):
            lw, lx = _rows(f, cross)
            s4 = np.sum(lw[a] ** 2 * lw[b] ** 2) * np.sum(lx[j] ** 2 * lx[m] ** 2)
            var[i] = 0.5 * (1.0 + target[i] ** 2 - 2.0 * s4)
        n = c.size
        se = np.sqrt(N_REAL * var.sum()) / n
        err = float(np.mean(c - target[None, :]))
        assert abs(err) <= 4.0 * se + 1e-12, (pair, (lo, hi), err, se)
        if a != b and (lo, hi) == BANDS[0] and _reach(cross)[a, b] > 0:
            # the test has power: a synthesis without the wires' factor (gamma_x alone) would fail it
            alt = np.exp(-grid.freq[k] * C_X * abs(X[j] - X[m]) / V)
            assert abs(float(np.mean(c - alt[None, :]))) > 4.0 * se
        if pair == (1, 0, 3, 0) and (lo, hi) == BANDS[1]:
            # dy and dz both non-zero: the test tells the two combinations apart
            other = ww.CrossCoherence(16.0, 10.0, "root" if cross.combine == "sum" else "sum")
            alt = np.exp(-grid.freq[k] * _reach(other)[a, b] / V)
            assert abs(float(np.mean(c - alt[None, :]))) > 4.0 * se
