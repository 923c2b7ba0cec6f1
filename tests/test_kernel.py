"""The optional compiled step loop (issue 20, ``linecheck[fast]``, Numba) gives the numpy loop's bits.

The reference is the numpy/LAPACK path itself (``LINECHECK_KERNEL=numpy``), which the rest of
the suite verifies against independent solvers; the kernel must reproduce it bit for bit on
every kind of run it serves: a synoptic line with quasi-steady (structural) damping, a
downburst (one operator per mean state), a section (load directions along the span normals)
with second-order tension, several realizations (lanes in groups of four, padded), and a long
line's banded background solves.  Without Numba installed these tests are skipped; the numpy
path runs in every other test.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.linalg import lapack

from linecheck import service
from linecheck.core import kernel
from linecheck.core.case import load_case
from linecheck.core.model import BANDWIDTH

from .conftest import CASES

needs_kernel = pytest.mark.skipif(not kernel.available(), reason="Numba (linecheck[fast]) not installed")


def _short(path, **analysis):
    case = load_case(path)
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


def _both(monkeypatch, case, **kw):
    """The run with the kernel forced on, then with the numpy loop; the kernel's step loop must
    really have run the first (and not the second), or the comparison would prove nothing."""
    calls = []
    block = kernel.newmark_block
    monkeypatch.setattr(kernel, "newmark_block", lambda *a: calls.append(1) or block(*a))
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    fast = service.run_case(case, spectral_check=False, **kw)
    n_fast = len(calls)
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    slow = service.run_case(case, spectral_check=False, **kw)
    assert n_fast > 0 and len(calls) == n_fast
    return fast, slow


@needs_kernel
@pytest.mark.parametrize("m", [1, 3, 4, 9])
def test_banded_solve_is_lapack_dpbtrs_bit_for_bit(m):
    """Random banded SPD systems (the core's band width, 47 unknowns) against dpbtrs itself."""
    rng = np.random.default_rng(m)
    n, kd = 47, BANDWIDTH
    ab = np.zeros((kd + 1, n))
    for off in range(1, kd + 1):
        ab[kd - off, off:] = rng.uniform(-1.0, 1.0, n - off)
    ab[kd] = 2.0 * kd + rng.uniform(0.0, 1.0, n)  # diagonally dominant: SPD
    c, info = lapack.dpbtrf(ab, lower=0)
    assert info == 0
    B = np.asfortranarray(rng.standard_normal((n, m)) * 10.0 ** rng.integers(-6, 6, m))
    ref, info = lapack.dpbtrs(c, B, lower=0)
    got = kernel.solve_columns(c, B.copy(order="F"))
    assert np.array_equal(got, ref)
    # and the solution is a solution (the comparison above is not against garbage)
    A = np.diag(ab[kd])
    for off in range(1, kd + 1):
        A += np.diag(ab[kd - off, off:], off) + np.diag(ab[kd - off, off:], -off)
    np.testing.assert_allclose(A @ got, B, rtol=1e-12, atol=1e-12 * np.abs(B).max())


@needs_kernel
@pytest.mark.parametrize("n", [3, 6, 47])
def test_one_vector_solve_is_lapack_dpbtrs_bit_for_bit(n):
    """The one-realization solve (the five unknowns a row reads held in registers from row 5 on;
    shorter systems take the general loop) against dpbtrs itself, right-hand sides over twelve
    decades."""
    from linecheck.core import _loops

    rng = np.random.default_rng(n)
    kd = BANDWIDTH
    ab = np.zeros((kd + 1, n))
    for off in range(1, kd + 1):
        ab[kd - off, off:] = rng.uniform(-1.0, 1.0, max(n - off, 0))
    ab[kd] = 2.0 * kd + rng.uniform(0.0, 1.0, n)
    c, info = lapack.dpbtrf(ab, lower=0)
    assert info == 0
    for scale in 10.0 ** np.arange(-6, 7, 3):
        b = rng.standard_normal(n) * scale
        ref, info = lapack.dpbtrs(c, b, lower=0)
        got = b.copy()
        _loops.band_solve_1(c, got)
        assert info == 0 and np.array_equal(got, ref)


@needs_kernel
def test_structural_damping_remainder_by_diagonals_is_the_csr_product():
    """The compiled C~_off w by diagonals (``rest_product``) against scipy's CSR product of the
    same stepper's remainder (the numpy loop's ``csr_matvecs``), bit for bit, for one vector and
    four lanes; and the diagonals hold exactly the CSR arrays' entries (zeros elsewhere)."""
    from linecheck.core import _loops
    from linecheck.core.dynamics import _Stepper, Newmark

    case = _short(CASES / "paper" / "case09-six.toml", damping="quasi-steady")
    st = service._static_analysis(case)
    model = service.build_model(st.system, st.mean.state(0))
    damping = service.damping_matrices(case, st, [model])[0]
    stepper = _Stepper.build(model, damping, Newmark(case.analysis.time_step))
    rest = stepper.rest
    assert rest is not None and rest.data.size > 0
    band = rest.band
    rows = np.repeat(np.arange(rest.shape[0]), np.diff(rest.indptr))
    bare = np.zeros_like(band)  # the diagonals rebuilt from the CSR arrays
    bare[rest.indices - rows + BANDWIDTH, rows] = rest.data
    assert np.array_equal(bare, band)
    rng = np.random.default_rng(7)
    n = rest.shape[0]
    for L in (1, 4):
        W = rng.standard_normal((L, n)) * 1e-3
        W[:, ::7] = 0.0  # rows of zeros as at the start of a record
        t = np.empty((L, n))
        _loops.rest_product(band, np.pad(W, ((0, 0), (BANDWIDTH, BANDWIDTH))), t)
        ref = rest.tocsr() @ W.T
        assert np.array_equal(t.T, ref) and np.array_equal(np.signbit(t.T), np.signbit(ref))
        assert np.abs(ref).max() > 0


@needs_kernel
@pytest.mark.parametrize("name", ["case05-six", "case07-six"])
def test_downburst_field_same_bits(monkeypatch, name):
    """The analytic downburst field compiled (kernel.field_velocity) against its numpy form on a
    paper case's record grid and line points, bit for bit; the field is really evaluated (the
    outflow passes the line) and the compiled form really ran."""
    from linecheck.core.wind import mean as wm

    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    case = load_case(CASES / "paper" / f"{name}.toml")
    field = wm.downburst_field(case)
    st = service._static_analysis(case)
    x = np.unique(np.concatenate([wm.span_node_x(st.system).ravel(), st.system.node_x0]))
    t = service.record_time(case)
    got = kernel.field_velocity(field, x, t)
    ref = field.velocity_numpy(x, t)
    assert got is not None
    assert all(np.array_equal(a, b) for a, b in zip(got, ref))
    assert np.hypot(*ref).max() > 0.9 * case.wind.v_ref


@needs_kernel
@pytest.mark.parametrize("path", ["paper/case09-six.toml", "examples/section-12span.toml"])
def test_frequency_domain_check_same_bits(monkeypatch, path):
    """The frequency-domain check with the compiled coherence quadrature (kernel.quad_kms)
    against the numpy one: every statistic and spectrum of estimate 1 bit for bit, on equal
    spans (one coherence) and on the section's unequal gaps (a coherence per gap); the compiled
    form really ran."""
    import dataclasses as dc

    from linecheck.core import spectral

    case = load_case(CASES / path)
    calls = []
    quad = kernel.quad_kms
    monkeypatch.setattr(kernel, "quad_kms", lambda *a: calls.append(1) or quad(*a))
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    fast = service.spectral_analysis(case).exact
    assert calls
    monkeypatch.setattr(spectral, "_quad_kms_nodes",
                        lambda w, rho, compiled=True, f=spectral._quad_kms_nodes: f(w, rho, compiled=False))
    slow = service.spectral_analysis(case).exact
    for fld in dc.fields(fast):
        a, b = getattr(fast, fld.name), getattr(slow, fld.name)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b, equal_nan=True), fld.name
    assert np.all(fast.rms_fluctuating > 0)


