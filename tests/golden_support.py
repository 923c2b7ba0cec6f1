"""Golden results: the committed statistics of every shipped case and their comparison.

Shared by ``tools/golden.py`` (write and check from the command line) and
``tests/integration/test_golden.py`` (the same check in the test suite); docs/testing.md, "Golden results".

A golden file ``tests/golden/<folder>-<name>.json`` holds what ``linecheck run CASE -n 2`` computes
for one case (plus one ``--until`` run): the numbers of the run's result document
(:func:`linecheck.io.jsonout.run_document`, its ``to_json()``) without the time histories and
without what is not a number of the analysis (schema version, provenance, strings, flags).  The
document is flattened to (path -> number) pairs; the numbers whose paths differ only by list
indices (``towers[3].Ry.peak_dynamic.mean`` and ``towers[4].Ry.peak_dynamic.mean``) form one
*quantity*, stored as one line ``"towers[].Ry.peak_dynamic.mean": [...]`` in document order.

Comparison (:func:`compare`): a float moves by ``|new - golden| / scale`` and a quantity by the
largest move of its numbers; it fails above :data:`RTOL` (:data:`RTOL_OF` for the one
ill-conditioned diagnostic).  ``scale`` is the largest ``|golden|`` of the quantity's array,
taken over its :func:`scale_group`: the three components of a vector (Rx, Ry, Rz; dx, dy, dz)
and the summary entries of a statistic (mean, std, se, p05/p50/p95, the Gumbel fit, the
interval) share one scale, and ratios and fractions of order one (GF, Cont, damping ratios) have
a scale of at least 1 (:data:`UNIT_SCALE`).  Without that, a reaction that vanishes by symmetry
(Rx at an interior tower: 1e-9 N of rounding noise) or the spread of a statistic that does not
vary (mean_max's std: 0 or 1e-13 N) moves by 100 % of itself on another CPU.  Integers
(realization counts, windows, spans, seeds, the frequency count) must be equal, and a null must
stay a null.  A quantity missing from the new document
fails; one the golden file does not have yet is reported, not failed (the document may grow).

No UI imports besides what ``linecheck run`` itself uses; numbers as the CLI's JSON writes them
(``json`` round-trips a float64 exactly).
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
GOLDEN_DIR = ROOT / "tests" / "golden"

#: Largest accepted move of a quantity, relative to its scale (the largest |golden value| of its
#: scale group, see :func:`scales`).  float64 rounds at 1.1e-16 per operation, and a BLAS kernel
#: or CPU that orders its sums differently moves single operations by that much; the static
#: solve (Newton, stopped at 1e-8 of the displacements but converged far below it), the
#: eigen-solutions and the dynamics' conditioning amplify it.  Measured on the paper cases
#: between OpenBLAS core types (SkylakeX, Haswell, Prescott): peaks, means and r.m.s. move by at
#: most 3e-11, any quantity by at most 2e-10 (Cont_R's 95 % interval, t = 12.7 times a spread of
#: two realizations); the numpy step loop reproduces the compiled one bit for bit.  1e-9 keeps
#: a margin of 5x over the worst and ~40x over peaks, means and r.m.s., while a real change of the
#: physics (a load, a damping term, a statistic) moves the results by 1e-6 or far more.  Not
#: held across CPUs today: the second-order tension's float32 product P W (~1e-7 of the
#: reactions, the examples) and the ring-jet's adaptive path integration (docs/testing.md).
RTOL = 1e-9

#: Realizations of every golden run (``linecheck run CASE -n 2``; seeds from the case files).
REALIZATIONS = 2

#: Top-level blocks that are not numbers of the analysis: the layout's version, the time
#: histories (large; their extremes are the peaks already compared) and the run's provenance
#: (versions, host, timestamps, paths).
DROP_TOP = frozenset({"schema_version", "time_histories", "provenance"})
#: Keys dropped wherever they appear: metadata, never a result, and the Cont_R flag (a string, or
#: null, derived from Cont_R's interval, which is compared).
DROP_ANY = frozenset({"provenance", "dynamic_analysis", "timestamp", "created", "version", "versions", "linecheck_version",
                      "elapsed", "elapsed_s", "wall_time", "host", "path", "file", "files"})

_INDEX = re.compile(r"\[\d+\]")

#: The components of one vector share a scale: a component that vanishes by symmetry (Rx at an
#: interior tower, Rz of a level single span, dx at mid-span) holds rounding noise only
#: (~1e-12 N), which another BLAS changes by 100 % of itself but by 1e-16 of the reaction.
_COMPONENT = re.compile(r"\b(R|d)[xyz]\b")
#: The summary of one statistic over realizations shares a scale: a spread (std, se, the Gumbel
#: scale, the interval's half-width) is rounded as the values it spreads are (mean_max does not
#: vary between realizations: its std is 0 or 1e-13 N, by rounding alone).
_SUMMARY = re.compile(r"\.(mean|std|se|p05|p50|p95|ci\[\]|gumbel\.(location|scale|design))$")
#: Dimensionless quantities of order one (ratios, fractions, damping ratios): their scale is at
#: least 1, so a Cont_M of 3e-12 (a vanishing mean over its peak) or the damping ratio 4e-8 of an
#: almost undamped mode is compared as the fraction of 1 it is.
UNIT_SCALE = frozenset({"GF_Dy", "GF_QS", "GF_ASCE74", "Cont_M", "Cont_BG", "Cont_R", "peak_normalised",
                        "peak_normalised_total", "ppcc", "ratio", "zeta", "zeta_a", "peak_factor",
                        "background_factor", "resonant_factor", "achieved", "target"})
#: Quantities with a looser bound, and why.  burn_in.required is the burn-in [s] a record would need
#: to become stationary, ~ 1/(zeta omega): with damping = "paper" zeta is 1e-6..4e-8, the real part
#: of an eigenvalue 1e6..1e8 times smaller than its modulus, so the eigen-solver's rounding
#: (1e-16 of the modulus) moves it by 1e-16/zeta relative: measured up to 2.3e-8 between OpenBLAS
#: core types.  It is reported, not used, there (the burn-in used is 0 s, the paper's record from
#: rest); where a burn-in is used (quasi-steady damping, zeta ~ 1e-2) it is as well conditioned as
#: the rest and burn_in.seconds, held to RTOL, guards it.
RTOL_OF = {"burn_in.required": 1e-6}


@dataclass(frozen=True)
class GoldenCase:
    """One golden run: a case file and the ``linecheck run`` options that make it."""

    name: str  #: file stem under tests/golden, "<folder>-<case>" (+ "-until")
    case: str  #: case file, relative to the repository root
    realizations: int = REALIZATIONS
    until: str | None = None  #: ``--until`` target, e.g. "5%"
    max_realizations: int | None = None  #: ``--max-realizations`` with ``until``

    @property
    def path(self) -> Path:
        return GOLDEN_DIR / f"{self.name}.json"

    def options(self) -> dict[str, Any]:
        return {"case": self.case, "realizations": self.realizations, "until": self.until,
                "max_realizations": self.max_realizations}

    def command(self) -> str:
        """The equivalent command line."""
        cmd = f"linecheck run {self.case} -n {self.realizations}"
        if self.until is not None:
            cmd += f" --until {self.until} --max-realizations {self.max_realizations}"
        return cmd

    @classmethod
    def from_options(cls, name: str, options: dict[str, Any]) -> GoldenCase:
        return cls(name, options["case"], options["realizations"], options.get("until"),
                   options.get("max_realizations"))


#: The ``--until`` run: a small paper case (single span, downburst) to 10 %, capped at 20: it adds
#: realizations 2 -> 8 and stops on the target (achieved 9.1 %), not on the cap, so its count,
#: compared exactly, is the stopping rule's result.
UNTIL_CASE = GoldenCase("paper-case07-single-until", "cases/paper/case07-single.toml", REALIZATIONS,
                        until="10%", max_realizations=20)


def _one_wire(path: Path) -> bool:
    """Whether the case file ``path`` is a single-wire case (no ``[[wires]]``): the runs whose
    result document the golden files record."""
    return "wires" not in tomllib.loads(path.read_text(encoding="utf-8"))


def golden_cases() -> list[GoldenCase]:
    """Every golden run: the paper's 24 cases, the single-wire examples (the 12-span section
    among them; an example with ``[[wires]]`` is not a single-wire run) and :data:`UNTIL_CASE`,
    sorted by name."""
    out = [GoldenCase(f"{folder}-{p.stem}", p.relative_to(ROOT).as_posix())
           for folder in ("paper", "examples") for p in sorted((ROOT / "cases" / folder).glob("*.toml"))
           if _one_wire(p)]
    out.append(UNTIL_CASE)
    return sorted(out, key=lambda g: g.name)


# --------------------------------------------------------------------------- running
def run_json(gc: GoldenCase, *, threads: int | None = None) -> dict[str, Any]:
    """The result document (its JSON form) of ``gc`` as ``linecheck run`` computes it: the case's
    seed, the CLI's ``-n`` override, the frequency-domain check of a synoptic case, the CLI's
    default threads (the same bits whatever their number)."""
    from linecheck import service
    from linecheck.batch.executors import default_jobs
    from linecheck.cli.run_cmd import override
    from linecheck.cli.stats_view import parse_until
    from linecheck.core.case import load_case
    from linecheck.io.jsonout import run_document

    case = override(load_case(ROOT / gc.case), gc.realizations, None)
    n_threads = default_jobs() if threads is None else threads
    if gc.until is not None:
        res = service.run_until(case, parse_until(gc.until), max_realizations=gc.max_realizations or 1000,
                                spectral_check=True, threads=n_threads)
    else:
        res = service.run_case(case, spectral_check=True, threads=n_threads)
    return run_document(res).to_json()


# --------------------------------------------------------------------------- flattening
Number = int | float | None


def flatten(doc: Any) -> list[tuple[str, Number]]:
    """(path, value) of every number and null of a result document, in document order.

    Paths read ``towers[3].Ry.peak_dynamic.gumbel.design``; strings and booleans are dropped,
    and so are :data:`DROP_TOP` and :data:`DROP_ANY`.
    """
    out: list[tuple[str, Number]] = []

    def walk(x: Any, path: str) -> None:
        if isinstance(x, dict):
            for k, v in x.items():
                if k in DROP_ANY or (not path and k in DROP_TOP):
                    continue
                walk(v, f"{path}.{k}" if path else str(k))
        elif isinstance(x, (list, tuple)):
            for i, v in enumerate(x):
                walk(v, f"{path}[{i}]")
        elif x is None or (isinstance(x, (int, float)) and not isinstance(x, bool)):
            out.append((path, x))

    walk(doc, "")
    return out


def quantity_of(path: str) -> str:
    """The quantity a path belongs to: the path with its list indices removed."""
    return _INDEX.sub("[]", path)


def quantities(doc: Any) -> dict[str, list[tuple[str, Number]]]:
    """The document's numbers grouped by quantity, each a list of (path, value) in document order."""
    out: dict[str, list[tuple[str, Number]]] = {}
    for path, v in flatten(doc):
        out.setdefault(quantity_of(path), []).append((path, v))
    return out


