"""Regenerate docs/case-files.md from the case schema (the single source of every key).

Run from the repository root: ``python tools/make_case_reference.py``.  A test checks
that the committed file is up to date.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck.core.case_schema import SCHEMA, WIRE_SCHEMA

HEADER = """# Case files

A case file is TOML. Its key layout is a public contract: the names below do not change.
This page is generated from the schema in `linecheck/core/case_schema.py`
(`python tools/make_case_reference.py`).

Every key is checked for type and range; an unknown key is rejected with the closest valid
key suggested; a TOML syntax error is reported with line and column. Every message names the
file, the key (and its line), the value and what is allowed, on one line, and the command
exits with code 2. `linecheck check CASE...` validates files without running them.

Cross-checks: `supports` has `spans + 1` entries and both end towers are `"strain"`;
`tower_of_interest` ≤ number of towers; `sag` < `span_length`/4; `[wind.downburst]` is
required for `type = "downburst"` and rejected for `"synoptic"`; `span_speeds` (synoptic only)
has one entry per span; a `preset` and explicit `jet_diameter`/`distance`/`angle` must agree;
`time_step` ≤ `duration`/4; `sag` < `height` (the lowest point of a parabola of average
elevation `height` is `height` − `sag`/3; insulator swing lifts the conductor, so no swing
allowance is added); with suspension towers, `insulator_length` < `height`; downburst `model`
(default `"table"` with a `field`, else `"holmes-oliver"`): `"table"` needs `field`, `field`
needs `"table"`, `jet_velocity` is for `"ring-jet"` and `"ring-jet-inviscid"` only and `t1`/`t_f`
are not (docs/wind.md).

Hostile input: every key and string value is refused if it holds a control character (C0
except tab, DEL, C1: they would inject terminal escape sequences and are illegal in Excel),
e.g. `c.toml:1: name: control character U+001B at position 5 is not allowed: expected
printable text`; the same rule holds for every cell of a tower CSV (`towers_file`), a quoted
newline included. A message quotes a bad list item by its position and value (`item 5000 of
10000 (value -3.5)`), a long list by its first items and length, never the whole list, and a
list is checked in time linear in its length. A UTF-8 byte-order mark at the start of a case
file or a tower CSV (spreadsheets write one) is ignored. Tables and arrays nested more than 16
levels are refused. Only regular
files are read (a FIFO, a socket or a link to a device such as `/dev/zero` is refused
before any read, so `check` never hangs), and only up to a size cap checked before reading:
10 MB for a case file, 200 MB for a field file (`field`; for an NPZ, the uncompressed
arrays), 1 GB for a saved JSON result read back by `export` or `batch --resume`.

`linecheck check` also reads and validates the field file, scales the downburst to `v_ref`
at point p and estimates the run's memory and time, so errors that used to appear only at
`run` appear at `check`.

