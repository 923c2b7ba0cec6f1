"""Uplift at suspension towers: the held clamp of the section solver and the margin it reports.

Reference (independent of linecheck's clipping-in and span element): the elastic catenary of
Irvine (1981) ch. 2, Eqs 2.20-2.21, solved here for (V_0, L_u) by scipy's fsolve for a span of
horizontal tension H0 between two clamps h apart.  V_0 is the vertical component of the tension
at the lower clamp along the cable: the wire pulls that clamp up by V_0 (down when negative), and
at the higher clamp down by V_0 + W L_u.

Hand calculation (shallow cable, load W per horizontal metre): between a low clamp at x = 0 and a
clamp h higher at x = L, z(x) = h x / L - W x (L - x) / (2 H); the tension at the low clamp is
H (1, z'(0)) with z'(0) = h / L - W L / (2 H), so the wire pulls that clamp down by
-H z'(0) = W L / 2 - H h / L (the vertical force at a clamp is H tan(slope) of each adjacent
span).  A valley tower between two such spans carries R_z = W L - 2 H h / L; its weight span
R_z / W = L - 2 H h / (W L) is the distance between the low points of its two spans.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import fsolve

from linecheck.core import catenary
from linecheck.core.case import case_from_dict, load_case
from linecheck.core.errors import ConvergenceError
from linecheck.core.system import LineSystem
from linecheck.core.uplift import uplift

from ..conftest import CASES

W, EA, H0 = 17.92, 5.2e10 * 0.7e-4, 22000.0  # paper Table 1 conductor [N/m], [N]; H0 [N]
L, DROP = 300.0, 40.0  # span [m]; the valley tower's clamp lies DROP [m] below its neighbours'


def valley_case(drop: float = DROP, *, tension: float = H0, v_ref: float = 30.0):
    """Five 300 m spans, strain ends, every clamp 30 m above ground; tower 3 (T3) stands ``drop``
    lower than the others (a valley tower)."""
    towers = [{"name": f"T{k + 1}", "station": k * L, "ground": 100.0 - (drop if k == 2 else 0.0), "height": 30.0,
               "support": "strain" if k in (0, 5) else "suspension", "angle": 0.0} for k in range(6)]
    data = {
        "line": {"weight": W, "diameter": 0.022, "area": 0.7e-4, "elastic_modulus": 5.2e10, "tension": tension,
                 "insulator_length": 4.0, "towers": towers, "tower_of_interest": 3},
        "wind": {"type": "synoptic", "v_ref": v_ref},
        "analysis": {"realizations": 1, "duration": 60.0},
    }
    return case_from_dict(data, default_name="valley")


def irvine_span(H: float, L_: float, h: float) -> tuple[float, float]:
    """(V_0, L_u) of Irvine's elastic catenary from its closed form by fsolve (module docstring)."""
    def equations(q):
        V0, Lu = q
        x = H * Lu / EA + (H / W) * (np.arcsinh((V0 + W * Lu) / H) - np.arcsinh(V0 / H))
        z = V0 * Lu / EA + W * Lu**2 / (2 * EA) + (np.hypot(H, V0 + W * Lu) - np.hypot(H, V0)) / W
        return [x - L_, z - h]

    V0, Lu = fsolve(equations, [H * h / L_ - 0.5 * W * L_, np.hypot(L_, h)], xtol=1e-13)
    return float(V0), float(Lu)


def test_valley_tower_is_held_in_still_air_with_irvines_margin():
    """T3, 40 m below its neighbours with H0 = 22 kN, would lift its insulator: the still-air state
    holds its clamp at the clipping-in point (no motion anywhere, a straight section), and its
    margin is -2 V_0 of Irvine's span (-491.65 N) to 1e-6 of W L; the shallow-cable hand
    calculation W L - 2 H0 h / L = -490.67 N agrees within 0.1 % of W L (5.4 N: the parabola spreads
    the weight along the chord, the wire carries it along its arc); the neighbour T2 carries half
    the level span's weight plus V_0 + W L_u of the inclined one."""
    system = LineSystem(valley_case().line)
    st = system.still_air
    assert st.held is not None and st.held.tolist() == [False, False, True, False, False, False]
    assert np.abs(st.displacement).max() < 1e-8  # nothing moves: H0 balances at every clamp
    V0, Lu = irvine_span(H0, L, DROP)  # from the valley clamp up to T2 / T4
    _V0_level, Lu_level = irvine_span(H0, L, 0.0)
    R = st.reactions
    assert R[2, 2] == pytest.approx(-2.0 * V0, abs=1e-6 * W * L)
    assert -2.0 * V0 == pytest.approx(-491.649, abs=1e-3)
    assert R[2, 2] == pytest.approx(W * L - 2.0 * H0 * DROP / L, abs=1e-3 * W * L)  # hand calculation
    assert R[1, 2] == pytest.approx(0.5 * W * Lu_level + V0 + W * Lu, abs=1e-6 * W * L)
    u = uplift(system, _still_air_only(system))
    assert u.margin_still_air[2] == R[2, 2] and u.weight_span_still_air[2] == pytest.approx(R[2, 2] / W, rel=1e-15)
    assert u.weight_span_still_air[2] == pytest.approx(-27.436, abs=1e-3)
    assert np.isnan(u.margin_still_air[[0, 5]]).all()  # strain towers: no insulator to lift
    assert u.first_uplift() == (2, None, pytest.approx(R[2, 2]))


