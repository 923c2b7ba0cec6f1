"""Realization chunks in threads (``run_case(threads=k)``, ``linecheck run --jobs k``): wall time
against one thread, interleaved run by run in this process, and the same bits.

    .venv/bin/python bench/bench_threads.py              # six-span synoptic and downburst, 60 spans
    .venv/bin/python bench/bench_threads.py --repeat 5

Whole runs (steps 1-3, statistics; the frequency-domain check off, except in the rows marked
"check", where it runs beside the chunks on a thread of its own), fresh turbulence, the compiled
step loop loaded (threads are used only with it).  Step 1, the models and the burn-in run once
before the chunks, so they bound the gain (Amdahl).
"""

from __future__ import annotations

import os

os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")  # time fresh turbulence
os.environ.setdefault("LINECHECK_KERNEL", "numba")

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_core import case_with, line_with_spans

from linecheck import service
from linecheck.batch.executors import default_jobs


def timed(case, n: int, threads: int, check: bool = False):
    t = time.perf_counter()
    res = service.run_case(case, realizations=list(range(n)), spectral_check=check, threads=threads)
    return time.perf_counter() - t, res


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=default_jobs())
    args = ap.parse_args()
    six, long = case_with("case09-six", realizations=10), line_with_spans(case_with("case09-six", realizations=4), 60)
    rows = [("Sy 40 m/s, 6 spans", six, 10, False),
            ("Db_y 40 m/s, 6 spans", case_with("case05-six", realizations=10), 10, False),
            ("Sy 40 m/s, 60 spans", long, 4, False),
            ("Sy 40 m/s, 6 spans, check", six, 1, True),  # the check beside the one chunk
            ("Sy 40 m/s, 60 spans, check", long, 1, True)]
    warm = case_with("case09-single", realizations=2)
    timed(warm, 2, 1)  # imports and the compiled loops loaded
    timed(warm, 2, 2)
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; "
          f"{time.strftime('%Y-%m-%d %H:%M')}; threads {args.threads}; best of {args.repeat}")
    print(f"{'run':34s} {'1 thread':>9s} {f'{args.threads} threads':>10s} {'ratio':>6s}  same bits")
    for label, case, n, check in rows:
        t1 = tk = np.inf
        same = True
        for _ in range(args.repeat):  # interleaved: the VM's speed drifts within minutes
            a, ra = timed(case, n, 1, check)
            b, rb = timed(case, n, args.threads, check)
            t1, tk = min(t1, a), min(tk, b)
            same &= bool(np.array_equal(ra.resonant, rb.resonant) and np.array_equal(ra.background, rb.background)
                         and (not check or np.array_equal(ra.spectral.exact.peak_dynamic, rb.spectral.exact.peak_dynamic)))
        print(f"{label + f', {n} realizations':34s} {t1:8.2f}s {tk:9.2f}s {t1 / tk:5.2f}x  {'yes' if same else 'NO'}",
              flush=True)


if __name__ == "__main__":
    main()
