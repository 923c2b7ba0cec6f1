"""Bench: Excel export of the 24-case paper batch (target: <= 10 s, workbook <= ~10 MB).

    .venv/bin/python bench/bench_excel.py [--from DIR] [--full-histories]

Without ``--from``, four representative paper cases (downburst/synoptic, single/six
spans) are run once with 2 realizations over their full records, and their result
documents are cloned onto the 24 paper case files (names, spans, V_ref, L_x and
parameters of each file), so every document has the size of a real one: full-length
records thinned peak-preserving by ``run_document`` (6,000 to 8,000 samples per
history).  With ``--from DIR`` the ``*.json`` run results in DIR are used (e.g. the
``--json-dir`` of a real ``linecheck batch``).

Timed: ``write_workbook`` from the typed documents (``run``/``batch --excel``) and
``load_result_docs`` + ``write_workbook`` from saved JSON files (``linecheck export``).
``--full-histories`` adds a row with un-thinned histories (what ``--full-histories``
runs produce), for information: that size is the user's explicit choice.
"""

from __future__ import annotations

import os

# time fresh runs: a run synthesises its turbulence (the per-process memo serves scans; docs/wind.md)
os.environ.setdefault("LINECHECK_UNIT_FIELD_MEMO", "0")

import argparse
import dataclasses
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck import service
from linecheck.core.case import case_to_dict, load_case
from linecheck.excel.writer import load_result_docs, write_workbook
from linecheck.io.document import RunDocument
from linecheck.io.jsonout import run_document, write_json

PAPER = ROOT / "cases" / "paper"
REPRESENTATIVE = ("case01-six", "case05-single", "case09-six", "case11-single")
TARGET_S = 10.0
TARGET_MB = 10.0


def representative_docs(full: bool) -> dict[tuple[str, int], RunDocument]:
    out = {}
    for name in REPRESENTATIVE:
        case = load_case(PAPER / f"{name}.toml")
        case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, realizations=2))
        t0 = time.perf_counter()
        res = service.run_case(case)
        doc = run_document(res, full_histories=full)
        print(f"  ran {name}: {time.perf_counter() - t0:.1f} s, {len(doc.time_histories.time)} samples "
              f"per history", file=sys.stderr)
        out[(case.wind.type, case.line.spans)] = doc
    return out


def paper_batch(reps: dict[tuple[str, int], RunDocument]) -> list[RunDocument]:
    docs = []
    for path in sorted(PAPER.glob("case*.toml")):
        case = load_case(path)
        docs.append(dataclasses.replace(reps[(case.wind.type, case.line.spans)], case=case.name,
                                        description=case.description, v_ref=case.wind.v_ref,
                                        span_length=case.line.span_length, parameters=case_to_dict(case)))
    return docs


def measure(label: str, docs: list[RunDocument], tmp: Path, repeat: int) -> dict:
    out = tmp / f"{label.replace(' ', '_')}.xlsx"
    t_dicts = t_export = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        write_workbook(docs, out, force=True)
        t_dicts = min(t_dicts, time.perf_counter() - t0)
    jdir = tmp / f"{label.replace(' ', '_')}-json"
    jdir.mkdir(exist_ok=True)
    files = []
    for k, doc in enumerate(docs):
        files.append(write_json(jdir / f"{k:02d}-{doc.case}.json", doc))
    json_mb = sum(f.stat().st_size for f in files) / 1e6
    for _ in range(repeat):
        t0 = time.perf_counter()
        write_workbook(load_result_docs(files), out, force=True)
        t_export = min(t_export, time.perf_counter() - t0)
    return {"label": label, "cases": len(docs), "json_mb": json_mb, "write_s": t_dicts, "export_s": t_export,
            "xlsx_mb": out.stat().st_size / 1e6}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--from", dest="src", type=Path, help="folder of saved run results (*.json)")
    ap.add_argument("--full-histories", action="store_true", help="also time un-thinned histories")
    ap.add_argument("--repeat", type=int, default=3, help="best of N timings (default 3)")
    args = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        if args.src is not None:
            docs = load_result_docs(sorted(args.src.glob("*.json")))
            rows.append(measure(f"saved results ({args.src.name})", docs, tmp, args.repeat))
        else:
            print("running the representative cases (2 realizations, full records)...", file=sys.stderr)
            rows.append(measure("24 paper cases", paper_batch(representative_docs(False)), tmp, args.repeat))
            if args.full_histories:
                rows.append(measure("24 cases full histories", paper_batch(representative_docs(True)), tmp, 1))
    print()
    print(f"{'workbook':<26} {'cases':>5} {'JSON MB':>8} {'write s':>8} {'export s':>9} {'xlsx MB':>8}  target")
    ok = True
    for r in rows:
        within = r["export_s"] <= TARGET_S and r["xlsx_mb"] <= TARGET_MB
        ok &= within or "full" in r["label"]
        print(f"{r['label']:<26} {r['cases']:>5} {r['json_mb']:>8.1f} {r['write_s']:>8.2f} {r['export_s']:>9.2f} "
              f"{r['xlsx_mb']:>8.2f}  <= {TARGET_S:g} s, <= {TARGET_MB:g} MB: {'ok' if within else 'MISSED'}")
    print(f"write s: write_workbook from the typed documents (run/batch --excel); export s: load the saved JSON "
          f"+ write (linecheck export); best of {args.repeat} (full histories: 1 run).")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
