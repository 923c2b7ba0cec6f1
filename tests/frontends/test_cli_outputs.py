"""CLI and Excel outputs (output safety and clarity): no formula injection, ENOSPC is one line, sanity check surfaced,
title-block options, help and usage texts, the run table at 120 columns."""

from __future__ import annotations

import copy
import dataclasses
import errno
import json
import os
import re
import sys
import zipfile
from pathlib import Path

import pytest
from openpyxl import load_workbook
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.case import case_to_toml, load_case
from linecheck.core.errors import CaseError
from linecheck.excel import template as tpl
from linecheck.excel.summary import SANITY_HEADER
from linecheck.excel.writer import write_workbook
from linecheck.io.document import RunDocument
from linecheck.io.jsonout import run_to_dict, write_json

from ..conftest import CASES

runner = CliRunner()

#: Texts a spreadsheet would read as formulas (OWASP CSV injection: = + - @ tab CR), and an error code.
HOSTILE = ["=cmd|' /C calc'!A0", '=HYPERLINK("http://evil.example","click")', "+1+2", "-2+3", "@SUM(A1:A2)",
           "\t=1+1", "\r=1+1", "#N/A"]


def _short(path: Path, **analysis):
    case = load_case(path)
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


@pytest.fixture(scope="module")
def short_case(tmp_path_factory) -> Path:
    """A synoptic paper case cut to 60 s and one realization (a run of a few seconds)."""
    case = _short(CASES / "paper" / "case10-single.toml", duration=60.0, realizations=1)
    path = tmp_path_factory.mktemp("case") / "case10-short.toml"
    path.write_text(case_to_toml(case), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def doc(short_case) -> dict:
    return run_to_dict(service.run_case(load_case(short_case)))


def _xml(text: str) -> str:
    """``text`` as an XML reader returns it (a carriage return reads back as a line feed)."""
    return text.replace("\r", "\n")


def _all_cells(wb):
    for ws in wb.worksheets:
        for row in ws.iter_rows():
            for c in row:
                if c.value is not None:
                    yield ws, c


# --------------------------------------------------------------------------- fault 1: injection
def test_injected_texts_are_stored_as_strings(doc, tmp_path):
    docs = []
    for k, text in enumerate(HOSTILE):
        d = copy.deepcopy(doc)
        d["case"] = text if k else HOSTILE[0]
        d["description"] = HOSTILE[(k + 1) % len(HOSTILE)]
        docs.append(d)
    docs.append({"case": "=failed-stem", "error": "=cmd|' /C calc'!A0"})
    title = {"project": HOSTILE[0], "line": HOSTILE[1], "engineer": "@me", "revision": "-1", "section": "+S"}
    path = write_workbook(docs, tmp_path / "inj.xlsx", title=title)

    # the stored XML holds no formula at all (the writer writes none; a template here has none)
    with zipfile.ZipFile(path) as z:
        for name in z.namelist():
            if name.startswith("xl/worksheets/sheet"):
                assert "<f>" not in z.read(name).decode() and "<f " not in z.read(name).decode(), name

    wb = load_workbook(path)
    seen: dict[str, list[str]] = {}
    for ws, c in _all_cells(wb):
        assert c.data_type != "f", (ws.title, c.coordinate, c.value)
        if isinstance(c.value, str) and any(_xml(h) in c.value for h in HOSTILE + ["=failed-stem"]):
            seen.setdefault(c.value, []).append(ws.title)
            assert c.data_type == "s", (ws.title, c.coordinate, c.value, c.data_type)
            if c.value.startswith(("=", "+", "-", "@", "\t", "\r")):
                assert c.quotePrefix, (ws.title, c.coordinate)  # stays a text when edited in Excel
    # every hostile text arrived, verbatim, in the Summary, Peaks and its case sheet
    for text in map(_xml, HOSTILE):
        assert "Summary" in seen[text] and "Peaks" in seen[text], text
        assert len(seen[text]) >= 3, (text, seen[text])
    assert "=failed-stem" in seen and seen["=failed-stem"] == ["Summary"]
    assert "FAILED: =cmd|' /C calc'!A0" in {c.value for _, c in _all_cells(wb)}
    for name, want in title.items():
        ws, cell = tpl.destination(wb, name)
        assert ws[cell].value == want and ws[cell].data_type == "s", name


def test_injected_title_via_cli(doc, tmp_path):
    js, xl = tmp_path / "r.json", tmp_path / "t.xlsx"
    write_json(js, doc)
    res = runner.invoke(app, ["export", str(js), "--excel", str(xl), "--project", "=HYPERLINK(\"x\")",
                              "--title", "section==cmd|' /C calc'!A0"])
    assert res.exit_code == 0, res.output
    wb = load_workbook(xl)
    for name, want in (("project", '=HYPERLINK("x")'), ("section", "=cmd|' /C calc'!A0")):
        ws, cell = tpl.destination(wb, name)
        assert ws[cell].value == want and ws[cell].data_type == "s"


# --------------------------------------------------------------------------- fault 7: ENOSPC
def _enospc(*_a, **_k):
    raise OSError(errno.ENOSPC, "No space left on device")


def _one_error_line(res) -> str:
    lines = [ln for ln in res.output.splitlines() if ln.strip().startswith("error:")]
    assert len(lines) == 1, res.output
    assert "Traceback" not in res.output and "internal error" not in res.output
    return lines[0]


def test_run_json_on_full_disk_is_exit_2(short_case, tmp_path, monkeypatch):
    js = tmp_path / "r.json"
    monkeypatch.setattr("linecheck.io.atomic.os.replace", _enospc)
    res = runner.invoke(app, ["run", str(short_case), "--json", str(js)])
    assert res.exit_code == 2, res.output
    line = _one_error_line(res)
    assert "no space left on device" in line and str(js) in line
    assert list(tmp_path.iterdir()) == []  # no half-written JSON, no temporary file left


def test_export_on_full_disk_is_exit_2_without_zipfile_traceback(doc, tmp_path, monkeypatch, capfd):
    js, xl = tmp_path / "r.json", tmp_path / "out.xlsx"
    write_json(js, doc)
    xl.write_bytes(b"previous workbook")
    real_open = open

    class FullDisk:
        """A file that takes 1000 bytes, then fails every write with ENOSPC (as a full disk does)."""

        def __init__(self, fh):
            self._fh, self._n = fh, 0

        def write(self, data):
            self._n += len(data)
            if self._n > 1000:
                _enospc()
            return self._fh.write(data)

        def __getattr__(self, name):
            return getattr(self._fh, name)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self._fh.close()

    def full_disk_open(file, mode="r", *a, **k):
        fh = real_open(file, mode, *a, **k)
        if "w" in mode and str(file).endswith(".tmp"):
            return FullDisk(fh)
        return fh

    unraisable = []  # what Python would print as "Exception ignored in: <ZipFile.__del__ ...>"
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    monkeypatch.setattr("builtins.open", full_disk_open)
    monkeypatch.setattr("io.open", full_disk_open)  # zipfile opens through io.open
    res = runner.invoke(app, ["export", str(js), "--excel", str(xl), "--force"])
    monkeypatch.setattr("builtins.open", real_open)
    monkeypatch.setattr("io.open", real_open)
    assert res.exit_code == 2, res.output
    assert "no space left on device" in _one_error_line(res)
    del res  # its exc_info keeps the failed frames (and any half-closed ZipFile) alive
    import gc

    gc.collect()  # a half-closed ZipFile would complain in its __del__ now
    assert not unraisable, [(u.object, u.exc_value) for u in unraisable]
    err = capfd.readouterr().err
    assert "ZipFile" not in err and "Exception ignored" not in err
    assert xl.read_bytes() == b"previous workbook"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.xlsx", "r.json"]


def test_write_json_enospc_raises_case_error(tmp_path, monkeypatch):
    monkeypatch.setattr("linecheck.io.atomic.os.replace", _enospc)
    with pytest.raises(CaseError, match="cannot write JSON file: no space left on device"):
        write_json(tmp_path / "a.json", {"a": 1})
    assert list(tmp_path.iterdir()) == []


def test_run_checks_outputs_before_computing(short_case, tmp_path, monkeypatch):
    called = []
    monkeypatch.setattr(service, "run_case", lambda *a, **k: called.append(1))
    targets = [["--json", str(tmp_path / "missing" / "r.json")], ["--excel", str(tmp_path / "missing" / "r.xlsx")]]
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    if not os.access(ro, os.W_OK):  # root writes anywhere: the read-only case cannot be shown then
        targets += [["--json", str(ro / "r.json")], ["--excel", str(ro / "r.xlsx")]]
    try:
        for args in targets:
            res = runner.invoke(app, ["run", str(short_case), *args])
            assert res.exit_code == 2, (args, res.output)
            assert "does not exist" in _one_error_line(res) or "not writable" in res.output
    finally:
        ro.chmod(0o700)
    assert not called


# --------------------------------------------------------------------------- sanity check in the Summary
def _flagged(doc: dict) -> dict:
    d = copy.deepcopy(doc)
    d["case"] = "flagged"
    item = d["spectral"]["sanity_check"][0]
    item["ok"] = False
    return d


def _summary_rows(wb):
    ws, cell = tpl.destination(wb, tpl.SUMMARY_ANCHOR)
    top, left = ws[cell].row, ws[cell].column
    headers = []
    while ws.cell(row=top, column=left + len(headers)).value is not None:
        headers.append(ws.cell(row=top, column=left + len(headers)).value)
    rows, r = [], top + 1
    while ws.cell(row=r, column=left).value is not None:
        rows.append({h: ws.cell(row=r, column=left + k).value for k, h in enumerate(headers)})
        r += 1
    return ws, rows


def test_summary_shows_the_sanity_check(doc, tmp_path):
    ok = copy.deepcopy(doc)
    for it in ok["spectral"]["sanity_check"]:
        it["ok"] = True
    bad = _flagged(ok)
    item = bad["spectral"]["sanity_check"][0]
    down = copy.deepcopy(doc)
    down["case"], down["wind"] = "down", "downburst"
    down.pop("spectral")
    path = write_workbook([ok, bad, down], tmp_path / "s.xlsx")
    wb = load_workbook(path)
    _ws, rows = _summary_rows(wb)
    by_case = {}
    for r in rows:
        by_case.setdefault(r["Case"], set()).add(r[SANITY_HEADER])
    assert by_case[ok["case"]] == {"ok"}
    assert by_case["flagged"] == {f"FLAG: {item['reaction']} {item['quantity']}"}
    assert by_case["down"] == {"—"}
    texts = [c.value for _, c in _all_cells(wb) if isinstance(c.value, str)]
    # the case sheet's FLAG legend only where a row is flagged
    flag_line = [t for t in texts if t.startswith("FLAG: time and frequency domain differ")]
    assert len(flag_line) == 1
    sheet_with_flag = [w.title for w, c in _all_cells(wb)
                       if isinstance(c.value, str) and c.value.startswith("FLAG: time and frequency")]
    assert sheet_with_flag == ["flagged"]


# --------------------------------------------------------------------------- title block options
TITLE_ARGS = ["--project", "Line 7 upgrade", "--line", "230 kV Aldon-Brix", "--engineer", "A. Engineer",
              "--revision", "B", "--title", "checked_by=B. Checker"]
TITLE_WANT = {"project": "Line 7 upgrade", "line": "230 kV Aldon-Brix", "engineer": "A. Engineer",
              "revision": "B", "checked_by": "B. Checker"}


def _title_of(path: Path) -> dict:
    wb = load_workbook(path)
    out = {}
    for name in TITLE_WANT:
        ws, cell = tpl.destination(wb, name)
        out[name] = ws[cell].value
    return out


def test_run_excel_fills_the_title_block(short_case, tmp_path):
    xl = tmp_path / "run.xlsx"
    res = runner.invoke(app, ["run", str(short_case), "--excel", str(xl), *TITLE_ARGS])
    assert res.exit_code == 0, res.output
    assert _title_of(xl) == TITLE_WANT


def test_batch_excel_fills_the_title_block(short_case, tmp_path):
    xl = tmp_path / "batch.xlsx"
    res = runner.invoke(app, ["batch", str(short_case), "--jobs", "1", "--excel", str(xl), *TITLE_ARGS])
    assert res.exit_code == 0, res.output
    assert _title_of(xl) == TITLE_WANT


def test_title_options_are_the_same_on_all_three_and_checked_first(short_case, tmp_path, monkeypatch):
    for cmd in ("run", "batch", "export"):
        res = runner.invoke(app, [cmd, "--help"], terminal_width=200)
        for opt in ("--project", "--line", "--engineer", "--revision", "--title"):
            assert opt in res.output, (cmd, opt)
    called = []
    monkeypatch.setattr(service, "run_case", lambda *a, **k: called.append(1))
    for args, msg in ((["--project", "P"], "add --excel"),
                      (["--excel", str(tmp_path / "a.xlsx"), "--title", "colour=red"], "unknown title field 'colour'"),
                      (["--excel", str(tmp_path / "a.xlsx"), "--title", "project"], "KEY=VALUE")):
        for cmd in ("run", "batch"):
            res = runner.invoke(app, [cmd, str(short_case), *args])
            assert res.exit_code == 2, (cmd, args, res.output)
            assert msg in _one_error_line(res)
    assert not called and not list(tmp_path.iterdir())


# --------------------------------------------------------------------------- help and usage
NEEDS_ARGUMENT = ["run", "batch", "export", "static", "check", "modes", "spectral", "wind", "scan"]


@pytest.mark.parametrize("cmd", NEEDS_ARGUMENT + ["validate", "tui"])
def test_missing_or_bad_arguments_are_one_line_exit_2(cmd):
    # validate and tui need no argument (they would start working): only the unknown option for them
    for args in ([cmd], [cmd, "--no-such-option"]) if cmd in NEEDS_ARGUMENT else ([cmd, "--no-such-option"],):
        res = runner.invoke(app, args)
        lines = [ln for ln in res.output.splitlines() if ln.strip()]
        assert res.exit_code == 2, (args, res.output)
        assert len(lines) == 1 and lines[0].startswith("error: "), (args, res.output)
        assert f"linecheck {cmd} --help" in lines[0]
        assert "╭" not in res.output and "Traceback" not in res.output


def test_run_without_argument_names_it():
    res = runner.invoke(app, ["run"])
    assert res.exit_code == 2
    assert res.output.strip() == ("error: Missing argument 'CASE_FILE'; usage: linecheck run [OPTIONS] {CASE_FILE} "
                                  "(see linecheck run --help)")


def test_flags_are_shown_without_a_value():
    res = runner.invoke(app, ["run", "--help"], terminal_width=200)
    for flag in ("--force", "--full-histories", "--no-check", "--help"):
        line = next(ln for ln in res.output.splitlines() if f"{flag} " in ln)
        assert "<bool>" not in line, line
    line = next(ln for ln in res.output.splitlines() if "--json " in ln)
    assert "<path>" in line  # an option with a value keeps its type
    res = runner.invoke(app, ["run", "case.toml", "--force", "true"])
    assert res.exit_code == 2  # --force takes no value: "true" is a second (extra) argument
    assert "unexpected extra argument(s) (true)" in res.output


def test_check_help_says_every_file_is_reported(tmp_path):
    res = runner.invoke(app, ["check", "--help"], terminal_width=200)
    assert "first bad file" not in res.output and "every bad file is reported" in res.output
    bad1, bad2 = tmp_path / "a.toml", tmp_path / "b.toml"
    bad1.write_text("name = 1\n")
    bad2.write_text("[line\n")
    res = runner.invoke(app, ["check", str(bad1), str(CASES / "paper" / "case10-single.toml"), str(bad2)])
    assert res.exit_code == 2
    assert str(bad1) in res.output and str(bad2) in res.output and "ok " in res.output


def test_static_explains_the_star():
    res = runner.invoke(app, ["static", str(CASES / "paper" / "case10-single.toml")])
    assert res.exit_code == 0, res.output
    assert "│   1 * │" in res.output
    assert "* tower of interest (line.tower_of_interest = 1)" in res.output


# --------------------------------------------------------------------------- run table, flags, burn-in note
def test_run_table_fits_120_columns_and_flags_cont_r(doc):
    from rich.console import Console

    from linecheck.cli.run_cmd import CONT_R_FLAG, results_table

    d = copy.deepcopy(doc)
    d["realizations"] = 2  # two lines per row: mean and ± std
    for r in ("Rx", "Ry", "Rz"):
        for st in d["reactions"][r].values():
            if isinstance(st, dict) and st.get("mean") is not None:
                st["std"] = 0.1 * abs(st["mean"])
    d["reactions"]["Rx"]["Cont_R"]["mean"] = CONT_R_FLAG + 0.05
    d["reactions"]["Ry"]["Cont_R"]["mean"] = CONT_R_FLAG - 0.05
    d["reactions"]["Rz"]["Cont_R"]["mean"] = 0.999  # Rz is not flagged (as in the Excel Summary)
    for r, state in (("Rx", "recommended"), ("Ry", None), ("Rz", "recommended")):  # the dynamic_analysis flag states
        d["reactions"][r]["dynamic_analysis"] = state
    con = Console(width=120, record=True, color_system="truecolor", force_terminal=True)
    con.print(results_table(RunDocument.from_json(d)))  # the console reads the typed document
    text = con.export_text(clear=False)
    assert "…" not in text
    assert max(len(ln) for ln in text.splitlines()) <= 120
    for header in ("peak QS", "peak Dy", "Cont_R", "GF_Dy", "rms R"):
        assert header in text
    styled = con.export_text(styles=True)
    red_cells = [c.strip() for c in re.findall(r"\x1b\[1;31m([^\x1b]*)\x1b\[0m", styled)]
    assert len(red_cells) == 2 and red_cells[0] == "15.0" and red_cells[1].startswith("±"), red_cells  # Rx only


def test_run_output_legend_flag_and_burn_in_note_once(short_case):
    res = runner.invoke(app, ["run", str(short_case)])
    assert res.exit_code == 0, res.output
    out = res.output
    assert "Cont_R: share of the peak that a quasi-static analysis misses" in out
    from dataclasses import replace

    from linecheck.cli.run_cmd import burn_in_note, cont_r_flagged
    from linecheck.io.jsonout import run_document

    d = run_document(service.run_case(load_case(short_case)))
    assert ("Cont_R above 10 %" in out) == any(cont_r_flagged(d, r) for r in ("Rx", "Ry"))
    # the paper's damping: the burn-in is never reached; one line says what it means and what to do
    assert d.damping == "paper" and not d.burn_in.sufficient
    notes = [ln for ln in out.splitlines() if "burn-in" in ln]
    assert len(notes) == 1, out
    assert notes[0].startswith("note: damping = \"paper\" leaves the") and "use damping = \"quasi-steady\"" in notes[0]
    assert "A flagged resonant component" not in out  # the note already says why, not twice
    assert burn_in_note(replace(d, burn_in=replace(d.burn_in, sufficient=True))) is None


# --------------------------------------------------------------------------- the typed document
def test_saved_run_and_batch_json_read_back_byte_for_byte(short_case, tmp_path):
    """Every front end reads the typed RunDocument; a saved `run --json` file and a batch result
    (with its case_file/case_hash keys) read with from_json and written again are the same bytes,
    keys in the same order -- the typed layer adds nothing to and drops nothing from the public JSON."""
    from linecheck.batch import run_batch

    js = tmp_path / "r.json"
    res = runner.invoke(app, ["run", str(short_case), "--json", str(js)])
    assert res.exit_code == 0, res.output
    out = tmp_path / "batch"
    assert run_batch([short_case], json_dir=out).exit_code == 0
    for path in (js, out / f"{short_case.stem}.json"):
        text = path.read_text()
        typed = RunDocument.from_json(json.loads(text), source=str(path))
        assert typed.blocks == {}, f"untyped blocks in {path.name}: {sorted(typed.blocks)}"
        again = write_json(tmp_path / f"again-{path.name}", typed)
        assert again.read_text() == text, path.name
    assert typed.batch is not None and typed.batch.case_file == str(short_case)
