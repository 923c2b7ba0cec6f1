"""The one definition of a tower's totals (linecheck.core.tower_totals): forces and moments about
the tower's base, M = sum r x F with z up, against hand values and numpy's cross product."""

from __future__ import annotations

import numpy as np

from linecheck.core.tower_totals import FORCES, MOMENTS, TOTALS, reaction_moments, tower_totals


def test_the_names():
    assert TOTALS == ("Fx", "Fy", "Fz", "Mx", "My", "Mz") and FORCES + MOMENTS == TOTALS


def test_one_reaction_by_hand():
    """R = (1, 2, 3) N (tower frame, z down) at (0, y, z) = (0, 2, 10) m: r x F with F = (1, 2, -3)
    about the axes x, y, z up: M_x = 2 (-3) - 10 (2) = -26, M_y = 10 (1) - 0 = 10, M_z = 0 - 2 (1) = -2."""
    np.testing.assert_array_equal(reaction_moments(np.array([[1.0, 2.0, 3.0]]), np.array([2.0]), np.array([10.0])),
                                  [[-26.0, 10.0, -2.0]])
    np.testing.assert_array_equal(np.cross([0.0, 2.0, 10.0], [1.0, 2.0, -3.0]), [-26.0, 10.0, -2.0])


def test_the_worked_example_of_docs_wires():
    """docs/wires.md: one attachment at y = 5 m, z = 30 m with R = (2, 10, 20) kN gives
    F = (2, 10, 20) kN and M = (-400, 60, -10) kN m."""
    tot = tower_totals(np.array([[[2e3, 10e3, 20e3]]]), np.array([[5.0]]), np.array([[30.0]]))
    np.testing.assert_allclose(tot, [[2e3, 10e3, 20e3, -400e3, 60e3, -10e3]], rtol=1e-15)


def test_totals_are_sums_of_cross_products():
    """Random reactions at random points of two towers with three wires, two instants: the forces
    are the sums, the moments the sums of numpy's r x (R_x, R_y, -R_z)."""
    rng = np.random.default_rng(3)
    R = rng.standard_normal((2, 2, 3, 3)) * 1e4
    y, z = rng.uniform(-8, 8, (2, 3)), rng.uniform(20, 45, (2, 3))
    tot = tower_totals(R, y, z)
    assert tot.shape == (2, 2, 6)
    r = np.stack([np.zeros_like(y), y, z], axis=-1)
    up = R * np.array([1.0, 1.0, -1.0])
    np.testing.assert_allclose(tot[..., :3], R.sum(axis=-2), rtol=1e-14)
    np.testing.assert_allclose(tot[..., 3:], np.cross(r, up).sum(axis=-2), rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(reaction_moments(R, y, z).sum(axis=-2), tot[..., 3:])
