"""The JSON Schema of a run-result document (docs/results.schema.json), built from the statistics
table and the header fields, and the layout facts it is built from: the schema version and the
header fields with their JSON types.

``tools/make_result_schema.py`` writes :func:`json_schema` to docs/results.schema.json; every
saved document read back is checked against it (:func:`result_schema`).  Forces in N.
"""

from __future__ import annotations

from typing import Any

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
                       "reactions": {"$ref": "#/$defs/reactions"}},
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
        "spectral": {"type": "object"},
        "time_histories": _histories_schema(),
        "provenance": {"$ref": "#/$defs/provenance"},
    }


def _definitions() -> dict[str, Any]:
    """The schema's ``$defs``: Gumbel fit, confidence interval, reactions, provenance, statistics."""
    reaction, reactions = _reaction_schemas()
    blas, provenance = _provenance_schemas()
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
