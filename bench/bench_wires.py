"""Every wire in one correlated wind against one wire of the same section (issue 37's speed target).

Run from the repository root:

    .venv/bin/python bench/bench_wires.py                   # 10 realizations, median of 3 pairs
    .venv/bin/python bench/bench_wires.py -n 4 --repeat 5   # other sizes
    .venv/bin/python bench/bench_wires.py --no-memory       # skip the traced memory runs

Times, in this process and back to back (the order alternates from pair to pair):

- **all wires**: ``run_wires`` of cases/examples/section-12span-double-circuit.toml (the 12-span
  section carrying 6 twin-bundle phases and 2 ground wires: 8 wires in one correlated field), or,
  where that example is absent, the same layout written here from section-12span.toml;
- **one wire**: ``run_case`` of the first phase's single-wire case (``wire_case``) with no
  frequency-domain check and the same realizations.

Both on one thread, with the turbulence memo off (``LINECHECK_UNIT_FIELD_MEMO=0``) and the
compiled kernel as installed.  The table gives each pair's times and ratio and their medians, the
parts of the medians (step 1 and the plans, the wind field, steps 2-3, everything else: the
statistics, the totals and the load trees) and the peak memory of one traced run of each
(tracemalloc: numpy's arrays included).  Target: the ratio of the medians <= 8 (the best
times' ratio is printed beside it: the one-wire run, a few seconds, carries most of the noise).
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import argparse
import platform
import statistics
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck.analysis import run as run_mod
from linecheck.analysis import wires_run
from linecheck.core import pieces
from linecheck.core.case import load_case, wire_case
from linecheck.core.wind import turbulence

EXAMPLE = ROOT / "cases" / "examples" / "section-12span-double-circuit.toml"
TARGET = 8.0

# the fallback layout (where the shipped example is absent): per tower type (height above ground
# of the phases' top crossarm) the attachments of circuits 1 (y > 0) and 2, and two ground wires
_PHASES = [("A1", 5.5, 0.0), ("B1", 5.5, -7.0), ("C1", 5.5, -14.0),
           ("A2", -5.5, 0.0), ("B2", -5.5, -7.0), ("C2", -5.5, -14.0)]
_GROUNDS = [("G1", 4.0, 7.0), ("G2", -4.0, 7.0)]


def _fallback_case(folder: Path) -> Path:
    """The 8-wire layout of the shipped example, written from section-12span.toml's towers."""
    rows = [r.split(",") for r in (ROOT / "cases" / "examples" / "section-12span.csv").read_text().splitlines()
            if r and not r.startswith("#")][1:]
    types, towers = {}, []
    for name, station, ground, height, support, angle, ins in rows:
        top = float(height) + 15.0
        key = f"{support}-{top:g}" + (f"-{ins}" if ins and ins != "4.2" else "")
        att = [f'{{ wire = "{w}", y = {y}, z = {top + dz}, support = "{support}"'
               + (f", insulator_length = {ins}" if support == "suspension" and ins and ins != "4.2" else "") + " }"
               for w, y, dz in _PHASES]
        att += [f'{{ wire = "{w}", y = {y}, z = {top + dz}, support = "{support}"'
                + (", insulator_length = 0.3" if support == "suspension" else "") + " }" for w, y, dz in _GROUNDS]
        types[key] = att
        towers.append(f"{name},{station},{ground},{angle},{key}")
    (folder / "towers.csv").write_text("name,station,ground,angle,type\n" + "\n".join(towers) + "\n")
    wires = "".join(f'[[wires]]\nname = "{w}"\nkind = "phase"\nweight = 17.92\ndiameter = 0.022\narea = 0.7e-4\n'
                    f'elastic_modulus = 5.2e10\ntension = 22000.0\nbundle = 2\nbundle_spacing = 0.4\n\n'
                    for w, _, _ in _PHASES)
    wires += "".join(f'[[wires]]\nname = "{w}"\nkind = "ground"\nweight = 5.0\ndiameter = 0.013\narea = 0.6e-4\n'
                     f'elastic_modulus = 1.2e11\ntension = 7200.0\n\n' for w, _, _ in _GROUNDS)
    kinds = "".join(f'[[tower_types]]\nname = "{k}"\nattachments = [{", ".join(v)}]\n\n' for k, v in types.items())
    text = (f'name = "section-12span-8-wires"\n[line]\ninsulator_length = 4.0\ntowers_file = "towers.csv"\n'
            f'tower_of_interest = 7\nelements_per_span = 10\n\n{wires}{kinds}'
            '[wind]\ntype = "synoptic"\nv_ref = 35.0\ndirection = 30.0\nprofile_exponent = 0.16\n'
            'reference_height = 10.0\nturbulence_intensity = 0.15\n\n'
            '[analysis]\nduration = 600.0\ntime_step = 0.05\nrealizations = 10\nseed = 2026\n')
    path = folder / "section-12span-8-wires.toml"
    path.write_text(text)
    return path


