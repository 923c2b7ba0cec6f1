"""Regenerate the downburst model figures of docs/wind.md (SVG written directly; no matplotlib).

Run from the repository root: ``python tools/make_wind_figures.py``.  For each built-in model:
the running-mean radial speed at the conductor height (43 m) at three radii (0.8, 1.2, 2.0 D_j)
versus time, for the stationary Db_y storm of paper case 7 (D_j = 1000 m, V_ref = 40 m/s at p).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck import service
from linecheck.core.case import load_case
from linecheck.core.wind.mean import downburst_field, event_window

RADII = (0.8, 1.2, 2.0)
COLOURS = ("#1f77b4", "#d62728", "#2ca02c")
W, H, ML, MR, MT, MB = 640, 320, 60, 150, 30, 45


def svg(model: str, t: np.ndarray, curves: list[np.ndarray], vmax: float) -> str:
    pw, ph = W - ML - MR, H - MT - MB
    tmax = float(t[-1])

    def X(v):
        return ML + pw * v / tmax

    def Y(v):
        return MT + ph * (1 - v / vmax)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{ML}" y="18" font-size="13">{model}: running-mean radial speed at z = 43 m (Db_y, D_j = 1000 m)</text>',
           f'<rect x="{ML}" y="{MT}" width="{pw}" height="{ph}" fill="none" stroke="black"/>']
    step = 100 if tmax <= 1000 else 200
    for tv in np.arange(0, tmax + 1e-9, step):
        out.append(f'<line x1="{X(tv):.1f}" y1="{MT + ph}" x2="{X(tv):.1f}" y2="{MT + ph + 4}" stroke="black"/>')
        out.append(f'<text x="{X(tv):.1f}" y="{MT + ph + 17}" text-anchor="middle">{tv:.0f}</text>')
    for vv in np.arange(0, vmax + 1e-9, 10):
        out.append(f'<line x1="{ML - 4}" y1="{Y(vv):.1f}" x2="{ML}" y2="{Y(vv):.1f}" stroke="black"/>')
        out.append(f'<text x="{ML - 7}" y="{Y(vv) + 4:.1f}" text-anchor="end">{vv:.0f}</text>')
        out.append(f'<line x1="{ML}" y1="{Y(vv):.1f}" x2="{ML + pw}" y2="{Y(vv):.1f}" stroke="#ddd"/>')
    out.append(f'<text x="{ML + pw / 2}" y="{H - 8}" text-anchor="middle">time t [s]</text>')
    out.append(f'<text x="15" y="{MT + ph / 2}" transform="rotate(-90 15 {MT + ph / 2})" text-anchor="middle">V [m/s]</text>')
    for k, (c, col) in enumerate(zip(curves, COLOURS)):
        pts = " ".join(f"{X(a):.1f},{Y(b):.1f}" for a, b in zip(t, c))
        out.append(f'<polyline points="{pts}" fill="none" stroke="{col}" stroke-width="1.5"/>')
        ly = MT + 15 + 18 * k
        out.append(f'<line x1="{ML + pw + 10}" y1="{ly}" x2="{ML + pw + 30}" y2="{ly}" stroke="{col}" stroke-width="2"/>')
        out.append(f'<text x="{ML + pw + 35}" y="{ly + 4}">r = {RADII[k]:g} D_j</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main() -> None:
    base = load_case(ROOT / "cases" / "paper" / "case07-six.toml")
    for model in service.BUILTIN_DOWNBURST_MODELS:
        case = service.case_with_model(base, model)
        f = downburst_field(case)
        t = np.linspace(*event_window(case), 1201)
        dj = case.wind.downburst.jet_diameter
        curves = [f.v_max * np.abs(f.shape(np.full(t.size, r * dj), t)) for r in RADII]
        vmax = 10 * np.ceil(max(c.max() for c in curves) / 10)
        (ROOT / "docs" / "images" / f"downburst-{model}.svg").write_text(svg(model, t, curves, vmax), encoding="utf-8")


if __name__ == "__main__":
    main()
