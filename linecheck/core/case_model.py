"""The case model: frozen dataclasses of one analysis case (line, towers, wires, tower types,
wind, analysis, codes).

A :class:`Case` is built and validated by :mod:`.case_load` from a TOML file; every field that
has a :data:`~.case_schema.SCHEMA` default takes it from there (:func:`~.case_schema.schema_default`),
so a default is written once.  Units are SI (m, s, N, kg, Pa); angles are degrees, as in the
file (converted where used).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .case_schema import DEFAULT_STRUCTURAL_DAMPING, schema_default

GRAVITY = 9.81  # [m/s2], paper Eq. 8


@dataclass(frozen=True)
class Tower:
    """One tower of a section (the section form; docs/case-files.md "Sections").  SI, angles in degrees."""

    name: str
    station: float  # [m] horizontal distance along the line from the first tower
    ground: float  # [m] ground elevation
    height: float  # [m] still-air clamp height above ground
    support: str  # SUPPORT_TYPES
    angle: float = schema_default("line.towers.angle")  # [deg] line deviation, + = turning left
    insulator_length: float | None = None  # [m]; None = the line's default (suspension towers)
    type: str | None = None  # with wires: the TowerType name (None: a single-wire case)


@dataclass(frozen=True)
class Line:
    """Conductor system of one line section (paper Table 1).

    Two forms: the paper's equal-span form (``spans``, ``span_length``, ``sag``, ``height``,
    ``supports``) and the section form (``towers`` + ``tension``), for which the
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
    elements_per_span: int = schema_default("line.elements_per_span")
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
    translation_speed: float = schema_default("wind.downburst.translation_speed")  # [m/s]
    translation_direction: float = schema_default("wind.downburst.translation_direction")  # [deg]
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
    """Mean wind and turbulence at the line (``[wind]``; docs/wind.md)."""

    type: str
    v_ref: float  # [m/s]
    turbulence_intensity: float = schema_default("wind.turbulence_intensity")
    air_density: float = schema_default("wind.air_density")  # [kg/m3]
    coherence_decay: float = schema_default("wind.coherence_decay")
    length_scale: float | None = None  # [m]; None = default of the wind type
    span_speeds: tuple[float, ...] | None = None  # [m/s]
    downburst: Downburst | None = None
    direction: float = schema_default("wind.direction")  # [deg] mean wind vector V (sin d, cos d, 0)
    profile_exponent: float = schema_default("wind.profile_exponent")  # [-] V(z) = v_ref (z / z_ref)^alpha
    reference_height: float | None = None  # [m]; None = mean clamp height above ground
    fft_length: str = schema_default("wind.fft_length")  # FFT_LENGTHS: the synthesis' transform length (docs/wind.md)
    coherence_decay_y: float = schema_default("wind.coherence_decay_y")  # [-] C_y across the line (wires)
    coherence_decay_z: float = schema_default("wind.coherence_decay_z")  # [-] C_z in height (wires)


@dataclass(frozen=True)
class Analysis:
    """Time stepping, realizations, the damping, drag and tension models and the peak statistics
    (``[analysis]``; docs/method.md)."""

    duration: float | None = None  # [s]; None = default of the wind type
    time_step: float = schema_default("analysis.time_step")  # [s]
    realizations: int = schema_default("analysis.realizations")
    seed: int = schema_default("analysis.seed")
    mean_states: int = schema_default("analysis.mean_states")
    damping: str = schema_default("analysis.damping")
    structural_damping: float | None = None  # [-]; None = default of the damping model
    burn_in: float | None = None  # [s]; None = derived (synoptic)
    drag: str = schema_default("analysis.drag")  # DRAG_MODELS (docs/method.md "Quadratic drag")
    tension: str = schema_default("analysis.tension")  # TENSION_MODELS (docs/method.md "Second-order tension")
    drag_direction: str = schema_default("analysis.drag_direction")  # DRAG_DIRECTIONS (docs/method.md "Loads")
    peak_window: float | None = None  # [s]; None = the whole analysed record
    design_fractile: float = schema_default("analysis.design_fractile")  # [-] non-exceedance probability of the design peak

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

    terrain: str = schema_default("codes.terrain")
    asce74_exposure: str | None = None
    iec60826_terrain: str | None = None
    en50341_terrain: str | None = None


