"""Pilot tests of the terminal UI (``linecheck tui``): keys in, typed messages and widgets out.

One short synoptic case (20 s, 2 realizations) drives a whole session: open, edit V_ref,
run, check the summary against ``run_to_dict(service.run_case(case))``, switch tabs,
export to xlsx and JSON, pin and compare.  A six-span downburst shows that keys are
handled while it runs, and that ``c`` cancels it.
"""

from __future__ import annotations

import asyncio
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck import service
from linecheck.core.case import case_to_toml, load_case, with_value, with_values
from linecheck.core.errors import CaseError
from linecheck.io.document import RunDocument
from linecheck.io.jsonout import run_to_dict

textual = pytest.importorskip("textual")

from textual.command import CommandList
from textual.widgets import DataTable, Input, Static, TabbedContent

from linecheck.tui import files
from linecheck.tui import messages as msg
from linecheck.tui.app import LinecheckApp
from linecheck.tui.commands import LinecheckCommands
from linecheck.tui.formatting import tower_dicts
from linecheck.tui.plotting import PlotView
from linecheck.tui.screens.confirm import ConfirmScreen
from linecheck.tui.screens.error import ErrorScreen
from linecheck.tui.screens.help import HelpScreen
from linecheck.tui.screens.prompt import PathPrompt
from linecheck.tui.widgets.browser import CaseBrowser

ROOT = Path(__file__).resolve().parents[2]
SIZE = (120, 40)


def write_case(folder: Path, source: str, name: str, **changes) -> Path:
    """A copy of a shipped case with ``changes`` ({"analysis.duration": 20.0, ...})."""
    case = load_case(ROOT / "cases" / "paper" / source)
    case = with_value(case, "name", name)
    for key, value in changes.items():
        case = with_value(case, key, value)
    path = folder / f"{name}.toml"
    path.write_text(case_to_toml(case), encoding="utf-8")
    return path


@pytest.fixture
def short_case(tmp_path: Path) -> Path:
    """Synoptic single span, 20 s, 2 realizations: a run takes well under a second."""
    folder = tmp_path / "cases"
    folder.mkdir()
    return write_case(folder, "case09-single.toml", "short", **{"analysis.duration": 20.0, "analysis.realizations": 2})


# A bound that only guards against a hung test, never a verdict: the waits below end on a
# message or a state change, however busy the machine.  The longest wait (a 20 s synoptic run)
# takes about 1 s on an idle 2-core machine; this whole file took 440 s (12 tests) with both
# cores hogged by tools/stress_tests.sh at load average 14: reaching 600 s in ONE wait means
# the app is stuck, not slow.
HANG_GUARD_S = 600.0


class Recorder(list):
    """``message_hook`` for ``run_test``: keeps every message and wakes the waiters on each one."""

    def __init__(self) -> None:
        super().__init__()
        self.arrived = asyncio.Event()

    def __call__(self, message) -> None:
        self.append(message)
        self.arrived.set()


async def wait_for(pilot, predicate, what: str = "condition", messages: Recorder | None = None) -> None:
    """Wait until ``predicate()`` holds while the app runs.

    Woken by each message reaching the app (``messages``: a :class:`Recorder`) and re-checked
    every 50 ms for state that changes after the last message; plain ``asyncio.sleep``, so no
    waiting for an idle CPU.  The outcome does not depend on the machine's load: only
    :data:`HANG_GUARD_S` (a hung app) ends the wait without the condition.
    """
    loop = asyncio.get_running_loop()
    t0 = loop.time()
    while not predicate():
        if loop.time() - t0 > HANG_GUARD_S:
            raise AssertionError(f"app stuck: nothing after {HANG_GUARD_S:.0f} s waiting for {what}")
        if messages is None:
            await asyncio.sleep(0.05)
            continue
        messages.arrived.clear()
        try:
            await asyncio.wait_for(messages.arrived.wait(), 0.05)
        except TimeoutError:
            pass


@pytest.fixture(autouse=True)
def generous_pilot(monkeypatch) -> None:
    """Textual's Pilot gives each press/pause 30 s to process pending messages, then raises:
    a load-dependent verdict.  Raise it to the hang guard."""
    from textual.pilot import Pilot

    wait = Pilot._wait_for_screen

    async def _wait_for_screen(self, timeout: float = HANG_GUARD_S) -> bool:
        return await wait(self, max(timeout, HANG_GUARD_S))

    monkeypatch.setattr(Pilot, "_wait_for_screen", _wait_for_screen)


def of_type(messages: list, kind: type) -> list:
    return [m for m in messages if isinstance(m, kind)]