class _Parts:
    """Wall time spent in the runs' parts (the wrapped functions; nested calls are not counted twice)."""

    def __init__(self) -> None:
        self.spent: dict[str, float] = {}
        self.depth = 0

    def wrap(self, module, name: str, part: str) -> None:
        fn = getattr(module, name)

        def timed(*a, **k):
            self.depth += 1
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.depth -= 1
                if self.depth == 0:
                    self.spent[part] = self.spent.get(part, 0.0) + time.perf_counter() - t

        setattr(module, name, timed)


def _median(xs):
    return statistics.median(xs)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", "--realizations", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3, help="back-to-back pairs (default 3)")
    ap.add_argument("--no-memory", action="store_true", help="skip the traced runs for the peak memory")
    args = ap.parse_args(argv)

    tmp = None
    path = EXAMPLE
    if not path.exists():
        tmp = tempfile.TemporaryDirectory()
        path = _fallback_case(Path(tmp.name))
    case = load_case(path)
    first = next(w.name for w in case.wires if w.kind == "phase")
    one = wire_case(case, first)
    real = list(range(args.realizations))

    parts = _Parts()
    for module in (run_mod, wires_run):
        parts.wrap(module, "plan_run", "step 1, plans")
        parts.wrap(module, "chunk_response", "steps 2-3")
    parts.wrap(turbulence, "fluctuating_velocity", "wind field")  # imported by run.chunk_velocity per call
    parts.wrap(wires_run, "fluctuating_velocity_wires", "wind field")

    def run_all():
        return wires_run.run_wires(case, realizations=real, threads=1)

    def run_one():
        return run_mod.run_case(one, realizations=real, spectral_check=False, threads=1)

    states = pieces.status()
    on = sum(p.on for p in states)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average "
          f"{os.getloadavg()[0]:.1f}; python {platform.python_version()}, numpy {np.__version__}; "
          f"kernel pieces on: {on}/{len(states)}")
    print(f"case: {path.relative_to(ROOT) if tmp is None else path.name + ' (written: the example is absent)'}, "
          f"{len(case.wires)} wires, {case.line.spans} spans; one wire: {first!r}; {args.realizations} realizations, "
          f"{case.analysis.duration:g} s at {case.analysis.time_step:g} s, one thread, no frequency-domain check")
    run_mod.run_case(one, realizations=[0], spectral_check=False, threads=1)  # warm-up: kernel, caches

    rows, split = [], {"all": [], "one": []}
    for k in range(args.repeat):
        order = ("all", "one") if k % 2 == 0 else ("one", "all")
        got = {}
        for which in order:
            parts.spent = {}
            t0 = time.perf_counter()
            (run_all if which == "all" else run_one)()
            got[which] = time.perf_counter() - t0
            split[which].append(dict(parts.spent, total=got[which]))
        rows.append((got["all"], got["one"]))
        print(f"  pair {k + 1} ({order[0]} first): all wires {got['all']:7.2f} s, one wire {got['one']:6.2f} s, "
              f"ratio {got['all'] / got['one']:5.2f}", flush=True)

    t_all, t_one = _median([r[0] for r in rows]), _median([r[1] for r in rows])
    ratios = [a / b for a, b in rows]
    names = ["step 1, plans", "wind field", "steps 2-3"]
    print()
    print(f"{'run':<26} {'median s':>9} " + " ".join(f"{n:>14}" for n in names) + f" {'rest':>8}")
    for which, label, t in (("all", f"all {len(case.wires)} wires (run_wires)", t_all),
                            ("one", f"one wire {first} (run_case)", t_one)):
        med = {n: _median([s.get(n, 0.0) for s in split[which]]) for n in names}
        rest = _median([s["total"] - sum(s.get(n, 0.0) for n in names) for s in split[which]])
        print(f"{label:<26} {t:>9.2f} " + " ".join(f"{med[n]:>14.2f}" for n in names) + f" {rest:>8.2f}")
    ratio = t_all / t_one
    best = min(r[0] for r in rows) / min(r[1] for r in rows)
    print(f"ratio of the medians {ratio:.2f} (pairs: {', '.join(f'{r:.2f}' for r in ratios)}; median pair "
          f"{_median(ratios):.2f}; best times {best:.2f}); target <= {TARGET:g}: {'met' if ratio <= TARGET else 'NOT MET'}")

    if not args.no_memory:
        for which, fn in (("all wires", run_all), ("one wire", run_one)):
            tracemalloc.start()
            fn()
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            print(f"peak traced memory, {which}: {peak / 1e6:.0f} MB")
        import resource

        print(f"process peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
    if not all(p.on for p in states):
        print("kernel pieces off: " + ", ".join(f"{p.name} ({p.reason})" for p in states if not p.on))
    if tmp is not None:
        tmp.cleanup()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
