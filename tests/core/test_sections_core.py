"""Line sections: geometry, clipping-in, the exact-span step 1 and tower frames.

References: Irvine (1981) elastic catenary in closed form (linecheck.reference for the level
span; the inclined form re-derived here from the parametric solution x(s), z(s)), statics
identities (a straight section does not move in still air; an angle tower's resultant is
2 H sin(alpha/2)), mirror symmetry, and the paper's equal-span form (Appendix A solver).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from linecheck.core.case import case_from_dict
from linecheck.core.catenary import clip_in, solve_spans
from linecheck.core.static import drag_intensity, solve_static, span_loads_uniform, still_air_state
from linecheck.core.system import LineSystem
from linecheck.reference import catenary_tension

W, EA, H0 = 17.92, 5.2e10 * 0.7e-4, 20000.0  # paper Table 1 conductor [N/m], [N]; H0 [N]


def _case(towers, *, tension=H0, wind=None, **line):
    data = {
        "line": {"weight": W, "diameter": 0.022, "area": 0.7e-4, "elastic_modulus": 5.2e10, "tension": tension,
                 "insulator_length": 4.0, "towers": towers, **line},
        "wind": {"type": "synoptic", "v_ref": 30.0, **(wind or {})},
        "analysis": {"realizations": 2, "duration": 60.0},
    }
    return case_from_dict(data, default_name="section")


def _tower(station, *, ground=0.0, height=40.0, support="suspension", angle=0.0, **kw):
    return {"station": station, "ground": ground, "height": height, "support": support, "angle": angle, **kw}


def _irvine_inclined(H, V0, Lu, s):
    """Irvine (1981) Eqs 2.20-2.21: the elastic catenary's parametric shape x(s), z(s) from the
    first support, tension H horizontally and V0 vertically (along the cable) there."""
    x = H * s / EA + (H / W) * (np.arcsinh((V0 + W * s) / H) - np.arcsinh(V0 / H))
    z = V0 * s / EA + W * s**2 / (2 * EA) + (np.hypot(H, V0 + W * s) - np.hypot(H, V0)) / W
    return x, z


def test_clip_in_level_span_matches_the_level_catenary():
    """h = 0: the unstretched length that gives H0 reproduces H0 through the level closed form."""
    L = np.array([250.0, 400.0])
    Lu, V0 = clip_in(np.full(2, H0), L, np.zeros(2), W, EA)
    for k in range(2):
        assert catenary_tension(L[k], Lu[k], W, EA) == pytest.approx(H0, rel=1e-10)
        assert V0[k] == pytest.approx(-0.5 * W * Lu[k], rel=1e-12)  # symmetric: half the weight each end


@pytest.mark.parametrize("rise", [-60.0, 25.0, 80.0])
def test_clip_in_inclined_span_satisfies_irvine(rise):
    """The clipped-in span ends exactly at the second clamp (Irvine's x(L_u) = L, z(L_u) = h)."""
    L = 380.0
    Lu, V0 = clip_in(np.array([H0]), np.array([L]), np.array([rise]), W, EA)
    x, z = _irvine_inclined(H0, V0[0], Lu[0], Lu[0])
    assert x == pytest.approx(L, abs=1e-9)
    assert z == pytest.approx(rise, abs=1e-9)


def test_span_element_reproduces_the_inclined_catenary_shape_and_forces():
    """The quadrature span element (4-point Gauss per element) against the closed form: end
    forces to 1e-9 relative and node positions to 1 micrometre (ne = 10)."""
    L, rise, ne = 420.0, 55.0, 10
    Lu, V0 = clip_in(np.array([H0]), np.array([L]), np.array([rise]), W, EA)
    p = np.zeros((1, ne + 1, 3))
    p[..., 2] = -W
    start = np.array([[0.9 * H0, 0.0, 0.5 * V0[0]]])  # deliberately off
    sol = solve_spans(np.array([[L, 0.0, rise]]), p, Lu, EA, start)
    assert sol.N0[0, 0] == pytest.approx(H0, rel=1e-9)
    assert sol.N0[0, 2] == pytest.approx(V0[0], rel=1e-9)
    assert sol.N_end[0, 2] == pytest.approx(V0[0] + W * Lu[0], rel=1e-9)
    s = np.linspace(0.0, Lu[0], ne + 1)
    x, z = _irvine_inclined(H0, V0[0], Lu[0], s)
    assert np.abs(sol.r[0, :, 0] - x).max() < 1e-6
    assert np.abs(sol.r[0, :, 2] - z).max() < 1e-6


def test_inclined_single_span_still_air_reactions_are_irvines():
    """Step 1 of an inclined single span (strain-strain) in still air: R_x = H0 at both ends,
    R_z = -V_0 and V_0 + W L_u (Irvine), to 1e-8 relative."""
    case = _case([_tower(0.0, support="strain"), _tower(350.0, ground=30.0, height=45.0, support="strain")])
    system = LineSystem(case.line)
    st = still_air_state(system)
    Lu, V0 = clip_in(np.array([H0]), np.array([350.0]), np.array([35.0]), W, EA)
    R = st.reactions
    assert R[0, 0] == pytest.approx(H0, rel=1e-8) and R[1, 0] == pytest.approx(-H0, rel=1e-8)
    assert R[0, 2] == pytest.approx(-V0[0], rel=1e-8)
    assert R[1, 2] == pytest.approx(V0[0] + W * Lu[0], rel=1e-8)
    assert abs(R[0, 1]) < 1e-9 and abs(R[1, 1]) < 1e-9


def test_straight_section_does_not_move_in_still_air():
    """Unequal, inclined but straight: clipping-in balances H0 at every suspension clamp, so the
    still-air equilibrium is the clipping-in state (linecheck's definition)."""
    towers = [_tower(0.0, support="strain"), _tower(260.0, ground=12.0), _tower(700.0, ground=-20.0, height=50.0),
              _tower(990.0, ground=5.0, height=35.0), _tower(1300.0, ground=40.0, support="strain")]
    system = LineSystem(_case(towers).line)
    st = still_air_state(system)
    assert np.abs(st.displacement).max() < 1e-8
    assert np.abs(st.reactions[:, 1]).max() < 1e-8
    # ... and the whole conductor stays on the clipped-in catenaries (node by node)
    assert np.abs(st.nodes - system.clip_in_nodes).max() < 1e-7
    # each suspension tower carries the weight of the conductor between the low points around it
    assert np.all(st.reactions[1:-1, 2] > 0)
    assert st.reactions[:, 2].sum() == pytest.approx(W * system.unstretched_lengths.sum(), rel=1e-10)


def test_angle_tower_swings_inside_and_carries_the_tension_resultant():
    """A 20 deg left turn at a suspension tower: its insulator swings toward the inside of the
    angle (+y of its frame) and the tower's transverse reaction is the resultant of the two
    span tensions, H_1 sin(a/2) + H_2 sin(a/2) with the chord directions of the equilibrium."""
    towers = [_tower(0.0, support="strain"), _tower(300.0, angle=20.0), _tower(620.0, support="strain")]
    case = _case(towers)
    system = LineSystem(case.line)
    st = still_air_state(system)
    d_local = system.to_tower_frames(st.displacement[None])[0]  # rotation applies to any vector
    assert d_local[1, 1] > 0.05  # swung inside (left) by several centimetres
    assert abs(d_local[1, 0]) < 0.5 * d_local[1, 1]
    R = system.to_tower_frames(st.reactions)
    # the insulator hangs along the force it carries: R_y'/R_z = d_y'/(v - d_z) (rigid link, Eq. 4)
    v = 4.0
    assert R[1, 1] / R[1, 2] == pytest.approx(d_local[1, 1] / (v - d_local[1, 2]), rel=1e-8)
    # a span under vertical loads only keeps its horizontal tension along its plan chord, so the
    # tower's transverse reaction is sum_i H_i sin(chord_i - psi), psi its frame's heading, and
    # both span tensions relax below H0 as the clamp swings inside (the section shortens)
    p = system.clamp_points + st.displacement
    c = np.diff(p, axis=0)
    chord = np.arctan2(c[:, 1], c[:, 0])
    H = st.tension / np.cos(chord - system.span_headings)  # st.tension: component along the heading
    psi = system.tower_headings[1]
    assert R[1, 1] == pytest.approx(H[1] * math.sin(chord[1] - psi) - H[0] * math.sin(chord[0] - psi), rel=1e-9)
    assert R[1, 1] < 2 * H0 * math.sin(math.radians(10.0))
    assert np.all(H < H0)
    # equilibrium of the whole section: the global reactions plus the weight sum to zero
    total = st.reactions.sum(axis=0)
    assert np.abs(total[:2]).max() < 1e-6 * H0
    assert total[2] == pytest.approx(W * system.unstretched_lengths.sum(), rel=1e-10)


def test_section_form_agrees_with_the_paper_form_on_the_paper_geometry():
    """The paper's six 300 m level spans written as towers, with H0 = the equal-span form's
    still-air tension: still-air and 40 m/s reactions agree with the Appendix-A solver within
    0.5 % of the largest component at every tower (parabolic vs exact span; the paper's
    geometry must be a special case of a section)."""
    from linecheck.validation import paper_line

    paper = LineSystem(paper_line(300.0, 6))
    st_p = still_air_state(paper)
    sup = paper.line.supports
    towers = [_tower(300.0 * j, height=43.0, support=sup[j]) for j in range(7)]
    sec = LineSystem(_case(towers, tension=float(st_p.tension.mean())).line)
    st_s = still_air_state(sec)
    g = span_loads_uniform(paper, drag_intensity(40.0, 1.25, 1.0, 0.022))
    w_p, w_s = solve_static(paper, g), solve_static(sec, g)
    for a, b in ((st_p.reactions, st_s.reactions), (w_p.reactions, w_s.reactions)):
        scale = np.abs(a).max(axis=1)
        assert np.all(np.abs(a - b).max(axis=1) <= 0.005 * scale)


def test_tower_frames_round_trip_and_mirror_symmetry():
    """Mirror the plan (angles negated): tower-frame R_x, R_z unchanged and R_y negated, still air."""
    left = [_tower(0.0, support="strain"), _tower(320.0, angle=15.0), _tower(600.0, angle=-25.0, insulator_length=5.0),
            _tower(930.0, support="strain")]
    right = [dict(t, angle=-t["angle"]) for t in left]
    sl, sr = LineSystem(_case(left).line), LineSystem(_case(right).line)
    Rl = sl.to_tower_frames(still_air_state(sl).reactions)
    Rr = sr.to_tower_frames(still_air_state(sr).reactions)
    assert np.allclose(Rl[:, [0, 2]], Rr[:, [0, 2]], rtol=0, atol=1e-6)
    assert np.allclose(Rl[:, 1], -Rr[:, 1], rtol=0, atol=1e-6)
    x = np.random.default_rng(1).normal(size=(5, sl.n_towers, 3))
    assert np.allclose(sl.from_tower_frames(sl.to_tower_frames(x)), x, rtol=0, atol=1e-12)


def test_section_dynamics_run_on_the_example(cases_dir):
    """The shipped 12-span example runs steps 1-3 with finite statistics in the tower frames."""
    from linecheck.core.case import load_case, with_values
    from linecheck.service import run_case

    case = with_values(load_case(cases_dir / "examples" / "section-12span.toml"),
                       {"analysis.realizations": 1, "analysis.duration": 60.0})
    res = run_case(case, spectral_check=False)
    pk = res.stats.peak_dynamic[0]
    assert np.all(np.isfinite(pk))
    # the angle-strain tower T5 (18 deg) carries the tension resultant in its frame's y
    assert pk[4, 1] > 2 * 22000.0 * math.sin(math.radians(9.0))


def test_frequency_domain_load_is_the_time_domain_load_on_an_oblique_section():
    """With an oblique wind both domains load node i with rho C_d D L_i V_n v cos(phi)
    (the normal part of the along-wind fluctuation), cos(phi) = |V_n|/|V| = |cos(d + h_i)| on a
    span of heading h_i; the spectral check's load per unit v equals the time domain's."""
    from linecheck import service

    towers = [_tower(0.0, support="strain"), _tower(300.0, angle=12.0), _tower(640.0, support="strain")]
    case = _case(towers, wind={"direction": 25.0})
    case = case.__class__(**{**case.__dict__, "analysis": case.analysis.__class__(  # the cross-flow form:
        **{**case.analysis.__dict__, "drag": "linear", "duration": 20.0,  # tests/core/test_crossflow.py
           "drag_direction": "horizontal-normal"})})
    st = service.static_analysis(case)
    sm = service.synoptic_model(case, st, vectors=False)
    t = service.record_time(case)[:8]
    vn, vl = service.record_mean_wind(case, st, t)
    ones = np.ones((1, t.size, st.system.n_nodes))
    loads, _ = service.fluctuating_loads(case, st.system, sm.model, t, ones, vn, vl)
    free = sm.model.dofs.free_nodes
    np.testing.assert_allclose(loads[0, 0], sm.load_per_v[free], rtol=1e-12)
    # an interior node of span 2 (heading 12 deg): V_n = 30 cos(37 deg), cos(phi) = cos(37 deg)
    node = st.system.ne + 3
    k = int(np.flatnonzero(free == node)[0])
    L = sm.model.tributary[node]
    expect = 1.25 * 1.0 * 0.022 * L * 30.0 * math.cos(math.radians(37.0)) ** 2
    assert loads[0, 0, k] == pytest.approx(expect, rel=1e-12)


def test_downburst_on_the_example_section_runs_in_tower_frames(cases_dir):
    """Steps 1-3 of a downburst on the 12-span example (centre placed from the tower of interest's
    frame): finite statistics, the mean-state reactions equal step 1's rotated into the tower
    frames, and the wind-induced mean at the tower of interest is largest in its frame's y."""
    from linecheck.core.case import load_case, with_values
    from linecheck.service import run_case

    case = with_values(load_case(cases_dir / "examples" / "section-12span.toml"), {
        "wind.type": "downburst", "wind.turbulence_intensity": 0.11,
        "wind.downburst": {"jet_diameter": 640.0, "distance": 770.0, "angle": 0.0},
        "analysis.realizations": 1, "analysis.mean_states": 40, "analysis.duration": None})
    res = run_case(case)
    j = case.line.tower_of_interest - 1
    assert np.all(np.isfinite(res.stats.peak_dynamic))
    rw = res.system.to_tower_frames(res.static.mean.reactions_wind)
    assert np.abs(res.mean[:, j, :]).max(axis=0) == pytest.approx(np.abs(rw[:, j, :]).max(axis=0), rel=1e-3)
    big = np.abs(rw[:, j, :]).max(axis=0)
    assert big[1] > 5 * big[0]  # the storm faces the tower (Theta = 0): transverse load dominates


def test_sparse_condensation_equals_the_dense_one(cases_dir, monkeypatch):
    """Above SPARSE_CONDENSATION_DOF the condensation of the insulator-axial DOFs is
    sparse; on the 12-span section (both paths forced) S, K*, M*, C* agree with the dense
    algebra to 1e-12 of their largest entry (the axial penalty, 1e3 EA/L_e, makes K* lose
    about 1e-14 to rounding in either path; measured 3e-14)."""
    import linecheck.core.model as mm
    from linecheck import service
    from linecheck.core.case import load_case

    case = load_case(cases_dir / "examples" / "section-12span.toml")
    st = service.static_analysis(case)
    model = mm.build_model(st.system, st.mean.state(0))
    C = service.damping_matrices(case, st, [model])[0]
    monkeypatch.setattr(mm, "SPARSE_CONDENSATION_DOF", 10**9)
    dense = mm.condensed(model, C)
    monkeypatch.setattr(mm, "SPARSE_CONDENSATION_DOF", 0)
    sparse = mm.condensed(model, C)
    for name in ("S", "K", "M", "C"):
        a, b = getattr(dense, name), getattr(sparse, name)
        assert a.shape == b.shape
        assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max(), name
