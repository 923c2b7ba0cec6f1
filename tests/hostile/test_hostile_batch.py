"""Hostile conditions for long jobs: the resource guard per batch case and per scan, scan
progress, a lost Dask scheduler, a full disk mid-batch and SIGTERM.

No timing decides a verdict: the tests wait on events (a progress event, a line on a pipe)
and the bounds on those waits only stop a hang.
"""

from __future__ import annotations

import errno
import logging
import os
import select
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck.batch import BatchEvent, ScanGrid, run_batch, run_scan
from linecheck.cli.app import app
from linecheck.core import budget
from linecheck.core.case import load_case

from ..batch.test_batch import write_short_case
from ..batch.test_scan import paper_line_case
from ..conftest import CASES

runner = CliRunner(env={"COLUMNS": "250"})
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def short_cases(tmp_path: Path) -> list[Path]:
    d = tmp_path / "cases"
    d.mkdir()
    return [write_short_case(CASES / "paper" / f"{n}.toml", d) for n in ("case01-single", "case09-single")]


def estimate(path: Path) -> budget.Estimate:
    return budget.estimate(load_case(path), "run")


# --------------------------------------------------------------------------- 8. batch: guard per case
def test_batch_warns_per_case_above_half_the_memory_limit_and_fails_one_above_it(short_cases, tmp_path,
                                                                                 monkeypatch):
    """Each case is estimated before the batch starts: one above the limit fails alone (its
    estimate in the summary), one above half of it runs with the README's warning line."""
    huge = write_short_case(CASES / "paper" / "case02-single.toml", tmp_path, realizations=1_000_000_000)
    small = short_cases[0]
    limit = 1.5 * estimate(small).memory  # the small case is above half of it
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, str(int(limit)))
    events: list[BatchEvent] = []
    rep = run_batch([small, huge], progress=events.append)
    ok, bad = rep.outcomes
    assert ok.status == "done" and "more than 50% of the memory limit" in ok.warning
    assert bad.status == "failed" and "above the memory limit" in bad.error and bad.warning is None
    warned = [e for e in events if e.kind == "case_warning"]
    assert [(e.name, e.message) for e in warned] == [(ok.name, ok.warning)]
    assert events.index(warned[0]) < min(i for i, e in enumerate(events) if e.kind == "case_start")

    r = runner.invoke(app, ["batch", str(small), str(huge), "--jobs", "1", "--json-dir", str(tmp_path / "res")])
    assert r.exit_code == 1, r.output
    lines = r.output.splitlines()
    warn = [ln for ln in lines if ln.startswith("warning: ") and "memory limit" in ln]
    assert len(warn) == 1 and warn[0].startswith(f"warning: {ok.name}: run needs about "), warn
    assert "batch summary" in r.output and "1 run, 0 skipped, 1 failed" in r.output
    assert "Traceback" not in r.output and "internal error" not in r.output


def test_batch_warns_a_case_estimated_to_run_long(short_cases, monkeypatch):
    """A case estimated above WARN_SECONDS (about 10 minutes; lowered here between the two
    cases' estimates) gets the long-job warning; the shorter one does not."""
    long_case, short_case = short_cases  # a 250-state downburst, a synoptic case
    t_long, t_short = estimate(long_case).seconds, estimate(short_case).seconds
    assert t_long > t_short
    monkeypatch.setattr(budget, "WARN_SECONDS", (t_long + t_short) / 2)
    rep = run_batch([long_case, short_case])
    assert "a long job; cancel with Ctrl-C" in rep.outcomes[0].warning
    assert rep.outcomes[1].warning is None and rep.exit_code == 0