def scale_group(quantity: str) -> str:
    """The quantities that share one scale: the components of a vector and the summary entries of
    a statistic (``towers[].reactions.R*.peak_dynamic.<stat>``)."""
    return _SUMMARY.sub(".<stat>", _COMPONENT.sub(r"\1*", quantity))


def unit_scale(quantity: str) -> bool:
    """Whether ``quantity`` is one of :data:`UNIT_SCALE` (its name, or its statistic's name)."""
    parts = _SUMMARY.sub("", quantity).replace("[]", "").split(".")
    return parts[-1] in UNIT_SCALE or quantity.replace("[]", "").split(".")[-1] in UNIT_SCALE


def scales(golden_values: dict[str, Any]) -> dict[str, float]:
    """The scale of every quantity's relative change: the largest |golden value| of its
    :func:`scale_group`, at least 1 for :data:`UNIT_SCALE` quantities (0: every value is 0)."""
    group: dict[str, float] = {}
    for q, v in golden_values.items():
        vals = v if isinstance(v, list) else [v]
        m = max((abs(x) for x in vals if x is not None), default=0.0)
        g = scale_group(q)
        group[g] = max(group.get(g, 0.0), m)
    return {q: max(group[scale_group(q)], 1.0 if unit_scale(q) else 0.0) for q in golden_values}


