"""Every wire on the tower, the case contract: [[wires]], [[tower_types]] and the towers' type
parsed and checked (one-line messages naming the key and value), the bundle-equivalent wire,
each wire's single-wire case, and a case without [[wires]] unchanged."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import pytest

from linecheck.core.case import (
    GRAVITY,
    Analysis,
    Attachment,
    Case,
    CaseError,
    Line,
    TowerType,
    Wind,
    Wire,
    case_from_dict,
    case_to_dict,
    case_to_toml,
    case_warnings,
    clamp_height,
    load_case,
    wire_case,
    with_value,
)

from ..conftest import CASES

# Three wires (a twin bundle A, a single conductor B, a ground wire G), two tower types (S:
# suspension, DE: dead-end strain), three towers.
THREE = """\
name = "three"

[line]
insulator_length = 3.6
tower_of_interest = 2

[[line.towers]]
name = "T1"
station = 0.0
type = "DE"

[[line.towers]]
name = "T2"
station = 300.0
ground = 2.0
type = "S"

[[line.towers]]
name = "T3"
station = 600.0
type = "DE"

[[wires]]
name = "A"
kind = "phase"
weight = 17.92
diameter = 0.022
area = 0.7e-4
elastic_modulus = 5.2e10
tension = 20000.0
bundle = 2
bundle_spacing = 0.4
shielding = 0.9

[[wires]]
name = "B"
kind = "phase"
weight = 17.92
diameter = 0.022
area = 0.7e-4
elastic_modulus = 5.2e10
tension = 20000.0

[[wires]]
name = "G"
kind = "ground"
weight = 6.0
diameter = 0.012
area = 0.5e-4
elastic_modulus = 1.6e11
tension = 8000.0

[[tower_types]]
name = "S"
attachments = [
    { wire = "A", y = -5.5, z = 31.0, support = "suspension" },
    { wire = "B", y = 5.5, z = 31.0, support = "suspension", insulator_length = 4.0 },
    { wire = "G", y = 0.0, z = 40.0, support = "suspension", insulator_length = 0.3 },
]

[[tower_types]]
name = "DE"
attachments = [
    { wire = "A", y = -5.5, z = 28.0, support = "strain" },
    { wire = "B", y = 5.5, z = 28.0, support = "strain" },
    { wire = "G", y = 0.0, z = 37.0, support = "strain" },
]

