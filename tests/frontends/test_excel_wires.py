"""The Excel design sheet of a run of several wires (docs/excel.md "Runs of several wires"): `linecheck
run --excel` of the two-wire case of tests/two_wires.py writes a workbook whose "Load trees" sheet
holds, per tower, its attachments and every load case's coincident loads equal to the JSON's load
trees in kN (numbers, the CSV's sign convention stated on the sheet), whose "Totals" sheet holds
every tower's totals equal to the JSON's, whose Summary shows the totals' forces at the tower of
interest with a note saying so; `linecheck export` of the saved JSON writes the same sheets; a
workbook of a single-wire and a multi-wire result keeps the single-wire sheets as they are."""

from __future__ import annotations

import json

import pytest
from openpyxl import load_workbook
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core.tower_totals import LOAD_CASES, TOTALS
from linecheck.excel.wires_sheets import ATTACHMENT_HEADERS, TOTALS_COLUMNS, TREE_HEADERS

from ..two_wires import write_two_wires

KN = 1e-3
COMPONENTS = (("Rz", 7), ("Ry", 9), ("Rx", 11))  # vertical, transverse, longitudinal: the value columns


def _invoke(*args):
    return CliRunner(env={"COLUMNS": "250"}).invoke(app, [str(a) for a in args])


def same(x):
    """Equal as Excel stores it (16 significant digits)."""
    return pytest.approx(x, rel=1e-15, abs=1e-300)


@pytest.fixture(scope="module")
def wired(tmp_path_factory):
    """`run two.toml --json run.json --excel run.xlsx` (2 realizations of 60 s, one thread), then
    `export run.json --excel export.xlsx`: the JSON and the two workbooks' paths."""
    folder = tmp_path_factory.mktemp("two-excel")
    path = write_two_wires(folder)
    r = _invoke("run", path, "--json", folder / "run.json", "--excel", folder / "run.xlsx", "--jobs", "1",
                "--project", "Line 7")
    assert r.exit_code == 0, r.output
    assert f"wrote {folder / 'run.xlsx'}" in " ".join(r.output.split())
    e = _invoke("export", folder / "run.json", "--excel", folder / "export.xlsx", "--project", "Line 7")
    assert e.exit_code == 0, e.output
    return json.loads((folder / "run.json").read_text(encoding="utf-8")), folder / "run.xlsx", folder / "export.xlsx"


def tree_blocks(ws) -> dict:
    """The "Load trees" sheet read back: {tower name: {"attachments": {wire: row cells},
    "trees": {load case: {"total", "value", "value_std", "unit", "loads": {wire: {r: (mean, std)}},
    "sum": {r: value}}}}}, following the blocks as a reader would."""
    blocks: dict = {}
    tower = mode = case = None
    for row in ws.iter_rows(min_row=1, values_only=True):
        a = row[0]
        if isinstance(a, str) and ": tower " in a and ", type " in a:
            tower = a.split(": tower ", 1)[1].split(" ")[1].rstrip(",")
            blocks[tower] = {"attachments": {}, "trees": {}}
            mode = None
            continue
        if tower is None:
            continue
        if a == ATTACHMENT_HEADERS[0]:
            mode = "attachments"
            continue
        if a == TREE_HEADERS[0][0]:
            mode = "trees"
            continue
        if mode == "attachments" and a is not None:
            blocks[tower]["attachments"][a] = row
        elif mode == "trees" and row[5] is not None:
            if a is not None:
                case = a
                blocks[tower]["trees"][case] = {"total": row[1], "value": row[2], "value_std": row[3],
                                                "unit": row[4], "loads": {}, "sum": None}
            tree = blocks[tower]["trees"][case]
            if row[5] == "all wires":
                tree["sum"] = {r: row[c - 1] for r, c in COMPONENTS}
            else:
                tree["loads"][row[5]] = {r: (row[c - 1], row[c]) for r, c in COMPONENTS}
    return blocks


