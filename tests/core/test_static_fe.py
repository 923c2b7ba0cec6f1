"""Step 1 against an independent non-linear FE reference (step 1 acceptance).

The reference (``tests/reference/fe_static.py``) models every span with 80 exact
(large-displacement) cable elements and every suspension insulator with a stiff truss,
and is solved by Newton-Raphson with load stepping; it is first validated against the
exact elastic catenary (Irvine 1981, ``tests/reference/irvine.py``).  linecheck's
semi-analytical solver (paper Appendix A, one element per span) must then match it
within 1 % on the paper's six-span system with only the three left spans loaded.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from linecheck.core.static import solve_static
from linecheck.core.system import LineSystem

from ..conftest import paper_line
from ..reference import irvine
from ..reference.fe_static import solve_fe

RHO, CD, D, W = 1.25, 1.0, 0.022, 17.92  # paper Table 1 (kg/m3, -, m, N/m)
TOL = 0.01  # acceptance: within 1 % of the FE solution
LEFT_LOADED = (1.0, 1.0, 1.0, 0.0, 0.0, 0.0)  # wind on spans 1-3 only


def _g(V: float) -> float:
    """Mean-wind load g_y = 1/2 rho C_d V^2 D [N/m] (paper Eq. 1); 22 N/m at 40 m/s."""
    return 0.5 * RHO * CD * V**2 * D


def _gy(system: LineSystem, per_span) -> np.ndarray:
    """Uniform load per span at linecheck's FE nodes, shape (n_spans, ne+1) [N/m]."""
    return np.repeat(np.asarray(per_span, dtype=float)[:, None], system.ne + 1, axis=1)


@cache
def _solved(L: float, V: float, spans: int):
    """(system, gy, linecheck state, FE reference) for the paper system; cached per module."""
    system = LineSystem(paper_line(L, spans=spans))
    pattern = (1.0,) if spans == 1 else LEFT_LOADED
    gy = _gy(system, _g(V) * np.array(pattern))
    return system, gy, solve_static(system, gy), solve_fe(system, gy)


def _table(lc, fe) -> str:
    """Per-tower comparison printed on failure."""
    rows = ["tower      Rx_lc      Rx_fe      Ry_lc      Ry_fe      Rz_lc      Rz_fe"]
    for j, (a, b) in enumerate(zip(lc.reactions, fe.reactions, strict=True), start=1):
        rows.append(f"{j:5d} " + " ".join(f"{x:10.2f} {y:10.2f}" for x, y in zip(a, b, strict=True)))
    rows.append("H_lc " + " ".join(f"{h:.2f}" for h in lc.tension))
    rows.append("H_fe " + " ".join(f"{h:.2f}" for h in fe.tension))
    return "\n".join(rows)


def _assert_matches(lc, fe) -> None:
    """linecheck within 1 % of the FE: R_x relative to the largest |R_x| (interior R_x are
    small differences of span tensions), R_y, R_z and H relative to each value."""
    Rl, Rf = lc.reactions, fe.reactions
    msg = _table(lc, fe)
    err_x = np.abs(Rl[:, 0] - Rf[:, 0]) / np.max(np.abs(Rf[:, 0]))
    assert np.all(err_x <= TOL), f"R_x off by {err_x.max():.3%} of max|R_x|\n{msg}"
    for c, name in ((1, "R_y"), (2, "R_z")):
        err = np.abs(Rl[:, c] - Rf[:, c]) / np.abs(Rf[:, c])
        assert np.all(err <= TOL), f"{name} off by {err.max():.3%} at tower {err.argmax() + 1}\n{msg}"
    err_h = np.abs(lc.tension - fe.tension) / fe.tension
    assert np.all(err_h <= TOL), f"span tension off by {err_h.max():.3%} in span {err_h.argmax() + 1}\n{msg}"
    # attachment-point displacements (insulator swing): within 1 % of the largest one
    dd = np.abs(lc.displacement - fe.displacement)
    scale = np.max(np.abs(fe.displacement))
    if scale > 0:
        assert np.all(dd <= TOL * scale), f"displacements differ by up to {dd.max():.3g} m\n{fe.displacement}\n{lc.displacement}"


