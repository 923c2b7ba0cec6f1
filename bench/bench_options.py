"""Cost of the non-linear options: drag = "quadratic" and tension = "second-order" (docs/performance.md).

Run from the repository root:

    .venv/bin/python bench/bench_options.py                   # case09-six, 10 realizations, 5 rounds
    .venv/bin/python bench/bench_options.py --case case10-six --repeat 5

``service.run_case`` of the six-span synoptic case (all 10 realizations, the paper's 600 s
record, wind synthesis, burn-in and frequency-domain check included) with every combination of
the two keys, timed in this process, interleaved in rounds (ABBA order, so that the machine's load affects all
alike), ``--repeat`` rounds, on one thread and on the CLI's default threads (``--threads``).  Ratios are to the paper's linear/linear run of the same case: the
ratio of the best times, and the median over the rounds of each round's ratio (the verdict).
All four runs analyse the same record: the burn-in is derived once (linear/linear) and imposed
(the derived burn-in can move by one step with the mean state, which changes the wind
synthesis' FFT length and its cost by up to 20 %, unrelated to the options).
Target: both options together add at most 15 %.
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")
# the compiled step loop when installed (linecheck[fast]; as in a batch or scan process that has
# loaded it); LINECHECK_KERNEL=numpy times the numpy loop
os.environ.setdefault("LINECHECK_KERNEL", "numba")

import argparse
import dataclasses
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck import service
from linecheck.batch.executors import default_jobs
from linecheck.core.case import load_case

COMBOS = (("linear", "linear"), ("quadratic", "linear"), ("linear", "second-order"), ("quadratic", "second-order"))
TARGET = 1.15


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="case09-six")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--damping", default="quasi-steady", choices=("quasi-steady", "paper"))
    ap.add_argument("--threads", type=int, nargs="+", default=[1, default_jobs()],
                    help="realization threads of run_case; default: 1 and the CLI's default (the CPUs)")
    args = ap.parse_args(argv)
    base = load_case(ROOT / "cases" / "paper" / f"{args.case}.toml")
    ref = dataclasses.replace(base, analysis=dataclasses.replace(base.analysis, damping=args.damping))
    # the same record for all: the derived burn-in moves by a step with the mean state, and the
    # wind synthesis' FFT length (hence its cost) with it
    burn = service.burn_in(ref, service.synoptic_model(ref, service.static_analysis(ref))).seconds \
        if ref.wind.type == "synoptic" else None
    cases = {c: dataclasses.replace(base, analysis=dataclasses.replace(
        base.analysis, damping=args.damping, drag=c[0], tension=c[1], burn_in=burn)) for c in COMBOS}
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}; python {platform.python_version()}, numpy {np.__version__}")
    print(f"{args.case}: {base.analysis.realizations} realizations, damping = \"{args.damping}\", {args.repeat} rounds")
    service.run_case(cases[COMBOS[-1]], realizations=[0])  # warm-up (imports, first calls)
    for threads in args.threads:
        bench(cases, args.repeat, threads)
    return 0


def bench(cases: dict, repeat: int, threads: int) -> float:
    """Time the four combinations in ``repeat`` rounds with ``threads``; print the table and the
    verdict; return the median ratio of both options."""
    best = {c: np.inf for c in COMBOS}
    rounds = []  # per round: each combination's time over the linear run's of the same round
    for r in range(repeat):
        order = COMBOS if r % 2 == 0 else COMBOS[::-1]  # ABBA: a drift of the machine's speed cancels
        times = {}
        for c in order:
            t0 = time.perf_counter()
            service.run_case(cases[c], threads=threads)
            times[c] = time.perf_counter() - t0
            best[c] = min(best[c], times[c])
        rounds.append({c: times[c] / times[COMBOS[0]] for c in COMBOS})
    ref = best[COMBOS[0]]
    print(f"\nthreads = {threads}:")
    print("| drag | tension | best time [s] | ratio of best | median ratio of the rounds (range) |")
    print("| --- | --- | ---: | ---: | ---: |")
    for c in COMBOS:
        rr = np.array([x[c] for x in rounds])
        print(f"| {c[0]} | {c[1]} | {best[c]:.2f} | {best[c] / ref:.3f} | {np.median(rr):.3f} "
              f"({rr.min():.3f}-{rr.max():.3f}) |")
    both = float(np.median([x[COMBOS[-1]] for x in rounds]))
    # the verdict rests on the median of the paired ratios: the runs of a round are adjacent in
    # time, so a phase of this shared VM affects both; the ratio of two best times pairs runs
    # from different phases (the same code once read +1 % and +29 % that way)
    print(f"both options, {threads} thread(s): +{100 * (both - 1):.1f} % (median of {repeat} rounds; target <= "
          f"+{100 * (TARGET - 1):.0f} %): {'met' if both <= TARGET else 'NOT met'}; "
          f"load average now {os.getloadavg()[0]:.1f}")
    return both


if __name__ == "__main__":
    raise SystemExit(main())
