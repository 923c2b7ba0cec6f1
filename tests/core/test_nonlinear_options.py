"""Nonlinear options: the drag's v^2 term, the second-order tension and the exported wind field."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import lapack, solve

from linecheck import service
from linecheck.analysis import run as run_module
from linecheck.core.case import load_case
from linecheck.core.model import build_model
from linecheck.core.second_order import second_order_of_loads, second_order_operator, second_order_reactions
from linecheck.core.static import solve_static, span_loads_uniform
from linecheck.core.system import LineSystem

CASES = Path(__file__).resolve().parents[2] / "cases"


def paper(name: str, **analysis):
    case = load_case(CASES / "paper" / f"{name}.toml")
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


# --------------------------------------------------------------------------- quadratic drag
@pytest.mark.parametrize("direction", [0.0, 25.0])
def test_synoptic_loads_from_the_held_mean_row(direction):
    """A synoptic record's mean is one row viewed over the record (stride 0): fluctuating_loads
    computes its per-node factors on that row; the loads must be those of the materialised record
    (linear and quadratic drag, normal and oblique wind)."""
    for drag in ("linear", "quadratic"):
        case = paper("case09-six", drag=drag)
        case = dataclasses.replace(case, wind=dataclasses.replace(case.wind, direction=direction))
        st = service.static_analysis(case)
        model = service.synoptic_model(case, st, vectors=False).model
        t = np.arange(400) * case.analysis.time_step
        vn, vl = service.record_mean_wind(case, st, t)
        assert vn.strides[0] == 0 and (vl is None) == (direction == 0.0)
        v = np.random.default_rng(7).standard_normal((2, t.size, st.system.n_nodes)) * 5.0
        held = service.fluctuating_loads(case, st.system, model, t, v, vn, vl)
        full = service.fluctuating_loads(case, st.system, model, t, v, np.array(vn), None if vl is None else np.array(vl))
        for a, b in zip(held, full):
            assert np.array_equal(a, b)


@pytest.mark.parametrize("name", ["case09-single", "case10-six", "case05-single"])
def test_quadratic_drag_mean_rises_by_I2(name):
    """The mean of 1/2 rho C_d D (V + v)^2 is 1/2 rho C_d D V^2 (1 + I^2): the step-1 mean R_y
    rises by I^2 = 1.44 % (within 0.1 %: a strain tower's R_y is linear in the transverse load,
    a suspension tower's nearly so; downburst: sigma = I V_m at every instant)."""
    lin = service.static_analysis(paper(name, drag="linear"))
    quad = service.static_analysis(paper(name, drag="quadratic"))
    I2 = quad.case.wind.turbulence_intensity ** 2
    j = quad.case.line.tower_of_interest - 1
    k = service.reference_state_index(lin.case, lin.mean)
    ratio = quad.mean.reactions_wind[k, j, 1] / lin.mean.reactions_wind[k, j, 1]
    assert abs(ratio - (1.0 + I2)) < 1e-3, ratio


def test_quadratic_drag_fluctuation_is_the_rest_of_the_square():
    """Step-1 load + fluctuating load = 1/2 rho C_d D (V + v)^2 L_i at every node and step
    (synoptic, one span): the v^2 term is the drag on the total wind minus Eq. 1 and Eq. 5."""
    case = paper("case09-single", drag="quadratic", duration=30.0)
    st = service.static_analysis(case)
    t, _ = service.record_grid(case, st)
    vn, vl = service.record_mean_wind(case, st, t)
    from linecheck.core.wind.turbulence import fluctuating_velocity

    v = fluctuating_velocity(case, st.system, t, [0])
    model = build_model(st.system, st.mean.state(0))
    loads, _ = service.fluctuating_loads(case, st.system, model, t, v, vn, vl)
    half = 0.5 * case.wind.air_density * case.line.drag_coefficient * case.line.diameter
    free = model.dofs.free_nodes
    L = model.tributary[free]
    g_mean = service.to_global_nodes(st.system, st.mean.gy)[0][free]  # Eq. 1 x (1 + I^2)
    total = g_mean * L + loads[:, 0]
    exact = half * (vn[:, free] + v[0][:, free]) ** 2 * L
    assert np.allclose(total, exact, rtol=1e-12, atol=1e-9)


# --------------------------------------------------------------------------- second-order tension
def _central_differences(name: str, pattern: np.ndarray, tower: int, comp: int):
    """(first, second) central differences of the non-linear static solver and (G u1, R2(u1)) of
    the linear model, for transverse load increments delta g (1 %, 5 %, 10 % of g*_yp)."""
    case = load_case(CASES / "paper" / f"{name}.toml")
    sy = LineSystem(case.line)
    g = case.g_yp
    s0 = solve_static(sy, span_loads_uniform(sy, g), tol=1e-13)
    model = build_model(sy, s0)
    op = second_order_operator(model, s0)
    out = []
    for d in (0.01, 0.05, 0.10):
        sp = solve_static(sy, span_loads_uniform(sy, g * (1 + d * pattern)), tol=1e-13)
        sm = solve_static(sy, span_loads_uniform(sy, g * (1 - d * pattern)), tol=1e-13)
        # nodal y-loads of the increment: tributary unstretched length of each span's nodes
        gl = np.zeros(sy.n_nodes)
        h = sy.unstretched_length / sy.ne
        for s in range(sy.n_spans):
            gl[s * sy.ne:(s + 1) * sy.ne + 1] += d * g * pattern[s] * h * np.r_[0.5, np.ones(sy.ne - 1), 0.5]
        F = np.zeros(model.mass.size)
        F[1::3] = gl[model.dofs.free_nodes]
        u1 = solve(model.K_dense, F)
        k = 3 * tower + comp
        first = 0.5 * (sp.reactions - sm.reactions).ravel()[k]
        second = 0.5 * (sp.reactions + sm.reactions - 2 * s0.reactions).ravel()[k]
        out.append((first, second, (model.G @ u1)[k], second_order_reactions(op, u1[None])[0, k]))
    return np.array(out)


@pytest.mark.parametrize("name, pattern, tower, comp", [
    ("case10-single", np.ones(1), 0, 0),  # strain tower: R_x = the span's tension change
    ("case09-six", np.array([0, 0, 1.0, 0, 0, 0]), 3, 0),  # suspension tower 4, one span loaded
    ("case09-six", np.array([0, 0, 1.0, 0, 0, 0]), 3, 2),  # its vertical reaction
])
def test_second_order_tension_against_static_solver(name, pattern, tower, comp):
    """R_2(u_1) is the second-order term of the non-linear static solver (step 1) under load
    increments of 1, 5 and 10 %: the central difference (R(+) + R(-) - 2 R(0))/2 = R_2 + O(d^4).

    Two parts of the remaining error, both measured here:
    * the linear model's tangent differs from step 1's by its 10 straight elements per span
      against the continuous shallow cable: the first-order term G u_1 is off by r1 (-0.9 % on
      R_x of the single span, -1.2 % at the suspension tower) and R_2 by the same amount
      (|r2 - r1| < 0.5 %, independent of the increment);
    * the O(d^2) relative error of the second difference (its d^4 term): r2 changes by
      less than 0.2 % from 1 % to 10 %, and the change from 1 % to 5 % is (25 - 1)/(100 - 1)
      = 0.24 of that from 1 % to 10 % (0.15 ... 0.35 allowed): the remaining error is of order
      d^2, i.e. R_2 is exact to second order.
    """
    r = _central_differences(name, pattern, tower, comp)
    first, second, lin, r2 = r.T
    sign = 1.0  # step 1 and G both report R_z downward
    r1 = lin * sign / first - 1.0
    rel2 = r2 * sign / second - 1.0
    assert np.all(np.abs(rel2) < 0.02), rel2
    assert np.all(np.abs(rel2 - r1) < 0.005), (rel2, r1)
    assert abs(rel2[2] - rel2[0]) < 2e-3
    if abs(rel2[2] - rel2[0]) > 1e-5:  # below that, rounding of the second difference decides
        frac = (rel2[1] - rel2[0]) / (rel2[2] - rel2[0])
        assert 0.15 < frac < 0.35, frac


@pytest.mark.numerics  # bitwise determinism: CI repeats it under another BLAS core type
def test_second_order_bit_identical_whatever_else_runs():
    """A realization's B and R with both options do not depend on the other realizations in
    the same run (batch chunking, workers)."""
    case = paper("case09-six", damping="quasi-steady", drag="quadratic", tension="second-order", duration=40.0,
                 burn_in=5.0)
    both = service.run_case(case, realizations=[0, 2], spectral_check=False)
    alone = service.run_case(case, realizations=[2], spectral_check=False)
    assert np.array_equal(both.background[1], alone.background[0])
    assert np.array_equal(both.resonant[1], alone.resonant[0])


def _reference_second_order(op, U, T=None, dtype=np.float64):
    """R_2 = f2 A as first built: the member forces f2 (module docstring of
    linecheck.core.second_order) assembled component by component, then the product with A.
    Kept here as the reference of the faster P W form (same operator, other arithmetic);
    ``dtype`` np.longdouble evaluates it in extended precision (x86: 64-bit mantissa)."""
    m, n_el = U.shape[0], op.n_nodes - 1
    n_m = op.c.size
    Un = U.astype(dtype).reshape(m, -1, 3)
    if T is not None:  # u = T u~ node by node
        Un = np.einsum("nkj,mnj->mnk", T.astype(dtype), Un)
    u = np.zeros((m, op.n_nodes, 3), dtype)
    u[:, np.setdiff1d(np.arange(op.n_nodes), op.pinned)] = Un
    d = np.concatenate([u[:, 1:] - u[:, :-1], u[:, op.ins_nodes]], axis=1)  # (m, n_m, 3)
    e = op.e.reshape(-1, 3).astype(dtype)
    a = np.einsum("mik,ik->mi", d, e)
    q = 0.5 * np.einsum("mik,mik->mi", d, d) - 1.5 * a * a
    f = op.c.astype(dtype)[:, None] * (a[..., None] * d + q[..., None] * e)  # force on end a, (m, n_m, 3)
    assert n_m == n_el + op.ins_nodes.size
    return f.transpose(0, 2, 1).reshape(m, 3 * n_m) @ op.A.astype(dtype)


@pytest.mark.numerics
@pytest.mark.parametrize("rotated", [False, True])
def test_second_order_fast_form_equals_member_forces(rotated):
    """The P W form of R_2 (cable elements' a du + q e, insulators' a s, a w, s^2 + w^2) equals f2 A to rounding, and
    is no less accurate.  Displacements: linear responses K^-1 F to random combinations of
    10 % transverse and vertical load increments per span and random nodal loads (so the
    insulators swing, e.du ~ 0: the ill-conditioned case, the rigid insulators' c ~ 10^4 times
    a cable element's times their small e.du), 600 rows (several blocks, the last one padded);
    rotated into random per-node bases for the Newmark form.

    Tolerances: against an extended-precision evaluation of f2 A, f2 A in float64 is off by
    0.9e-12 (global) and 2.3e-12 (rotated) of max |R_2|, the P W form by 0.9e-12 and 1.5e-12:
    1e-12 between two float64 evaluations is below this problem's rounding floor, so the two
    forms are compared within 5e-12 and the P W form's error must not exceed 1.5 times f2 A's
    (plus 1e-13 of max |R_2|).  A row's result does not depend on the other rows of the call
    (bit for bit: one code path on one machine, the products always of one shape)."""
    case = load_case(CASES / "paper" / "case09-six.toml")
    sy = LineSystem(case.line)
    s0 = solve_static(sy, span_loads_uniform(sy, case.g_yp), tol=1e-13)
    model = build_model(sy, s0)
    op = second_order_operator(model, s0)
    rng = np.random.default_rng(16)
    n_dof = model.mass.size
    g = 0.1 * case.g_yp * sy.unstretched_length / sy.ne  # [N] 10 % of a node's transverse load
    span = np.repeat(np.arange(sy.n_spans), sy.ne)[np.minimum(model.dofs.free_nodes, sy.n_spans * sy.ne - 1)]
    F = np.zeros((n_dof, 2 * sy.n_spans + 4))
    for s in range(sy.n_spans):
        F[1::3, s] = g * (span == s)  # transverse, span by span
        F[2::3, sy.n_spans + s] = -g * (span == s)  # vertical
    F[:, 2 * sy.n_spans:] = 0.2 * g * rng.standard_normal((n_dof, 4))  # random nodal loads
    U = rng.standard_normal((600, F.shape[1])) @ solve(model.K_dense, F).T
    T = None
    if rotated:
        T, _ = np.linalg.qr(rng.standard_normal((n_dof // 3, 3, 3)))
        U = np.einsum("njk,mnj->mnk", T, U.reshape(600, -1, 3)).reshape(600, -1)  # u~ = T^T u
    ref = _reference_second_order(op, U, T)
    fast = second_order_reactions(op, U, T)
    scale = np.abs(ref).max()
    assert scale > 100.0  # [N] the test has something to compare (249 N)
    assert np.abs(fast - ref).max() <= 5e-12 * scale, np.abs(fast - ref).max() / scale
    if np.finfo(np.longdouble).eps < 1e-18:  # extended precision available (x86)
        exact = _reference_second_order(op, U, T, dtype=np.longdouble)
        err_fast, err_ref = (float(np.abs(x - exact).max()) for x in (fast, ref))
        assert err_fast <= 1.5 * err_ref + 1e-13 * scale, (err_fast / scale, err_ref / scale)
    # block by block: a row's result does not depend on the other rows
    assert np.array_equal(second_order_reactions(op, U[37:38], T), fast[37:38])
    assert np.array_equal(second_order_reactions(op, U[5:300:3], T), fast[5:300:3])
    if not rotated:  # the quasi-static entry: loads l on the free nodes, K u = l by the band factor
        n_free = n_dof // 3
        c = lapack.dpbtrf(model.K_band, lower=0)[0]
        dirs = rng.standard_normal((n_free, 3))
        dirs /= np.linalg.norm(dirs, axis=1)[:, None]
        L = g * rng.standard_normal((300, n_free))
        for d in (None, dirs):
            E = np.zeros((n_dof, n_free))  # nodal load directions: global y, or dirs
            for i in range(n_free):
                E[3 * i:3 * i + 3, i] = [0.0, 1.0, 0.0] if d is None else d[i]
            of_loads = second_order_of_loads(op, L, c, d)
            direct = second_order_reactions(op, L @ solve(model.K_dense, E).T)
            # two solvers (band substitution, dense LU): K's condition number (~1e5 here) times
            # the rounding, relative to max |R_2|
            assert np.abs(of_loads - direct).max() <= 1e-9 * np.abs(direct).max()
            assert np.abs(direct).max() > 10.0  # [N] something to compare
            assert np.array_equal(second_order_of_loads(op, L[7:200:4], c, d), of_loads[7:200:4])


def test_second_order_raises_strain_tower_tension():
    """The second-order stretch is always positive: the mean wind-induced R_x at a strain tower
    over a gusty record rises with tension = "second-order" (single span, 20 m/s)."""
    lin = service.run_case(paper("case10-single", duration=120.0), realizations=[0], spectral_check=False)
    sec = service.run_case(paper("case10-single", duration=120.0, tension="second-order"), realizations=[0],
                           spectral_check=False)
    x_lin = (lin.background + lin.resonant)[0, :, 0].mean()
    x_sec = (sec.background + sec.resonant)[0, :, 0].mean()
    assert x_sec > x_lin + 1.0  # [N]: E[R_2] > 0 (about +15 N here)
    # the same linear history underneath: the R_y (first order in the motion) barely moves
    assert np.allclose(sec.background[0, :, 1], lin.background[0, :, 1], rtol=0, atol=0.02 * np.abs(
        lin.background[0, :, 1]).max())


# --------------------------------------------------------------------------- wind field export
@pytest.mark.parametrize("name, changes", [
    ("case09-six", dict(damping="quasi-steady", drag="quadratic", duration=30.0)),  # synoptic, burn-in
    ("case05-single", dict(time_step=0.25, drag="quadratic")),  # downburst: oblique running mean
])
def test_exported_field_round_trips(tmp_path, monkeypatch, name, changes):
    """Reading the NPZ back gives the loads the run used, bit for bit."""
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    case = paper(name, **changes)
    captured = {}
    real = run_module.integrate

    def spy(models, damping, state_of_step, loads, dt, **kw):
        captured["loads"], captured["direct"] = loads.copy(), kw["direct"].copy()
        return real(models, damping, state_of_step, loads, dt, **kw)

    monkeypatch.setattr(run_module, "integrate", spy)
    res = service.run_case(case, realizations=[1], spectral_check=False)
    fld = service.wind_field(case, realization=1)
    path = tmp_path / "field.npz"
    np.savez(path, **fld.to_npz_dict())
    back = service.read_wind_field(path)
    loads, direct = service.loads_from_field(case, back)
    assert np.array_equal(loads, captured["loads"])
    assert np.array_equal(direct, captured["direct"])
    # public layout
    n_nodes = case.line.spans * case.line.elements_per_span + 1
    n_t = back["t"].size
    assert back["x_node"].shape == (n_nodes, 3)
    assert back["u_mean"].shape == back["u_turb"].shape == (n_t, n_nodes, 3)
    assert np.allclose(back["t"][back["t"] >= back["t"][0] + float(back["burn_in"]) - 1e-9], res.time)
    assert str(back["case"]) == case.name and int(back["realization"]) == 2
    # the turbulence is along the running mean: u_turb x u_mean = 0, |u_turb| = |v|
    cross = np.cross(back["u_mean"], back["u_turb"])
    assert np.abs(cross).max() < 1e-9 * max(1.0, np.abs(back["u_mean"]).max() ** 2)
    if name == "case09-six":  # the CLI writes the same file (case from disk: default duration)
        out = tmp_path / "cli.npz"
        r = CliRunner().invoke(app, ["wind", str(CASES / "paper" / "case10-single.toml"), "--field", str(out),
                                     "--realization", "2"])
        assert r.exit_code == 0, r.output
        z = service.read_wind_field(out)
        ref = service.wind_field(load_case(CASES / "paper" / "case10-single.toml"), realization=1)
        assert np.array_equal(z["u_turb"], ref.u_turb) and np.array_equal(z["t"], ref.t)