# --------------------------------------------------------------------------- 9. scan: guard and progress
def test_a_scan_of_100000_positions_is_estimated_and_warned_before_it_starts(tmp_path):
    case = load_case(CASES / "paper" / "case01-six.toml")
    grid = ScanGrid.from_options(case, "1:5882:1m", None, None)  # 5882 x 17 = 99,994 positions
    warned: list[str] = []
    from linecheck.batch.scan import scan_estimate

    est = scan_estimate(case, grid.size, workers=2, warn=warned.append)
    assert est.seconds > budget.WARN_SECONDS and est.points == grid.size
    assert len(warned) == 1 and "scan needs about" in warned[0] and "99994 positions on 2 worker(s)" in warned[0]
    assert "a long job; cancel with Ctrl-C" in warned[0]
    # the default grid (357 positions) of the same line: no warning
    quiet: list[str] = []
    scan_estimate(case, ScanGrid.from_options(case).size, workers=2, warn=quiet.append)
    assert quiet == []
    # --dynamic adds steps 2-3 of K realizations per position
    dyn = budget.estimate_scan(case, 357, dynamic_realizations=10, workers=2)
    assert dyn.seconds > 10 * est.seconds * 357 / grid.size and dyn.memory > est.memory


def test_scan_cli_warns_and_refuses_before_any_position_runs(tmp_path, monkeypatch):
    path = paper_line_case(tmp_path, "single")
    ran: list[int] = []
    from linecheck.batch import tasks

    real = tasks.scan_point
    monkeypatch.setattr(tasks, "scan_point", lambda *a, **k: ran.append(1) or real(*a, **k))
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, "50MB")  # restored after the test (--max-memory sets it too)
    r = runner.invoke(app, ["scan", str(path), "--distance", "1.0:1.4:0.2Dj", "--angle", "0,30", "--jobs", "1",
                            "--dynamic", "--max-memory", "50MB"])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "scan needs about" in lines[0] and "above the memory limit of 50 MB" in lines[0]
    assert ran == []
    monkeypatch.delenv(budget.ENV_MAX_MEMORY)
    monkeypatch.setattr(budget, "WARN_SECONDS", 0.0)
    r = runner.invoke(app, ["scan", str(path), "--distance", "1.0:1.4:0.2Dj", "--angle", "0,30", "--jobs", "1",
                            "--progress-interval", "0"])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert sum(ln.startswith("warning: scan needs about") for ln in lines) == 1
    start = lines.index("scan on sequential (1 worker): 6 position(s)")
    progress = [ln for ln in lines if ln.startswith("progress: positions ")]
    assert lines.index(progress[0]) > start
    assert [ln.split()[2] for ln in progress] == [f"{k}/6" for k in range(1, 7)]  # per position in this process


def test_run_scan_reports_progress_before_submitting_and_per_point(tmp_path):
    path = paper_line_case(tmp_path, "single")
    grid = ScanGrid.from_options(load_case(path), "1.0:1.4:0.2Dj", "0,30", None)
    calls: list[tuple[str, int, int]] = []
    run_scan(path, grid, chunk_size=4, progress=lambda *a: calls.append(a))
    assert calls[0] == ("scan", 0, 6) and calls[-1] == ("scan", 6, 6)
    done = [c[1] for c in calls]
    assert done == sorted(done) and set(range(7)) <= set(done)


