"""Malformed sections through the CLI (section acceptance): ``linecheck check`` exits 2 with ONE
line naming the file, the row (CSV) or key (TOML), the value and what is allowed.

Each case is the shipped 12-span example with one defect: its CSV edited (one row or column) or
its TOML edited (tension, an inline [[line.towers]] table).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app

from ..conftest import CASES, one_error_line

EXAMPLE = CASES / "examples" / "section-12span.toml"
CSV = CASES / "examples" / "section-12span.csv"


def cli(*args: str):
    return CliRunner().invoke(app, list(args))


def _section(tmp_path: Path, csv_text: str | None = None, toml_edit: tuple[str, str] | None = None) -> Path:
    """A copy of the example in ``tmp_path`` (CSV text replaced when given; one TOML text edit)."""
    toml = EXAMPLE.read_text(encoding="utf-8")
    if toml_edit is not None:
        assert toml_edit[0] in toml
        toml = toml.replace(*toml_edit)
    (tmp_path / CSV.name).write_text(csv_text if csv_text is not None else CSV.read_text(encoding="utf-8"),
                                     encoding="utf-8")
    path = tmp_path / EXAMPLE.name
    path.write_text(toml, encoding="utf-8")
    return path


def _csv_with(old: str, new: str) -> str:
    text = CSV.read_text(encoding="utf-8")
    assert text.count(old) == 1, old
    return text.replace(old, new)



# CSV row numbers count the file's lines (the comment line is row 1, the header row 2, T1 row 3).
CSV_CASES = [
    pytest.param("T4,940,", "T4,600,", "row 6, column station", "value 600.0",
                 "expected stations increasing along the line", id="stations-not-increasing"),
    pytest.param("T1,0,120.0,27.0,strain,0,", "T1,0,120.0,27.0,strain,5,", "row 3, column angle", "value 5.0",
                 "expected 0", id="angle-at-end-tower"),
    pytest.param("T13,4010,150.0,27.0,strain,", "T13,4010,150.0,27.0,suspension,", "row 15, column support",
                 'value "suspension"', 'expected "strain"', id="suspension-end"),
    pytest.param("T6,1620,139.5,36.0,", "T6,1620,139.5,0,", "row 8, column height", "value 0.0",
                 "expected a number > 0", id="clamp-at-ground"),
    pytest.param("T6,1620,139.5,36.0,", "T6,1620,139.5,-2.5,", "row 8, column height", "value -2.5",
                 "expected a number > 0", id="clamp-below-ground"),
    pytest.param("T3,655,141.0,", "T3,655,abc,", "row 5, column ground", 'value "abc" is not a number',
                 "expected a number >= -1000", id="non-number"),
]


@pytest.mark.parametrize(("old", "new", "where", "value", "allowed"), CSV_CASES)
def test_bad_csv_row_names_file_row_value_and_what_is_allowed(tmp_path, old, new, where, value, allowed):
    path = _section(tmp_path, _csv_with(old, new))
    line = one_error_line(cli("check", str(path)))
    assert f"{tmp_path / CSV.name}: {where}: " in line
    assert value in line and allowed in line


def test_csv_missing_column(tmp_path):
    lines = CSV.read_text(encoding="utf-8").splitlines()
    # drop the 4th column (height) of the header and of every tower row; keep the comment line
    text = "\n".join(ln if ln.startswith("#") else ",".join(ln.split(",")[:3] + ln.split(",")[4:])
                     for ln in lines) + "\n"
    assert "height" not in text.splitlines()[1]
    line = one_error_line(cli("check", str(_section(tmp_path, text))))
    assert f"{tmp_path / CSV.name}: row 2: " in line
    assert 'missing column "height"' in line and "required: station, height, support" in line


def test_tension_too_low_for_a_span(tmp_path):
    # span 1 (T1-T2) is 310 m: its parabolic sag W L^2 / 8 H0 reaches L/4 below H0 = W L / 2
    # = 17.92 * 310 / 2 = 2777.6 N (Irvine 1981 Eq. 2.8); 2500 N is below that.
    path = _section(tmp_path, toml_edit=("tension = 22000.0", "tension = 2500.0"))
    line = one_error_line(cli("check", str(path)))
    assert re.search(rf"{re.escape(str(path))}:\d+: line\.tension: value 2500\.0 is too low for span 1 \(T1-T2, 310 m\)",
                     line), line
    assert "expected tension > W L/2 = 2777.6 N" in line


def test_tension_letting_a_span_reach_the_ground(tmp_path):
    # above W L / 2 but the 310 m span sags 17.92 * 310^2 / (8 * 6000) = 35.9 m below a chord
    # whose lower end is 27 m above ground: the clearance check names the span and the tension.
    path = _section(tmp_path, toml_edit=("tension = 22000.0", "tension = 6000.0"))
    line = one_error_line(cli("check", str(path)))
    assert "line.tension: value 6000.0 lets span 1 (T1-T2) reach the ground" in line
    assert "expected a higher tension or taller towers" in line


def test_towers_file_and_inline_towers_together(tmp_path):
    inline = '\n[[line.towers]]\nstation = 0.0\nheight = 30.0\nsupport = "strain"\n'
    path = _section(tmp_path, toml_edit=("elements_per_span = 10\n", "elements_per_span = 10\n" + inline))
    line = one_error_line(cli("check", str(path)))
    assert re.search(rf"{re.escape(str(path))}:\d+: line\.towers_file: value \"section-12span\.csv\" is not "
                     r"allowed together with \[\[line\.towers\]\]", line), line
    assert "not both" in line


INLINE = """name = "inline"
[line]
weight = 17.92
diameter = 0.022
area = 0.7e-4
elastic_modulus = 5.2e10
tension = 22000.0

[[line.towers]]
station = 0.0
height = 30.0
support = "strain"

[[line.towers]]
station = 300.0
height = 33.0
support = "suspension"
angle = {angle}

[[line.towers]]
station = {station}
height = 30.0
support = "strain"

[wind]
type = "synoptic"
v_ref = 30.0
"""


@pytest.mark.parametrize(("angle", "station", "key", "value", "allowed"), [
    ("0.0", "250.0", "line.towers[3].station", "value 250.0", "expected stations increasing"),
    ("95.0", "600.0", "line.towers[2].angle", "value 95.0 is out of range", "expected a number > -90 and <= 90 deg"),
])
def test_inline_towers_name_the_table_key_and_file_line(tmp_path, angle, station, key, value, allowed):
    path = tmp_path / "inline.toml"
    path.write_text(INLINE.format(angle=angle, station=station), encoding="utf-8")
    line = one_error_line(cli("check", str(path)))
    text = path.read_text(encoding="utf-8").splitlines()
    m = re.match(rf"error: {re.escape(str(path))}:(\d+): {re.escape(key)}: ", line)
    assert m, line
    # the line number points at that key inside that [[line.towers]] table
    assert text[int(m.group(1)) - 1].startswith(key.rsplit(".", 1)[1] + " =")
    assert value in line and allowed in line


def test_the_example_section_checks_with_a_summary_line():
    r = cli("check", str(EXAMPLE))
    assert r.exit_code == 0, r.output
    # spans of the CSV: 310 345 285 390 290 385 255 390 335 315 420 290 -> 255-420 m; T5 and T9 turn
    assert "section: 13 towers T1-T13, 12 spans, 255-420 m, 2 angle towers; tower of interest 7 (T7)" in r.output
