"""The fast paths of steps 2-3 and of the frequency domain against straightforward references.

- Newmark in per-node bases (elementwise M and C products) against a dense Newmark in global
  coordinates (Bathe 1996 Table 9.3, written out here independently);
- block tridiagonal solves vectorised over frequencies against LAPACK zgbsv;
- complex modal superposition against direct solves of the dynamic stiffness.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from linecheck import service
from linecheck.core import spectral
from linecheck.core.case import load_case
from linecheck.core.dynamics import Newmark, _Stepper, integrate, node_bases
from linecheck.core.model import band_blocks, band_to_dense, blocks_to_band, rotate_band
from linecheck.core.spectral import ModalTransfer, _banded_solve, dynamic_solve

from ..conftest import CASES


def synoptic_state(name: str, **analysis):
    case = load_case(CASES / "paper" / f"{name}.toml")
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))
    st = service.static_analysis(case)
    return case, service.synoptic_model(case, st)


def test_band_blocks_round_trip_and_rotation_match_dense():
    rng = np.random.default_rng(3)
    n_nodes = 7
    n = 3 * n_nodes
    A = rng.standard_normal((n, n))
    A = A + A.T
    A[np.abs(np.arange(n)[:, None] // 3 - np.arange(n)[None, :] // 3) > 1] = 0.0  # block tridiagonal
    ab = np.zeros((6, n))
    for k in range(6):
        ab[5 - k, k:] = np.diag(A, k)
    assert np.array_equal(band_to_dense(ab), A)
    assert np.array_equal(band_to_dense(blocks_to_band(*band_blocks(ab))), A)
    T = np.linalg.qr(rng.standard_normal((n_nodes, 3, 3)))[0]
    Tf = np.zeros((n, n))
    for i in range(n_nodes):
        Tf[3 * i:3 * i + 3, 3 * i:3 * i + 3] = T[i]
    np.testing.assert_allclose(band_to_dense(rotate_band(ab, T)), Tf.T @ A @ Tf, atol=1e-13 * np.abs(A).max())


@pytest.mark.parametrize("damping", ["paper", "quasi-steady"])
def test_node_bases_make_mass_and_aerodynamic_damping_diagonal(damping):
    """Six spans (suspension insulators): in the node bases M is diag(m, m, 0) at attachment
    nodes and m elsewhere, and the aerodynamic damping has no off-diagonal term left."""
    _, sm = synoptic_state("case09-six", damping=damping, structural_damping=0.0)
    model = sm.model
    T = node_bases(model, sm.damping)
    np.testing.assert_allclose(np.einsum("nai,naj->nij", T, T), np.broadcast_to(np.eye(3), T.shape), atol=1e-14)
    Mr = band_to_dense(rotate_band(model.M_band, T))
    Cr = band_to_dense(rotate_band(sm.damping, T))
    expected = model.mass.copy()
    expected[model.axial_dof + 2] = 0.0
    np.testing.assert_allclose(np.diag(Mr), expected, atol=1e-12 * expected.max())
    assert np.abs(Mr - np.diag(np.diag(Mr))).max() < 1e-12 * expected.max()
    assert np.abs(Cr - np.diag(np.diag(Cr))).max() < 1e-12 * np.abs(Cr).max()
    st = _Stepper.build(model, sm.damping, Newmark(0.05))
    assert st.rest is None  # nothing but rounding off the diagonal: elementwise products only


def dense_newmark(model, c_band, loads, dt):
    """Average-acceleration Newmark in global coordinates, dense matrices (Bathe 1996 Table 9.3).

    Starts from the quasi-static state (u0 = K^-1 F0, v0 = a0 = 0) like linecheck.  Returns
    the reactions G u, shape (n_steps, n_real, n_r).
    """
    K, M, C = band_to_dense(model.K_band), band_to_dense(model.M_band), band_to_dense(c_band)
    n_steps, n_real, n_free = loads.shape
    ydof = 3 * np.arange(n_free) + 1
    F = np.zeros((n_steps, model.mass.size, n_real))
    F[:, ydof, :] = loads.transpose(0, 2, 1)
    a0, a1, a2 = 4 / dt**2, 2 / dt, 4 / dt
    Khat = K + a1 * C + a0 * M
    u = np.linalg.solve(K, F[0])
    v, a = np.zeros_like(u), np.zeros_like(u)
    out = [model.G @ u]
    for n in range(1, n_steps):
        u_new = np.linalg.solve(Khat, F[n] + M @ (a0 * u + a2 * v + a) + C @ (a1 * u + v))
        a_new = a0 * (u_new - u) - a2 * v - a
        v = v + 0.5 * dt * (a + a_new)
        u, a = u_new, a_new
        out.append(model.G @ u)
    return np.array(out).transpose(0, 2, 1)


@pytest.mark.parametrize("damping", ["paper", "quasi-steady"])
def test_rotated_newmark_matches_dense_global_newmark(damping):
    """Six spans, 400 steps of random loads, two realizations.  Quasi-steady damping brings
    stiffness-proportional structural damping, i.e. the sparse inter-node remainder.  The two
    schemes are the same recurrence in different coordinates: agreement to rounding (the
    insulator penalty makes K ill-conditioned, cond ~ 1e8, so 1e-9 and not 1e-15)."""
    _, sm = synoptic_state("case09-six", damping=damping)
    model = sm.model
    rng = np.random.default_rng(11)
    n_free = model.dofs.free_nodes.size
    loads = 50.0 * rng.standard_normal((400, 2, n_free))
    dt = 0.05
    resp = integrate([model], sm.damping[None], np.zeros(400, dtype=int), loads, dt)
    ref = dense_newmark(model, sm.damping, loads, dt)
    got = resp.fluctuating.transpose(1, 0, 2, 3).reshape(ref.shape)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_block_tridiagonal_solves_match_lapack_and_fall_back():
    """Dynamic stiffness solves at 300 frequencies, many of them on top of lightly damped
    poles (the paper's damping leaves modes with zeta ~ 1e-9): the vectorised block
    elimination agrees with LAPACK's pivoted zgbsv; with a zero backward-error tolerance
    every frequency goes through the fallback and the result is LAPACK's."""
    case, sm = synoptic_state("case09-six", damping="paper")
    model = sm.model
    blocks = [band_blocks(m) for m in (model.K_band, sm.damping, model.M_band)]
    j = case.line.tower_of_interest - 1
    rhs = model.G[3 * j:3 * j + 3].T.reshape(-1, 3, 3)
    poles = sm.modes.poles[:100]
    omega = np.concatenate([np.geomspace(1e-4, 60.0, 200), np.abs(poles)])
    ref = _banded_solve(blocks, omega, rhs).transpose(1, 2, 3, 0)
    got = dynamic_solve(blocks, omega, rhs)
    scale = np.abs(ref).max(axis=(0, 1, 2))
    assert np.max(np.abs(got - ref).max(axis=(0, 1, 2)) / scale) < 1e-8
    old = spectral.BACKWARD_ERROR_TOL
    try:
        spectral.BACKWARD_ERROR_TOL = 0.0
        assert np.array_equal(dynamic_solve(blocks, omega, rhs), ref)
    finally:
        spectral.BACKWARD_ERROR_TOL = old


@pytest.mark.parametrize("damping", ["paper", "quasi-steady"])
def test_modal_superposition_matches_direct_solves(damping):
    """Complex modal superposition (with the insulator feed-through) against direct solves:
    transfer functions on the whole pole-refined grid, then estimate 1 itself."""
    case, sm = synoptic_state("case09-six", damping=damping)
    model = sm.model
    j = case.line.tower_of_interest - 1
    blocks = [band_blocks(m) for m in (model.K_band, sm.damping, model.M_band)]
    rhs = model.G[3 * j:3 * j + 3].T.reshape(-1, 3, 3)
    omega = 2 * np.pi * spectral.frequency_grid(1e-5, 10.0, sm.modes)
    direct = dynamic_solve(blocks, omega, rhs)[:, 1].transpose(1, 0, 2)
    static = dynamic_solve(blocks, np.zeros(1), rhs)[:, 1, :, 0].T.real
    modal = ModalTransfer(model, sm.modes, j, static)(omega)
    err = np.abs(modal - direct).max(axis=(0, 1)) / np.abs(direct).max(axis=(0, 1))
    assert err.max() < 1e-7
    a = service.spectral_analysis(case, synoptic=sm).exact
    # direct solves on the same (full) grid: modes without eigenvectors
    no_vectors = dataclasses.replace(sm.modes, expansion=None, right=None, left=None)
    b = service.spectral_analysis(case, synoptic=dataclasses.replace(sm, modes=no_vectors)).exact
    assert (a.method, b.method, a.n_frequencies) == ("modal", "direct", b.n_frequencies)
    for q in ("rms_background", "rms_resonant", "rms_fluctuating", "nu_fluctuating"):
        np.testing.assert_allclose(getattr(a, q), getattr(b, q), rtol=1e-8)
    # the direct path with eigenvectors refines only the poles that matter at the tower
    # (single-mode r.m.s. > 1e-3 of the background's) and keeps coarse points away from the
    # others: each unrefined mode then counts at most ~1e3 x its own variance (< 1e-6 of the
    # background's); 0.1 % on the r.m.s. leaves room for a few hundred such modes
    pruned = dataclasses.replace(sm.modes, expansion=None)
    c = service.spectral_analysis(case, synoptic=dataclasses.replace(sm, modes=pruned)).exact
    assert c.method == "direct" and c.n_frequencies < 0.8 * a.n_frequencies
    for q in ("rms_background", "rms_resonant", "rms_fluctuating"):
        np.testing.assert_allclose(getattr(c, q), getattr(a, q), rtol=1e-3)


def test_project_axial_matches_dense_projector():
    """P^T A P with P = I - a a^T at the suspension attachment nodes, against dense matrices."""
    _, sm = synoptic_state("case09-six", damping="quasi-steady")
    from linecheck.core.model import project_axial

    model = sm.model
    A = band_to_dense(model.K_band)
    P = np.eye(A.shape[0])
    for first, a in zip(model.axial_dof, model.axes):
        P[first:first + 3, first:first + 3] -= np.outer(a, a)
    got = band_to_dense(project_axial(model, model.K_band))
    np.testing.assert_allclose(got, P.T @ A @ P, rtol=0, atol=1e-13 * np.abs(A).max())
    assert model.axial_dof.size == 5


def test_unrefined_pole_gets_an_exclusion_zone():
    """A pole of half-width b = 1e-9 f left unrefined, placed exactly on a point of the log
    grid: that point is dropped, nothing remains within sqrt(Delta / (pi b) / 1e3)
    half-widths of the pole (Delta the log spacing there)."""
    f0, z = float(np.geomspace(1e-3, 10.0, 300)[150]), 1e-9
    modes = spectral.ComplexModes(np.array([f0]), np.array([z]), np.array([-z * 2 * np.pi * f0 + 2j * np.pi * f0]))
    full = spectral.frequency_grid(1e-3, 10.0, modes)
    assert np.min(np.abs(full - f0)) < 10 * z * f0  # refined: points on the peak
    pruned = spectral.frequency_grid(1e-3, 10.0, modes, refine=np.array([False]))
    spacing = (10.0 / 1e-3) ** (1 / 299) - 1
    kappa = np.sqrt(spacing * f0 / (np.pi * z * f0) / spectral.EXCLUSION_RATIO)
    assert np.min(np.abs(pruned - f0)) >= kappa * z * f0
    assert pruned.size <= 300


def test_structural_damping_product_without_dispatch_is_the_same_bits(monkeypatch):
    """The step loop's C~_off (a1 u + v) calls scipy's CSR kernel directly; a run with
    quasi-steady damping (structural damping on: the remainder exists) gives the same bits as
    with the public ``rest @ x`` product (of the scipy matrix built from the stepper's CSR arrays)."""
    from linecheck.core import dynamics

    case = load_case(CASES / "examples" / "section-12span.toml")
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, realizations=2, duration=60.0))
    assert case.analysis.damping == "quasi-steady" and case.analysis.structural_ratio > 0
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")  # the numpy step loop, where the product is used
    fast = service.run_case(case, spectral_check=False)
    monkeypatch.setattr(dynamics, "_csr_matvecs", None)
    slow = service.run_case(case, spectral_check=False)
    assert np.array_equal(fast.background, slow.background)
    assert np.array_equal(fast.resonant, slow.resonant)


@pytest.mark.parametrize("name", ["paper/case05-six", "paper/case05-single", "paper/case03-single",
                                  "examples/downburst-ring-jet", "examples/downburst-user-field", "paper/case09-six",
                                  "examples/section-12span"])
def test_record_wind_is_the_mean_wind_and_modulation_bit_for_bit(name):
    """service.record_wind (one evaluation of an equal-span downburst's field at the distinct
    stations of the span and global nodes) against record_mean_wind and
    turbulence.modulation, which evaluate it at each set by itself: the same bits (the paper's
    single spans have stations that differ in the last bit between the two sets)."""
    from linecheck.core.wind.turbulence import modulation

    case = load_case(CASES / f"{name}.toml")
    st = service.static_analysis(case)
    t = service.record_time(case)[::7]
    vn, vl, a = service.record_wind(case, st, t)
    rn, rl = service.record_mean_wind(case, st, t)
    assert np.array_equal(vn, rn) and (vl is None and rl is None or np.array_equal(vl, rl))
    assert np.array_equal(a, modulation(case, st.system, t))
    if case.wind.type == "downburst":
        assert a.shape == (t.size, st.system.n_nodes) and np.ptp(a) > 0  # a varying field, not a constant
