"""Bench: the resource guard's estimates (linecheck/core/budget.py) against measured runs.

    .venv/bin/python bench/bench_budget.py            # a few paper-case variants, one process each

Each row runs ``service.run_case`` (or ``modes_analysis``) in a fresh subprocess and
records its wall time and peak resident memory (``ru_maxrss``); the ratio columns are
estimate / measured.  The guard aims at the order of magnitude (about a factor of 2);
calibrate the coefficients in budget.py from this table, never from a single run.
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CHILD = r"""
import json, resource, sys, time
from linecheck import service
from linecheck.core.budget import estimate
from linecheck.core.case import load_case, with_values
case = with_values(load_case(sys.argv[1]), json.loads(sys.argv[2]))
job = sys.argv[3]
est = estimate(case, job, spectral_check=False)
t = time.perf_counter()
if job == "run":
    service.run_case(case, spectral_check=False)
else:
    service.modes_analysis(case)
dt = time.perf_counter() - t
print(json.dumps({"est_mem": est.memory, "est_s": est.seconds,
                  "mem": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0, "s": dt}))
"""

ROWS = [
    ("case01-single, 2 realizations", "case01-single.toml", {"analysis.realizations": 2}, "run"),
    ("case01-single, 20 realizations", "case01-single.toml", {"analysis.realizations": 20}, "run"),
    ("case01-six, 4 realizations", "case01-six.toml", {"analysis.realizations": 4}, "run"),
    ("case09-single, 10 realizations", "case09-single.toml", {"analysis.realizations": 10}, "run"),
    ("case09-six, 2 realizations, dt 0.02", "case09-six.toml",
     {"analysis.realizations": 2, "analysis.time_step": 0.02}, "run"),
    ("case01-single, 2000 mean states", "case01-single.toml",
     {"analysis.realizations": 1, "analysis.mean_states": 2000}, "run"),
    ("20 spans x 40 elements, modes", "case01-six.toml",
     {"line.spans": 20, "line.elements_per_span": 40,
      "line.supports": ["strain"] + ["suspension"] * 19 + ["strain"], "line.tower_of_interest": 4}, "modes"),
]


def main() -> None:
    print(f"{'case':40s} {'est MB':>8s} {'meas MB':>8s} {'ratio':>6s} {'est s':>8s} {'meas s':>8s} {'ratio':>6s}")
    for label, f, changes, job in ROWS:
        out = subprocess.run([sys.executable, "-c", CHILD, str(ROOT / "cases" / "paper" / f), json.dumps(changes), job],
                             capture_output=True, text=True, cwd=ROOT)
        if out.returncode:
            print(f"{label:40s} failed: {out.stderr.strip().splitlines()[-1]}")
            continue
        r = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"{label:40s} {r['est_mem'] / 1e6:8.0f} {r['mem'] / 1e6:8.0f} {r['est_mem'] / r['mem']:6.2f} "
              f"{r['est_s']:8.2f} {r['s']:8.2f} {r['est_s'] / r['s']:6.2f}", flush=True)


if __name__ == "__main__":
    main()
