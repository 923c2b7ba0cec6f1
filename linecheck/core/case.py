"""Case model: frozen dataclasses, the TOML key schema and its validation.

The TOML key layout is a public contract (see ``docs/case-files.md``).  Every
key is declared once in :data:`SCHEMA` with its type, physical range, default,
unit and help text; the loader, the TUI editor and the Excel inputs sheet all
read that table, so a message or a unit is written in one place only.

Units are SI inside (m, s, N, kg, Pa); angles are degrees in the file and in
the dataclasses (converted where used).
"""

from __future__ import annotations

import dataclasses
import datetime
import difflib
import hashlib
import math
import os
import re
import stat
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import CaseError

SUPPORT_TYPES = ("strain", "suspension")
WIND_TYPES = ("synoptic", "downburst")
DOWNBURST_PRESETS = ("Db_x", "Db_y")
# Downburst running-mean models (issue 15; docs/wind.md).  "holmes-oliver": separable
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
# Conductor self-damping assumed with the quasi-steady model (ratio at the lowest mean-state
# mode, stiffness-proportional): it damps the axial modes that no aerodynamic model damps.
DEFAULT_STRUCTURAL_DAMPING = 0.002


# --------------------------------------------------------------------------- schema
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


SCHEMA: dict[str, tuple[FieldSpec, ...]] = {
    "": (
        FieldSpec("name", "str", "", "case name (default: file stem)"),
        FieldSpec("description", "str", "", "one-line description", default=""),
    ),
    "line": (
        _i("spans", "-", "number of spans in the modelled section (equal-span form)", low=1, high=200),
        _f("span_length", "m", "span length L_x (equal-span form)", low=10.0, high=3000.0),
        _f("sag", "m", "still-air mid-span sag S (equal-span form)", low=0.0, high=None, low_open=True),
        _f("weight", "N/m", "conductor weight per unit length W", required=True, low=0.0, high=1000.0, low_open=True),
        _f("diameter", "m", "projected area per unit length D, i.e. the diameter of a single conductor (paper Table 1)", required=True, low=0.0, high=1.0, low_open=True),
        _f("drag_coefficient", "-", "drag coefficient C_d", default=1.0, low=0.0, high=3.0, low_open=True),
        _f("area", "m2", "conductor cross-section A", required=True, low=0.0, high=0.1, low_open=True),
        _f("elastic_modulus", "Pa", "elastic modulus E", required=True, low=1e8, high=1e12),
        _f("height", "m", "average conductor elevation (equal-span form)", low=1.0, high=500.0),
        _f("insulator_length", "m", "suspension insulator length v", default=4.0, low=0.0, high=20.0, low_open=True),
        FieldSpec("supports", "str_list", "-", 'one per tower: "strain" or "suspension"', choices=SUPPORT_TYPES),
        _i("tower_of_interest", "-", "1-based tower whose reactions are reported", default=1, low=1),
        _i("elements_per_span", "-", "cable finite elements per span (step 2)", default=10, low=2, high=200),
        _f("tension", "N", "section form: still-air horizontal tension H0 at clipping-in", low=0.0, high=1e7, low_open=True),
        FieldSpec("towers_file", "str", "", "section form: CSV tower table (same columns as [[line.towers]]), relative to the case file"),
    ),
    "line.towers": (  # one [[line.towers]] table (or CSV row) per tower, in line order (issue 17)
        FieldSpec("name", "str", "", "tower label shown in tables and sheets (default T1, T2, ...)"),
        _f("station", "m", "horizontal distance along the line from the first tower", required=True, low=-1e7, high=1e7),
        _f("ground", "m", "ground elevation at the tower", default=0.0, low=-1000.0, high=9000.0),
        _f("height", "m", "conductor clamp height above ground in still air (> 0: a clamp below ground is not allowed)", required=True, low=0.0, high=500.0, low_open=True),
        FieldSpec("support", "choice", "-", '"strain" or "suspension"; both end towers "strain"', required=True, choices=SUPPORT_TYPES),
        _f("angle", "deg", "horizontal deviation of the line at the tower, + = turning left; 0 at the end towers", default=0.0, low=-90.0, high=90.0, low_open=True),
        _f("insulator_length", "m", "suspension insulator length (default: line.insulator_length); suspension towers only", low=0.0, high=20.0, low_open=True),
    ),
    "wind": (
        FieldSpec("type", "choice", "-", "wind type", required=True, choices=WIND_TYPES),
        _f("v_ref", "m/s", "reference mean speed V_ref at conductor height", required=True, low=0.0, high=150.0),
        _f("turbulence_intensity", "-", "turbulence intensity I", default=0.12, low=0.0, high=0.6),
        _f("air_density", "kg/m3", "air density rho", default=1.25, low=0.5, high=2.0),
        _f("coherence_decay", "-", "Davenport coherence decay constant C", default=10.0, low=0.0, high=100.0, low_open=True),
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
        _f("structural_damping", "-", 'structural (self-)damping ratio at the lowest mean-state mode (default: 0 with "paper", 0.002 with "quasi-steady")', low=0.0, high=0.2),
        _f("burn_in", "s", "synoptic: discarded start of the record (default: from the least-damped significant mode)", low=0.0, high=1e5),
        FieldSpec("drag", "choice", "-", 'fluctuating drag: "linear" (paper Eq. 5) or "quadratic" (the v^2 term kept, its mean I^2 in step 1)', default="quadratic", choices=DRAG_MODELS),
        FieldSpec("tension", "choice", "-", 'reactions: "linear" (paper) or "second-order" (+ the tension increment quadratic in the linear motion)', default="second-order", choices=TENSION_MODELS),
        _f("peak_window", "s", "peaks taken per window of the analysed record; statistics over windows x realizations (default: the whole record; a downburst's whole event)", low=0.0, high=1e5, low_open=True),
        _f("design_fractile", "-", "non-exceedance probability of the Gumbel design peak (0.5 = median peak)", default=0.5, low=0.0, high=0.999, low_open=True),
    ),
    "codes": (  # design-code comparison (issue 19, docs/codes.md)
        FieldSpec("terrain", "choice", "-", 'terrain for the design codes: "sea", "open", "suburban" or "urban" (maps to each code\'s category)', default="open", choices=CODE_TERRAINS),
        FieldSpec("asce74_exposure", "choice", "-", "ASCE 74 exposure category (default: from terrain)", choices=("B", "C", "D")),
        FieldSpec("iec60826_terrain", "choice", "-", "IEC 60826 terrain category (default: from terrain)", choices=("A", "B", "C", "D")),
        FieldSpec("en50341_terrain", "choice", "-", "EN 50341-1 / EN 1991-1-4 terrain category (default: from terrain)", choices=("0", "I", "II", "III", "IV")),
    ),
}