async def edit(pilot, app: LinecheckApp, key: str, text: str) -> None:
    """Highlight ``key`` in the parameter table, enter, replace the text, enter."""
    await pilot.press("2")
    table = app.query_one("#params-table", DataTable)
    table.move_cursor(row=table.get_row_index(key))
    await pilot.press("enter")
    await wait_for(pilot, lambda: app.focused is app.query_one("#edit-input", Input), "the editor")
    await pilot.press("end", "ctrl+u", *text)
    await pilot.pause()
    await pilot.press("enter")
    await pilot.pause()


def expected_cell(entry: dict, scale: float, fmt: str) -> str:
    """The summary text of one JSON statistic, written out independently of the TUI code."""
    if entry["mean"] is None:
        return "**"
    return f"{fmt.format(entry['mean'] * scale)} ± {fmt.format(entry['std'] * scale)}"


async def test_session_open_edit_run_tabs_export_compare(short_case: Path, tmp_path: Path) -> None:
    messages = Recorder()
    app = LinecheckApp([short_case.parent])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await pilot.pause()
        # ---- open the case from the browser (the cursor starts on the first case)
        await pilot.press("enter")
        await wait_for(pilot, lambda: of_type(messages, msg.CaseOpened), "CaseOpened", messages)
        assert app.case.name == "short"
        assert app.query_one("#main-tabs", TabbedContent).active == "params"

        # ---- edit V_ref
        await edit(pilot, app, "wind.v_ref", "30")
        changed = of_type(messages, msg.ParameterChanged)
        assert changed and changed[-1].key == "wind.v_ref" and app.case.wind.v_ref == 30.0
        assert "(edited)" in app.sub_title

        # ---- run to completion
        await pilot.press("r")
        await wait_for(pilot, lambda: of_type(messages, msg.RunFinished), "RunFinished", messages)
        assert {m.stage for m in of_type(messages, msg.RunProgress)} >= {"step 1: mean states", "steps 2-3: dynamics"}
        doc = of_type(messages, msg.RunFinished)[-1].output.doc.to_json()  # the TUI reads the typed document
        expected = run_to_dict(service.run_case(app.case))  # what `linecheck run --json` writes
        assert doc["reactions"] == expected["reactions"]
        assert doc["seed"] == expected["seed"] and doc["v_ref"] == 30.0

        # the summary shows exactly these values (kN, %, ± std over the 2 realizations)
        table = app.query_one("#summary-table", DataTable)
        rows = {str(table.get_row_at(i)[0]): [str(c) for c in table.get_row_at(i)] for i in range(table.row_count)}
        for label, key, scale, fmt in [("peak dynamic M+B+R", "peak_dynamic", 1e-3, "{:.3f}"),
                                       ("mean max", "mean_max", 1e-3, "{:.3f}"),
                                       ("GF_Dy", "GF_Dy", 1.0, "{:.3f}"),
                                       ("Cont_R", "Cont_R", 100.0, "{:.1f}")]:
            for col, r in enumerate(("Rx", "Ry", "Rz"), start=2):
                assert rows[label][col] == expected_cell(expected["reactions"][r][key], scale, fmt), (label, r)

        # ---- switch tabs: ] steps through the result tabs
        results = app.query_one("#results-tabs", TabbedContent)
        seen = [results.active]
        for _ in range(6):
            await pilot.press("right_square_bracket")
            await pilot.pause()
            seen.append(results.active)
        assert seen == ["res-summary", "res-histories", "res-mean", "res-wind", "res-contrib", "res-spectral",
                        "res-freq"]
        history = app.query_one("#plot-history", PlotView).figure
        assert [s.label for s in history.series] == ["M+B+R (dynamic)", "M+B (quasi-static)", "M (mean)"]
        assert app.query_one("#plot-wind", PlotView).figure is not None
        assert app.query_one("#plot-contrib", PlotView).figure.kind == "stacked_bar"
        assert app.query_one("#spectral-table", DataTable).row_count > 0  # synoptic: spectral check shown
        assert app.query_one("#freq-table", DataTable).row_count == 20
        await pilot.press("3")
        await pilot.press("4")
        assert app.query_one("#main-tabs", TabbedContent).active == "compare"

        # ---- export to a temporary xlsx and to JSON
        xlsx = tmp_path / "out" / "short.xlsx"
        xlsx.parent.mkdir()
        await pilot.press("x")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), "the export dialog", messages)
        app.screen.query_one(Input).value = str(xlsx)
        await pilot.press("enter")
        await wait_for(pilot, lambda: any(m.kind == "xlsx" for m in of_type(messages, msg.Exported)), "xlsx", messages)
        import openpyxl

        wb = openpyxl.load_workbook(xlsx)
        assert len(wb.sheetnames) >= 2
        # the file's description speaks of Vref = 40 m/s: exported with the edit marked
        marked = "Vref = 40 m/s, single span (paper case 9) (edited: wind.v_ref 40 → 30)"
        assert any(marked in str(c.value) for ws in wb for row in ws.iter_rows() for c in row if c.value)

        out_json = tmp_path / "out" / "short.json"
        await pilot.press("j")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), "the export dialog", messages)
        app.screen.query_one(Input).value = str(out_json)
        await pilot.press("enter")
        await wait_for(pilot, lambda: any(m.kind == "json" for m in of_type(messages, msg.Exported)), "json", messages)
        assert json.loads(out_json.read_text())["reactions"] == json.loads(json.dumps(expected["reactions"]))
        assert json.loads(out_json.read_text())["description"].endswith(marked)

        # ---- compare: pin, change V_ref, run the variant
        await pilot.press("p")
        await edit(pilot, app, "wind.v_ref", "25")
        await pilot.press("r")
        await wait_for(pilot, lambda: len(of_type(messages, msg.RunFinished)) == 2, "second RunFinished", messages)
        await pilot.pause()
        assert app.query_one("#main-tabs", TabbedContent).active == "compare"
        cmp_rows = app.query_one("#compare-table", DataTable)
        assert cmp_rows.row_count == 33  # 11 statistics x 3 reactions
        first = [str(c) for c in cmp_rows.get_row_at(0)]
        assert first[:3] == ["Rx", "mean max", "kN"] and first[5].endswith("%")
        assert "wind.v_ref" in str(app.query_one("#compare-params", Static).render())

        # the command palette offers the export and run commands now
        names = [c.name for c in LinecheckCommands(app.screen)._commands()]
        assert "export: Excel workbook (.xlsx)" in names and "run: short" in names and "case: open short" in names
    assert not of_type(messages, msg.RunFailed)


