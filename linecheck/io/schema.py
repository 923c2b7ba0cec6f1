"""Reading a saved result document safely: JSON text to checked values (no UI imports).

:func:`read_json_file` parses a user's JSON file and turns every way the parse can fail -- bad
syntax, an integer too long for Python to convert (more than 4300 digits), arrays or objects
nested deeper than the parser can recurse -- into one :class:`CaseError` naming the file.

:func:`first_violation` checks a document against a JSON Schema of the subset
docs/results.schema.json uses (type, properties, required, additionalProperties, items,
prefixItems, minItems, maxItems, enum, const, local ``$ref``, minimum, maximum), and against
limits every document obeys (:data:`MAX_MAGNITUDE`, :data:`MAX_INTEGER`, :data:`MAX_DEPTH`),
reporting the first violation as a key path, the value and what is allowed (one line).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from ..core.errors import CaseError

#: [any unit] Largest magnitude of a number in a result: far above any force [N], length [m],
#: time [s] or modulus [Pa] a result holds, far below what overflows float64 in sums and squares.
MAX_MAGNITUDE = 1e15
#: Largest magnitude of an integer (seeds are 64-bit).
MAX_INTEGER = 2**63 - 1
#: Deepest nesting of arrays and objects (a result nests about 8 levels).
MAX_DEPTH = 64
#: Integers of more digits than this are not converted while parsing (Python refuses above 4300).
_MAX_DIGITS = 1000


class HugeInteger:
    """A JSON integer of more than ``_MAX_DIGITS`` digits, kept unconverted (its digit count) so
    that the check names where it is."""

    __slots__ = ("digits",)

    def __init__(self, digits: int) -> None:
        self.digits = digits


def _parse_int(text: str) -> int | HugeInteger:
    digits = len(text.lstrip("-"))
    return HugeInteger(digits) if digits > _MAX_DIGITS else int(text)


def parse_json(text: str, source: str, expected: str) -> Any:
    """The value of JSON ``text``; :class:`CaseError` naming ``source`` and what was ``expected``
    for bad syntax or nesting too deep to parse.  Integers too long to convert come back as
    :class:`HugeInteger` (refused by :func:`first_violation`)."""
    try:
        return json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as exc:
        raise CaseError(f"invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg} (expected {expected})",
                        file=source) from None
    except RecursionError:
        raise CaseError(f"arrays or objects nested too deeply to read: expected {expected} (at most {MAX_DEPTH} "
                        "levels)", file=source) from None
    except ValueError as exc:  # e.g. an integer too long for int(); the hook above should catch those
        raise CaseError(f"not readable as JSON ({' '.join(str(exc).split())}): expected {expected}",
                        file=source) from None


def read_json_file(path: str | Path, expected: str, max_bytes: int) -> Any:
    """Parse the JSON file ``path`` (a regular UTF-8 file of at most ``max_bytes``); every
    failure is one :class:`CaseError` naming the file (see :func:`parse_json`)."""
    from ..core.case import read_text_file

    return parse_json(read_text_file(path, expected, max_bytes), str(path), expected)


# --------------------------------------------------------------------------- values shown in messages
def shown(value: Any) -> str:
    """A short text of a JSON value for a message."""
    if isinstance(value, HugeInteger):
        return f"(an integer of {value.digits} digits)"
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value) if abs(value) < 10**20 else f"(an integer of {len(str(abs(value)))} digits)"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else {math.inf: "Infinity", -math.inf: "-Infinity"}.get(value, "NaN")
    if isinstance(value, str):
        text = json.dumps(value[:40], ensure_ascii=False)
        return text if len(value) <= 40 else text[:-1] + '..."'
    if isinstance(value, list):
        return f"(a list of {len(value)} items)"
    if isinstance(value, dict):
        return "(an object)"
    return f"({type(value).__name__})"


def _g(x: float) -> str:
    if isinstance(x, int):
        return str(x)
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e16 else f"{x:g}"


_TYPE_NAMES = {"object": "an object", "array": "a list", "string": "a string", "integer": "an integer",
               "number": "a number", "boolean": "true or false", "null": "null"}


def allowed(schema: dict[str, Any], root: dict[str, Any]) -> str:
    """What ``schema`` allows, in words (``an integer >= 1``, ``one of "a", "b" or null``)."""
    while "$ref" in schema:
        schema = root["$defs"][schema["$ref"].split("/")[-1]]
    if "const" in schema:
        return json.dumps(schema["const"])
    if "enum" in schema:
        items = [json.dumps(v) for v in schema["enum"]]
        return items[0] if len(items) == 1 else "one of " + ", ".join(items[:-1]) + " or " + items[-1]
    types = schema.get("type", [])
    types = [types] if isinstance(types, str) else list(types)
    lo, hi = schema.get("minimum"), schema.get("maximum")
    words = []
    for t in types:
        text = _TYPE_NAMES.get(t, t)
        if t in ("integer", "number"):
            if lo is not None and hi is not None:
                text += f" between {_g(lo)} and {_g(hi)}"
            elif lo is not None:
                text += f" >= {_g(lo)}"
            elif hi is not None:
                text += f" <= {_g(hi)}"
        if t == "array" and "minItems" in schema and schema.get("minItems") == schema.get("maxItems"):
            text += f" of {schema['minItems']} items"
        words.append(text)
    if not words:
        return "a JSON value"
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]


# --------------------------------------------------------------------------- the check
_IS_TYPE = {
    "object": lambda v: isinstance(v, dict),
    "array": lambda v: isinstance(v, list),
    "string": lambda v: isinstance(v, str),
    "integer": lambda v: isinstance(v, (int, HugeInteger)) and not isinstance(v, bool),
    "number": lambda v: isinstance(v, (int, float, HugeInteger)) and not isinstance(v, bool),
    "boolean": lambda v: isinstance(v, bool),
    "null": lambda v: v is None,
}


def _key(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _limits(value: Any) -> tuple[str, str] | None:
    """(path, message) of the first value anywhere in ``value`` beyond the limits every document
    obeys (finite numbers of bounded magnitude, 64-bit integers, bounded nesting); None if none."""
    stack: list[tuple[Any, str, int]] = [(value, "", 0)]
    while stack:
        v, path, depth = stack.pop()
        if isinstance(v, dict):
            if depth >= MAX_DEPTH:
                return path, f"value nested {depth + 1} levels deep is not allowed: expected at most {MAX_DEPTH} levels"
            stack.extend((x, _key(path, str(k)), depth + 1) for k, x in reversed(list(v.items())))
        elif isinstance(v, list):
            if depth >= MAX_DEPTH:
                return path, f"value nested {depth + 1} levels deep is not allowed: expected at most {MAX_DEPTH} levels"
            stack.extend((x, f"{path}[{i}]", depth + 1) for i, x in reversed(list(enumerate(v))))
        elif isinstance(v, HugeInteger) or (isinstance(v, int) and not isinstance(v, bool) and abs(v) > MAX_INTEGER):
            return path, (f"value {shown(v)} is not allowed: expected an integer between -{MAX_INTEGER} and "
                          f"{MAX_INTEGER}")
        elif isinstance(v, float) and not (math.isfinite(v) and abs(v) <= MAX_MAGNITUDE):
            return path, f"value {shown(v)} is not allowed: expected a finite number of magnitude at most {MAX_MAGNITUDE:g}"
        elif not (v is None or isinstance(v, (str, int, float))):  # bool is an int
            return path, f"value {shown(v)} is not allowed: expected a JSON value"
    return None


def _schema(value: Any, schema: dict[str, Any], root: dict[str, Any], path: str) -> tuple[str, str] | None:
    while "$ref" in schema:
        schema = root["$defs"][schema["$ref"].split("/")[-1]]

    def bad() -> tuple[str, str]:
        return path, f"value {shown(value)} is not allowed: expected {allowed(schema, root)}"

    if "type" in schema:
        types = [schema["type"]] if isinstance(schema["type"], str) else schema["type"]
        if not any(_IS_TYPE[t](value) for t in types):
            return bad()
    if "const" in schema and not (value == schema["const"] and type(value) is type(schema["const"])):
        return bad()
    if "enum" in schema and not any(value == e and type(value) is type(e) for e in schema["enum"]):
        return bad()
    if isinstance(value, HugeInteger) and ("minimum" in schema or "maximum" in schema):
        return bad()
    if isinstance(value, (int, float)) and not isinstance(value, bool) and (
            ("minimum" in schema and value < schema["minimum"]) or ("maximum" in schema and value > schema["maximum"])):
        return bad()
    if isinstance(value, dict):
        props = schema.get("properties", {})
        for k in schema.get("required", ()):
            if k not in value:
                sub = props.get(k, {})
                return _key(path, k), f"missing: expected {allowed(sub, root) if sub else 'this key'}"
        extra = schema.get("additionalProperties", True)
        for k, v in value.items():
            if k in props:
                found = _schema(v, props[k], root, _key(path, k))
            elif extra is False:
                return _key(path, str(k)), f"unknown key: expected one of {', '.join(props)}"
            elif isinstance(extra, dict):
                found = _schema(v, extra, root, _key(path, str(k)))
            else:
                found = None
            if found:
                return found
    if isinstance(value, list):
        if ("minItems" in schema and len(value) < schema["minItems"]) or \
                ("maxItems" in schema and len(value) > schema["maxItems"]):
            return bad()
        pre = schema.get("prefixItems", [])
        for i, v in enumerate(value):
            sub = pre[i] if i < len(pre) else schema.get("items")
            if sub is not None:
                found = _schema(v, sub, root, f"{path}[{i}]")
                if found:
                    return found
    return None


def first_violation(value: Any, schema: dict[str, Any]) -> tuple[str, str] | None:
    """``(key path, message)`` of the first place where ``value`` breaks ``schema`` or the limits
    every document obeys; None when it is valid.  (The schema's own recursion follows the schema,
    not the data, so it is bounded whatever the document's nesting.)  The key path is dotted with list
    indices (``reactions.Rx.GF_Dy.mean``, ``towers[0].index``; "" for the whole document)."""
    return _schema(value, schema, schema, "") or _limits(value)


def check(value: Any, schema: dict[str, Any], source: str | None) -> None:
    """:class:`CaseError` (one line: file, key path, value, what is allowed) at the first
    violation of :func:`first_violation`."""
    found = first_violation(value, schema)
    if found is not None:
        path, message = found
        raise CaseError(message, file=source, key=path or None)