def record(gc: GoldenCase, doc: dict[str, Any], *, code: str | None = None) -> dict[str, Any]:
    """The golden file's content: the run's options, the code it came from, and per quantity its
    value (no list index in the path) or its values in document order."""
    values: dict[str, Any] = {}
    for q, items in quantities(doc).items():
        values[q] = items[0][1] if q == items[0][0] else [v for _, v in items]
    return {"command": gc.command(), "options": gc.options(), "code": code, "values": values}


def render(rec: dict[str, Any]) -> str:
    """The golden file's text: one quantity per line (readable diffs), floats as ``json`` writes
    them (shortest repr, exact)."""
    head = {k: v for k, v in rec.items() if k != "values"}
    lines = [f"  {json.dumps(k)}: {json.dumps(v, allow_nan=False)}" for k, v in head.items()]
    vals = [f"    {json.dumps(k)}: {json.dumps(v, allow_nan=False)}" for k, v in sorted(rec["values"].items())]
    return "{\n" + ",\n".join(lines) + ',\n  "values": {\n' + ",\n".join(vals) + "\n  }\n}\n"


def load(path: Path) -> tuple[GoldenCase, dict[str, Any]]:
    rec = json.loads(path.read_text(encoding="utf-8"))
    return GoldenCase.from_options(path.stem, rec["options"]), rec


