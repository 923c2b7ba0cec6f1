"""Speed and memory targets for long lines: one realization of 60 and 200 spans with the
frequency-domain check, the check's cost against the whole-line check, and the peak memory of a
200-span, 10-realization run.

    .venv/bin/python bench/bench_long.py            # everything (about 10 minutes)
    .venv/bin/python bench/bench_long.py --quick    # 6/20/60 spans, no 200-span or memory rows

The paper's six-span line (case 9: 300 m spans, 40 m/s, paper damping) with n spans and the tower
of interest in the middle, 600 s at 0.05 s.  Baselines run in the same process: the whole-line
check (the windows switched off) and, for memory, all realizations in one chunk (each memory row
in a fresh process, peak resident memory from ``ru_maxrss``).
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")
# the compiled step loop when installed (linecheck[fast]; as in a batch or scan process that has
# loaded it); LINECHECK_KERNEL=numpy times the numpy loop
os.environ.setdefault("LINECHECK_KERNEL", "numba")

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_core import case_with, line_with_spans

from linecheck import service

MEMORY_SNIPPET = """
import resource, sys, time
sys.path.insert(0, {here!r})
from bench_core import case_with, line_with_spans
from linecheck import service
from linecheck.core import budget
if {whole}:
    budget.RUN_CHUNK_BYTES = 1e30
c = line_with_spans(case_with("case09-six", realizations={real}), {spans})
t = time.perf_counter()
service.run_case(c)
print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
"""


def one_run(spans: int, *, windows: bool = True) -> tuple[float, float, object]:
    """(whole run [s], check alone [s], spectral result) of one realization."""
    c = line_with_spans(case_with("case09-six", realizations=1), spans)
    saved = service.CHECK_WINDOW_MIN_SPANS
    if not windows:
        service.CHECK_WINDOW_MIN_SPANS = 10**9
    try:
        t = time.perf_counter()
        res = service.run_case(c)
        total = time.perf_counter() - t
        st = service.static_analysis(c)
        t = time.perf_counter()
        sp = service.spectral_analysis(c, static=st)
        check = time.perf_counter() - t
    finally:
        service.CHECK_WINDOW_MIN_SPANS = saved
    return total, check, sp if res is not None else None


def memory_run(spans: int, realizations: int, whole: bool) -> tuple[float, float]:
    code = MEMORY_SNIPPET.format(here=str(HERE), whole=whole, real=realizations, spans=spans)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONWARNINGS": "ignore"})
    secs, mb = out.stdout.split()[-2:]
    return float(secs), float(mb)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    rows = []
    one_run(1)  # warm-up: imports, and the compiled kernel loaded (or compiled) once
    for n in (6, 20, 60) if args.quick else (6, 20, 60, 200):
        total, check, sp = one_run(n)
        w = sp.window
        note = "whole line" if w is None else (f"window {w.spans} spans (tried {w.windows}), "
                                               f"est. error {100 * w.estimated_error.max():.2f} %")
        pk = sp.exact.peak_dynamic
        rows.append((f"{n} spans, 1 realization, run with check", f"{total:.2f} s", f"check {check:.2f} s; {note}; "
                     f"peaks {pk[0]:.1f} / {pk[1]:.1f} / {pk[2]:.1f} N"))
        if n == 60:
            _, check0, sp0 = one_run(n, windows=False)
            pk0 = sp0.exact.peak_dynamic
            diff = max(abs(pk[i] / pk0[i] - 1) for i in range(3))
            rows.append(("60 spans: whole-line check (baseline)", f"{check0:.2f} s",
                         f"x{check0 / check:.1f} the windowed check; windowed peaks within {100 * diff:.3f} %"))
    if not args.quick:
        s_c, mb_c = memory_run(200, 10, whole=False)
        rows.append(("200 spans, 10 realizations, chunked", f"{mb_c:.0f} MB", f"{s_c:.0f} s"))
        s_w, mb_w = memory_run(200, 10, whole=True)
        rows.append(("200 spans, 10 realizations, one chunk (baseline)", f"{mb_w:.0f} MB",
                     f"{s_w:.0f} s; chunked uses x{mb_c / mb_w:.2f} the memory, x{s_c / s_w:.2f} the time"))
    w = [max(len(r[i]) for r in rows) for i in range(3)]
    print(f"machine: {os.cpu_count()} cores; {time.strftime('%Y-%m-%d %H:%M')}")
    print("  ".join(h.ljust(w[i]) for i, h in enumerate(("what", "measured", "note"))))
    for r in rows:
        print("  ".join(r[i].ljust(w[i]) for i in range(3)))


if __name__ == "__main__":
    main()
