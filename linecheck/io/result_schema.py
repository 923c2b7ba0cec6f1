"""The JSON Schema of a run-result document (docs/results.schema.json), built from the statistics
table and the header fields, and the layout facts it is built from: the schema version and the
header fields with their JSON types.

``tools/make_result_schema.py`` writes :func:`json_schema` to docs/results.schema.json; every
saved document read back is checked against it (:func:`result_schema`).  Forces in N.
"""

from __future__ import annotations

from typing import Any

from ..core.tower_totals import LOAD_CASES, TOTALS
from .schema import MAX_DEPTH, MAX_INTEGER, MAX_MAGNITUDE
from .stat_table import FLAG_STATES, GUMBEL_KEYS, REACTIONS, STAT_TABLE, SUMMARY_KEYS, StatDef

#: Version of the run-result JSON layout.  1 (no "schema_version" key): the first layout, with
#: statistics as {"mean", "std"} only.
SCHEMA_VERSION = 2

#: Header fields of a run document, in JSON order, with their JSON types (for the schema).
HEADER_FIELDS: tuple[tuple[str, str], ...] = (
    ("schema_version", "integer"),
    ("case", "string"),
    ("description", "string"),
    ("wind", "string"),
    ("units", "string"),
    ("tower_of_interest", "integer"),
    ("g_yp_L", "number"),
    ("v_ref", "number"),
    ("span_length", "number"),
    ("spans", "integer"),
    ("realizations", "integer"),
    ("seed", "integer"),
    ("duration", "number"),
    ("time_step", "number"),
    ("peak_window", "number|null"),
    ("windows", "integer"),
    ("design_fractile", "number"),
)

NUM_OR_NULL = {"type": ["number", "null"]}
STRING_OR_NULL = {"type": ["string", "null"]}


def _stat_schema(s: StatDef) -> dict[str, Any]:
    """Schema of one statistic of a reaction: the summary keys, ``gumbel`` of a peak, ``ci``."""
    props: dict[str, Any] = {k: NUM_OR_NULL for k in SUMMARY_KEYS}
    req = list(SUMMARY_KEYS)
    if s.peak:
        props["gumbel"] = {"$ref": "#/$defs/gumbel"}
        req.append("gumbel")
    if s.ci:
        props["ci"] = {"$ref": "#/$defs/ci"}
        req.append("ci")
    unit = s.unit if s.unit != "-" else "dimensionless"
    return {"type": "object", "description": f"{s.meaning} [{unit}]", "properties": props,
            "required": req, "additionalProperties": False}


def _reaction_schemas() -> tuple[dict[str, Any], dict[str, Any]]:
    """Schemas of one reaction's block (every statistic, its flag) and of the three reactions."""
    reaction = {
        "type": "object",
        "properties": {**{s.name: {"$ref": f"#/$defs/stat_{s.name}"} for s in STAT_TABLE},
                       "dynamic_analysis": {"enum": [*FLAG_STATES, None]}},
        "required": [*(s.name for s in STAT_TABLE), "dynamic_analysis"],
        "additionalProperties": False,
    }
    reactions = {"type": "object", "properties": {r: {"$ref": "#/$defs/reaction"} for r in REACTIONS},
                 "required": list(REACTIONS), "additionalProperties": False}
    return reaction, reactions


def _provenance_schemas() -> tuple[dict[str, Any], dict[str, Any]]:
    """Schemas of a BLAS library entry and of the ``provenance`` block."""
    blas = {"type": "object", "description": "a BLAS library loaded by the run's process: library (openblas, mkl, "
            "blis), version, core (the core kernel OpenBLAS selected for the CPU, e.g. Haswell, SkylakeX), "
            "threads, path of the shared library; null where the library does not say",
            "properties": {"library": {"type": "string"}, "version": STRING_OR_NULL, "core": STRING_OR_NULL,
                           "threads": {"type": ["integer", "null"]}, "path": STRING_OR_NULL},
            "required": ["library", "version", "core", "threads", "path"], "additionalProperties": False}
    piece = {"type": "object", "properties": {"name": {"type": "string"}, "on": {"type": "boolean"},
                                              "reason": {"type": "string"}},
             "required": ["name", "on", "reason"], "additionalProperties": False}
    provenance = {
        "type": "object",
        "description": "where the result was computed (as `linecheck info --json`): versions (numba: \"not "
                       "installed\" when absent), the BLAS numpy calls, the BLAS scipy.linalg calls (null when "
                       "numpy's) and the compiled kernel: Numba installed, LINECHECK_KERNEL mode, and per piece "
                       "whether it ran compiled (reason: why not, \"\" when on); absent from older results",
        "properties": {**{k: {"type": "string"} for k in ("linecheck", "python", "numpy", "scipy", "numba")},
                       "blas": {"$ref": "#/$defs/blas"},
                       "scipy_blas": {**blas, "type": ["object", "null"]},
                       "kernel": {"type": "object",
                                  "properties": {"installed": {"type": "boolean"},
                                                 "mode": {"enum": ["auto", "numpy", "numba"]},
                                                 "pieces": {"type": "array", "items": piece}},
                                  "required": ["installed", "mode", "pieces"], "additionalProperties": False}},
        "required": ["linecheck", "python", "numpy", "scipy", "numba", "blas", "kernel"],
        "additionalProperties": True,
    }
    return blas, provenance


