"""Speed of the numerical core against its targets (docs/performance.md, "Targets and current readings").

Run: ``python bench/bench_core.py [--quick]`` (from the repository root).  Prints one table:
measured value, target, and the ratio against a straightforward baseline run in the same
process (dense matrices, factorised every step).  Results are recorded by hand in
docs/performance.md with the machine and its BLAS core (`linecheck info`).
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import argparse
import dataclasses
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck import service
from linecheck.core.case import load_case
from linecheck.core.dynamics import Newmark
from linecheck.core.model import build_model, reaction_matrix_direct
from linecheck.core.spectral import davenport_gust_factor
from linecheck.core.static import drag_intensity, solve_mean_states, span_loads_uniform
from linecheck.core.system import LineSystem

CASES = ROOT / "cases" / "paper"


def timed(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def case_with(name: str, **analysis):
    case = load_case(CASES / f"{name}.toml")
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


def line_with_spans(case, spans: int):
    sup = ("strain",) + ("suspension",) * (spans - 1) + ("strain",) if spans > 1 else ("strain", "strain")
    line = dataclasses.replace(case.line, spans=spans, supports=sup, tower_of_interest=spans // 2 + 1)
    return dataclasses.replace(case, line=line)


def baseline_newmark(case) -> float:
    """Straightforward step 2: dense K_hat, factorised (solved from scratch) every step."""
    st = service.static_analysis(case)
    model = build_model(st.system, st.mean.state(0))
    K = model.K_dense
    from linecheck.core.model import band_to_dense

    M = band_to_dense(model.M_band)
    C = band_to_dense(service.damping_matrices(case, st, [model])[0])
    t = service.record_time(case)
    from linecheck.core.wind.turbulence import fluctuating_velocity

    v = fluctuating_velocity(case, st.system, t, [0])[0]
    nm = Newmark(case.analysis.time_step)
    n = K.shape[0]
    F = np.zeros(n)
    u = np.zeros(n)
    vel = np.zeros(n)
    acc = np.zeros(n)
    a = case.wind.air_density * case.line.drag_coefficient * case.line.diameter * model.tributary * case.wind.v_ref
    free = model.dofs.free_nodes
    G = model.G
    D = reaction_matrix_direct(st.system)
    start = time.perf_counter()
    for k in range(1, t.size):
        F[1::3] = a[free] * v[k, free]
        Khat = K + nm.a1 * C + nm.a0 * M
        rhs = F + M @ (nm.a0 * u + nm.a2 * vel + acc) + C @ (nm.a1 * u + vel)
        un = np.linalg.solve(Khat, rhs)
        an = nm.a0 * (un - u) - nm.a2 * vel - acc
        vel = vel + 0.5 * case.analysis.time_step * (acc + an)
        u, acc = un, an
        _ = G @ u + D @ (a * v[k])
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="skip the slow baseline and the 60-span runs")
    args = ap.parse_args()
    rows = []

    # ---- step 1, six spans, 250 downburst-like states
    case = case_with("case09-six")
    system = LineSystem(case.line)
    g = float(drag_intensity(40.0, 1.25, 1.0, 0.022))
    gy = np.stack([span_loads_uniform(system, g * np.clip(np.sin(np.pi * k / 249), 0, 1) *
                                      np.array([1.0, 1.0, 0.9, 0.8, 0.7, 0.6])) for k in range(250)])
    t250 = timed(lambda: solve_mean_states(system, np.arange(250.0), gy), 3)
    rows.append(("step 1, six spans, per state", f"{1e3 * t250 / 250:.2f} ms", "<= 5 ms", ""))
    rows.append(("step 1, six spans, 250 states", f"{t250:.2f} s", "<= 1.5 s", ""))

    # ---- one realization of the six-span synoptic case, 600 s at 0.05 s, wind included
    one = case_with("case09-six", realizations=1)
    t1 = timed(lambda: service.run_case(one), 3)
    if args.quick:
        rows.append(("steps 1-3 + wind, six spans, 1 realization", f"{t1:.2f} s", "<= 0.5 s", "baseline skipped"))
    else:
        tb = baseline_newmark(one)
        rows.append(("steps 1-3 + wind, six spans, 1 realization", f"{t1:.2f} s", "<= 0.5 s",
                     f"baseline (dense, solve every step, step 2 only) {tb:.1f} s: x{tb / t1:.0f}"))
    t10 = timed(lambda: service.run_case(case_with("case09-six", realizations=10)), 1)
    rows.append(("six spans, 10 realizations (columns of one RHS)", f"{t10:.2f} s", "", f"{t10 / t1:.1f} x one"))

    # ---- frequency domain
    st = service.static_analysis(one)
    ts = timed(lambda: service.spectral_analysis(one, static=st), 3)
    rows.append(("estimate 1 (exact), six spans", f"{ts:.3f} s", "<= 0.2 s", "incl. complex modes"))
    sm = service.synoptic_model(one, st)
    ts2 = timed(lambda: service.spectral_analysis(one, static=st, synoptic=sm), 3)
    rows.append(("estimate 1, model and modes reused", f"{ts2:.3f} s", "", "as inside run"))
    te2 = timed(lambda: davenport_gust_factor(span=300.0, v_mean=40.0, intensity=0.12, length_scale=173.3,
                                              coherence_decay=10.0, f1=0.2, mass_per_length=1.83,
                                              air_density=1.25, drag_coefficient=1.0, diameter=0.022,
                                              duration=600.0, height=43.0), 5)
    rows.append(("estimate 2 (closed form)", f"{1e3 * te2:.1f} ms", "<= 10 ms", ""))

    # ---- scaling with spans and record length (1 realization, synoptic)
    base = case_with("case09-six", realizations=1)
    spans_list = (1, 6, 20) if args.quick else (1, 6, 20, 60)
    ref = None
    for n in spans_list:
        c = line_with_spans(base, n)
        tt = timed(lambda: service.run_case(c), 1)  # noqa: B023 - called at once, in this iteration
        ref = ref or tt / max(n, 1)
        rows.append((f"scaling: {n} spans, 600 s", f"{tt:.2f} s", "linear", f"{tt / n:.3f} s per span"))
    for dur in (150.0, 600.0, 2400.0):
        c = case_with("case09-six", realizations=1, duration=dur)
        tt = timed(lambda: service.run_case(c), 1)  # noqa: B023 - called at once, in this iteration
        rows.append((f"scaling: six spans, {dur:.0f} s", f"{tt:.2f} s", "linear", f"{1e3 * tt / dur:.2f} ms per s"))

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    rows.append(("peak memory of this process", f"{rss:.0f} MB", "<= 1 GB", ""))

    w = [max(len(r[i]) for r in rows) for i in range(4)]
    print(f"machine: {os.cpu_count()} cores; {time.strftime('%Y-%m-%d')}")
    print("  ".join(h.ljust(w[i]) for i, h in enumerate(("what", "measured", "target", "baseline / note"))))
    for r in rows:
        print("  ".join(r[i].ljust(w[i]) for i in range(4)))


if __name__ == "__main__":
    main()