def field_spec(section: str, key: str) -> FieldSpec:
    """The :class:`FieldSpec` of ``section.key`` (``section`` "" for top level)."""
    for spec in SCHEMA[section]:
        if spec.name == key:
            return spec
    raise KeyError(f"{section}.{key}")


# --------------------------------------------------------------------------- dataclasses
@dataclass(frozen=True)
class Tower:
    """One tower of a section (issue 17; docs/case-files.md "Sections").  SI, angles in degrees."""

    name: str
    station: float  # [m] horizontal distance along the line from the first tower
    ground: float  # [m] ground elevation
    height: float  # [m] still-air clamp height above ground
    support: str  # SUPPORT_TYPES
    angle: float = 0.0  # [deg] line deviation, + = turning left
    insulator_length: float | None = None  # [m]; None = the line's default (suspension towers)


@dataclass(frozen=True)
class Line:
    """Conductor system of one line section (paper Table 1).

    Two forms: the paper's equal-span form (``spans``, ``span_length``, ``sag``, ``height``,
    ``supports``) and the section form (``towers`` + ``tension``, issue 17), for which the
    loader derives ``spans`` (n_towers - 1), ``span_length`` (Eq. 17's L_x: the mean of the two
    spans adjacent to the tower of interest), ``sag`` (W L_x^2 / 8 H0, display only),
    ``height`` (mean clamp height above ground) and ``supports`` (from the towers) for display;
    the numerical path reads the section's geometry from :class:`~linecheck.core.system.LineSystem`.
    """

    spans: int
    span_length: float  # [m]
    sag: float  # [m]
    weight: float  # [N/m]
    diameter: float  # [m] (projected area per unit length, m2/m = m)
    drag_coefficient: float  # [-]
    area: float  # [m2]
    elastic_modulus: float  # [Pa]
    height: float  # [m]
    insulator_length: float  # [m]
    supports: tuple[str, ...]
    tower_of_interest: int  # 1-based
    elements_per_span: int = 10
    tension: float | None = None  # [N] H0 at clipping-in (section form)
    towers: tuple[Tower, ...] | None = None  # section form: one per tower, in line order
    towers_file: str | None = None  # section form: CSV the towers were read from (as written)

    @property
    def is_section(self) -> bool:
        """True for the section (towers) form, False for the paper's equal-span form."""
        return self.towers is not None

    @property
    def n_towers(self) -> int:
        return self.spans + 1

    @property
    def ea(self) -> float:
        """Axial stiffness E*A [N]."""
        return self.elastic_modulus * self.area

    @property
    def mass_per_length(self) -> float:
        """Mass per unit length [kg/m] (W / g, g = 9.81 m/s2 as in paper Eq. 8)."""
        return self.weight / GRAVITY


@dataclass(frozen=True)
class Downburst:
    """Downburst geometry and time history (paper Fig. 2; see docs/method.md)."""

    jet_diameter: float  # [m] D_j
    distance: float  # [m] R
    angle: float  # [deg] Theta
    preset: str | None = None
    r_max: float | None = None  # [m]
    radial_decay: float | None = None  # [m]
    z_max: float | None = None  # [m]
    t1: float | None = None  # [s]
    t_f: float | None = None  # [s]
    translation_speed: float = 0.0  # [m/s]
    translation_direction: float = 90.0  # [deg]
    field: str | None = None  # path as written in the file
    field_path: Path | None = None  # resolved path
    model: str | None = None  # None: derived, see model_name
    jet_velocity: float | None = None  # [m/s] V_j ("ring-jet", "ring-jet-inviscid")

    @property
    def model_name(self) -> str:
        """The running-mean model in force: ``model``, else "table" with a field, else "holmes-oliver"."""
        if self.model is not None:
            return self.model
        return "table" if self.field is not None else "holmes-oliver"


@dataclass(frozen=True)
class Wind:
    type: str
    v_ref: float  # [m/s]
    turbulence_intensity: float = 0.12
    air_density: float = 1.25  # [kg/m3]
    coherence_decay: float = 10.0
    length_scale: float | None = None  # [m]; None = default of the wind type
    span_speeds: tuple[float, ...] | None = None  # [m/s]
    downburst: Downburst | None = None
    direction: float = 0.0  # [deg] mean wind vector V (sin d, cos d, 0)
    profile_exponent: float = 0.0  # [-] V(z) = v_ref (z / z_ref)^alpha
    reference_height: float | None = None  # [m]; None = mean clamp height above ground
    fft_length: str = "record"  # FFT_LENGTHS: the synthesis' transform length (docs/wind.md)


@dataclass(frozen=True)
class Analysis:
    duration: float | None = None  # [s]; None = default of the wind type
    time_step: float = 0.05  # [s]
    realizations: int = 10
    seed: int = 2015
    mean_states: int = 250
    damping: str = "quasi-steady"
    structural_damping: float | None = None  # [-]; None = default of the damping model
    burn_in: float | None = None  # [s]; None = derived (synoptic)
    drag: str = "quadratic"  # DRAG_MODELS (docs/method.md "Quadratic drag")
    tension: str = "second-order"  # TENSION_MODELS (docs/method.md "Second-order tension")
    peak_window: float | None = None  # [s]; None = the whole analysed record (issue 18)
    design_fractile: float = 0.5  # [-] non-exceedance probability of the design peak (issue 18)

    @property
    def structural_ratio(self) -> float:
        """Structural damping ratio in force [-]: the key, else 0 with ``"paper"`` (the paper has
        none) and :data:`DEFAULT_STRUCTURAL_DAMPING` with ``"quasi-steady"`` (docs/method.md)."""
        if self.structural_damping is not None:
            return self.structural_damping
        return 0.0 if self.damping == "paper" else DEFAULT_STRUCTURAL_DAMPING


@dataclass(frozen=True)
class Codes:
    """Terrain of the design-code comparison (docs/codes.md); None = from ``terrain``."""

    terrain: str = "open"
    asce74_exposure: str | None = None
    iec60826_terrain: str | None = None
    en50341_terrain: str | None = None