# --------------------------------------------------------------------------- 10. a lost Dask scheduler
def test_lost_dask_scheduler_is_one_line_per_case_and_a_resume_hint(tmp_path, monkeypatch):
    """A real LocalCluster on the loopback; its scheduler is closed when the first case is done
    (from the progress display: an event, not a delay).  Every unfinished case fails with one
    line naming the scheduler, the summary follows, exit 1 and a --resume hint; distributed's
    client logs no traceback about the lost connection."""
    distributed = pytest.importorskip("distributed")
    import linecheck.cli.batch_cmd as batch_cmd

    d = tmp_path / "cases"
    d.mkdir()
    cases = [write_short_case(CASES / "paper" / "case01-single.toml", d, realizations=2)]
    cases += [write_short_case(CASES / "paper" / f"case0{i}-single.toml", d, realizations=12) for i in (2, 3, 4)]
    records: list[logging.LogRecord] = []

    class Keep(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            records.append(record)

    keep = Keep(level=logging.DEBUG)
    client_log = logging.getLogger("distributed.client")
    client_log.addHandler(keep)
    try:
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                                      host="127.0.0.1", dashboard_address=None,
                                      silence_logs=logging.CRITICAL) as cluster:
            address = cluster.scheduler_address
            real = batch_cmd.BatchDisplay.__call__
            closed: list[str] = []

            def display(self, ev):
                real(self, ev)
                if ev.kind == "case_done" and not closed:
                    closed.append(ev.name)
                    cluster.sync(cluster.scheduler.close)  # the scheduler goes away mid-batch

            monkeypatch.setattr(batch_cmd.BatchDisplay, "__call__", display)
            r = runner.invoke(app, ["batch", *map(str, cases), "--scheduler", address, "--chunk", "1",
                                    "--json-dir", str(tmp_path / "res"), "--connect-timeout", "2"])
    finally:
        client_log.removeHandler(keep)
    assert closed, r.output
    assert r.exit_code == 1, r.output
    lines = r.output.splitlines()
    lost = [ln for ln in lines if ln.startswith("failed  ")]
    assert lost and all(f"lost the connection to the Dask scheduler at {address}" in ln for ln in lost), lost
    assert "batch summary" in r.output and "cancelled" not in r.output
    last = [ln for ln in lines if ln.startswith("error: ")]
    assert len(last) == 1 and "--resume" in last[0] and address in last[0], last
    assert "Traceback" not in r.output and "CommClosedError" not in r.output
    assert not [rec for rec in records if rec.levelno >= logging.WARNING or rec.exc_info], \
        [rec.getMessage() for rec in records]
    assert (tmp_path / "res" / "case01-single.json").exists()


# --------------------------------------------------------------------------- 13. a full disk mid-batch
def test_full_disk_mid_batch_stops_exits_2_and_writes_no_workbook(short_cases, tmp_path, monkeypatch):
    """The atomic writer's write of the second result fails with ENOSPC: as docs/batch.md says,
    the batch stops, the summary is printed, one error line with the --resume hint, exit 2, the
    first result kept, no workbook and no temporary file left."""
    pytest.importorskip("openpyxl")
    second = short_cases[1].stem
    real_write_text = Path.write_text

    def write_text(self, *a, **k):
        if self.name.startswith(f".{second}.json."):  # the temporary file of the second result
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write_text(self, *a, **k)

    monkeypatch.setattr(Path, "write_text", write_text)
    out, book = tmp_path / "res", tmp_path / "book.xlsx"
    r = runner.invoke(app, ["batch", *map(str, short_cases), "--jobs", "1", "--json-dir", str(out),
                            "--excel", str(book)])
    assert r.exit_code == 2, r.output
    assert "batch summary" in r.output
    errors = [ln for ln in r.output.splitlines() if ln.startswith("error:")]
    assert len(errors) == 1, errors
    assert f"cannot save the result {out / (second + '.json')}: No space left on device" in errors[0]
    assert "the batch stopped, 1 result(s) saved" in errors[0] and "--resume" in errors[0]
    assert not book.exists()
    assert sorted(p.name for p in out.iterdir()) == [f"{short_cases[0].stem}.json"]
    assert "internal error" not in r.output and "Traceback" not in r.output


