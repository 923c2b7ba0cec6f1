"""`static` of a case with [[wires]]: every attachment is its wire's own single-wire step 1, the
tower totals are the attachments' resultant and moment about the tower's base (docs/wires.md),
one wind for every wire, the JSON blocks and their schema, the console, `check`'s uplift and a
bad reference through the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.case import case_to_toml, load_case, wire_case
from linecheck.core.wind.downburst_case import reference_height
from linecheck.core.wind.mean import downburst_field, mean_speed_at_nodes
from linecheck.io.jsonout import wires_static_to_dict

from ..conftest import one_error_line
from ..schema_check import errors
from ..two_wires import DOWNBURST, TOWERS, WIRES, two_wires_text, write_two_wires

REACTIONS = ("Rx", "Ry", "Rz")
TOTALS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")


def _invoke(*args):
    return CliRunner(env={"COLUMNS": "250"}).invoke(app, [str(a) for a in args])


def _static_json(tmp_path, path, name: str) -> dict:
    out = tmp_path / f"{name}.json"
    r = _invoke("static", path, "--json", out)
    assert r.exit_code == 0, r.output
    return json.loads(out.read_text(encoding="utf-8"))


def _values(v) -> np.ndarray:
    return np.atleast_1d(np.asarray(v, dtype=float))


# --------------------------------------------------------------------------- (a) each wire alone
@pytest.mark.parametrize("wind", ["synoptic", "downburst"])
def test_every_attachment_is_its_wires_own_static(tmp_path, wind):
    """Acceptance (a): each attachment's mean reactions (total, wind-induced, still air; every
    step-1 instant of a downburst) equal `linecheck static` of that wire's single-wire case
    written as a case file (its own JSON) -- identical, within 1e-12 of the largest reaction
    (the acceptance allows 0.1 %)."""
    path = write_two_wires(tmp_path, **({"wind": DOWNBURST} if wind == "downburst" else {}))
    case = load_case(path)
    doc = _static_json(tmp_path, path, "all")
    for w, wire in enumerate(case.wires):
        alone = tmp_path / f"wire-{wire.name}.toml"
        alone.write_text(case_to_toml(wire_case(case, wire.name)), encoding="utf-8")
        single = _static_json(tmp_path, alone, wire.name)
        scale = max(np.abs(_values(t[r])).max() for t in single["towers"] for r in REACTIONS)
        for t, s in zip(doc["towers"], single["towers"]):
            a = t["attachments"][w]
            assert a["wire"] == wire.name and a["support"] == s["support"] and a["height"] == s["height"]
            for key in (*REACTIONS, *(f"{r}_wind" for r in REACTIONS), *(f"{r}_still_air" for r in REACTIONS)):
                np.testing.assert_allclose(_values(a[key]), _values(s[key]), rtol=0, atol=1e-12 * scale, err_msg=key)
            assert ("uplift" in a) == ("uplift" in s) == (s["support"] == "suspension")
            if "uplift" in a:
                assert a["uplift"] == s["uplift"]
        assert doc["wires"][w]["spans"] == single["spans"]
    if wind == "downburst":
        assert doc["time"] == single["time"] and len(doc["time"]) == case.analysis.mean_states


def test_one_wind_for_every_wire(tmp_path):
    """Every wire sees the case's wind: V_ref (z / z_ref)^alpha with the case's z_ref (the first
    wire's mean clamp height), not the wire's own mean clamp height; a downburst is one storm
    (one V_max)."""
    case = load_case(write_two_wires(tmp_path))
    z_ref = case.line.height
    assert z_ref == pytest.approx(np.mean([27.0, 30.0 - 3.5, 30.0 - 3.5, 27.0]))
    res = service.wires_static_analysis(case)
    for st in res.wires:
        assert reference_height(st.case) == z_ref
        speed = mean_speed_at_nodes(st.case, st.system, np.zeros(1))[0]
        h = st.system.node_height
        # synoptic, direction 15 deg: the power law at each node (Hellmann 1916), v_ref = 32 m/s, alpha = 0.16
        np.testing.assert_allclose(speed, 32.0 * (h / z_ref) ** 0.16, rtol=1e-12)
    assert res.wires[1].case.line.height > z_ref + 8.0  # the ground wire's own mean clamp height: 10 m above
    db = load_case(write_two_wires(tmp_path, "db.toml", wind=DOWNBURST))
    v_max = {downburst_field(wire_case(db, w.name)).v_max for w in db.wires}
    assert len(v_max) == 1


# --------------------------------------------------------------------------- (b) identical wires at one point
IDENTICAL = WIRES.split("[[tower_types]]")[0].replace('name = "G"', 'name = "Q"').replace("""\
weight = 5.8
diameter = 0.0126
area = 9.8e-5
elastic_modulus = 1.5e11
tension = 9000.0
""", """\
weight = 15.97
diameter = 0.0281
area = 4.25e-4
elastic_modulus = 6.9e10
tension = 25000.0
bundle = 2
bundle_spacing = 0.45
""") + """\
[[wires]]
name = "R"
kind = "phase"
weight = 15.97
diameter = 0.0281
area = 4.25e-4
elastic_modulus = 6.9e10
tension = 25000.0
bundle = 2
bundle_spacing = 0.45

[[tower_types]]
name = "S"
attachments = [
    { wire = "P", y = 0.0, z = 30.0, support = "suspension", insulator_length = 3.5 },
    { wire = "Q", y = 0.0, z = 30.0, support = "suspension", insulator_length = 3.5 },
    { wire = "R", y = 0.0, z = 30.0, support = "suspension", insulator_length = 3.5 },
]

[[tower_types]]
name = "DE"
attachments = [
    { wire = "P", y = 0.0, z = 27.0, support = "strain" },
    { wire = "Q", y = 0.0, z = 27.0, support = "strain" },
    { wire = "R", y = 0.0, z = 27.0, support = "strain" },
]
"""


def test_identical_wires_at_one_point_are_n_times_one_wire(tmp_path):
    """Acceptance (b): three identical wires at one point (y = 0, the same z) each give the single
    wire's reactions, so the totals are F = 3 R and, with r = (0, 0, z) and F = (R_x, R_y, -R_z)
    (z up), M = r x F = (-z F_y, z F_x, 0): M_x = -3 z R_y, M_y = 3 z R_x, M_z = 0."""
    path = tmp_path / "three.toml"
    path.write_text(two_wires_text(wires=IDENTICAL), encoding="utf-8")
    case = load_case(path)
    assert [w.name for w in case.wires] == ["P", "Q", "R"]
    doc = _static_json(tmp_path, path, "three")
    alone = tmp_path / "one.toml"
    alone.write_text(case_to_toml(wire_case(case, "P")), encoding="utf-8")
    single = _static_json(tmp_path, alone, "one")
    for t, s in zip(doc["towers"], single["towers"]):
        z = 27.0 if t["type"] == "DE" else 30.0
        for a in t["attachments"]:
            assert (a["y"], a["z"]) == (0.0, z)
            assert all(a[r] == s[r] for r in REACTIONS)  # the same wire: bit for bit
        tot = t["totals"]
        for part in ("", "_wind", "_still_air"):
            rx, ry, rz = (s[f"{r}{part}"] for r in REACTIONS)
            assert [tot[f"{f}{part}"] for f in ("Fx", "Fy", "Fz")] == pytest.approx([3 * rx, 3 * ry, 3 * rz], rel=1e-14)
            assert tot[f"Mx{part}"] == pytest.approx(-3 * z * ry, rel=1e-14)
            assert tot[f"My{part}"] == pytest.approx(3 * z * rx, rel=1e-14)
            assert tot[f"Mz{part}"] == 0.0
            # the tower's single-wire keys are the totals' forces
            assert [t[f"{r}{part}"] for r in REACTIONS] == [tot[f"{f}{part}"] for f in ("Fx", "Fy", "Fz")]


# --------------------------------------------------------------------------- (c) the moments' signs
def test_moment_signs_on_a_hand_example():
    """Acceptance (c): one attachment at y = 5 m (left), z = 30 m with R = (2, 10, 20) kN (x along
    the line, y left, z down): F = (2, 10, 20) kN; with F_up = (2, 10, -20) kN and r = (0, 5, 30) m,
    M = r x F_up = (5 (-20) - 30 (10), 30 (2) - 0, 0 - 5 (2)) = (-400, 60, -10) kN m.  Read: the
    wind toward +y and the weight on the left arm both tip the top toward +y (a rotation about
    -x), the pull along +x tips it forward (about +y), and the pull along +x on the left arm
    twists the tower clockwise seen from above (about -z)."""
    R = np.array([[[2e3, 10e3, 20e3]]])
    tot = service.tower_totals(R, np.array([[5.0]]), np.array([[30.0]]))
    np.testing.assert_allclose(tot[0], [2e3, 10e3, 20e3, -400e3, 60e3, -10e3], rtol=1e-15)
    np.testing.assert_allclose(tot[0, 3:], np.cross([0.0, 5.0, 30.0], [2e3, 10e3, -20e3]), rtol=1e-15)
    # each part alone, and two attachments add
    for R1, M in [((0, 10e3, 0), (-300e3, 0, 0)), ((0, 0, 20e3), (-100e3, 0, 0)), ((2e3, 0, 0), (0, 60e3, -10e3))]:
        np.testing.assert_allclose(service.tower_totals(np.array([[R1]]), np.array([[5.0]]),
                                   np.array([[30.0]]))[0, 3:], M, rtol=1e-15, atol=0)
    two = service.tower_totals(np.array([[[0, 0, 20e3], [0, 0, 20e3]]]), np.array([[5.0, -5.0]]), np.array([[30.0, 30.0]]))
    np.testing.assert_allclose(two[0], [0, 0, 40e3, 0, 0, 0], atol=1e-9)  # symmetric arms: no moment


def test_the_wind_overturns_the_tower_about_minus_x(tmp_path):
    """On the two-wire case (wind 15 deg off the normal, toward +y) every suspension tower's
    wind-induced Fy is positive and its Mx_wind negative, Mx_wind = -sum z Ry_wind - sum y Rz_wind."""
    doc = _static_json(tmp_path, write_two_wires(tmp_path), "two")
    for t in doc["towers"]:
        ry = [a["Ry_wind"] for a in t["attachments"]]
        assert t["totals"]["Fy_wind"] == pytest.approx(sum(ry), rel=1e-14)
        hand = -sum(a["z"] * a["Ry_wind"] + a["y"] * a["Rz_wind"] for a in t["attachments"])
        assert t["totals"]["Mx_wind"] == pytest.approx(hand, rel=1e-13)
        if t["type"] == "S":
            assert t["totals"]["Fy_wind"] > 0 and t["totals"]["Mx_wind"] < 0


# --------------------------------------------------------------------------- JSON, console, check
@pytest.mark.parametrize("wind", ["synoptic", "downburst"])
def test_the_document_blocks_follow_the_schema(tmp_path, wind):
    from ..conftest import _result_schema

    path = write_two_wires(tmp_path, **({"wind": DOWNBURST} if wind == "downburst" else {}))
    doc = _static_json(tmp_path, path, "two")
    schema = _result_schema()
    for t in doc["towers"]:
        assert set(t) >= {"index", "name", "station", "ground", "angle", "heading", "type", "attachments", "totals"}
        for a in t["attachments"]:
            assert errors(a, {"$ref": "#/$defs/static_attachment"}, schema) == []
        assert errors(t["totals"], {"$ref": "#/$defs/static_totals"}, schema) == []
        assert set(TOTALS) <= set(t["totals"])
    bad = dict(doc["towers"][1]["attachments"][0], Ry="x")
    del bad["wire"]
    assert len(errors(bad, {"$ref": "#/$defs/static_attachment"}, schema)) == 2
    assert [w["name"] for w in doc["wires"]] == ["P", "G"] and len(doc["wires"][0]["spans"]) == 3
    series = isinstance(doc["towers"][0]["totals"]["Fy"], list)
    assert series == (wind == "downburst")


def test_the_console_shows_every_attachment_and_the_totals(tmp_path):
    r = _invoke("static", write_two_wires(tmp_path))
    assert r.exit_code == 0, r.output
    assert "step-1 mean reactions at every attachment (kN)" in r.output
    assert "tower totals, forces (kN) and moments about the tower's base (kN m)" in r.output
    assert "Mx = -sum(z Ry + y Rz), My = sum z Rx, Mz = -sum y Rx" in " ".join(r.output.split())
    assert "wire P: span tensions H (kN)" in r.output and "wire G: span tensions H (kN)" in r.output


def test_uplift_per_attachment_in_static_and_check(tmp_path):
    """T2 45 m below ground level of its neighbours: both its clamps lift.  `static` exits 0 and
    names each attachment; `check` warns once per wire."""
    path = write_two_wires(tmp_path, towers=TOWERS.replace("ground = 3.0", "ground = -45.0"))
    r = _invoke("static", path, "--json", tmp_path / "v.json")
    assert r.exit_code == 0, r.output
    doc = json.loads((tmp_path / "v.json").read_text(encoding="utf-8"))
    for a in doc["towers"][1]["attachments"]:
        assert a["uplift"]["held"] is True and a["uplift"]["margin"] == a["Rz"] < 0
    for wire in ("P", "G"):
        assert f"uplift at tower T2, wire {wire}: margin -" in r.output
    c = _invoke("check", path)
    assert c.exit_code == 0, c.output
    lines = [ln for ln in c.output.splitlines() if ln.startswith("warning:")]
    assert [ln.split(":")[1] for ln in lines] == [" two, wire P", " two, wire G"]
    assert all(": uplift at tower T2 (margin -" in ln for ln in lines)


def test_a_bad_reference_exits_2_through_static(tmp_path):
    """Acceptance (d): an unknown wire in an attachment and an unknown tower type, one line each."""
    bad_wire = write_two_wires(tmp_path, "w.toml", wires=WIRES.replace('{ wire = "G", y = 0.0, z = 38.0',
                                                                       '{ wire = "X", y = 0.0, z = 38.0'))
    line = one_error_line(_invoke("static", bad_wire))
    assert "tower_types[1].attachments[2].wire: value \"X\" is not allowed" in line
    bad_type = write_two_wires(tmp_path, "t.toml", towers=TOWERS.replace('type = "S"\n', 'type = "SS"\n', 1))
    line = one_error_line(_invoke("static", bad_type))
    assert 'line.towers[2].type: value "SS" is not allowed' in line and '(did you mean "S"?)' in line


def test_the_service_keeps_one_wire_jobs_off_a_case_with_wires(tmp_path):
    """Step 1 of the case's line alone (its first wire) is refused: every wire goes through
    wires_static_analysis, which refuses a case without wires."""
    case = load_case(write_two_wires(tmp_path))
    with pytest.raises(ValueError, match="wires_static_analysis"):
        service.static_result(case)
    with pytest.raises(ValueError, match="no \\[\\[wires\\]\\]"):
        service.wires_static_analysis(wire_case(case, "P"))
    doc = wires_static_to_dict(service.wires_static_analysis(case))
    assert [a["wire"] for a in doc["towers"][0]["attachments"]] == ["P", "G"]
