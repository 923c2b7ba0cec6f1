"""Design codes at angle towers: the code load is compared like for like with linecheck's peak.

linecheck's transverse reaction at an angle tower carries the resultant of the wind-induced rise
in conductor tension; the code side adds the code's own wind-induced angle load (docs/codes.md,
"What is compared").  References: Irvine's elastic catenary in closed form for the tension
under the code's load (Irvine 1981, Eq. 2.21 for a level span: l = H L_u / EA +
(2 H / q) asinh(q L_u / (2 H))), the statics of a clamp (two span tensions H at a deviation
alpha: resultant 2 H sin(alpha/2) along the bisector's normal), and linecheck's own step-1
reaction under the same load.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from linecheck import service
from linecheck.analysis import code_check
from linecheck.analysis.step1 import static_result
from linecheck.core import codes as C
from linecheck.core.case import case_from_dict, load_case
from linecheck.core.system import LineSystem

from ..conftest import ROOT

W, EA, H0, L = 17.92, 5.2e10 * 0.7e-4, 22000.0, 400.0  # [N/m], [N], [N] still-air tension, [m] spans
ALPHA = math.radians(10.0)  # line deviation at tower 2


def _section(direction: float, support: str = "strain", **analysis):
    """Two level 400 m spans, a 10 deg left turn at tower 2; ``direction`` -5 deg blows along the
    normal of tower 2's bisector toward the inside of the angle (both spans see cos 5 deg)."""
    towers = [{"station": s, "ground": 0.0, "height": 40.0, "support": sup, "angle": a}
              for s, sup, a in ((0.0, "strain", 0.0), (L, support, 10.0), (2 * L, "strain", 0.0))]
    return case_from_dict({
        "line": {"weight": W, "diameter": 0.022, "area": 0.7e-4, "elastic_modulus": 5.2e10, "tension": H0,
                 "insulator_length": 4.0, "elements_per_span": 10, "towers": towers},
        "wind": {"type": "synoptic", "v_ref": 35.0, "direction": direction, "turbulence_intensity": 0.15},
        # the codes' load acts along each span's horizontal normal (their sin^2(Omega) factor)
        "analysis": {"realizations": 4, "duration": 300.0, "seed": 3, "drag_direction": "horizontal-normal",
                     **analysis},
    }, default_name="angle-10deg")


def _irvine_tension(q: float, Lu: float) -> float:
    """[N] horizontal tension of a level elastic catenary of span L under q [N/m of L_u] (Irvine 1981)."""
    return brentq(lambda H: H * Lu / EA + 2 * H / q * math.asinh(q * Lu / (2 * H)) - L, 1e2, 1e7, xtol=1e-9)


def test_angle_load_is_the_resultant_of_the_codes_tension_rise():
    """Hand computation: each code's load w on both spans (normal component cos^2 5 deg), the level
    elastic catenary under the resultant of weight and wind gives dT; angle load = 2 dT sin 5 deg.
    ASCE 74 here: w = 21.80 N/m, dT = 6806 N (22.0 -> 28.8 kN), angle load 1.186 kN beside a wind
    load of 8.622 kN (= w 400 m cos^2 5 deg cos 5 deg) at tower 2."""
    res = service.codes_analysis(_section(-5.0))
    Lu = brentq(lambda u: H0 * u / EA + 2 * H0 / W * math.asinh(W * u / (2 * H0)) - L, 0.9 * L, 1.1 * L)  # clip-in
    c5 = math.cos(ALPHA / 2)
    seen = 0
    for check in res.checks:
        w = check.load_per_length
        if w is None:
            continue
        seen += 1
        q = math.hypot(W, w * c5**2 * L / Lu)  # the code's load per metre of horizontal span, per metre of L_u
        dT = _irvine_tension(q, Lu) - H0
        end, mid, _ = (t.reactions["Ry"] for t in check.towers)
        assert mid.angle_load == pytest.approx(2 * dT * math.sin(ALPHA / 2), rel=1e-8), check.code
        assert mid.wind_load == pytest.approx(w * L * c5**2 * c5, rel=1e-12)  # resolved on the tower's y
        assert mid.code_load == pytest.approx(mid.wind_load + mid.angle_load, rel=1e-15)
        # the end towers: no deviation inside the section, the wind load alone (as before)
        assert end.angle_load == 0.0 and end.code_load == end.wind_load == pytest.approx(w * L / 2 * c5**2, rel=1e-12)
        if check.code == "ASCE74":
            assert (w, dT, mid.angle_load, mid.wind_load) == pytest.approx((21.80, 6806.0, 1186.4, 8621.5), rel=2e-4)
    assert seen == 4


