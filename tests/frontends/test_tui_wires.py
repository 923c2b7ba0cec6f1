"""Pilot tests of the TUI on a case with ``[[wires]]`` (docs/tui.md "Load trees"): `r` runs the
two-wire case of tests/two_wires.py as `linecheck run` does (service.run_wires: the same document),
the Results show the Summary (the totals' forces), Contributions and Load trees only; on Load trees
↑/↓ pick the tower and ←/→ the load case, and the tables show the JSON's load trees and totals in
kN; `x` writes the workbook with its "Load trees" sheet; `m` (the model spread) is refused with a
notification.  Every wait ends on a message or a state change (tests/frontends/test_tui.py)."""

from __future__ import annotations

from pathlib import Path

from textual.widgets import DataTable, Input, Static, TabbedContent

from linecheck import service
from linecheck.core.case import load_case
from linecheck.core.tower_totals import LOAD_CASES, TOTALS
from linecheck.io.wires_document import wires_run_document
from linecheck.tui import messages as msg
from linecheck.tui.app import LinecheckApp
from linecheck.tui.commands import LinecheckCommands
from linecheck.tui.screens.prompt import PathPrompt
from linecheck.tui.widgets.results import ResultsView
from linecheck.tui.widgets.trees import TreeShown

from ..two_wires import write_two_wires
from .test_tui import SIZE, Recorder, generous_pilot, of_type, wait_for  # noqa: F401  (generous_pilot: autouse)

KN = 1e-3


def kn(v: float) -> str:
    return f"{v * KN:.3f}"


def table_rows(table: DataTable) -> list[list[str]]:
    return [[str(c) for c in table.get_row_at(i)] for i in range(table.row_count)]


def expected_tree(doc: dict, index: int, case: str) -> list[list[str]]:
    """The tree table of tower ``index`` (1-based), written out from the JSON independently of the TUI."""
    tree = doc["towers"][index - 1]["load_trees"][case]
    rows = [[a["wire"], *(x for r in ("Rz", "Ry", "Rx") for x in (kn(a[r]), kn(a[f"{r}_std"])))]
            for a in tree["attachments"]]
    sums = [sum(a[r] for a in tree["attachments"]) for r in ("Rz", "Ry", "Rx")]
    return rows + [["all wires", kn(sums[0]), "", kn(sums[1]), "", kn(sums[2]), ""]]


def shown(messages: Recorder, tower: int, case: str):
    return lambda: any(isinstance(m, TreeShown) and (m.tower, m.case) == (tower, case) for m in messages)