@dataclass(frozen=True)
class Case:
    """One analysis case: a line section, a wind and the analysis settings."""

    name: str
    line: Line
    wind: Wind
    analysis: Analysis = field(default_factory=Analysis)
    description: str = ""
    source: Path | None = None
    codes: Codes = field(default_factory=Codes)

    @property
    def g_yp(self) -> float:
        """Reference transverse load intensity g*_yp = 1/2 rho C_d V_ref^2 D [N/m] (paper Eq. 17)."""
        return 0.5 * self.wind.air_density * self.line.drag_coefficient * self.wind.v_ref**2 * self.line.diameter

    @property
    def g_yp_L(self) -> float:
        """Normalising force g*_yp * L_x [N] (paper Eq. 17, Fig. 13).

        L_x is the case's (equal) span length.  On a section of unequal spans (issue 17)
        L_x becomes the mean of the two spans adjacent to the tower of interest, which for
        equal spans is this same value.
        """
        return self.g_yp * self.line.span_length


GRAVITY = 9.81  # [m/s2], paper Eq. 8

_SUBTABLES = {"": ("line", "wind", "analysis", "codes"), "wind": ("downburst",)}


#: Bulk density of a conductor, W / (g pi D^2 / 4) [kg/m3], outside which ``line.weight`` is
#: probably mistyped: aluminium 2,700 to copper 8,900 with strands' voids (the paper's
#: conductor: 4,805); a weight typed in kg/m gives about 1/9.81 of it (490 for the paper's).
DENSITY_RANGE = (1500.0, 9000.0)


def case_warnings(case: Case) -> list[str]:
    """One-line warnings about values the schema allows but that are probably mistyped: the
    weight against the conductor's bulk density (:data:`DENSITY_RANGE`).  Names the file (and
    line when the file is readable), key, value and what is expected.  Never prints."""
    out: list[str] = []
    ln = case.line
    density = ln.weight / (GRAVITY * math.pi * ln.diameter**2 / 4.0)
    low, high = DENSITY_RANGE
    if not low <= density <= high:
        text = None
        if case.source is not None:
            try:
                text = Path(case.source).read_text(encoding="utf-8", errors="replace")
            except OSError:
                text = None
        where = ""
        if case.source is not None:
            line_no = _find_line(text, "line", "weight")
            where = f"{case.source}" + (f":{line_no}" if line_no is not None else "") + ": "
        if density < low:
            hint = (f"a weight in kg/m? In N/m it would be {ln.weight:g} x {GRAVITY:g} = "
                    f"{ln.weight * GRAVITY:.4g} N/m")
        else:
            hint = (f"a bundle's weight with one sub-conductor's diameter, or a unit slip? "
                    f"{high:,.0f} kg/m3 would be a weight of {high * GRAVITY * math.pi * ln.diameter**2 / 4.0:.4g} N/m")
        out.append(f"{where}line.weight: value {ln.weight:g} N/m with diameter {ln.diameter:g} m gives a "
                   f"bulk density W/(g pi D^2/4) of {density:,.0f} kg/m3, outside {low:,.0f}-{high:,.0f} "
                   f"(the paper's conductor: 4,805): {hint}")
    return out


# --------------------------------------------------------------------------- loading
def _find_line(text: str | None, section: str, key: str | None) -> int | None:
    """1-based line of ``key`` inside ``[section]`` (or of the header when key is None)."""
    if text is None:
        return None
    current = ""
    header = re.compile(r"^\s*\[\s*([A-Za-z0-9_.\-\" ]+?)\s*\]\s*(#.*)?$")
    for n, raw in enumerate(text.splitlines(), start=1):
        m = header.match(raw)
        if m:
            current = m.group(1).replace('"', "").replace(" ", "")
            if key is None and current == section:
                return n
            continue
        if key is not None and current == section and re.match(rf"^\s*\"?{re.escape(key)}\"?\s*=", raw):
            return n
    return None


class _Ctx:
    """Where a value came from, to build messages that name file, key and line."""

    def __init__(self, file: str | None, text: str | None) -> None:
        self.file = file
        self.text = text

    def error(self, section: str, key: str | None, message: str) -> CaseError:
        dotted = f"{section}.{key}" if section and key else (key or section or None)
        return CaseError(message, file=self.file, key=dotted, line=_find_line(self.text, section, key))


FMT_LIST_ITEMS = 5  # a list in a message shows its first items and its length, never the whole list


def _fmt(value: Any) -> str:
    """A value as a message shows it: strings quoted, TOML spellings, a long list abbreviated
    (``[1.0, 2.0, 3.0, 4.0, 5.0, ... (10000 items)]``) so that a message stays one short line."""
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        if len(value) > FMT_LIST_ITEMS + 1:
            head = ", ".join(_fmt(v) for v in value[:FMT_LIST_ITEMS])
            return f"[{head}, ... ({len(value)} items)]"
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, (datetime.date, datetime.time)):  # a TOML date/time: its TOML text
        return value.isoformat()
    return repr(value)


def _check_number(spec: FieldSpec, v: Any, ctx: _Ctx, section: str, item: tuple[int, int] | None = None) -> float:
    """``v`` checked against ``spec``'s kind and range.  ``item``: (1-based position, list length)
    of ``v`` in a list; a message then names that item and its value, never the whole list (the
    value is formatted only when it is refused: checking a list is linear in its length)."""
    if _number_ok(spec, v):
        return v
    shown = f"item {item[0]} of {item[1]} (value {_fmt(v)})" if item is not None else f"value {_fmt(v)}"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ctx.error(section, spec.name, f"{shown} is not allowed: expected {spec.allowed()}")
    if spec.kind == "int" and not isinstance(v, int):
        raise ctx.error(section, spec.name, f"{shown} is not allowed: expected {spec.allowed()}")
    if not math.isfinite(float(v)):
        raise ctx.error(section, spec.name, f"{shown} is not allowed: expected {spec.allowed()}")
    raise ctx.error(section, spec.name, f"{shown} is out of range: expected {spec.allowed()}")


