"""Benchmark of the downburst mean-state models built in one vectorised pass.

Run from the repository root:  ``.venv/bin/python bench/bench_downburst_build.py [--case ...] [--repeat 5]``

Target: one six-span downburst realization >= 30x faster than OpenSeesPy (8.6x with
the one-state-at-a-time code; bench/bench_nonlinear.py measures that ratio).  This script
measures, in one process, interleaved and best of ``--repeat``, the phases vectorised
across the n_k mean states against the one-state-at-a-time code they replace:

- models: ``[build_model(system, s) for s in states]`` vs ``build_models(system, states)``;
- damping: ``aerodynamic_damping`` (+ structural) state by state vs the stacked functions;
- steppers: ``_Stepper.build`` state by state (node bases, two band rotations, dpbtrf) vs
  ``_rotated_stack`` (batched eigh and rotations) + ``_Stepper.from_bases`` (dpbtrf per state);
- realization: one full ``service.run_case(case, realizations=[0])`` with the one-by-one
  functions patched back in (before) vs as shipped (after).

Both sides give bit-identical results (tests/core/test_build_models.py); the script checks the
realization's reactions are equal.  With ``--baseline REV`` (default: fe644a7, the last commit
with the one-state-at-a-time code) the package as it was at REV is also extracted
(``git archive``) and imported under another name, and its ``run_case`` is timed in the same
loop: the speed-up of the whole realization over the code at REV, whatever else changed.
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
    ap.add_argument("--case", default="cases/paper/case05-six.toml")
    ap.add_argument("--repeat", type=int, default=5, help="interleaved runs per variant (best is reported)")
    ap.add_argument("--threads", type=int, default=1, help="BLAS threads")
    ap.add_argument("--baseline", default="fe644a7", help="git revision timed as the baseline ('' = none)")
    args = ap.parse_args()
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(args.threads)

    import contextlib
    import time
    from pathlib import Path

    import numpy as np

    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root))
    from linecheck import service
    from linecheck.core import damping as dmod
    from linecheck.core import dynamics
    from linecheck.core.case import load_case
    from linecheck.core.model import build_model, build_models, rotate_band

    case = load_case(root / args.case)
    st = service.static_analysis(case)
    system, mean = st.system, st.mean
    states = [mean.state(k) for k in range(mean.time.size)]
    nm = dynamics.Newmark(case.analysis.time_step)

    # ---- the one-state-at-a-time code (before the vectorised pass), from the per-state functions
    def models_before():
        return [build_model(system, s) for s in states]

    def aero_before(case_, models, vn_, nodes):
        return np.stack([dmod.aerodynamic_damping(case_, m, vn_[k], nodes[k]) for k, m in enumerate(models)])

    def structural_before(models, ratio, w1):
        return np.stack([dmod.stiffness_proportional(m, ratio, w1) for m in models])

    class BasesBefore:
        def __init__(self, models, damping, order):
            self.models, self.damping = models, damping

        def get(self, k):
            T = dynamics.node_bases(self.models[k], self.damping[k])
            return T, rotate_band(self.models[k].K_band, T), rotate_band(self.damping[k], T)

    @contextlib.contextmanager
    def one_by_one():
        saved = (service.build_models, service.aerodynamic_damping_stack, service.stiffness_proportional_stack,
                 dynamics._StackedBases)
        service.build_models = lambda system_, states_: [build_model(system_, s) for s in states_]
        service.aerodynamic_damping_stack, service.stiffness_proportional_stack = aero_before, structural_before
        dynamics._StackedBases = BasesBefore
        try:
            yield
        finally:
            (service.build_models, service.aerodynamic_damping_stack, service.stiffness_proportional_stack,
             dynamics._StackedBases) = saved

    models = build_models(system, states)
    C = service.damping_matrices(case, st, models)

    def damping_before():
        with one_by_one():
            return service.damping_matrices(case, st, models)

    def steppers_before():
        return [dynamics._Stepper.build(m, C[k], nm) for k, m in enumerate(models)]

    def steppers_after():
        T, Kr, Cr = dynamics._rotated_stack(models, C)
        return [dynamics._Stepper.from_bases(m, T[k], Kr[k], Cr[k], nm) for k, m in enumerate(models)]

    def run_before():
        with one_by_one():
            return service.run_case(case, realizations=[0])

    def run_after():
        return service.run_case(case, realizations=[0])

    base_run = None
    if args.baseline:
        import atexit
        import importlib
        import io
        import shutil
        import subprocess
        import tarfile
        import tempfile

        tmp = Path(tempfile.mkdtemp(prefix="lc-baseline-"))
        atexit.register(shutil.rmtree, tmp, True)
        tar = subprocess.run(["git", "-C", str(root), "archive", args.baseline, "linecheck"],
                             capture_output=True, check=True).stdout
        with tarfile.open(fileobj=io.BytesIO(tar)) as archive:
            archive.extractall(tmp, filter="data")
        (tmp / "linecheck").rename(tmp / "linecheck_baseline")  # its imports are relative
        sys.path.insert(0, str(tmp))
        base_service = importlib.import_module("linecheck_baseline.service")
        base_case = importlib.import_module("linecheck_baseline.core.case").load_case(root / args.case)

        def base_run():
            return base_service.run_case(base_case, realizations=[0])

    phases = [
        ("models (build_model x n_k)", models_before, lambda: build_models(system, states)),
        ("damping matrices", damping_before, lambda: service.damping_matrices(case, st, models)),
        ("steppers (bases, rotations, dpbtrf)", steppers_before, steppers_after),
        ("one realization (run_case)", run_before, run_after),
    ]
    if base_run is not None:
        phases.append((f"one realization, code at {args.baseline}", base_run, run_after))
    best = {name: [float("inf"), float("inf")] for name, _, _ in phases}
    out = {}
    for _ in range(args.repeat):
        for name, before, after in phases:
            for i, f in enumerate((before, after)):
                t0 = time.perf_counter()
                out[name, i] = f()
                best[name][i] = min(best[name][i], time.perf_counter() - t0)
    r0, r1 = out["one realization (run_case)", 0], out["one realization (run_case)", 1]
    identical = all(np.array_equal(getattr(r0, f), getattr(r1, f)) for f in ("mean", "background", "resonant"))
    if base_run is not None:
        rb = out[phases[-1][0], 0]
        identical &= all(np.array_equal(getattr(rb, f), getattr(r1, f)) for f in ("mean", "background", "resonant"))
    print(f"{case.name}: {mean.time.size} mean states, {system.n_spans} spans, "
          f"{models[0].dofs.n_dof} DOFs, best of {args.repeat}, {args.threads} BLAS thread(s)")
    print(f"{'phase':<40}{'before s':>10}{'after s':>10}{'speed-up':>10}")
    for name, _, _ in phases:
        b, a = best[name]
        print(f"{name:<40}{b:10.3f}{a:10.3f}{b / a:10.2f}")
    print(f"realization reactions bit-identical before/after{' and to the baseline' if base_run else ''}: {identical}")


if __name__ == "__main__":
    main()
