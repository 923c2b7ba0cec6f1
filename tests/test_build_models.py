"""Issue 20: the mean-state models of a downburst built in one vectorised pass.

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

from .conftest import CASES

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