async def test_invalid_input_shows_the_cli_message_and_keeps_running(short_case: Path, tmp_path: Path) -> None:
    messages = Recorder()
    app = LinecheckApp([short_case])  # one file: opened directly
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        before = app.case
        await edit(pilot, app, "wind.v_ref", "abc")
        rejected = of_type(messages, msg.ParameterRejected)
        assert rejected and rejected[-1].key == "wind.v_ref"
        with pytest.raises(CaseError) as err:  # the case validation, as the CLI loader runs it
            with_value(before, "wind.v_ref", "abc")
        assert rejected[-1].message == str(err.value)
        shown = str(app.query_one("#edit-message", Static).render())
        assert 'wind.v_ref: value "abc" is not allowed: expected a number >= 0 and <= 150 m/s' in shown
        assert app.query_one("#edit-input", Input).has_class("-invalid")
        assert app.case is before  # nothing applied

        # the same words as `linecheck check` on a file holding that value
        bad = tmp_path / "bad.toml"
        bad.write_text(short_case.read_text().replace("v_ref = 40.0", 'v_ref = "abc"'))
        from linecheck.cli.app import app as cli

        res = CliRunner().invoke(cli, ["check", str(bad)])
        assert res.exit_code == 2
        assert 'wind.v_ref: value "abc" is not allowed: expected a number >= 0 and <= 150 m/s' in " ".join(
            res.output.split())

        # validation as you type: out of range, then valid again
        inp = app.query_one("#edit-input", Input)
        await pilot.press("ctrl+u", *"500")
        await pilot.pause()
        assert "out of range" in str(app.query_one("#edit-message", Static).render())
        await pilot.press("ctrl+u", *"35")
        await pilot.pause()
        assert not inp.has_class("-invalid")
        await pilot.press("escape")
        await pilot.pause()
        assert app.case is before

        # a broken case file: an error dialog, no crash
        broken = tmp_path / "broken.toml"
        broken.write_text("[line]\nspans = 1\n")
        app.open_case(broken)
        await pilot.pause()
        assert isinstance(app.screen, ErrorScreen)
        await pilot.press("enter")
        await pilot.pause()
        assert not isinstance(app.screen, ErrorScreen) and app.case is before


async def test_six_span_run_never_blocks_and_cancels(tmp_path: Path, monkeypatch) -> None:
    from linecheck.tui import runner

    real_execute = runner.execute

    def until_cancelled(case, **kw):
        """The real six-span run, started again each time it ends, so that the run is still in
        progress whenever the keys below arrive (on any machine, at any load) until ``c``."""
        while True:
            real_execute(case, **kw)  # raises Cancelled once ``c`` sets the event

    monkeypatch.setattr(runner, "execute", until_cancelled)
    path = write_case(tmp_path, "case01-six.toml", "six", **{"analysis.realizations": 2})
    messages = Recorder()
    app = LinecheckApp([path])
    async with app.run_test(size=SIZE, message_hook=messages) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        await pilot.press("r")
        await wait_for(pilot, lambda: of_type(messages, msg.RunProgress), "progress", messages)
        # keys are sent as a terminal sends them (Pilot.press would wait for the busy CPU to idle);
        # each is handled while the solver thread computes: the UI never waits for the run
        tabs = app.query_one("#main-tabs", TabbedContent)
        for key, tab in [("1", "cases"), ("3", "results"), ("2", "params"), ("4", "compare"), ("1", "cases")]:
            app.simulate_key(key)
            await wait_for(pilot, lambda: tabs.active == tab, f"tab {tab}", messages)  # noqa: B023 - called at once, in this iteration
            assert app.running, "the run should still be in progress"
        app.simulate_key("question_mark")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), "help", messages)
        app.simulate_key("escape")
        await wait_for(pilot, lambda: not isinstance(app.screen, HelpScreen), "help closed", messages)
        assert app.running
        app.simulate_key("c")
        await wait_for(pilot, lambda: of_type(messages, msg.RunCancelled), "RunCancelled", messages)
        assert not app.running and app.output is None
        assert not of_type(messages, msg.RunFinished) and not isinstance(app.screen, ErrorScreen)
        assert "cancelled" in str(app.query_one("#run-status", Static).render())


