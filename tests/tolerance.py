"""Tolerances for comparing two implementations of the same quantity (compiled vs numpy, two
formulations, another CPU's BLAS kernels), and the helper that applies them.

Bits are compared only between runs of one code path on one machine (``--jobs``, chunking,
executors, ``--resume``).  Between implementations the measure is the largest absolute
difference over the largest |value| of the compared array (:func:`rel_diff`), so that entries
near zero (a reaction component that is almost nil) are judged on the array's scale:

- :data:`RTOL_OP` (1e-12) for one operation or a short chain on the same input: float64 forms of
  the same arithmetic in another order differ by a few ulps (~1e-16) times the condition number
  of the operation (≤ 1e2 in these tests); the compiled kernel's load check uses the same bound
  (:data:`linecheck.core.kernel.RTOL`).
- :data:`RTOL_SOLVE` (1e-9) for anything that goes through a solve with the line's static
  stiffness K (step 3, the second-order displacements of loads): two correct solvers differ by up
  to about κ(K) ε, and a conductor line's K is ill-conditioned (stiff along the wire, soft across
  it: κ ≈ 1.9e6 for paper case 9, six spans, and 2.9e6 for the 12-span section), so κ ε ≈ 3e-10;
  1e-9 leaves a factor 3 over that worst case (measured: ≤ 2e-12).
- :data:`RTOL_RUN` (1e-9) for a whole run (thousands of Newmark steps, step 3, statistics over
  the record): the average-acceleration recurrence is unconditionally stable and does not
  amplify a rounding difference entering at one step, and its effective stiffness (K plus the
  mass and damping terms) is far better conditioned than K, so a run's differences are those of
  its step-3 solves: the bound of RTOL_SOLVE.  Measured between the compiled and numpy paths and
  between OpenBLAS core types: docs/testing.md.
"""

from __future__ import annotations

import numpy as np

RTOL_OP = 1e-12
RTOL_SOLVE = 1e-9
RTOL_RUN = 1e-9


def rel_diff(got, ref) -> float:
    """max |got - ref| / max |ref| over the finite entries (inf when shapes or the finite
    pattern differ; 0 when both are all zero)."""
    got, ref = np.asarray(got, dtype=float), np.asarray(ref, dtype=float)
    if got.shape != ref.shape or not np.array_equal(np.isfinite(got), np.isfinite(ref)):
        return np.inf
    fin = np.isfinite(ref)
    if not fin.any():
        return 0.0
    scale = np.max(np.abs(ref[fin]))
    diff = np.max(np.abs(got[fin] - ref[fin]))
    return float(diff / scale) if scale > 0 else (0.0 if diff == 0 else np.inf)


def assert_close(got, ref, rtol: float = RTOL_OP, what: str = "") -> None:
    """Assert :func:`rel_diff` (got, ref) <= rtol, naming ``what`` and the measured difference."""
    d = rel_diff(got, ref)
    assert d <= rtol, f"{what or 'arrays'}: relative difference {d:.2e} > {rtol:.0e}"
