"""The built-in verification set behind ``linecheck validate``: the method checked against closed
forms and published results.

Closed-form checks (elastic catenary, Newmark on an SDOF, lumped-string modes),
Matheson & Holmes (1981) Table 4, time vs frequency domain, and the paper's Table 5
side by side.  No UI imports; progress through ``progress(stage, done, total)``.
"""

from __future__ import annotations

import csv
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import service
from .core.case import Line, load_case
from .core.dynamics import integrate
from .core.errors import CaseError
from .core.model import LinearModel, build_model, dof_map
from .core.modes import natural_modes
from .core.static import drag_intensity, solve_static, span_loads_uniform, still_air_state
from .core.system import LineSystem
from .reference import catenary_tension, discrete_string_frequencies, sdof_harmonic

ROOT = Path(__file__).resolve().parents[1]
PAPER_CASES = ROOT / "cases" / "paper"
VALIDATION_CASES = ROOT / "cases" / "validation"
# the paper's tables travel with the project (a user's clone has no ../shared)
TABLE4 = Path(__file__).resolve().parent / "data" / "table4_matheson_holmes.csv"
TABLE5 = Path(__file__).resolve().parent / "data" / "table5_gust_factors.csv"


@dataclass(frozen=True)
class Check:
    """One verification line: ``passed`` is None for side-by-side (information) rows."""

    group: str
    name: str
    reference: str
    measured: str
    difference: str
    tolerance: str
    passed: bool | None

    def __post_init__(self) -> None:
        if self.passed is not None:  # numpy bools are not JSON-serialisable
            object.__setattr__(self, "passed", bool(self.passed))


def _pct(a: float, b: float) -> str:
    return f"{100 * (a / b - 1):+.2f} %"


def paper_line(L: float, spans: int = 1, **kw) -> Line:
    """The paper's conductor system (Table 1)."""
    supports = ("strain", "strain") if spans == 1 else ("strain",) + ("suspension",) * (spans - 1) + ("strain",)
    args = dict(spans=spans, span_length=L, sag=L / 30, weight=17.92, diameter=0.022, drag_coefficient=1.0,
                area=0.7e-4, elastic_modulus=5.2e10, height=43.0, insulator_length=4.0, supports=supports,
                tower_of_interest=1 if spans == 1 else spans // 2 + 1, elements_per_span=10)
    args.update(kw)
    return Line(**args)


def closed_form_checks() -> list[Check]:
    out = []
    for L in (300.0, 500.0):
        for V in (0.0, 20.0, 40.0):
            system = LineSystem(paper_line(L))
            g = float(drag_intensity(V, 1.25, 1.0, 0.022))
            st = solve_static(system, span_loads_uniform(system, g))
            H = catenary_tension(L, system.unstretched_length, float(np.hypot(17.92, g)), system.line.ea)
            err = abs(st.tension[0] / H - 1)
            out.append(Check("static", f"single span L={L:.0f} m V={V:.0f} m/s: H vs elastic catenary",
                             f"{H / 1e3:.3f} kN", f"{st.tension[0] / 1e3:.3f} kN", _pct(st.tension[0], H),
                             "0.5 %", err <= 0.005))
    # Newmark on a damped SDOF under harmonic load
    system = LineSystem(paper_line(300.0, elements_per_span=2))
    dm = dof_map(system)
    k, m, zeta = 400.0, 10.0, 0.05
    ab = np.zeros((6, 3))
    ab[-1] = k
    G = np.zeros((6, 3))
    G[4, 1] = 1.0
    model = LinearModel(system, dm, ab, np.full(3, m), np.ones(system.n_nodes), G,
                        np.zeros((0, 3)), np.zeros(0, dtype=int), np.zeros_like(ab))
    wn = np.sqrt(k / m)
    damp = np.zeros((1, 6, 3))
    damp[0, -1, 1] = 2 * zeta * m * wn
    dt, n = 0.0025, 8000
    t = dt * np.arange(n)
    W = 0.8 * wn
    F = 50.0 * np.sin(W * t)
    u = integrate([model], damp, np.zeros(n, dtype=int), F[:, None, None], dt).fluctuating[0, :, 1, 1]
    exact = sdof_harmonic(t, k, m, zeta, 50.0, W)
    err = np.max(np.abs(u - exact)) / np.max(np.abs(exact))
    out.append(Check("dynamics", "Newmark, damped SDOF under harmonic load", "exact (Chopra 3.2)",
                     f"max error {err:.1e}", f"{err:.1e}", "1e-3", err < 1e-3))
    # lumped string
    ne = 50
    system = LineSystem(paper_line(300.0, elements_per_span=ne))
    st = still_air_state(system)
    modes = natural_modes(build_model(system, st), 6)
    f_oop = modes.frequencies_hz[modes.dominant_direction() == 1][:3]
    ref = discrete_string_frequencies(st.tension[0], 300.0, ne, 17.92 * system.unstretched_length / ne / 9.81, 3)
    err = float(np.max(np.abs(f_oop / ref - 1)))
    out.append(Check("modes", "out-of-plane modes of the still-air span vs lumped string",
                     " ".join(f"{x:.4f}" for x in ref) + " Hz", " ".join(f"{x:.4f}" for x in f_oop) + " Hz",
                     f"{err:.1e}", "1e-9", err < 1e-9))
    return out


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def matheson_holmes_checks(realizations: int = 10) -> list[Check]:
    out = []
    for row in _rows(TABLE4):
        V = int(float(row["v_ref_ms"]))
        case = load_case(VALIDATION_CASES / f"matheson-holmes-v{V}.toml")
        case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, realizations=realizations))
        res = service.run_case(case)
        mean = float(res.stats.mean("mean_max")[0, 1])
        rms = float(res.stats.mean("rms_fluctuating")[0, 1])
        mh_mean, mh_rms = float(row["matheson_holmes_mean_kN"]) * 1e3, float(row["matheson_holmes_rms_kN"]) * 1e3
        out.append(Check("Matheson & Holmes", f"V={V} m/s mean transverse reaction", f"{mh_mean / 1e3:.3f} kN",
                         f"{mean / 1e3:.3f} kN", _pct(mean, mh_mean), "3 %", abs(mean / mh_mean - 1) <= 0.03))
        out.append(Check("Matheson & Holmes", f"V={V} m/s r.m.s. transverse reaction (L_u assumed 173 m)",
                         f"{mh_rms / 1e3:.4f} kN (paper {float(row['paper_rms_kN']):.3f})", f"{rms / 1e3:.4f} kN",
                         _pct(rms, mh_rms), "shown", None))
    return out