async def test_save_as_never_overwrites_silently(short_case: Path) -> None:
    messages = Recorder()
    app = LinecheckApp([short_case])
    original_text = short_case.read_text()
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        await edit(pilot, app, "wind.v_ref", "33")
        await pilot.press("s")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), "the save dialog", messages)
        prompt = app.screen
        assert not Path(prompt.query_one(Input).value).exists()  # proposes a new name
        prompt.query_one(Input).value = str(short_case)  # an existing file
        await pilot.press("enter")
        await pilot.pause()
        assert app.screen is prompt and "exists" in str(prompt.query_one("#prompt-message", Static).render())
        assert short_case.read_text() == original_text
        new = short_case.with_name("short-v33.toml")
        prompt.query_one(Input).value = str(new)
        await pilot.press("enter")
        await wait_for(pilot, lambda: of_type(messages, msg.Exported), "the saved file", messages)
        saved = load_case(new)
        assert saved.wind.v_ref == 33.0 and saved.name == "short-v33"
        assert "wind.v_ref = 33" in saved.description
        assert app.case.source == new and short_case.read_text() == original_text


async def test_command_palette_and_help(short_case: Path) -> None:
    app = LinecheckApp([short_case.parent])
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        names = [c.name for c in LinecheckCommands(app.screen)._commands()]
        assert "case: open short" in names and "run: short" in names
        await pilot.press("ctrl+p")
        await pilot.pause()
        await pilot.press(*"open short")
        palette = app.screen
        hits = palette.query_one(CommandList)

        def top_hit() -> str:
            return "" if hits.highlighted is None else str(hits.get_option_at_index(hits.highlighted).prompt)

        # the palette searches in the background: wait for its answer, not for a fixed time
        await wait_for(pilot, lambda: "open short" in top_hit(), "the palette's hit")
        await pilot.press("enter")
        await wait_for(pilot, lambda: app.case is not None, "the case opened from the palette")
        assert app.case.name == "short"
        await pilot.press("f1")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), "help")
        await pilot.press("escape")
        await pilot.pause()
        assert not isinstance(app.screen, HelpScreen)