def test_full_disk_report_from_the_runner(short_cases, tmp_path, monkeypatch):
    real_write_text = Path.write_text

    def write_text(self, *a, **k):
        if self.name.endswith(".tmp"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write_text(self, *a, **k)

    monkeypatch.setattr(Path, "write_text", write_text)
    rep = run_batch(short_cases, json_dir=tmp_path / "res")
    assert rep.exit_code == 2 and "No space left on device" in rep.output_error
    assert [o.status for o in rep.outcomes] == ["failed", "cancelled"]


# --------------------------------------------------------------------------- 14. SIGTERM
def test_sigterm_stops_a_batch_like_ctrl_c(tmp_path):
    """SIGTERM once the first case is done (its line on the piped stderr: the handshake): the
    batch stops like Ctrl-C -- the summary, finished results kept, exit 130 -- and no leaked
    semaphore warning (the pool's workers and queues are released).  The 300 s bounds only
    stop a hang."""
    d = tmp_path / "cases"
    d.mkdir()
    quick = write_short_case(CASES / "paper" / "case01-single.toml", d, realizations=1)
    slow = [write_short_case(CASES / "paper" / f"case0{i}-single.toml", d, realizations=2000) for i in (2, 3)]
    out = tmp_path / "res"
    env = {**os.environ, "PYTHONWARNINGS": "default", "COLUMNS": "200"}
    proc = subprocess.Popen([sys.executable, "-c", "from linecheck.cli.app import main; main()", "batch",
                             str(quick), *map(str, slow), "--jobs", "2", "--json-dir", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=ROOT)
    seen: list[str] = []
    try:
        while True:  # wait for the quick case's "done" line
            ready, _, _ = select.select([proc.stderr], [], [], 300.0)
            assert ready, f"no progress line within 300 s: {seen}"
            line = proc.stderr.readline()
            assert line, f"batch ended before the first case was done: {seen}"
            seen.append(line)
            if line.startswith("done    case01-single"):
                break
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:  # pragma: no cover - a hang
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, (stdout, stderr)
    assert "batch summary" in stdout and "cancelled" in stdout
    assert "interrupted: finished cases are saved" in stderr
    assert "leaked semaphore" not in stderr and "Traceback" not in stderr, stderr
    assert sorted(p.name for p in out.glob("*.json")) == ["case01-single.json"]


def test_sigterm_handler_sets_the_cancel_event_and_is_only_installed_while_the_command_runs():
    """The handler raises nothing in the main thread (an asynchronous exception there can leave a
    future's lock held and hang the process pool at exit): it sets the cancel event, which the
    coordinators poll; a second SIGTERM takes the default action; the old handler comes back."""
    import threading

    from linecheck.cli.signals import sigterm_cancels

    before = signal.getsignal(signal.SIGTERM)
    cancel = threading.Event()
    with sigterm_cancels(cancel):
        assert signal.getsignal(signal.SIGTERM) is not before
        os.kill(os.getpid(), signal.SIGTERM)  # the handler runs in this thread before the next line
        assert cancel.wait(timeout=60.0)  # an event, not a sleep: set by the handler's thread
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL  # a second SIGTERM: the default action
    assert signal.getsignal(signal.SIGTERM) == before

def test_abort_stops_running_pool_tasks_without_killing_their_workers(tmp_path, monkeypatch):
    """``ProcessPool.abort`` sets the pool's stop event: a running task ends with Cancelled at its
    next cancellation check and no worker is terminated -- a worker killed while writing to the
    pool's result pipe can leave a cut-off message that the pool's manager thread then waits on
    for ever at interpreter exit.  (Terminations are counted where they happen: a worker's exit
    code can be read as None when two threads reap it at once.)"""
    import multiprocessing.process

    from linecheck.batch.executors import ProcessPool
    from linecheck.batch.tasks import run_chunk

    terminated: list[int] = []
    real_terminate = multiprocessing.process.BaseProcess.terminate

    def terminate(self):
        terminated.append(self.pid)
        real_terminate(self)

    monkeypatch.setattr(multiprocessing.process.BaseProcess, "terminate", terminate)

    case = write_short_case(CASES / "paper" / "case02-single.toml", tmp_path, realizations=2000)
    pool = ProcessPool(2)
    try:
        handles = [pool.submit(run_chunk, str(case), list(range(2000)), report_key=k) for k in range(2)]
        started: set[int] = set()
        while len(started) < 2:  # both tasks running: wait for their "start" reports (blocking reads)
            msg = pool._queue.get()
            if msg[0] == "start":
                started.add(msg[1])
        assert not any(h.done() for h in handles), [h.exception() for h in handles]
        pool.abort(handles)
        assert all(type(h.exception()).__name__ == "Cancelled" for h in handles)
    finally:
        pool.close()
    assert terminated == []
