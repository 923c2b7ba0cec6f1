"""Cost of line sections: steps 1-3 per span, equal-span form vs the section form.

Run from the repository root:

    .venv/bin/python bench/bench_sections.py              # best of 3
    .venv/bin/python bench/bench_sections.py --repeat 5 --realizations 4

``service.run_case`` (step 1, wind synthesis, steps 2-3; the frequency-domain check is off: its
cost on long lines is measured by bench/bench_long.py) of

- the baseline: paper case 9 on six equal spans (equal-span form, the paper's Appendix-A step 1),
- the same six spans written as towers (section form: exact-span step 1, Markov coherence),
- the 12-span example section (cases/examples/section-12span.toml: unequal, inclined, two angles),
- that section repeated to 24 and 48 spans (linearity in the number of spans),

all with the same record (``--duration`` s, ``--realizations``), the default drag/tension
options and ``time_step`` 0.05 s, timed in this process, interleaved, best of ``--repeat``.  The
table gives the time per span and its ratio to the baseline's.  Targets: the 12-span section costs
no more per span than the six equal spans, and the time per span stays flat from 12 to 48 spans.
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

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
from linecheck.core.case import Tower, load_case, replace


def _settings(case, duration: float, n: int):
    return replace(case, analysis=dataclasses.replace(case.analysis, duration=duration, realizations=n, burn_in=30.0,
                                                      drag="quadratic", tension="second-order",
                                                      damping="quasi-steady"))


def _repeat_section(case, times: int):
    """The example section's towers repeated ``times`` times end to end (interior ends become strain)."""
    towers = list(case.line.towers)
    length = towers[-1].station - towers[0].station
    out = []
    for k in range(times):
        for j, t in enumerate(towers):
            if k and j == 0:
                continue
            out.append(dataclasses.replace(t, name=f"{t.name}.{k + 1}", station=t.station + k * length))
    line = dataclasses.replace(case.line, towers=tuple(out), spans=len(out) - 1,
                               supports=tuple(t.support for t in out), towers_file=None)
    return replace(case, line=line, name=f"{case.name}x{times}")


def _six_as_towers(paper):
    """Paper case 9's six 300 m spans as a section with H0 = its still-air tension."""
    st = service.static_analysis(paper)
    H0 = float(st.mean.still_air.tension.mean())
    towers = tuple(Tower(f"T{j + 1}", 300.0 * j, 0.0, 43.0, paper.line.supports[j]) for j in range(7))
    line = dataclasses.replace(paper.line, towers=towers, tension=H0)
    return replace(paper, line=line, name="case09-six-as-towers")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--realizations", type=int, default=2)
    ap.add_argument("--duration", type=float, default=120.0)
    args = ap.parse_args(argv)
    paper = _settings(load_case(ROOT / "cases" / "paper" / "case09-six.toml"), args.duration, args.realizations)
    example = _settings(load_case(ROOT / "cases" / "examples" / "section-12span.toml"), args.duration,
                        args.realizations)
    cases = {
        "case09-six (baseline)": paper,
        "case09-six as towers": _six_as_towers(paper),
        "section-12span": example,
        "section x2 (24 spans)": _repeat_section(example, 2),
        "section x4 (48 spans)": _repeat_section(example, 4),
    }
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}; python {platform.python_version()}, numpy {np.__version__}")
    print(f"record {args.duration:g} s at 0.05 s (+30 s burn-in), {args.realizations} realizations, "
          f"no frequency-domain check, best of {args.repeat}")
    # the dense eigen-analyses inside a run (complex modes for the burn-in's significant modes,
    # the lowest undamped mode that calibrates the structural damping) are timed apart: their
    # cost is cubic in the spans and is measured on long lines (bench/bench_long.py)
    import linecheck.core.modes as modes_mod

    spent = {"modes": 0.0}

    def timed(fn):
        def wrapper(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                spent["modes"] += time.perf_counter() - t
        return wrapper

    service.synoptic_model = timed(service.synoptic_model)
    modes_mod.natural_modes = timed(modes_mod.natural_modes)
    service.run_case(paper, realizations=[0], spectral_check=False)  # warm-up
    best = {k: np.inf for k in cases}
    step1 = {k: np.inf for k in cases}
    modal = {k: np.inf for k in cases}
    for _ in range(args.repeat):
        for name, case in cases.items():
            t0 = time.perf_counter()
            service.static_analysis(case)
            t1 = time.perf_counter()
            spent["modes"] = 0.0
            service.run_case(case, spectral_check=False)
            t2 = time.perf_counter()
            step1[name] = min(step1[name], t1 - t0)
            modal[name] = min(modal[name], spent["modes"])
            best[name] = min(best[name], t2 - t1 - spent["modes"])
    base = best["case09-six (baseline)"] / paper.line.spans
    print(f"{'case':<24} {'spans':>5} {'step 1 s':>9} {'steps 1-3 s':>12} {'s/span':>8} {'ratio':>6} {'modal s':>8}")
    for name, case in cases.items():
        per = best[name] / case.line.spans
        print(f"{name:<24} {case.line.spans:>5} {step1[name]:>9.3f} {best[name]:>12.2f} {per:>8.3f} {per / base:>6.2f} "
              f"{modal[name]:>8.2f}")
    print("steps 1-3: the run without its eigen-analyses (modal s: complex modes for the burn-in and the lowest "
          "mode for the structural damping)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