def test_cli_tui_command_is_registered_and_lazy(tmp_path: Path) -> None:
    from linecheck.cli.app import app as cli

    res = CliRunner().invoke(cli, ["tui", "--help"])
    assert res.exit_code == 0 and "terminal UI" in res.output
    res = CliRunner().invoke(cli, ["tui", str(tmp_path / "missing.toml")])
    assert res.exit_code == 2 and "not found" in res.output
    code = "import sys, linecheck.cli.app; print('textual' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", "other commands must not import Textual"
    # the TUI's data modules are plain Python (the widgets only draw what they compute)
    code = ("import sys; import linecheck.tui.runner, linecheck.tui.formatting, linecheck.tui.figures, "
            "linecheck.tui.catalog, linecheck.tui.files; print('textual' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"



async def test_run_errors_open_a_dialog_not_a_crash(short_case: Path, monkeypatch) -> None:
    from linecheck.core.errors import NumericalError
    from linecheck.tui import runner

    errors = iter([NumericalError("non-finite fluctuating wind load"), RuntimeError("a bug")])

    def failing(case, **kw):
        raise next(errors)

    monkeypatch.setattr(runner, "execute", failing)
    messages = Recorder()
    app = LinecheckApp([short_case])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        for title in ("Numerical failure", "Unexpected error"):
            await pilot.press("r")
            await wait_for(pilot, lambda: isinstance(app.screen, ErrorScreen), "the error dialog", messages)
            assert str(app.screen.query_one("#error-title", Static).render()) == title
            await pilot.press("enter")
            await wait_for(pilot, lambda: not isinstance(app.screen, ErrorScreen), "dialog closed", messages)
            assert not app.running
        assert [m.title for m in of_type(messages, msg.RunFailed)] == ["Numerical failure", "Unexpected error"]
        assert "non-finite" in of_type(messages, msg.RunFailed)[0].message


# --------------------------------------------------------------------------- unsaved edits
async def test_switching_case_with_unsaved_edits_asks(short_case: Path) -> None:
    other = write_case(short_case.parent, "case09-single.toml", "other", **{"analysis.duration": 20.0})
    messages = Recorder()
    app = LinecheckApp([short_case.parent])
    async with app.run_test(size=SIZE, message_hook=messages) as pilot:
        app.open_case(short_case)
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        await edit(pilot, app, "wind.v_ref", "31")
        edited = app.case
        assert edited.wind.v_ref == 31.0 and app.edited

        def asking() -> bool:  # the dialog on screen, composed
            return isinstance(app.screen, ConfirmScreen) and bool(app.screen.query("#confirm-message"))

        # from the browser (tab 1, enter on the other case) and from the palette: a question
        for how in ("browser", "palette"):
            if how == "browser":
                await pilot.press("1")
                app.query_one(CaseBrowser).select_path(other)
                await pilot.press("enter")
            else:
                {c.name: c for c in LinecheckCommands(app.screen)._commands()}["case: open other"].callback()
            await wait_for(pilot, asking, f"the question ({how})", messages)
            assert "wind.v_ref" in str(app.screen.query_one("#confirm-message", Static).render())
            await pilot.press("enter")  # the focus starts on "keep editing": enter alone keeps the edits
            await wait_for(pilot, lambda: not isinstance(app.screen, ConfirmScreen), "the dialog closed", messages)
            assert app.case is edited and app.case.name == "short" and app.edited
        assert not [m for m in of_type(messages, msg.CaseOpened) if m.case.name == "other"]

        # y discards them and opens the other case; the last run's status is not kept either
        await pilot.press("1")
        app.query_one(CaseBrowser).select_path(other)
        await pilot.press("enter")
        await wait_for(pilot, asking, "the question", messages)
        await pilot.press("y")
        await wait_for(pilot, lambda: app.case is not None and app.case.name == "other", "the other case", messages)
        assert not app.edited and app.sub_title == "other"
        assert "opened other" in str(app.query_one("#run-status", Static).render())

        # without edits: no question
        app.open_case(short_case)
        await wait_for(pilot, lambda: app.case.name == "short", "the case, unasked", messages)
        assert not isinstance(app.screen, ConfirmScreen)


async def test_compare_with_a_zero_pinned_value_shows_the_absolute_difference(short_case: Path) -> None:
    import dataclasses

    messages = Recorder()
    app = LinecheckApp([short_case])
    async with app.run_test(size=SIZE, message_hook=messages) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        await pilot.press("r")
        await wait_for(pilot, lambda: of_type(messages, msg.RunFinished), "RunFinished", messages)
        first = app.output
        # a pinned peak about zero (as a symmetric case gives: 1e-13 N), beside a real one
        doc = first.doc.to_json()
        doc["reactions"]["Ry"]["peak_dynamic"]["mean"] = 1e-13
        app.output = dataclasses.replace(first, doc=RunDocument.from_json(doc))
        await pilot.press("p")
        await edit(pilot, app, "wind.v_ref", "25")
        await pilot.press("r")
        await wait_for(pilot, lambda: len(of_type(messages, msg.RunFinished)) == 2, "second RunFinished", messages)
        await pilot.pause()
        current = app.output.doc.to_json()["reactions"]
        table = app.query_one("#compare-table", DataTable)
        rows = [[str(c) for c in table.get_row_at(i)] for i in range(table.row_count)]
        reaction = ""
        by_key = {}
        for row in rows:
            reaction = row[0] or reaction
            by_key[reaction, row[1]] = row
        # the absolute difference in kN, not (0.14 kN - 1e-13 N) / 1e-13 N = +1e17 %
        b = current["Ry"]["peak_dynamic"]["mean"]
        assert b > 10.0  # a real peak [N]: a relative change would be astronomically large
        assert by_key["Ry", "peak dynamic M+B+R"][5] == f"{(b - 1e-13) / 1e3:+.3f} kN"
        # a value well above the floor keeps the relative difference, computed here from the JSON
        a, b = first.doc.reactions["Rx"]["mean_max"].mean, current["Rx"]["mean_max"]["mean"]
        assert by_key["Rx", "mean max"][5] == f"{(b - a) / abs(a) * 100:+.1f} %"
        assert not any("e+" in row[5] for row in rows)


async def test_save_as_never_proposes_a_shipped_case_folder(tmp_path: Path, monkeypatch) -> None:
    shipped = ROOT / "cases" / "paper"
    before = sorted(p.name for p in shipped.iterdir())
    messages = Recorder()
    app = LinecheckApp([shipped / "case10-single.toml"])
    async with app.run_test(size=SIZE, message_hook=messages) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        await edit(pilot, app, "wind.v_ref", "30")
        for cwd in (tmp_path, shipped):  # even when started inside cases/paper/
            monkeypatch.chdir(cwd)
            await pilot.press("s")
            await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), "the save dialog", messages)
            proposed = Path(app.screen.query_one(Input).value).resolve()
            assert not proposed.is_relative_to(ROOT / "cases"), proposed
            if cwd == tmp_path:
                assert proposed.parent == tmp_path
            await pilot.press("escape")
            await wait_for(pilot, lambda: not isinstance(app.screen, PathPrompt), "the dialog closed", messages)

        # typed into cases/paper/: a warning and a second enter needed; esc writes nothing
        await pilot.press("s")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), "the save dialog", messages)
        prompt = app.screen
        prompt.query_one(Input).value = str(shipped / "case10-single-edited.toml")
        await pilot.press("enter")
        await pilot.pause()
        assert app.screen is prompt
        assert "shipped case folder" in str(prompt.query_one("#prompt-message", Static).render())
        await pilot.press("escape")
        await wait_for(pilot, lambda: not isinstance(app.screen, PathPrompt), "the dialog closed", messages)
        assert not of_type(messages, msg.Exported)
    assert sorted(p.name for p in shipped.iterdir()) == before


