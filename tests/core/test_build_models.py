"""The mean-state models of a downburst built in one vectorised pass.

:func:`build_models` must give, for every mean state, exactly (bit for bit) the model that
:func:`build_model` gives for that state alone: the paper's six-span downburst (level,
straight, strain ends and suspension towers) and the 12-span section example (unequal,
inclined spans, angle-strain and angle-suspension towers, so that every element block
and insulator axis is oblique).
"""

from __future__ import annotations

import numpy as np
import pytest

from linecheck import service
from linecheck.core.case import load_case
from linecheck.core.model import build_model, build_models
from linecheck.core.static import solve_static_batch

from ..conftest import CASES

MODEL_ARRAYS = ("K_band", "mass", "tributary", "G", "axes", "axial_dof", "K_axial_band")


def same_bits(x: np.ndarray, y: np.ndarray) -> bool:
    """Equal shape, dtype and bytes (stricter than np.array_equal: -0.0 != 0.0 here)."""
    x, y = np.asarray(x), np.asarray(y)
    return x.shape == y.shape and x.dtype == y.dtype and np.ascontiguousarray(x).tobytes() == \
        np.ascontiguousarray(y).tobytes()


@pytest.fixture(scope="module")
def downburst_six():
    case = load_case(CASES / "paper" / "case05-six.toml")
    st = service.static_analysis(case)
    return case, st, [st.mean.state(k) for k in range(st.mean.time.size)]


@pytest.fixture(scope="module")
def section_states():
    """Seven states of the section: the mean wind scaled 0.2..1.3, the synoptic state, still air."""
    case = load_case(CASES / "examples" / "section-12span.toml")
    st = service.static_analysis(case)
    gy = st.mean.gy[0]
    scaled = solve_static_batch(st.system, np.stack([f * gy for f in (0.2, 0.5, 0.8, 1.0, 1.3)]),
                                labels=[f"x{f}" for f in range(5)])
    return case, st, scaled + [st.mean.state(0), st.mean.still_air]


def assert_models_identical(one, many) -> None:
    assert len(one) == len(many)
    for k, (a, b) in enumerate(zip(one, many)):
        for name in MODEL_ARRAYS:
            assert same_bits(getattr(a, name), getattr(b, name)), f"state {k}: {name} differs"
        assert a.dofs.n_dof == b.dofs.n_dof
        assert same_bits(a.dofs.free_nodes, b.dofs.free_nodes)
        assert same_bits(a.dofs.node_dof, b.dofs.node_dof)


@pytest.mark.numerics  # bitwise determinism: CI repeats it under another BLAS core type
@pytest.mark.parametrize("which", ["downburst_six", "section_states"])
def test_build_models_bit_identical_to_one_by_one(which, request):
    _, st, states = request.getfixturevalue(which)
    assert len(states) > 1
    one = [build_model(st.system, s) for s in states]
    many = build_models(st.system, states)
    assert_models_identical(one, many)
    # the states differ, so the comparison is not vacuous
    assert not np.array_equal(many[0].K_band, many[-1].K_band)
    assert not np.array_equal(many[0].G, many[-1].G)


def test_build_models_shares_only_state_independent_arrays(downburst_six):
    _, st, states = downburst_six
    many = build_models(st.system, states[:3])
    assert many[0].mass is many[1].mass and not many[0].mass.flags.writeable
    assert not np.shares_memory(many[0].G, many[1].G)
    assert build_models(st.system, []) == []


def stepper_fields_identical(a, b) -> bool:
    fields = ("T", "chat", "dm", "cu", "cv", "ycoef", "axial", "nz", "GT")
    if not all(same_bits(getattr(a, f), getattr(b, f)) for f in fields) or (a.rest is None) != (b.rest is None):
        return False
    if a.rest is None:
        return True
    return same_bits(a.rest.indptr, b.rest.indptr) and same_bits(a.rest.indices, b.rest.indices) and \
        same_bits(a.rest.data, b.rest.data)