def time_vs_frequency_checks(names: tuple[str, ...], realizations: int = 20,
                             progress: Callable[[str, int, int], None] | None = None) -> list[Check]:
    out = []
    for i, name in enumerate(names):
        case = load_case(PAPER_CASES / f"{name}.toml")
        case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, damping="quasi-steady",
                                                                      structural_damping=None,
                                                                      realizations=realizations))
        res = service.run_case(case)
        j = res.tower_index
        ex = res.spectral.exact
        scale = float(np.max(ex.rms_fluctuating))
        for q in ("rms_background", "rms_fluctuating"):
            td, fd = res.stats.mean(q)[j], getattr(ex, q)
            for c, r in enumerate(("Rx", "Ry", "Rz")):
                if fd[c] < 0.01 * scale:
                    continue
                out.append(Check("time vs frequency", f"{name} (quasi-steady) {r} {q}", f"{fd[c] / 1e3:.4f} kN",
                                 f"{td[c] / 1e3:.4f} kN", _pct(td[c], fd[c]), "5 %", abs(td[c] / fd[c] - 1) <= 0.05))
        if progress is not None:
            progress("time vs frequency domain", i + 1, len(names))
    return out


def table5_rows(progress: Callable[[str, int, int], None] | None = None) -> list[Check]:
    """The paper's Table 5 beside linecheck (damping = "paper", the case files as shipped)."""
    rows = _rows(TABLE5)
    results: dict[str, service.RunResult] = {}
    needed = sorted({(int(r["case"]), "single" if r["reaction"].endswith("1") else "six") for r in rows})
    for i, (n, system) in enumerate(needed):
        name = f"case{n:02d}-{system}"
        results[name] = service.run_case(load_case(PAPER_CASES / f"{name}.toml"))
        if progress is not None:
            progress("paper Table 5", i + 1, len(needed))
    out = []
    for r in rows:
        n = int(r["case"])
        name = f"case{n:02d}-{'single' if r['reaction'].endswith('1') else 'six'}"
        res = results[name]
        j = res.tower_index
        c = 0 if r["reaction"].startswith("Rx") else 1

        def stat(q: str, scale: float = 1.0) -> str:
            m, s = res.stats.mean(q)[j, c], res.stats.std(q)[j, c]  # noqa: B023 - called at once, in this iteration
            return "**" if not np.isfinite(m) else f"{m * scale:.2f}±{s * scale:.2f}"

        ref = f"{r['GF_Dy'] or '**'} / {r['GF_QS'] or '**'} / {r['Cont_R_pct']}"
        got = f"{stat('GF_Dy')} / {stat('GF_QS')} / {stat('Cont_R', 100)}"
        out.append(Check("paper Table 5", f"case {n} {r['wind']} L={r['span_m']} V={r['v_ref_ms']} {r['reaction']}",
                         ref, got, "", "GF_Dy / GF_QS / Cont_R %", None))
    return out


def run_validation(*, quick: bool = False, progress: Callable[[str, int, int], None] | None = None) -> list[Check]:
    """The whole verification set; ``quick`` skips the six-span time-vs-frequency runs and Table 5."""
    if not PAPER_CASES.is_dir():
        raise CaseError(f"the shipped cases are not at {PAPER_CASES}: run validate from a source checkout "
                        "(pip install -e .)")
    checks = closed_form_checks()
    if progress is not None:
        progress("closed forms", 1, 1)
    checks += matheson_holmes_checks()
    if progress is not None:
        progress("Matheson & Holmes", 1, 1)
    names = ("case09-single", "case10-single") if quick else ("case09-single", "case10-single", "case09-six", "case10-six")
    checks += time_vs_frequency_checks(names, progress=progress)
    if not quick:
        checks += table5_rows(progress)
    return checks


def to_markdown(checks: list[Check]) -> str:
    """The table as Markdown (docs/validation.md)."""
    lines = ["| group | check | reference | linecheck | difference | tolerance | result |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for c in checks:
        res = "—" if c.passed is None else ("pass" if c.passed else "**FAIL**")
        lines.append(f"| {c.group} | {c.name} | {c.reference} | {c.measured} | {c.difference} | {c.tolerance} | {res} |")
    return "\n".join(lines) + "\n"
