"""Golden results: regenerate or check the committed statistics of every shipped case.

    python tools/golden.py --write          # regenerate tests/golden/*.json from the code as it is
    python tools/golden.py                  # recompute every case, print what moved; exit 1 above the tolerance
    python tools/golden.py -k section -v    # only the cases whose name contains "section", every moved quantity

Each golden file holds the statistics of ``linecheck run CASE -n 2`` (the paper cases, the
examples, and one ``--until`` run); the check recomputes them and prints, per case, the quantities
that moved and the largest relative change of each (relative to the largest |value| of that
quantity's array).  The tolerance, what the files hold and when to regenerate them:
docs/testing.md, "Golden results"; the flattening and the comparison: tests/golden_support.py.
Run from the repository root; ``PYTHONPATH=<another checkout>`` checks that checkout's code
against these files.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _support():
    """tests/golden_support.py of this checkout, loaded by its path: ``sys.path`` is left alone, so
    a ``PYTHONPATH`` naming another checkout decides which linecheck runs (and its ``tests``
    package, which may not have the module, is not the one imported)."""
    spec = importlib.util.spec_from_file_location("golden_support", ROOT / "tests" / "golden_support.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


gs = _support()


def code_version() -> str | None:
    """The commit of the linecheck package that runs (``+dirty`` with local changes), or None."""
    import linecheck

    where = Path(linecheck.__file__).resolve().parent
    try:
        head = subprocess.run(["git", "-C", str(where), "rev-parse", "--short=7", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(where), "status", "--porcelain", "--", "."], capture_output=True,
                               text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return head + ("+dirty" if dirty else "")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", action="store_true", help="regenerate the golden files instead of checking them")
    ap.add_argument("-k", dest="select", default=None, help="only the cases whose name contains this text")
    ap.add_argument("-v", "--verbose", action="store_true", help="list every quantity that moved, not the 3 largest")
    ap.add_argument("--rtol", type=float, default=gs.RTOL, help=f"tolerance (default {gs.RTOL:g})")
    ap.add_argument("--summary", type=Path, default=None,
                    help="write the largest change per case (and per quantity) to this JSON file")
    args = ap.parse_args(argv)

    import linecheck

    code = code_version()
    print(f"linecheck from {Path(linecheck.__file__).resolve().parent} (code {code or 'unknown'})", flush=True)
    if args.write:
        cases = [g for g in gs.golden_cases() if args.select is None or args.select in g.name]
    else:
        cases = [gs.load(p)[0] for p in gs.golden_files()]
        cases = [g for g in cases if args.select is None or args.select in g.name]
        if not cases:
            print("no golden files (python tools/golden.py --write)", file=sys.stderr)
            return 2
        have = {g.name for g in cases}
        for g in gs.golden_cases():
            if g.name not in have and (args.select is None or args.select in g.name):
                print(f"{g.name}: no golden file ({g.command()}; python tools/golden.py --write -k {g.name})")
    if args.write:
        gs.GOLDEN_DIR.mkdir(parents=True, exist_ok=True)

    failed: list[str] = []
    summary: dict[str, dict] = {}
    t_all = time.perf_counter()
    for gc in cases:
        t0 = time.perf_counter()
        doc = gs.run_json(gc)
        dt = time.perf_counter() - t0
        if args.write:
            rec = gs.record(gc, doc, code=code)
            gc.path.write_text(gs.render(rec), encoding="utf-8")
            print(f"{gc.name}: wrote {gc.path.relative_to(ROOT)} ({len(rec['values'])} quantities, {dt:.1f} s)",
                  flush=True)
            continue
        _, rec = gs.load(gc.path)
        cmp = gs.compare(gc.name, rec["values"], doc, args.rtol)
        big = cmp.largest
        state = "ok" if cmp.ok else "FAILED"
        head = (f"{gc.name}: {state}, {len(cmp.moves)} of {cmp.n_quantities} quantities moved"
                + (f", largest {big.change:.3g} ({big.quantity})" if big else "") + f" [{dt:.1f} s]")
        print(head, flush=True)
        shown = cmp.moves if args.verbose else cmp.moves[:3]
        for m in shown:
            flag = f"  > {m.rtol:g}" if m.failed else ""
            print(f"    {m.change:9.3g}  {m.quantity}   ({m.path}: {m.golden!r} -> {m.new!r}){flag}")
        if not args.verbose and len(cmp.moves) > 3:
            print(f"    ... {len(cmp.moves) - 3} more moved (-v lists them)")
        extra = [m for m in cmp.failures if m not in shown]
        for m in extra:
            print(f"    {m.change:9.3g}  {m.quantity}   ({m.path}: {m.golden!r} -> {m.new!r})  > {m.rtol:g}")
        for q in cmp.missing:
            print(f"    missing: {q} (in the golden file, not in the recomputed document)")
        if cmp.added:
            print(f"    new quantities (not in the golden file, not compared): {', '.join(cmp.added[:5])}"
                  + (" ..." if len(cmp.added) > 5 else ""))
        if not cmp.ok:
            failed.append(gc.name)
        summary[gc.name] = {"ok": cmp.ok, "largest": big.change if big else 0.0,
                            "quantity": big.quantity if big else None,
                            "moves": {m.quantity: m.change for m in cmp.moves}}
    total = time.perf_counter() - t_all
    if args.summary is not None:
        args.summary.write_text(json.dumps({"code": code, "rtol": args.rtol, "cases": summary}, indent=1,
                                           default=str) + "\n", encoding="utf-8")
    if args.write:
        print(f"wrote {len(cases)} golden files in {total:.0f} s")
        return 0
    if failed:
        print(f"{len(failed)} of {len(cases)} cases moved by more than {args.rtol:g}: {', '.join(failed)} "
              f"({total:.0f} s)")
        return 1
    print(f"all {len(cases)} cases within {args.rtol:g} ({total:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