@pytest.mark.parametrize("which,damping,zeta", [
    ("downburst_six", "paper", 0.0),  # the paper's case: transverse damping only
    ("downburst_six", "quasi-steady", 0.005),  # full 3x3 node blocks and a structural remainder
    ("section_states", "paper", 0.0),  # oblique node normals and insulator axes
    ("section_states", "quasi-steady", 0.002),
])
def test_damping_and_steppers_stacked_bit_identical(which, damping, zeta, request):
    """The stacked build's second part: damping matrices, node bases (batched eigh), rotated bands and the
    Newmark operators of all states at once equal those built state by state, bit for bit."""
    import dataclasses

    from linecheck.core.damping import (
        aerodynamic_damping,
        aerodynamic_damping_stack,
        stiffness_proportional,
        stiffness_proportional_stack,
    )
    from linecheck.core.dynamics import Newmark, _rotated_stack, _Stepper

    case, st, states = request.getfixturevalue(which)
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, damping=damping,
                                                                  structural_damping=zeta))
    models = build_models(st.system, states)
    vn_all = service.to_global_nodes(st.system, st.wind.normal)
    vn0 = vn_all[np.argmax(np.abs(vn_all).sum(axis=1))]  # the strongest mean wind of the case
    vn = np.stack([(0.5 + 0.1 * k) * vn0 for k in range(len(states))])  # a different wind per state
    nodes = np.stack([s.nodes for s in states])
    w1 = 2.5  # [rad/s] any calibration frequency: the same one on both sides
    one = np.stack([aerodynamic_damping(case, m, vn[k], nodes[k]) for k, m in enumerate(models)])
    many = aerodynamic_damping_stack(case, models, vn, nodes)
    if zeta > 0:
        one = one + np.stack([stiffness_proportional(m, zeta, w1) for m in models])
        many = many + stiffness_proportional_stack(models, zeta, w1)
    assert same_bits(one, many)
    assert not np.array_equal(one[0], one[-1])
    nm = Newmark(case.analysis.time_step)
    T, Kr, Cr = _rotated_stack(models, many)
    system = st.system  # a section's loads along its node normals (as service.run_case passes them)
    ld = None if system.straight_in_plan else system.node_normals[models[0].dofs.free_nodes]
    stacked = _Stepper.stack(models, T, Kr, Cr, nm, ld)  # all operators in vectorised passes
    for k, m in enumerate(models):
        ref = _Stepper.build(m, one[k], nm, ld)
        assert stepper_fields_identical(ref, _Stepper.from_bases(m, T[k], Kr[k], Cr[k], nm, ld)), f"state {k}"
        assert stepper_fields_identical(ref, stacked[k]), f"state {k}, stacked"
        assert np.array_equal(ref.cols, stacked[k].cols) and ref.a1 == stacked[k].a1 and ref.r2 == stacked[k].r2
        assert (ref.rest is not None) == (zeta > 0)


def test_build_models_without_suspension_towers():
    """A single span (two strain towers): no insulator blocks, G from the cable elements only."""
    case = load_case(CASES / "paper" / "case05-single.toml")
    st = service.static_analysis(case)
    states = [st.mean.state(k) for k in range(0, st.mean.time.size, 10)]
    assert not st.system.suspension.any()
    assert_models_identical([build_model(st.system, s) for s in states], build_models(st.system, states))


def _dia_csr(ab: np.ndarray):
    """scipy's own banded -> CSR conversion (dia_matrix.tocsr), written out independently."""
    from scipy.sparse import dia_matrix

    u, n = ab.shape[0] - 1, ab.shape[1]
    data, offsets = [], []
    for k in range(u + 1):
        data.append(ab[u - k])  # dia convention: data[k', j] = A[j - offset, j]
        offsets.append(k)
        if k:
            low = np.zeros(n)
            low[: n - k] = ab[u - k, k:]  # A[j + k, j] = A[j, j + k]
            data.append(low)
            offsets.append(-k)
    return dia_matrix((np.array(data), np.array(offsets)), shape=(n, n)).tocsr()


@pytest.mark.parametrize("n, u", [(2, 1), (6, 5), (7, 5), (183, 5), (30, 0)])
def test_band_to_sparse_gives_scipys_csr_arrays(n, u):
    """model.band_to_csr / band_to_sparse (one vectorised gather) against scipy's dia -> csr: the same
    indptr, indices (int32) and data, explicit zeros dropped, columns ascending -- the
    structural-damping remainder's products (CSR order) keep their bits -- and the dense matrix."""
    from linecheck.core.model import band_to_csr, band_to_dense, band_to_sparse

    rng = np.random.default_rng(n + u)
    ab = rng.standard_normal((u + 1, n))
    ab[rng.random(ab.shape) < 0.3] = 0.0
    for k in range(1, u + 1):
        ab[u - k, :k] = 0.0  # outside the matrix in upper band storage
    ref = _dia_csr(ab)
    for got in (band_to_csr(ab), band_to_sparse(ab)):  # the arrays the step loops read, and the scipy matrix
        for f in ("indptr", "indices", "data"):
            assert getattr(got, f).dtype == getattr(ref, f).dtype and np.array_equal(getattr(got, f), getattr(ref, f)), f
    got = band_to_sparse(ab)
    assert np.array_equal(got.toarray(), band_to_dense(ab))


def test_stacked_steppers_where_the_sparsity_patterns_differ(downburst_six):
    """_Stepper.stack takes each state's sparse reaction rows by itself when the states' reaction
    maps touch different coordinates (here one state's G with a node's columns set to exact zeros): the
    same operators as state by state, each with its own reaction coordinates."""
    import dataclasses

    from linecheck.core.damping import aerodynamic_damping_stack
    from linecheck.core.dynamics import Newmark, _rotated_stack, _Stepper

    case, st, states = downburst_six
    models = build_models(st.system, states[:4])
    G = models[1].G.copy()
    node = int(np.flatnonzero(np.any(G.reshape(G.shape[0], -1, 3) != 0.0, axis=(0, 2)))[0])
    G[:, 3 * node:3 * node + 3] = 0.0
    models[1] = dataclasses.replace(models[1], G=G)
    vn = service.to_global_nodes(st.system, st.wind.normal)[:4]
    c = aerodynamic_damping_stack(case, models, vn, np.stack([s.nodes for s in states[:4]]))
    nm = Newmark(case.analysis.time_step)
    T, Kr, Cr = _rotated_stack(models, c)
    stacked = _Stepper.stack(models, T, Kr, Cr, nm)
    for k, m in enumerate(models):
        assert stepper_fields_identical(_Stepper.from_bases(m, T[k], Kr[k], Cr[k], nm), stacked[k]), f"state {k}"
    assert stacked[1].nz.size < stacked[0].nz.size
