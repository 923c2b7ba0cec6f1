"""`linecheck run` of a case with [[wires]] (docs/wires.md "The dynamic run"): the two-wire case of
tests/two_wires.py (a twin phase P at y = 6 m, a ground wire G above the centre) runs in one
correlated wind, exit 0; its JSON carries every tower's attachments, totals (with the bounds of
their peaks) and load trees, follows docs/results.schema.json and reads back byte for byte; the
totals' peaks lie between the largest attachment's and the sum of the attachments'; each load
tree's attachments add up to its total; `--load-trees` writes the same trees as CSV (kN); the
options a run of several wires does not take, and `--load-trees` without wires, are refused in
one line (its workbook: tests/frontends/test_excel_wires.py)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core.tower_totals import LOAD_CASES, TOTALS, tower_totals
from linecheck.io.document import RunDocument

from ..conftest import CASES, _result_schema, one_error_line
from ..schema_check import errors
from ..two_wires import DOWNBURST, write_two_wires

COMPONENTS = ("Rx", "Ry", "Rz")


def _invoke(*args):
    return CliRunner(env={"COLUMNS": "250"}).invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def two_run(tmp_path_factory):
    """`run two.toml --json run.json --load-trees trees.csv` (2 realizations of 60 s): the
    console output, the JSON and the CSV text."""
    folder = tmp_path_factory.mktemp("two-run")
    path = write_two_wires(folder)
    r = _invoke("run", path, "--json", folder / "run.json", "--load-trees", folder / "trees.csv", "--jobs", "1")
    assert r.exit_code == 0, r.output
    return (r.output, json.loads((folder / "run.json").read_text(encoding="utf-8")),
            (folder / "trees.csv").read_text(encoding="utf-8"), folder)


def test_the_run_document_has_every_block_and_follows_the_schema(two_run):
    _, doc, _, _ = two_run
    assert errors(doc, _result_schema()) == []
    assert [w["name"] for w in doc["wires"]] == ["P", "G"] and doc["wires"][0]["bundle"] == 2
    assert doc["wires"][0]["field_offset"] == {"y": 6.0, "z": 30.0 - 3.5}
    assert doc["wires"][0]["burn_in"]["seconds"] > 0
    assert [t["name"] for t in doc["towers"]] == ["T1", "T2", "T3", "T4"]
    for t in doc["towers"]:
        assert set(t) >= {"index", "name", "station", "type", "reactions", "attachments", "totals", "load_trees"}
        assert [a["wire"] for a in t["attachments"]] == ["P", "G"]
        assert all(set(a["reactions"]) == set(COMPONENTS) for a in t["attachments"])
        assert list(t["totals"]) == list(TOTALS) and list(t["load_trees"]) == list(LOAD_CASES)
        for name, x in t["totals"].items():
            assert {"peak_dynamic", "GF_Dy", "Cont_R", "peak_sum", "peak_largest", "peak_to_sum", "peak_to_largest"} <= set(x)
            assert x["peak_dynamic"]["gumbel"]["design"] is not None and x["peak_sum"]["gumbel"] is not None, name
        # the tower's reactions are its totals' forces (a reader of single-wire results sees the whole load)
        for r, f in zip(COMPONENTS, ("Fx", "Fy", "Fz")):
            assert t["reactions"][r]["peak_dynamic"] == t["totals"][f]["peak_dynamic"]
    assert doc["reactions"] == doc["towers"][1]["reactions"]  # the tower of interest, T2
    back = RunDocument.from_json(doc)
    assert back.has_wires and json.dumps(back.to_json()) == json.dumps(doc)


def test_each_total_peaks_between_the_largest_attachment_and_the_sum(two_run):
    """Per tower, the mean peak of each total is at most the mean sum of the attachments' peaks
    (the triangle inequality in each sample) and, the two wires pushing the same way, at least
    the largest attachment's.  Torsion: the ground wire at y = 0 has no arm, so the total is the
    phase's own (ratios 1).  What the correlation saves at T2: the transverse force 1.1 %, the
    overturning moment 1.5 %, the longitudinal force 13.5 % (2 realizations)."""
    _, doc, _, _ = two_run
    for t in doc["towers"]:
        for name, x in t["totals"].items():
            peak, top, big = x["peak_dynamic"]["mean"], x["peak_sum"]["mean"], x["peak_largest"]["mean"]
            assert big * (1 - 1e-12) <= peak <= top * (1 + 1e-12), (t["name"], name)
            assert x["peak_to_sum"] == pytest.approx(peak / top, rel=1e-12)
            assert x["peak_to_largest"] == pytest.approx(peak / big, rel=1e-12)
        assert t["totals"]["Mz"]["peak_to_sum"] == t["totals"]["Mz"]["peak_to_largest"] == 1.0
    fy = doc["towers"][1]["totals"]["Fy"]
    assert 0.95 < fy["peak_to_sum"] < 1.0 and fy["peak_to_largest"] > 1.1


def test_the_load_trees_add_up_to_their_totals(two_run):
    """Every load tree's attachments (means over the realizations) add up to the tree's value:
    the forces by their sum, the moments by tower_totals at the attachments' points (the JSON's y,
    z); and min_vertical's F_z is at most the F_z of every other case's tree (the least in each
    realization, so in the mean)."""
    _, doc, _, _ = two_run
    for t in doc["towers"]:
        y = np.array([[a["y"] for a in t["attachments"]]])
        z = np.array([[a["z"] for a in t["attachments"]]])
        for case, tree in t["load_trees"].items():
            assert tree["total"] == LOAD_CASES[case][0]
            assert [a["wire"] for a in tree["attachments"]] == ["P", "G"]
            loads = np.array([[[a[c] for c in COMPONENTS] for a in tree["attachments"]]])
            six = tower_totals(loads, y, z)[0]
            k = TOTALS.index(tree["total"])
            assert six[k] == pytest.approx(tree["value"], rel=1e-9, abs=1e-6), (t["name"], case)
            assert all(a[f"{c}_std"] >= 0 for a in tree["attachments"] for c in COMPONENTS)
        fz = {case: sum(a["Rz"] for a in tree["attachments"]) for case, tree in t["load_trees"].items()}
        assert all(fz["min_vertical"] <= v + 1e-9 for v in fz.values())


def test_the_csv_is_the_json_load_trees_in_kn(two_run):
    _, doc, text, _ = two_run
    lines = text.splitlines()
    assert lines[0].startswith("# linecheck load trees, case two") and "kN" in lines[0]
    assert "vertical downward positive" in lines[0] and "transverse positive toward +y" in lines[0]
    assert "longitudinal positive toward +x" in lines[0]
    rows = list(csv.reader(lines[1:]))
    assert rows[0] == ["structure", "load_case", "attachment", "vertical", "transverse", "longitudinal"]
    expected = [(t["name"], case, a["wire"], a["Rz"] / 1e3, a["Ry"] / 1e3, a["Rx"] / 1e3)
                for t in doc["towers"] for case, tree in t["load_trees"].items() for a in tree["attachments"]]
    assert len(rows) - 1 == len(expected) == 4 * 5 * 2
    for row, want in zip(rows[1:], expected):
        assert tuple(row[:3]) == want[:3]
        np.testing.assert_allclose([float(v) for v in row[3:]], want[3:], atol=5.0001e-4)


def test_the_console_report(two_run):
    out, _, _, _ = two_run
    assert "tower totals at tower 2 (T2)" in out and "load trees at tower 2 (T2)" in out
    assert "attachments at tower 2 (T2)" in out
    assert "correlation at tower 2 (T2): each total's peak is below the sum of its attachments' peaks by Fx" in out
    assert "wrote" in out and "trees.csv" in out


def test_a_downburst_runs_without_burn_in(tmp_path):
    path = write_two_wires(tmp_path, wind=DOWNBURST)
    out = tmp_path / "db.json"
    r = _invoke("run", path, "--json", out, "-n", "1", "--jobs", "1")
    assert r.exit_code == 0, r.output
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["wind"] == "downburst" and all(w["burn_in"] is None for w in doc["wires"])
    assert errors(doc, _result_schema()) == []
    assert "burn-in discarded" not in r.output


def test_load_trees_without_wires_is_refused(tmp_path):
    case = CASES / "paper" / "case09-single.toml"
    out = tmp_path / "trees.csv"
    line = one_error_line(_invoke("run", case, "--load-trees", out))
    assert line == (f"error: {case}: --load-trees: the case has no [[wires]]: load trees are the coincident loads of "
                    "every wire a tower carries (docs/wires.md); describe the tower's wires with [[wires]] and "
                    "[[tower_types]]")
    assert not out.exists()


@pytest.mark.parametrize(("args", "option"), [
    (["--until", "0.05"], "--until"),
    (["--models", "all"], "--models"),
    (["--full-histories"], "--full-histories"),
])
def test_options_a_run_of_several_wires_does_not_take(tmp_path, args, option):
    path = write_two_wires(tmp_path)
    line = one_error_line(_invoke("run", path, *(a.format(tmp=tmp_path) for a in args)))
    assert line.startswith(f"error: {path}: {option}: a run of a case with several wires writes the console report, "
                           "--json, --load-trees and --excel; ")
    assert list(tmp_path.iterdir()) == [path]


def test_outputs_are_checked_before_the_run(tmp_path):
    """--load-trees onto the case file, or onto the --json path: one line, nothing run."""
    path = write_two_wires(tmp_path)
    text = path.read_text(encoding="utf-8")
    assert one_error_line(_invoke("run", path, "--load-trees", path)).startswith("error: ")
    assert path.read_text(encoding="utf-8") == text
    same = tmp_path / "out"
    assert one_error_line(_invoke("run", path, "--json", same, "--load-trees", same)).startswith("error: ")
    assert not same.exists()