def test_a_shallower_valley_hangs_with_the_closed_form_margin():
    """20 m below its neighbours T3 hangs (nothing held); margin -2 V_0 = 2420.88 N (Irvine), the
    shallow-cable W L - 2 H0 h / L = 2442.67 N within 0.5 % of W L."""
    system = LineSystem(valley_case(20.0).line)
    st = system.still_air
    assert st.held is None
    V0, _Lu = irvine_span(H0, L, 20.0)
    assert st.reactions[2, 2] == pytest.approx(-2.0 * V0, abs=1e-6 * W * L)
    assert st.reactions[2, 2] == pytest.approx(2420.877, abs=1e-3)
    assert st.reactions[2, 2] == pytest.approx(W * L - 2.0 * H0 * 20.0 / L, abs=5e-3 * W * L)
    assert uplift(system, _still_air_only(system)).first_uplift() is None


def test_paper_form_weight_span_is_the_span():
    """The paper's six equal level spans: every interior tower carries one span of wire, R_z = W L_u,
    so its weight span is L_u (to 1e-9) and nothing is held."""
    system = LineSystem(load_case(CASES / "paper" / "case01-six.toml").line)
    u = uplift(system, _still_air_only(system))
    assert not u.any_held
    np.testing.assert_allclose(u.weight_span_still_air[1:-1], system.unstretched_length, rtol=1e-9)
    assert np.isnan(u.weight_span_still_air[[0, -1]]).all()


def _still_air_only(system: LineSystem):
    """Step-1 results with one windless mean state (for :func:`uplift`)."""
    from linecheck.core.static import solve_mean_states

    return solve_mean_states(system, np.zeros(1), np.zeros((1, system.n_spans, system.ne + 1)))


def _weight_only(system: LineSystem, start_swing: float):
    """:func:`catenary.equilibrium` of a section under its weight, T2's clamp starting swung
    ``start_swing`` [m] sideways (+y) on its insulator sphere (the other clamps at their points)."""
    Lu = system.unstretched_lengths
    p = np.zeros((1, system.n_spans, system.ne + 1, 3))
    p[..., 2] = -W
    clamps, tops, v = system.clamp_points, system.insulator_tops, system.insulator_lengths
    pos = clamps[None].copy()
    s = start_swing
    pos[0, 1] = tops[1] + np.array([0.0, s, -np.sqrt(v[1] ** 2 - s**2)])
    N0 = catenary.start_tension(np.diff(pos, axis=1), p, Lu, np.full((1, system.n_spans), H0))
    return catenary.equilibrium(clamps, tops, v, system.suspension, system.tower_along, p, Lu, system.line.ea, pos,
                                N0, labels=["weight"], tol=1e-10, max_iter=200)


def test_a_transient_compression_is_released():
    """T2 starting swung horizontally (3.999 m on its 4 m insulator, toward +y): the spans pull its
    clamp back, its insulator is in compression at the start and the clamp is held; at convergence
    the wire pulls it down, so it is released and the iteration ends at the equilibrium of the
    ordinary start (positions to 1e-9 m, nothing held)."""
    system = LineSystem(valley_case(20.0).line)
    ref = _weight_only(system, 0.0)
    swung = _weight_only(system, 3.999)
    assert not swung.held.any() and not ref.held.any()
    np.testing.assert_allclose(swung.p, ref.p, atol=1e-9)
    np.testing.assert_allclose(swung.force, ref.force, atol=1e-6 * W * L)


def test_an_undecided_uplift_is_refused(monkeypatch):
    """A load case that would need more releases than allowed (here: none allowed) is refused with
    one message naming the state and the tower: its uplift is undecided."""
    monkeypatch.setattr(catenary, "MAX_RELEASES", 0)
    system = LineSystem(valley_case(20.0).line)
    with pytest.raises(ConvergenceError, match=r"weight: the suspension insulator at tower 2 alternates"):
        _weight_only(system, 3.999)
