"""Front ends on a line section (everything works on a section): the shared display
helpers (linecheck/io/section.py), the CLI tables and the Excel "Section" block.

Reference values are read from the example's CSV with the csv module and the plan positions
are derived here from the issue's definition (P_1 = 0, P_{i+1} = P_i + L_i (cos h_i, sin h_i),
h_i the sum of the angles of towers 1..i), independently of LineSystem.
"""

from __future__ import annotations

import copy
import csv
import dataclasses
import json
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest
from openpyxl import load_workbook
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.case import case_to_dict, load_case, with_values
from linecheck.excel.writer import write_workbook
from linecheck.io.jsonout import run_to_dict
from linecheck.io.section import (
    insulators_known,
    line_from_parameters,
    line_summary,
    section_geometry,
    section_summary,
    tower_rows,
)

from ..conftest import CASES

EXAMPLE = CASES / "examples" / "section-12span.toml"
CSV = CASES / "examples" / "section-12span.csv"
DEFAULT_INSULATOR = 4.2  # line.insulator_length of the example


def csv_towers() -> list[dict]:
    with CSV.open(encoding="utf-8") as f:
        lines = [ln for ln in f if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def inline_case():
    """The example with its towers inline ([[line.towers]]) instead of in the CSV."""
    case = load_case(EXAMPLE)
    towers = [{k: v for k, v in dataclasses.asdict(t).items() if v is not None} for t in case.line.towers]
    return with_values(case, {"line.towers_file": None, "line.towers": towers})


def expected_plan(rows: list[dict]) -> np.ndarray:
    """Plan positions (x, y) [m] of the towers from the issue's definition."""
    st = [float(r["station"]) for r in rows]
    ang = [math.radians(float(r["angle"] or 0.0)) for r in rows]
    p = [(0.0, 0.0)]
    h = 0.0
    for i in range(len(rows) - 1):
        h += ang[i]  # heading of span i: angles of towers 1..i
        L = st[i + 1] - st[i]
        p.append((p[-1][0] + L * math.cos(h), p[-1][1] + L * math.sin(h)))
    return np.array(p)


# --------------------------------------------------------------------------- shared helpers
def test_tower_rows_and_summary_of_the_example():
    line = load_case(EXAMPLE).line
    rows = tower_rows(line)
    ref = csv_towers()
    assert [r.name for r in rows] == [t["name"] for t in ref]
    stations = [float(t["station"]) for t in ref]
    assert [r.station for r in rows] == stations
    assert [r.span for r in rows] == [b - a for a, b in zip(stations, stations[1:])] + [None]
    for r, t in zip(rows, ref):
        assert (r.ground, r.height, r.support, r.angle) == (float(t["ground"]), float(t["height"]), t["support"],
                                                            float(t["angle"]))
        given = float(t["insulator_length"]) if t["insulator_length"] else None
        assert r.insulator_length == given
        assert r.insulator_used == (None if t["support"] == "strain" else (given or DEFAULT_INSULATOR))
    # spans 310 345 285 390 290 385 255 390 335 315 420 290: 255 to 420 m; T5 (18 deg), T9 (-4 deg)
    assert section_summary(line) == "12 spans, 255-420 m, 2 angle towers"
    assert line_summary(line) == section_summary(line)


def test_summary_wording_equal_section_and_paper_form():
    line = load_case(CASES / "paper" / "case01-six.toml").line
    assert line_summary(line) == "6 spans x 300 m, sag 10 m, height 43 m"
    assert tower_rows(line) == []
    straight = with_values(inline_case(), {"line.towers": [
        {"station": 0.0, "height": 30.0, "support": "strain"},
        {"station": 300.0, "height": 30.0, "support": "suspension"},
        {"station": 600.0, "height": 30.0, "support": "strain"}], "line.tower_of_interest": 2})
    assert section_summary(straight.line) == "2 spans of 300 m, no angle tower"


def test_geometry_of_the_example_against_the_definition():
    ref = csv_towers()
    geo = section_geometry(load_case(EXAMPLE).line)
    np.testing.assert_allclose(np.c_[geo.x, geo.y], expected_plan(ref), rtol=0, atol=1e-9)
    np.testing.assert_allclose(geo.z, [float(t["ground"]) + float(t["height"]) for t in ref], atol=1e-12)
    # the still-air conductor passes through every clamp (lifted where an angle tower's insulator
    # swung: the still-air equilibrium) and hangs below the chords between them
    from linecheck.core.static import still_air_state
    from linecheck.core.system import LineSystem

    system = LineSystem(load_case(EXAMPLE).line)
    at_towers = system.tower_nodes
    lift = still_air_state(system).displacement[:, 2]
    assert 0.05 < lift[8] < 0.1 and np.all(np.abs(np.delete(lift, 8)) < 0.01)  # T9, the 4 deg suspension angle
    np.testing.assert_allclose(geo.node_z[at_towers], geo.z + lift, atol=1e-6)
    chord = np.interp(geo.node_station, geo.station, geo.z)
    inside = np.setdiff1d(np.arange(geo.node_z.size), at_towers)
    assert np.all(geo.node_z[inside] < chord[inside])


def test_line_from_parameters_inline_file_and_paper():
    case = inline_case()
    params = json.loads(json.dumps(case_to_dict(case)))  # as in a JSON result
    assert line_from_parameters(params).towers == case.line.towers
    file_params = json.loads(json.dumps(case_to_dict(load_case(EXAMPLE))))
    assert line_from_parameters(file_params) is None  # only the file name: no table
    # a result whose towers[] carry the geometry (the section JSON): rebuilt from them
    towers = [{"index": k + 1, "name": t.name, "station": t.station, "ground": t.ground, "height": t.height,
               "support": t.support, "angle": t.angle} for k, t in enumerate(case.line.towers)]
    line = line_from_parameters(file_params, towers)
    assert [(t.name, t.station, t.ground, t.height, t.angle) for t in line.towers] == \
        [(t.name, t.station, t.ground, t.height, t.angle) for t in case.line.towers]
    assert line.towers[8].insulator_length is None  # T9's 4.6 m is not in towers[]: unknown, not guessed
    assert insulators_known(params) and not insulators_known(file_params, towers)
    # typed tower entries (attributes instead of keys), with their insulator lengths
    typed = [SimpleNamespace(**t, insulator_length=c.insulator_length) for t, c in zip(towers, case.line.towers)]
    assert line_from_parameters(file_params, typed).towers == case.line.towers
    assert insulators_known(file_params, typed)
    # a typed document tower keeps the section keys in its `section` dict (the section JSON)
    nested = [SimpleNamespace(index=t["index"], support=t["support"], reactions={},
                              section={k: v for k, v in t.items() if k not in ("index", "support")}) for t in towers]
    assert [(t.name, t.station, t.height) for t in line_from_parameters(file_params, nested).towers] == \
        [(t.name, t.station, t.height) for t in case.line.towers]
    paper = json.loads(json.dumps(case_to_dict(load_case(CASES / "paper" / "case01-six.toml"))))
    assert line_from_parameters(paper) is None


# --------------------------------------------------------------------------- CLI
def test_static_table_shows_tower_names_and_stations():
    r = CliRunner().invoke(app, ["static", str(EXAMPLE)])
    assert r.exit_code == 0, r.output
    ref = csv_towers()
    for k, t in enumerate(ref):
        mark = r"\s\*" if k + 1 == 7 else ""
        assert re.search(rf"│\s+{k + 1}{mark} │ {t['name']}\s+│\s+{t['station']} │\s+[-\d.]+ │\s+{t['support']} │",
                         r.output), t


def test_static_table_is_in_each_towers_frame_as_the_json(tmp_path):
    """Every number of the static console table equals the JSON's (each tower's own frame, not the
    global frame: T13's Ry 1.975 kN, global -3.880 kN; T5's wind Ry 5.678 kN, as the Excel; the
    cross-flow drag's values), and a caption names the frame."""
    out = tmp_path / "s.json"
    r = CliRunner(env={"COLUMNS": "250"}).invoke(app, ["static", str(EXAMPLE), "--json", str(out)])
    assert r.exit_code == 0, r.output
    doc = json.loads(out.read_text(encoding="utf-8"))
    keys = ("Rx", "Ry", "Rz", "Rx_wind", "Ry_wind", "Rz_wind")
    rows = [ln.split("│")[1:-1] for ln in r.output.splitlines() if re.match(r"│\s+\d+", ln)]
    assert len(rows) == len(doc["towers"]) == 13
    for cells, t in zip(rows, doc["towers"]):
        assert float(cells[3]) == pytest.approx(t["heading"], abs=0.05)
        assert [float(c) for c in cells[-6:]] == [round(t[k] / 1e3, 3) for k in keys], t["name"]
    t13, t5 = doc["towers"][12], doc["towers"][4]
    assert round(t13["Ry"] / 1e3, 3) == 1.975 and round(t13["global"]["Ry"] / 1e3, 3) == -3.880
    assert round(t5["Ry_wind"] / 1e3, 3) == 5.678
    assert "own frame" in r.output and "tower frame: x along the line bisector" in r.output


def test_static_table_of_a_paper_case_has_no_name_column():
    r = CliRunner().invoke(app, ["static", str(CASES / "paper" / "case09-single.toml")])
    assert r.exit_code == 0, r.output
    header = next(ln for ln in r.output.splitlines() if "tower" in ln and "support" in ln)
    assert "name" not in header and "station" not in header


# --------------------------------------------------------------------------- Excel
@pytest.fixture(scope="module")
def section_book(tmp_path_factory):
    """A workbook of a paper result and two section results (towers inline / in a CSV).

    The Section block reads only the document's case parameters (and towers[]), so the section
    documents reuse one short paper run's statistics with the section case's parameters.
    """
    paper = load_case(CASES / "paper" / "case09-single.toml")
    paper = dataclasses.replace(paper, analysis=dataclasses.replace(paper.analysis, duration=20.0, realizations=1))
    doc = run_to_dict(service.run_case(paper))
    inline = copy.deepcopy(doc)
    inline["case"], inline["tower_of_interest"] = "section-inline", 7
    inline["parameters"] = json.loads(json.dumps(case_to_dict(inline_case())))
    from_file = copy.deepcopy(doc)
    from_file["case"] = "section-file"
    from_file["parameters"] = json.loads(json.dumps(case_to_dict(load_case(EXAMPLE))))
    path = tmp_path_factory.mktemp("xl") / "sections.xlsx"
    write_workbook([doc, inline, from_file], path)
    return load_workbook(path)


def _chart_title(ch) -> str:
    return "".join(r.t for p in ch.title.tx.rich.p for r in (p.r or []))


def _ref_values(wb, ref: str) -> list:
    m = re.fullmatch(r"'?(.+?)'?!\$([A-Z]+)\$(\d+):\$([A-Z]+)\$(\d+)", ref)
    ws = wb[m.group(1)]
    return [c.value for row in ws[f"{m.group(2)}{m.group(3)}:{m.group(4)}{m.group(5)}"] for c in row]


def test_excel_section_block_table(section_book):
    ws = section_book["section-inline"]
    rows = [[c.value for c in r] for r in ws.iter_rows(min_col=1, max_col=8)]
    start = next(k for k, r in enumerate(rows) if isinstance(r[0], str) and r[0].startswith("Section: "))
    assert rows[start][0] == "Section: 13 towers, 12 spans, 255-420 m, 2 angle towers, H0 = 22 kN"
    assert rows[start + 1] == ["Tower", "station", "ground", "height", "support", "angle", "insulator",
                               "span to next"]
    ref = csv_towers()
    body = rows[start + 3:start + 3 + len(ref)]
    for k, (got, t) in enumerate(zip(body, ref)):
        name = t["name"] + (" *" if k + 1 == 7 else "")
        ins = None if t["support"] == "strain" else float(t["insulator_length"] or DEFAULT_INSULATOR)
        span = float(ref[k + 1]["station"]) - float(t["station"]) if k + 1 < len(ref) else None
        assert got == [name, float(t["station"]), float(t["ground"]), float(t["height"]), t["support"],
                       float(t["angle"]), ins, span]
    # the inputs table does not list [line.towers] keys, and marks the derived equal-span keys
    keys = {r[0]: r[2] for r in rows[:start]}
    assert keys["span_length"] == "(section: see Section)" and "[line.towers]" not in keys


def test_excel_section_charts_plan_and_profile(section_book):
    ws = section_book["section-inline"]
    charts = {_chart_title(ch): ch for ch in ws._charts if ch.title is not None}
    plan = charts["Section plan: clamp points (first span along +x)"]
    profile = charts["Section profile: clamps, ground and still-air conductor"]
    ref = csv_towers()
    xy = expected_plan(ref)
    s = plan.series[0]
    np.testing.assert_allclose(_ref_values(section_book, s.xVal.numRef.f), xy[:, 0], atol=1e-9)
    np.testing.assert_allclose(_ref_values(section_book, s.yVal.numRef.f), xy[:, 1], atol=1e-9)
    assert len(profile.series) == 3  # conductor, clamps, ground
    clamp_z = [float(t["ground"]) + float(t["height"]) for t in ref]
    ground = [float(t["ground"]) for t in ref]
    ys = [_ref_values(section_book, s.yVal.numRef.f) for s in profile.series]
    xs = [_ref_values(section_book, s.xVal.numRef.f) for s in profile.series]
    assert clamp_z in ys and ground in ys
    conductor = next(k for k, y in enumerate(ys) if len(y) > len(ref))
    assert len(ys[conductor]) == 12 * 10 + 1  # 12 spans x 10 elements + 1 nodes
    assert xs[conductor][0] == 0.0 and xs[conductor][-1] == pytest.approx(4010.0)
    # plan and profile come first among the sheet's charts, the paper charts follow
    first = sorted(ws._charts, key=lambda ch: ch.anchor._from.row)[:2]
    assert {_chart_title(ch) for ch in first} == {_chart_title(plan), _chart_title(profile)}


def test_excel_paper_sheet_has_no_section_block(section_book):
    ws = section_book["case09-single"]
    texts = [c.value for r in ws.iter_rows(min_col=1, max_col=1) for c in r if isinstance(c.value, str)]
    assert not [t for t in texts if t.startswith("Section")]
    assert not [ch for ch in ws._charts if ch.title is not None and _chart_title(ch).startswith("Section")]


def test_excel_section_from_a_towers_file_says_where_the_table_is(section_book):
    ws = section_book["section-file"]
    texts = [c.value for r in ws.iter_rows(min_col=1, max_col=1) for c in r if isinstance(c.value, str)]
    assert ("Section: the tower table is not in this result (the case read it from section-12span.csv); "
            "see the case file.") in texts


def test_cli_export_of_a_section_result(section_book, tmp_path):
    """``linecheck export`` reads a section result's JSON and writes the Section block."""
    paper = load_case(CASES / "paper" / "case09-single.toml")
    paper = dataclasses.replace(paper, analysis=dataclasses.replace(paper.analysis, duration=20.0, realizations=1))
    doc = run_to_dict(service.run_case(paper))
    doc["case"] = "section-inline"
    doc["parameters"] = json.loads(json.dumps(case_to_dict(inline_case())))
    src = tmp_path / "section.json"
    src.write_text(json.dumps(doc), encoding="utf-8")
    out = tmp_path / "section.xlsx"
    r = CliRunner().invoke(app, ["export", str(src), "--excel", str(out)])
    assert r.exit_code == 0, r.output
    ws = load_workbook(out)["section-inline"]
    texts = [c.value for row in ws.iter_rows(min_col=1, max_col=1) for c in row if isinstance(c.value, str)]
    assert "Section: 13 towers, 12 spans, 255-420 m, 2 angle towers, H0 = 22 kN" in texts
    assert sum(1 for ch in ws._charts if ch.title is not None and _chart_title(ch).startswith("Section")) == 2


def test_tui_parameter_keys_of_each_form():
    """The TUI parameter table lists one form's line keys: a section hides the equal-span keys its
    towers derive, an equal-span case the section keys; the per-tower keys are the tower table's."""
    from linecheck.tui.formatting import fields_for

    section = [k for k, _ in fields_for("synoptic", True)]
    paper = [k for k, _ in fields_for("synoptic", False)]
    equal = ["line.spans", "line.span_length", "line.sag", "line.height", "line.supports"]
    assert not set(equal) & set(section) and set(equal) <= set(paper)
    assert {"line.tension", "line.towers_file"} <= set(section) and not {"line.tension", "line.towers_file"} & set(paper)
    assert not [k for k in section + paper if k.startswith("line.towers.")]
    assert set(section) - set(paper) == {"line.tension", "line.towers_file"}


def test_spectral_line_without_a_closed_form():
    """On unequal spans the closed form (and its ASCE 74 factor) is not applicable: a line of text,
    not a formatting error."""
    from linecheck.cli.spectral_cmd import davenport_line

    note = "not applicable: the spans of this section are unequal (the closed form is for one span length)"
    doc = {"davenport": {"applicable": False, "note": note, "GF_ASCE74": None}}
    assert davenport_line(doc) == f"closed form (Davenport/Castanheta): not shown: {note}. ASCE 74 wire GRF n/a."
    doc["davenport"]["GF_ASCE74"] = 1.23456
    assert davenport_line(doc).endswith("ASCE 74 wire GRF 1.235.")


def test_tui_codes_rows_name_the_section_towers():
    """The TUI's Codes table labels a section's towers "index name"."""
    from linecheck.io.document import CodeCheckRecord, CodeTower, CodeVerdict
    from linecheck.tui.widgets.codes import codes_rows

    block = CodeCheckRecord(edition="2010", verified=True, provision="synoptic", inputs={}, note="", load_per_length=10.0,
                      towers=(CodeTower(7, {"Ry": CodeVerdict(4000.0, 5000.0, 1.25, "code exceeded by 25 %")}),))
    assert codes_rows({"ASCE74": block}, {7: "T7"})[0][2] == "7 T7"
    assert codes_rows({"ASCE74": block})[0][2] == "7"  # the equal-span form: numbers only


def test_tui_summary_names_the_tower_frame():
    """The TUI's summary notes name the frame of the tower of interest's reactions (its own frame,
    as the console, the JSON and the Excel), with its heading on a section."""
    from linecheck.io.display import doc_frame_caption

    towers = (SimpleNamespace(section={"heading": 0.0}), SimpleNamespace(section={"heading": 9.0}))
    text = doc_frame_caption(SimpleNamespace(tower_of_interest=2, towers=towers))
    assert text.startswith("tower frame: x along the line bisector") and "heading 9.0 deg" in text
    paper = doc_frame_caption(SimpleNamespace(tower_of_interest=1, towers=(SimpleNamespace(section=None),)))
    assert "tower frame" in paper and "deg from the global x" not in paper
