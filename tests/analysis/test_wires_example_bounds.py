"""The shipped double circuit (cases/examples/section-12span-double-circuit.toml) run in one
correlated wind: every tower total's peak against its attachments' peaks (docs/wires.md).

The total of signed histories peaks at most at the sum of the attachments' peaks (triangle
inequality: max_t |sum_a r_a(t)| <= sum_a max_t |r_a(t)|), exactly, per realization.  When every
attachment loads the tower in the same sense, the total's peak is also at least the largest
attachment's; this holds for the forces and the overturning moments of the example, whose
attachments all push the tower the same way.  Torsion is the exception: the two circuits sit on
arms of opposite sign (y = +-5.5 m), so their torsions cancel and the total can stay below its
largest attachment -- measured at the end towers (T1: 75 vs 99 kN m).
"""

from __future__ import annotations

import numpy as np
import pytest

from linecheck import service
from linecheck.core.case import load_case
from linecheck.core.tower_totals import TOTALS

from ..conftest import CASES


@pytest.fixture(scope="module")
def example():
    case = load_case(CASES / "examples" / "section-12span-double-circuit.toml")
    return service.run_wires(case, realizations=[0, 1])


def test_every_total_is_at_most_the_sum_of_its_attachment_peaks(example):
    total, most = example.totals("peak_dynamic"), example.peak_sum()
    assert np.all(total <= most * (1 + 1e-12))
    # correlation saves something at every tower for the transverse force (the wires' gusts are
    # not fully coherent: 35 m/s, C_y = 16, C_z = 10 over 5-20 m)
    assert np.all(total[..., TOTALS.index("Fy")] < most[..., TOTALS.index("Fy")])


def test_forces_and_overturning_are_at_least_the_largest_attachment(example):
    total, largest = example.totals("peak_dynamic"), example.peak_largest()
    for name in ("Fx", "Fy", "Fz", "Mx", "My"):
        k = TOTALS.index(name)
        assert np.all(total[..., k] >= largest[..., k] * (1 - 1e-12)), name


def test_torsion_of_the_two_circuits_cancels(example):
    """Mz: opposite arms; the total is far below the sum (the two circuits cancel) and, at the
    end towers, below the largest attachment."""
    k = TOTALS.index("Mz")
    total, most, largest = example.totals("peak_dynamic")[..., k], example.peak_sum()[..., k], \
        example.peak_largest()[..., k]
    assert np.all(total < 0.5 * most)
    assert np.any(total < largest)