def _json_type(t: str) -> dict[str, Any]:
    """``{"type": ...}`` of a :data:`HEADER_FIELDS` type (``"number|null"``: either)."""
    parts = t.split("|")
    return {"type": parts[0] if len(parts) == 1 else parts}


def _header_schema() -> dict[str, Any]:
    """Schemas of the header fields, in :data:`HEADER_FIELDS` order, with their bounds."""
    header = {k: _json_type(t) for k, t in HEADER_FIELDS}
    header["schema_version"] = {"const": SCHEMA_VERSION}
    header["tower_of_interest"] = {"type": "integer", "minimum": 1}
    header["spans"] = {"type": "integer", "minimum": 1}
    header["realizations"] = {"type": "integer", "minimum": 1, "maximum": 1_000_000_000}
    header["seed"] = {"type": "integer", "minimum": 0, "maximum": MAX_INTEGER}
    header["windows"] = {"type": "integer", "minimum": 1}
    header["wind"] = {"enum": ["synoptic", "downburst"]}
    header["units"] = {"const": "SI"}
    header["design_fractile"] = {"type": "number", "minimum": 0, "maximum": 1}
    return header


def _histories_schema() -> dict[str, Any]:
    """Schema of the ``time_histories`` block: time [s], per reaction M, B, R [N]."""
    series = {"type": "array", "items": NUM_OR_NULL}
    return {
        "type": "object", "description": "one realization at the tower of interest: time [s] and per reaction "
        "the mean M, background B and resonant R parts [N], maybe thinned (decimated)",
        "properties": {"realization": {"type": "integer", "minimum": 1}, "decimated": {"type": "boolean"},
                       "time": series,
                       **{r: {"type": "object", "properties": {k: series for k in ("M", "B", "R")},
                              "required": ["M", "B", "R"]} for r in REACTIONS}},
        "required": ["realization", "decimated", "time"]}


def _towers_schema() -> dict[str, Any]:
    """Schema of the ``towers`` list: index, support, the section metadata and the reactions."""
    return {"type": "array", "items": {
        "type": "object",
        "properties": {"index": {"type": "integer"}, "support": {"enum": ["strain", "suspension"]},
                       "name": {"type": "string"}, "station": {"type": "number"},
                       "ground": {"type": "number"}, "height": {"type": "number"},
                       "angle": {"type": "number"}, "heading": {"type": "number"},
                       "insulator_length": {"type": ["number", "null"]},
                       "global": {"type": "object", "description": "section form: still-air and "
                                  "step-1 mean reactions [N] in the global frame (x along the first span, "
                                  "y to its left, z down); the tower's reactions are in its own frame, "
                                  "x along heading"},
                       "uplift": _uplift_schema(),
                       "reactions": {"$ref": "#/$defs/reactions"},
                       "type": {"type": "string", "description": "a case with [[wires]]: the tower's type"},
                       "attachments": {"type": "array", "items": {"$ref": "#/$defs/run_attachment"}},
                       "totals": {"$ref": "#/$defs/run_totals"},
                       "load_trees": {"$ref": "#/$defs/load_trees"}},
        "required": ["index", "support", "reactions"], "additionalProperties": False}}


def _uplift_schema() -> dict[str, Any]:
    """Schema of a suspension tower's ``uplift`` (:class:`~linecheck.io.result_blocks.UpliftRecord`)."""
    still = {"type": "object", "properties": {"margin": NUM_OR_NULL, "weight_span": NUM_OR_NULL},
             "required": ["margin", "weight_span"], "additionalProperties": False}
    return {"type": "object", "description": "suspension towers only (absent at strain towers): margin [N], the "
            "smallest downward vertical force of the conductor on the clamp over the step-1 mean states "
            "(negative: the insulator would be in compression, uplift), weight_span [m] = margin / conductor "
            "weight per unit length there, time [s] its instant, and still_air: the same in still air",
            "properties": {"margin": NUM_OR_NULL, "weight_span": NUM_OR_NULL, "time": NUM_OR_NULL, "still_air": still},
            "required": ["margin", "weight_span", "time", "still_air"], "additionalProperties": False}