def _number_ok(spec: FieldSpec, v: Any) -> bool:
    """Whether ``v`` is a number of ``spec``'s kind within its range (no message built)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    if spec.kind == "int" and not isinstance(v, int):
        return False
    if not math.isfinite(float(v)):
        return False
    if spec.low is not None and (v <= spec.low if spec.low_open else v < spec.low):
        return False
    return not (spec.high is not None and v > spec.high)


def _check_value(spec: FieldSpec, v: Any, ctx: _Ctx, section: str) -> Any:
    if spec.kind in ("float", "int"):
        out = _check_number(spec, v, ctx, section)
        return float(out) if spec.kind == "float" else int(out)
    if spec.kind == "str":
        if not isinstance(v, str):
            raise ctx.error(section, spec.name, f"value {_fmt(v)} is not allowed: expected {spec.allowed()}")
        return v
    if spec.kind == "choice":
        if not isinstance(v, str) or v not in spec.choices:
            hint = ""
            if isinstance(v, str):
                close = difflib.get_close_matches(v, spec.choices, n=1)
                hint = f' (did you mean "{close[0]}"?)' if close else ""
            raise ctx.error(section, spec.name, f"value {_fmt(v)} is not allowed: expected {spec.allowed()}{hint}")
        return v
    if spec.kind == "bool":
        if not isinstance(v, bool):
            raise ctx.error(section, spec.name, f"value {_fmt(v)} is not allowed: expected {spec.allowed()}")
        return v
    if spec.kind == "float_list":
        if not isinstance(v, list) or not v:
            raise ctx.error(section, spec.name, f"value {_fmt(v)} is not allowed: expected {spec.allowed()}")
        n = len(v)
        return tuple(float(_check_number(spec, x, ctx, section, item=(i, n))) for i, x in enumerate(v, start=1))
    if spec.kind == "str_list":
        if not isinstance(v, list) or not v:
            raise ctx.error(section, spec.name, f"value {_fmt(v)} is not allowed: expected a list, each {spec.allowed()}")
        for i, x in enumerate(v, start=1):
            if not isinstance(x, str) or (spec.choices and x not in spec.choices):
                raise ctx.error(section, spec.name, f"item {i} of {len(v)} (value {_fmt(x)}) is not allowed: "
                                f"expected each {spec.allowed()}")
        return tuple(v)
    raise ValueError(spec.kind)  # pragma: no cover - schema bug


def _read_section(data: dict, section: str, ctx: _Ctx) -> dict[str, Any]:
    """Validate the keys of one table against :data:`SCHEMA`; fill defaults."""
    specs = {s.name: s for s in SCHEMA[section]}
    subtables = set(_SUBTABLES.get(section, ()))
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key in subtables:
            if not isinstance(value, dict):
                raise ctx.error(section, key, f"value {_fmt(value)} is not allowed: expected a table [{(section + '.') if section else ''}{key}]")
            continue
        if key not in specs:
            candidates = list(specs) + sorted(subtables)
            close = difflib.get_close_matches(key, candidates, n=1, cutoff=0.5)
            hint = f'; did you mean "{close[0]}"?' if close else ""
            where = f"[{section}]" if section else "the top level"
            allowed = ", ".join(candidates)
            raise ctx.error(section, key, f"unknown key in {where}{hint} (allowed: {allowed})")
        out[key] = _check_value(specs[key], value, ctx, section)
    for name, spec in specs.items():
        if name not in out:
            if spec.required:
                raise ctx.error(section, name, f"missing required key: expected {spec.allowed()}")
            out[name] = spec.default
    return out


# C0 controls except tab, DEL and the C1 controls: they inject terminal escape sequences and
# openpyxl refuses them (IllegalCharacterError); no case text needs them (issue 14).
_CONTROL = re.compile("[\x00-\x08\x0a-\x1f\x7f-\x9f]")
MAX_NESTING = 16  # deepest table/array nesting a case file needs is 3 ([wind.downburst], a list)


def _check_text(data: dict[str, Any], ctx: _Ctx) -> None:
    """Reject control characters in every key and string value, and absurd nesting."""
    stack: list[tuple[str, Any, int]] = [("", data, 0)]
    while stack:
        where, value, depth = stack.pop()
        section, _, key = where.rpartition(".")
        if depth > MAX_NESTING:
            raise ctx.error(section, key or None, f"value nested {depth} levels deep is not allowed: expected "
                            f"at most {MAX_NESTING} levels of tables and arrays")
        if isinstance(value, str):
            m = _CONTROL.search(value)
            if m:
                raise ctx.error(section, key or None, f"control character U+{ord(m.group()):04X} at position "
                                f"{m.start() + 1} is not allowed: expected printable text")
        elif isinstance(value, dict):
            for k, v in value.items():
                m = _CONTROL.search(k)
                if m:
                    raise ctx.error(where, None, f"a key holds control character U+{ord(m.group()):04X}: "
                                    "expected printable key names")
                stack.append((f"{where}.{k}" if where else k, v, depth + 1))
        elif isinstance(value, list):
            stack.extend((where, v, depth + 1) for v in value)


def case_from_dict(
    data: dict[str, Any],
    *,
    file: str | None = None,
    text: str | None = None,
    default_name: str = "case",
    base_dir: Path | None = None,
) -> Case:
    """Validate a parsed TOML document and build a :class:`Case`.

    Raises :class:`CaseError` naming file, key, line, value and what is allowed.
    """
    ctx = _Ctx(file, text)
    _check_text(data, ctx)
    top = _read_section(data, "", ctx)
    for required in ("line", "wind"):
        if required not in data:
            raise ctx.error("", required, f"missing required table [{required}]")
    line_data = dict(data["line"]) if isinstance(data["line"], dict) else data["line"]
    towers_data = line_data.pop("towers", None) if isinstance(line_data, dict) else None
    line_d = _read_section(line_data, "line", ctx)
    wind_d = _read_section(data["wind"], "wind", ctx)
    an_d = _read_section(data.get("analysis", {}), "analysis", ctx)

    # ---- line cross-checks
    if towers_data is not None or line_d["towers_file"] is not None or line_d["tension"] is not None:
        line = _section_line(line_d, towers_data, ctx, base_dir)
    else:
        line = _equal_span_line(line_d, ctx)
    return _finish_case(data, top, line, wind_d, an_d, ctx, file, default_name, base_dir)


def _equal_span_line(line_d: dict[str, Any], ctx: _Ctx) -> Line:
    """The paper's equal-span form: ``spans``, ``span_length``, ``sag``, ``height`` (and ``supports``)."""
    for key in ("spans", "span_length", "sag", "height"):
        if line_d[key] is None:
            raise ctx.error("line", key, f"missing required key: expected {field_spec('line', key).allowed()} "
                            "(or describe the section with [[line.towers]] or towers_file and tension)")
    n_towers = line_d["spans"] + 1
    if line_d["supports"] is None:
        if line_d["spans"] == 1:
            line_d["supports"] = ("strain", "strain")
        else:
            raise ctx.error("line", "supports", f"missing: give {n_towers} entries, one per tower (\"strain\" or \"suspension\")")
    sup = line_d["supports"]
    if len(sup) != n_towers:
        raise ctx.error("line", "supports", f"value {_fmt(list(sup))} has {len(sup)} entries: expected {n_towers} (spans + 1), one per tower")
    if sup[0] != "strain" or sup[-1] != "strain":
        raise ctx.error("line", "supports", f"value {_fmt(list(sup))} is not allowed: the end towers must be \"strain\" (a suspension end leaves the section unrestrained along the line)")
    toi = line_d["tower_of_interest"]
    if toi > n_towers:
        raise ctx.error("line", "tower_of_interest", f"value {toi} is out of range: expected an integer from 1 to {n_towers} (number of towers)")
    if line_d["sag"] >= 0.25 * line_d["span_length"]:
        raise ctx.error("line", "sag", f"value {line_d['sag']!r} is out of range: expected a sag below span_length/4 = {0.25 * line_d['span_length']:g} m (shallow-cable method)")
    # physically meaningful geometry (issue 14): the lowest conductor point of a parabola whose
    # average elevation is `height` is height - sag/3; requiring sag < height keeps it at least
    # 2/3 sag above ground.  Insulator swing lifts the conductor, so no allowance is added.
    if line_d["sag"] >= line_d["height"]:
        raise ctx.error("line", "sag", f"value {line_d['sag']!r} is not allowed with height = {line_d['height']!r}: "
                        "expected sag < height (the conductor would reach the ground)")
    if "suspension" in sup and line_d["insulator_length"] >= line_d["height"]:
        raise ctx.error("line", "insulator_length", f"value {line_d['insulator_length']!r} is not allowed with "
                        f"height = {line_d['height']!r} and suspension towers: expected insulator_length < height")
    return Line(**line_d)