[wind]
type = "synoptic"
v_ref = 30.0
"""


def load(tmp_path: Path, text: str, name: str = "c.toml") -> Case:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return load_case(p)


def refused(tmp_path: Path, text: str) -> str:
    with pytest.raises(CaseError) as info:
        load(tmp_path, text)
    message = str(info.value)
    assert "\n" not in message
    return message


def edit(old: str, new: str, text: str = THREE) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


# --------------------------------------------------------------------------- parsing
def test_three_wires_two_types_parse(tmp_path):
    case = load(tmp_path, THREE)
    assert case.has_wires
    assert [w.name for w in case.wires] == ["A", "B", "G"]
    assert [w.kind for w in case.wires] == ["phase", "phase", "ground"]
    a = case.wire("A")
    assert (a.bundle, a.bundle_spacing, a.shielding, a.drag_coefficient) == (2, 0.4, 0.9, 1.0)
    assert case.wire("B") == Wire(name="B", kind="phase", weight=17.92, diameter=0.022, area=0.7e-4,
                                  elastic_modulus=5.2e10, tension=20000.0)
    assert [t.name for t in case.tower_types] == ["S", "DE"]
    assert case.tower_type("S").attachment("B") == Attachment(wire="B", y=5.5, z=31.0, support="suspension",
                                                              insulator_length=4.0)
    assert case.tower_type("DE").attachment("G") == Attachment(wire="G", y=0.0, z=37.0, support="strain")
    assert [t.type for t in case.line.towers] == ["DE", "S", "DE"]
    # the case's line is the first wire's single-wire line (its towers keep their type)
    assert case.line == dataclasses.replace(wire_case(case, "A").line, towers=case.line.towers)
    assert [t.height for t in case.line.towers] == [28.0, 31.0 - 3.6, 28.0]
    # the wind keys of the wires' coherence take their defaults (Simiu & Scanlan's 16 and 10)
    assert (case.wind.coherence_decay_y, case.wind.coherence_decay_z) == (16.0, 10.0)


def test_wire_and_type_lookups_raise_key_error(tmp_path):
    case = load(tmp_path, THREE)
    with pytest.raises(KeyError):
        case.wire("X")
    with pytest.raises(KeyError):
        case.tower_type("X")
    with pytest.raises(KeyError):
        wire_case(case, "X")
    with pytest.raises(KeyError):
        TowerType(name="S", attachments=()).attachment("A")


def test_coherence_keys_are_read_and_written_only_when_set(tmp_path):
    case = load(tmp_path, edit('v_ref = 30.0\n', 'v_ref = 30.0\ncoherence_decay_y = 12.0\ncoherence_decay_z = 8.0\n'))
    assert (case.wind.coherence_decay_y, case.wind.coherence_decay_z) == (12.0, 8.0)
    assert case_to_dict(case)["wind"]["coherence_decay_y"] == 12.0
    default = load(tmp_path, THREE)
    assert "coherence_decay_y" not in case_to_dict(default)["wind"]
    assert "coherence_decay_z" not in case_to_dict(default)["wind"]


def test_a_multi_wire_case_round_trips_through_toml_and_edits(tmp_path):
    case = load(tmp_path, THREE)
    plain = dataclasses.replace(case, source=None)
    assert case_from_dict(case_to_dict(case), default_name="three") == plain
    text = case_to_toml(case)
    assert case_from_dict(tomllib.loads(text), default_name="three") == plain
    assert "shielding" not in case_to_dict(case)["wires"][1]  # a single conductor's is at its default
    edited = with_value(case, "wind.v_ref", 35.0)
    assert edited.wires == case.wires and edited.tower_types == case.tower_types and edited.wind.v_ref == 35.0
    with pytest.raises(CaseError, match=r"line\.weight: value 3\.0 is not allowed with \[\[wires\]\]"):
        with_value(case, "line.weight", 3.0)


def test_towers_file_with_a_type_column(tmp_path):
    csv = "name,station,ground,angle,type\nT1,0,0,0,DE\nT2,300,2,0,S\nT3,600,0,0,DE\n"
    (tmp_path / "t.csv").write_text(csv, encoding="utf-8")
    start, end = THREE.index("[[line.towers]]"), THREE.index("[[wires]]")
    text = THREE[:start].replace("tower_of_interest = 2\n", 'tower_of_interest = 2\ntowers_file = "t.csv"\n') + THREE[end:]
    case = load(tmp_path, text)
    inline = load(tmp_path, THREE, "inline.toml")
    assert case.line.towers == inline.line.towers and case.line.towers_file == "t.csv"
    assert wire_case(case, "G") == dataclasses.replace(wire_case(inline, "G"), source=case.source)
    # the single-wire case holds its towers inline: it reloads without the CSV's type column
    assert case_from_dict(case_to_dict(wire_case(case, "G")), default_name="three").line == wire_case(case, "G").line

    (tmp_path / "t.csv").write_text(csv.replace(",type\n", ",kind\n"), encoding="utf-8")
    message = refused(tmp_path, text)
    assert 'unknown column "kind"' in message
    (tmp_path / "t.csv").write_text(csv.replace(",angle,type\n", ",angle\n").replace(",DE\n", "\n").replace(",S\n", "\n"),
                                    encoding="utf-8")
    message = refused(tmp_path, text)
    assert 'row 1: missing column "type"' in message and "required: station, type with [[wires]]" in message
    (tmp_path / "t.csv").write_text(csv.replace("T2,300,2,0,S", "T2,300,2,0,"), encoding="utf-8")
    message = refused(tmp_path, text)
    assert "t.csv: row 3, column type: missing: expected one of" in message


# --------------------------------------------------------------------------- bad references
BAD = [
    pytest.param(('type = "S"\n', 'type = "SS"\n'), "line.towers[2].type", 'value "SS"',
                 'expected one of "S", "DE" (the [[tower_types]] names) (did you mean "S"?)', id="unknown-type"),
    pytest.param(('ground = 2.0\ntype = "S"\n', 'ground = 2.0\n'), "line.towers[2].type", "missing",
                 'expected one of "S", "DE"', id="tower-without-type"),
    pytest.param(('{ wire = "B", y = 5.5, z = 31.0,', '{ wire = "C", y = 5.5, z = 31.0,'),
                 "tower_types[1].attachments[2].wire", 'value "C"', 'expected one of "A", "B", "G" (the [[wires]] names)',
                 id="unknown-wire"),
    pytest.param(('    { wire = "G", y = 0.0, z = 37.0, support = "strain" },\n', ''), "tower_types[2].attachments",
                 'no attachment of wire "G"', 'expected one attachment per wire ("A", "B", "G")', id="attachment-missing"),
    pytest.param(('{ wire = "G", y = 0.0, z = 37.0,', '{ wire = "A", y = 0.0, z = 37.0,'),
                 "tower_types[2].attachments[3].wire", 'value "A"', "attachment 1 of this type carries that wire",
                 id="wire-attached-twice"),
    pytest.param(('name = "B"', 'name = "A"'), "wires[2].name", 'value "A"', "wires[1] has that name; expected unique",
                 id="duplicate-wire"),
    pytest.param(('name = "DE"', 'name = "S"'), "tower_types[2].name", 'value "S"', "tower_types[1] has that name",
                 id="duplicate-type"),
    pytest.param(('name = "G"', 'name = " "'), "wires[3].name", 'value " "', "expected a non-empty name", id="blank-name"),
    pytest.param(('name = "T3"\nstation = 600.0\ntype = "DE"', 'name = "T3"\nstation = 600.0\ntype = "S"'),
                 "line.towers[3].type", 'value "S"', 'attachment of wire "A" is "suspension"; expected a type whose '
                 'attachments are all "strain"', id="suspension-at-end-tower"),
    pytest.param(('[line]\n', '[line]\nweight = 3.0\n'), "line.weight", "value 3.0",
                 "not allowed with [[wires]]: each wire gives its own weight", id="line-conductor-key"),
    pytest.param(('[line]\n', '[line]\ntension = 30000.0\n'), "line.tension", "value 30000.0",
                 "each wire gives its own tension", id="line-tension"),
    pytest.param(('ground = 2.0\n', 'ground = 2.0\nheight = 30.0\n'), "line.towers[2].height", "value 30.0",
                 "the tower's type places each wire", id="tower-height"),
    pytest.param(('ground = 2.0\n', 'ground = 2.0\nsupport = "suspension"\n'), "line.towers[2].support",
                 'value "suspension"', "the tower's type places each wire", id="tower-support"),
    pytest.param(('{ wire = "A", y = -5.5, z = 28.0, support = "strain" }',
                  '{ wire = "A", y = -5.5, z = 28.0, support = "strain", insulator_length = 3.0 }'),
                 "tower_types[2].attachments[1].insulator_length", "value 3.0",
                 "expected it on suspension attachments only", id="insulator-on-strain"),
    pytest.param(('z = 40.0, support = "suspension", insulator_length = 0.3', 'z = 0.5, support = "suspension", insulator_length = 0.3'),
                 "tower_types[1].attachments[3].z", "value 0.5", "expected z > 2 x insulator_length = 0.6 m", id="clamp-too-low"),
    pytest.param(('{ wire = "A", y = -5.5, z = 31.0, support = "suspension" }', '{ wire = "A", y = -5.5, z = 31.0 }'),
                 "tower_types[1].attachments[1].support", "missing required key", 'one of "strain", "suspension"',
                 id="attachment-without-support"),
    pytest.param(('{ wire = "A", y = -5.5, z = 31.0, support = "suspension" }',
                  '{ wire = "A", y = -5.5, z = 31.0, support = "suspension", x = 1.0 }'),
                 "tower_types[1].attachments[1].x", "unknown key in [tower_types.attachments]", "allowed: wire, y, z",
                 id="attachment-unknown-key"),
    pytest.param(('tension = 20000.0\n\n[[wires]]\nname = "G"', 'tension = 20000.0\nbundle_spacing = 0.4\n\n[[wires]]\nname = "G"'),
                 "wires[2].bundle_spacing", "value 0.4", "not allowed with bundle = 1: expected it on bundles only",
                 id="spacing-on-single"),
    pytest.param(('tension = 8000.0\n', 'tension = 8000.0\nshielding = 0.8\n'), "wires[3].shielding", "value 0.8",
                 "expected it on bundles only", id="shielding-on-single"),
    pytest.param(('bundle = 2\n', 'bundle = 0\n'), "wires[1].bundle", "value 0", "expected an integer >= 1 and <= 12",
                 id="bundle-zero"),
    pytest.param(('kind = "ground"', 'kind = "earth"'), "wires[3].kind", 'value "earth"', 'one of "phase", "ground"',
                 id="bad-kind"),
    pytest.param(('weight = 6.0', 'wieght = 6.0'), "wires[3].wieght", "unknown key in [wires]", 'did you mean "weight"?',
                 id="wire-unknown-key"),
    pytest.param(('tension = 8000.0', 'tension = 1000.0'), "wires[3].tension", "value 1000.0",
                 "reach the ground", id="ground-wire-too-slack"),
    pytest.param(('tension = 8000.0', 'tension = 500.0'), "wires[3].tension", "value 500.0",
                 "exceeds a quarter of the span; expected tension > W L/2 = 900 N", id="sag-over-quarter-span"),
]


@pytest.mark.parametrize(("change", "key", "value", "allowed"), BAD)
def test_a_bad_reference_is_one_line_naming_key_and_value(tmp_path, change, key, value, allowed):
    message = refused(tmp_path, edit(*change))
    assert "c.toml:" in message and f": {key}: " in message, message
    assert value in message and allowed in message, message


def test_messages_give_the_line_of_the_key(tmp_path):
    text = edit('type = "S"\n', 'type = "SS"\n')
    line = text.splitlines().index('type = "SS"') + 1
    assert refused(tmp_path, text).startswith(f"{tmp_path / 'c.toml'}:{line}: line.towers[2].type: ")
    text = edit('{ wire = "B", y = 5.5, z = 31.0,', '{ wire = "C", y = 5.5, z = 31.0,')
    line = next(n for n, raw in enumerate(text.splitlines(), start=1) if 'wire = "C"' in raw)
    assert refused(tmp_path, text).startswith(f"{tmp_path / 'c.toml'}:{line}: tower_types[1].attachments[2].wire: ")
    text = edit('name = "B"', 'name = "A"')
    line = text.splitlines().index('name = "A"', text.splitlines().index('name = "A"') + 1) + 1
    assert refused(tmp_path, text).startswith(f"{tmp_path / 'c.toml'}:{line}: wires[2].name: ")


def test_wires_and_types_come_together_in_a_section(tmp_path):
    types_start = THREE.index("[[tower_types]]")
    no_types = THREE[:types_start] + THREE[THREE.index("[wind]"):]
    assert "tower_types: missing: [[wires]] need tower types" in refused(tmp_path, no_types)
    wires_start = THREE.index("[[wires]]")
    no_wires = THREE[:wires_start] + THREE[types_start:]
    assert "wires: missing: [[tower_types]] attach wires" in refused(tmp_path, no_wires)
    start, end = THREE.index("[[line.towers]]"), THREE.index("[[wires]]")
    message = refused(tmp_path, THREE[:start] + THREE[end:])
    assert "line.towers: missing: a case with [[wires]] is a section" in message
    message = refused(tmp_path, edit("[[wires]]\nname = \"A\"", "[wires]\nname = \"A\"").split("[[wires]]\nname = \"B\"")[0]
                      + THREE[THREE.index("[[tower_types]]"):])
    assert "wires: value a table is not allowed: expected [[wires]] tables, one per wire" in message
    message = refused(tmp_path, edit('attachments = [\n    { wire = "A", y = -5.5, z = 31.0', 'kind = [\n    { wire = "A", y = -5.5, z = 31.0'))
    assert "tower_types[1].kind: unknown key in [tower_types]" in message


def test_a_type_without_wires_is_refused(tmp_path):
    single = """\