#: A step-1 value: a number, or a list over a downburst's step-1 instants (null where undefined).
STEP1_VALUE = {"type": ["number", "null", "array"], "items": NUM_OR_NULL}


def _static_wires_schemas() -> tuple[dict[str, Any], dict[str, Any]]:
    """Schemas of ``towers[i].attachments[j]`` and ``towers[i].totals`` of the step-1 document of
    a case with ``[[wires]]`` (``linecheck static --json``, docs/wires.md; not a run result)."""
    reactions = ("Rx", "Ry", "Rz")
    held = {"type": ["boolean", "array"], "items": {"type": "boolean"}}
    still = {"type": "object", "properties": {"margin": NUM_OR_NULL, "weight_span": NUM_OR_NULL,
                                              "held": {"type": "boolean"}},
             "required": ["margin", "weight_span", "held"], "additionalProperties": False}
    uplift = {"type": "object", "description": "suspension attachments only: margin [N] (R_z, negative: the "
              "insulator would be in compression), weight_span [m] = margin / the wire's weight per length, held "
              "(the clamp held at its still-air point), in each step-1 state and in still_air",
              "properties": {"margin": STEP1_VALUE, "weight_span": STEP1_VALUE, "held": held, "still_air": still},
              "required": ["margin", "weight_span", "held", "still_air"], "additionalProperties": False}
    attachment = {
        "type": "object",
        "description": "`linecheck static --json` of a case with [[wires]]: towers[i].attachments[j], wire j's "
                       "attachment on tower i: its point y (to the left of the line's centre) and z (above the "
                       "tower's ground) [m], the wire's support and clamp height [m], its reactions Rx, Ry, Rz [N] "
                       "in the tower frame (x along the tower's heading, y to its left, z down), their wind-induced "
                       "(_wind) and still-air (_still_air) parts, the clamp's displacements dx, dy, dz [m], the "
                       "reactions in the global frame, and uplift at a suspension attachment; a downburst lists "
                       "each value over the step-1 instants",
        "properties": {"wire": {"type": "string"}, "kind": {"enum": ["phase", "ground"]}, "y": {"type": "number"},
                       "z": {"type": "number"}, "support": {"enum": ["strain", "suspension"]},
                       "height": {"type": "number"},
                       **{r: STEP1_VALUE for r in reactions}, **{f"{r}_wind": STEP1_VALUE for r in reactions},
                       **{f"{r}_still_air": NUM_OR_NULL for r in reactions},
                       **{d: STEP1_VALUE for d in ("dx", "dy", "dz")},
                       "global": {"type": "object"}, "uplift": uplift},
        "required": ["wire", "kind", "y", "z", "support", *reactions, *(f"{r}_wind" for r in reactions)],
        "additionalProperties": False}
    totals = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
    tot = {
        "type": "object",
        "description": "`linecheck static --json` of a case with [[wires]]: towers[i].totals, the tower's "
                       "resultant [N] of its attachments' reactions (Fx, Fy, Fz: tower frame, z down) and its "
                       "moment [N m] about the tower's base (0, 0, 0), M = sum r x F with r = (0, y, z) and F = "
                       "(Rx, Ry, -Rz) in the right-handed frame x along the line, y to its left, z up: Mx = -sum (z "
                       "Ry + y Rz), My = sum z Rx, Mz = -sum y Rx; with the wind-induced (_wind) and still-air "
                       "(_still_air) parts; a downburst lists each value over the step-1 instants",
        "properties": {**{k: STEP1_VALUE for k in totals}, **{f"{k}_wind": STEP1_VALUE for k in totals},
                       **{f"{k}_still_air": NUM_OR_NULL for k in totals}},
        "required": [*totals, *(f"{k}_wind" for k in totals), *(f"{k}_still_air" for k in totals)],
        "additionalProperties": False}
    return attachment, tot