Resource guard: before any work, `run`, `batch` (every case before the batch starts, then each
task), `scan` (the whole grid), `static`, `modes`, `spectral`, `wind` and `check` estimate the
job's peak memory and time from the number of steps (`duration`/`time_step`), nodes (`spans` ×
`elements_per_span`), `realizations` and `mean_states` (and a scan's positions). Above the
memory limit the job is refused (exit 2; in a batch that case fails alone) with the estimate:

```
error: c.toml: run needs about 4.22 PB of memory and 3.82 years (time histories; 12001 steps,
27 DOF, 1000000000 realization(s), 250 mean state(s)): above the memory limit of 19 GB
(default 75% of the physical memory); reduce time_step, duration, realizations, mean_states
or elements_per_span, or raise the limit with --max-memory SIZE or LINECHECK_MAX_MEMORY=SIZE
```

The limit is 75 % of the physical memory unless `--max-memory SIZE` (`run`, `batch`, `scan`)
or the environment variable `LINECHECK_MAX_MEMORY` (every command, and the local batch
workers) says otherwise (`8GB`, `512MB`, `1.5GiB` or bytes; Dask workers read their own
environment). Above half the limit, or above an estimated 10 minutes, a one-line warning is
printed and the job runs. In a batch or a scan each task checks its own estimate (a batch
task holds one chunk of realizations), and a task above the limit fails that case only. The estimate includes
what a process keeps of the turbulence for reuse (unit fields and random phases, up to 384 MB;
docs/wind.md). The
estimate is rough (within about a factor of 2 on the paper
cases, see docs/performance.md); command-line overrides (`-n`, `--seed`) are checked against
the same ranges as the file and the message names the option.

A value inside its range can still be mistyped: `check`, `static`, `modes` and `run` warn in one
line (and run) when `line.weight` over g·πD²/4 — the wire's bulk density — is outside
1,500–9,000 kg/m³ (the paper's conductor: 4,805; a weight typed in kg/m gives about 490). The
line names the file, key, value and density, and the weight in N/m a kg/m value would be:

```
warning: c.toml:8: line.weight: value 1.827 N/m with diameter 0.022 m gives a bulk density
W/(g pi D^2/4) of 490 kg/m3, outside 1,500-9,000 (the paper's conductor: 4,805): a weight in
kg/m? In N/m it would be 1.827 x 9.81 = 17.92 N/m
```

Example (paper case 9, single span):

```toml
name = "case09"
description = "Synoptic, L = 300 m, Vref = 40 m/s (paper case 9)"

[line]
spans = 1
span_length = 300.0
sag = 10.0
weight = 17.92
diameter = 0.022
drag_coefficient = 1.0
area = 0.7e-4
elastic_modulus = 5.2e10
height = 43.0
insulator_length = 4.0
supports = ["strain", "strain"]
tower_of_interest = 1
elements_per_span = 10

[wind]
type = "synoptic"
v_ref = 40.0
turbulence_intensity = 0.12
air_density = 1.25
coherence_decay = 10.0

[analysis]
duration = 600.0
time_step = 0.05
realizations = 10
seed = 2015
damping = "paper"
drag = "linear"
tension = "linear"
```

## Sections: towers, angles and terrain

A real section is described by its towers instead of the equal-span keys: `[line] tension` (H0,
the still-air horizontal tension at clipping-in) and either one `[[line.towers]]` table per
tower, in line order, or `towers_file = "section.csv"` (a CSV with a header row and the same
columns: `name, station, ground, height, support, angle, insulator_length`, and `type` with
`[[wires]]`; blank cells take the default; `#` lines are comments). `spans`, `span_length`, `sag`, `height` and `supports`
are then not given (the loader derives them for display: `span_length` is Eq. 17's L_x, the
mean of the two spans adjacent to the tower of interest). `cases/examples/section-12span.toml`
is a worked example. The definitions (plan geometry, clipping-in, loads, tower frames) are in
docs/method.md, "Line sections".

```toml
[line]
tension = 20000.0          # N
[[line.towers]]
name = "T1"
station = 0.0              # m along the line
ground = 0.0               # m
height = 43.0              # m above ground (clamp, still air)
support = "strain"         # both end towers "strain"
angle = 0.0                # deg, + turning left; 0 at the ends
# insulator_length = 4.0   # suspension towers only (default: [line] insulator_length)
```

Section cross-checks (one line naming file, key or CSV row and column, value and what is
allowed; exit 2): stations strictly increasing with spans of 10–3000 m; end towers `"strain"`
with `angle = 0`; `insulator_length` only on suspension towers and below `height`; `height` >
0 (a clamp below ground is refused); `tension` > W L/2 on every span (sag W L²/8H0 below a
quarter of the span) and the still-air parabola clear of the straight ground line between
towers; not both `towers_file` and `[[line.towers]]`; a CSV with a missing column, an unknown
column or a non-number is refused naming its row and column. A file whose first row is not a
tower header -- at least two comma-separated column names, each a short printable token, one of
them a tower column or close to one -- is refused as `not a tower table` without quoting any of
its content (`towers_file = "/etc/passwd"` says nothing of that file); a bad cell longer than 40
characters is described by its length. `[wind] direction`,
`profile_exponent` and `reference_height` apply to both forms (equal-span form: every node at
`height`).

`drag` and `tension` choose how much of the non-linearity the method keeps. The
paper's method is `drag = "linear"` (Eq. 5: the drag's v² term dropped) and `tension =
"linear"` (reactions linear in the motion); the paper cases pin both and reproduce the paper's
method bit for bit. A case that omits them gets `drag = "quadratic"` (the v² term kept: its
mean I² in step 1, its zero-mean rest in the fluctuating load) and `tension = "second-order"`
(reactions with the tension increment quadratic in the linear motion): against a full
non-linear analysis of the same wind the linear pair is unconservative on every synoptic peak
(R_y −3 … −6 %, R_x −7 … −18 %, docs/validation.md), the pair of options closes most of that
gap, and it adds about a tenth to a ten-realization run (+9 … +15 % measured,
docs/performance.md). Derivations: docs/method.md, "Closing the linearisation gap".

"""

WIRES = """## Every wire on the tower: phases, bundles and ground wires

A tower carries several wires. `[[wires]]` lists them (one table per wire: a phase conductor or
bundle, a ground wire), `[[tower_types]]` says where each wire hangs on each type of tower, and
every tower of the section (`[[line.towers]]` or a `towers_file` row) names its `type`. A case
without `[[wires]]` is the single wire of `[line]`, unchanged.

With `[[wires]]` the line is a section (towers, no equal-span keys). `[line]` keeps
`insulator_length` (the default of suspension attachments), `tower_of_interest`,
`elements_per_span` and `towers_file`; `weight`, `diameter`, `drag_coefficient`, `area`,
`elastic_modulus` and `tension` are given per wire and refused in `[line]`. A tower gives
`station`, `ground`, `angle`, `name` and `type` (required); `height`, `support` and
`insulator_length` come from its type's attachments and are refused on the tower (a tower CSV
needs the columns `station` and `type`).

