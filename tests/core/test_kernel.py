"""The optional compiled kernel (``linecheck[fast]``, Numba) agrees with the numpy code.

The reference is the numpy/LAPACK path itself (``LINECHECK_KERNEL=numpy``), which the rest of
the suite verifies against independent solvers; every compiled piece must agree with it within
the tolerances of :mod:`tests.tolerance` (one operation: RTOL_OP; a whole run: RTOL_RUN) on
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
from linecheck.core.case import load_case
from linecheck.core.model import BANDWIDTH
from linecheck.core.pieces import kernel  # with every piece's load check registered

from ..conftest import CASES
from ..tolerance import RTOL_OP, RTOL_RUN, RTOL_SOLVE, assert_close

pytestmark = pytest.mark.numerics

needs_kernel = pytest.mark.skipif(not kernel.installed(), reason="Numba (linecheck[fast]) not installed")


@pytest.fixture(autouse=True)
def _kernel_asked_for(monkeypatch):
    """Every test here starts with the kernel asked for (also when the suite runs under
    LINECHECK_KERNEL=numpy), so a test comparing the two forms never compares numpy with itself;
    a test that wants the numpy form sets it."""
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")


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
def test_banded_solve_agrees_with_lapack_dpbtrs(m):
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
    for q in range(m):  # each column on its own scale (the right-hand sides span twelve decades)
        assert_close(got[:, q], ref[:, q], RTOL_OP, f"column {q}")
    # and the solution is a solution (the comparison above is not against garbage)
    A = np.diag(ab[kd])
    for off in range(1, kd + 1):
        A += np.diag(ab[kd - off, off:], off) + np.diag(ab[kd - off, off:], -off)
    np.testing.assert_allclose(A @ got, B, rtol=1e-12, atol=1e-12 * np.abs(B).max())


@needs_kernel
@pytest.mark.parametrize("n", [3, 6, 47])
def test_one_vector_solve_agrees_with_lapack_dpbtrs(n):
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
        assert info == 0
        assert_close(got, ref, RTOL_OP, f"scale {scale:g}")


@needs_kernel
def test_structural_damping_remainder_by_diagonals_is_the_csr_product():
    """The compiled C~_off w by diagonals (``rest_product``) against scipy's CSR product of the
    same stepper's remainder (the numpy loop's ``csr_matvecs``), within RTOL_OP, for one vector and
    four lanes; and the diagonals hold exactly the CSR arrays' entries (zeros elsewhere)."""
    from linecheck.core import _loops
    from linecheck.core.dynamics import Newmark, _Stepper

    case = _short(CASES / "paper" / "case09-six.toml", damping="quasi-steady")
    st = service.static_result(case)
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
        assert_close(t.T, ref, RTOL_OP, f"{L} lanes")
        assert np.abs(ref).max() > 0


@needs_kernel
@pytest.mark.parametrize("name", ["case05-six", "case07-six"])
def test_downburst_field_agrees(monkeypatch, name):
    """The analytic downburst field compiled (kernel.field_velocity) against its numpy form on a
    paper case's record grid and line points, within RTOL_OP; the field is really evaluated (the
    outflow passes the line) and the compiled form really ran."""
    from linecheck.core.wind import mean as wm

    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    case = load_case(CASES / "paper" / f"{name}.toml")
    field = wm.downburst_field(case)
    st = service.static_result(case)
    x = np.unique(np.concatenate([wm.span_node_x(st.system).ravel(), st.system.node_x0]))
    t = service.record_time(case)
    got = kernel.field_velocity(field, x, t, float(wm.vertical_profile(field.height, field.delta)),
                                wm.intensity(t, field.t1, field.t_f))
    ref = field.velocity_numpy(x, t)
    assert got is not None
    for a, b in zip(got, ref):
        assert_close(a, b, RTOL_OP, "field velocity")
    assert np.hypot(*ref).max() > 0.9 * case.wind.v_ref


