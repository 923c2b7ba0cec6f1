"""Print the sections' acceptance numbers as Markdown: linecheck's public outputs against the
independent section reference (``python -m tests.reference.section_report`` from the repository root).

Runs ``linecheck static CASE --json`` / ``linecheck modes CASE --json`` in process on every case of
tests/data/sections/ and prints, per tower and component, linecheck, the reference and the
difference relative to the largest reference component at that tower (the acceptance measure).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from . import irvine_inclined as ii
from . import section_fe as fe

DATA = Path(__file__).resolve().parents[1] / "data" / "sections"
STATIC = ["unequal-still", "unequal-wind", "inclined-still", "inclined-wind", "angles-still", "angles-wind"]


def _run(command: str, case: Path, out: Path, *extra: str) -> dict:
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    r = CliRunner(env={"COLUMNS": "250"}).invoke(app, [command, str(case), "--json", str(out), *extra])
    if r.exit_code != 0:
        raise RuntimeError(f"linecheck {command} {case.name}: exit {r.exit_code}: {r.output.strip()[-400:]}")
    return json.loads(out.read_text(encoding="utf-8"))


def _rows(stem: str, lc_tw, lc_gl, ref_tw, ref_gl) -> list[str]:
    out = []
    for j in range(ref_tw.shape[0]):
        for frame, lc, ref in (("tower", lc_tw, ref_tw), ("global", lc_gl, ref_gl)):
            scale = np.abs(ref[j]).max()
            cells = [f"{lc[j, c]:.1f} / {ref[j, c]:.1f} ({(lc[j, c] - ref[j, c]) / scale:+.3%})" for c in range(3)]
            out.append(f"| {stem} | {j + 1} | {frame} | " + " | ".join(cells) + " |")
    return out


def main() -> int:
    worst: dict[str, float] = {}
    lines = ["| case | tower | frame | Rx: linecheck / reference [N] (diff) | Ry | Rz |", "|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as tmp:
        for stem in STATIC:
            doc = _run("static", DATA / f"{stem}.toml", Path(tmp) / f"{stem}.json")
            sol = fe.solve(DATA / f"{stem}.toml", n_el=100)
            st = sol.wind if sol.wind is not None else sol.still
            tw = np.array([[t["Rx"], t["Ry"], t["Rz"]] for t in doc["towers"]], dtype=float)
            gl = np.array([[t["global"][k] for k in ("Rx", "Ry", "Rz")] for t in doc["towers"]], dtype=float)
            lines += _rows(stem, tw, gl, st.reactions_tower, st.reactions)
            worst[stem] = max(float(np.max(np.abs(a - b) / np.abs(b).max(axis=1, keepdims=True)))
                              for a, b in ((tw, st.reactions_tower), (gl, st.reactions)))
        print("\n".join(lines))
        print()
        print("| case | largest difference / largest component at the tower |\n|---|---|")
        for k, v in worst.items():
            print(f"| {k} | {v:.3%} |")
        print()
        # inclined single span vs Irvine
        doc = _run("static", DATA / "inclined-span.toml", Path(tmp) / "span.json")
        c = ii.from_tension(400.0, 40.0, fe.read_section(DATA / "inclined-span.toml").W, 0.7e-4 * 5.2e10, 20000.0)
        exact = np.array([[c.H, 0.0, c.VA], [-c.H, 0.0, c.VB]])
        print("| inclined span, end | component | linecheck [N] | Irvine [N] | difference |\n|---|---|---|---|---|")
        for j, t in enumerate(doc["towers"]):
            for k, comp in enumerate(("Rx", "Ry", "Rz")):
                v, e = float(t["global"][comp]), exact[j, k]
                rel = (v - e) / abs(e) if e != 0 else (v - e) / np.abs(exact[j]).max()
                print(f"| {'AB'[j]} | {comp} | {v:.2f} | {e:.2f} | {rel:+.4%} |")
        print()
        doc = _run("modes", DATA / "inclined-span-modes.toml", Path(tmp) / "modes.json", "--count", "16")
        f = np.array(doc["still_air"]["frequencies_hz"], dtype=float)
        d = np.array(doc["still_air"]["direction"])
        ip, op = fe.refined_frequencies(DATA / "inclined-span-modes.toml", n_el=200)
        print("| mode | in-plane linecheck / ref [Hz] | diff | out-of-plane linecheck / ref [Hz] | diff |\n|---|---|---|---|---|")
        lip, lop = f[d != "y"][:4], f[d == "y"][:4]
        for k in range(4):
            a = f"{lip[k]:.4f} / {ip[k]:.4f} | {lip[k] / ip[k] - 1:+.2%}" if k < lip.size else "- | -"
            b = f"{lop[k]:.4f} / {op[k]:.4f} | {lop[k] / op[k] - 1:+.2%}" if k < lop.size else "- | -"
            print(f"| {k + 1} | {a} | {b} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
