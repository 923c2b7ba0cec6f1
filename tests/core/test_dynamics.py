"""Steps 2-3: Newmark against exact solutions, the linear model against step 1, modes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from linecheck.core.dynamics import integrate
from linecheck.core.model import LinearModel, build_model, dof_map, reaction_matrix_direct
from linecheck.core.modes import natural_modes
from linecheck.core.results import compute_statistics
from linecheck.core.static import drag_intensity, solve_static, span_loads_uniform, still_air_state
from linecheck.core.system import LineSystem

from ..conftest import paper_line


def sdof_model(k: float, m: float) -> LinearModel:
    """One free node with isotropic spring k and mass m: three uncoupled SDOFs."""
    system = LineSystem(paper_line(300.0, elements_per_span=2))
    dm = dof_map(system)  # one free node (the mid node), 3 DOFs
    assert dm.n_dof == 3
    ab = np.zeros((6, 3))
    ab[-1] = k
    G = np.zeros((6, 3))
    G[4, 1] = 1.0  # "reaction" row = displacement y (to read u back)
    return LinearModel(system, dm, ab, np.full(3, m), np.ones(system.n_nodes), G,
                       np.zeros((0, 3)), np.zeros(0, dtype=int), np.zeros_like(ab))


def test_newmark_sdof_harmonic_matches_exact_solution():
    """Damped SDOF, u(0)=0, u'(0)=0, F = F0 sin(W t): exact solution (Chopra 2012 Eq. 3.2.1-3.2.4)."""
    k, m, zeta = 400.0, 10.0, 0.05
    wn = np.sqrt(k / m)
    c = 2 * zeta * m * wn
    W, F0 = 0.8 * wn, 50.0
    dt, n = 0.0025, 8000  # w_n dt = 0.016: Newmark period error (w dt)^2/12 ~ 2e-5
    t = dt * np.arange(n)
    F = F0 * np.sin(W * t)
    model = sdof_model(k, m)
    damping = np.zeros((1, 6, 3))
    damping[0, -1, 1] = c  # diagonal band row: c on the y DOF
    resp = integrate([model], damping, np.zeros(n, dtype=int), F[:, None, None], dt)
    u = resp.fluctuating[0, :, 1, 1]
    # exact: steady state + transient (Chopra, "Dynamics of Structures", section 3.2)
    r = W / wn
    ust = F0 / k
    C = ust * (1 - r**2) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2)
    D = ust * (-2 * zeta * r) / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2)
    wd = wn * np.sqrt(1 - zeta**2)
    A = -D
    B = (-C * W + zeta * wn * A) / wd
    exact = np.exp(-zeta * wn * t) * (A * np.cos(wd * t) + B * np.sin(wd * t)) + C * np.sin(W * t) + D * np.cos(W * t)
    err = np.max(np.abs(u - exact)) / np.max(np.abs(exact))
    assert err < 1e-3
    # step 3 of the same system is the static response F/k
    np.testing.assert_allclose(resp.background[0, :, 1, 1], F / k, rtol=1e-12)


def test_newmark_mdof_matches_modal_superposition():
    """Transverse (y) vibration of the still-air span: y decouples from x, z, the paper's
    damping is mass-proportional on y (c_i/m_i = rho C_d D V g / W), so modal
    superposition with exact SDOF responses is an independent exact reference."""
    system = LineSystem(paper_line(300.0))
    model = build_model(system, still_air_state(system))
    V = 20.0
    alpha = 1.25 * 1.0 * 0.022 * V * 9.81 / 17.92  # c/m on every y DOF [1/s]
    damping = np.zeros((1, 6, model.dofs.n_dof))
    damping[0, -1, 1::3] = alpha * model.mass[1::3]
    y = np.arange(1, model.dofs.n_dof, 3)
    Kyy = model.K_dense[np.ix_(y, y)]
    assert np.allclose(model.K_dense[np.ix_(y, np.arange(0, model.dofs.n_dof, 3))], 0.0)
    m = model.mass[y]
    w2, psi = np.linalg.eigh(Kyy / np.sqrt(np.outer(m, m)))
    phi = psi / np.sqrt(m)[:, None]
    wn = np.sqrt(w2)
    dt, n = 0.01, 6000
    t = dt * np.arange(n)
    W = 0.9 * wn[0]
    p = np.linspace(1.0, 2.0, y.size) * 30.0  # load pattern [N]
    F = np.sin(W * t)[:, None] * p[None, :]
    resp = integrate([model], damping, np.zeros(n, dtype=int), F[:, None, :], dt)
    # modal: q_i'' + alpha q_i' + w_i^2 q_i = phi_i . p sin(W t), q(0) = q'(0) = 0
    exact_u = np.zeros((n, y.size))
    for i in range(y.size):
        zeta = alpha / (2 * wn[i])
        r = W / wn[i]
        ust = phi[:, i] @ p / wn[i] ** 2
        den = (1 - r**2) ** 2 + (2 * zeta * r) ** 2
        C, D = ust * (1 - r**2) / den, -ust * 2 * zeta * r / den
        wd = wn[i] * np.sqrt(1 - zeta**2)
        A = -D
        B = (-C * W + zeta * wn[i] * A) / wd
        q = np.exp(-zeta * wn[i] * t) * (A * np.cos(wd * t) + B * np.sin(wd * t)) + C * np.sin(W * t) + D * np.cos(W * t)
        exact_u += q[:, None] * phi[:, i][None, :]
    G = model.G
    Ry_exact = exact_u @ G[1, y]  # y reaction at tower 1
    Ry = resp.fluctuating[0, :, 0, 1]
    assert np.max(np.abs(Ry - Ry_exact)) / np.max(np.abs(Ry_exact)) < 1e-3


