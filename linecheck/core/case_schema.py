"""The case key schema: every TOML key of a case file declared once.

:data:`SCHEMA` gives each key of each table its type, physical range, default, unit and help
text.  The loader (:mod:`.case_validate`), the case dataclasses' defaults (:mod:`.case_model`),
the TUI editor, the Excel inputs sheet and ``docs/case-files.md`` all read this table, so a
range, a default, a message or a unit is written in one place only.  The TOML key layout is a
public contract (``docs/case-files.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

SUPPORT_TYPES = ("strain", "suspension")
WIND_TYPES = ("synoptic", "downburst")
DOWNBURST_PRESETS = ("Db_x", "Db_y")
# Downburst running-mean models (docs/wind.md).  "holmes-oliver": separable
# Holmes-Oliver x Wood x Chay; "table": the user field file; "ring-jet": travelling ring vortex
# kinematics with a wall-layer outflow; "ring-jet-inviscid": the ring + image field itself (what
# "ring-jet" was before the wall layer; linecheck/core/wind/ring.py).  A file without ``model``
# keeps its meaning: "table" when it names a ``field``, else "holmes-oliver" (see docs/wind.md for
# the choice of default).
RING_MODELS = ("ring-jet", "ring-jet-inviscid")  # time scale D_j/V_j, key jet_velocity (ring.MODELS)
DOWNBURST_MODELS = ("holmes-oliver", "table", *RING_MODELS)
DAMPING_MODELS = ("quasi-steady", "paper")
CODE_TERRAINS = ("sea", "open", "suburban", "urban")  # [codes] terrain (docs/codes.md)
DRAG_MODELS = ("linear", "quadratic")
FFT_LENGTHS = ("record", "fast")  # turbulence synthesis: docs/wind.md "Synthesis length"
TENSION_MODELS = ("linear", "second-order")
# Direction of the drag on a section (docs/method.md "Loads"): "cross-flow" loads the conductor
# with the wind component normal to its own deformed axis (Hoerner 1965, the cross-flow
# principle); "horizontal-normal" the component along each span's horizontal normal only.
DRAG_DIRECTIONS = ("cross-flow", "horizontal-normal")
# Conductor self-damping assumed with the quasi-steady model (ratio at the lowest mean-state
# mode, stiffness-proportional): it damps the axial modes that no aerodynamic model damps.
DEFAULT_STRUCTURAL_DAMPING = 0.002
WIRE_KINDS = ("phase", "ground")  # [[wires]] kind
# [wind] coherence_decay_y, coherence_decay_z (one wind for every wire): the decay constants C_y,
# C_z of the exponential coherence across the line and in height (its form: docs/wind.md "Many
# wires"); defaults C_y = 16, C_z = 10 as in Simiu & Scanlan, "Wind Effects on Structures" (3rd ed.,
# Wiley 1996, Sect. 2.3, after Vellozzi & Cohen 1968) -- quoted as the literature quotes them, not
# checked against the book's page.


@dataclass(frozen=True)
class FieldSpec:
    """Declaration of one case key.

    kind: ``float``, ``int``, ``str``, ``choice``, ``float_list``, ``str_list``, ``bool``.
    ``low``/``high`` bound the value (or every list item); ``low_open`` makes the
    lower bound exclusive.  ``default`` of ``None`` with ``required=False`` means
    "derived elsewhere" (documented in ``help``).
    """

    name: str
    kind: str
    unit: str = ""
    help: str = ""
    default: Any = None
    required: bool = False
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] = ()

    def allowed(self) -> str:
        """Human text of the allowed values."""
        if self.kind == "choice" or (self.kind == "str_list" and self.choices):
            return "one of " + ", ".join(f'"{c}"' for c in self.choices)
        if self.kind in ("float", "int", "float_list"):
            what = {"float": "a number", "int": "an integer", "float_list": "a list of numbers"}[
                self.kind
            ]
            parts = []
            if self.low is not None:
                parts.append(f"{'>' if self.low_open else '>='} {self.low:g}")
            if self.high is not None:
                parts.append(f"<= {self.high:g}")
            rng = (" " + " and ".join(parts)) if parts else ""
            unit = f" {self.unit}" if self.unit and self.unit != "-" else ""
            return f"{what}{rng}{unit}"
        if self.kind == "bool":
            return "true or false"
        return "a string"


def _f(name, unit, help, default=None, required=False, low=None, high=None, low_open=False):
    return FieldSpec(name, "float", unit, help, default, required, low, high, low_open)


def _i(name, unit, help, default=None, required=False, low=None, high=None):
    return FieldSpec(name, "int", unit, help, default, required, low, high)


# The conductor keys of [line], declared once: [[wires]] (WIRE_SCHEMA) reuses their names, units
# and ranges, so a range and its message live here only.
_WEIGHT = _f("weight", "N/m", "conductor weight per unit length W", required=True, low=0.0, high=1000.0, low_open=True)
_DIAMETER = _f("diameter", "m", "projected area per unit length D, i.e. the diameter of a single conductor (paper Table 1)", required=True, low=0.0, high=1.0, low_open=True)
_DRAG_COEFFICIENT = _f("drag_coefficient", "-", "drag coefficient C_d", default=1.0, low=0.0, high=3.0, low_open=True)
_AREA = _f("area", "m2", "conductor cross-section A", required=True, low=0.0, high=0.1, low_open=True)
_ELASTIC_MODULUS = _f("elastic_modulus", "Pa", "elastic modulus E", required=True, low=1e8, high=1e12)
_INSULATOR_LENGTH = _f("insulator_length", "m", "suspension insulator length v", default=4.0, low=0.0, high=20.0, low_open=True)
_TENSION = _f("tension", "N", "section form: still-air horizontal tension H0 at clipping-in", low=0.0, high=1e7, low_open=True)

SCHEMA: dict[str, tuple[FieldSpec, ...]] = {
    "": (
        FieldSpec("name", "str", "", "case name (default: file stem)"),
        FieldSpec("description", "str", "", "one-line description", default=""),
    ),
    "line": (
        _i("spans", "-", "number of spans in the modelled section (equal-span form)", low=1, high=200),
        _f("span_length", "m", "span length L_x (equal-span form)", low=10.0, high=3000.0),
        _f("sag", "m", "still-air mid-span sag S (equal-span form)", low=0.0, high=None, low_open=True),
        _WEIGHT,
        _DIAMETER,
        _DRAG_COEFFICIENT,
        _AREA,
        _ELASTIC_MODULUS,
        _f("height", "m", "average conductor elevation (equal-span form)", low=1.0, high=500.0),
        _INSULATOR_LENGTH,
        FieldSpec("supports", "str_list", "-", 'one per tower: "strain" or "suspension"', choices=SUPPORT_TYPES),
        _i("tower_of_interest", "-", "1-based tower whose reactions are reported", default=1, low=1),
        _i("elements_per_span", "-", "cable finite elements per span (step 2)", default=10, low=2, high=200),
        _TENSION,
        FieldSpec("towers_file", "str", "", "section form: CSV tower table (same columns as [[line.towers]]), relative to the case file"),
    ),
    "line.towers": (  # one [[line.towers]] table (or CSV row) per tower, in line order (the section form)
        FieldSpec("name", "str", "", "tower label shown in tables and sheets (default T1, T2, ...)"),
        _f("station", "m", "horizontal distance along the line from the first tower", required=True, low=-1e7, high=1e7),
        _f("ground", "m", "ground elevation at the tower", default=0.0, low=-1000.0, high=9000.0),
        _f("height", "m", "conductor clamp height above ground in still air (> 0: a clamp below ground is not allowed)", required=True, low=0.0, high=500.0, low_open=True),
        FieldSpec("support", "choice", "-", '"strain" or "suspension"; both end towers "strain"', required=True, choices=SUPPORT_TYPES),
        _f("angle", "deg", "horizontal deviation of the line at the tower, + = turning left; 0 at the end towers", default=0.0, low=-90.0, high=90.0, low_open=True),
        _f("insulator_length", "m", "suspension insulator length (default: line.insulator_length); suspension towers only", low=0.0, high=20.0, low_open=True),
        FieldSpec("type", "str", "", "with [[wires]]: the tower's [[tower_types]] name (required then, and height, support and insulator_length are not given: the type's attachments place each wire)"),
    ),
    "wind": (
        FieldSpec("type", "choice", "-", "wind type", required=True, choices=WIND_TYPES),
        _f("v_ref", "m/s", "reference mean speed V_ref at conductor height", required=True, low=0.0, high=150.0),
        _f("turbulence_intensity", "-", "turbulence intensity I", default=0.12, low=0.0, high=0.6),
        _f("air_density", "kg/m3", "air density rho", default=1.25, low=0.5, high=2.0),
        _f("coherence_decay", "-", "Davenport coherence decay constant C", default=10.0, low=0.0, high=100.0, low_open=True),
        _f("coherence_decay_y", "-", "with [[wires]]: exponential coherence decay constant C_y for separations across the line (tower frame y)", default=16.0, low=0.0, high=100.0, low_open=True),
        _f("coherence_decay_z", "-", "with [[wires]]: exponential coherence decay constant C_z for separations in height", default=10.0, low=0.0, high=100.0, low_open=True),
        _f("length_scale", "m", "von Karman length scale L_u (default: synoptic 52/0.3, downburst D_j)", low=0.0, high=1e5, low_open=True),
        FieldSpec("span_speeds", "float_list", "m/s", "synoptic only: mean speed per span (default v_ref on every span)", low=0.0, high=150.0),
        _f("direction", "deg", "mean wind vector V (sin d, cos d, 0): 0 = +y, normal to the first span", default=0.0, low=-360.0, high=360.0),
        _f("profile_exponent", "-", "power-law exponent alpha of V(z) = v_ref (z / reference_height)^alpha (0: uniform)", default=0.0, low=0.0, high=1.0),
        _f("reference_height", "m", "height above ground of v_ref (default: the mean clamp height above ground)", low=0.0, high=1000.0, low_open=True),
        FieldSpec("fft_length", "choice", "-", 'turbulence synthesis: "record" (an inverse FFT as long as the record, the paper cases) or "fast" (the next length with prime factors 2, 3, 5 only, the record\'s first samples kept: the same spectrum and coherence, other random draws; docs/wind.md)', default="record", choices=FFT_LENGTHS),
    ),
    "wind.downburst": (
        FieldSpec("model", "choice", "-", 'running-mean model (default: "table" with a field file, else "holmes-oliver")', choices=DOWNBURST_MODELS),
        FieldSpec("preset", "choice", "-", "critical configuration: Db_x (D_j=2L, R=1.6D_j, 30 deg) or Db_y (D_j=2L, R=1.2D_j, 0 deg)", choices=DOWNBURST_PRESETS),
        _f("jet_diameter", "m", "downburst jet diameter D_j", low=10.0, high=1e5),
        _f("distance", "m", "distance R from the tower of interest to the downburst centre", low=0.0, high=1e6),
        _f("angle", "deg", "angle Theta of the centre from the perpendicular to the line (Fig. 2)", low=-180.0, high=180.0),
        _f("r_max", "m", "radius of peak outflow (default 1.2 D_j)", low=0.0, high=1e6, low_open=True),
        _f("radial_decay", "m", "radial decay length R_r beyond r_max (default D_j/2)", low=0.0, high=1e6, low_open=True),
        _f("z_max", "m", "height of peak outflow (default 0.025 D_j)", low=0.0, high=1e4, low_open=True),
        _f("t1", "s", "rise time T1 of the intensity function", low=0.0, high=1e5, low_open=True),
        _f("t_f", "s", "end time T_f of the intensity function", low=0.0, high=1e5, low_open=True),
        _f("translation_speed", "m/s", "storm translation speed (Holmes & Oliver vector sum)", default=0.0, low=0.0, high=100.0),
        _f("translation_direction", "deg", "direction of storm travel, from +x toward +y", default=90.0, low=-360.0, high=360.0),
        FieldSpec("field", "str", "", "user running-mean field file (CSV or NPZ), relative to the case file"),
        _f("jet_velocity", "m/s", 'models "ring-jet", "ring-jet-inviscid": downdraft speed V_j setting the time scale D_j/V_j (default: from v_ref at p)', low=0.0, high=200.0, low_open=True),
    ),
    "analysis": (
        _f("duration", "s", "analysed record length (downburst default: 0 to T_f)", low=0.0, high=1e5, low_open=True),
        _f("time_step", "s", "time step", default=0.05, low=0.0, high=1.0, low_open=True),
        _i("realizations", "-", "number of turbulence realizations (memory and time bounded by the resource guard)", default=10, low=1, high=1_000_000_000),
        _i("seed", "-", "random seed", default=2015, low=0, high=2**63 - 1),
        _i("mean_states", "-", "downburst: step-1 mean-state instants over the event", default=250, low=2, high=100000),
        FieldSpec("damping", "choice", "-", 'aerodynamic damping: "quasi-steady" (every direction of relative motion) or "paper" (Eq. 13, transverse only)', default="quasi-steady", choices=DAMPING_MODELS),
        _f("structural_damping", "-", 'structural (self-)damping ratio at the lowest mean-state mode (default: 0 with "paper", '
           f'{DEFAULT_STRUCTURAL_DAMPING:g} with "quasi-steady")', low=0.0, high=0.2),
        _f("burn_in", "s", "synoptic: discarded start of the record (default: from the least-damped significant mode)", low=0.0, high=1e5),
        FieldSpec("drag", "choice", "-", 'fluctuating drag: "linear" (paper Eq. 5) or "quadratic" (the v^2 term kept, its mean I^2 in step 1)', default="quadratic", choices=DRAG_MODELS),
        FieldSpec("tension", "choice", "-", 'reactions: "linear" (paper) or "second-order" (+ the tension increment quadratic in the linear motion)', default="second-order", choices=TENSION_MODELS),
        FieldSpec("drag_direction", "choice", "-", 'section form: "cross-flow" (the drag on the wind component normal to the deformed conductor\'s axis, Hoerner 1965) or "horizontal-normal" (the component along each span\'s horizontal normal); the equal-span (paper) form always uses "horizontal-normal"', default="cross-flow", choices=DRAG_DIRECTIONS),
        _f("peak_window", "s", "peaks taken per window of the analysed record; statistics over windows x realizations (default: the whole record; a downburst's whole event)", low=0.0, high=1e5, low_open=True),
        _f("design_fractile", "-", "non-exceedance probability of the Gumbel design peak (0.5 = median peak)", default=0.5, low=0.0, high=0.999, low_open=True),
    ),
    "codes": (  # design-code comparison (docs/codes.md)
        FieldSpec("terrain", "choice", "-", 'terrain for the design codes: "sea", "open", "suburban" or "urban" (maps to each code\'s category)', default="open", choices=CODE_TERRAINS),
        FieldSpec("asce74_exposure", "choice", "-", "ASCE 74 exposure category (default: from terrain)", choices=("B", "C", "D")),
        FieldSpec("iec60826_terrain", "choice", "-", "IEC 60826 terrain category (default: from terrain)", choices=("A", "B", "C", "D")),
        FieldSpec("en50341_terrain", "choice", "-", "EN 50341-1 / EN 1991-1-4 terrain category (default: from terrain)", choices=("0", "I", "II", "III", "IV")),
    ),
}


def _per_wire(spec: FieldSpec, help: str, **changes: Any) -> FieldSpec:
    """A [line] key as a [[wires]] key: its name, unit and range kept, its help said per wire."""
    return replace(spec, help=help, **changes)


#: The multi-wire tables (docs/case-files.md "Every wire on the tower"): ``[[wires]]`` (one per
#: wire), ``[[tower_types]]`` (one per tower type) and each type's ``attachments`` (one inline
#: table per wire).  Arrays of tables, kept apart from :data:`SCHEMA` (whose tables the TUI
#: parameter editor and the Excel inputs sheet list key by key); the loader, the dataclasses'
#: defaults and ``docs/case-files.md`` read both.  The conductor keys are [line]'s specs.
WIRE_SCHEMA: dict[str, tuple[FieldSpec, ...]] = {
    "wires": (
        FieldSpec("name", "str", "", "wire label, unique; the attachments name it", required=True),
        FieldSpec("kind", "choice", "-", '"phase" (a phase conductor or bundle) or "ground" (a ground or earth wire)', required=True, choices=WIRE_KINDS),
        _per_wire(_WEIGHT, "weight per unit length W of one sub-conductor (the bundle: bundle x W)"),
        _per_wire(_DIAMETER, "diameter D of one sub-conductor (the bundle's drag acts on bundle x D x shielding)"),
        _DRAG_COEFFICIENT,
        _per_wire(_AREA, "cross-section A of one sub-conductor (the bundle: bundle x A)"),
        _ELASTIC_MODULUS,
        _per_wire(_TENSION, "still-air horizontal tension H0 of one sub-conductor at clipping-in (the bundle: bundle x H0)", required=True),
        _i("bundle", "-", "number of sub-conductors acting as one wire (1: a single conductor)", default=1, low=1, high=12),
        _f("bundle_spacing", "m", "distance between neighbouring sub-conductors (recorded, not used by the analysis); bundles only", low=0.0, high=2.0, low_open=True),
        _f("shielding", "-", "bundle drag factor: the bundle's drag is bundle x D x shielding times C_d (1: no shielding, each sub-conductor loaded as if alone); bundles only", default=1.0, low=0.0, high=1.0, low_open=True),
    ),
    "tower_types": (  # one [[tower_types]] table per type; its attachments: the next table
        FieldSpec("name", "str", "", "tower type label, unique; [[line.towers]] type names it", required=True),
    ),
    "tower_types.attachments": (  # attachments = [{ wire = "A", y = ..., z = ..., support = ... }, ...]: one per wire
        FieldSpec("wire", "str", "", "the [[wires]] name this attachment carries (every wire once per type)", required=True),
        _f("y", "m", "attachment point to the left of the line's centre (tower frame y, + = left looking along the line)", required=True, low=-100.0, high=100.0),
        _f("z", "m", "attachment point above the tower's ground: the insulator's top at a suspension attachment, the clamp at a strain one", required=True, low=0.0, high=500.0, low_open=True),
        FieldSpec("support", "choice", "-", '"strain" or "suspension"; "strain" at both end towers', required=True, choices=SUPPORT_TYPES),
        replace(_INSULATOR_LENGTH, default=None, help="suspension insulator length (default: line.insulator_length); suspension attachments only"),
    ),
}


def field_spec(section: str, key: str) -> FieldSpec:
    """The :class:`FieldSpec` of ``section.key`` (``section`` "" for top level; a
    :data:`WIRE_SCHEMA` table such as ``"wires"`` too)."""
    for spec in schema_table(section):
        if spec.name == key:
            return spec
    raise KeyError(f"{section}.{key}")


def schema_table(section: str) -> tuple[FieldSpec, ...]:
    """The key specs of one table of :data:`SCHEMA` or :data:`WIRE_SCHEMA`."""
    return SCHEMA[section] if section in SCHEMA else WIRE_SCHEMA[section]


def schema_default(dotted_key: str) -> Any:
    """The :data:`SCHEMA` default of a dotted key (``"analysis.time_step"``, ``"wind.downburst.t1"``,
    ``"description"`` at top level): the case dataclasses take their field defaults from here."""
    section, _, key = dotted_key.rpartition(".")
    return field_spec(section, key).default


#: columns of a tower table (``[[line.towers]]`` keys, the header of a ``towers_file`` CSV)
TOWER_COLUMNS = tuple(spec.name for spec in SCHEMA["line.towers"])
