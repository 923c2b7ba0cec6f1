"""Benchmark: cost of the statistics over realizations relative to a 10-realization six-span run.

Run from the repository root:  ``.venv/bin/python bench/bench_stats.py [--repeat 3] [--case case09-six]``

Target: the statistics add <= 5 % to a 10-realization six-span run.  "baseline"
is ``service.run_case`` (steps 1-3, the per-realization statistics of Eqs 15-17 and the
frequency-domain check); "measured" is what the statistics over realizations add on top:
``RunResult.summary()`` (moments, fractiles, Gumbel fits, intervals, flags at every tower)
plus the typed :class:`~linecheck.io.document.RunDocument` of those summaries.  Both in the
same process, best of ``--repeat``; the table prints the ratio.
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import argparse
import sys
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--case", default="case09-six")
    args = ap.parse_args()
    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root))
    from linecheck import service
    from linecheck.core.case import load_case, replace
    from linecheck.io.document import reactions_of

    case = load_case(root / "cases" / "paper" / f"{args.case}.toml")
    case = replace(case, analysis=replace(case.analysis, realizations=10))
    t_run = t_stats = float("inf")
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        res = service.run_case(case)
        t_run = min(t_run, time.perf_counter() - t0)
        t0 = time.perf_counter()
        summary = res.summary()
        for k in range(res.system.n_towers):
            reactions_of(summary, k)
        t_stats = min(t_stats, time.perf_counter() - t0)
    ratio = t_stats / t_run
    print(f"{'what':<58} {'time s':>9} {'ratio':>8} {'target':>8}")
    print(f"{'baseline: run_case, ' + args.case + ', 10 realizations':<58} {t_run:9.3f} {1.0:8.3f}")
    print(f"{'measured: summaries + typed document (all towers)':<58} {t_stats:9.4f} {ratio:8.4f} {'<= 0.05':>8}"
          f"  {'ok' if ratio <= 0.05 else 'MISSED'}")


if __name__ == "__main__":
    main()