[line]
weight = 17.92
diameter = 0.022
area = 0.7e-4
elastic_modulus = 5.2e10
tension = 20000.0
[[line.towers]]
station = 0.0
height = 30.0
support = "strain"
type = "DE"
[[line.towers]]
station = 300.0
height = 30.0
support = "strain"
[wind]
type = "synoptic"
v_ref = 30.0
"""
    message = refused(tmp_path, single)
    assert ": line.towers[1].type: value \"DE\" is not allowed without [[wires]] and [[tower_types]]" in message


# --------------------------------------------------------------------------- bundles
def test_bundle_equivalence_against_hand_values(tmp_path):
    """A twin bundle (n = 2, shielding 0.9) of the paper's conductor (W 17.92 N/m, D 22 mm,
    A 70 mm2, E 52 GPa) strung at 20 kN per sub-conductor."""
    case = load(tmp_path, THREE)
    a = case.wire("A")
    assert a.weight_total == 35.84  # 2 x 17.92 N/m
    assert a.mass_per_length == pytest.approx(35.84 / 9.81, rel=1e-15)  # 3.6534 kg/m
    assert a.mass_per_length == pytest.approx(3.6534, abs=1e-4)
    assert a.area_total == pytest.approx(1.4e-4, rel=1e-15)  # 2 x 70 mm2
    assert a.ea == pytest.approx(7.28e6, rel=1e-15)  # 5.2e10 Pa x 1.4e-4 m2
    assert a.tension_total == 40000.0  # 2 x 20 kN
    assert a.drag_diameter == pytest.approx(0.0396, rel=1e-15)  # 2 x 0.022 m x 0.9
    line = wire_case(case, "A").line
    assert (line.weight, line.area, line.tension) == (a.weight_total, a.area_total, a.tension_total)
    assert line.diameter == a.drag_diameter and line.drag_coefficient == 1.0
    assert line.ea == pytest.approx(7.28e6, rel=1e-15) and line.mass_per_length == pytest.approx(3.6534, abs=1e-4)
    # the bundle's still-air sag is the sub-conductor's: W L^2 / 8 H0 = 17.92 x 300^2 / 160000 = 10.08 m
    assert line.sag == pytest.approx(10.08, rel=1e-14)
    # Eq. 17 on the bundle: g*_yp = 1/2 x 1.25 x 1.0 x 30^2 x 0.0396 = 22.275 N/m
    assert wire_case(case, "A").g_yp == pytest.approx(22.275, rel=1e-14)
    # a single conductor is itself
    b = wire_case(case, "B").line
    assert (b.weight, b.diameter, b.area, b.tension) == (17.92, 0.022, 0.7e-4, 20000.0)


def test_a_quad_bundle_without_shielding(tmp_path):
    case = load(tmp_path, edit("bundle = 2\nbundle_spacing = 0.4\nshielding = 0.9\n", "bundle = 4\n"))
    a = case.wire("A")
    assert a.shielding == 1.0  # default: no shielding
    assert a.drag_diameter == pytest.approx(0.088, rel=1e-15)  # 4 x 0.022 m
    assert a.weight_total == pytest.approx(71.68, rel=1e-15) and a.tension_total == 80000.0
    assert a.ea == pytest.approx(4 * 5.2e10 * 0.7e-4, rel=1e-15)  # 1.456e7 N


# --------------------------------------------------------------------------- heights and insulators
def test_each_wire_hangs_at_its_attachment(tmp_path):
    case = load(tmp_path, THREE)
    # suspension: clamp = z - v (v given, else [line] insulator_length 3.6); strain: clamp = z
    expected = {"A": [28.0, 31.0 - 3.6, 28.0], "B": [28.0, 27.0, 28.0], "G": [37.0, 40.0 - 0.3, 37.0]}
    for wire, heights in expected.items():
        single = wire_case(case, wire)
        assert not single.has_wires and single.tower_types == ()
        towers = single.line.towers
        assert [t.height for t in towers] == heights
        assert [t.support for t in towers] == ["strain", "suspension", "strain"]
        assert [t.type for t in towers] == [None, None, None]
        assert [(t.name, t.station, t.ground, t.angle) for t in towers] == [
            ("T1", 0.0, 0.0, 0.0), ("T2", 300.0, 2.0, 0.0), ("T3", 600.0, 0.0, 0.0)]
        assert single.line.insulator_length == 3.6 and single.line.towers_file is None
        assert (single.name, single.analysis) == (case.name, case.analysis)
        # one wind: V_ref at the case's reference height (the first wire's mean clamp height),
        # written in where the wire's own default would differ
        pinned = None if wire == "A" else case.line.height
        assert single.wind == dataclasses.replace(case.wind, reference_height=pinned)
    assert case.line.height == pytest.approx((28.0 + 27.4 + 28.0) / 3)
    assert [t.insulator_length for t in wire_case(case, "G").line.towers] == [None, 0.3, None]
    assert clamp_height(Attachment(wire="A", y=0.0, z=31.0, support="suspension"), 3.6) == 31.0 - 3.6
    assert clamp_height(Attachment(wire="A", y=0.0, z=31.0, support="strain"), 3.6) == 31.0


# --------------------------------------------------------------------------- no wires: today's case
PAPER_CASE9 = """\
name = "case09"
[line]
spans = 1
span_length = 300.0
sag = 10.0
weight = 17.92
diameter = 0.022
area = 0.7e-4
elastic_modulus = 5.2e10
height = 43.0
[wind]
type = "synoptic"
v_ref = 40.0
"""


def test_a_case_without_wires_is_todays_case(tmp_path):
    case = load(tmp_path, PAPER_CASE9)
    expected = Case(
        name="case09",
        line=Line(spans=1, span_length=300.0, sag=10.0, weight=17.92, diameter=0.022, drag_coefficient=1.0,
                  area=0.7e-4, elastic_modulus=5.2e10, height=43.0, insulator_length=4.0,
                  supports=("strain", "strain"), tower_of_interest=1),
        wind=Wind(type="synoptic", v_ref=40.0), analysis=Analysis(), source=tmp_path / "c.toml")
    assert case == expected
    assert case.wires == () and case.tower_types == () and not case.has_wires
    doc = case_to_dict(case)
    assert "wires" not in doc and "tower_types" not in doc
    assert not {"coherence_decay_y", "coherence_decay_z"} & set(doc["wind"])


def test_the_shipped_section_is_unchanged():
    case = load_case(CASES / "examples" / "section-12span.toml")
    assert not case.has_wires and all(t.type is None for t in case.line.towers)
    assert all("type" not in t for t in case_to_dict(dataclasses.replace(case, line=dataclasses.replace(
        case.line, towers_file=None)))["line"]["towers"])
    assert case_warnings(case) == []


SECTION = """\
name = "sec"
description = "one wire, four towers"