@pytest.mark.parametrize("spans", [1, 6])
@pytest.mark.parametrize("V", [20.0, 40.0])
def test_linear_model_is_the_tangent_of_step_1(spans, V):
    """Reactions of the linear model (Eq. 7) under a load increment equal the central
    difference of the non-linear step-1 solver (independent formulations) within 2 %."""
    system = LineSystem(paper_line(300.0, spans=spans))
    g = float(drag_intensity(V, 1.25, 1.0, 0.022))
    st = solve_static(system, span_loads_uniform(system, g))
    dg = 1e-3 * g
    up = solve_static(system, span_loads_uniform(system, g + dg), initial=st)
    dn = solve_static(system, span_loads_uniform(system, g - dg), initial=st)
    dR = (up.reactions - dn.reactions) / 2
    model = build_model(system, st)
    f = dg * model.tributary
    F = np.zeros(model.dofs.n_dof)
    F[1::3] = f[model.dofs.free_nodes]
    R = (model.G @ np.linalg.solve(model.K_dense, F) + reaction_matrix_direct(system) @ f).reshape(-1, 3)
    j = system.line.tower_of_interest - 1
    for c in range(2):
        if abs(dR[j, c]) > 1e-6 * abs(dR[j]).max():
            assert R[j, c] == pytest.approx(dR[j, c], rel=0.02)
    # global equilibrium of the linear model
    assert R[:, 1].sum() == pytest.approx(f.sum(), rel=1e-9)
    assert abs(R[:, 0].sum()) < 1e-9 * f.sum()


def test_modes_single_span_closed_form():
    """Out-of-plane modes are exactly the discrete (lumped) string, T_e/L_e = H/dx;
    the first symmetric in-plane mode follows Irvine's (1981, Eq. 3.54) equation
    tan(w/2) = w/2 - 4/lambda^2 (w/2)^3."""
    ne = 50
    system = LineSystem(paper_line(300.0, elements_per_span=ne))
    st = still_air_state(system)
    modes = natural_modes(build_model(system, st), 6)
    H, L = st.tension[0], 300.0
    m_node = 17.92 * system.unstretched_length / ne / 9.81
    k = H * ne / L
    string = [2 * np.sqrt(k / m_node) * np.sin(n * np.pi / (2 * ne)) / (2 * np.pi) for n in (1, 2, 3)]
    out_of_plane = modes.frequencies_hz[modes.dominant_direction() == 1][:3]
    np.testing.assert_allclose(out_of_plane, string, rtol=1e-9)
    # Irvine: lambda^2 = (m g L / H)^2 L / (H L_e / EA), L_e = L (1 + 8 (d/L)^2)
    mu = 17.92 / 9.81
    d = 17.92 * L**2 / (8 * H)
    Le = L * (1 + 8 * (d / L) ** 2)
    lam2 = (17.92 * L / H) ** 2 * L / (H * Le / system.line.ea)
    x = brentq(lambda x: np.tan(x) - x + 4 / lam2 * x**3, np.pi / 2 + 1e-6, 3 * np.pi / 2 - 1e-6)
    f_sym = 2 * x * np.sqrt(H / mu) / L / (2 * np.pi)
    in_plane = modes.frequencies_hz[modes.dominant_direction() == 2]
    assert in_plane[0] == pytest.approx(f_sym, rel=0.01)