async def test_replace_checkbox_shows_x_only_when_ticked(short_case: Path) -> None:
    from linecheck.tui.screens.prompt import TickBox

    app = LinecheckApp([short_case])
    async with app.run_test(size=SIZE) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case")
        await pilot.press("s")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt) and bool(app.screen.query(TickBox)),
                       "the save dialog")
        box = app.screen.query_one(TickBox)
        assert not box.value and box._button.plain == "▐ ▌"
        await pilot.press("tab", "space")  # as a user ticks it
        await pilot.pause()
        assert box.value and box._button.plain == "▐X▌"


async def test_parameter_table_lists_the_wind_types_keys_uncut(short_case: Path, tmp_path: Path) -> None:
    six = write_case(tmp_path, "case01-six.toml", "six")
    app = LinecheckApp([short_case.parent])
    async with app.run_test(size=SIZE) as pilot:
        table = app.query_one("#params-table", DataTable)
        for path, shown, hidden in [(short_case, "wind.span_speeds", "wind.downburst.translation_direction"),
                                    (six, "wind.downburst.translation_direction", "wind.span_speeds")]:
            app.open_case(path, discard=True)
            await wait_for(pilot, lambda: app.case is not None and app.case.source == path, "the case")  # noqa: B023 - called at once, in this iteration
            await pilot.pause()
            keys = [table.coordinate_to_cell_key((i, 0)).row_key.value for i in range(table.row_count)]
            assert shown in keys and hidden not in keys
            if app.case.wind.type == "synoptic":
                assert not [k for k in keys if k.startswith("wind.downburst.")]
            # the longest key fits its column: the whole name is drawn
            column = table.columns["parameter"]
            assert column.width >= len("wind.downburst.translation_direction") >= max(len(k) for k in keys)


def test_export_description_marks_edits_unless_the_user_rewrote_it() -> None:
    import dataclasses

    from linecheck.tui.files import doc_for_export

    original = load_case(ROOT / "cases" / "paper" / "case09-single.toml")
    assert "Vref = 40 m/s" in original.description
    doc = RunDocument(schema_version=2, case=original.name, description=original.description, wind="synoptic",
                      units="SI", tower_of_interest=1, g_yp_L=None, v_ref=40.0, span_length=1.0, spans=1,
                      realizations=1, seed=0, duration=None, time_step=0.1, peak_window=None, windows=1,
                      design_fractile=0.5, reactions={}, towers=())  # only the description matters here
    assert doc_for_export(doc, original, original) is doc  # not edited: as it is
    edited = with_value(with_value(original, "wind.v_ref", 30.0), "line.sag", 12.0)
    assert doc_for_export(doc, edited, original).description == (
        f"{original.description} (edited: line.sag {original.line.sag:g} → 12, wind.v_ref 40 → 30)")
    rewritten = with_value(edited, "description", "my variant at 30 m/s")
    own = dataclasses.replace(doc, description=rewritten.description)
    assert doc_for_export(own, rewritten, original) is own  # the user's own words stay


async def test_model_spread_action(tmp_path: Path) -> None:
    """m runs a downburst case under every built-in model: the document gets the "models" block
    (same as the service's) and the summary notes list each model and the envelope."""
    folder = tmp_path / "cases"
    folder.mkdir()
    write_case(folder, "case07-single.toml", "db", **{"analysis.duration": 30.0, "analysis.realizations": 1})
    messages = Recorder()
    app = LinecheckApp([folder])
    async with app.run_test(size=SIZE, message_hook=messages) as pilot:
        await pilot.pause()
        await pilot.press("enter")
        await wait_for(pilot, lambda: of_type(messages, msg.CaseOpened), "CaseOpened", messages)
        await pilot.press("m")
        await wait_for(pilot, lambda: of_type(messages, msg.RunFinished), "RunFinished", messages)
        doc = of_type(messages, msg.RunFinished)[-1].output.doc.to_json()
        assert list(doc["models"]) == ["holmes-oliver", "ring-jet"]
        assert doc["models"]["holmes-oliver"] == doc["reactions"]
        notes = str(app.query_one("#summary-notes", Static).render())
        assert "ring-jet" in notes and "envelope" in notes


