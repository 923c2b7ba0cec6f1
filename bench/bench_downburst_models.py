"""Benchmark of the downburst running-mean models against their speed target.

Run from the repository root:  ``.venv/bin/python bench/bench_downburst_models.py [--case ...] [--realizations 10]``

Target: a six-span downburst run with 10 realizations takes at most 1.5x the baseline's time per
model.  The baseline is the "holmes-oliver" model (the paper cases pin it; bit-identical to the
code before running-mean models could be chosen), run in the same process; every other model is
timed the same way (one full ``service.run_case``, best of ``--repeat``) and its ratio printed.
The table also gives each run's record length, since the event window of "ring-jet" scales with
D_j/V_j and the cost of steps 2-3 with the record length, and R_x / g*_yp L at the tower.
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import argparse
import os
import sys


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="cases/paper/case03-six.toml")
    ap.add_argument("--realizations", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=1, help="runs per model (best is reported)")
    ap.add_argument("--threads", type=int, default=1, help="BLAS threads")
    args = ap.parse_args()
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(args.threads)

    import dataclasses
    import time
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root))
    from linecheck import service
    from linecheck.core.case import load_case

    case = load_case(root / args.case)
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, realizations=args.realizations))
    rows = []
    for model in ("holmes-oliver",) + tuple(m for m in service.BUILTIN_DOWNBURST_MODELS if m != "holmes-oliver"):
        c = service.case_with_model(case, model)
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            res = service.run_case(c)
            best = min(best, time.perf_counter() - t0)
        j = res.tower_index
        rx = res.stats.mean("peak_normalised")[j, 0]
        rows.append((model, best, float(res.time[-1] - res.time[0]), float(rx)))
    base = rows[0][1]
    print(f"{case.name}: {args.realizations} realizations, dt = {case.analysis.time_step} s")
    print(f"{'model':<15}{'time s':>9}{'ratio':>8}{'record s':>10}{'Rx peak/g*L':>13}")
    for model, t, rec, rx in rows:
        print(f"{model:<15}{t:9.2f}{t / base:8.2f}{rec:10.1f}{rx:13.3f}")


if __name__ == "__main__":
    main()
