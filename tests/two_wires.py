"""A small case with two wires for the tests of every-wire jobs: a twin-bundle phase ``P`` on the
left of the line and a ground wire ``G`` above the centre, on a 3-span section (dead-end types
``DE`` at both ends, suspension type ``S`` between).  ``two_wires_text`` gives the TOML; the
keyword arguments change the wind."""

from __future__ import annotations

from pathlib import Path

TOWERS = """\
[[line.towers]]
name = "T1"
station = 0.0
type = "DE"

[[line.towers]]
name = "T2"
station = 320.0
ground = 3.0
type = "S"

[[line.towers]]
name = "T3"
station = 620.0
ground = -2.0
angle = 8.0
type = "S"

[[line.towers]]
name = "T4"
station = 950.0
type = "DE"
"""

WIRES = """\
[[wires]]
name = "P"
kind = "phase"
weight = 15.97
diameter = 0.0281
area = 4.25e-4
elastic_modulus = 6.9e10
tension = 25000.0
bundle = 2
bundle_spacing = 0.45

[[wires]]
name = "G"
kind = "ground"
weight = 5.8
diameter = 0.0126
area = 9.8e-5
elastic_modulus = 1.5e11
tension = 9000.0

[[tower_types]]
name = "S"
attachments = [
    { wire = "P", y = 6.0, z = 30.0, support = "suspension", insulator_length = 3.5 },
    { wire = "G", y = 0.0, z = 38.0, support = "suspension", insulator_length = 0.4 },
]

[[tower_types]]
name = "DE"
attachments = [
    { wire = "P", y = 6.0, z = 27.0, support = "strain" },
    { wire = "G", y = 0.0, z = 36.0, support = "strain" },
]
"""

SYNOPTIC = """\
[wind]
type = "synoptic"
v_ref = 32.0
direction = 15.0
profile_exponent = 0.16
"""

DOWNBURST = """\
[wind]
type = "downburst"
v_ref = 40.0

[wind.downburst]
model = "ring-jet"
preset = "Db_x"
"""

ANALYSIS = """\
[analysis]
time_step = 0.1
duration = 60.0
realizations = 2
mean_states = 4
seed = 7
"""


def two_wires_text(*, name: str = "two", wind: str = SYNOPTIC, towers: str = TOWERS, wires: str = WIRES) -> str:
    """The TOML of the two-wire case (``wind``: :data:`SYNOPTIC` or :data:`DOWNBURST` or any
    ``[wind]`` text)."""
    return (f'name = "{name}"\ndescription = "two wires: a twin phase and a ground wire"\n\n'
            f"[line]\ninsulator_length = 3.5\ntower_of_interest = 2\nelements_per_span = 6\n\n"
            f"{towers}\n{wires}\n{wind}\n{ANALYSIS}")


def write_two_wires(folder: Path, file: str = "two.toml", **kwargs) -> Path:
    """Write :func:`two_wires_text` (``kwargs``: its options) to ``folder / file``; its path."""
    path = Path(folder) / file
    path.write_text(two_wires_text(**kwargs), encoding="utf-8")
    return path
