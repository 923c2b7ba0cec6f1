"""Pilot tests of the terminal UI (``linecheck tui``): keys in, typed messages and widgets out.

One short synoptic case (20 s, 2 realizations) drives a whole session: open, edit V_ref,
run, check the summary against ``run_to_dict(service.run_case(case))``, switch tabs,
export to xlsx and JSON, pin and compare.  A six-span downburst shows that keys are
handled while it runs, and that ``c`` cancels it.
"""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck import service
from linecheck.core.case import case_to_toml, load_case, with_value
from linecheck.core.errors import CaseError
from linecheck.io.jsonout import run_to_dict

textual = pytest.importorskip("textual")

from textual.widgets import DataTable, Input, Static, TabbedContent  # noqa: E402

from linecheck.tui import messages as msg  # noqa: E402
from linecheck.tui.app import LinecheckApp  # noqa: E402
from linecheck.tui.commands import LinecheckCommands  # noqa: E402
from linecheck.tui.plotting import PlotView  # noqa: E402
from linecheck.tui.screens.error import ErrorScreen  # noqa: E402
from linecheck.tui.screens.help import HelpScreen  # noqa: E402
from linecheck.tui.screens.prompt import PathPrompt  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
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


async def wait_for(pilot, predicate, timeout: float = 60.0, what: str = "condition") -> None:
    """Poll ``predicate`` while the app runs (plain sleeps: no waiting for an idle CPU)."""
    t0 = time.monotonic()
    while not predicate():
        if time.monotonic() - t0 > timeout:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.02)


def of_type(messages: list, kind: type) -> list:
    return [m for m in messages if isinstance(m, kind)]


async def edit(pilot, app: LinecheckApp, key: str, text: str) -> None:
    """Highlight ``key`` in the parameter table, enter, replace the text, enter."""
    await pilot.press("2")
    table = app.query_one("#params-table", DataTable)
    table.move_cursor(row=table.get_row_index(key))
    await pilot.press("enter")
    await wait_for(pilot, lambda: app.focused is app.query_one("#edit-input", Input), 5, "the editor")
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
    messages: list = []
    app = LinecheckApp([short_case.parent])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await pilot.pause()
        # ---- open the case from the browser (the cursor starts on the first case)
        await pilot.press("enter")
        await wait_for(pilot, lambda: of_type(messages, msg.CaseOpened), 5, "CaseOpened")
        assert app.case.name == "short"
        assert app.query_one("#main-tabs", TabbedContent).active == "params"

        # ---- edit V_ref
        await edit(pilot, app, "wind.v_ref", "30")
        changed = of_type(messages, msg.ParameterChanged)
        assert changed and changed[-1].key == "wind.v_ref" and app.case.wind.v_ref == 30.0
        assert "(edited)" in app.sub_title

        # ---- run to completion
        await pilot.press("r")
        await wait_for(pilot, lambda: of_type(messages, msg.RunFinished), 60, "RunFinished")
        assert {m.stage for m in of_type(messages, msg.RunProgress)} >= {"step 1: mean states", "steps 2-3: dynamics"}
        doc = of_type(messages, msg.RunFinished)[-1].output.doc
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
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), 5, "the export dialog")
        app.screen.query_one(Input).value = str(xlsx)
        await pilot.press("enter")
        await wait_for(pilot, lambda: any(m.kind == "xlsx" for m in of_type(messages, msg.Exported)), 60, "xlsx")
        import openpyxl

        wb = openpyxl.load_workbook(xlsx)
        assert len(wb.sheetnames) >= 2

        out_json = tmp_path / "out" / "short.json"
        await pilot.press("j")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), 5, "the export dialog")
        app.screen.query_one(Input).value = str(out_json)
        await pilot.press("enter")
        await wait_for(pilot, lambda: any(m.kind == "json" for m in of_type(messages, msg.Exported)), 10, "json")
        assert json.loads(out_json.read_text())["reactions"] == json.loads(json.dumps(expected["reactions"]))

        # ---- compare: pin, change V_ref, run the variant
        await pilot.press("p")
        await edit(pilot, app, "wind.v_ref", "25")
        await pilot.press("r")
        await wait_for(pilot, lambda: len(of_type(messages, msg.RunFinished)) == 2, 60, "second RunFinished")
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
    messages: list = []
    app = LinecheckApp([short_case])  # one file: opened directly
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, 5, "the case")
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


