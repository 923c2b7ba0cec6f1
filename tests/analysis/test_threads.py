"""Realization chunks in threads (``run_case(threads=k)``, ``linecheck run --jobs``): the same bits
as one thread, failures and cancellation reach the caller, memory decides how many run at once.

The reference is the one-thread run of the same realizations, which the rest of the suite checks
against independent solvers.  Threads are used only with the compiled step loop (the numpy loop
holds the GIL between its small calls), so the threaded tests need Numba (``linecheck[fast]``,
part of the test extra).
"""

from __future__ import annotations

import dataclasses
import json
import threading

import numpy as np
import pytest

from linecheck import service
from linecheck.analysis import run as run_module
from linecheck.core import budget, kernel
from linecheck.core.case import load_case
from linecheck.core.errors import Cancelled

from ..conftest import CASES

needs_kernel = pytest.mark.skipif(not kernel.available(), reason="Numba (linecheck[fast]) not installed")

STATS = ("peak_dynamic", "peak_quasi_static", "GF_Dy", "GF_QS", "Cont_R", "rms_resonant")


def _short(path, **analysis):
    case = load_case(path)
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


def _threads_of(monkeypatch, name: str) -> list[str]:
    """Record the thread that calls ``<name>`` in a run (:mod:`linecheck.analysis.run`, where the
    run looks it up) each time (so a test knows where it ran)."""
    names: list[str] = []
    real = getattr(run_module, name)

    def spy(*a, **kw):
        names.append(threading.current_thread().name)
        return real(*a, **kw)

    monkeypatch.setattr(run_module, name, spy)
    return names


def _same(a, b) -> bool:
    return (np.array_equal(a.background, b.background) and np.array_equal(a.resonant, b.resonant)
            and np.array_equal(a.realizations, b.realizations)
            and all(np.array_equal(getattr(a.stats, f), getattr(b.stats, f), equal_nan=True) for f in STATS))


@pytest.mark.numerics  # bitwise determinism: CI repeats it under another BLAS core type
@needs_kernel
@pytest.mark.parametrize("name, reals", [("paper/case09-six", 5), ("paper/case05-six", 3)])
def test_threads_give_the_bits_of_one_thread(monkeypatch, name, reals):
    """Synoptic (quasi-steady damping: the structural-damping remainder) and downburst (250 mean
    states): two threads, chunks of ceil(n/2) realizations, against one thread, one chunk."""
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    extra = {"damping": "quasi-steady", "duration": 60.0, "burn_in": 10.0} if "09" in name else {}
    case = _short(CASES / f"{name}.toml", **extra)
    names = _threads_of(monkeypatch, "integrate")  # one call per chunk
    one = service.run_case(case, realizations=list(range(reals)), spectral_check=False)
    assert names == ["MainThread"]
    names.clear()
    two = service.run_case(case, realizations=list(range(reals)), spectral_check=False, threads=2)
    assert len(names) == 2 and all(n.startswith("linecheck-chunk") for n in names)
    assert _same(one, two)
    assert np.abs(two.resonant).max() > 0


@needs_kernel
def test_a_failed_chunk_raises_its_own_error_and_stops_the_others(monkeypatch):
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    case = _short(CASES / "paper" / "case09-six.toml", duration=30.0, burn_in=5.0)
    real = run_module.integrate
    calls: list[int] = []

    def failing(models, damping, state_of_step, loads, *a, **kw):
        calls.append(loads.shape[1])
        if loads.shape[1] == 1:  # the last chunk (realization 4 of 0..4 in chunks of 2)
            raise ValueError("boom in chunk 3")
        return real(models, damping, state_of_step, loads, *a, **kw)

    monkeypatch.setattr(run_module, "integrate", failing)
    monkeypatch.setattr(budget, "realization_chunk", lambda case, n, threads=1: 2)  # chunks [0, 1], [2, 3], [4]
    with pytest.raises(ValueError, match="boom in chunk 3"):
        service.run_case(case, realizations=[0, 1, 2, 3, 4], spectral_check=False, threads=2)
    assert 1 in calls


@needs_kernel
def test_cancel_during_a_threaded_run(monkeypatch):
    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    case = _short(CASES / "paper" / "case09-six.toml", duration=60.0, burn_in=5.0)
    cancel = threading.Event()

    def progress(stage, done, total):
        if stage.startswith("steps") and done > 0:
            cancel.set()

    with pytest.raises(Cancelled):
        service.run_case(case, realizations=[0, 1, 2, 3], spectral_check=False, threads=2, progress=progress,
                         cancel=cancel)


def test_threads_fit_the_memory_limit(monkeypatch):
    """Each thread holds its own chunk: where two chunks would exceed the limit, one thread runs."""
    case = load_case(CASES / "paper" / "case09-six.toml")
    one = budget.estimate(case, "run", realizations=10, threads=1).memory
    two = budget.estimate(case, "run", realizations=10, threads=2).memory
    assert two >= one  # ten realizations fit one chunk; two threads hold two chunks of five: the same
    monkeypatch.setattr(budget, "RUN_CHUNK_BYTES", 1.0)  # one realization per chunk
    one = budget.estimate(case, "run", realizations=10, threads=1).memory
    two = budget.estimate(case, "run", realizations=10, threads=2).memory
    assert two > one
    monkeypatch.setattr(budget, "memory_limit", lambda: ((one + two) / 2, "test"))
    assert service.run_threads(case, 10, 2) == 1
    monkeypatch.setattr(budget, "memory_limit", lambda: (2 * two, "test"))
    assert service.run_threads(case, 10, 2) == 2
    assert service.run_threads(case, 1, 8) == 1  # never more threads than realizations


@needs_kernel
def test_cli_run_jobs_same_json(tmp_path, monkeypatch):
    """``linecheck run --jobs 1`` and ``--jobs 2`` write the same JSON (bar the timings)."""
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    src = (CASES / "paper" / "case09-six.toml").read_text()
    path = tmp_path / "short.toml"
    path.write_text(src.replace("duration = 600.0", "duration = 30.0\nburn_in = 5.0", 1))
    out = {}
    for jobs in (1, 2):
        res = CliRunner().invoke(app, ["run", str(path), "-n", "3", "--no-check", "--jobs", str(jobs),
                                       "--json", str(tmp_path / f"j{jobs}.json")])
        assert res.exit_code == 0, res.output
        doc = json.loads((tmp_path / f"j{jobs}.json").read_text())
        out[jobs] = {k: v for k, v in doc.items() if k not in ("timing", "created", "elapsed")}
    assert out[1] == out[2]


@pytest.mark.numerics  # bitwise determinism: CI repeats it under another BLAS core type
@needs_kernel
def test_the_check_runs_beside_the_chunks_with_the_same_result(monkeypatch):
    """With threads the frequency-domain check runs on a thread of its own while the chunks
    integrate; its estimate is the one-thread estimate, and the interpreter's switch interval
    (shortened meanwhile) is restored afterwards."""
    import sys

    monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    case = _short(CASES / "paper" / "case09-six.toml", duration=30.0, burn_in=5.0)
    where = _threads_of(monkeypatch, "spectral_analysis")
    before = sys.getswitchinterval()
    one = service.run_case(case, realizations=[0, 1])
    two = service.run_case(case, realizations=[0, 1], threads=2)
    assert where[0] == "MainThread" and where[1].startswith("linecheck-check")
    assert sys.getswitchinterval() == before
    for f in ("peak_dynamic", "rms_fluctuating", "GF_Dy"):
        assert np.array_equal(getattr(one.spectral.exact, f), getattr(two.spectral.exact, f), equal_nan=True)
    assert _same(one, two)