TOWER_COLUMNS = tuple(spec.name for spec in SCHEMA["line.towers"])
MAX_TOWERS = 201  # 200 spans (the equal-span form's limit)
_EQUAL_SPAN_KEYS = ("spans", "span_length", "sag", "height", "supports")


def _tower_line(text: str | None, k: int, key: str | None) -> int | None:
    """1-based file line of ``key`` in the k-th (0-based) ``[[line.towers]]`` table."""
    if text is None:
        return None
    count = -1
    inside = False
    for n, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if stripped.startswith("["):
            inside = re.match(r"^\[\[\s*line\s*\.\s*towers\s*\]\]", stripped) is not None
            if inside:
                count += 1
                if count == k and key is None:
                    return n
            continue
        if inside and count == k and key is not None and re.match(rf"^\s*\"?{re.escape(key)}\"?\s*=", raw):
            return n
    return None


class _TowerCtx(_Ctx):
    """Error context of one tower: an inline [[line.towers]] table or a CSV row."""

    def __init__(self, ctx: _Ctx, k: int, csv_file: str | None, row: int | None) -> None:
        super().__init__(ctx.file, ctx.text)
        self.k, self.csv_file, self.row = k, csv_file, row

    def error(self, section: str, key: str | None, message: str) -> CaseError:
        if self.csv_file is not None:
            where = f"row {self.row}" + (f", column {key}" if key else "")
            return CaseError(message, file=self.csv_file, key=where)
        dotted = f"line.towers[{self.k + 1}]" + (f".{key}" if key else "")
        return CaseError(message, file=self.file, key=dotted, line=_tower_line(self.text, self.k, key))


# A tower CSV's column names are quoted in a message only when they are short printable tokens
# like these; anything else -- a file that is not a tower table (towers_file = "/etc/shadow") --
# is refused without quoting its content.
_COLUMN_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_ .-]{0,31}")
MAX_QUOTED_CELL = 40  # [characters] a longer cell is described by its length, not quoted


def _not_a_tower_table(path: Path) -> CaseError:
    return CaseError(f"not a tower table: expected a comma-separated (CSV) file whose first row names its columns "
                     f"({', '.join(TOWER_COLUMNS)}; required: station, height, support) and one row per tower",
                     file=str(path))


def reads_as_header(header: list[str], columns: tuple[str, ...]) -> bool:
    """Whether a CSV file's first row makes it a table of ``columns`` (a tower table, a field
    file), so that its column names may be quoted in messages: at least two cells, each a short
    printable token (:data:`_COLUMN_TOKEN`), at least one of them one of ``columns`` or close to one."""
    if len(header) < 2 or not all(_COLUMN_TOKEN.fullmatch(h) for h in header):
        return False
    lower = [c.lower() for c in columns]
    return any(h.lower() in lower or difflib.get_close_matches(h.lower(), lower, n=1, cutoff=0.6) for h in header)


def _reads_as_tower_header(header: list[str]) -> bool:
    return reads_as_header(header, TOWER_COLUMNS)


def cell_text(cell: str) -> str:
    """A CSV data cell as a message quotes it: a short printable cell quoted (``"abc"``), anything
    longer or holding a control character described by its length (``of 60 characters``)."""
    return _fmt(cell) if len(cell) <= MAX_QUOTED_CELL and not _CONTROL.search(cell) else f"of {len(cell)} characters"


