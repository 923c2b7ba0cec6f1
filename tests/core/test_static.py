"""Step 1 against closed-form and independent solutions."""

from __future__ import annotations

import numpy as np
import pytest

from linecheck.core.errors import ConvergenceError
from linecheck.core.static import drag_intensity, solve_static, span_loads_uniform, still_air_state
from linecheck.core.system import LineSystem

from ..conftest import paper_line
from ..reference import irvine


@pytest.mark.parametrize("L", [300.0, 500.0])
@pytest.mark.parametrize("V", [0.0, 20.0, 40.0])
def test_single_span_matches_elastic_catenary(L, V):
    system = LineSystem(paper_line(L))
    g = float(drag_intensity(V, 1.25, 1.0, 0.022))
    st = solve_static(system, span_loads_uniform(system, g))
    Lu, EA = system.unstretched_length, system.line.ea
    Rx, Ry, Rz = irvine.reactions(L, Lu, 17.92, g, EA)
    # acceptance: within 0.5 % of the exact elastic catenary
    assert st.tension[0] == pytest.approx(Rx, rel=5e-3)
    assert st.reactions[0, 0] == pytest.approx(Rx, rel=5e-3)
    assert st.reactions[0, 1] == pytest.approx(Ry, rel=5e-3, abs=1e-6)
    assert st.reactions[0, 2] == pytest.approx(Rz, rel=5e-3)
    # the right tower mirrors the left one
    assert st.reactions[1] == pytest.approx(st.reactions[0] * np.array([-1, 1, 1]), rel=1e-9, abs=1e-6)
    # deformed mid-span sag in the plane of the resultant load (Irvine Eq. 2.6)
    w = np.hypot(17.92, g)
    mid = st.nodes[system.ne // 2]
    assert np.hypot(mid[1], mid[2]) == pytest.approx(irvine.midspan_sag(L, Lu, w, EA), rel=5e-3)


def test_still_air_state_is_the_nominal_reference():
    """Zero wind reproduces the issue's reference: T0 = W L^2/(8S) within the parabola error."""
    system = LineSystem(paper_line(300.0))
    st = still_air_state(system)
    # Table 1: T0 = 20 kN (20.16 kN exactly); the elastic catenary differs by < 0.5 %
    assert st.tension[0] == pytest.approx(system.tension_nominal, rel=5e-3)
    assert st.nodes[5, 2] == pytest.approx(-system.line.sag, rel=1e-2)


def test_six_spans_uniform_wind_equilibrium_and_symmetry():
    system = LineSystem(paper_line(300.0, spans=6))
    g = float(drag_intensity(40.0, 1.25, 1.0, 0.022))
    st = solve_static(system, span_loads_uniform(system, g))
    Lu = system.unstretched_length
    R = st.reactions
    # global equilibrium: the towers carry all the load
    assert R[:, 0].sum() == pytest.approx(0.0, abs=1e-6)
    assert R[:, 1].sum() == pytest.approx(6 * g * Lu, rel=1e-12)
    assert R[:, 2].sum() == pytest.approx(6 * 17.92 * Lu, rel=1e-12)
    # symmetry: R_x at the middle tower vanishes to round-off; mirror towers agree
    assert abs(R[3, 0]) < 1e-6 * abs(R[0, 0])
    np.testing.assert_allclose(R[::-1] * [-1, 1, 1], R, rtol=1e-8, atol=1e-6)
    # insulators swing with the load: d_y = v R_y / R_res (paper Eq. 4)
    d = st.displacement
    np.testing.assert_allclose(d[1:-1, 1], 4.0 * R[1:-1, 1] / st.insulator_force[1:-1], rtol=1e-6)
    assert st.residual < 1e-3


def test_absurd_load_raises_convergence_error_naming_the_state():
    system = LineSystem(paper_line(300.0))
    with pytest.raises(ConvergenceError, match=r"bad state.*strain.*out-of-balance"):
        solve_static(system, span_loads_uniform(system, 1e6), label="bad state")


def test_iteration_limit_raises_with_residual():
    system = LineSystem(paper_line(300.0, spans=6))
    gy = span_loads_uniform(system, np.array([400.0, 400, 400, 0, 0, 0]))
    with pytest.raises(ConvergenceError, match=r"state X.*did not converge in 2 iterations.*out-of-balance force"):
        solve_static(system, gy, max_iter=2, label="state X")


def test_batched_mean_states_match_the_sequential_solver():
    """Step 1 at the 250 mean states of a six-span downburst, vectorised over the states,
    against solve_static state by state (warm-started from the previous state): the same
    converged equilibria to the solver tolerance (1e-8 v on the attachment displacements)."""
    from linecheck.core.case import load_case
    from linecheck.core.static import solve_mean_states, solve_static
    from linecheck.service import static_analysis

    from ..conftest import CASES

    st = static_analysis(load_case(CASES / "paper" / "case05-six.toml"))
    m = st.mean
    assert m.time.size == 250
    prev, seq = m.still_air, []
    for k in range(0, m.time.size, 10):  # every 10th state, each warm-started from the last
        prev = solve_static(st.system, m.gy[k], initial=prev)
        seq.append(prev)
    ks = np.arange(0, m.time.size, 10)
    R = np.stack([s.reactions for s in seq])
    np.testing.assert_allclose(m.reactions[ks], R, rtol=0, atol=1e-8 * np.abs(R).max())
    np.testing.assert_allclose(m.tension[ks], np.stack([s.tension for s in seq]), rtol=1e-9)
    np.testing.assert_allclose(m.nodes[ks], np.stack([s.nodes for s in seq]), rtol=0, atol=1e-6)
    # a bad state is named in the error
    gy = m.gy.copy()
    gy[17, 2, 3] = np.nan
    with pytest.raises(ConvergenceError, match="mean state 18 of 250"):
        solve_mean_states(st.system, m.time, gy)


def test_vectorised_tridiagonal_solve_matches_dense():
    from linecheck.core.static import _tridiag_solve

    rng = np.random.default_rng(5)
    n_b, k = 7, 6
    off = rng.random((n_b, k - 1))
    diag = -(1.0 + rng.random((n_b, k)) + np.pad(off, ((0, 0), (0, 1))) + np.pad(off, ((0, 0), (1, 0))))
    b = rng.standard_normal((n_b, k))
    x = _tridiag_solve(off, diag, off, b)
    for i in range(n_b):
        A = np.diag(diag[i]) + np.diag(off[i], 1) + np.diag(off[i], -1)
        np.testing.assert_allclose(A @ x[i], b[i], rtol=0, atol=1e-13)


def test_final_states_are_batch_invariant_and_hang_from_the_attachments():
    """The deformed shapes and element tensions of many converged states in one
    vectorised pass (static._final_states): a state's arrays are the same bits alone as in the
    batch; the shape starts and ends at the attachment points, and every element's tension is at
    least the span's horizontal tension (T = H ds/dx)."""
    from linecheck.core.static import _final_states, _Spans, solve_static_batch

    system = LineSystem(paper_line(6))
    g = drag_intensity(np.array([10.0, 25.0, 40.0, 32.0]), 1.25, 1.0, 0.022)
    gy = np.stack([span_loads_uniform(system, gi * np.linspace(0.6, 1.0, system.n_spans)) for gi in g])
    states = solve_static_batch(system, gy, labels=[f"s{k}" for k in range(g.size)])
    sp = _Spans(system, gy)
    d, H, R, Rres = (np.stack([getattr(s, f) for s in states])
                     for f in ("displacement", "tension", "reactions", "insulator_force"))
    it = np.array([s.iterations for s in states])
    res = np.array([s.residual for s in states])
    for j, s in enumerate(states):
        one = _final_states(system, sp.Lu, sp.my_hat[j:j + 1], sp.mz_hat, d[j:j + 1], H[j:j + 1], R[j:j + 1],
                            Rres[j:j + 1], it[j:j + 1], res[j:j + 1], [f"s{j}"])[0]
        assert np.array_equal(one.nodes, s.nodes) and np.array_equal(one.element_tension, s.element_tension)
        ends = s.nodes[::system.ne]  # the span ends: the attachment points (tower x + d)
        att = np.column_stack([system.tower_x, np.zeros(system.n_towers), np.zeros(system.n_towers)]) + s.displacement
        assert np.allclose(ends, att, rtol=0.0, atol=1e-9)
        assert np.all(s.element_tension >= np.repeat(s.tension, system.ne) * (1.0 - 1e-15))
    assert not np.array_equal(states[0].nodes, states[2].nodes)
    with pytest.raises(ConvergenceError, match="s2: no admissible equilibrium"):
        big = H.copy()
        big[2] *= 1e4  # a strain far above MAX_STRAIN
        _final_states(system, sp.Lu, sp.my_hat, sp.mz_hat, d, big, R, Rres, it, res, [f"s{k}" for k in range(g.size)])
