"""Golden results: every shipped case recomputed against its committed statistics.

One test per file under tests/golden (``linecheck run CASE -n 2`` of the paper cases and the
examples, and one ``--until`` run), each within :data:`golden_support.RTOL` of its scale
(docs/testing.md, "Golden results"; the comparison in tests/golden_support.py).  A move above
it fails with the quantity, the path, both values and the relative change; if the move is
intended, regenerate with ``python tools/golden.py --write`` and explain it in the commit.
"""

from __future__ import annotations

import math

import pytest

from .. import golden_support as gs

pytestmark = pytest.mark.numerics  # repeated under another OpenBLAS core type by .ci/run

FILES = gs.golden_files()


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_golden(path):
    gc, rec = gs.load(path)
    doc = gs.run_json(gc)
    cmp = gs.compare(gc.name, rec["values"], doc)
    if not cmp.ok:
        pytest.fail(f"{gc.command()} moved away from {path.name} (code {rec.get('code')}); if intended, regenerate "
                    "with `python tools/golden.py --write` and explain the move in the commit:\n" + cmp.report(),
                    pytrace=False)


def test_every_case_has_a_golden_file():
    """The golden set is the paper cases, the examples and the --until run, no more, no less."""
    assert {g.name for g in gs.golden_cases()} == {p.stem for p in FILES}, \
        "python tools/golden.py --write regenerates the set"
    assert any(g.until for g in gs.golden_cases()) and "examples-section-12span" in {p.stem for p in FILES}


# --------------------------------------------------------------------------- the comparison itself
def _doc(**changes):
    """A small result-like document: a tower list, a vanishing component, a non-varying statistic."""
    doc = {"schema_version": 2, "case": "x", "realizations": 2,
           "towers": [{"index": i + 1, "name": f"T{i + 1}",
                       "reactions": {"Rx": {"mean_max": {"mean": 1e-9 * i, "std": 0.0}},
                                     "Ry": {"mean_max": {"mean": 1000.0 * (i + 1), "std": 0.0},
                                            "Cont_R": {"mean": 0.2, "std": 0.01, "ci": [0.1, 0.3]},
                                            "dynamic_analysis": "recommended"}}} for i in range(3)],
           "GF": None, "time_histories": {"Rx": [1.0, 2.0]}, "burn_in": {"required": 2.0e7, "zeta": 4e-8}}
    for path, value in changes.items():
        *keys, last = path.split("/")
        d = doc
        for k in keys:
            d = d[int(k)] if isinstance(d, list) else d[k]
        d[int(last) if isinstance(d, list) else last] = value
    return doc


def _values(doc):
    return gs.record(gs.GoldenCase("x", "cases/x.toml"), doc)["values"]


def test_flatten_keeps_numbers_of_the_analysis_only():
    doc = _doc()
    doc["provenance"] = {"linecheck": "0.1.0", "created": 1733000000.0, "numpy": [2, 4, 6]}
    values = _values(doc)
    assert "towers[].reactions.Ry.mean_max.mean" in values and values["GF"] is None
    assert values["towers[].reactions.Ry.mean_max.mean"] == [1000.0, 2000.0, 3000.0]
    assert values["towers[].reactions.Ry.Cont_R.ci[]"] == [0.1, 0.3] * 3
    assert not [q for q in values if q.startswith(("provenance", "time_histories", "schema_version"))]
    assert not [q for q in values if "name" in q or "dynamic_analysis" in q]


def test_rounding_noise_passes_and_a_real_move_fails():
    gold = _values(_doc())
    noise = _doc(**{"towers/1/reactions/Rx/mean_max/mean": 1.3e-9,  # a vanishing component, 30 % of itself
                    "towers/2/reactions/Ry/mean_max/std": 4e-13,  # a spread of a value that does not vary
                    "towers/0/reactions/Ry/mean_max/mean": 1000.0 * (1 + 1e-12),
                    "burn_in/zeta": 4.0000001e-8, "burn_in/required": 2.0e7 * (1 + 1e-7),
                    "provenance": {"created": 2.0}})
    cmp = gs.compare("x", gold, noise)
    assert cmp.ok, cmp.report()
    assert len(cmp.moves) == 5 and all(m.change < gs.RTOL for m in cmp.moves if m.quantity != "burn_in.required")
    assert not gs.compare("x", gold, _doc(**{"burn_in/required": 2.0e7 * (1 + 1e-5)})).ok
    moved = _doc(**{"towers/2/reactions/Ry/mean_max/mean": 3000.0 * (1 + 1e-6)})
    cmp = gs.compare("x", gold, moved)
    assert not cmp.ok
    (m,) = cmp.failures
    assert m.quantity == "towers[].reactions.Ry.mean_max.mean" and m.path == "towers[2].reactions.Ry.mean_max.mean"
    assert math.isclose(m.change, 1e-6, rel_tol=1e-6)
    text = cmp.report()
    assert "towers[].reactions.Ry.mean_max.mean: towers[2].reactions.Ry.mean_max.mean golden 3000.0 now 3000.00299" in text
    assert "relative change 1e-06" in text


def test_counts_nulls_and_layout_are_exact():
    gold = _values(_doc())
    assert not gs.compare("x", gold, _doc(realizations=3)).ok
    assert not gs.compare("x", gold, _doc(GF=1.5)).ok
    lost = _doc()
    del lost["burn_in"]
    cmp = gs.compare("x", gold, lost)
    assert cmp.missing == ["burn_in.required", "burn_in.zeta"] and not cmp.ok
    grown = _doc()
    grown["spectral"] = {"duration": 600.0}
    cmp = gs.compare("x", gold, grown)
    assert cmp.ok and cmp.added == ["spectral.duration"]