@dataclass(frozen=True)
class Wire:
    """One wire strung along the section (``[[wires]]``; docs/case-files.md "Every wire on the
    tower"): a phase conductor or bundle, or a ground wire.  The conductor keys describe ONE
    sub-conductor; a bundle of ``bundle`` sub-conductors acts as one wire (:attr:`weight_total`,
    :attr:`area_total`, :attr:`ea`, :attr:`tension_total`, :attr:`drag_diameter`)."""

    name: str
    kind: str  # WIRE_KINDS
    weight: float  # [N/m] one sub-conductor
    diameter: float  # [m] one sub-conductor
    area: float  # [m2] one sub-conductor
    elastic_modulus: float  # [Pa]
    tension: float  # [N] still-air H0 of one sub-conductor at clipping-in
    drag_coefficient: float = schema_default("wires.drag_coefficient")  # [-]
    bundle: int = schema_default("wires.bundle")  # [-] sub-conductors
    bundle_spacing: float | None = None  # [m] recorded only
    shielding: float = schema_default("wires.shielding")  # [-] bundle drag factor (1: none)

    @property
    def weight_total(self) -> float:
        """Weight per unit length of the bundle, n W [N/m]."""
        return self.bundle * self.weight

    @property
    def mass_per_length(self) -> float:
        """Mass per unit length of the bundle, n W / g [kg/m] (g = 9.81 m/s2 as in paper Eq. 8)."""
        return self.weight_total / GRAVITY

    @property
    def area_total(self) -> float:
        """Cross-section of the bundle, n A [m2]."""
        return self.bundle * self.area

    @property
    def ea(self) -> float:
        """Axial stiffness of the bundle, n E A [N]."""
        return self.elastic_modulus * self.area_total

    @property
    def tension_total(self) -> float:
        """Still-air horizontal tension of the bundle, n H0 [N] (the sub-conductors' sag W L^2 / 8 H0 kept)."""
        return self.bundle * self.tension

    @property
    def drag_diameter(self) -> float:
        """Projected area per unit length the bundle's drag acts on, n D s [m] (s: ``shielding``;
        1 = every sub-conductor loaded as if alone)."""
        return self.bundle * self.diameter * self.shielding


@dataclass(frozen=True)
class Attachment:
    """One wire's attachment on a tower type, in the tower frame (``attachments`` of a
    ``[[tower_types]]`` table) [m]: ``y`` to the left of the line's centre, ``z`` above the
    tower's ground at the point on the tower (a suspension insulator's top, a strain clamp)."""

    wire: str
    y: float  # [m] tower frame y, + = left looking along the line
    z: float  # [m] above the tower's ground: the insulator's top (suspension) or the clamp (strain)
    support: str  # SUPPORT_TYPES
    insulator_length: float | None = None  # [m]; None = line.insulator_length (suspension only)


@dataclass(frozen=True)
class TowerType:
    """One tower type (``[[tower_types]]``): where each wire hangs on it."""

    name: str
    attachments: tuple[Attachment, ...]

    def attachment(self, wire: str) -> Attachment:
        """The attachment carrying ``wire`` (KeyError when the type has none)."""
        for a in self.attachments:
            if a.wire == wire:
                return a
        raise KeyError(f"tower type {self.name!r} has no attachment of wire {wire!r}")


@dataclass(frozen=True)
class Case:
    """One analysis case: a line section, a wind and the analysis settings."""

    name: str
    line: Line
    wind: Wind
    analysis: Analysis = field(default_factory=Analysis)
    description: str = schema_default("description")
    source: Path | None = None
    codes: Codes = field(default_factory=Codes)
    wires: tuple[Wire, ...] = ()  # every wire of the section; () = the single wire of [line]
    tower_types: tuple[TowerType, ...] = ()  # with wires: the types line.towers[k].type names

    @property
    def has_wires(self) -> bool:
        """True when the case gives its wires (``[[wires]]``); its ``line`` is then the first
        wire's single-wire line (:func:`~linecheck.core.case_wires.wire_case`)."""
        return bool(self.wires)

    def wire(self, name: str) -> Wire:
        """The wire called ``name`` (KeyError when there is none)."""
        for w in self.wires:
            if w.name == name:
                return w
        raise KeyError(f"no wire {name!r}")

    def tower_type(self, name: str) -> TowerType:
        """The tower type called ``name`` (KeyError when there is none)."""
        for t in self.tower_types:
            if t.name == name:
                return t
        raise KeyError(f"no tower type {name!r}")

    @property
    def g_yp(self) -> float:
        """Reference transverse load intensity g*_yp = 1/2 rho C_d V_ref^2 D [N/m] (paper Eq. 17)."""
        return 0.5 * self.wind.air_density * self.line.drag_coefficient * self.wind.v_ref**2 * self.line.diameter

    @property
    def g_yp_L(self) -> float:
        """Normalising force g*_yp * L_x [N] (paper Eq. 17, Fig. 13).

        L_x is the case's (equal) span length.  On a section of unequal spans (the section form)
        L_x becomes the mean of the two spans adjacent to the tower of interest, which for
        equal spans is this same value.
        """
        return self.g_yp * self.line.span_length
