"""Every default is written once, in SCHEMA: the case dataclasses' field defaults equal the
SCHEMA defaults they stand for, and a case loaded with the keys left out equals one built from
the dataclasses' defaults."""

from __future__ import annotations

import dataclasses

import pytest

from linecheck.core.case import (
    SCHEMA,
    WIRE_SCHEMA,
    Analysis,
    Attachment,
    Case,
    Codes,
    Downburst,
    Line,
    Tower,
    TowerType,
    Wind,
    Wire,
    case_from_dict,
    field_spec,
    schema_default,
    schema_table,
)

#: the dataclass each SCHEMA (and WIRE_SCHEMA) table fills
TABLES = {
    "": Case,
    "line": Line,
    "line.towers": Tower,
    "wind": Wind,
    "wind.downburst": Downburst,
    "analysis": Analysis,
    "codes": Codes,
    "wires": Wire,
    "tower_types": TowerType,
    "tower_types.attachments": Attachment,
}

#: SCHEMA keys with a default whose dataclass field has none (a required field: the loader
#: always passes the SCHEMA default).  A change here is deliberate: update this set.
FILLED_BY_THE_LOADER_ONLY = {
    "line.drag_coefficient",
    "line.insulator_length",
    "line.tower_of_interest",
    "line.towers.ground",
}


def _dotted(section: str, key: str) -> str:
    return f"{section}.{key}" if section else key


def _field_defaults(cls) -> dict[str, object]:
    return {f.name: f.default for f in dataclasses.fields(cls)}


def test_every_schema_table_and_key_is_a_dataclass_field():
    assert set(TABLES) == set(SCHEMA) | set(WIRE_SCHEMA)
    for section, cls in TABLES.items():
        fields = _field_defaults(cls)
        missing = [spec.name for spec in schema_table(section) if spec.name not in fields]
        assert not missing, f"{cls.__name__} lacks fields for SCHEMA keys {missing}"


@pytest.mark.parametrize("section", list(SCHEMA) + list(WIRE_SCHEMA))
def test_every_dataclass_default_is_the_schema_default(section):
    """A field default (value and type: 0.0 is not 0) equals the SCHEMA default of its key."""
    fields = _field_defaults(TABLES[section])
    for spec in schema_table(section):
        default = fields[spec.name]
        dotted = _dotted(section, spec.name)
        if default is dataclasses.MISSING:
            if spec.default is not None:
                assert dotted in FILLED_BY_THE_LOADER_ONLY, f"{dotted}: SCHEMA default {spec.default!r}, no field default"
            continue
        assert dotted not in FILLED_BY_THE_LOADER_ONLY, f"{dotted} now has a field default: update the list"
        assert default == spec.default and type(default) is type(spec.default), (
            f"{dotted}: dataclass default {default!r}, SCHEMA default {spec.default!r}")


def test_the_tied_defaults_are_counted():
    """The defaults written twice before they were derived from SCHEMA (guards against a
    mapping error above that would make the comparison vacuous)."""
    tied = [_dotted(section, spec.name) for section, cls in TABLES.items() for spec in schema_table(section)
            if spec.default is not None and _field_defaults(cls)[spec.name] is not dataclasses.MISSING]
    assert len(tied) == 26, tied
    assert "analysis.time_step" in tied and "wind.downburst.translation_direction" in tied
    assert {"wind.coherence_decay_y", "wind.coherence_decay_z", "wires.drag_coefficient", "wires.bundle",
            "wires.shielding"} <= set(tied)


def test_a_changed_schema_default_is_seen(monkeypatch):
    """The comparison fails when SCHEMA and a dataclass disagree: SCHEMA's time step altered."""
    spec = field_spec("analysis", "time_step")
    altered = tuple(dataclasses.replace(s, default=0.01) if s is spec else s for s in SCHEMA["analysis"])
    monkeypatch.setitem(SCHEMA, "analysis", altered)
    assert schema_default("analysis.time_step") == 0.01
    with pytest.raises(AssertionError, match="analysis.time_step"):
        test_every_dataclass_default_is_the_schema_default("analysis")


MINIMAL = {
    "line": {"spans": 1, "span_length": 300.0, "sag": 10.0, "weight": 17.92, "diameter": 0.022,
             "area": 0.7e-4, "elastic_modulus": 5.2e10, "height": 43.0},
    "wind": {"type": "downburst", "v_ref": 40.0, "downburst": {"preset": "Db_x"}},
}


def test_a_case_without_optional_keys_equals_the_dataclass_defaults():
    """The loader fills left-out keys from SCHEMA; the dataclasses' own defaults give the same case."""
    case = case_from_dict(MINIMAL, default_name="minimal")
    assert case.analysis == Analysis()
    assert case.codes == Codes()
    assert case.description == Case.__dataclass_fields__["description"].default
    wind = dict(MINIMAL["wind"])
    wind.pop("downburst")
    assert case.wind == Wind(**wind, downburst=case.wind.downburst)
    d = case.wind.downburst
    assert d == Downburst(jet_diameter=d.jet_diameter, distance=d.distance, angle=d.angle, preset=d.preset)
    assert case.line.elements_per_span == Line.__dataclass_fields__["elements_per_span"].default


def test_a_tower_without_optional_keys_equals_the_dataclass_defaults():
    towers = [{"station": 0.0, "height": 40.0, "support": "strain"},
              {"station": 300.0, "height": 40.0, "support": "strain"}]
    line = {k: v for k, v in MINIMAL["line"].items() if k not in ("spans", "span_length", "sag", "height")}
    doc = {"line": {**line, "tension": 20000.0, "towers": towers}, "wind": {"type": "synoptic", "v_ref": 30.0}}
    case = case_from_dict(doc, default_name="towers")
    first = case.line.towers[0]
    assert first == Tower(name="T1", station=0.0, ground=field_spec("line.towers", "ground").default,
                          height=40.0, support="strain")
