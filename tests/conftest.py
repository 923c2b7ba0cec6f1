"""Shared fixtures: paths and paper systems."""

from __future__ import annotations

from pathlib import Path

import pytest

from linecheck.core.case import Line

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "cases"
DATA = Path(__file__).resolve().parent / "data"


def paper_line(L: float = 300.0, spans: int = 1, **kw) -> Line:
    """The paper's conductor system (Table 1): single span (strain-strain) or six spans."""
    supports = ("strain", "strain") if spans == 1 else ("strain",) + ("suspension",) * (spans - 1) + ("strain",)
    args = dict(
        spans=spans, span_length=L, sag=L / 30, weight=17.92, diameter=0.022, drag_coefficient=1.0,
        area=0.7e-4, elastic_modulus=5.2e10, height=43.0, insulator_length=4.0, supports=supports,
        tower_of_interest=1 if spans == 1 else spans // 2 + 1, elements_per_span=10,
    )
    args.update(kw)
    return Line(**args)


@pytest.fixture
def cases_dir() -> Path:
    return CASES