[line]
weight = 17.92
diameter = 0.022
drag_coefficient = 1.1
area = 0.7e-4
elastic_modulus = 5.2e10
insulator_length = 4.0
tension = 22000.0
tower_of_interest = 2
elements_per_span = 8
{towers}
[wind]
type = "synoptic"
v_ref = 35.0
direction = 30.0
profile_exponent = 0.16
reference_height = 10.0

[analysis]
duration = 300.0
realizations = 4
"""

TODAY_TOWERS = """
[[line.towers]]
name = "A1"
station = 0.0
ground = 10.0
height = 30.0
support = "strain"

[[line.towers]]
name = "A2"
station = 350.0
ground = 14.0
height = 40.0
support = "suspension"
angle = 4.0

[[line.towers]]
name = "A3"
station = 700.0
ground = 12.0
height = 38.5
support = "suspension"
insulator_length = 3.5

[[line.towers]]
name = "A4"
station = 1000.0
ground = 8.0
height = 31.0
support = "strain"
"""

ONE_WIRE_TOWERS = """
[[line.towers]]
name = "A1"
station = 0.0
ground = 10.0
type = "E1"

[[line.towers]]
name = "A2"
station = 350.0
ground = 14.0
angle = 4.0
type = "S1"

[[line.towers]]
name = "A3"
station = 700.0
ground = 12.0
type = "S2"