@needs_kernel
@pytest.mark.parametrize("path", ["paper/case09-six.toml", "examples/section-12span.toml"])
def test_frequency_domain_check_agrees(monkeypatch, path):
    """The frequency-domain check with the compiled coherence quadrature (kernel.quad_kms)
    against the numpy one: every statistic and spectrum of estimate 1 within RTOL_OP, on equal
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
            assert_close(a, b, RTOL_OP, fld.name)
    assert np.all(fast.rms_fluctuating > 0)


@needs_kernel
@pytest.mark.parametrize("reals", [[3], [0, 1, 2, 3, 4]])
def test_synoptic_with_structural_damping_agrees(monkeypatch, reals):
    """Quasi-steady damping with structural damping: the inter-node remainder C~_off is used
    (one realization: the single-vector kernel; five: two groups of four lanes, padded)."""
    case = _short(CASES / "paper" / "case09-six.toml", damping="quasi-steady", duration=60.0, burn_in=10.0)
    assert case.analysis.structural_ratio > 0
    fast, slow = _both(monkeypatch, case, realizations=reals)
    assert_close(fast.resonant, slow.resonant, RTOL_RUN, "resonant")
    assert_close(fast.background, slow.background, RTOL_RUN, "background")
    assert np.abs(fast.resonant).max() > 0


@needs_kernel
def test_downburst_one_realization_agrees(monkeypatch):
    case = _short(CASES / "paper" / "case05-six.toml")
    fast, slow = _both(monkeypatch, case, realizations=[2])
    assert_close(fast.resonant, slow.resonant, RTOL_RUN, "resonant")
    assert_close(fast.background, slow.background, RTOL_RUN, "background")


@needs_kernel
def test_section_second_order_agrees(monkeypatch):
    """A 12-span section (load directions along the span normals) with second-order tension."""
    case = _short(CASES / "examples" / "section-12span.toml", duration=60.0, tension="second-order")
    got, fps = [], []
    loop_on = kernel.use("second_order_loop")
    passes, dgemm = kernel.second_order_passes, kernel.second_order_dgemm
    monkeypatch.setattr(kernel, "second_order_passes", lambda: got.append(passes()) or got[-1])
    monkeypatch.setattr(kernel, "second_order_dgemm", lambda: fps.append(dgemm()) or fps[-1])
    fast, slow = _both(monkeypatch, case, realizations=[0, 1])
    n_compiled = sum(p is not None for p in got)
    assert n_compiled > 0 and n_compiled < len(got)  # the compiled passes ran in the first run only
    assert fps and all(fp is not None for fp in fps) == loop_on  # and the block loop
    assert_close(fast.resonant, slow.resonant, RTOL_RUN, "resonant")
    assert_close(fast.background, slow.background, RTOL_RUN, "background")


@needs_kernel
def test_second_order_passes_agree():
    """The compiled second-order passes (rotation out of the node bases, insulator frames, the
    products P) and the compiled block loop with scipy's dgemm agree with the numpy passes within
    RTOL_OP on case09-six's operator (RTOL_SOLVE through the band solve of loads): the Newmark history in node bases, global displacements,
    and the quasi-static displacements of loads, with a padded last block and rows of zeros, all
    reactions and a tower's three."""
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
    gemm = kernel.second_order_dgemm()  # scipy's dgemm: the whole block loop compiled too
    assert gemm is not None
    L = rng.standard_normal((700, n_dof // 3)) * 50.0
    L[[0, 300]] = 0.0
    c = lapack.dpbtrf(model.K_band, lower=0)[0]
    dirs = rng.standard_normal((n_dof // 3, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    for fp in (None, gemm) if gemm is not None else (None,):
        for t in (T, None):
            ref = second_order_reactions(op, U, t, passes=None, dgemm=None)
            got = second_order_reactions(op, U, t, passes=fns, dgemm=fp)
            assert_close(got, ref, RTOL_OP, "history")
            # the compiled Newmark loop's dof-major history (a column block of it, as dynamics passes)
            H = np.zeros((n_dof, U.shape[0] + 40))
            H[:, 20:-20] = U.T
            got = second_order_reactions(op, H[:, 20:-20], t, transposed=True, passes=fns, dgemm=fp)
            assert_close(got, ref, RTOL_OP, "dof-major history")
            assert_close(second_order_reactions(op, H[:, 20:-20], t, transposed=True, passes=None, dgemm=None),
                         ref, RTOL_OP, "dof-major history, numpy")
        for d in (None, dirs):
            ref = second_order_of_loads(op, L, c, d, passes=None, dgemm=None)
            got = second_order_of_loads(op, L, c, d, passes=fns, dgemm=fp)
            assert_close(got, ref, RTOL_SOLVE, "of loads")
            assert np.abs(ref).max() > 0.0
        # a tower of interest's three columns (a scan): other chunk and block sizes
        op3 = dataclasses.replace(op, A=np.ascontiguousarray(op.A[:, 9:12]), W=np.ascontiguousarray(op.W[:, 9:12]))
        ref = second_order_reactions(op3, U, T, passes=None, dgemm=None)
        assert_close(second_order_reactions(op3, U, T, passes=fns, dgemm=fp), ref, RTOL_OP, "a tower's three")
        ref = second_order_of_loads(op3, L, c, dirs, passes=None, dgemm=None)
        assert_close(second_order_of_loads(op3, L, c, dirs, passes=fns, dgemm=fp), ref, RTOL_SOLVE, "a tower's three")


@needs_kernel
def test_long_line_background_solves_agree(monkeypatch):
    """Above BACKGROUND_SOLVE_DOF step 3 solves the banded stiffness per step (kernel: four
    steps' right-hand sides at a time)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    from bench_core import case_with, line_with_spans

    case = line_with_spans(case_with("case09-six", realizations=1), 24)
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, duration=30.0, burn_in=5.0))
    used = []
    bg = kernel.background
    monkeypatch.setattr(kernel, "background", lambda *a: used.append(1) or bg(*a))
    fast, slow = _both(monkeypatch, case)
    assert used  # the fused step-3 kernel ran
    assert_close(fast.resonant, slow.resonant, RTOL_RUN, "resonant")
    assert_close(fast.background, slow.background, RTOL_RUN, "background")


def test_numpy_mode_never_loads_the_kernel(monkeypatch):
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    monkeypatch.setattr(kernel, "_pieces", {})
    assert not kernel.use("newmark")
    assert not kernel.available()
    assert not kernel.loaded()
    assert all(not p.on and p.reason == "LINECHECK_KERNEL=numpy" for p in kernel.status())


@needs_kernel
def test_every_piece_is_on_here_and_the_choice_does_not_depend_on_the_work(monkeypatch):
    """With Numba installed every piece passes its load check on this machine (whatever
    OPENBLAS_CORETYPE the suite runs under), and whether a piece runs depends on the
    installation only: the first call loads the kernel whatever the size of the job, so two runs
    of one case take the same path in any process."""
    monkeypatch.setenv("LINECHECK_KERNEL", "auto")
    monkeypatch.setattr(kernel, "_pieces", {})
    assert not kernel.loaded()
    assert kernel.use("rotate")  # a call with no work to speak of loads it
    assert kernel.loaded()
    off = [f"{p.name}: {p.reason}" for p in kernel.status() if not p.on]
    assert not off, off
    assert [p.name for p in kernel.status()] == list(kernel.PIECES)


@needs_kernel
def test_a_piece_that_fails_its_check_falls_back_alone(monkeypatch):
    """A piece whose compiled form differs from numpy beyond RTOL is switched off by itself, with
    the measured difference as the reason; the other pieces stay on and a run still agrees."""
    monkeypatch.setenv("LINECHECK_KERNEL", "auto")
    monkeypatch.setattr(kernel, "_pieces", {})
    monkeypatch.setitem(kernel._checks, "newmark", lambda fns: 6e-10)  # the check dynamics registered
    states = {p.name: p for p in kernel.status()}
    assert not states["newmark"].on
    assert states["newmark"].reason == "load check: differs from numpy by 6.0e-10 of the largest value (allowed 1e-12)"
    assert all(p.on for n, p in states.items() if n != "newmark")
    case = _short(CASES / "paper" / "case09-single.toml", duration=20.0, burn_in=5.0)
    res = service.run_case(case, realizations=[0], spectral_check=False)
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    ref = service.run_case(case, realizations=[0], spectral_check=False)
    assert_close(res.resonant, ref.resonant, RTOL_RUN, "resonant")
    assert np.abs(res.resonant).max() > 0


@needs_kernel
def test_change_of_node_bases_agrees():
    """kernel.rotate (compiled where verified at load) against st_rotate on random bases."""
    from types import SimpleNamespace

    from linecheck.core.dynamics import st_rotate

    rng = np.random.default_rng(5)
    To, Tn = (np.linalg.qr(rng.standard_normal((59, 3, 3)))[0] for _ in range(2))
    X = rng.standard_normal((10, 177))
    for old in (None, SimpleNamespace(T=To)):
        got = kernel.rotate(X, old, SimpleNamespace(T=Tn))
        assert_close(got, st_rotate(X, old, SimpleNamespace(T=Tn)), RTOL_OP, "rotation")
    # a rotation: lengths per node kept
    back = kernel.rotate(X, None, SimpleNamespace(T=Tn))
    np.testing.assert_allclose(np.linalg.norm(back.reshape(10, 59, 3), axis=2),
                               np.linalg.norm(X.reshape(10, 59, 3), axis=2), rtol=1e-14)


@needs_kernel
def test_static_transfer_rows_agree():
    """kernel.rowdot (step 3's static transfer, compiled where verified at load) against rowdot_numpy."""
    from linecheck.core.dynamics import rowdot_numpy

    rng = np.random.default_rng(6)
    X, BT = rng.standard_normal((250, 59)), rng.standard_normal((59, 21))
    got = kernel.rowdot(X, BT)
    assert_close(got, rowdot_numpy(X, BT), RTOL_OP, "rowdot")
    np.testing.assert_allclose(got, X @ BT, rtol=1e-12, atol=1e-12 * np.abs(X @ BT).max())


@needs_kernel
@pytest.mark.parametrize("tension", ["linear", "second-order"])
def test_section_banded_background_agrees(monkeypatch, tension):
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
    assert_close(fast.background, slow.background, RTOL_RUN, "background")
    assert_close(fast.resonant, slow.resonant, RTOL_RUN, "resonant")
    assert np.abs(fast.background).max() > 0


def test_a_numba_that_fails_falls_back_to_numpy(monkeypatch):
    """A Numba that cannot compile (or cache) here leaves the numpy loop, not an error."""
    def broken():
        raise RuntimeError("no locator available for the cache")

    import builtins

    real_import = builtins.__import__

    def no_loops(name, globals=None, locals=None, fromlist=(), level=0):
        if fromlist and "_loops" in fromlist and level == 1:
            broken()
        return real_import(name, globals, locals, fromlist, level)

    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    monkeypatch.setattr(kernel, "_pieces", {})
    monkeypatch.setattr(builtins, "__import__", no_loops)
    assert not kernel.available()
    monkeypatch.setattr(builtins, "__import__", real_import)
    assert not kernel.use("newmark")
    assert all(p.reason == "Numba failed to load: RuntimeError: no locator available for the cache"
               for p in kernel.status())
    case = _short(CASES / "paper" / "case09-single.toml", duration=20.0, burn_in=5.0)
    res = service.run_case(case, realizations=[0], spectral_check=False)
    assert np.all(np.isfinite(res.resonant)) and np.abs(res.resonant).max() > 0


_CACHE_PROBE = r'''
import dataclasses, os
from linecheck import service
from linecheck.core.pieces import kernel  # with every piece's load check registered
from linecheck.core.case import load_case
case = load_case(os.environ["PROBE_CASE"])
case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, duration=4.0, burn_in=1.0))
for n in (1, 5):  # steps_1 and the four-lane steps
    service.run_case(case, realizations=list(range(n)), spectral_check=False)
fns = kernel._fns
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
def test_wind_spectrum_agrees(monkeypatch, name):
    """The synthesis' phasors, coherence recursion and scaling compiled in one pass
    (kernel.coherent_spectrum) against the numpy form: the unit turbulence within RTOL_OP; equal spans (the KMS recursion) and a section of unequal spans (Markov, a
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
    assert_close(fast, slow, RTOL_OP, "unit turbulence")
    assert 0.5 < float(fast.std()) < 1.5  # a unit-variance field (200 s of it): not a comparison of zeros


@needs_kernel
@pytest.mark.parametrize("name, drag", [("paper/case09-six", "linear"), ("paper/case05-six", "quadratic")])
def test_drag_loads_agree(monkeypatch, name, drag):
    """The fluctuating drag on the free nodes (paper Eq. 5, and the quadratic drag's v² term)
    compiled in one pass (kernel.drag_loads) against the numpy loop."""
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
    assert_close(fast, slow, RTOL_OP, "loads")
    assert_close(fast_d, slow_d, RTOL_OP, "direct loads")
    assert np.abs(fast).max() > 0


@needs_kernel
@pytest.mark.parametrize("name", ["paper/case05-six", "paper/case09-single", "examples/downburst-ring-jet", "examples/downburst-user-field"])
def test_step1_span_tension_agrees(monkeypatch, name):
    """Step 1's span-tension Newton (static._Spans.tension) with its integrands compiled
    (kernel.span_terms) against the numpy form: every mean state's tensions,
    displacements and reactions within RTOL_OP (a downburst's 250 states at once, a synoptic
    state; sections solve their spans by :mod:`linecheck.core.catenary` instead)."""
    case = load_case(CASES / f"{name}.toml")
    calls = []
    fn = kernel.span_compiled  # the compiled form's call
    monkeypatch.setattr(kernel, "span_compiled", lambda *a, **k: calls.append(1) or fn(*a, **k))
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    fast = service.static_analysis(case).mean
    n_fast = len(calls)
    monkeypatch.setenv("LINECHECK_KERNEL", "numpy")
    slow = service.static_analysis(case).mean
    assert n_fast > 0 and len(calls) == n_fast  # compiled in the first, numpy in the second
    assert fast.tension.shape[0] == (case.analysis.mean_states if case.wind.type == "downburst" else 1)
    for f in ("tension", "displacement", "reactions", "insulator_force", "nodes", "element_tension"):
        assert_close(getattr(fast, f), getattr(slow, f), RTOL_OP, f)


@needs_kernel
@pytest.mark.parametrize("name, window", [("paper/case05-six", None), ("paper/case09-six", None),
                                          ("paper/case09-six", 60.0)])
def test_statistics_reductions_agree(monkeypatch, name, window):
    """The statistics' r.m.s. values and peaks over time in one compiled pass
    (kernel.history_reductions) against the numpy form, through whole runs: every statistic of
    every realization and tower within RTOL_RUN (with peak windows: one mean per sample)."""
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
        if isinstance(a, np.ndarray):
            assert_close(a, b, RTOL_RUN, f.name)
        else:
            assert a == b, f.name
    assert fast.n_samples == (3 if window is None else 3 * 2)
    assert np.all(fast.peak_dynamic > 0)