async def test_six_span_run_never_blocks_and_cancels(tmp_path: Path) -> None:
    path = write_case(tmp_path, "case01-six.toml", "six", **{"analysis.realizations": 4})
    messages: list = []
    app = LinecheckApp([path])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, 5, "the case")
        await pilot.press("r")
        await wait_for(pilot, lambda: of_type(messages, msg.RunProgress), 30, "progress")
        # keys are sent as a terminal sends them (Pilot.press would wait for the busy CPU to idle)
        tabs = app.query_one("#main-tabs", TabbedContent)
        latencies = []
        for key, tab in [("1", "cases"), ("3", "results"), ("2", "params"), ("4", "compare"), ("1", "cases")]:
            t0 = time.monotonic()
            app.simulate_key(key)
            await wait_for(pilot, lambda: tabs.active == tab, 5, f"tab {tab}")
            latencies.append(time.monotonic() - t0)
            assert app.running, "the run should still be in progress"
        assert max(latencies) < 3.0, latencies  # typically well under 0.5 s, even on a busy machine
        app.simulate_key("question_mark")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), 5, "help")
        app.simulate_key("escape")
        await wait_for(pilot, lambda: not isinstance(app.screen, HelpScreen), 5, "help closed")
        assert app.running
        app.simulate_key("c")
        await wait_for(pilot, lambda: of_type(messages, msg.RunCancelled), 30, "RunCancelled")
        assert not app.running and app.output is None
        assert not of_type(messages, msg.RunFinished) and not isinstance(app.screen, ErrorScreen)
        assert "cancelled" in str(app.query_one("#run-status", Static).render())


async def test_save_as_never_overwrites_silently(short_case: Path) -> None:
    messages: list = []
    app = LinecheckApp([short_case])
    original_text = short_case.read_text()
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, 5, "the case")
        await edit(pilot, app, "wind.v_ref", "33")
        await pilot.press("s")
        await wait_for(pilot, lambda: isinstance(app.screen, PathPrompt), 5, "the save dialog")
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
        await wait_for(pilot, lambda: of_type(messages, msg.Exported), 5, "the saved file")
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
        await pilot.pause(0.5)
        await pilot.press("enter")
        await wait_for(pilot, lambda: app.case is not None, 5, "the case opened from the palette")
        assert app.case.name == "short"
        await pilot.press("f1")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), 5, "help")
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
    messages: list = []
    app = LinecheckApp([short_case])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await wait_for(pilot, lambda: app.case is not None, 5, "the case")
        for title in ("Numerical failure", "Unexpected error"):
            await pilot.press("r")
            await wait_for(pilot, lambda: isinstance(app.screen, ErrorScreen), 10, "the error dialog")
            assert str(app.screen.query_one("#error-title", Static).render()) == title
            await pilot.press("enter")
            await wait_for(pilot, lambda: not isinstance(app.screen, ErrorScreen), 5, "dialog closed")
            assert not app.running
        assert [m.title for m in of_type(messages, msg.RunFailed)] == ["Numerical failure", "Unexpected error"]
        assert "non-finite" in of_type(messages, msg.RunFailed)[0].message


async def test_model_spread_action(tmp_path: Path) -> None:
    """m runs a downburst case under every built-in model: the document gets the "models" block
    (same as the service's) and the summary notes list each model and the envelope."""
    folder = tmp_path / "cases"
    folder.mkdir()
    write_case(folder, "case07-single.toml", "db", **{"analysis.duration": 30.0, "analysis.realizations": 1})
    messages: list = []
    app = LinecheckApp([folder])
    async with app.run_test(size=SIZE, message_hook=messages.append) as pilot:
        await pilot.pause()
        await pilot.press("enter")
        await wait_for(pilot, lambda: of_type(messages, msg.CaseOpened), 5, "CaseOpened")
        await pilot.press("m")
        await wait_for(pilot, lambda: of_type(messages, msg.RunFinished), 120, "RunFinished")
        doc = of_type(messages, msg.RunFinished)[-1].output.doc
        assert list(doc["models"]) == ["holmes-oliver", "ring-jet"]
        assert doc["models"]["holmes-oliver"] == doc["reactions"]
        notes = str(app.query_one("#summary-notes", Static).render())
        assert "ring-jet" in notes and "envelope" in notes
