"""Uplift in the front ends: `check` warns, `static` reports it and exits 0, `run` (and every job
that linearises) refuses in one line, a run that can proceed carries every suspension tower's
margin (JSON, console, Excel, TUI summary).

The valley section of tests/core/test_uplift.py: T3 40 m below its neighbours lifts in still air
(margin -2 V_0 = -491.65 N, Irvine's closed form there); 20 m below it hangs (2420.88 N in still air).
"""

from __future__ import annotations

import json
import re

import pytest
from openpyxl import load_workbook
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core.case import case_to_toml
from linecheck.io.document import RunDocument

from ..core.test_uplift import W, valley_case

RUN_ERROR = ("error: valley: uplift at tower T3 (margin -492 N in still air): the dynamic model needs every "
             "suspension insulator in tension; see `linecheck static`")


def _write(tmp_path, drop: float):
    path = tmp_path / f"valley{drop:g}.toml"
    path.write_text(case_to_toml(valley_case(drop)), encoding="utf-8")
    return path


def _invoke(*args):
    return CliRunner(env={"COLUMNS": "250"}).invoke(app, [str(a) for a in args])


def test_check_warns_in_one_line(tmp_path):
    r = _invoke("check", _write(tmp_path, 40.0))
    assert r.exit_code == 0, r.output
    lines = [ln for ln in r.output.splitlines() if "uplift" in ln]
    assert len(lines) == 1
    assert re.match(r"warning: valley: uplift at tower T3 \(margin -492 N in still air, -\d+ N under the mean wind\)",
                    lines[0])


def test_check_of_a_hanging_section_says_nothing_of_uplift(tmp_path):
    r = _invoke("check", _write(tmp_path, 20.0))
    assert r.exit_code == 0 and "uplift" not in r.output, r.output


def test_static_reports_the_uplift_and_exits_0(tmp_path):
    """`static` exits 0; the JSON's suspension towers carry ``uplift`` (margin [N], weight span [m],
    held) in still air and under the mean wind, strain towers none; the console marks the held
    clamp and names the tower with its margins in kN."""
    out = tmp_path / "s.json"
    r = _invoke("static", _write(tmp_path, 40.0), "--json", out)
    assert r.exit_code == 0, r.output
    towers = json.loads(out.read_text(encoding="utf-8"))["towers"]
    assert "uplift" not in towers[0] and "uplift" not in towers[5]
    u = towers[2]["uplift"]
    assert u["still_air"]["margin"] == pytest.approx(-491.649, abs=1e-3)
    assert u["still_air"]["weight_span"] == pytest.approx(-491.649 / W, abs=1e-4)
    assert u["still_air"]["held"] is True and u["held"] is True
    assert u["margin"] < u["still_air"]["margin"] and u["weight_span"] == pytest.approx(u["margin"] / W)
    assert towers[2]["Rz"] == u["margin"]  # the margin is the tower's total R_z
    assert [t["uplift"]["held"] for t in towers[1:5]] == [False, True, False, False]
    assert all(t["uplift"]["margin"] > 0 for t in (towers[1], towers[3], towers[4]))
    assert re.search(r"│\s+3 \*\s+│ T3\s+│.*│\s+suspension │\s+-\d+\.\d !\s+│", r.output)
    assert re.search(r"uplift at tower T3: margin -0\.492 kN in still air \(weight span -27\.4 m\), -\d\.\d{3} kN under "
                     r"the mean wind", r.output)
    assert "run, modes and spectral refuse the case" in r.output


@pytest.mark.parametrize("command", ["run", "modes", "spectral"])
def test_jobs_that_linearise_exit_1_with_one_line(tmp_path, command):
    r = _invoke(command, _write(tmp_path, 40.0))
    assert r.exit_code == 1
    assert r.output.strip() == RUN_ERROR  # one line, no traceback


def test_run_of_a_hanging_section_reports_every_margin(tmp_path):
    """20 m lower, T3 hangs: the run completes and its JSON has ``uplift`` at every suspension tower
    (the still-air margin of T3 2420.88 N, Irvine's), none at the strain towers; it reads back
    unchanged; the console, the Excel case sheet and the TUI summary name the smallest margin."""
    out, book = tmp_path / "r.json", tmp_path / "r.xlsx"
    r = _invoke("run", _write(tmp_path, 20.0), "--json", out, "--excel", book, "--no-check")
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text(encoding="utf-8"))
    assert [("uplift" in t) for t in d["towers"]] == [False, True, True, True, True, False]
    u3 = d["towers"][2]["uplift"]
    assert u3["still_air"]["margin"] == pytest.approx(2420.877, abs=1e-3)
    assert u3["time"] == 0.0 and u3["margin"] > 0 and u3["weight_span"] == pytest.approx(u3["margin"] / W)
    doc = RunDocument.from_json(d)
    assert doc.to_json() == d and doc.towers[2].uplift.margin == u3["margin"]
    assert re.search(rf"uplift margin: smallest {u3['margin'] / 1e3:.3f} kN at tower T3 under the mean wind", r.output)
    ws = load_workbook(book)["valley"]
    rows = [row for row in ws.iter_rows(values_only=True) if row[0] and str(row[0]).startswith("3 T3")]
    assert rows[-1][2:6] == pytest.approx((2.420877, 2420.877 / W, u3["margin"] / 1e3, u3["weight_span"]), rel=1e-6)
    from linecheck.io.display import uplift_run_text

    assert uplift_run_text(doc).startswith(f"uplift margin: smallest {u3['margin'] / 1e3:.3f} kN at tower T3")


def test_an_older_result_without_uplift_reads_and_writes_unchanged(tmp_path):
    """Results saved before the uplift was recorded have no ``uplift`` key: they read back with
    none and are written again byte for byte."""
    out = tmp_path / "r.json"
    assert _invoke("run", _write(tmp_path, 20.0), "--json", out, "--no-check").exit_code == 0
    d = json.loads(out.read_text(encoding="utf-8"))
    for t in d["towers"]:
        t.pop("uplift", None)
    doc = RunDocument.from_json(d)
    assert all(t.uplift is None for t in doc.towers) and doc.to_json() == d