def test_the_code_side_is_linechecks_reaction_under_the_code_load():
    """Like for like: a "code" whose load per metre is linecheck's own mean load gives, as wind load +
    angle load, exactly linecheck's step-1 wind-induced R_y at the angle tower (still air excluded),
    the angle part being 2 dH sin(alpha/2) of the mean state's tension rise.  The wind load alone,
    the comparison before the angle load, misses 10.7 % of that reaction here."""
    case = _section(-5.0)
    st = static_result(case)
    system = st.system
    ry = system.to_tower_frames(st.mean.reactions_wind[0])[1, 1]  # [N] tower 2, its own frame
    dH = st.mean.tension[0] - system.still_air.tension
    g = float(st.mean.gy[0, 0, 0])  # [N/m of L_u] linecheck's mean load on span 1 (uniform: no profile)
    assert np.allclose(st.mean.gy[0], g, rtol=1e-14, atol=0.0)
    w = g * system.unstretched_lengths[0] / L / math.cos(ALPHA / 2) ** 2  # per metre of span, normal wind
    own = C.CodeLoad("linecheck-mean", "-", True, "synoptic", w)
    angle = code_check.angle_loads(case, [own], system)["linecheck-mean"]
    eq = code_check.equivalent_spans(case, signed=True) * np.cos(0.5 * code_check.deviation_angles(system))
    rc = code_check.reaction_check(own, None, float(eq[1]), float(angle[1]))
    assert angle[1] == pytest.approx(dH.sum() * math.sin(ALPHA / 2), rel=1e-8)
    assert rc.code_load == pytest.approx(ry, rel=1e-8)
    assert rc.angle_load / ry == pytest.approx(0.107, abs=1e-3)


def test_wind_toward_the_outside_of_the_angle_subtracts_the_angle_load():
    """The same wind reversed (175 deg: toward the outside of the left turn): the same tension rise
    and wind load, the angle load now opposes the wind load, code load = wind - angle."""
    inside = service.codes_analysis(_section(-5.0)).checks[0].towers[1].reactions["Ry"]
    outside = service.codes_analysis(_section(175.0)).checks[0].towers[1].reactions["Ry"]
    assert outside.wind_load == pytest.approx(inside.wind_load, rel=1e-12)
    assert outside.angle_load == pytest.approx(-inside.angle_load, rel=1e-8)
    assert outside.code_load == pytest.approx(inside.wind_load - inside.angle_load, rel=1e-8)


def test_suspension_angle_tower_carries_both_spans_tension_rise():
    """At a suspension angle tower the insulator swings; the two spans keep (nearly) one tension and
    the angle load is (dT_1 + dT_2) sin(alpha/2) of the code's static state."""
    case = _section(-5.0, support="suspension")
    system = LineSystem(case.line)
    loads = [x for x in service.code_loads(case) if x.load_per_length is not None]
    dT = code_check.code_tensions(case, loads, system) - system.still_air.tension
    angle = code_check.angle_loads(case, loads, system)
    for k, x in enumerate(loads):
        assert dT[k, 0] == pytest.approx(dT[k, 1], rel=1e-3) and dT[k, 0] > 0.2 * H0
        assert angle[x.code][1] == pytest.approx(dT[k].sum() * math.sin(ALPHA / 2), rel=1e-14)
        assert angle[x.code][0] == angle[x.code][2] == 0.0


def test_straight_towers_and_straight_lines_are_unchanged(monkeypatch):
    """The shipped 12-span section: every tower but the two angle towers (T5 18 deg, T9 -4 deg) keeps
    the code load w * sum of its half spans weighted by cos^2(d + h) (the comparison before the
    angle load), with angle load 0; a line without angle towers solves no static state."""
    case = load_case(ROOT / "cases" / "examples" / "section-12span.toml")
    system = LineSystem(case.line)
    c2 = np.cos(math.radians(case.wind.direction) + system.span_headings) ** 2
    half = 0.5 * system.span_lengths * c2
    eq = np.zeros(system.n_towers)
    eq[:-1] += half
    eq[1:] += half
    res = service.codes_analysis(case, strict=False)
    for check in res.checks:
        if check.load_per_length is None:
            continue
        for t in check.towers:
            rc = t.reactions["Ry"]
            if t.index in (5, 9):
                assert rc.angle_load != 0.0
                continue
            assert rc.angle_load == 0.0 and rc.code_load == rc.wind_load == check.load_per_length * eq[t.index - 1]
        t5, t9 = check.towers[4].reactions["Ry"], check.towers[8].reactions["Ry"]
        # the wind (30 deg, toward +y) blows toward the inside of T5's left turn and the outside of T9's right turn
        assert t5.angle_load > 0.0 > t9.angle_load
    import linecheck.analysis.code_check as mod

    def no_solve(*a, **k):
        raise AssertionError("a straight line needs no static solve")

    monkeypatch.setattr(mod, "solve_static_batch", no_solve)
    straight = service.codes_analysis(load_case(ROOT / "cases" / "paper" / "case09-six.toml"))
    assert all(t.reactions["Ry"].angle_load == 0.0 for c in straight.checks for t in c.towers)