[[line.towers]]
name = "A4"
station = 1000.0
ground = 8.0
type = "E2"

[[wires]]
name = "W"
kind = "phase"
weight = 17.92
diameter = 0.022
drag_coefficient = 1.1
area = 0.7e-4
elastic_modulus = 5.2e10
tension = 22000.0

[[tower_types]]
name = "E1"
attachments = [{ wire = "W", y = 0.0, z = 30.0, support = "strain" }]

[[tower_types]]
name = "S1"
attachments = [{ wire = "W", y = 0.0, z = 44.0, support = "suspension" }]

[[tower_types]]
name = "S2"
attachments = [{ wire = "W", y = 0.0, z = 42.0, support = "suspension", insulator_length = 3.5 }]

[[tower_types]]
name = "E2"
attachments = [{ wire = "W", y = 0.0, z = 31.0, support = "strain" }]
"""


def test_wire_case_of_a_wire_identical_to_the_line_is_todays_case():
    """One wire with [line]'s conductor and tension, its attachments where today's towers clamp
    it (suspension: z = height + insulator length): its single-wire case equals today's."""
    today = case_from_dict(tomllib.loads(SECTION.format(towers=TODAY_TOWERS)), default_name="sec")
    doc = tomllib.loads(SECTION.format(towers=ONE_WIRE_TOWERS))
    for key in ("weight", "diameter", "drag_coefficient", "area", "elastic_modulus", "tension"):
        del doc["line"][key]  # given by the wire
    multi = case_from_dict(doc, default_name="sec")
    single = wire_case(multi, "W")
    assert single == today
    assert single.line.ea == today.line.ea and single.g_yp_L == today.g_yp_L
    assert case_from_dict(case_to_dict(single), default_name="sec") == today
    # the case's own line is that wire's, its towers typed
    assert multi.line == dataclasses.replace(today.line, towers=tuple(
        dataclasses.replace(t, type=k) for t, k in zip(today.line.towers, ("E1", "S1", "S2", "E2"))))


# --------------------------------------------------------------------------- warnings
def test_density_warning_names_the_wire(tmp_path):
    case = load(tmp_path, edit("weight = 6.0\n", "weight = 0.61\n"))
    (warning,) = case_warnings(case)
    line = THREE.splitlines().index("weight = 6.0") + 1
    assert warning.startswith(f"{tmp_path / 'c.toml'}:{line}: wires[3].weight: value 0.61 N/m with diameter 0.012 m")
    assert f"0.61 x {GRAVITY:g}" in warning
    assert case_warnings(load(tmp_path, THREE)) == []  # the twin bundle's sub-conductor is checked, not the bundle