def _read_towers_csv(path: Path) -> list[tuple[dict[str, Any], int]]:
    """Rows of a tower CSV as raw dicts (numbers parsed) with their 1-based CSV record numbers.

    The same text rule as TOML strings (:data:`_CONTROL`: no control characters, a quoted newline
    included) holds for every cell; a leading byte-order mark is dropped (:func:`read_text_file`).
    A file whose first row is not a tower header (:func:`_reads_as_tower_header`) is "not a tower
    table", and no message quotes its content."""
    import csv
    import io

    text = read_text_file(path, "a CSV tower table", MAX_CASE_BYTES)
    try:
        rows = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error:
        raise _not_a_tower_table(path) from None
    # skip blank and comment lines, remembering file row numbers
    numbered = [(i + 1, r) for i, r in enumerate(rows) if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not numbered:
        raise CaseError(f"is empty: expected a header row with the columns {', '.join(TOWER_COLUMNS)} and one row per tower",
                        file=str(path))
    head_row, header = numbered[0]
    header = [h.strip() for h in header]
    if not _reads_as_tower_header(header):
        raise _not_a_tower_table(path)
    for h in header:
        if h not in TOWER_COLUMNS:
            close = difflib.get_close_matches(h, TOWER_COLUMNS, n=1, cutoff=0.5)
            hint = f'; did you mean "{close[0]}"?' if close else ""
            raise CaseError(f"unknown column {_fmt(h)}{hint} (allowed: {', '.join(TOWER_COLUMNS)})", file=str(path),
                            key=f"row {head_row}")
    repeated = [h for h in TOWER_COLUMNS if header.count(h) > 1]
    if repeated:
        raise CaseError(f"header repeats column {_fmt(repeated[0])}: expected each of {', '.join(TOWER_COLUMNS)} at most once",
                        file=str(path), key=f"row {head_row}")
    for spec in SCHEMA["line.towers"]:
        if spec.required and spec.name not in header:
            raise CaseError(f"missing column {_fmt(spec.name)}: expected the columns {', '.join(TOWER_COLUMNS)} "
                            f"(required: station, height, support)", file=str(path), key=f"row {head_row}")
    specs = {sp.name: sp for sp in SCHEMA["line.towers"]}
    out = []
    for row_no, r in numbered[1:]:
        if len(r) > len(header):
            raise CaseError(f"has {len(r)} cells: expected at most {len(header)} (one per header column)",
                            file=str(path), key=f"row {row_no}")
        d: dict[str, Any] = {}
        for col, cell in zip(header, r):
            m = _CONTROL.search(cell)
            if m:  # the TOML strings' rule (_check_text): ESC, NUL, a quoted newline ...
                raise CaseError(f"control character U+{ord(m.group()):04X} at position {m.start() + 1} is not "
                                "allowed: expected printable text", file=str(path), key=f"row {row_no}, column {col}")
            cell = cell.strip()
            if cell == "":
                continue
            if specs[col].kind == "float":
                try:
                    d[col] = float(cell)
                except ValueError:
                    raise CaseError(f"value {cell_text(cell)} is not a number: expected {specs[col].allowed()}",
                                    file=str(path), key=f"row {row_no}, column {col}") from None
            else:
                d[col] = cell
        out.append((d, row_no))
    return out


def _section_line(line_d: dict[str, Any], towers_data: Any, ctx: _Ctx, base_dir: Path | None) -> Line:
    """The section form (issue 17): [[line.towers]] or towers_file, and tension H0."""
    for key in _EQUAL_SPAN_KEYS:
        if line_d[key] is not None:
            raise ctx.error("line", key, f"value {_fmt(list(line_d[key]) if isinstance(line_d[key], tuple) else line_d[key])} "
                            "is not allowed with a tower table: the towers define the section (remove "
                            f"{key}, or remove [[line.towers]]/towers_file/tension to use the equal-span form)")
    if towers_data is not None and line_d["towers_file"] is not None:
        raise ctx.error("line", "towers_file", f"value {_fmt(line_d['towers_file'])} is not allowed together with "
                        "[[line.towers]]: give the towers either inline or in the file, not both")
    if line_d["tension"] is None:
        raise ctx.error("line", "tension", f"missing required key for a tower table: expected {field_spec('line', 'tension').allowed()} "
                        "(still-air horizontal tension H0 at clipping-in)")
    raw: list[tuple[dict[str, Any], _TowerCtx]] = []
    if line_d["towers_file"] is not None:
        path = Path(line_d["towers_file"])
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.exists():
            raise ctx.error("line", "towers_file", f"value {_fmt(line_d['towers_file'])}: file {path} does not exist "
                            "(expected a CSV tower table, see docs/case-files.md)")
        for k, (d, row_no) in enumerate(_read_towers_csv(path)):
            raw.append((d, _TowerCtx(ctx, k, str(path), row_no)))
    elif towers_data is None:
        raise ctx.error("line", "towers", "missing: give one [[line.towers]] table per tower or towers_file = \"section.csv\"")
    else:
        if not isinstance(towers_data, list) or not all(isinstance(t, dict) for t in towers_data):
            raise ctx.error("line", "towers", f"value {_fmt(towers_data)} is not allowed: expected [[line.towers]] tables, one per tower")
        raw = [(d, _TowerCtx(ctx, k, None, None)) for k, d in enumerate(towers_data)]
    n = len(raw)
    if not 2 <= n <= MAX_TOWERS:
        raise ctx.error("line", "towers_file" if line_d["towers_file"] else "towers",
                        f"has {n} towers: expected 2 to {MAX_TOWERS} towers (1 to {MAX_TOWERS - 1} spans)")
    towers = []
    for k, (d, tctx) in enumerate(raw):
        td = _read_section(d, "line.towers", tctx)
        if td["name"] is None:
            td["name"] = f"T{k + 1}"
        end = k in (0, n - 1)
        if end and td["support"] != "strain":
            raise tctx.error("", "support", f"value {_fmt(td['support'])} is not allowed at an end tower: expected \"strain\" "
                             "(a suspension end leaves the section unrestrained along the line)")
        if end and td["angle"] != 0.0:
            raise tctx.error("", "angle", f"value {td['angle']!r} is not allowed at an end tower: expected 0 (the line "
                             "deviates only at interior towers)")
        if td["insulator_length"] is not None and td["support"] != "suspension":
            raise tctx.error("", "insulator_length", f"value {td['insulator_length']!r} is not allowed at a strain tower: "
                             "expected it on suspension towers only (remove it)")
        v = td["insulator_length"] if td["insulator_length"] is not None else line_d["insulator_length"]
        if td["support"] == "suspension" and v >= td["height"]:
            raise tctx.error("", "height", f"value {td['height']!r} is not allowed with insulator length {v!r}: expected "
                             "height > insulator_length (the insulator's top would be below its clamp's ground)")
        if k and td["station"] <= towers[-1].station:
            raise tctx.error("", "station", f"value {td['station']!r} is not allowed: expected stations increasing along the "
                             f"line (the previous tower is at {towers[-1].station!r} m)")
        if k:
            span = td["station"] - towers[-1].station
            if not 10.0 <= span <= 3000.0:
                raise tctx.error("", "station", f"value {td['station']!r} gives a span of {span:g} m: expected spans "
                                 "from 10 to 3000 m")
        towers.append(Tower(**td))
    H0, W = line_d["tension"], line_d["weight"]
    for i in range(n - 1):
        a, b = towers[i], towers[i + 1]
        L = b.station - a.station
        sag = W * L**2 / (8.0 * H0)  # parabolic mid-span sag (Irvine 1981 Eq. 2.8)
        if sag >= 0.25 * L:
            raise ctx.error("line", "tension", f"value {H0!r} is too low for span {i + 1} ({a.name}-{b.name}, {L:g} m): its "
                            f"sag W L^2/(8 H0) = {sag:.4g} m exceeds a quarter of the span; expected tension > "
                            f"W L/2 = {0.5 * W * L:.6g} N")
        # lowest clearance above the ground line (parabola between the clamps)
        s = np.linspace(0.0, 1.0, 201)
        clear = a.height + (b.height - a.height) * s - 4.0 * sag * s * (1.0 - s)
        if clear.min() <= 0.0:
            raise ctx.error("line", "tension", f"value {H0!r} lets span {i + 1} ({a.name}-{b.name}) reach the ground "
                            f"(lowest still-air clearance {clear.min():.3g} m): expected a higher tension or taller towers")
    toi = line_d["tower_of_interest"]
    if toi > n:
        raise ctx.error("line", "tower_of_interest", f"value {toi} is out of range: expected an integer from 1 to {n} (number of towers)")
    stations = np.array([t.station for t in towers])
    spans = np.diff(stations)
    j = toi - 1
    adj = [spans[i] for i in (j - 1, j) if 0 <= i < n - 1]
    L_x = float(sum(adj) / len(adj))  # Eq. 17's L_x: mean of the adjacent spans (issue 17)
    d = dict(line_d)
    d.update(spans=n - 1, span_length=L_x, sag=W * L_x**2 / (8.0 * H0),
             height=float(np.mean([t.height for t in towers])),
             supports=tuple(t.support for t in towers), towers=tuple(towers))
    return Line(**d)


def _finish_case(data, top, line: Line, wind_d, an_d, ctx: _Ctx, file, default_name, base_dir) -> Case:

    # ---- wind cross-checks
    db_data = data["wind"].get("downburst")
    if wind_d["type"] == "downburst":
        if db_data is None:
            raise ctx.error("wind", "downburst", "missing table [wind.downburst] for type = \"downburst\"")
        db_d = _read_section(db_data, "wind.downburst", ctx)
        db = _build_downburst(db_d, line, ctx, base_dir)
        if wind_d["span_speeds"] is not None:
            raise ctx.error("wind", "span_speeds", "is for synoptic winds only: a downburst's speeds come from its field")
    else:
        if db_data is not None:
            raise ctx.error("wind", "downburst", "table [wind.downburst] given but type = \"synoptic\": remove it or set type = \"downburst\"")
        db = None
        if wind_d["span_speeds"] is not None and len(wind_d["span_speeds"]) != line.spans:
            raise ctx.error("wind", "span_speeds", f"value {_fmt(wind_d['span_speeds'])} has {len(wind_d['span_speeds'])} entries: expected {line.spans}, one per span")
    wind = Wind(downburst=db, **wind_d)

    analysis = Analysis(**an_d)
    if analysis.duration is not None and analysis.time_step * 4 > analysis.duration:
        raise ctx.error("analysis", "time_step", f"value {analysis.time_step!r} is too large for duration {analysis.duration!r}: expected at most duration/4")
    if analysis.peak_window is not None and analysis.peak_window < 4 * analysis.time_step:
        raise ctx.error("analysis", "peak_window", f"value {analysis.peak_window!r} is too short for time_step {analysis.time_step!r}: expected at least 4 time steps")
    codes = Codes(**_read_section(data.get("codes", {}), "codes", ctx))
    name = top["name"] or default_name
    return Case(name=name, description=top["description"] or "", line=line, wind=wind, analysis=analysis,
                source=Path(file) if file else None, codes=codes)


def _build_downburst(d: dict[str, Any], line: Line, ctx: _Ctx, base_dir: Path | None) -> Downburst:
    sec = "wind.downburst"
    preset = d["preset"]
    if preset is not None:
        dj = 2.0 * line.span_length  # paper Table 2 note: D_j = 2.0 L_x
        r_ratio, theta = (1.6, 30.0) if preset == "Db_x" else (1.2, 0.0)
        for key, val in (("jet_diameter", dj), ("distance", r_ratio * dj), ("angle", theta)):
            if d[key] is not None and not math.isclose(d[key], val, rel_tol=1e-9, abs_tol=1e-9):
                raise ctx.error(sec, key, f"value {d[key]!r} contradicts preset \"{preset}\" (which sets {key} = {val:g}): remove one of them")
            d[key] = val
    for key in ("jet_diameter", "distance", "angle"):
        if d[key] is None:
            raise ctx.error(sec, key, f"missing: give {key} or a preset (\"Db_x\" or \"Db_y\")")
    if d["t1"] is not None and d["t_f"] is not None and d["t_f"] <= d["t1"]:
        raise ctx.error(sec, "t_f", f"value {d['t_f']!r} is not allowed: expected t_f > t1 = {d['t1']!r}")
    model = d["model"] if d["model"] is not None else ("table" if d["field"] is not None else "holmes-oliver")
    if model == "table" and d["field"] is None:
        raise ctx.error(sec, "model", 'value "table" needs a field file: give field = "file.csv" (or .npz), see docs/wind.md')
    if model != "table" and d["field"] is not None:
        raise ctx.error(sec, "field", f'is read by model "table" only, but model = "{model}": remove field or set model = "table"')
    if model not in RING_MODELS and d["jet_velocity"] is not None:
        raise ctx.error(sec, "jet_velocity", f'is a parameter of model "ring-jet" (and "ring-jet-inviscid") only, but model = "{model}": remove it')
    if model in RING_MODELS:
        for key in ("t1", "t_f"):
            if d[key] is not None:
                raise ctx.error(sec, key, f'shapes the "holmes-oliver" time history only; model "{model}" takes its time scale from D_j/V_j (jet_velocity): remove {key}')
    path = None
    if d["field"] is not None:
        path = Path(d["field"])
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        if not path.exists():
            raise ctx.error(sec, "field", f"value {_fmt(d['field'])}: file {path} does not exist (expected a CSV or NPZ running-mean field, see docs/wind.md)")
    return Downburst(field_path=path, **d)


MAX_CASE_BYTES = 10 * 2**20  # [bytes] size cap of a TOML case file (docs/case-files.md)
MAX_RESULT_BYTES = 2**30  # [bytes] size cap of a saved JSON result read back (export, batch --resume)


def _size_text(n: int) -> str:
    return f"{n / 2**20:.1f} MB" if n >= 2**20 else f"{n} bytes"


def read_regular_file(path: str | Path, expected: str, max_bytes: int) -> bytes:
    """Bytes of a user file, read only if it is a regular file of at most ``max_bytes``.

    The file is opened without blocking (a FIFO never hangs), checked with ``fstat`` after
    opening (a symlink to /dev/zero or a device is refused before any read), its size is
    checked before reading, and at most ``max_bytes + 1`` bytes are read (a file growing
    while read is still refused).  One-line :class:`CaseError` naming the file otherwise.
    """
    p = Path(path)
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except FileNotFoundError:
        raise CaseError(f"file not found (expected {expected})", file=str(p)) from None
    except IsADirectoryError:
        raise CaseError(f"is a directory, expected {expected}", file=str(p)) from None
    except OSError as exc:
        raise CaseError(f"cannot read: {exc.strerror}", file=str(p)) from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise CaseError(f"is a directory, expected {expected}", file=str(p))
        if not stat.S_ISREG(st.st_mode):
            raise CaseError(f"is not a regular file (a pipe, socket or device), expected {expected}", file=str(p))
        if st.st_size > max_bytes:
            raise CaseError(f"file size {_size_text(st.st_size)} is too large: expected at most "
                            f"{_size_text(max_bytes)} ({expected})", file=str(p))
        chunks: list[bytes] = []
        left = max_bytes + 1
        while left > 0:
            b = os.read(fd, min(left, 2**20))
            if not b:
                break
            chunks.append(b)
            left -= len(b)
        if left <= 0:
            raise CaseError(f"file grew beyond {_size_text(max_bytes)} while read: expected at most "
                            f"{_size_text(max_bytes)} ({expected})", file=str(p))
        return b"".join(chunks)
    except OSError as exc:
        raise CaseError(f"cannot read: {exc.strerror}", file=str(p)) from None
    finally:
        os.close(fd)


def read_text_file(path: str | Path, expected: str, max_bytes: int = MAX_CASE_BYTES) -> str:
    """UTF-8 text of a user file; one-line :class:`CaseError` naming the file and ``expected``
    (e.g. "a TOML case file") when it is missing, a folder, not a regular file (FIFO, device),
    larger than ``max_bytes``, unreadable or not UTF-8.  A leading UTF-8 byte-order mark (which
    spreadsheets and some editors write) is dropped; the bytes, hence ``case_hash``, are as read."""
    data = read_regular_file(path, expected, max_bytes)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise CaseError(f"not a UTF-8 text file (expected {expected})", file=str(path)) from None


def load_case(path: str | Path) -> Case:
    """Read and validate a TOML case file.

    Raises :class:`CaseError` (one line: file, key, line, value, what is allowed).
    """
    p = Path(path)
    text = read_text_file(p, "a .toml case file")
    try:
        data = tomllib.loads(text)
    except RecursionError:  # tomllib recurses per nesting level (e.g. a = [[[[...]]]])
        raise CaseError(f"arrays or tables nested too deeply: expected at most {MAX_NESTING} levels",
                        file=str(p)) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        if m:
            raise CaseError(f"TOML syntax error at line {m.group(1)}, column {m.group(2)}: {msg}", file=str(p)) from None
        raise CaseError(f"TOML syntax error: {msg}", file=str(p)) from None
    return case_from_dict(data, file=str(p), text=text, default_name=p.stem, base_dir=p.parent)


def case_hash(path: str | Path) -> str:
    """SHA-256 of the case file's bytes (batch --resume)."""
    return hashlib.sha256(read_regular_file(path, "a .toml case file", MAX_CASE_BYTES)).hexdigest()


# --------------------------------------------------------------------------- editing / writing
_QUIET_DEFAULTS = ("direction", "profile_exponent")


def case_to_dict(case: Case) -> dict[str, Any]:
    """The TOML document of a case (only keys that are set), inverse of :func:`case_from_dict`."""
    def pick(obj: Any, section: str) -> dict[str, Any]:
        out = {}
        for spec in SCHEMA[section]:
            v = getattr(obj, spec.name)
            if v is None:
                continue
            out[spec.name] = list(v) if isinstance(v, tuple) else v
        return out

    doc: dict[str, Any] = {"name": case.name}
    if case.description:
        doc["description"] = case.description
    doc["line"] = pick(case.line, "line")
    if case.line.is_section:  # the towers define the section: the derived equal-span keys are not written
        for key in _EQUAL_SPAN_KEYS:
            doc["line"].pop(key, None)
        if case.line.towers_file is None:
            doc["line"]["towers"] = [{k: v for k, v in dataclasses.asdict(t).items() if v is not None}
                                     for t in case.line.towers]
    doc["wind"] = pick(case.wind, "wind")
    for key in _QUIET_DEFAULTS:  # issue 17 keys at their defaults are not written (older documents unchanged)
        if doc["wind"].get(key) == field_spec("wind", key).default:
            doc["wind"].pop(key)
    if case.wind.downburst is not None:
        db = pick(case.wind.downburst, "wind.downburst")
        if db.get("preset"):
            for k in ("jet_diameter", "distance", "angle"):
                db.pop(k, None)
        doc["wind"]["downburst"] = db
    doc["analysis"] = pick(case.analysis, "analysis")
    if case.codes != Codes():
        doc["codes"] = pick(case.codes, "codes")
    return doc


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return str(v)


def case_to_toml(case: Case) -> str:
    """Serialise a case to TOML text with units as comments."""
    doc = case_to_dict(case)
    lines: list[str] = []

    def emit(section: str, table: dict[str, Any]) -> None:
        for spec in SCHEMA[section]:
            if spec.name in table:
                unit = f"  # {spec.unit}" if spec.unit and spec.unit != "-" else ""
                lines.append(f"{spec.name} = {_toml_value(table[spec.name])}{unit}")

    emit("", doc)
    for section in ("line", "wind", "wind.downburst", "analysis", "codes"):
        table = doc.get(section) if "." not in section else doc["wind"].get("downburst")
        if table is None:
            continue
        lines.append("")
        lines.append(f"[{section}]")
        emit(section, table)
        if section == "line":
            for tower in table.get("towers", ()):
                lines.append("")
                lines.append("[[line.towers]]")
                emit("line.towers", tower)
    return "\n".join(lines) + "\n"


def with_value(case: Case, dotted_key: str, value: Any) -> Case:
    """A validated copy of ``case`` with one key changed (e.g. ``"wind.v_ref"``).

    The same validation and messages as the file loader (TUI editor, scans).
    """
    return with_values(case, {dotted_key: value})


def with_values(case: Case, changes: dict[str, Any]) -> Case:
    """A validated copy of ``case`` with several keys changed (``None`` removes a key)."""
    if not changes:
        return case
    doc = case_to_dict(case)
    for dotted_key, value in changes.items():
        *path, key = dotted_key.split(".")
        table = doc
        for p in path:
            table = table.setdefault(p, {})
        if value is None:
            table.pop(key, None)
        else:
            table[key] = value
    base = case.source.parent if case.source else None
    return case_from_dict(doc, file=str(case.source) if case.source else None, default_name=case.name, base_dir=base)


def with_options(case: Case, options: dict[str, tuple[str, Any]]) -> Case:
    """A validated copy of ``case`` with command-line overrides, e.g.
    ``{"--realizations": ("analysis.realizations", 20)}``: each value is checked against the
    :data:`SCHEMA` range with a message naming the option, then the case is re-validated."""
    changes: dict[str, Any] = {}
    for option, (dotted, value) in options.items():
        if value is None:
            continue
        section, _, key = dotted.rpartition(".")
        ctx = _Ctx(None, None)
        try:
            _check_value(field_spec(section, key), value, ctx, section)
        except CaseError as err:
            raise CaseError(err.message.split(": ", 1)[1] + f" (overrides {dotted})", key=option) from None
        changes[dotted] = value
    return with_values(case, changes)


def replace(obj: Any, **changes: Any) -> Any:
    """``dataclasses.replace`` re-exported for convenience."""
    return dataclasses.replace(obj, **changes)