# --------------------------------------------------------------------------- sections
SECTION = ROOT / "cases" / "examples" / "section-12span.toml"


@pytest.fixture
def section_case(tmp_path: Path) -> Path:
    """A copy of the 12-span example (TOML + CSV) in a case folder."""
    folder = tmp_path / "cases"
    folder.mkdir()
    for name in (SECTION.name, "section-12span.csv"):
        (folder / name).write_text((SECTION.parent / name).read_text(encoding="utf-8"), encoding="utf-8")
    return folder / SECTION.name


def _csv_rows() -> list[list[str]]:
    lines = (SECTION.parent / "section-12span.csv").read_text(encoding="utf-8").splitlines()
    return [ln.split(",") for ln in lines if not ln.startswith("#")][1:]  # without the header


async def edit_tower(pilot, app: LinecheckApp, row: int, column: str, text: str, *, submit: bool = True) -> None:
    """Highlight cell ``column`` of tower row ``row`` (0-based) in the tower table, enter, type, enter."""
    await pilot.press("2")
    table = app.query_one("#towers-table", DataTable)
    table.focus()
    table.cursor_coordinate = (row, table.get_column_index(column))
    await pilot.press("enter")
    await wait_for(pilot, lambda: app.focused is app.query_one("#edit-input", Input), "the editor")
    await pilot.press("end", "ctrl+u", *text)
    await pilot.pause()
    if submit:
        await pilot.press("enter")
        await pilot.pause()


async def test_section_browser_and_tower_table(section_case: Path) -> None:
    messages = Recorder()
    app = LinecheckApp([section_case.parent])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await pilot.pause()
        # the browser's preview: a section summary, not "n spans x L m"
        shown = str(app.query_one("#case-preview", Static).render())
        assert "12 spans, 255-420 m, 2 angle towers, tower of interest 7" in shown
        assert "13 towers from section-12span.csv, H0 22 kN, angles T5 +18 deg, T9 -4 deg" in shown
        assert " x " not in shown.split("line", 1)[1].split("\n", 1)[0]
        await pilot.press("enter")
        await wait_for(pilot, lambda: of_type(messages, msg.CaseOpened), "CaseOpened", messages)
        await pilot.press("2")
        await pilot.pause()
        box, table = app.query_one("#towers-box"), app.query_one("#towers-table", DataTable)
        assert box.display and table.region.height >= table.row_count + 1  # every tower on screen
        rows = _csv_rows()
        assert table.row_count == len(rows) == 13
        for k, ref in enumerate(rows):
            cells = [str(c) for c in table.get_row_at(k)]
            name, station, ground, height, support, angle, ins = ref
            span = "" if k + 1 == len(rows) else f"{float(rows[k + 1][1]) - float(station):g}"
            # insulator: the tower's own, "(4.2)" for the line default, empty at strain towers
            ins_shown = ins if ins else ("" if support == "strain" else "(4.2)")
            assert cells == ["", name, f"{float(station):g}", f"{float(ground):g}", f"{float(height):g}", support,
                             f"{float(angle):g}", ins_shown, span], k
        # the parameter table lists the section keys, not the equal-span keys the towers derive
        keys = [table_key for table_key in app.query_one("#params-table", DataTable).rows]
        names = [k.value for k in keys]
        assert "line.tension" in names and "line.towers_file" in names
        assert "line.span_length" not in names and "line.supports" not in names
        assert not [n for n in names if n.startswith("line.towers.")]


async def test_section_tower_edit_marks_the_case_and_saves_inline(section_case: Path, tmp_path: Path) -> None:
    messages = Recorder()
    app = LinecheckApp([section_case])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        original = app.case
        await edit_tower(pilot, app, 3, "height", "35")
        changed = of_type(messages, msg.ParameterChanged)
        assert changed and changed[-1].key == "line.towers[4].height" and changed[-1].value == 35.0
        assert app.case.line.towers[3].height == 35.0 and app.case.line.towers_file is None
        assert app.case.line.towers[:3] == original.line.towers[:3]
        assert app.edited and "(edited)" in app.sub_title
        assert "1 edited (*)" in str(app.query_one("#params-title", Static).render())
        table = app.query_one("#towers-table", DataTable)
        assert str(table.get_row_at(3)[0]) == "*" and str(table.get_row_at(2)[0]) == ""
        assert app.focused is table  # back on the table after the edit
        # the mean clamp height the equal-span display key derives follows the edit:
        # (sum of the CSV heights + 5 m) / 13
        heights = [float(r[3]) for r in _csv_rows()]
        assert app.case.line.height == pytest.approx((sum(heights) + 5.0) / 13, rel=1e-12)

        # save as: the towers written inline, the edit noted, reloading gives the same towers
        path = tmp_path / "edited.toml"
        saved = files.case_for_saving(app.case, app.original, path)
        assert "line.towers[4].height = 35" in saved.description
        files.save_case(saved, path, replace=False)
        again = load_case(path)
        assert again.line.towers == app.case.line.towers and again.line.towers_file is None

        # revert: the file's table again, no marker
        app.action_revert()
        await pilot.pause()
        assert app.case is original and not app.edited
        assert str(app.query_one("#towers-table", DataTable).get_row_at(3)[0]) == ""


