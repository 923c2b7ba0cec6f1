"""The shipped every-wire example, cases/examples/section-12span-double-circuit.toml: the 12-span
section of section-12span.toml carrying a double circuit (six twin-bundle phases) and two ground
wires.  It loads, `check` accepts it without a warning, and `static --json` reports every
attachment of every tower and the tower totals (docs/wires.md)."""

from __future__ import annotations

import json
import math

import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core.case import load_case

from ..conftest import CASES

EXAMPLE = CASES / "examples" / "section-12span-double-circuit.toml"
SINGLE = CASES / "examples" / "section-12span.toml"
PHASES = ("A1", "B1", "C1", "A2", "B2", "C2")
GROUND = ("G1", "G2")


def _invoke(*args):
    return CliRunner(env={"COLUMNS": "250"}).invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def static_doc(tmp_path_factory):
    out = tmp_path_factory.mktemp("example-wires") / "static.json"
    r = _invoke("static", EXAMPLE, "--json", out)
    assert r.exit_code == 0, r.output
    return json.loads(out.read_text(encoding="utf-8"))


def test_the_example_loads_with_eight_wires_and_a_type_on_every_tower():
    case = load_case(EXAMPLE)
    assert [w.name for w in case.wires] == [*PHASES, *GROUND]
    assert [w.kind for w in case.wires] == ["phase"] * 6 + ["ground"] * 2
    assert [w.bundle for w in case.wires] == [2] * 6 + [1] * 2
    assert all(w.bundle_spacing == 0.4 for w in case.wires[:6])
    towers = case.line.towers
    assert len(towers) == 13
    names = {t.name for t in case.tower_types}
    assert all(t.type in names for t in towers)
    assert [t.name for t in towers if t.type == "angle-strain"] == ["T1", "T5", "T13"]
    for tt in case.tower_types:  # every type carries every wire
        assert sorted(a.wire for a in tt.attachments) == sorted([*PHASES, *GROUND])


def test_the_example_is_the_single_wire_section():
    """The same stations, ground, angles, tower of interest and wind as section-12span.toml."""
    double, single = load_case(EXAMPLE), load_case(SINGLE)
    assert [(t.name, t.station, t.ground, t.angle) for t in double.line.towers] == \
           [(t.name, t.station, t.ground, t.angle) for t in single.line.towers]
    assert double.line.tower_of_interest == single.line.tower_of_interest == 7
    assert double.wind == single.wind
    phase = double.wires[0]
    assert (phase.weight, phase.diameter, phase.area, phase.elastic_modulus) == \
           (single.line.weight, single.line.diameter, single.line.area, single.line.elastic_modulus)


def test_check_accepts_the_example_without_a_warning():
    r = _invoke("check", EXAMPLE)
    assert r.exit_code == 0, r.output
    assert r.output.startswith("ok ") and "warning" not in r.output


def test_static_reports_eight_attachments_per_tower_and_the_totals(static_doc):
    assert [w["name"] for w in static_doc["wires"]] == [*PHASES, *GROUND]
    assert [w["bundle"] for w in static_doc["wires"]] == [2] * 6 + [1] * 2
    towers = static_doc["towers"]
    assert [t["name"] for t in towers] == [f"T{i}" for i in range(1, 14)]
    for t in towers:
        att = t["attachments"]
        assert [a["wire"] for a in att] == [*PHASES, *GROUND], t["name"]
        assert set(t["totals"]) >= {f"{k}{s}" for k in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
                                   for s in ("", "_wind", "_still_air")}
        # the example's wind (35 m/s, 30 deg off the normal, toward +y) pushes every wire to +y
        assert all(a["Ry_wind"] > 0.0 for a in att), (t["name"], [a["Ry_wind"] for a in att])
        for key in ("Fx", "Fy", "Fz"):  # the totals' forces: the sums of the attachments' (round-off)
            for suffix in ("", "_wind", "_still_air"):
                values = [a["R" + key[1:] + suffix] for a in att]
                assert math.isclose(t["totals"][key + suffix], sum(values), rel_tol=0.0,
                                    abs_tol=1e-12 * sum(abs(v) for v in values)), (t["name"], key + suffix)
        assert t["totals"]["Fy_wind"] > 0.0 and t["totals"]["Mx_wind"] < 0.0  # wind toward +y: Mx < 0