- **Wires.** The conductor keys describe one sub-conductor, with the units and ranges of
  `[line]`. A bundle of n = `bundle` sub-conductors acts as one wire, the sum of n identical
  sub-conductors: weight n W (mass n W/g), area n A (axial stiffness n E A), tension n H0 (the
  still-air sag W L²/8H0 stays the sub-conductor's), and drag on the projected width n D s with
  s = `shielding`. The default s = 1 takes no shielding of the leeward sub-conductors (each loaded
  as if alone); no code's value is assumed, give s from a source you trust. `bundle_spacing` is
  recorded only.
- **Attachments.** An attachment is a point of the tower in the tower frame: `y` to the left of
  the line's centre (looking along the line), `z` above the tower's ground, at the insulator's
  top for a suspension attachment (its still-air clamp hangs `insulator_length` v below, at
  z − v: the insulator's top is T = C + (0, 0, v), docs/method.md "Line sections") and at the
  clamp for a strain attachment. Each wire's single-wire line (`linecheck.core.case.wire_case`)
  has at tower k the clamp height, support and insulator of the wire's attachment on tower k's
  type, on the towers' stations, ground and angles; it runs along the line's centre (the offset
  `y` is kept for the tower's moments, not in the wire's plan geometry).
- **Coherence.** `[wind] coherence_decay_y` and `coherence_decay_z` are the decay constants C_y,
  C_z of the exponential coherence between wires separated across the line and in height (the
  along-line constant stays `coherence_decay`; the model: docs/wind.md "Many wires"); defaults 16
  and 10 as in Simiu & Scanlan, "Wind Effects on Structures" (3rd ed., 1996, Sect. 2.3, after
  Vellozzi & Cohen 1968; quoted as the literature quotes them, not checked against the book's
  page). Only a case with `[[wires]]` reads them.
- **One wind.** Every wire is loaded by the case's wind, with V_ref at the case's
  `reference_height` (default: the case's mean clamp height, which with `[[wires]]` is the
  first wire's); a wire's single-wire case carries that height (docs/wires.md "One wind").
- **Jobs.** A case with `[[wires]]` runs `check`, `static` (every attachment's reactions and
  each tower's totals) and `linecheck run` (every wire in one correlated wind: each attachment,
  the tower totals and load trees; docs/wires.md; the TUI's run does the same). Every other job
  (`spectral`, `modes`, `wind`, `codes`, `scan`, a batch's run) analyses one wire and refuses it
  in one line before any work (exit 2; a batch fails that case and runs the others):

  ```
  error: c.toml: wires: a case with several wires runs `check`, `static` and `linecheck run` (every
  attachment, the tower totals and load trees); `modes` of several wires is not available yet: run
  each wire as a single-wire case
  ```

Cross-checks (one line naming the file, key and line or CSV row and column, the value and what
is allowed; exit 2): `[[wires]]` and `[[tower_types]]` both given; wire and type names unique
and not empty; every type attaches every wire exactly once, each attachment naming a known
wire; every tower names a known type; at both end towers every attachment is `"strain"`;
`insulator_length` only on suspension attachments; at a suspension attachment z > 2 v (the clamp
z − v above v, as a single-wire tower's `height` > `insulator_length`); `bundle_spacing` and
`shielding` only with `bundle` ≥ 2; every wire's still-air spans, with its own W and H0, as a
section's `tension` (sag below a quarter of the span, clear of the ground line; the message
names `wires[k].tension`). For example:

```
error: c.toml:16: line.towers[2].type: value "SS" is not allowed: expected one of "S", "DE"
(the [[tower_types]] names) (did you mean "S"?)
error: c.toml:63: tower_types[2].attachments: has no attachment of wire "G": expected one
attachment per wire ("A", "B", "G")
```

Example (three wires, two tower types; a full case adds `[wind]` and `[analysis]`):

```toml
[line]
insulator_length = 3.6     # m, default of the suspension attachments
tower_of_interest = 2

[[line.towers]]
name = "T1"
station = 0.0              # m
type = "DE"                # a dead-end (strain) type at both ends
[[line.towers]]
name = "T2"
station = 300.0
ground = 2.0               # m
type = "S"
[[line.towers]]
name = "T3"
station = 600.0
type = "DE"

[[wires]]
name = "A"
kind = "phase"
weight = 17.92             # N/m, one sub-conductor
diameter = 0.022           # m
area = 0.7e-4              # m2
elastic_modulus = 5.2e10   # Pa
tension = 20000.0          # N, H0 of one sub-conductor
bundle = 2                 # twin bundle: 35.84 N/m, 40 kN, drag on 2 x 0.022 x 0.9 m
bundle_spacing = 0.4       # m, recorded only
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
name = "S"                 # suspension: z at the insulator's top
attachments = [
    { wire = "A", y = -5.5, z = 31.0, support = "suspension" },
    { wire = "B", y = 5.5, z = 31.0, support = "suspension", insulator_length = 4.0 },
    { wire = "G", y = 0.0, z = 40.0, support = "suspension", insulator_length = 0.3 },
]
[[tower_types]]
name = "DE"                # strain: z at the clamp
attachments = [
    { wire = "A", y = -5.5, z = 28.0, support = "strain" },
    { wire = "B", y = 5.5, z = 28.0, support = "strain" },
    { wire = "G", y = 0.0, z = 37.0, support = "strain" },
]
```

"""

#: headings of the array-of-tables sections
HEADINGS = {
    "line.towers": "[[line.towers]] (one table per tower, in line order; or one row of `towers_file`)",
    "wires": "[[wires]] (one table per wire)",
    "tower_types": "[[tower_types]] (one table per tower type; its `attachments`: the next table)",
    "tower_types.attachments": "attachments of a [[tower_types]] table (one inline table per wire)",
}


def _table(section: str, specs) -> list[str]:
    heading = HEADINGS.get(section) or ("[" + section + "]" if section else "Top level")
    out = [f"## {heading}\n", "| key | type | unit | default | allowed | meaning |", "| --- | --- | --- | --- | --- | --- |"]
    for s in specs:
        default = "required" if s.required else ("—" if s.default is None else f"`{s.default!r}`".replace("'", '"'))
        unit = s.unit if s.unit and s.unit != "-" else ""
        out.append(f"| `{s.name}` | {s.kind} | {unit} | {default} | {s.allowed()} | {s.help} |")
    out.append("")
    return out


def render() -> str:
    out = [HEADER]
    for section, specs in SCHEMA.items():
        out += _table(section, specs)
    out.append(WIRES)
    for section, specs in WIRE_SCHEMA.items():
        out += _table(section, specs)
    return "\n".join(out)


if __name__ == "__main__":
    (ROOT / "docs" / "case-files.md").write_text(render())
