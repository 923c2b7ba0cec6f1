"""The cross-flow drag on inclined spans (docs/method.md "Loads"; linecheck/core/crossflow.py).

Independent checks: the issue's closed form of the normal wind on an inclined chord, the global
equilibrium of the step-1 section (the towers carry exactly the applied drag), finite differences
of the exact drag 1/2 rho C_d D |W_perp| W_perp for the fluctuating loads, and the level-span
limit (bit-identical to the horizontal-normal form).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from linecheck import service
from linecheck.analysis.record import record_cross_wind
from linecheck.core.case import case_from_dict
from linecheck.core.crossflow import applies, normal_part, span_wind_vectors
from linecheck.core.damping import node_tangents
from linecheck.core.loads import fluctuating_loads

W = 15.97  # [N/m]
RHO, CD, D = 1.25, 1.0, 0.022


def _case(grounds, *, direction=30.0, drag="linear", drag_direction="cross-flow", profile=0.0, angle=0.0,
          v_ref=30.0):
    """A 3-span straight section over ``grounds`` [m] (4 towers, strain ends), synoptic wind."""
    stations = [0.0, 300.0, 650.0, 980.0]
    towers = [{"station": s, "ground": g, "height": 40.0, "support": "strain" if k in (0, 3) else "suspension",
               "angle": angle if k == 1 else 0.0} for k, (s, g) in enumerate(zip(stations, grounds))]
    data = {
        "line": {"weight": W, "diameter": D, "area": 0.7e-4, "elastic_modulus": 5.2e10, "tension": 25000.0,
                 "insulator_length": 3.0, "towers": towers, "drag_coefficient": CD},
        "wind": {"type": "synoptic", "v_ref": v_ref, "direction": direction, "profile_exponent": profile,
                 "air_density": RHO, "turbulence_intensity": 0.15},
        "analysis": {"realizations": 2, "duration": 20.0, "drag": drag, "drag_direction": drag_direction},
    }
    return case_from_dict(data, default_name="inclined")


HILLY = [0.0, 45.0, 80.0, 130.0]  # spans sloping +15 %, +10 %, +15 % (every insulator in tension)


def test_normal_wind_on_an_inclined_chord_has_the_closed_form_vertical_part():
    """V_perp = V - (V.c)c on a chord of slope theta: horizontal normal part V_n, in-plane part of
    size V_x sin(theta), i.e. a vertical component -V_x sin(theta) cos(theta) and |V_perp|^2 =
    V_n^2 + V_x^2 sin^2(theta) (the issue's decomposition, derived by hand)."""
    case = _case(HILLY, direction=30.0)
    st = service.static_analysis(case)
    system = st.system
    # V_perp on every span's still-air chord (step 1's first pass)
    u = normal_part(span_wind_vectors(system, st.wind.normal, st.wind.longitudinal),
                    system.span_directions[:, None, :])[0]  # (n_spans, ne+1, 3)
    v = 30.0
    vn, vx = v * math.cos(math.radians(30.0)), v * math.sin(math.radians(30.0))
    for i, (g0, g1, L) in enumerate(((0.0, 45.0, 300.0), (45.0, 80.0, 350.0), (80.0, 130.0, 330.0))):
        theta = math.atan2(g1 - g0, L)
        assert u[i, :, 2] == pytest.approx(-vx * math.sin(theta) * math.cos(theta), rel=1e-12)
        assert np.linalg.norm(u[i], axis=-1) == pytest.approx(math.sqrt(vn**2 + (vx * math.sin(theta)) ** 2), rel=1e-12)
        assert u[i, :, 1] == pytest.approx(vn, rel=1e-12)  # the horizontal normal part is V_n (first span along +x)


def test_step1_towers_carry_the_applied_drag():
    """Global equilibrium under uniform wind: horizontal-normal, the wind-induced reactions summed
    over the towers (global, R_z down) equal 1/2 rho C_d D |V_n| V_n n_i L_u summed over the spans
    (exact: no vertical drag); cross-flow, the summed vertical reaction is the vertical drag, whose
    chord estimate -1/2 rho C_d D |V_perp| V_x sin(theta) cos(theta) L_u it matches within 20 %
    (the sag and the blow-out turn the tangents away from the chord: the independent FE
    reference measures 13 % on its inclined section, tests/integration/test_inclined_crossflow.py)."""
    for dd in ("horizontal-normal", "cross-flow"):
        case = _case(HILLY, drag_direction=dd)
        st = service.static_analysis(case)
        system = st.system
        Lu = system.unstretched_lengths
        V = 30.0 * np.array([math.sin(math.radians(30.0)), math.cos(math.radians(30.0)), 0.0])
        total = np.zeros(3)
        for i in range(system.n_spans):
            c = system.span_chords[i] / np.linalg.norm(system.span_chords[i])
            up = V - (V @ c) * c if dd == "cross-flow" else (V @ system.span_normals[i]) * system.span_normals[i]
            total += 0.5 * RHO * CD * D * np.linalg.norm(up) * up * Lu[i]
        R = st.mean.reactions_wind[0].sum(axis=0) * np.array([1.0, 1.0, -1.0])  # z up, as the loads
        scale = np.abs(total).max()
        if dd == "horizontal-normal":
            np.testing.assert_allclose(R, total, atol=1e-6 * scale)
        else:
            assert total[2] < -0.03 * scale  # a real vertical drag (slopes 10-15 %, 30 deg wind), downward
            assert R[2] == pytest.approx(total[2], rel=0.2)


def _fluct(case, u_along: float):
    st = service.static_analysis(case)
    system = st.system
    sm = service.synoptic_model(case, st, vectors=False)
    t = service.record_time(case)[:3]
    nw = record_cross_wind(case, st, t, *service.record_mean_wind(case, st, t))
    v = np.full((1, t.size, system.n_nodes), u_along)
    loads, direct = fluctuating_loads(case, system, sm.model, t, v, None, None, nw)
    return st, sm, nw, loads, direct


@pytest.mark.parametrize("drag", ["linear", "quadratic"])
def test_fluctuating_loads_are_the_exact_cross_flow_drag_of_the_gust(drag):
    """A gust u along the mean wind: the node's load along d is (F(u) - F_mean) . d with
    F(u) = 1/2 rho C_d D L |W_perp| W_perp, W = V (1 + u/|V|) (exact drag of the total wind) and
    F_mean = F(0)(1 + sigma^2/|V|^2) (quadratic) or F(0); linear: its derivative at u = 0 (central
    difference, error O(h^2) ~ 1e-10 relative); the axis is the mean state's deformed tangent."""
    case = _case(HILLY, drag=drag)
    u = 4.0
    st, sm, nw, loads, _ = _fluct(case, u)
    system, model = st.system, sm.model
    free = model.dofs.free_nodes
    axes = node_tangents(st.mean.nodes[0])  # the mean state's deformed conductor axes
    V = 30.0 * np.array([math.sin(math.radians(30.0)), math.cos(math.radians(30.0)), 0.0])
    sig2 = (0.15 * 30.0) ** 2
    for node in (3, system.ne + 4, 2 * system.ne + 5):  # an interior node of every span
        c = axes[node]
        L = model.tributary[node]

        def F(w, c=c, L=L):
            wp = w - (w @ c) * c
            return 0.5 * RHO * CD * D * L * np.linalg.norm(wp) * wp

        d = nw.directions[node]
        k = int(np.flatnonzero(free == node)[0])
        if drag == "quadratic":
            expect = (F(V * (1 + u / 30.0)) - F(V) * (1 + sig2 / 900.0)) @ d
        else:
            h = 1e-3
            expect = u * ((F(V * (1 + h / 30.0)) - F(V * (1 - h / 30.0))) / (2 * h)) @ d
        assert loads[0, 0, k] == pytest.approx(expect, rel=1e-9)
        # the load acts along V_perp: d is its direction (synoptic: exact)
        wp = V - (V @ c) * c
        np.testing.assert_allclose(d, wp / np.linalg.norm(wp), atol=1e-12)


def test_frequency_domain_load_is_the_time_domain_load_in_cross_flow():
    """The spectral check loads the same nodes along the same directions as the time domain."""
    case = _case(HILLY, drag="linear")
    _st, sm, nw, loads, _ = _fluct(case, 1.0)
    free = sm.model.dofs.free_nodes
    np.testing.assert_allclose(loads[0, 0], sm.load_per_v[free], rtol=1e-12)
    np.testing.assert_array_equal(sm.model.load_directions, nw.directions)


def test_pinned_node_loads_go_to_the_strain_tower_along_d_with_z_down():
    """A strain tower's own node: its load f d goes straight into R (x, y, and z downward)."""
    case = _case(HILLY, drag="linear")
    st, _sm, nw, _loads, direct = _fluct(case, 1.0)
    system = st.system
    node = system.tower_nodes[0]
    d = nw.directions[node]
    r = direct[0, 0, 0:3]
    f = np.linalg.norm(r)
    assert f > 0
    np.testing.assert_allclose(r, f * np.array([d[0], d[1], -d[2]]) * np.sign(r @ np.array([d[0], d[1], -d[2]])),
                               rtol=1e-12, atol=1e-12 * f)


def test_the_equal_span_form_and_horizontal_normal_keep_the_paper_path_bit_for_bit(cases_dir):
    """The equal-span (paper) form never takes the cross-flow path (its default drag_direction
    changes nothing: the same bits), nor does a section with drag_direction = "horizontal-normal"."""
    from linecheck.core.case import load_case, with_values

    paper = with_values(load_case(cases_dir / "paper" / "case01-six.toml"),
                        {"analysis.realizations": 1, "analysis.duration": 60.0})
    cf = with_values(paper, {"analysis.drag_direction": "cross-flow"})
    assert not applies(cf, service.static_analysis(cf).system)
    a, b = service.run_case(paper, spectral_check=False), service.run_case(cf, spectral_check=False)
    np.testing.assert_array_equal(a.resonant, b.resonant)
    section = _case(HILLY)
    assert applies(section, service.static_analysis(section).system)
    assert not applies(_case(HILLY, drag_direction="horizontal-normal"), service.static_analysis(section).system)


def test_downburst_on_an_inclined_section_runs_with_frozen_directions():
    """A downburst: every node's load direction is V_perp's at its largest |V_perp| among the step-1
    states (checked against the mean wind of that state); the run completes, and the vertical
    wind-induced mean reaction differs from the horizontal-normal form's."""
    from linecheck.core.case import with_values

    case = with_values(_case(HILLY), {
        "wind.type": "downburst", "wind.v_ref": 40.0, "wind.turbulence_intensity": 0.11,
        "wind.downburst": {"jet_diameter": 640.0, "distance": 500.0, "angle": 30.0},
        "analysis.realizations": 1, "analysis.mean_states": 20, "analysis.duration": None})
    st = service.static_analysis(case)
    cross = st.cross_wind
    assert cross is not None
    size = np.linalg.norm(cross.perp_vectors, axis=-1)
    for node in (3, st.system.ne + 4):
        k = int(np.argmax(size[:, node]))
        np.testing.assert_allclose(cross.directions[node], cross.perp_vectors[k, node] / size[k, node], rtol=1e-12)
    hn = with_values(case, {"analysis.drag_direction": "horizontal-normal"})
    rz = st.mean.reactions_wind[..., 2]
    rz_hn = service.static_analysis(hn).mean.reactions_wind[..., 2]
    assert np.abs(rz - rz_hn).max() > 1e-3 * np.abs(st.mean.reactions_wind).max()
    r = service.run_case(case, spectral_check=False)
    assert np.all(np.isfinite(r.resonant)) and np.all(np.isfinite(r.stats.peak_dynamic))


@pytest.mark.parametrize("damping", ["paper", "quasi-steady"])
def test_aerodynamic_damping_follows_the_normal_wind(damping):
    """The damping block of a span node in the cross-flow form: "paper" (Eq. 13 along the load)
    c d d^T with c = rho C_d D L |V_perp|; quasi-steady: c along the relative wind w = P V_perp/|P V_perp|
    (P normal to the deformed axis e), c/2 across it in the normal plane, 0 along e."""
    from linecheck.analysis.linear import damping_matrices
    from linecheck.core.case import with_values
    from linecheck.core.model import band_to_dense, build_model

    case = with_values(_case(HILLY), {"analysis.damping": damping, "analysis.structural_damping": 0.0})
    st = service.static_analysis(case)
    model = build_model(st.system, st.mean.state(0))
    C = band_to_dense(damping_matrices(case, st, [model])[0])
    cross = st.cross_wind
    node = st.system.ne + 4
    i = model.dofs.node_dof[node]
    B = C[i:i + 3, i:i + 3]
    u = cross.perp_vectors[0, node]
    c = RHO * CD * D * model.tributary[node] * np.linalg.norm(u)
    if damping == "paper":
        d = cross.directions[node]
        np.testing.assert_allclose(B, c * np.outer(d, d), rtol=1e-12, atol=1e-12 * c)
        return
    e = node_tangents(st.mean.nodes[0])[node]
    w = u - (u @ e) * e
    w /= np.linalg.norm(w)
    np.testing.assert_allclose(B @ w, c * w, atol=1e-12 * c)
    np.testing.assert_allclose(B @ e, 0.0, atol=1e-12 * c)
    x = np.cross(e, w)
    np.testing.assert_allclose(B @ x, 0.5 * c * x, atol=1e-12 * c)