async def test_a_run_of_several_wires_shows_its_load_trees(tmp_path: Path) -> None:
    path = write_two_wires(tmp_path)
    case = load_case(path)
    expected = wires_run_document(service.run_wires(case)).to_json()  # what `linecheck run --json` writes
    messages = Recorder()
    app = LinecheckApp([path])
    async with app.run_test(size=SIZE, message_hook=messages) as pilot:
        await wait_for(pilot, lambda: of_type(messages, msg.CaseOpened), "CaseOpened", messages)
        results = app.query_one(ResultsView)
        assert not results.has_tab("res-trees")  # no result yet: the tab is a multi-wire result's

        # ---- `m` (the model spread) is refused; `r` runs every wire in one correlated wind
        await pilot.press("m")
        await pilot.press("r")
        await wait_for(pilot, lambda: of_type(messages, msg.RunFinished) or of_type(messages, msg.RunFailed),
                       "RunFinished", messages)
        assert not of_type(messages, msg.RunFailed)
        assert len(of_type(messages, msg.RunStarted)) == 1
        out = of_type(messages, msg.RunFinished)[-1].output
        assert out.has_wires and out.modes is None and out.wind is None
        doc = out.doc.to_json()
        assert doc["towers"] == expected["towers"] and doc["reactions"] == expected["reactions"]
        stages = {m.stage for m in of_type(messages, msg.RunProgress)}
        assert {"wind", "steps 2-3: dynamics"} <= stages and any(s.endswith(", wire G") for s in stages)

        # ---- Results: the summary is the totals' forces at the tower of interest, and says so
        assert app.query_one("#main-tabs", TabbedContent).active == "results"
        title = str(app.query_one("#results-title", Static).render())
        assert title.startswith("two: tower totals of 2 wires at tower 2")
        summary = {r[0]: r for r in table_rows(app.query_one("#summary-table", DataTable))}
        fy = expected["towers"][1]["totals"]["Fy"]["peak_dynamic"]
        assert summary["peak dynamic M+B+R"][3] == f"{kn(fy['mean'])} ± {kn(fy['std'])}"
        assert "Rx, Ry, Rz are the tower totals' forces" in str(app.query_one("#summary-notes", Static).render())

        # ---- only the views of several wires: ] steps Summary -> Contributions -> Load trees -> Summary
        tabs = app.query_one("#results-tabs", TabbedContent)
        seen = [tabs.active]
        for _ in range(3):
            before = tabs.active
            await pilot.press("right_square_bracket")
            await wait_for(pilot, lambda before=before: tabs.active != before, "the next tab", messages)
            seen.append(tabs.active)
        assert seen == ["res-summary", "res-contrib", "res-trees", "res-summary"]
        await pilot.press("left_square_bracket")
        await wait_for(pilot, lambda: tabs.active == "res-trees", "Load trees", messages)
        await wait_for(pilot, lambda: app.focused is app.query_one("#tree-towers"), "the tower list", messages)

        # ---- the tree of the tower of interest, max_transverse; then T3; then max_longitudinal
        await wait_for(pilot, shown(messages, 2, "max_transverse"), "T2 max_transverse", messages)
        tree = app.query_one("#tree-table", DataTable)
        totals = app.query_one("#tree-totals", DataTable)
        assert table_rows(tree) == expected_tree(expected, 2, "max_transverse")
        value = expected["towers"][1]["load_trees"]["max_transverse"]
        line = str(app.query_one("#tree-total", Static).render())
        assert f"Fy = {kn(value['value'])} ± {kn(value['value_std'])} kN" in line
        await pilot.press("down")
        await wait_for(pilot, shown(messages, 3, "max_transverse"), "T3 max_transverse", messages)
        assert table_rows(tree) == expected_tree(expected, 3, "max_transverse")
        await pilot.press("right")
        await wait_for(pilot, shown(messages, 3, "max_longitudinal"), "T3 max_longitudinal", messages)
        assert table_rows(tree) == expected_tree(expected, 3, "max_longitudinal")
        assert "the largest |Fx|" in str(app.query_one("#tree-total", Static).render())
        rows = table_rows(totals)
        assert [r[0] for r in rows] == ["Fx kN", "Fy kN", "Fz kN", "Mx kN m", "My kN m", "Mz kN m"]
        for r, name in zip(rows, TOTALS):
            x = expected["towers"][2]["totals"][name]
            assert r[1] == f"{kn(x['peak_dynamic']['mean'])} ± {kn(x['peak_dynamic']['std'])}"
            assert r[5] == kn(x["peak_sum"]["mean"]) and r[6] == f"{x['peak_to_sum']:.3f}"
        for _ in range(len(LOAD_CASES) - 1):  # ←/→ wrap around the five load cases
            await pilot.press("right")
        await wait_for(pilot, shown(messages, 3, "max_transverse"), "back to max_transverse", messages)

        # ---- the command palette has the view; x writes the workbook with its Load trees sheet
        names = [c.name for c in LinecheckCommands(app.screen)._commands()]
        assert "view: load trees" in names
        xlsx = tmp_path / "two.xlsx"
        await pilot.press("x")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), "the export dialog", messages)
        app.screen.query_one(Input).value = str(xlsx)
        await pilot.press("enter")
        await wait_for(pilot, lambda: any(m.kind == "xlsx" for m in of_type(messages, msg.Exported)), "xlsx", messages)
        import openpyxl

        wb = openpyxl.load_workbook(xlsx)
        assert {"Totals", "Load trees"} <= set(wb.sheetnames)
    assert not of_type(messages, msg.RunFailed)