@needs_kernel
@pytest.mark.parametrize("reals", [[3], [0, 1, 2, 3, 4]])
def test_synoptic_with_structural_damping_same_bits(monkeypatch, reals):
    """Quasi-steady damping with structural damping: the inter-node remainder C~_off is used
    (one realization: the single-vector kernel; five: two groups of four lanes, padded)."""
    case = _short(CASES / "paper" / "case09-six.toml", damping="quasi-steady", duration=60.0, burn_in=10.0)
    assert case.analysis.structural_ratio > 0
    fast, slow = _both(monkeypatch, case, realizations=reals)
    assert np.array_equal(fast.resonant, slow.resonant)
    assert np.array_equal(fast.background, slow.background)
    assert np.abs(fast.resonant).max() > 0


@needs_kernel
def test_downburst_one_realization_same_bits(monkeypatch):
    case = _short(CASES / "paper" / "case05-six.toml")
    fast, slow = _both(monkeypatch, case, realizations=[2])
    assert np.array_equal(fast.resonant, slow.resonant)
    assert np.array_equal(fast.background, slow.background)


@needs_kernel
def test_section_second_order_same_bits(monkeypatch):
    """A 12-span section (load directions along the span normals) with second-order tension."""
    case = _short(CASES / "examples" / "section-12span.toml", duration=60.0, tension="second-order")
    got, fps = [], []
    passes, gemm = kernel.second_order_passes, kernel.second_order_sgemm
    monkeypatch.setattr(kernel, "second_order_passes", lambda: got.append(passes()) or got[-1])
    monkeypatch.setattr(kernel, "second_order_sgemm", lambda: fps.append(gemm()) or fps[-1])
    fast, slow = _both(monkeypatch, case, realizations=[0, 1])
    n_compiled = sum(p is not None for p in got)
    assert n_compiled > 0 and n_compiled < len(got)  # the compiled passes ran in the first run only
    assert fps and (kernel._state.get("sgemm") is None or all(fp is not None for fp in fps))  # and the block loop
    assert np.array_equal(fast.resonant, slow.resonant)
    assert np.array_equal(fast.background, slow.background)