# ------------------------------------------------------------------ the reference itself
@pytest.mark.parametrize("L", [300.0, 500.0])
@pytest.mark.parametrize("V", [0.0, 20.0, 40.0])
def test_fe_reference_matches_elastic_catenary(L, V):
    """The FE reference reproduces Irvine's exact elastic catenary (validates the reference)."""
    system = LineSystem(paper_line(L))
    g = _g(V)
    fe = solve_fe(system, _gy(system, [g]))
    Lu, EA = system.unstretched_length, system.line.ea
    Rx, Ry, Rz = irvine.reactions(L, Lu, W, g, EA)
    assert fe.residual <= 1e-6
    assert fe.tension[0] == pytest.approx(Rx, rel=1e-3)
    assert fe.reactions[0, 0] == pytest.approx(Rx, rel=1e-3)
    assert fe.reactions[0, 1] == pytest.approx(Ry, rel=1e-9, abs=1e-6)
    assert fe.reactions[0, 2] == pytest.approx(Rz, rel=1e-9)
    np.testing.assert_allclose(fe.reactions[1], fe.reactions[0] * [-1, 1, 1], rtol=1e-9, atol=1e-6)
    # the chord-plane mid-span sag (mid-span node = half the unstretched length, Irvine Eq. 2.6)
    n = fe.nodes.shape[0] - 1
    mid = fe.nodes[n // 2]
    assert np.hypot(mid[1], mid[2]) == pytest.approx(irvine.midspan_sag(L, Lu, np.hypot(W, g), EA), rel=1e-3)


@pytest.mark.parametrize(("L", "V"), [(300.0, 40.0), (500.0, 20.0)])
def test_fe_reference_six_spans_is_consistent(L, V):
    """Global equilibrium, constant horizontal force per span, rigid insulators, mesh convergence."""
    system, gy, _, fe = _solved(L, V, 6)
    Lu = system.unstretched_length
    R = fe.reactions
    assert fe.residual <= 1e-6
    assert R[:, 0].sum() == pytest.approx(0.0, abs=1e-5)
    assert R[:, 1].sum() == pytest.approx(3 * _g(V) * Lu, rel=1e-9)
    assert R[:, 2].sum() == pytest.approx(6 * W * Lu, rel=1e-9)
    assert fe.tension_spread < 1e-9  # no load along x: N e_x is constant along a span
    assert fe.insulator_length_error < 1e-4 * system.line.insulator_length  # penalty is rigid enough
    # suspension towers: the reaction lies along the insulator (it swings freely)
    sus = system.suspension
    d = fe.displacement[sus]
    axis = np.column_stack([d[:, 0], d[:, 1], system.line.insulator_length - d[:, 2]])
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    np.testing.assert_allclose(R[sus] / np.linalg.norm(R[sus], axis=1)[:, None], axis, atol=1e-8)
    # discretisation error of the reference is far below the 1 % tolerance
    coarse = solve_fe(system, gy, n_el=40)
    np.testing.assert_allclose(coarse.tension, fe.tension, rtol=5e-4)
    np.testing.assert_allclose(coarse.reactions, fe.reactions, rtol=5e-4, atol=5e-4 * np.abs(R).max())


# ------------------------------------------------------------------ linecheck against the reference
def test_single_span_40ms_matches_fe_and_catenary():
    system, _, lc, fe = _solved(300.0, 40.0, 1)
    _assert_matches(lc, fe)
    Rx, Ry, Rz = irvine.reactions(300.0, system.unstretched_length, W, _g(40.0), system.line.ea)
    assert fe.tension[0] == pytest.approx(Rx, rel=1e-3)
    assert lc.tension[0] == pytest.approx(Rx, rel=5e-3)
    np.testing.assert_allclose(lc.reactions[0], [Rx, Ry, Rz], rtol=5e-3)


@pytest.mark.parametrize(("L", "V"), [(300.0, 40.0), (500.0, 20.0)])
def test_six_spans_left_half_loaded_matches_fe(L, V):
    """Paper six-span system (strain ends, five 4 m suspension insulators), wind on spans 1-3."""
    _, _, lc, fe = _solved(L, V, 6)
    _assert_matches(lc, fe)
