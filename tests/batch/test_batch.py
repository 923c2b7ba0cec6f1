"""Batch runs: executors, merging, bit-identity, failures, resume."""

from __future__ import annotations

import functools
import json
import logging
import operator
import re
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from linecheck import service
from linecheck.batch import (
    DEFAULT_CHUNK,
    BatchEvent,
    ProcessPool,
    SequentialExecutor,
    auto_chunk_size,
    chunk_ranges,
    make_executor,
    merge_runs,
    run_batch,
)
from linecheck.cli.app import app
from linecheck.core.case import load_case
from linecheck.core.errors import CaseError, ConvergenceError
from linecheck.core.results import STATISTICS

from ..conftest import CASES

runner = CliRunner(env={"COLUMNS": "250"})  # wide tables: messages are not folded

SHORT = ("case01-single", "case09-single", "case02-single")  # downburst Db_x, synoptic, downburst Db_y


def write_short_case(src: Path, dest_dir: Path, *, realizations: int = 3, duration: float = 30.0) -> Path:
    """A copy of a shipped case shortened for tests: ``duration``, ``realizations``."""
    text = src.read_text(encoding="utf-8")
    text = re.sub(r"(?m)^\s*(duration|realizations)\s*=.*$", "", text)
    text = text.replace("[analysis]", f"[analysis]\nduration = {duration}\nrealizations = {realizations}", 1)
    dest = dest_dir / src.name
    dest.write_text(text, encoding="utf-8")
    return dest


@pytest.fixture(scope="session")
def pool():
    """One local process pool of 2 workers shared by the tests (worker start-up is paid once)."""
    with ProcessPool(2) as p:
        yield p


@pytest.fixture
def short_cases(tmp_path: Path) -> list[Path]:
    d = tmp_path / "cases"
    d.mkdir()
    return [write_short_case(CASES / "paper" / f"{n}.toml", d) for n in SHORT]


def broken_case(folder: Path) -> Path:
    p = folder / "broken.toml"
    p.write_text("[line]\nspans = 1\n", encoding="utf-8")
    return p


def assert_same_results(a, b) -> None:
    """Bit-identical runs: every statistic and history with np.array_equal."""
    assert a.case.name == b.case.name
    assert np.array_equal(a.realizations, b.realizations)
    for s in STATISTICS:
        assert np.array_equal(a.stats.values(s), b.stats.values(s), equal_nan=True), s
    assert np.array_equal(a.background, b.background)
    assert np.array_equal(a.resonant, b.resonant)
    assert np.array_equal(a.mean, b.mean)


def results_by_name(report) -> dict:
    return {o.name: o.result for o in report.outcomes if o.result is not None}


# --------------------------------------------------------------------------- units
def test_auto_chunk_size_spreads_small_batches():
    assert auto_chunk_size(240, 2) == DEFAULT_CHUNK == 10  # the paper batch: one task per case
    assert auto_chunk_size(10, 4) == 2  # one 10-realization case on 4 workers: 5 tasks
    assert auto_chunk_size(10, 1) == 10 and auto_chunk_size(3, 8) == 1


def test_chunk_ranges_are_balanced_and_cover_all():
    assert chunk_ranges(10, 10) == [list(range(10))]
    assert chunk_ranges(3, 2) == [[0, 1], [2]]
    chunks = chunk_ranges(25, 10)
    assert [len(c) for c in chunks] == [8, 9, 8]
    assert functools.reduce(operator.iadd, chunks, []) == list(range(25))
    assert chunk_ranges(0, 4) == []


def test_merge_runs_orders_realizations_and_concatenates(short_cases):
    case = load_case(short_cases[1])  # synoptic, fast
    a = service.run_case(case, realizations=[0, 1])
    b = service.run_case(case, realizations=[2])
    m = merge_runs([b, a])  # any order in, realization order out
    assert m.realizations.tolist() == [0, 1, 2]
    assert np.array_equal(m.background[:2], a.background) and np.array_equal(m.background[2:], b.background)
    assert np.array_equal(m.stats.peak_dynamic[2:], b.stats.peak_dynamic)
    assert_same_results(m, service.run_case(case))  # one run of all realizations, bit for bit
    with pytest.raises(ValueError):
        merge_runs([a, a])
    with pytest.raises(ValueError):
        merge_runs([])