def test_statistics_definitions():
    """Eqs 15-16 on hand-made histories."""
    n = 1000
    t = np.linspace(0, 1, n)
    M = np.zeros((n, 1, 3))
    M[:, 0, 0] = 100.0  # mean R_x 100 N; R_y mean zero by symmetry
    B = np.zeros((1, n, 1, 3))
    B[0, :, 0, 0] = 20 * np.sin(2 * np.pi * 5 * t)
    B[0, :, 0, 1] = 30 * np.sin(2 * np.pi * 5 * t)
    R = np.zeros_like(B)
    R[0, :, 0, 0] = 10 * np.sin(2 * np.pi * 5 * t)
    st = compute_statistics(M, B, R, np.array([[1000.0, 0.0, 50.0]]), g_yp_L=200.0)
    pk = np.abs(100 + 30 * np.sin(2 * np.pi * 5 * t)).max()
    assert st.mean_max[0, 0, 0] == 100.0
    assert st.peak_dynamic[0, 0, 0] == pytest.approx(pk)
    assert st.GF_Dy[0, 0, 0] == pytest.approx(pk / 100)
    assert st.GF_QS[0, 0, 0] == pytest.approx(np.abs(100 + 20 * np.sin(2 * np.pi * 5 * t)).max() / 100)
    gf, gq = st.GF_Dy[0, 0, 0], st.GF_QS[0, 0, 0]
    assert st.Cont_M[0, 0, 0] == pytest.approx(1 / gf)
    assert st.Cont_BG[0, 0, 0] == pytest.approx((gq - 1) / gf)
    assert st.Cont_R[0, 0, 0] == pytest.approx((gf - gq) / gf)
    assert st.Cont_M[0, 0, 0] + st.Cont_BG[0, 0, 0] + st.Cont_R[0, 0, 0] == pytest.approx(1.0)
    assert st.peak_normalised[0, 0, 0] == pytest.approx(pk / 200.0)
    assert st.peak_dynamic_total[0, 0, 0] == pytest.approx(1000 + pk)
    assert np.isnan(st.GF_Dy[0, 0, 1]) and st.Cont_R[0, 0, 1] == pytest.approx(0.0)
    assert st.rms_background[0, 0, 0] == pytest.approx(20 / np.sqrt(2), rel=1e-2)


def test_time_step_halving_changes_rms_by_less_than_one_percent():
    """The same wind record (synthesised at 0.025 s; every second sample for 0.05 s)
    integrated at the default 0.05 s and at 0.025 s: r.m.s. of the fluctuating and resonant
    reactions differ by < 1 % (same realization, so no sampling error enters)."""
    import dataclasses

    from linecheck import service
    from linecheck.core.case import load_case
    from linecheck.core.wind.turbulence import fluctuating_velocity

    from ..conftest import CASES

    case = load_case(CASES / "paper" / "case10-single.toml")
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, damping="quasi-steady", duration=300.0))
    st = service.static_analysis(case)
    model = build_model(st.system, st.mean.state(0))
    C = service.damping_matrices(case, st, [model])
    t_fine = 0.025 * np.arange(12001)
    v = fluctuating_velocity(case, st.system, t_fine, [0])[0]
    a = 1.25 * 1.0 * 0.022 * model.tributary * 20.0
    free = model.dofs.free_nodes
    out = {}
    for dt, step in ((0.05, 2), (0.025, 1)):
        f = (a[None, :] * v[::step])[:, free]
        n = f.shape[0]
        resp = integrate([model], C, np.zeros(n, dtype=int), f[:, None, :], dt)
        keep = slice(n // 5, None)  # after the start-up transient (burn-in ~ 60 s)
        out[dt] = (np.sqrt((resp.fluctuating[0, keep, 0, :2] ** 2).mean(axis=0)),
                   np.sqrt((resp.resonant[0, keep, 0, :2] ** 2).mean(axis=0)))
    for k in range(2):
        np.testing.assert_allclose(out[0.05][k], out[0.025][k], rtol=0.01)


def test_non_positive_definite_state_and_nan_loads_are_reported():
    """A non-positive-definite stiffness or non-finite loads raise NumericalError
    (one line naming the state), never a result."""
    from linecheck.core.errors import NumericalError

    model = sdof_model(-5.0, 1.0)  # negative stiffness: not positive definite
    damping = np.zeros((1, 6, 3))
    with pytest.raises(NumericalError, match="not positive definite"):
        integrate([model], damping, np.zeros(4, dtype=int), np.ones((4, 1, 1)), 0.05)
    good = sdof_model(5.0, 1.0)
    loads = np.ones((4, 1, 1))
    loads[2] = np.nan
    with pytest.raises(NumericalError, match="non-finite"):
        integrate([good], damping, np.zeros(4, dtype=int), loads, 0.05)
