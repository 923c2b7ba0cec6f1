"""The optional compiled kernel (``linecheck[fast]``, Numba) against the numpy code.

    .venv/bin/python bench/bench_kernel.py            # --repeat 3

Each row runs the same case twice in this process, the numpy loop (``LINECHECK_KERNEL=numpy``,
the baseline) and the compiled kernel (``LINECHECK_KERNEL=numba``), fresh turbulence every run,
best of ``--repeat``; the frequency-domain check is included where a run makes it.  The two
agree within a tolerance (tests/core/test_kernel.py: RTOL_RUN, 1e-9 of the largest value); the last
column prints their largest relative difference here.
"""

from __future__ import annotations

import os

os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_core import case_with, line_with_spans

from linecheck import service
from linecheck.core import kernel


def timed(case, reals, repeat):
    """Best time and result of each mode, the modes interleaved run by run (this VM's speed
    drifts by up to 2x over minutes: interleaving keeps the ratio fair)."""
    best = {"numpy": float("inf"), "numba": float("inf")}
    res = {}
    for i in range(repeat + 1):
        for mode in best:
            os.environ["LINECHECK_KERNEL"] = mode
            t = time.perf_counter()
            res[mode] = service.run_case(case, realizations=reals)
            if i:  # the first round warms up
                best[mode] = min(best[mode], time.perf_counter() - t)
    return best, res


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if not kernel.installed():
        sys.exit("Numba is not installed: pip install -e '.[fast]'")
    rows = [
        ("Sy 40 m/s, 6 spans, 1 realization", case_with("case09-six"), [0]),
        ("Sy 40 m/s, 6 spans, 10 realizations", case_with("case09-six"), list(range(10))),
        ("Db_y 40 m/s, 6 spans, 1 realization", case_with("case05-six"), [0]),
        ("Db_y 40 m/s, 6 spans, 10 realizations", case_with("case05-six"), list(range(10))),
        ("Sy 40 m/s, 60 spans, 1 realization", line_with_spans(case_with("case09-six"), 60), [0]),
    ]
    out = []
    for name, case, reals in rows:
        best, res = timed(case, reals, args.repeat)
        diff = max(float(np.abs(getattr(res["numba"], k) - getattr(res["numpy"], k)).max()
                         / np.abs(getattr(res["numpy"], k)).max()) for k in ("background", "resonant"))
        out.append((name, best["numpy"], best["numba"], diff))
    print(f"machine: {os.cpu_count()} cores; {time.strftime('%Y-%m-%d %H:%M')}; best of {args.repeat}")
    off = [f"{p.name} ({p.reason})" for p in kernel.status() if not p.on]
    print("kernel pieces off: " + (", ".join(off) if off else "none"))
    print(f"{'run':40s} {'numpy loop':>11s} {'kernel':>8s} {'ratio':>6s}  rel. difference")
    for name, a, b, diff in out:
        print(f"{name:40s} {a:10.2f}s {b:7.2f}s {a / b:5.2f}x  {diff:.1e}")


if __name__ == "__main__":
    main()