def test_the_load_trees_sheet_holds_the_json_trees_in_kn(wired):
    doc, book, _ = wired
    wb = load_workbook(book)
    assert wb.sheetnames == ["Summary", "Peaks", "Totals", "Load trees", "two"]
    ws = wb["Load trees"]
    blocks = tree_blocks(ws)
    assert list(blocks) == [t["name"] for t in doc["towers"]]
    for t in doc["towers"]:
        block = blocks[t["name"]]
        assert list(block["trees"]) == list(LOAD_CASES)
        for case, tree in t["load_trees"].items():
            got = block["trees"][case]
            assert got["total"] == tree["total"] == LOAD_CASES[case][0]
            assert got["unit"] == ("kN m" if tree["total"].startswith("M") else "kN")
            assert got["value"] == same(tree["value"] * KN) and got["value_std"] == same(tree["value_std"] * KN)
            assert list(got["loads"]) == [a["wire"] for a in tree["attachments"]] == ["P", "G"]
            for a in tree["attachments"]:
                for r, _ in COMPONENTS:
                    assert got["loads"][a["wire"]][r] == (same(a[r] * KN), same(a[f"{r}_std"] * KN)), (t["name"], case)
            for r, _ in COMPONENTS:  # the wires' sum: the tower's force at that instant
                assert got["sum"][r] == pytest.approx(sum(a[r] for a in tree["attachments"]) * KN, rel=1e-12)
        for a in t["attachments"]:  # the block's attachments: point, support, clamp height, peaks, uplift
            cells = block["attachments"][a["wire"]]
            assert cells[1:6] == (a["kind"], a["support"], a["y"], a["z"], a["height"])
            for k, r in enumerate(("Rx", "Ry", "Rz")):
                assert cells[6 + k] == same(a["reactions"][r]["peak_dynamic"]["mean"] * KN)
            margin = a["uplift"]["margin"] * KN if "uplift" in a else None
            assert cells[9] == (None if margin is None else same(margin))


def test_the_load_trees_sheet_is_numbers_with_its_convention_and_print_area(wired):
    doc, book, _ = wired
    ws = load_workbook(book)["Load trees"]
    texts = [c.value for row in ws.iter_rows() for c in row if isinstance(c.value, str)]
    note = next(x for x in texts if x.startswith("Sign convention"))
    assert "vertical downward positive" in note and "transverse positive toward +y" in note
    assert "longitudinal positive toward +x" in note
    trees = False
    checked = 0
    for row in ws.iter_rows():
        a = row[0].value
        if isinstance(a, str) and ": tower " in a:
            trees = False
        elif a == TREE_HEADERS[0][0]:
            trees = True
        elif trees and row[5].value is not None:  # a wire's row (and the load case's first: its value)
            cells = list(row[6:12]) + (list(row[2:4]) if a is not None else [])
            if row[5].value == "all wires":
                cells = [row[6], row[8], row[10]]
            for c in cells:
                assert isinstance(c.value, float) and c.number_format == "#,##0.000", (c.coordinate, c.value)
                checked += 1
    assert checked == len(doc["towers"]) * len(LOAD_CASES) * (2 * 6 + 2 + 3)
    area = ws.print_area
    assert area.replace("$", "").endswith(f"!A1:L{ws.max_row}"), area
    assert [b.id for b in ws.row_breaks.brk] and len(ws.row_breaks.brk) == len(doc["towers"]) - 1
    assert ws.page_setup.orientation == "landscape" and ws.sheet_properties.pageSetUpPr.fitToPage


