"""Bench: batch scaling (1 vs N workers) and a 1,000-point critical-downburst scan.

    .venv/bin/python bench/bench_batch.py                 # 24 paper cases + 1,000-point scan
    .venv/bin/python bench/bench_batch.py --cases 6       # first 6 paper cases only
    .venv/bin/python bench/bench_batch.py --skip-batch    # scan only
    .venv/bin/python bench/bench_batch.py --workers 1 2 4

Batch: every paper case file, all realizations over the full record, run with
``run_batch`` on the sequential executor (1 worker) and on a local process pool of N
workers (start-up of the pool included), results saved as JSON; the saved JSON of the
runs is compared byte for byte (bit-identity).  Scan: step 1 of the paper's line
(case01-single: L = 300 m, D_j = 600 m) on 25 distances x 40 angles = 1,000
configurations, with the same executors.  Timings are wall-clock seconds; the ratio
is t(1 worker) / t(N workers).  "cpu s" is the CPU time of this process and its worker
processes (start-up included): on a machine shared with other jobs the wall-clock ratio
is noisy, and N x cpu(1) / cpu(N) is the speed-up the same work would reach on N idle cores.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck.batch import ProcessPool, ScanGrid, SequentialExecutor, run_batch, run_scan
from linecheck.core.case import load_case

PAPER = ROOT / "cases" / "paper"
SCAN_CASE = PAPER / "case01-single.toml"
SCAN_DISTANCE = "0.4:2.8:0.1Dj"  # 25 values
SCAN_ANGLE = "-78:78:4"  # 40 values


def executor(n: int):
    return SequentialExecutor() if n == 1 else ProcessPool(n)


def cpu_seconds() -> float:
    """CPU time [s] of this process and of its finished children (pool workers)."""
    try:
        import resource
    except ImportError:  # pragma: no cover - Windows
        return float("nan")
    a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime


def load() -> str:
    """1-minute load average (the machine may be shared: compare it with the core count)."""
    try:
        return f"{os.getloadavg()[0]:.1f}"
    except OSError:  # pragma: no cover - not on Windows
        return "?"


def bench_batch(cases: list[Path], workers: list[int], out: Path) -> list[tuple]:
    rows = []
    ref: dict[str, bytes] | None = None
    n_real = sum(load_case(p).analysis.realizations for p in cases)
    for n in workers:
        d = out / f"batch-{n}"
        l0 = load()
        c0 = cpu_seconds()
        t0 = time.perf_counter()
        with executor(n) as ex:
            rep = run_batch(cases, executor=ex, json_dir=d)
        dt = time.perf_counter() - t0
        cpu = cpu_seconds() - c0
        if rep.exit_code != 0:
            raise SystemExit(f"batch with {n} workers failed: {[(o.name, o.error) for o in rep.failed]}")
        saved = {p.name: p.read_bytes() for p in sorted(d.glob("*.json"))}
        if ref is None:
            ref, same = saved, "reference"
        else:
            same = "identical" if saved == ref else "DIFFERENT"
        rows.append((f"batch {len(cases)} cases / {n_real} realizations", n, dt, cpu, same, f"{l0} / {load()}"))
        print(f"  batch, {n} worker(s): {dt:.1f} s, cpu {cpu:.1f} s ({same})", flush=True)
    return rows


def bench_scan(workers: list[int]) -> list[tuple]:
    case = load_case(SCAN_CASE)
    grid = ScanGrid.from_options(case, SCAN_DISTANCE, SCAN_ANGLE)
    rows = []
    ref = None
    for n in workers:
        l0 = load()
        c0 = cpu_seconds()
        t0 = time.perf_counter()
        with executor(n) as ex:
            res = run_scan(SCAN_CASE, grid, executor=ex)
        dt = time.perf_counter() - t0
        cpu = cpu_seconds() - c0
        crit = ", ".join(f"{c.reaction}: {c.distance_over_dj:.1f} D_j / {c.angle:g} deg" for c in res.criticals())
        if ref is None:
            ref, same = res.peak, "reference"
        else:
            import numpy as np

            same = "identical" if np.array_equal(res.peak, ref, equal_nan=True) else "DIFFERENT"
        rows.append((f"scan {grid.size} points ({res.n_failed} failed)", n, dt, cpu, same, f"{l0} / {load()}"))
        print(f"  scan, {n} worker(s): {dt:.1f} s, {dt / grid.size * 1e3:.0f} ms/point; critical {crit}", flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=None, help="run only the first N paper cases")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--skip-batch", action="store_true")
    ap.add_argument("--skip-scan", action="store_true")
    args = ap.parse_args()
    cases = sorted(PAPER.glob("*.toml"))[: args.cases]
    rows: list[tuple] = []
    with tempfile.TemporaryDirectory() as tmp:
        if not args.skip_batch:
            rows += bench_batch(cases, args.workers, Path(tmp))
        if not args.skip_scan:
            rows += bench_scan(args.workers)
    print()
    print(f"cores: {os.cpu_count()}; load = 1-minute load average before / after each run")
    print(f"| {'job':<42} | workers | wall s | ratio t1/tN | cpu s | N cpu1/cpuN | results | load |")
    print(f"| {'-' * 42} | ------- | ------ | ----------- | ----- | ----------- | ------- | ---- |")
    base: dict[str, tuple[float, float]] = {}
    for job, n, dt, cpu, same, ld in rows:
        base.setdefault(job, (dt, cpu))
        t1, c1 = base[job]
        print(f"| {job:<42} | {n:>7} | {dt:>6.1f} | {t1 / dt:>11.2f} | {cpu:>5.1f} | {n * c1 / cpu:>11.2f} "
              f"| {same} | {ld} |")


if __name__ == "__main__":
    main()