def golden_files() -> list[Path]:
    return sorted(GOLDEN_DIR.glob("*.json"))


# --------------------------------------------------------------------------- comparison
@dataclass
class Move:
    """The largest move of one quantity."""

    quantity: str
    change: float  #: relative to the largest |golden| of the quantity (inf: a null or an integer changed)
    path: str  #: where the largest move is
    golden: Number
    new: Number
    exact: bool = False  #: an integer quantity (compared exactly)
    rtol: float = RTOL  #: its bound (:data:`RTOL`, or :data:`RTOL_OF`)

    @property
    def failed(self) -> bool:
        return self.change > self.rtol

    def text(self) -> str:
        rel = "exact count" if self.exact else f"relative change {self.change:.3g}"
        return f"{self.quantity}: {self.path} golden {self.golden!r} now {self.new!r} ({rel})"


@dataclass
class Comparison:
    """Every quantity's move between a golden record and a recomputed document."""

    name: str
    rtol: float
    moves: list[Move] = field(default_factory=list)  #: quantities that moved at all, largest first
    missing: list[str] = field(default_factory=list)  #: golden quantities the document lost
    added: list[str] = field(default_factory=list)  #: quantities the golden file does not have
    n_quantities: int = 0

    @property
    def failures(self) -> list[Move]:
        return [m for m in self.moves if m.failed]

    @property
    def ok(self) -> bool:
        return not self.failures and not self.missing

    @property
    def largest(self) -> Move | None:
        return self.moves[0] if self.moves else None

    def report(self, limit: int = 20) -> str:
        """The failures, largest first, one line each (quantity, path, both values, relative
        change), at most ``limit`` of them, then the quantities the document lost."""
        bad = self.failures
        lines = [f"{self.name}: {m.text()}" + ("" if m.exact else f" > {m.rtol:g}") for m in bad[:limit]]
        if len(bad) > limit:
            lines.append(f"{self.name}: ... and {len(bad) - limit} more quantities above their bound "
                         "(python tools/golden.py -v lists every move)")
        lines += [f"{self.name}: quantity {q} missing from the recomputed document" for q in self.missing]
        return "\n".join(lines)


def _is_int(v: Number) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def compare_values(q: str, paths: list[str], old: list[Number], new: list[Number], scale: float) -> Move | None:
    """The largest move of quantity ``q`` relative to ``scale`` (None when nothing moved)."""
    if len(old) != len(new):
        return Move(q, math.inf, f"{q} ({len(old)} golden values, {len(new)} now)", len(old), len(new), exact=True)
    best: Move | None = None
    # integers: counts (realizations, windows, the until run's count), compared exactly
    for p, a, b in zip(paths, old, new):
        if (_is_int(a) or _is_int(b)) and a != b:
            return Move(q, math.inf, p, a, b, exact=True)
        if (a is None) != (b is None):
            return Move(q, math.inf, p, a, b)
    if scale == 0.0:  # every golden value is 0: relative to what is there now
        scale = max((abs(b) for b in new if b is not None), default=0.0)
    for p, a, b in zip(paths, old, new):
        if a is None or a == b:
            continue
        change = abs(b - a) / scale if scale > 0 else math.inf
        if best is None or change > best.change:
            best = Move(q, change, p, a, b)
    return best


def compare(name: str, golden_values: dict[str, Any], doc: dict[str, Any], rtol: float = RTOL) -> Comparison:
    """Compare a golden record's ``values`` with a recomputed document."""
    cmp = Comparison(name, rtol)
    now = quantities(doc)
    scale = scales(golden_values)
    cmp.n_quantities = len(golden_values)
    for q, gold in golden_values.items():
        if q not in now:
            cmp.missing.append(q)
            continue
        items = now[q]
        old = gold if isinstance(gold, list) and q != items[0][0] else [gold]
        m = compare_values(q, [p for p, _ in items], old, [v for _, v in items], scale[q])
        if m is not None:
            m.rtol = max(RTOL_OF.get(q, rtol), rtol)
            cmp.moves.append(m)
    cmp.added = [q for q in now if q not in golden_values]
    cmp.moves.sort(key=lambda m: m.change, reverse=True)
    return cmp