@pytest.mark.numerics  # bitwise determinism: CI repeats it under another BLAS core type
def test_any_chunking_equals_run_case_exactly(short_cases):
    """Each realization's response is computed independently of the others in its run."""
    for path in short_cases[:2]:  # downburst and synoptic
        whole = service.run_case(load_case(path))
        for size in (1, 2):
            rep = run_batch([path], keep_results=True, chunk_size=size)
            assert_same_results(rep.outcomes[0].result, whole)


def test_make_executor_choices_and_usage_errors():
    assert isinstance(make_executor(1), SequentialExecutor)
    with make_executor(2) as ex:
        assert isinstance(ex, ProcessPool) and ex.workers == 2
    with pytest.raises(CaseError, match="--jobs"):
        make_executor(0)
    with pytest.raises(CaseError, match="cannot be combined"):
        make_executor(2, "tcp://127.0.0.1:8786")
    with pytest.raises(CaseError, match="tcp://HOST:PORT"):
        make_executor(None, "localhost:8786")


def test_dask_missing_is_a_clear_case_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    with pytest.raises(CaseError, match=r"linecheck\[dask\]"):
        make_executor(None, "tcp://127.0.0.1:8786")


def test_batch_package_imports_no_ui_libraries():
    code = (
        "import sys, linecheck.batch, linecheck.batch.tasks, linecheck.batch.executors, "
        "linecheck.batch.runner, linecheck.batch.scan, linecheck.batch.merge, linecheck.batch.scheduler, "
        "linecheck.batch.plan, linecheck.batch.recovery, linecheck.batch.saving, linecheck.batch.report\n"
        "print(','.join(n for n in ('textual', 'rich', 'typer', 'distributed') if n in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


# --------------------------------------------------------------------------- bit identity
def test_process_pool_equals_sequential_exactly(short_cases, tmp_path, pool):
    kw = dict(keep_results=True, chunk_size=2)  # 3 realizations -> chunks [0, 1], [2]: merged
    seq = run_batch(short_cases, executor=SequentialExecutor(), json_dir=tmp_path / "seq", **kw)
    par = run_batch(short_cases, executor=pool, json_dir=tmp_path / "par", **kw)
    assert seq.exit_code == par.exit_code == 0
    a, b = results_by_name(seq), results_by_name(par)
    assert set(a) == set(b) == {load_case(p).name for p in short_cases}
    for name in a:
        assert_same_results(a[name], b[name])
    for p in short_cases:  # and so are the saved documents, byte for byte
        saved = (tmp_path / "seq" / f"{p.stem}.json").read_bytes()
        assert saved == (tmp_path / "par" / f"{p.stem}.json").read_bytes()
        doc = json.loads(saved)
        assert doc["case_file"] == str(p) and doc["realizations"] == 3 and len(doc["case_hash"]) == 64


def test_dask_local_cluster_equals_sequential(short_cases):
    distributed = pytest.importorskip("distributed")
    from linecheck.batch import DaskExecutor

    seq = run_batch(short_cases, keep_results=True, chunk_size=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None,
                                  silence_logs=logging.ERROR) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        with DaskExecutor(cluster.scheduler_address) as ex:  # connects like --scheduler does
            assert ex.workers == 2
            dask = run_batch(short_cases, executor=ex, keep_results=True, chunk_size=2)
    assert dask.exit_code == 0
    a, b = results_by_name(seq), results_by_name(dask)
    assert set(a) == set(b) and len(a) == len(short_cases)
    for name in a:
        assert_same_results(a[name], b[name])


# --------------------------------------------------------------------------- failures
def test_broken_case_is_reported_and_others_complete(short_cases, tmp_path):
    bad = broken_case(tmp_path)
    missing = tmp_path / "nope.toml"
    out = tmp_path / "res"
    r = runner.invoke(app, ["batch", str(short_cases[0]), str(bad), str(missing), str(short_cases[1]),
                            "--jobs", "2", "--json-dir", str(out)])
    assert r.exit_code == 1, r.output
    assert "broken" in r.output and "missing required table [wind]" in r.output
    assert "file not found" in r.output
    assert "2 case(s) failed" in r.output
    assert "batch summary" in r.output and "process pool (2 workers)" in r.output
    assert sorted(p.name for p in out.glob("*.json")) == sorted([f"{short_cases[0].stem}.json",
                                                                 f"{short_cases[1].stem}.json"])


def test_case_above_the_memory_limit_fails_alone_before_the_batch_starts(short_cases, tmp_path, monkeypatch):
    """Every task checks its own chunk, but the merged result holds every realization: a case
    whose whole run is above the memory limit is refused before any task is submitted (its
    one-line estimate, a CaseError: exit 2 on its own), and the other cases run."""
    huge_dir = tmp_path / "huge"
    huge_dir.mkdir()
    huge = write_short_case(CASES / "paper" / "case02-single.toml", huge_dir, realizations=1_000_000_000)
    ran: list[str] = []
    real = service.run_case

    def spy(case, **kw):
        ran.append(case.name)
        return real(case, **kw)

    monkeypatch.setattr(service, "run_case", spy)  # sequential: tasks run in this process
    events: list[BatchEvent] = []
    rep = run_batch([short_cases[0], huge], progress=events.append)
    by_path = {o.path: o for o in rep.outcomes}
    bad = by_path[huge]
    assert bad.status == "failed" and bad.error_kind == "CaseError", bad
    assert "run needs about" in bad.error and "--max-memory" in bad.error
    assert by_path[short_cases[0]].status == "done"
    assert set(ran) == {load_case(short_cases[0]).name}  # the huge case never ran a chunk
    assert [e.name for e in events if e.kind == "case_failed"] == [bad.name]
    assert events[-1].overall_total == 3 and events[-1].overall_done == pytest.approx(3)  # the huge one left out
    assert rep.exit_code == 1


def test_non_convergence_fails_only_its_case(short_cases, monkeypatch):
    real = service.run_case
    victim = load_case(short_cases[1]).name

    def flaky(case, **kw):
        if case.name == victim:
            raise ConvergenceError(f"{case.name}: mean state 1 did not converge (residual 1e-3)")
        return real(case, **kw)

    monkeypatch.setattr(service, "run_case", flaky)  # sequential: tasks run in this process
    rep = run_batch(short_cases)
    status = {o.name: o.status for o in rep.outcomes}
    assert status[victim] == "failed"
    assert sum(s == "done" for s in status.values()) == len(short_cases) - 1
    failed = rep.failed[0]
    assert failed.error_kind == "ConvergenceError" and "did not converge" in failed.error
    assert failed.excel_doc().to_json() == {"case": victim, "error": failed.error}
    assert rep.exit_code == 1


def test_excel_gets_results_and_errors(short_cases, tmp_path, monkeypatch):
    writer = pytest.importorskip("linecheck.excel.writer")
    seen = {}

    def fake_write(docs, path, **kw):
        seen["docs"], seen["path"], seen["kw"] = docs, Path(path), kw
        Path(path).write_bytes(b"xlsx")
        return Path(path)

    monkeypatch.setattr(writer, "write_workbook", fake_write)
    bad = broken_case(tmp_path)
    xlsx = tmp_path / "out.xlsx"
    r = runner.invoke(app, ["batch", str(short_cases[1]), str(bad), "--jobs", "1", "--excel", str(xlsx)])
    assert r.exit_code == 1, r.output
    docs = seen["docs"]
    assert docs[0].case == load_case(short_cases[1]).name and docs[0].reactions["Ry"]  # typed documents
    assert docs[1].case == "broken" and "missing required table" in docs[1].error
    assert seen["kw"]["force"] is False
    assert (tmp_path / "results" / f"{short_cases[1].stem}.json").exists()  # default: next to the workbook
    # an existing workbook without --force is a usage error before any work
    r = runner.invoke(app, ["batch", str(short_cases[1]), "--jobs", "1", "--excel", str(xlsx)])
    assert r.exit_code == 2 and "--force" in r.output


# --------------------------------------------------------------------------- resume
def test_resume_redoes_only_missing_cases(short_cases, tmp_path):
    out = tmp_path / "res"
    first = run_batch(short_cases, json_dir=out)
    assert first.exit_code == 0
    (out / f"{short_cases[1].stem}.json").unlink()  # as if interrupted before it was saved
    before = (out / f"{short_cases[0].stem}.json").read_bytes()
    again = run_batch(short_cases, json_dir=out, resume=True)
    assert [o.status for o in again.outcomes] == ["skipped", "done", "skipped"]
    assert again.outcomes[0].doc is not None and again.outcomes[0].excel_doc().case == first.outcomes[0].name
    assert (out / f"{short_cases[0].stem}.json").read_bytes() == before
    # editing a case file invalidates its saved result
    p = short_cases[2]
    p.write_text(p.read_text(encoding="utf-8") + "\n# edited\n", encoding="utf-8")
    third = run_batch(short_cases, json_dir=out, resume=True)
    assert [o.status for o in third.outcomes] == ["skipped", "skipped", "done"]


def test_cancelled_batch_keeps_finished_cases_and_resumes(short_cases, tmp_path):
    out = tmp_path / "res"
    cancel = threading.Event()
    events: list[BatchEvent] = []

    def progress(ev: BatchEvent) -> None:
        events.append(ev)
        if ev.kind == "case_done":
            cancel.set()  # Ctrl-C right after the first case is saved

    rep = run_batch(short_cases, json_dir=out, progress=progress, cancel=cancel)
    assert rep.cancelled and rep.exit_code == 130
    assert [o.status for o in rep.outcomes] == ["done", "cancelled", "cancelled"]
    assert [p.name for p in out.glob("*.json")] == [f"{short_cases[0].stem}.json"]
    kinds = [e.kind for e in events]
    assert kinds[0] == "start" and kinds[-1] == "finish" and "case_progress" in kinds
    assert events[0].overall_total == 9
    r = runner.invoke(app, ["batch", *map(str, short_cases), "--jobs", "1", "--json-dir", str(out), "--resume"])
    assert r.exit_code == 0, r.output
    assert "1 skipped" in r.output and "2 run" in r.output
    assert len(list(out.glob("*.json"))) == 3


def test_duplicate_json_names_are_a_usage_error(short_cases, tmp_path):
    other = tmp_path / "other"
    other.mkdir()
    dup = other / short_cases[0].name
    dup.write_bytes(short_cases[0].read_bytes())
    r = runner.invoke(app, ["batch", str(short_cases[0]), str(dup), "--jobs", "1", "--json-dir", str(tmp_path / "r")])
    assert r.exit_code == 2 and "same result" in r.output


def test_cli_usage_errors_exit_2(short_cases):
    assert runner.invoke(app, ["batch", str(short_cases[0]), "--jobs", "0"]).exit_code == 2
    r = runner.invoke(app, ["batch", str(short_cases[0]), "--scheduler", "nohost"])
    assert r.exit_code == 2 and "tcp://HOST:PORT" in r.output


@pytest.mark.slow
def test_paper_batch_pool_equals_sequential(tmp_path):
    """All 24 paper cases, full length and realizations: --jobs 2 equals --jobs 1 byte for byte."""
    cases = sorted((CASES / "paper").glob("*.toml"))
    r1 = runner.invoke(app, ["batch", *map(str, cases), "--jobs", "1", "--json-dir", str(tmp_path / "a")])
    r2 = runner.invoke(app, ["batch", *map(str, cases), "--jobs", "2", "--json-dir", str(tmp_path / "b")])
    assert r1.exit_code == r2.exit_code == 0
    for p in cases:
        assert (tmp_path / "a" / f"{p.stem}.json").read_bytes() == (tmp_path / "b" / f"{p.stem}.json").read_bytes()


# --------------------------------------------------------------------------- faults (killed workers)
def test_killed_worker_fails_only_the_case_it_held(short_cases, tmp_path, monkeypatch):
    """An out-of-memory kill of one pool worker (SIGKILL, here by the test hook in the worker
    running case09-single): the pool is replaced, the other cases -- running or pending --
    are re-run and saved bit for bit; only the held case fails, with a message saying so."""
    from linecheck.batch.tasks import KILL_HOOK_ENV

    victim = short_cases[1]
    monkeypatch.setenv(KILL_HOOK_ENV, victim.stem)  # inherited by the workers spawned below
    out = tmp_path / "res"
    with ProcessPool(2) as pool:
        rep = run_batch(short_cases, executor=pool, json_dir=out, chunk_size=10)
    monkeypatch.delenv(KILL_HOOK_ENV)
    assert [o.status for o in rep.outcomes] == ["done", "failed", "done"]
    err = rep.outcomes[1].error
    assert err == f"worker died (killed by signal 9, SIGKILL: out of memory?) while running {rep.outcomes[1].name}"
    assert rep.exit_code == 1
    assert sorted(p.name for p in out.glob("*.json")) == sorted(f"{p.stem}.json" for p in (short_cases[0], short_cases[2]))
    ref = run_batch([short_cases[0]], json_dir=tmp_path / "ref")  # sequential, no kill
    assert ref.exit_code == 0
    for p in short_cases[:1]:  # re-run on the new pool (or finished before the kill): the same bytes
        assert (out / f"{p.stem}.json").read_bytes() == (tmp_path / "ref" / f"{p.stem}.json").read_bytes()



def test_recovery_policy_fails_the_tasks_of_dead_workers_and_reruns_the_others():
    """The worker-recovery policy alone: a task held by a worker that died on its own fails its
    case (once per case); a task finished before the pool broke is kept; the rest run again."""
    from linecheck.batch.recovery import HeldTask, WorkerRecovery

    policy = WorkerRecovery()
    held = [HeldTask(0, 0, 101), HeldTask(1, 0, 102), HeldTask(2, 1, 102, finished=True), HeldTask(3, 1, None),
            HeldTask(4, 2, 102)]
    plan = policy.after_restart(held, {101: -9})
    assert [(t.index, why) for t, why in plan.failed] == [(0, "killed by signal 9, SIGKILL: out of memory?")]
    assert [t.index for t in plan.rerun] == [3, 4]  # case 0 failed: its task 1 is dropped; task 2 is in
    assert policy.failure("killed by signal 9", "A").message == "worker died (killed by signal 9) while running A"


def test_recovery_policy_suspects_running_tasks_when_the_dead_worker_is_unknown():
    from linecheck.batch.recovery import HeldTask, WorkerRecovery

    policy = WorkerRecovery()
    held = [HeldTask(0, 0, 101), HeldTask(1, 1, None)]
    first = policy.after_restart(held, {})
    assert first.failed == [] and [t.index for t in first.rerun] == [0, 1]
    policy.progressed()
    second = policy.after_restart([HeldTask(0, 0, 103), HeldTask(1, 1, 104)], {})
    assert [(t.index, why) for t, why in second.failed] == [(0, "ended abruptly, twice")]
    assert [t.index for t in second.rerun] == [1]  # suspected once only


def test_recovery_policy_gives_up_after_restarts_without_progress():
    from linecheck.batch.recovery import MAX_IDLE_RESTARTS, HeldTask, WorkerRecovery

    policy = WorkerRecovery()
    held = [HeldTask(0, 0, None), HeldTask(1, 1, None)]
    for _ in range(MAX_IDLE_RESTARTS):
        assert policy.after_restart(held, {999: 1}).failed == []
    plan = policy.after_restart(held, {999: 1})
    assert [why for _, why in plan.failed] == [f"ended abruptly {MAX_IDLE_RESTARTS + 1} times in a row"] * 2
    assert plan.rerun == []
    policy.progressed()  # a task finished: the count starts again
    assert policy.after_restart(held, {999: 1}).failed == []

COORDINATOR = """
import sys, time
from multiprocessing import resource_tracker
from linecheck.batch import ProcessPool

if __name__ == "__main__":
    pool = ProcessPool(2)
    busy = pool.submit(time.sleep, 3600)  # one worker busy, one idle
    pool.submit(int, 1).result()  # both workers up and running their initializer
    print(*pool._pool._processes, resource_tracker._resource_tracker._pid, flush=True)
    busy.result()
"""


@pytest.mark.skipif(not hasattr(__import__("os"), "pidfd_open"), reason="waits on Linux pidfds")
@pytest.mark.parametrize("sig", ["SIGKILL", pytest.param("SIGTERM", marks=pytest.mark.slow)])
def test_workers_exit_when_the_coordinator_dies(sig):
    """Kill the coordinating process: its pool workers (busy and idle) and the resource
    tracker exit instead of waiting forever.  Waits on process-exit events (pidfds); the
    120 s bound only stops a hang (the watchdog polls every second; PR_SET_PDEATHSIG is
    immediate), it does not decide the outcome on a slow machine."""
    import os
    import select
    import signal

    proc = subprocess.Popen([sys.executable, "-c", COORDINATOR], stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        pids = [int(x) for x in line.split()]
        assert len(pids) == 3, line  # two workers, the resource tracker
        fds = []
        for pid in pids:
            try:
                fds.append(os.pidfd_open(pid))
            except ProcessLookupError:  # pragma: no cover - already gone
                pass
        proc.send_signal(getattr(signal, sig))
        proc.wait()
        try:
            waiting = list(fds)
            while waiting:
                ready, _, _ = select.select(waiting, [], [], 120.0)
                assert ready, f"processes still alive 120 s after the coordinator died: {pids}"
                waiting = [fd for fd in waiting if fd not in ready]
        finally:
            for fd in fds:
                os.close(fd)
    finally:
        if proc.poll() is None:  # pragma: no cover
            proc.kill()
            proc.wait()


@pytest.mark.parametrize("answer", [None, b"HTTP/1.1 400 Bad Request\r\n\r\n"], ids=["silent", "http"])
def test_scheduler_that_never_handshakes_exits_2(short_cases, answer):
    """A TCP peer on the loopback that accepts and stays silent (a hung process) or answers
    something else (an HTTP server): one line, exit 2, after --connect-timeout.  The 120 s
    bound of the join only stops a hang (before the fix: > 120 s, or a 3 EiB
    MemoryError); the verdict is the exit code and the message."""
    import socket

    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen(4)
        port = srv.getsockname()[1]
        stop = threading.Event()
        conns = []

        def serve() -> None:
            srv.settimeout(0.2)
            while not stop.is_set():
                try:
                    c, _ = srv.accept()
                except OSError:
                    continue
                conns.append(c)
                if answer is not None:
                    c.sendall(answer)

        t = threading.Thread(target=serve, daemon=True)
        t.start()
        box = {}

        def invoke() -> None:
            box["r"] = runner.invoke(app, ["batch", str(short_cases[0]), "--scheduler", f"tcp://127.0.0.1:{port}",
                                           "--connect-timeout", "1"])

        cli = threading.Thread(target=invoke, daemon=True)
        try:
            cli.start()
            cli.join(120.0)  # only stops a hang; the verdict is below
        finally:
            stop.set()
            t.join()
            for c in conns:
                c.close()
    assert not cli.is_alive(), "--scheduler still waiting 120 s after connecting to a silent peer"
    r = box["r"]
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1, lines
    if answer is None:
        assert "no Dask handshake within 1 s" in lines[0] and f"tcp://127.0.0.1:{port}" in lines[0]
    else:
        assert "not a Dask handshake" in lines[0]


def test_scheduler_address_schemes_are_checked():
    for bad in ("tls://127.0.0.1:8786", "ucx://127.0.0.1:8786", "http://x", "inproc://x"):
        with pytest.raises(CaseError, match=r"is not supported, expected an address like tcp://HOST:PORT"):
            make_executor(None, bad)
    with pytest.raises(CaseError, match="bad port"):
        make_executor(None, "tcp://127.0.0.1:99999")
    with pytest.raises(CaseError, match="--connect-timeout"):
        make_executor(None, "tcp://127.0.0.1:8786", connect_timeout=0)


def test_unwritable_results_folder_is_refused_before_computing(short_cases, tmp_path, monkeypatch):
    """A read-only --json-dir is a usage error (exit 2) before any case runs.  As root, mode
    0o555 does not stop writes, so the probe's file creation is made to fail as on a
    read-only folder; the run_case spy shows nothing was computed."""
    import errno
    import tempfile

    calls = []
    monkeypatch.setattr(service, "run_case", lambda *a, **k: calls.append(1))
    real_mkstemp = tempfile.mkstemp

    def read_only(*a, **k):
        if str(k.get("dir", "")).endswith("ro"):
            raise PermissionError(errno.EACCES, "Permission denied")
        return real_mkstemp(*a, **k)

    monkeypatch.setattr(tempfile, "mkstemp", read_only)
    r = runner.invoke(app, ["batch", str(short_cases[1]), "--jobs", "1", "--json-dir", str(tmp_path / "ro")])
    assert r.exit_code == 2, r.output
    assert "results folder is not writable: Permission denied" in r.output and str(tmp_path / "ro") in r.output
    assert calls == []


def test_disk_full_stops_with_exit_2_keeps_saved_results_and_prints_summary(short_cases, tmp_path, monkeypatch):
    """ENOSPC while saving the second case (the JSON writer patched to raise it): exit 2 with
    one clear error line, the first case's result kept, the summary printed."""
    import errno

    from linecheck.io import jsonout

    real = jsonout.write_json
    written = []

    def full_disk(path, doc, **kw):
        if written:
            raise OSError(errno.ENOSPC, "No space left on device")
        written.append(path)
        return real(path, doc, **kw)

    monkeypatch.setattr(jsonout, "write_json", full_disk)
    out = tmp_path / "res"
    r = runner.invoke(app, ["batch", *map(str, short_cases), "--jobs", "1", "--json-dir", str(out)])
    assert r.exit_code == 2, r.output
    assert "batch summary" in r.output and "1 run, 0 skipped, 1 failed" in r.output
    errors = [ln for ln in r.output.splitlines() if ln.startswith("error:")]
    assert len(errors) == 1 and "No space left on device" in errors[0] and "--resume" in errors[0]
    assert "1 result(s) saved" in errors[0]
    assert [p.name for p in out.glob("*.json")] == [f"{short_cases[0].stem}.json"]
    assert json.loads((out / f"{short_cases[0].stem}.json").read_text())["realizations"] == 3
    assert "internal error" not in r.output


def test_pool_progress_moves_within_a_chunk_per_realization(short_cases, pool):
    """Workers report progress to the coordinator while a chunk runs: with one task of all 3
    realizations, events arrive inside every realization (1.x, 2.x) before the result, and
    the piped display prints plain progress lines from them."""
    import io

    from rich.console import Console

    from linecheck.cli.batch_cmd import BatchDisplay

    events: list[BatchEvent] = []
    rep = run_batch([short_cases[0]], executor=pool, chunk_size=3, progress=events.append)
    assert rep.exit_code == 0
    kinds = [e.kind for e in events]
    before = [e.overall_done for e in events[:kinds.index("case_done")] if e.kind == "case_progress"]
    assert {int(d) for d in before if d < 3} >= {1, 2}, before  # at least once per realization
    assert before == sorted(before) and before[-1] == 3
    assert events[-1].cases_done == events[-1].cases_total == 1

    buf = io.StringIO()
    display = BatchDisplay(interval=0.0, live=False, console=Console(file=buf, width=200))
    for ev in events:
        display(ev)
    lines = buf.getvalue().splitlines()
    assert lines[0] == "batch: 1 case(s), 3 realizations on process pool (2 workers)"
    progress = [ln for ln in lines if ln.startswith("progress: cases 0/1, realizations ")]
    assert len(progress) >= 2 and all("elapsed 0:" in ln and "ETA " in ln for ln in progress)
    assert lines[-1].startswith(f"done    {rep.outcomes[0].name}  [cases 1/1, realizations 3/3 (100 %)")


def test_summary_flags_cont_r_and_failed_sanity_check(short_cases):
    """Cont_R above 10 % and a failed time- vs frequency-domain check are marked in the
    batch summary and explained below it; a clean result gets neither."""
    import copy
    import io

    from rich.console import Console

    from linecheck.batch import BatchReport
    from linecheck.cli.batch_cmd import summary_notes, summary_table
    from linecheck.io.document import RunDocument

    clean = run_batch([short_cases[1]]).outcomes[0]  # synoptic: has the sanity check
    assert clean.doc.spectral.sanity_check, "synoptic results carry the sanity check"
    flagged = copy.deepcopy(clean)
    flagged.name = "flagged"
    d = flagged.doc.to_json()  # edit the JSON, read it back typed (as a saved result would be)
    d["reactions"]["Ry"]["Cont_R"]["mean"] = 0.25
    d["reactions"]["Ry"]["dynamic_analysis"] = "recommended"  # interval above 10 % (the adaptive-count rule)
    d["spectral"]["sanity_check"][0].update(reaction="Rz", quantity="rms_fluctuating", time_domain=176.0,
                                            frequency_domain=212.0, allowed_difference=20.0, ok=False)
    flagged.doc = RunDocument.from_json(d)
    d = clean.doc.to_json()
    for item in d["spectral"]["sanity_check"]:
        item["ok"] = True
    d["reactions"]["Ry"]["Cont_R"]["mean"] = 0.05
    for r in ("Rx", "Ry", "Rz"):
        d["reactions"][r]["dynamic_analysis"] = None
    clean.doc = RunDocument.from_json(d)
    report = BatchReport([clean, flagged])

    def render(obj) -> str:
        buf = io.StringIO()
        Console(file=buf, width=250).print(obj)
        return buf.getvalue()

    table = render(summary_table(report)).splitlines()
    row = next(ln for ln in table if "flagged" in ln)
    assert "25.0" in row and "Cont_R>10% Ry" in row and "t/f check" in row
    # every reaction a Cont_R flag names has its value in the table: Rx and Ry columns,
    # Rz (no column) in the flag itself
    header = next(ln for ln in table if "Cont_R Ry %" in ln)
    assert "Cont_R Rx %" in header
    d = flagged.doc.to_json()
    d["reactions"]["Rx"]["Cont_R"]["mean"] = 0.097
    d["reactions"]["Rx"]["dynamic_analysis"] = "inconclusive"
    d["reactions"]["Rz"]["Cont_R"]["mean"] = 0.123
    d["reactions"]["Rz"]["dynamic_analysis"] = "recommended"
    both = copy.deepcopy(flagged)
    both.name = "both"
    both.doc = RunDocument.from_json(d)
    lines = render(summary_table(BatchReport([both]))).splitlines()
    header = next(ln for ln in lines if "Cont_R Ry %" in ln)
    row = next(ln for ln in lines if "both" in ln)
    cells = [c.strip() for c in row.split("│")]
    names = [c.strip() for c in header.split("┃")]
    assert cells[names.index("Cont_R Rx %")] == "9.7" and cells[names.index("Cont_R Ry %")] == "25.0"
    assert "Cont_R>10% Ry Rz 12.3%" in row and "Cont_R~10% Rx" in row
    clean_row = next(ln for ln in table if clean.name in ln)
    assert "5.0" in clean_row and "Cont_R>10%" not in clean_row and "t/f" not in clean_row
    notes = summary_notes(report)
    assert len(notes) == 2
    assert "dynamic analysis recommended" in notes[0]
    assert "flagged: Rz fluctuating r.m.s. 0.176 vs 0.212 kN (allowed difference 0.020)" in notes[1]
    assert summary_notes(BatchReport([clean])) == []
