"""Values the schema allows but that are probably mistyped: a weight typed in
kg/m is warned about in one line by ``check``, ``static``, ``modes`` and ``run``."""

from __future__ import annotations

import dataclasses
import math

import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core.case import DENSITY_RANGE, GRAVITY, case_warnings, load_case

from ..conftest import CASES

runner = CliRunner()
PAPER = CASES / "paper" / "case01-single.toml"


def _kg_per_m_case(tmp_path):
    """The paper's case with its weight 17.92 N/m typed as 1.827 (kg/m)."""
    text = PAPER.read_text()
    assert "\nweight = 17.92 " in text
    path = tmp_path / "kgm.toml"
    path.write_text(text.replace("\nweight = 17.92 ", "\nweight = 1.827 "))
    return path


def test_paper_conductor_density_is_inside_the_range():
    case = load_case(PAPER)
    rho = case.line.weight / (GRAVITY * math.pi * case.line.diameter**2 / 4)
    assert rho == pytest.approx(4805, abs=1)
    assert DENSITY_RANGE[0] < rho < DENSITY_RANGE[1]
    assert case_warnings(case) == []


def test_weight_in_kg_per_m_is_one_line_naming_file_key_value_density_and_n_per_m(tmp_path):
    path = _kg_per_m_case(tmp_path)
    (msg,) = case_warnings(load_case(path))
    assert "\n" not in msg
    assert msg.startswith(f"{path}:8: line.weight: value 1.827 N/m")
    assert "bulk density W/(g pi D^2/4) of 490 kg/m3" in msg
    assert "1.827 x 9.81 = 17.92 N/m" in msg


def test_heavy_weight_is_warned_too():
    case = load_case(PAPER)
    heavy = dataclasses.replace(case, line=dataclasses.replace(case.line, weight=6 * 17.92))
    (msg,) = case_warnings(heavy)
    assert "of 28,8" in msg and "outside 1,500-9,000" in msg


def test_check_and_static_warn_and_still_succeed(tmp_path):
    path = _kg_per_m_case(tmp_path)
    res = runner.invoke(app, ["check", str(PAPER)])
    assert res.exit_code == 0 and "warning" not in res.output
    res = runner.invoke(app, ["check", str(path)])
    assert res.exit_code == 0, res.output
    warnings = [ln for ln in res.output.splitlines() if ln.startswith("warning: ")]
    assert len(warnings) == 1 and "line.weight" in warnings[0] and "490 kg/m3" in warnings[0]
    assert "ok " in res.output
    res = runner.invoke(app, ["static", str(path)])
    assert res.exit_code == 0, res.output
    assert sum(ln.startswith("warning: ") and "line.weight" in ln for ln in res.output.splitlines()) == 1