@needs_kernel
def test_second_order_passes_same_bits():
    """The compiled second-order passes (issue 16: rotation out of the node bases, insulator
    frames, the products P) and the compiled block loop with numpy's own cblas_sgemm give the numpy
    passes' bits on case09-six's operator: the Newmark history in node bases, global
    displacements, and the quasi-static displacements of loads, with a padded last block, rows of
    zeros and negative zeros, all reactions and a tower's three."""
    from linecheck.core.second_order import second_order_of_loads, second_order_operator, second_order_reactions

    case = _short(CASES / "paper" / "case09-six.toml", tension="second-order")
    st = service.static_analysis(case)
    model = service.synoptic_model(case, st).model
    op = second_order_operator(model, st.mean.state(0))
    fns = kernel.second_order_passes()
    assert fns is not None
    rng = np.random.default_rng(16)
    n_dof = model.mass.size
    U = rng.standard_normal((1001, n_dof)) * 0.3
    U[[0, 500]] = 0.0
    U[:, 7] = -0.0
    T = np.linalg.qr(rng.standard_normal((n_dof // 3, 3, 3)))[0]
    # numpy's own wheels (scipy-openblas, 64-bit integers): the whole block loop is compiled too
    blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    gemm = kernel.second_order_sgemm()
    if blas.get("name") == "scipy-openblas" and "USE64BITINT" in str(blas.get("openblas configuration")):
        assert gemm is not None
    L = rng.standard_normal((700, n_dof // 3)) * 50.0
    L[[0, 300]] = 0.0
    c = lapack.dpbtrf(model.K_band, lower=0)[0]
    dirs = rng.standard_normal((n_dof // 3, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    for fp in (None, gemm) if gemm is not None else (None,):
        for t in (T, None):
            ref = second_order_reactions(op, U, t, passes=None, gemm=None)
            got = second_order_reactions(op, U, t, passes=fns, gemm=fp)
            assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
            # the compiled Newmark loop's dof-major history (a column block of it, as dynamics passes)
            H = np.zeros((n_dof, U.shape[0] + 40))
            H[:, 20:-20] = U.T
            got = second_order_reactions(op, H[:, 20:-20], t, transposed=True, passes=fns, gemm=fp)
            assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
            assert np.array_equal(second_order_reactions(op, H[:, 20:-20], t, transposed=True, passes=None,
                                                         gemm=None), ref)
        for d in (None, dirs):
            ref = second_order_of_loads(op, L, c, d, passes=None, gemm=None)
            got = second_order_of_loads(op, L, c, d, passes=fns, gemm=fp)
            assert np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref))
            assert np.abs(ref).max() > 0.0
        # a tower of interest's three columns (a scan): other chunk and block sizes
        op3 = dataclasses.replace(op, A=np.ascontiguousarray(op.A[:, 9:12]), W=np.ascontiguousarray(op.W[:, 9:12]))
        ref = second_order_reactions(op3, U, T, passes=None, gemm=None)
        assert np.array_equal(second_order_reactions(op3, U, T, passes=fns, gemm=fp), ref)
        ref = second_order_of_loads(op3, L, c, dirs, passes=None, gemm=None)
        assert np.array_equal(second_order_of_loads(op3, L, c, dirs, passes=fns, gemm=fp), ref)


@needs_kernel
def test_long_line_background_solves_same_bits(monkeypatch):
    """Above BACKGROUND_SOLVE_DOF step 3 solves the banded stiffness per step (kernel: four
    steps' right-hand sides at a time)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
    from bench_core import case_with, line_with_spans

    case = line_with_spans(case_with("case09-six", realizations=1), 24)
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, duration=30.0, burn_in=5.0))
    used = []
    bg = kernel.background
    monkeypatch.setattr(kernel, "background", lambda *a: used.append(1) or bg(*a))
    fast, slow = _both(monkeypatch, case)
    assert used  # the fused step-3 kernel ran
    assert np.array_equal(fast.resonant, slow.resonant)
    assert np.array_equal(fast.background, slow.background)


def test_numpy_mode_never_loads_the_kernel(monkeypatch):
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    assert not kernel.use(1e12)
    assert not kernel.available()


def test_small_work_keeps_the_numpy_loop_until_loaded(monkeypatch):
    """A process that has not loaded Numba does not pay ≈ 0.6 s to save less than that."""
    monkeypatch.setenv("LINECHECK_KERNEL", "auto")
    monkeypatch.setattr(kernel, "_state", {})
    assert not kernel.use(kernel.LOAD_WORK / 10)
    assert "ok" not in kernel._state


@needs_kernel
def test_change_of_node_bases_same_bits():
    """kernel.rotate (compiled where verified at load) against st_rotate on random bases."""
    from types import SimpleNamespace

    from linecheck.core.dynamics import st_rotate

    rng = np.random.default_rng(5)
    To, Tn = (np.linalg.qr(rng.standard_normal((59, 3, 3)))[0] for _ in range(2))
    X = rng.standard_normal((10, 177))
    for old in (None, SimpleNamespace(T=To)):
        got = kernel.rotate(X, old, SimpleNamespace(T=Tn))
        assert np.array_equal(got, st_rotate(X, old, SimpleNamespace(T=Tn)))
    # a rotation: lengths per node kept
    back = kernel.rotate(X, None, SimpleNamespace(T=Tn))
    np.testing.assert_allclose(np.linalg.norm(back.reshape(10, 59, 3), axis=2),
                               np.linalg.norm(X.reshape(10, 59, 3), axis=2), rtol=1e-14)


@needs_kernel
def test_static_transfer_rows_same_bits():
    """kernel.rowdot (step 3's static transfer, compiled where verified at load) against _rowdot."""
    from linecheck.core.dynamics import _rowdot

    rng = np.random.default_rng(6)
    X, BT = rng.standard_normal((250, 59)), rng.standard_normal((59, 21))
    got = kernel.rowdot(X, BT)
    assert np.array_equal(got, _rowdot(X, BT))
    np.testing.assert_allclose(got, X @ BT, rtol=1e-12, atol=1e-12 * np.abs(X @ BT).max())


@needs_kernel
@pytest.mark.parametrize("tension", ["linear", "second-order"])
def test_section_banded_background_same_bits(monkeypatch, tension):
    """A long line's step 3 along a section's span normals: the 12-span section forced onto the
    long-line path (banded background solves) by lowering its DOF threshold; linear tension takes
    the fused kernel, second-order tension (which needs the displacements) the compiled solves."""
    from linecheck.core import dynamics

    monkeypatch.setattr(dynamics, "BACKGROUND_SOLVE_DOF", 100)
    case = _short(CASES / "examples" / "section-12span.toml", duration=30.0, tension=tension)
    used = []
    bg = kernel.background
    monkeypatch.setattr(kernel, "background", lambda *a: used.append(1) or bg(*a))
    fast, slow = _both(monkeypatch, case, realizations=[0, 1, 2])
    assert bool(used) == (tension == "linear")  # the fused step-3 kernel ran where it should
    assert np.array_equal(fast.background, slow.background)
    assert np.array_equal(fast.resonant, slow.resonant)
    assert np.abs(fast.background).max() > 0


def test_a_numba_that_fails_falls_back_to_numpy(monkeypatch):
    """A Numba that cannot compile (or cache) here leaves the numpy loop, not an error."""
    def broken():
        raise RuntimeError("no locator available for the cache")

    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    monkeypatch.setattr(kernel, "_state", {})
    monkeypatch.setattr(kernel, "_compile", broken)
    assert not kernel.available()
    assert not kernel.use(1e12)
    case = _short(CASES / "paper" / "case09-single.toml", duration=20.0, burn_in=5.0)
    res = service.run_case(case, realizations=[0], spectral_check=False)
    assert np.all(np.isfinite(res.resonant)) and np.abs(res.resonant).max() > 0


_CACHE_PROBE = r'''
import dataclasses, os
from linecheck import service
from linecheck.core import kernel
from linecheck.core.case import load_case
case = load_case(os.environ["PROBE_CASE"])
case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, duration=4.0, burn_in=1.0))
for n in (1, 5):  # steps_1 and the four-lane steps
    service.run_case(case, realizations=list(range(n)), spectral_check=False)
fns = kernel._state["fns"]
print(sum(sum(getattr(fns, f).stats.cache_misses.values()) for f in ("steps", "steps_1", "band_solve")),
      sum(sum(getattr(fns, f).stats.cache_hits.values()) for f in ("steps", "steps_1", "band_solve")))
'''


@needs_kernel
def test_the_compiled_loops_load_from_the_disk_cache_in_a_new_process(tmp_path):
    """A second process finds the step loops in Numba's disk cache instead of compiling them
    again (they once called other jitted functions through closure cells, which gave every
    process a new cache key: ≈ 1–2 s of compilation per function and process)."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, LINECHECK_KERNEL="numba", NUMBA_CACHE_DIR=str(tmp_path),
               PROBE_CASE=str(CASES / "paper" / "case09-single.toml"))
    runs = [subprocess.run([sys.executable, "-c", _CACHE_PROBE], env=env, capture_output=True, text=True,
                           check=True).stdout.split() for _ in range(2)]
    assert int(runs[0][0]) == 3  # a fresh cache folder: compiled (and written) by the first
    assert runs[1] == ["0", "3"]  # the second loads all three from it


@needs_kernel
@pytest.mark.parametrize("name", ["paper/case09-six", "paper/case05-six", "examples/section-12span"])
def test_wind_spectrum_same_bits(monkeypatch, name):
    """The synthesis' phasors, coherence recursion and scaling compiled in one pass
    (kernel.coherent_spectrum) against the numpy form: the unit turbulence bit for bit, signs of
    zeros included; equal spans (the KMS recursion) and a section of unequal spans (Markov, a
    coefficient row per gap)."""
    from linecheck.core.system import LineSystem
    from linecheck.core.wind import turbulence as tb

    case = load_case(CASES / f"{name}.toml")
    system = LineSystem(case.line)
    calls = []
    spec = kernel.coherent_spectrum
    monkeypatch.setattr(kernel, "coherent_spectrum", lambda *a: calls.append(spec(*a)) or calls[-1])
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    fast = tb.unit_field(case, system, 4001, 0.05, 3)
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    slow = tb.unit_field(case, system, 4001, 0.05, 3)
    assert calls[0] is not None and calls[1] is None  # compiled, then the numpy form
    assert np.array_equal(fast, slow) and np.array_equal(np.signbit(fast), np.signbit(slow))
    assert 0.5 < float(fast.std()) < 1.5  # a unit-variance field (200 s of it): not a comparison of zeros


@needs_kernel
@pytest.mark.parametrize("name, drag", [("paper/case09-six", "linear"), ("paper/case05-six", "quadratic")])
def test_drag_loads_same_bits(monkeypatch, name, drag):
    """The fluctuating drag on the free nodes (paper Eq. 5, and the quadratic drag's v² term of
    issue 16) compiled in one pass (kernel.drag_loads) against the numpy loop."""
    from linecheck.core.model import build_model
    from linecheck.core.wind.turbulence import fluctuating_velocity

    case = _short(CASES / f"{name}.toml", drag=drag)
    st = service.static_analysis(case)
    system = st.system
    model = build_model(system, st.mean.state(0))
    t = service.record_time(case)[:3001]
    vn, vl = service.record_mean_wind(case, st, t)
    calls = []
    fn = kernel.drag_loads
    monkeypatch.setattr(kernel, "drag_loads", lambda *a: calls.append(fn(*a)) or calls[-1])
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    v = fluctuating_velocity(case, system, t, [0, 1, 2])
    fast, fast_d = service.fluctuating_loads(case, system, model, t, v, vn, vl)
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    slow, slow_d = service.fluctuating_loads(case, system, model, t, v, vn, vl)
    assert calls[0] is True and calls[1] is False  # compiled, then the numpy loop
    assert np.array_equal(fast, slow) and np.array_equal(fast_d, slow_d)
    assert np.abs(fast).max() > 0


@needs_kernel
@pytest.mark.parametrize("name", ["paper/case05-six", "paper/case09-single", "examples/downburst-ring-jet", "examples/downburst-user-field"])
def test_step1_span_tension_same_bits(monkeypatch, name):
    """Step 1's span-tension Newton (static._Spans.tension) with its integrands compiled
    (kernel.span_terms, issue 20) against the numpy form: every mean state's tensions,
    displacements and reactions bit for bit (a downburst's 250 states at once, a synoptic
    state; sections solve their spans by :mod:`linecheck.core.catenary` instead)."""
    case = load_case(CASES / f"{name}.toml")
    calls = []
    fn = kernel.span_terms
    monkeypatch.setattr(kernel, "span_terms", lambda *a, **k: calls.append(1) or fn(*a, **k))
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    fast = service.static_analysis(case).mean
    n_fast = len(calls)
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    slow = service.static_analysis(case).mean
    assert n_fast > 0 and len(calls) == n_fast  # compiled in the first, numpy in the second
    assert fast.tension.shape[0] == (case.analysis.mean_states if case.wind.type == "downburst" else 1)
    for f in ("tension", "displacement", "reactions", "insulator_force", "nodes", "element_tension"):
        assert np.array_equal(getattr(fast, f), getattr(slow, f)), f


@needs_kernel
@pytest.mark.parametrize("name, window", [("paper/case05-six", None), ("paper/case09-six", None),
                                          ("paper/case09-six", 60.0)])
def test_statistics_reductions_same_bits(monkeypatch, name, window):
    """The statistics' r.m.s. values and peaks over time in one compiled pass
    (kernel.history_reductions, issue 20) against the numpy form, through whole runs: every
    statistic of every realization and tower bit for bit (with peak windows: one mean per sample)."""
    from linecheck.core import results

    case = _short(CASES / f"{name}.toml", duration=120.0, peak_window=window)
    calls = []
    fn = results.history_reductions
    monkeypatch.setattr(results, "history_reductions", lambda *a: calls.append(1) or fn(*a))
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    fast = service.run_case(case, realizations=[0, 1, 2], spectral_check=False).stats
    assert not calls  # the compiled pass, not the numpy form
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    slow = service.run_case(case, realizations=[0, 1, 2], spectral_check=False).stats
    assert calls  # the numpy form
    for f in dataclasses.fields(results.Statistics):
        a, b = getattr(fast, f.name), getattr(slow, f.name)
        assert np.array_equal(a, b, equal_nan=True), f.name
    assert fast.n_samples == (3 if window is None else 3 * 2)
    assert np.all(fast.peak_dynamic > 0)


@needs_kernel
@pytest.mark.parametrize("reals, loaded", [(list(range(10)), True), ([0], False)])
def test_the_kernel_loads_before_step_1_when_the_steps_pay_for_it(monkeypatch, reals, loaded):
    """run_case decides on the compiled kernel before step 1 (issue 20), so that step 1's span
    tension and the statistics use it too: a fresh process (no kernel loaded yet) running ten
    realizations of a six-span downburst (12,001 steps x 10 x 183 DOFs > LOAD_WORK) loads it
    first; one realization (below LOAD_WORK) does not."""
    monkeypatch.setenv("LINECHECK_KERNEL", "auto")
    monkeypatch.setattr(kernel, "_state", {})
    seen = []

    class Stop(Exception):
        pass

    def step1(case, **kw):
        seen.append("ok" in kernel._state)
        raise Stop

    monkeypatch.setattr(service, "_static_analysis", step1)
    with pytest.raises(Stop):
        service.run_case(load_case(CASES / "paper" / "case05-six.toml"), realizations=reals, spectral_check=False)
    assert seen == [loaded]