async def test_section_invalid_tower_cell_shows_the_cli_message(section_case: Path, tmp_path: Path) -> None:
    messages = Recorder()
    app = LinecheckApp([section_case])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        before = app.case
        await edit_tower(pilot, app, 3, "station", "600")  # T4 before T3 (655 m)
        rejected = of_type(messages, msg.ParameterRejected)
        assert rejected and rejected[-1].key == "line.towers[4].station"
        shown = str(app.query_one("#edit-message", Static).render())
        expected = ("line.towers[4].station: value 600.0 is not allowed: expected stations increasing along the "
                    "line (the previous tower is at 655.0 m)")
        assert shown == f"{section_case}: {expected}" and rejected[-1].message == shown
        assert "\n" not in shown
        assert app.query_one("#edit-input", Input).has_class("-invalid")
        assert app.case is before and not app.edited

        # the CLI on a file holding that table says the same after its file:line prefix
        bad = tmp_path / "bad.toml"
        inline = with_values(before, {"line.towers_file": None, "line.towers": tower_dicts(before)})
        text = case_to_toml(inline).replace("station = 940.0", "station = 600.0")
        bad.write_text(text, encoding="utf-8")
        from linecheck.cli.app import app as cli

        res = CliRunner().invoke(cli, ["check", str(bad)])
        assert res.exit_code == 2
        out = res.output.strip()
        assert out.endswith(expected) and re.search(rf"error:\S* {re.escape(str(bad))}:\d+: line\.towers\[4\]", out)

        # an end tower cannot be suspension: the loader's words, as you type
        await pilot.press("escape")
        await pilot.pause()
        await edit_tower(pilot, app, 12, "support", "suspension", submit=False)
        shown = str(app.query_one("#edit-message", Static).render())
        assert shown.startswith(f"{section_case}: line.towers[13].support: value \"suspension\" is not allowed at "
                                "an end tower: expected \"strain\"")
        await pilot.press("escape")
        await pilot.pause()
        assert app.case is before


async def test_section_towers_added_and_removed(section_case: Path) -> None:
    """+ adds a suspension tower midway (station, ground, height interpolated), - removes the
    highlighted one; the tower of interest keeps pointing at the same tower; removing an end
    tower that would leave a suspension end is refused with the loader's one-line message."""
    messages = Recorder()
    app = LinecheckApp([section_case])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, "the case", messages)
        original = app.case
        await pilot.press("2")
        table = app.query_one("#towers-table", DataTable)
        table.focus()
        table.cursor_coordinate = (1, 0)  # T2 (station 310, ground 128.5, height 36) -> T3 (655, 141, 33)
        await pilot.press("plus")
        await wait_for(pilot, lambda: app.case.line.spans == 13, "the added tower", messages)
        added = app.case.line.towers[2]
        assert (added.name, added.station, added.ground, added.height, added.support) == \
            ("T2a", 482.5, 134.75, 34.5, "suspension")
        assert app.case.line.tower_of_interest == 8 and app.case.line.towers[7].name == "T7"
        assert table.row_count == 14 and of_type(messages, msg.ParameterChanged)[-1].key == "line.towers"
        assert app.edited
        # remove it again: the original table (inline now) and tower of interest
        table.cursor_coordinate = (2, 0)
        await pilot.press("minus")
        await wait_for(pilot, lambda: app.case.line.spans == 12, "the removed tower", messages)
        assert app.case.line.towers == original.line.towers and app.case.line.tower_of_interest == 7
        # removing the first tower would make T2 (suspension) an end: refused, nothing changes
        before = app.case
        table.cursor_coordinate = (0, 0)
        await pilot.press("minus")
        await wait_for(pilot, lambda: of_type(messages, msg.ParameterRejected), "the refusal", messages)
        rejected = of_type(messages, msg.ParameterRejected)[-1]
        assert "line.towers[1].support" in rejected.message and "end tower" in rejected.message
        assert "\n" not in rejected.message and app.case is before
