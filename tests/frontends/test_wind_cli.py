"""`linecheck wind CASE --csv --json --realization` (paper Fig. 3)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.cli.wind_cmd import CSV_COLUMNS

from ..conftest import CASES

runner = CliRunner()


def read_csv(path):
    header = path.read_text().splitlines()[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return header, data


def test_wind_writes_csv_and_json_for_a_downburst(tmp_path):
    out_csv, out_json = tmp_path / "p.csv", tmp_path / "p.json"
    res = runner.invoke(app, ["wind", str(CASES / "paper" / "case01-six.toml"), "--csv", str(out_csv),
                              "--json", str(out_json), "--realization", "2"])
    assert res.exit_code == 0, res.output
    header, data = read_csv(out_csv)
    assert tuple(header) == CSV_COLUMNS
    t, mean, fluct, total = data[:, 0], data[:, 2], data[:, 3], data[:, 4]
    assert t[0] == 0.0 and t[-1] == pytest.approx(600.0) and t.size == 12001
    assert mean.max() == pytest.approx(40.0, abs=1e-6)  # V_ref at p, at T1 = 120 s
    assert t[np.argmax(mean)] == pytest.approx(120.0)
    np.testing.assert_allclose(total, mean + fluct, atol=2e-6)  # 6 decimals in the file
    assert data[:, 5].max() == pytest.approx(1.0, abs=1e-6)  # mean / V_ref
    doc = json.loads(out_json.read_text())
    assert doc["case"] == "case01-six" and doc["wind"] == "downburst" and doc["realization"] == 2
    assert doc["point_p"]["x"] == pytest.approx(1380.0) and doc["point_p"]["node_x"] == pytest.approx(1380.0)
    assert doc["mean"]["max"] == pytest.approx(40.0, rel=1e-12)
    assert doc["length_scale"] == 600.0 and doc["downburst"]["preset"] == "Db_x"
    assert doc["total"]["max"] >= doc["mean"]["max"] * 0.9 and doc["gust_factor"] > 1.0
    # another realization gives another turbulence record, the same mean
    res1 = runner.invoke(app, ["wind", str(CASES / "paper" / "case01-six.toml"), "--csv", str(tmp_path / "q.csv")])
    assert res1.exit_code == 0, res1.output
    _, other = read_csv(tmp_path / "q.csv")
    np.testing.assert_array_equal(other[:, 2], mean)
    assert not np.array_equal(other[:, 3], fluct)


def test_wind_synoptic_summary(tmp_path):
    out_json = tmp_path / "s.json"
    res = runner.invoke(app, ["wind", str(CASES / "paper" / "case09-six.toml"), "--json", str(out_json)])
    assert res.exit_code == 0, res.output
    doc = json.loads(out_json.read_text())
    assert doc["wind"] == "synoptic" and "downburst" not in doc
    assert doc["mean"]["max"] == 40.0 and doc["point_p"]["x"] == 900.0
    # one 600 s record at one point: the unit field's std scatters by ~10 % (few dof at 0.03 Hz)
    assert doc["fluctuation"]["std"] == pytest.approx(0.12 * 40.0, rel=0.3)


def test_wind_user_field_case_runs(tmp_path):
    out_csv = tmp_path / "u.csv"
    res = runner.invoke(app, ["wind", str(CASES / "examples" / "downburst-user-field.toml"), "--csv", str(out_csv)])
    assert res.exit_code == 0, res.output
    _, data = read_csv(out_csv)
    assert data[:, 2].max() == pytest.approx(40.0, abs=1e-6)


def test_wind_errors_are_one_line_with_exit_2(tmp_path):
    case = CASES / "paper" / "case09-six.toml"
    res = runner.invoke(app, ["wind", str(case), "--realization", "11"])
    assert res.exit_code == 2 and "realization 11 is out of range: expected 1 to 10" in res.output
    res = runner.invoke(app, ["wind", str(case), "--csv", str(tmp_path)])
    assert res.exit_code == 2 and "is a directory" in res.output
    bad = tmp_path / "bad.csv"
    bad.write_text("r_over_dj,z_over_dj,t,speed\n0,0,0,1\n")
    text = (CASES / "examples" / "downburst-user-field.toml").read_text().replace(
        '"../fields/example-field.csv"', '"bad.csv"')
    (tmp_path / "c.toml").write_text(text)
    res = runner.invoke(app, ["wind", str(tmp_path / "c.toml"), "--csv", str(tmp_path / "o.csv")])
    assert res.exit_code == 2
    assert 'bad.csv:1: header column 4 "speed" is not allowed' in " ".join(res.output.split())
    assert not (tmp_path / "o.csv").exists()


def test_wind_json_reports_the_line_peak_beside_v_ref(tmp_path):
    """The downburst block carries the field's largest running mean on the line over the event
    (where and when) beside V_ref at p: for case 5 (Db_y, the storm centred on p's normal) that is
    V_ref itself, at p (x = 900 m), at the running mean's peak (t1 = 120 s); the console says so."""
    out = tmp_path / "w.json"
    res = runner.invoke(app, ["wind", str(CASES / "paper" / "case05-six.toml"), "--json", str(out)])
    assert res.exit_code == 0, res.output
    lp = json.loads(out.read_text())["downburst"]["line_peak"]
    assert lp["speed"] == pytest.approx(40.0, rel=1e-9) and lp["over_v_ref"] == pytest.approx(1.0, rel=1e-9)
    assert lp["station"] == pytest.approx(900.0) and lp["time"] == pytest.approx(120.0, abs=0.05)
    assert "largest running mean on the line" in res.output


def test_a_model_spread_keeps_the_jet_velocity_of_both_ring_models():
    """Switching a case to either ring model keeps its jet_velocity (both read it); the other
    models drop it."""
    from linecheck import service
    from linecheck.core.case import load_case

    case = load_case(CASES / "examples" / "downburst-ring-jet.toml")
    assert "wind.downburst.jet_velocity" not in service.model_changes(case, "ring-jet-inviscid")
    assert service.model_changes(case, "holmes-oliver")["wind.downburst.jet_velocity"] is None