def test_the_totals_sheet_holds_every_towers_totals(wired):
    doc, book, _ = wired
    ws = load_workbook(book)["Totals"]
    headers = [ws.cell(row=4, column=c + 1).value for c in range(len(TOTALS_COLUMNS))]
    assert headers == [h for h, _ in TOTALS_COLUMNS]
    rows = [r for r in ws.iter_rows(min_row=5, values_only=True) if r[0] == "two"]
    assert len(rows) == len(doc["towers"]) * len(TOTALS)
    by = {(r[1], r[4]): r for r in rows}
    for t in doc["towers"]:
        for name in TOTALS:
            r, x = by[(t["index"], name)], t["totals"][name]
            assert r[2] == t["name"] + (" *" if t["index"] == doc["tower_of_interest"] else "")
            assert r[3] == t["type"] and r[5] == ("kN m" if name.startswith("M") else "kN")
            pk = x["peak_dynamic"]
            assert r[6] == same(x["mean_max"]["mean"] * KN)
            assert r[7] == same(pk["mean"] * KN) and r[8] == same(pk["std"] * KN)
            assert r[9] == ("**" if x["GF_Dy"]["mean"] is None else same(x["GF_Dy"]["mean"]))
            assert r[10] == same(x["Cont_R"]["mean"])
            assert r[11] == same(pk["gumbel"]["design"] * KN)
            assert r[12] == same(x["peak_dynamic_total"]["gumbel"]["design"] * KN)
            assert r[13] == same(x["peak_sum"]["mean"] * KN) and r[14] == same(x["peak_largest"]["mean"] * KN)
            assert r[15] == same(x["peak_to_sum"]) and r[16] == same(x["peak_to_largest"])


def test_the_summary_shows_the_totals_at_the_tower_of_interest_and_says_so(wired):
    doc, book, _ = wired
    wb = load_workbook(book)
    ws = wb["Summary"]
    rows = {r[7]: r for r in ws.iter_rows(values_only=True) if r[0] == "two" and r[7] in ("Rx", "Ry")}
    assert rows["Ry"][11] == same(doc["reactions"]["Ry"]["peak_dynamic"]["mean"] * KN)
    assert doc["reactions"]["Ry"]["peak_dynamic"] == doc["towers"][1]["totals"]["Fy"]["peak_dynamic"]
    texts = [c.value for row in ws.iter_rows() for c in row if isinstance(c.value, str)]
    assert any(x.startswith("two is a run of 2 wires in one correlated wind: its Rx, Ry, Rz are the tower totals' "
                            "forces Fx, Fy, Fz") and "'Totals' and 'Load trees'" in x for x in texts)
    case = wb["two"]
    texts = [c.value for row in case.iter_rows() for c in row if isinstance(c.value, str)]
    assert case["A1"].value == "two: tower totals of 2 wires at tower 2"
    assert "Section: 4 towers, 2 wires in one correlated wind" in texts
    assert not any("(the case read it from" in x for x in texts)
    assert any(x.startswith("Spectral check: none for a run of several wires") for x in texts)


def test_export_of_the_json_writes_the_same_sheets(wired):
    _, book, exported = wired
    a, b = load_workbook(book), load_workbook(exported)
    assert a.sheetnames == b.sheetnames
    for name in ("Totals", "Load trees", "two"):
        assert [[c.value for c in row] for row in a[name].iter_rows()] == \
               [[c.value for c in row] for row in b[name].iter_rows()], name
    assert a["Load trees"].print_area == b["Load trees"].print_area


def test_a_workbook_of_single_and_multi_wire_results(wired, tmp_path):
    """A single-wire result beside a multi-wire one: the single-wire case keeps its sheet and
    Summary rows (no note on it), the wires' sheets hold only the multi-wire case."""
    from linecheck.excel import load_result_docs, write_workbook

    doc, book, _ = wired
    single = json.loads(json.dumps(doc))
    for key in ("wires",):
        single.pop(key)
    single["case"] = "one"
    for t in single["towers"]:
        for key in ("type", "attachments", "totals", "load_trees"):
            t.pop(key)
    src = tmp_path / "one.json"
    src.write_text(json.dumps(single), encoding="utf-8")
    out = tmp_path / "both.xlsx"
    write_workbook(load_result_docs([src, book.with_name("run.json")]), out)
    wb = load_workbook(out)
    assert wb.sheetnames == ["Summary", "Peaks", "Totals", "Load trees", "one", "two"]
    assert wb["one"]["A1"].value == "one: reactions at tower 2"
    names = {r[0] for r in wb["Totals"].iter_rows(min_row=5, values_only=True) if r[0] in ("one", "two")}
    assert names == {"two"}
    summary = [c.value for row in wb["Summary"].iter_rows() for c in row if isinstance(c.value, str)]
    assert not any(x.startswith("one is a run of") for x in summary)
