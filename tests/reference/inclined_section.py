"""An inclined line section in oblique wind, written as a towers-form case (TOML + towers CSV)
for the drag-direction checks (tests/integration/test_inclined_crossflow.py).

Five spans of 310-390 m on a straight line (every tower angle 0), strain towers at both ends,
suspension towers (insulator 3.0 m) in between.  The ground rises and falls so that the chords
slope +6 %, +10 %, +15 % (the steep span), -8 %, +5 % (clamp rise h_i over the horizontal span
L_i).  Synoptic wind, v_ref = 35 m/s at 10 m, power-law profile alpha = 0.16 (open terrain, as
cases/examples/section-12span.toml), direction 30 deg from the line's normal, so the wind has an
along-line component V sin 30 deg = V/2 and a normal one V cos 30 deg.  Conductor and keys as
the shipped example (docs/case-files.md, "Sections: towers, angles and terrain").

Like the references it imports nothing from linecheck.
"""

from __future__ import annotations

from pathlib import Path

# (name, station [m], clamp elevation above datum [m], height above ground [m], support)
# clamp elevations 130.0 -> 150.4 -> 186.4 -> 232.9 -> 201.7 -> 218.2: rises 20.4, 36.0, 46.5,
# -31.2, 16.5 m over 340, 360, 310, 390, 330 m = +6 %, +10 %, +15 %, -8 %, +5 %
TOWERS = (
    ("T1", 0.0, 130.0, 30.0, "strain"),
    ("T2", 340.0, 150.4, 36.0, "suspension"),
    ("T3", 700.0, 186.4, 33.0, "suspension"),
    ("T4", 1010.0, 232.9, 36.0, "suspension"),
    ("T5", 1400.0, 201.7, 33.0, "suspension"),
    ("T6", 1730.0, 218.2, 30.0, "strain"),
)
INSULATOR = 3.0  # [m] suspension insulator length
SLOPES = (0.06, 0.10, 0.15, -0.08, 0.05)  # [-] h_i / L_i of the chords, as built above

LINE = dict(weight=17.92, diameter=0.022, area=0.7e-4, elastic_modulus=5.2e10, drag_coefficient=1.0,
            tension=22000.0)  # [N/m, m, m2, Pa, -, N]: the conductor of cases/examples/section-12span.toml
WIND = dict(v_ref=35.0, direction=30.0, profile_exponent=0.16, reference_height=10.0)  # [m/s, deg, -, m]


def inclined_section_case(directory: str | Path, *, v_ref: float = WIND["v_ref"],
                          direction: float = WIND["direction"], drag_direction: str = "cross-flow",
                          stem: str = "inclined-crossflow", elements_per_span: int = 10) -> Path:
    """Write ``<stem>.toml`` and ``<stem>.csv`` into ``directory`` and return the TOML's path.

    Args:
        v_ref: [m/s] reference mean speed at 10 m (0: still air).
        direction: [deg] wind direction from the line's normal (V = V(z) (sin d, cos d, 0)).
        drag_direction: ``[analysis] drag_direction`` ("cross-flow" or "horizontal-normal").
        elements_per_span: linecheck's ``[line] elements_per_span``.
    The case pins ``drag = "linear"`` so that linecheck's step 1 carries the mean drag
    1/2 rho C_d D |V| V exactly (no turbulence-intensity term), as the FE reference does.
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    rows = ["name,station,ground,height,support,angle,insulator_length"]
    for name, station, clamp, height, support in TOWERS:
        ins = f"{INSULATOR}" if support == "suspension" else ""
        rows.append(f"{name},{station},{clamp - height:.1f},{height},{support},0,{ins}")
    (d / f"{stem}.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    toml = f'''# Inclined 5-span section (chords +6/+10/+15/-8/+5 %), wind 30 deg off the normal:
# written by tests/reference/inclined_section.py for the drag-direction checks.
name = "{stem}"
description = "5 inclined spans 310-390 m, suspension insulators 3 m, synoptic {v_ref} m/s at {direction} deg"

[line]
weight = {LINE["weight"]}             # N/m
diameter = {LINE["diameter"]}           # m
area = {LINE["area"]}              # m2
elastic_modulus = {LINE["elastic_modulus"]}   # Pa
drag_coefficient = {LINE["drag_coefficient"]}
insulator_length = {INSULATOR}     # m (suspension towers)
tension = {LINE["tension"]}          # N: still-air horizontal tension at clipping-in
towers_file = "{stem}.csv"
tower_of_interest = 3
elements_per_span = {elements_per_span}

[wind]
type = "synoptic"
v_ref = {v_ref}               # m/s at the reference height
direction = {direction}           # deg from the line's normal: V (sin d, cos d, 0)
profile_exponent = {WIND["profile_exponent"]}    # open terrain
reference_height = {WIND["reference_height"]}    # m
turbulence_intensity = 0.15

[analysis]
realizations = 1
seed = 2026
drag = "linear"           # step 1 under the mean drag 1/2 rho C_d D |V| V exactly (no I^2 term)
drag_direction = "{drag_direction}"
'''
    path = d / f"{stem}.toml"
    path.write_text(toml, encoding="utf-8")
    return path