def _run_wires_schemas() -> dict[str, Any]:
    """The ``$defs`` of a run of a case with ``[[wires]]`` (docs/wires.md,
    :mod:`linecheck.io.wires_blocks`): ``run_attachment``, ``total``, ``run_totals``,
    ``peak_bound``, ``load_tree``, ``load_trees`` and ``wire``."""
    reaction, _ = _reaction_schemas()
    bound = {"type": "object", "properties": {**{k: NUM_OR_NULL for k in SUMMARY_KEYS},
                                              "gumbel": {"$ref": "#/$defs/gumbel"}},
             "required": [*SUMMARY_KEYS, "gumbel"], "additionalProperties": False}
    total = {**reaction, "description": "one total of the tower, from the summed histories of its attachments: "
             "every statistic of a reaction [N; moments N m] and the flag, peak_sum: the sum over the attachments "
             "of their own peak_dynamic and peak_largest the largest of them (per sample, summarised with a "
             "Gumbel fit), peak_to_sum and peak_to_largest: the mean peak_dynamic of the total over their means",
             "properties": {**reaction["properties"], "peak_sum": {**bound, "description": "sum of the attachments' "
                            "peak_dynamic [N or N m]"},
                            "peak_largest": {**bound, "description": "largest attachment's peak_dynamic"},
                            "peak_to_sum": NUM_OR_NULL, "peak_to_largest": NUM_OR_NULL},
             "required": [*reaction["required"], "peak_sum", "peak_largest", "peak_to_sum", "peak_to_largest"]}
    attachment = {
        "type": "object",
        "description": "a run of a case with [[wires]]: towers[i].attachments[j], wire j's attachment on tower i: "
                       "its point y (to the left of the line's centre) and z (above the tower's ground) [m], support, "
                       "the wire's still-air clamp height [m], the statistics of its reactions Rx, Ry, Rz [N] in the "
                       "tower frame (z down) and its uplift at a suspension attachment",
        "properties": {"wire": {"type": "string"}, "kind": {"enum": ["phase", "ground"]}, "y": {"type": "number"},
                       "z": {"type": "number"}, "support": {"enum": ["strain", "suspension"]}, "height": NUM_OR_NULL,
                       "uplift": _uplift_schema(), "reactions": {"$ref": "#/$defs/reactions"}},
        "required": ["wire", "kind", "y", "z", "support", "reactions"], "additionalProperties": False}
    totals = {"type": "object", "description": "a run of a case with [[wires]]: towers[i].totals, forces Fx, Fy, Fz "
              "[N] (tower frame, z down) and moments Mx, My, Mz [N m] about the tower's base (M = sum r x F, z up: "
              "Mx = -sum (z Ry + y Rz), My = sum z Rx, Mz = -sum y Rx)",
              "properties": {k: {"$ref": "#/$defs/total"} for k in TOTALS}, "required": list(TOTALS),
              "additionalProperties": False}
    comps = ("Rx", "Ry", "Rz")
    load = {"type": "object", "description": "one wire's reaction [N] (tower frame, z down, still air included) at "
            "the instant the load case's total is reached: mean over the samples and its standard deviation (_std)",
            "properties": {"wire": {"type": "string"}, **{c: NUM_OR_NULL for c in comps},
                           **{f"{c}_std": NUM_OR_NULL for c in comps}},
            "required": ["wire", *comps, *(f"{c}_std" for c in comps)], "additionalProperties": False}
    tree = {"type": "object", "description": "the coincident attachment loads of one load case: total (the "
            "governing total), value: that total at its instant, still air included [N or N m], mean over the "
            "samples, value_std its standard deviation, attachments: every wire's load (they add up to value)",
            "properties": {"total": {"enum": list(TOTALS)}, "value": NUM_OR_NULL, "value_std": NUM_OR_NULL,
                           "attachments": {"type": "array", "items": load}},
            "required": ["total", "value", "value_std", "attachments"], "additionalProperties": False}
    trees = {"type": "object", "description": "a run of a case with [[wires]]: towers[i].load_trees, one per load "
             "case: " + ", ".join(f"{k} ({'least' if sense == 'min' else 'largest |'}{t}{'' if sense == 'min' else '|'})"
                                  for k, (t, sense) in LOAD_CASES.items()),
             "properties": {k: {"$ref": "#/$defs/load_tree"} for k in LOAD_CASES}, "required": list(LOAD_CASES),
             "additionalProperties": False}
    wire = {"type": "object", "description": "a run of a case with [[wires]]: wires[k], wire k's name, kind, "
            "sub-conductors, its offset in the one turbulence field (y, z [m]: its attachment's y and still-air "
            "clamp height at the tower of interest) and its record's burn-in (null: a downburst)",
            "properties": {"name": {"type": "string"}, "kind": {"enum": ["phase", "ground"]},
                           "bundle": {"type": "integer", "minimum": 1},
                           "field_offset": {"type": "object", "properties": {"y": NUM_OR_NULL, "z": NUM_OR_NULL},
                                            "required": ["y", "z"], "additionalProperties": False},
                           "burn_in": {"type": ["object", "null"]}},
            "required": ["name", "kind", "bundle", "field_offset", "burn_in"], "additionalProperties": False}
    return {"run_attachment": attachment, "total": total, "run_totals": totals, "load_tree": tree,
            "load_trees": trees, "wire": wire}


