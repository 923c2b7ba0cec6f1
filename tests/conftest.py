"""Shared fixtures: paths and paper systems."""

from __future__ import annotations

from pathlib import Path

import pytest

from linecheck.validation import paper_line  # noqa: F401  (the paper's system, Table 1)

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "cases"
DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture
def cases_dir() -> Path:
    return CASES
