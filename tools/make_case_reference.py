"""Regenerate docs/case-files.md from the case schema (the single source of every key).

Run from the repository root: ``python tools/make_case_reference.py``.  A test checks
that the committed file is up to date.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from linecheck.core.case import SCHEMA  # noqa: E402

HEADER = """# Case files

A case file is TOML. Its key layout is a public contract: the names below do not change.
This page is generated from the schema in `linecheck/core/case.py`
(`python tools/make_case_reference.py`).

Every key is checked for type and range; an unknown key is rejected with the closest valid
key suggested; a TOML syntax error is reported with line and column. Every message names the
file, the key (and its line), the value and what is allowed, on one line, and the command
exits with code 2. `linecheck check CASE...` validates files without running them.

Cross-checks: `supports` has `spans + 1` entries and both end towers are `"strain"`;
`tower_of_interest` ≤ number of towers; `sag` < `span_length`/4; `[wind.downburst]` is
required for `type = "downburst"` and rejected for `"synoptic"`; `span_speeds` (synoptic only)
has one entry per span; a `preset` and explicit `jet_diameter`/`distance`/`angle` must agree;
`time_step` ≤ `duration`/4.

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

`drag` and `tension` (issue 16) choose how much of the non-linearity the method keeps. The
paper's method is `drag = "linear"` (Eq. 5: the drag's v² term dropped) and `tension =
"linear"` (reactions linear in the motion); the paper cases pin both and reproduce the paper's
method bit for bit. A case that omits them gets `drag = "quadratic"` (the v² term kept: its
mean I² in step 1, its zero-mean rest in the fluctuating load) and `tension = "second-order"`
(reactions with the tension increment quadratic in the linear motion): against a full
non-linear analysis of the same wind the linear pair is unconservative on every synoptic peak
(R_y −3 … −6 %, R_x −7 … −18 %, docs/validation.md), the pair of options closes most of that
gap, and it costs little (docs/performance.md). Derivations: docs/method.md, "Closing the
linearisation gap".

"""


def render() -> str:
    out = [HEADER]
    for section, specs in SCHEMA.items():
        out.append(f"## {'[' + section + ']' if section else 'Top level'}\n")
        out.append("| key | type | unit | default | allowed | meaning |")
        out.append("| --- | --- | --- | --- | --- | --- |")
        for s in specs:
            default = "required" if s.required else ("—" if s.default is None else f"`{s.default!r}`".replace("'", '"'))
            unit = s.unit if s.unit and s.unit != "-" else ""
            out.append(f"| `{s.name}` | {s.kind} | {unit} | {default} | {s.allowed()} | {s.help} |")
        out.append("")
    return "\n".join(out)


if __name__ == "__main__":
    (ROOT / "docs" / "case-files.md").write_text(render())
