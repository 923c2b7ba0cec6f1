"""linecheck's three steps against a full non-linear dynamic analysis (OpenSeesPy).

Run from the repository root (needs the ``bench`` extra: ``pip install -e '.[bench]'``):

    .venv/bin/python bench/bench_nonlinear.py                 # the six cases, full records
    .venv/bin/python bench/bench_nonlinear.py --duration 300  # shorter records
    .venv/bin/python bench/bench_nonlinear.py --cases case09-six --mesh 20 40 --dt-check --diagnostic

For every case, realization 1 (index 0): linecheck's ``run_case`` with ``damping = "quasi-steady"``
(the like-for-like model: the non-linear drag damps every direction of relative motion normal to
the conductor) and with ``"paper"`` (same record: the same burn-in is imposed, so the same wind
is synthesised), and the OpenSeesPy analysis of the same record (``bench/opensees_reference.py``:
corotational trusses, stiff insulator trusses, drag with the total relative velocity, Newmark
with Newton iterations; the same 0.2 % stiffness-proportional structural damping as the
quasi-steady default).  Statistics of the wind-induced reactions (total - still air) R_x, R_y
at the tower of interest over the analysed record:

* synoptic: mean = time average, r.m.s. = standard deviation about it, peak = max |R|;
* downburst: mean = the running-mean reaction at the instant where it is largest (linecheck:
  step 1; OpenSees: its own static equilibria under the running mean at linecheck's mean-state
  instants), r.m.s. = of R(t) - M(t), peak = max |R|.

Differences are (linecheck - OpenSees) / |OpenSees|; a mean below 1 % of the largest mean
reaction of the case is "zero by symmetry" and gets no percentage.  Options add the checks of
the investigation: finer meshes (``--mesh``), half the time step (``--dt-check``), the drag
linearised about the running mean on the non-linear structure (``--diagnostic``, splits the
difference into the structural linearisation and the drag's non-linearity), the transverse-only
drag without structural damping, the non-linear counterpart of linecheck's ``"paper"``
(``--transverse``), several realizations with a mean ± std table (``--realizations 0 1 2``).
``--json FILE`` saves every number, ``--from-json FILE`` prints the tables again.

Timing: wall time of ``service.run_case(case, realizations=[0])`` (all three steps, the wind
synthesis, burn-in and frequency-domain check included) against the OpenSeesPy analysis of
the same record (model, statics, time stepping; the wind it is fed is linecheck's, not timed),
both in this process, after a warm-up run; ``--repeat N`` takes the best of N of each, the two
alternating (linecheck, OpenSees, linecheck, ...: the shared machine's speed drifts), and also
prints the ratio of every back-to-back pair and their median,
``--ensemble N`` also times linecheck with N realizations in one run (best of ``--repeat``);
``--threads N`` gives the timed linecheck runs N threads (default 1, as OpenSees; ``linecheck run``
uses 2); ``--no-check`` times them without the frequency-domain check (an extra estimate OpenSees
does not make; the burn-in still computes its complex modes).  The numbers recorded in
docs/validation.md and docs/performance.md come from

    .venv/bin/python bench/bench_nonlinear.py --diagnostic --transverse --dt-check --mesh 20 40
    .venv/bin/python bench/bench_nonlinear.py --diagnostic --realizations 0 1 2 3 4
    .venv/bin/python bench/bench_nonlinear.py --no-paper --repeat 2 --ensemble 10
    .venv/bin/python bench/bench_nonlinear.py --no-paper --repeat 2 --ensemble 10 --fft-length fast  # fast FFT length
    .venv/bin/python bench/bench_nonlinear.py --options --no-paper --realizations 0 1 2 3 4   # drag/tension options

``--options`` adds linecheck with every combination of ``[analysis] drag`` and ``tension``
(``linecheck_quadratic_linear``, ``linecheck_linear_second-order``,
``linecheck_quadratic_second-order``; ``linecheck_quasi_steady`` is linear/linear), all with
the quasi-steady damping, against the same OpenSees analysis.  The wind reaches OpenSees through
the exported field file (``linecheck wind --field``, read by ``opensees_reference.read_field``).

An import failure of openseespy (e.g. the system BLAS/LAPACK missing) is reported in one line
and the script exits with status 2.
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
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from opensees_reference import (
    NonlinearLine,
    OpenSeesUnavailable,
    WindRecord,
    load_opensees,
    read_field,
)

from linecheck import service
from linecheck.core.case import load_case

CASES = ("case10-single", "case09-single", "case10-six", "case09-six", "case05-single", "case05-six")
COMPONENTS = ("R_x", "R_y")
STATS = ("mean", "rms", "peak")
OPTION_COMBOS = (("linear", "linear"), ("quadratic", "linear"), ("linear", "second-order"),
                 ("quadratic", "second-order"))
ZERO_MEAN = 0.01  # a mean below 1 % of the case's largest mean reaction is zero (by symmetry), as in linecheck


def field_wind(case, realization: int) -> WindRecord:
    """linecheck's wind for ``case`` and ``realization`` (0-based) through the exported field
    file (``linecheck wind --field``; the same arrays, via the service layer) read back by the
    OpenSees reference."""
    import tempfile

    fld = service.wind_field(case, realization=realization)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "field.npz"
        np.savez(path, **fld.to_npz_dict())
        return read_field(path)


def with_analysis(case, **changes):
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **changes))


def structural_beta(case, st) -> float:
    """beta = 2 zeta_s / omega_1 exactly as linecheck calibrates it (service.damping_matrices)."""
    from linecheck.core.model import build_model
    from linecheck.core.modes import natural_modes

    zs = case.analysis.structural_ratio
    if zs <= 0:
        return 0.0
    k = service.reference_state_index(case, st.mean)
    w1 = 2 * np.pi * float(natural_modes(build_model(st.system, st.mean.state(k)), 1).frequencies_hz[0])
    return 2.0 * zs / w1


def statistics(R: np.ndarray, M: np.ndarray | None) -> dict:
    """mean / rms / peak of the wind-induced R (n, 3) over the analysed steps (module docstring)."""
    out = {}
    for c, name in enumerate(COMPONENTS):
        x = R[:, c]
        if M is None:  # synoptic
            mean = float(x.mean())
            rms = float(x.std())
        else:
            k = int(np.argmax(np.abs(M[:, c])))
            mean = float(M[k, c])
            rms = float(np.sqrt(np.mean((x - M[:, c]) ** 2)))
        out[name] = {"mean": mean, "rms": rms, "peak": float(np.max(np.abs(x)))}
    return out


def linecheck_history(res) -> tuple[np.ndarray, np.ndarray]:
    """Wind-induced total reaction M + B + R and the mean M at the tower of interest, (n, 3) each."""
    j = res.tower_index
    M = res.mean[:, j, :]
    return M + res.background[0] + res.resonant[0], M


def diff_pct(a: float, ref: float, stats: dict, stat: str) -> float | None:
    """(a - ref) / |ref| in %; None for a mean that is zero by symmetry (below 1 % of the largest
    mean reaction of the reference statistics ``stats``)."""
    largest = max(abs(stats[c]["mean"]) for c in COMPONENTS)
    if stat == "mean" and abs(ref) < ZERO_MEAN * largest:
        return None
    return 100.0 * (a - ref) / abs(ref) if ref != 0 else None


def nl_mean_history(case, res, wind: WindRecord, n_el: int) -> np.ndarray:
    """OpenSees static reactions under the running mean at linecheck's mean-state instants,
    interpolated to the analysed record (downburst), wind-induced, tower of interest (n, 3)."""
    st = res.static
    vn = service.to_global_nodes(st.system, st.wind.normal)  # (n_k, n_nodes)
    Rk, still = NonlinearLine(case, n_el=n_el).mean_states(vn)
    j = res.tower_index
    Rw = Rk[:, j, :] - still[j]
    t = wind.time[wind.keep]
    return np.stack([np.interp(t, st.mean.time, Rw[:, c]) for c in range(3)], axis=1)


def run_nl(case, wind, res, *, n_el, drag="crossflow", beta=0.0, substeps=1, label=""):
    j = res.tower_index
    model = NonlinearLine(case, n_el=n_el, drag=drag, structural_beta=beta)
    t0 = time.perf_counter()

    def prog(n, total):
        if n % max(1, total // 10) < max(1, total // 50):
            print(f"    {label}: {100 * n / total:3.0f} %  ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)

    nl = model.run(wind, substeps=substeps, progress=prog)
    Rw = nl.wind_induced[nl.keep, j, :]
    return nl, Rw


def fmt(x: float | None, w: int = 7) -> str:
    return f"{'—':>{w}}" if x is None else f"{x:+{w}.1f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    ap.add_argument("--duration", type=float, default=None, help="shorten every record to this many seconds")
    ap.add_argument("--realizations", type=int, nargs="+", default=[0],
                    help="0-based realization indices (default 0 = realization 1); several give a spread table")
    ap.add_argument("--mesh", type=int, nargs="*", default=[], help="extra OpenSees runs with these elements per span")
    ap.add_argument("--dt-check", action="store_true", help="extra OpenSees run at dt/2")
    ap.add_argument("--diagnostic", action="store_true", help="extra run with the drag linearised about the mean")
    ap.add_argument("--transverse", action="store_true", help="extra run with the transverse-only drag, no structural damping")
    ap.add_argument("--options", action="store_true",
                    help="also linecheck with drag = quadratic and/or tension = second-order")
    ap.add_argument("--no-paper", action="store_true", help="skip linecheck's \"paper\" damping")
    ap.add_argument("--repeat", type=int, default=1, help="time both analyses best of N")
    ap.add_argument("--fft-length", choices=("record", "fast"), default="record",
                    help='[wind] fft_length of the cases (default "record", as the paper cases pin it)')
    ap.add_argument("--ensemble", type=int, default=0,
                    help="also time linecheck with this many realizations in one run (vs N OpenSees runs)")
    ap.add_argument("--threads", type=int, default=1,
                    help="threads of the timed linecheck runs (service.run_case; default 1, OpenSees runs on one; "
                         "`linecheck run` uses 2: the frequency-domain check beside the time domain)")
    ap.add_argument("--no-check", action="store_true",
                    help="time linecheck without the frequency-domain check (the time-domain analysis alone, "
                         "what OpenSees computes; the burn-in's complex modes are still computed)")
    ap.add_argument("--json", type=Path, default=None, help="save all numbers here")
    ap.add_argument("--from-json", type=Path, nargs="+", default=None,
                    help="print the tables of saved --json files instead of running")
    args = ap.parse_args(argv)
    if args.from_json:
        results = [e for f in args.from_json for e in json.loads(f.read_text())]
        for e in results:
            e.setdefault("realization", 1)
            print(f"\n== {e['case']}, realization {e['realization']}")
            print_case(e)
        print("\n" + summary_table(results))
        if len({e["realization"] for e in results}) > 1:
            print("\n" + spread_table(results))
        return 0

    try:
        load_opensees()
    except OpenSeesUnavailable as exc:
        print(f"bench_nonlinear: {exc}", file=sys.stderr)
        return 2

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}; python {platform.python_version()}, numpy {np.__version__}")
    # warm-up: imports and first-call costs of both codes, on a tiny record
    warm = with_analysis(load_case(ROOT / "cases" / "paper" / "case10-single.toml"), duration=5.0,
                         damping="quasi-steady")
    service.run_case(warm, realizations=[0])
    service.run_case(warm, realizations=[0, 1])  # the several-realization loop loaded too (--ensemble)
    NonlinearLine(warm).run(field_wind(warm, 0))

    results = []
    for name in args.cases:
        for r in args.realizations:
            results.append(run_one(name, r, args))
    print("\n" + summary_table(results))
    if len(args.realizations) > 1:
        print("\n" + spread_table(results))
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1))
    return 0


def run_one(name: str, r: int, args) -> dict:
    """linecheck (quasi-steady, paper) and OpenSees (+ the requested checks) for one case and realization."""
    base = load_case(ROOT / "cases" / "paper" / f"{name}.toml")
    changes = {"damping": "quasi-steady", "drag": "linear", "tension": "linear"}
    if args.duration is not None:
        changes["duration"] = args.duration
    case = with_analysis(base, **changes)
    if args.fft_length != case.wind.fft_length:  # the synthesis length (docs/wind.md; OpenSees gets the same wind)
        case = dataclasses.replace(case, wind=dataclasses.replace(case.wind, fft_length=args.fft_length))
    print(f"\n== {name}, realization {r + 1}: {base.description}", flush=True)
    t0 = time.perf_counter()
    res = service.run_case(case, realizations=[r], threads=args.threads, spectral_check=not args.no_check)
    t_lc = time.perf_counter() - t0
    burn = res.burn_in.seconds
    wind = field_wind(case, r)
    if not np.allclose(wind.time[wind.keep], res.time, rtol=0, atol=1e-9):
        raise SystemExit(f"{name}: record grid differs from linecheck's")
    R_lc, M_lc = linecheck_history(res)
    synoptic = case.wind.type == "synoptic"
    beta = structural_beta(case, res.static)
    ne = case.line.elements_per_span
    nl, R_nl = run_nl(case, wind, res, n_el=ne, beta=beta, label=f"{name} OpenSees")
    # best of --repeat of each, the two analyses alternating (the shared VM's speed drifts by up to
    # 2x within minutes: both bests then come from the same stretch of time); also the ratio of
    # every back-to-back pair, whose median drift moves least
    pairs = [nl.wall / t_lc]
    for _ in range(args.repeat - 1):  # same record, same answer
        t0 = time.perf_counter()
        service.run_case(case, realizations=[r], threads=args.threads, spectral_check=not args.no_check)
        t_i = time.perf_counter() - t0
        t_lc = min(t_lc, t_i)
        again, _r = run_nl(case, wind, res, n_el=ne, beta=beta, label=f"{name} OpenSees (timing)")
        pairs.append(again.wall / t_i)
        if again.wall < nl.wall:
            nl = again
    M_nl = None if synoptic else nl_mean_history(case, res, wind, ne)
    if synoptic:  # step 1 against the OpenSees statics under the mean wind alone
        Rs, still = NonlinearLine(case, n_el=ne).mean_states(
            service.to_global_nodes(res.static.system, res.static.wind.normal))
        j = res.tower_index
        step1 = res.static.mean.reactions_wind[0, j]
        nls = Rs[0, j] - still[j]
        print(f"  mean-wind statics: linecheck step 1 R_x {step1[0]:.1f} N, R_y {step1[1]:.1f} N; "
              f"OpenSees R_x {nls[0]:.1f} N, R_y {nls[1]:.1f} N", flush=True)
    entry = {
        "case": name, "realization": r + 1, "type": case.wind.type, "spans": case.line.spans, "v_ref": case.wind.v_ref,
        "tower": case.line.tower_of_interest, "record_s": float(res.time[-1] - res.time[0]),
        "burn_in_s": burn, "steps": int(wind.time.size), "beta": beta,
        "time_linecheck_s": t_lc, "threads": args.threads, "check": not args.no_check,
        "pair_ratios": pairs, "ratio_pairs_median": float(np.median(pairs)), "time_opensees_s": nl.wall, "ratio": nl.wall / t_lc,
        "time_opensees_solver_s": nl.solver_wall,
        "newton_iterations_per_step": float(nl.iterations[1:].mean()),
        "stats": {
            "opensees": statistics(R_nl, M_nl),
            "linecheck_quasi_steady": statistics(R_lc, None if synoptic else M_lc),
        },
    }
    if args.options:  # every drag/tension combination (quasi-steady damping), same wind
        for drag, tension in OPTION_COMBOS[1:]:
            co = with_analysis(case, drag=drag, tension=tension, burn_in=burn)  # same record, same wind
            ro = service.run_case(co, realizations=[r])
            Ro, Mo = linecheck_history(ro)
            entry["stats"][f"linecheck_{drag}_{tension}"] = statistics(Ro, None if synoptic else Mo)
    if not args.no_paper:
        cp = with_analysis(case, damping="paper", burn_in=burn)  # same record, same wind
        rp = service.run_case(cp, realizations=[r])
        Rp, Mp = linecheck_history(rp)
        entry["stats"]["linecheck_paper"] = statistics(Rp, None if synoptic else Mp)
    extra = []
    for n_el in args.mesh:
        extra.append((f"opensees_ne{n_el}", dict(n_el=n_el, beta=beta)))
    if args.dt_check:
        extra.append(("opensees_dt_half", dict(n_el=ne, beta=beta, substeps=2)))
    if args.diagnostic:
        extra.append(("opensees_linear_drag", dict(n_el=ne, beta=beta, drag="crossflow-linear")))
    if args.transverse:
        extra.append(("opensees_transverse", dict(n_el=ne, beta=0.0, drag="transverse")))
    for key, kw in extra:
        nle, Re = run_nl(case, wind, res, label=f"{name} {key}", **kw)
        Me = M_nl
        if not synoptic and kw["n_el"] != ne:
            Me = nl_mean_history(case, res, wind, kw["n_el"])
        entry["stats"][key] = statistics(Re, Me)
        entry[f"time_{key}_s"] = nle.wall
    if args.ensemble > 1:
        te = np.inf
        for _ in range(args.repeat):  # best of --repeat, as the one-realization time
            t0 = time.perf_counter()
            service.run_case(case, realizations=list(range(args.ensemble)), threads=args.threads,
                             spectral_check=not args.no_check)
            te = min(te, time.perf_counter() - t0)
        entry["ensemble"] = args.ensemble
        entry["time_linecheck_ensemble_s"] = te
        entry["ratio_ensemble"] = args.ensemble * nl.wall / te
        print(f"  linecheck with {args.ensemble} realizations: {te:.2f} s; {args.ensemble} OpenSees records "
              f"~{args.ensemble * nl.wall:.0f} s: ratio {entry['ratio_ensemble']:.0f}x", flush=True)
    print_case(entry)
    if len(pairs) > 1:
        print(f"  back-to-back pairs (OpenSees / linecheck): {', '.join(f'{p:.1f}' for p in pairs)}; "
              f"median {np.median(pairs):.1f}x", flush=True)
    print(f"  time: linecheck {t_lc:.2f} s ({args.threads} thread(s){', no check' if args.no_check else ''}), OpenSees {nl.wall:.1f} s (of which analyze {nl.solver_wall:.1f} s; "
          f"{entry['steps']} steps, "
          f"{entry['newton_iterations_per_step']:.1f} Newton iterations/step): ratio {entry['ratio']:.1f}x",
          flush=True)
    return entry


def print_case(e: dict) -> None:
    ref = e["stats"]["opensees"]
    keys = [k for k in e["stats"] if k != "opensees"]
    print(f"  {'':>4} {'stat':>5} {'OpenSees':>10} " + " ".join(f"{k[:22]:>24}" for k in keys))
    for c in COMPONENTS:
        for s in STATS:
            v = ref[c][s]
            cells = []
            for k in keys:
                x = e["stats"][k][c][s]
                d = diff_pct(x, v, ref, s)
                cells.append(f"{x / 1e3:9.3f} ({fmt(d, 6)} %)".rjust(24))
            print(f"  {c:>4} {s:>5} {v / 1e3:10.3f} " + " ".join(cells))


def summary_table(results: list[dict]) -> str:
    """Markdown table: OpenSees vs linecheck (quasi-steady; paper), kN and %."""
    lines = ["| case | real. | reaction | stat | OpenSees [kN] | linecheck quasi-steady [kN] | diff | "
             "linecheck paper [kN] | diff |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for e in results:
        ref = e["stats"]["opensees"]
        for c in COMPONENTS:
            for s in STATS:
                v = ref[c][s]
                row = [e["case"], str(e["realization"]), c, s, f"{v / 1e3:.3f}"]
                for k in ("linecheck_quasi_steady", "linecheck_paper"):
                    if k in e["stats"]:
                        x = e["stats"][k][c][s]
                        d = diff_pct(x, v, ref, s)
                        row += [f"{x / 1e3:.3f}", "—" if d is None else f"{d:+.1f} %"]
                    else:
                        row += ["", ""]
                lines.append("| " + " | ".join(row) + " |")
    lines.append("")
    lines.append("| case | real. | steps | linecheck [s] | OpenSees [s] | ratio |")
    lines.append("| --- | --- | --- | --- | --- | --- |")
    for e in results:
        lines.append(f"| {e['case']} | {e['realization']} | {e['steps']} | {e['time_linecheck_s']:.2f} | "
                     f"{e['time_opensees_s']:.1f} | {e['ratio']:.1f}× |")
    return "\n".join(lines)


def spread_table(results: list[dict]) -> str:
    """Mean and standard deviation over the realizations of every difference (%) and column."""
    keys = [k for k in results[0]["stats"] if k != "opensees"]
    lines = ["difference (%) against OpenSees, mean ± std over realizations",
             "| case | reaction | stat | " + " | ".join(keys) + " |",
             "| --- | --- | --- | " + " | ".join("---" for _ in keys) + " |"]
    for name in dict.fromkeys(e["case"] for e in results):
        es = [e for e in results if e["case"] == name]
        for c in COMPONENTS:
            for s in STATS:
                cells = []
                for k in keys:
                    d = [diff_pct(e["stats"][k][c][s], e["stats"]["opensees"][c][s],
                                  e["stats"]["opensees"], s) for e in es]
                    d = [x for x in d if x is not None]
                    cells.append("—" if not d else f"{np.mean(d):+.1f} ± {np.std(d, ddof=1) if len(d) > 1 else 0:.1f}")
                lines.append(f"| {name} | {c} | {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