# --------------------------------------------------------------------------- every front end
@pytest.fixture(scope="module")
def angle_run():
    case = _section(-5.0)
    return service.run_case(case, spectral_check=False)


def test_run_document_and_ratio_compare_wind_plus_angle(angle_run):
    from linecheck.io.document import RunDocument
    from linecheck.io.jsonout import run_to_dict

    doc = json.loads(json.dumps(run_to_dict(angle_run)))
    ry = doc["codes"]["ASCE74"]["towers"][1]["Ry"]
    assert list(ry) == ["wind_load", "angle_load", "code_load", "linecheck_peak", "ratio", "verdict"]
    assert ry["code_load"] == pytest.approx(ry["wind_load"] + ry["angle_load"], rel=1e-15)
    assert ry["ratio"] == pytest.approx(ry["linecheck_peak"] / ry["code_load"], rel=1e-15)
    typed = RunDocument.from_json(doc)
    assert typed.codes["ASCE74"].towers[1].reactions["Ry"].angle_load == ry["angle_load"]
    assert json.dumps(typed.to_json()) == json.dumps(doc)  # read and written again: byte for byte
    # a result saved before the two parts were recorded reads and writes back as it was
    old = json.loads(json.dumps(doc))
    for block in old["codes"].values():
        for t in block["towers"]:
            del t["Ry"]["wind_load"], t["Ry"]["angle_load"]
    again = RunDocument.from_json(old)
    assert again.codes["ASCE74"].towers[1].reactions["Ry"].angle_load is None
    assert json.dumps(again.to_json()) == json.dumps(old)


def test_cli_codes_shows_the_angle_part_and_what_is_compared(tmp_path):
    from typer.testing import CliRunner

    from linecheck.cli.app import app
    from linecheck.core.case import case_to_toml

    p = tmp_path / "angle.toml"
    p.write_text(case_to_toml(_section(-5.0)))
    out = tmp_path / "codes.json"
    r = CliRunner().invoke(app, ["codes", str(p), "--loads-only", "--json", str(out)], env={"COLUMNS": "200"})
    assert r.exit_code == 0, r.output
    assert "angle kN" in r.output and "wind kN" in r.output and "code load = |wind load + angle load|" in r.output
    doc = json.loads(out.read_text())
    assert doc["compared"] == C.CODES_COMPARED
    ry = doc["codes"]["ASCE74"]["towers"][1]["Ry"]
    assert ry["angle_load"] == pytest.approx(1186.4, rel=2e-4)
    assert f"{ry['angle_load'] / 1e3:.3f}" in r.output


def test_excel_and_tui_show_the_angle_part(angle_run):
    from openpyxl import Workbook

    from linecheck.excel import template as tpl
    from linecheck.excel.codes_sheet import COLUMNS, write_codes
    from linecheck.io.document import RunDocument
    from linecheck.io.jsonout import run_to_dict
    from linecheck.tui.widgets.codes import PEAK_NOTE, codes_rows

    typed = RunDocument.from_json(json.loads(json.dumps(run_to_dict(angle_run))))
    ry = typed.codes["ASCE74"].towers[1].reactions["Ry"]
    wb = Workbook()
    tpl.ensure_styles(wb)
    ws = wb.active
    assert write_codes(ws, [typed]) == 4 * 3
    head = [c.split("\n")[0] for c, _ in COLUMNS]
    row = next(r for r in ws.iter_rows(min_row=4, values_only=True) if r[1] == "ASCE74" and r[4] == 2)
    assert row[head.index("Angle load")] == pytest.approx(ry.angle_load / 1e3)
    assert row[head.index("Wind load")] == pytest.approx(ry.wind_load / 1e3)
    assert row[head.index("Code load")] == pytest.approx(ry.code_load / 1e3)
    assert any(isinstance(c, str) and c.startswith(C.CODES_COMPARED) for r in ws.iter_rows(values_only=True) for c in r)
    tui = next(r for r in codes_rows(typed.codes) if r[0] == "ASCE74" and r[2] == "2")
    assert tui[4:7] == (f"{ry.wind_load / 1e3:.3f}", f"{ry.angle_load / 1e3:.3f}", f"{ry.code_load / 1e3:.3f}")
    assert PEAK_NOTE.startswith(C.CODES_COMPARED)
