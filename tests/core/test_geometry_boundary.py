"""LineSystem owns the geometry (structure first).

No module under linecheck/ reads the case's ``span_length`` key except the geometry code
(linecheck/core/case_model.py defines it, case_load.py reads it for a downburst preset,
linecheck/core/system.py turns it into the per-span and per-node arrays) and the front ends
listed below, which only DISPLAY the key.
Everything numerical goes through ``LineSystem`` arrays, so that unequal spans change one place.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

import linecheck
from linecheck.core.case import Line
from linecheck.core.system import LineSystem

PACKAGE = Path(linecheck.__file__).resolve().parent

# the case model (defines the key), its loader (derives L_x for a downburst preset) and the system
GEOMETRY_CODE = {"core/case_model.py", "core/case_load.py", "core/system.py"}

# front ends / documents that display or copy the case's key; they never compute with it
DISPLAY_ONLY = {
    "io/section.py": "one-line line summary of the front ends: '6 spans x 300 m' (equal-span form)",
    "io/document.py": "run document copies the case's span_length key into the JSON identity block",
    "io/wires_document.py": "a run of several wires: the same JSON identity block as io/document.py",
    "excel/summary.py": "summary sheet prints the document's span_length column",
}


def _readers() -> dict[str, list[int]]:
    """Module path (relative to linecheck/) -> line numbers of every ``<expr>.span_length``."""
    out: dict[str, list[int]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        lines = [n.lineno for n in ast.walk(tree) if isinstance(n, ast.Attribute) and n.attr == "span_length"]
        if lines:
            out[path.relative_to(PACKAGE).as_posix()] = sorted(lines)
    return out


def test_only_geometry_code_reads_span_length():
    readers = _readers()
    # the scan sees real reads (otherwise this test could not fail)
    assert "core/system.py" in readers and "core/case_load.py" in readers
    offenders = {m: ln for m, ln in readers.items() if m not in GEOMETRY_CODE and m not in DISPLAY_ONLY}
    assert not offenders, f"read LineSystem arrays (span_lengths, tower_x, ...) instead of .span_length: {offenders}"


def test_display_exceptions_are_not_stale():
    readers = _readers()
    stale = sorted(m for m in DISPLAY_ONLY if m not in readers)
    assert not stale, f"remove from DISPLAY_ONLY (no longer reads span_length): {stale}"


def test_equal_span_arrays():
    """The arrays of the paper's equal-span section against hand-computed values."""
    line = Line(spans=3, span_length=300.0, sag=10.0, weight=17.92, diameter=0.022, drag_coefficient=1.0,
                area=0.7e-4, elastic_modulus=5.2e10, height=43.0, insulator_length=4.0,
                supports=("strain", "suspension", "suspension", "strain"), tower_of_interest=2,
                elements_per_span=4)
    s = LineSystem(line)
    np.testing.assert_array_equal(s.span_lengths, [300.0, 300.0, 300.0])
    np.testing.assert_array_equal(s.tower_x, [0.0, 300.0, 600.0, 900.0])
    np.testing.assert_array_equal(s.clamp_points[:, 0], s.tower_x)
    assert not s.clamp_points[:, 1:].any()
    np.testing.assert_array_equal(s.element_lengths, [75.0, 75.0, 75.0])
    np.testing.assert_array_equal(s.node_x0, np.arange(13) * 75.0)
    np.testing.assert_array_equal(s.span_node_x0[1], [300.0, 375.0, 450.0, 525.0, 600.0])
    np.testing.assert_array_equal(s.weight_spans, [300.0, 300.0, 300.0, 300.0])
    # L_u = L (1 + 8/3 (S/L)^2) / (1 + T0/EA), T0 = W L^2 / (8 S)  (Irvine 1981 Eq. 2.14; paper Table 1)
    t0 = 17.92 * 300.0**2 / 80.0
    lu = 300.0 * (1.0 + 8.0 / 3.0 / 900.0) / (1.0 + t0 / (5.2e10 * 0.7e-4))
    np.testing.assert_allclose(s.unstretched_lengths, lu, rtol=1e-15)
    np.testing.assert_allclose(s.element_unstretched_lengths, np.full(12, lu / 4), rtol=1e-15)
    assert s.equal_spans and s.common_span_length == 300.0 and s.uniform_element_length == 75.0
