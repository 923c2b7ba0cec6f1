"""Case files: the key contract, validation messages, shipped cases."""

from __future__ import annotations

from pathlib import Path

import pytest

from linecheck.core.case import case_from_dict, case_to_toml, load_case, with_value
from linecheck.core.errors import CaseError

from ..conftest import CASES

GOOD = """\
name = "case09"
description = "Synoptic, L = 300 m, Vref = 40 m/s (paper case 9)"

[line]
spans = 1
span_length = 300.0
sag = 10.0
weight = 17.92
diameter = 0.022
drag_coefficient = 1.0
area = 0.7e-4
elastic_modulus = 5.2e10
height = 43.0
insulator_length = 4.0
supports = ["strain", "strain"]
tower_of_interest = 1
elements_per_span = 10

[wind]
type = "synoptic"
v_ref = 40.0
turbulence_intensity = 0.12
air_density = 1.25
coherence_decay = 10.0

[analysis]
duration = 600.0
time_step = 0.05
realizations = 10
seed = 2015
"""


def write(tmp_path: Path, text: str, name: str = "c.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def test_issue_example_loads(tmp_path):
    case = load_case(write(tmp_path, GOOD))
    assert case.name == "case09"
    assert case.line.span_length == 300.0 and case.line.supports == ("strain", "strain")
    assert case.wind.v_ref == 40.0 and case.wind.type == "synoptic"
    assert case.analysis.realizations == 10 and case.analysis.seed == 2015
    # Eq. 17: g*_yp = 1/2 * 1.25 * 1.0 * 40^2 * 0.022 = 22.0 N/m
    assert case.g_yp == pytest.approx(22.0)
    assert case.g_yp_L == pytest.approx(6600.0)


def test_name_defaults_to_file_stem(tmp_path):
    case = load_case(write(tmp_path, GOOD.replace('name = "case09"\n', ""), "my-line.toml"))
    assert case.name == "my-line"


@pytest.mark.parametrize(
    "old,new,expect",
    [
        ("v_ref = 40.0", "v_ref = -3.0", ["c.toml:21", "wind.v_ref", "-3.0", ">= 0"]),
        ("v_ref = 40.0", 'v_ref = "fast"', ["wind.v_ref", '"fast"', "a number"]),
        ("sag = 10.0", "sagg = 10.0", ["line.sagg", "unknown key", 'did you mean "sag"']),
        ('type = "synoptic"', 'type = "synoptik"', ["wind.type", '"synoptik"', '"synoptic"', "did you mean"]),
        ('supports = ["strain", "strain"]', 'supports = ["strain", "suspension"]', ["line.supports", "end towers must be \"strain\""]),
        ("spans = 1", "spans = 2", ["line.supports", "expected 3"]),
        ("tower_of_interest = 1", "tower_of_interest = 5", ["line.tower_of_interest", "5", "from 1 to 2"]),
        ("elements_per_span = 10", "elements_per_span = 2.5", ["line.elements_per_span", "2.5", "an integer"]),
        ("realizations = 10", "realizations = 0", ["analysis.realizations", ">= 1"]),
        ("weight = 17.92\n", "", ["line.weight", "missing required key"]),
    ],
)
def test_bad_values_name_file_key_value_and_allowed(tmp_path, old, new, expect):
    assert old in GOOD
    with pytest.raises(CaseError) as info:
        load_case(write(tmp_path, GOOD.replace(old, new)))
    msg = str(info.value)
    assert "\n" not in msg
    assert info.value.exit_code == 2
    for piece in expect:
        assert piece in msg, (piece, msg)


def test_toml_syntax_error_has_line_and_column(tmp_path):
    with pytest.raises(CaseError) as info:
        load_case(write(tmp_path, GOOD.replace("sag = 10.0", "sag = = 10.0")))
    assert "line 7, column" in str(info.value) and "c.toml" in str(info.value)


def test_missing_file_and_downburst_without_table(tmp_path):
    with pytest.raises(CaseError, match="file not found"):
        load_case(tmp_path / "nope.toml")
    with pytest.raises(CaseError, match=r"wind.downburst.*missing table"):
        load_case(write(tmp_path, GOOD.replace('type = "synoptic"', 'type = "downburst"')))


def test_preset_sets_paper_geometry(tmp_path):
    text = GOOD.replace('type = "synoptic"', 'type = "downburst"') + '\n[wind.downburst]\npreset = "Db_x"\n'
    # [wind.downburst] must follow [wind]: rebuild the document in order
    text = GOOD.replace('type = "synoptic"', 'type = "downburst"').replace(
        "\n[analysis]", '\n[wind.downburst]\npreset = "Db_x"\n\n[analysis]')
    case = load_case(write(tmp_path, text))
    db = case.wind.downburst
    # Table 2 note: Db_x = D_j 2 L_x, R = 1.6 D_j, Theta = 30 deg
    assert (db.jet_diameter, db.distance, db.angle) == (600.0, 960.0, 30.0)
    with pytest.raises(CaseError, match="contradicts preset"):
        load_case(write(tmp_path, text.replace('preset = "Db_x"', 'preset = "Db_x"\nangle = 10.0')))


def test_round_trip_and_with_value(tmp_path):
    case = load_case(write(tmp_path, GOOD))
    again = case_from_dict(__import__("tomllib").loads(case_to_toml(case)))
    assert again.line == case.line and again.wind == case.wind and again.analysis == case.analysis
    faster = with_value(case, "wind.v_ref", 20.0)
    assert faster.wind.v_ref == 20.0 and faster.line == case.line
    with pytest.raises(CaseError, match="wind.v_ref"):
        with_value(case, "wind.v_ref", -1.0)


def test_all_shipped_cases_validate():
    files = sorted(CASES.rglob("*.toml"))
    assert len([f for f in files if f.parent.name == "paper"]) == 24
    for f in files:
        case = load_case(f)
        if f.parent.name == "paper":
            n = int(f.stem[4:6])
            assert case.line.span_length == (300.0 if n in (1, 2, 5, 6, 9, 10) else 500.0)
            assert case.wind.v_ref == (40.0 if n % 2 else 20.0)
            assert case.wind.type == ("synoptic" if n >= 9 else "downburst")
            assert case.line.tower_of_interest == (1 if f.stem.endswith("single") else 4)


def test_case_reference_doc_is_up_to_date():
    """docs/case-files.md is generated from the schema; regenerate with tools/make_case_reference.py."""
    import importlib.util

    from ..conftest import ROOT

    spec = importlib.util.spec_from_file_location("mcr", ROOT / "tools" / "make_case_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert (ROOT / "docs" / "case-files.md").read_text() == mod.render()


def test_cli_error_is_one_line_exit_2_and_keeps_brackets(tmp_path):
    """Messages name TOML tables in brackets; the CLI must not eat them as markup."""
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    bad = write(tmp_path, "[line]\nspans = 1\n")
    r = CliRunner().invoke(app, ["run", str(bad)])
    assert r.exit_code == 2
    out = r.output.strip()
    assert "missing required table [wind]" in out and "Traceback" not in out
    assert len(out.splitlines()) == 1