def _properties() -> dict[str, Any]:
    """The document's top-level properties: header, ``until``, reactions, towers, blocks."""
    return {
        **_header_schema(),
        "until": {"type": "object",
                  "properties": {"target": {"type": "number"}, "achieved": NUM_OR_NULL,
                                 "reached": {"type": "boolean"}, "max_realizations": {"type": "integer"}},
                  "required": ["target", "achieved"]},
        "reactions": {"$ref": "#/$defs/reactions"},
        "towers": _towers_schema(),
        "still_air": {"type": "object"},
        "static": {"type": "object"},
        "parameters": {"type": "object"},
        "burn_in": {"type": "object"},
        "damping": {"type": "string"},
        "structural_damping": {"type": "number"},
        "wires": {"type": "array", "items": {"$ref": "#/$defs/wire"}},
        "spectral": {"type": "object"},
        "time_histories": _histories_schema(),
        "provenance": {"$ref": "#/$defs/provenance"},
    }


def _definitions() -> dict[str, Any]:
    """The schema's ``$defs``: Gumbel fit, confidence interval, reactions, provenance, statistics,
    and the step-1 blocks of a case with ``[[wires]]`` (``static_attachment``, ``static_totals``)."""
    reaction, reactions = _reaction_schemas()
    blas, provenance = _provenance_schemas()
    static_attachment, static_totals = _static_wires_schemas()
    return {
        "gumbel": {"type": "object", "description": "method-of-moments Gumbel (EV-I) fit of the peak; "
                   "design = value at non-exceedance probability design_fractile",
                   "properties": {k: NUM_OR_NULL for k in GUMBEL_KEYS}, "required": list(GUMBEL_KEYS),
                   "additionalProperties": False},
        "ci": {"type": "array", "description": "95 % confidence interval of the mean [low, high]",
               "prefixItems": [NUM_OR_NULL, NUM_OR_NULL], "minItems": 2, "maxItems": 2},
        "reaction": reaction,
        "reactions": reactions,
        "blas": blas,
        "provenance": provenance,
        "static_attachment": static_attachment,
        "static_totals": static_totals,
        **_run_wires_schemas(),
        **{f"stat_{s.name}": _stat_schema(s) for s in STAT_TABLE},
    }


def json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12 subset) of a run-result document, generated from
    :data:`~linecheck.io.stat_table.STAT_TABLE` and :data:`HEADER_FIELDS`
    (``tools/make_result_schema.py`` writes it to docs/results.schema.json).  Keywords used:
    type, properties, required, additionalProperties, items, prefixItems, minItems, maxItems,
    enum, const, $ref, $defs, minimum, maximum, description."""
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://github.com/linecheck/linecheck/docs/results.schema.json",
        "title": "linecheck run result",
        "description": ("Result of `linecheck run --json` and of each case of a batch (schema_version "
                        f"{SCHEMA_VERSION}). Forces in N, Cont_* as fractions; null where undefined. "
                        f"Everywhere in the document (linecheck checks it on read): numbers finite and of magnitude "
                        f"at most {MAX_MAGNITUDE:g}, integers of magnitude at most {MAX_INTEGER}, arrays and "
                        f"objects nested at most {MAX_DEPTH} levels. "
                        "$defs static_attachment and static_totals describe the per-tower blocks of `linecheck "
                        "static --json` of a case with [[wires]] (docs/wires.md); a run of such a case adds wires, "
                        "and to each tower its type, attachments, totals and load_trees ($defs run_attachment, "
                        "run_totals, load_trees, wire). "
                        "Generated by tools/make_result_schema.py from linecheck/io/document.py."),
        "type": "object",
        "properties": _properties(),
        "required": [k for k, _ in HEADER_FIELDS] + ["reactions", "towers"],
        "additionalProperties": True,
        "$defs": _definitions(),
    }


_SCHEMA: dict[str, Any] | None = None


def result_schema() -> dict[str, Any]:
    """:func:`json_schema`, built once (every document read is checked against it)."""
    global _SCHEMA
    if _SCHEMA is None:
        _SCHEMA = json_schema()
    return _SCHEMA
