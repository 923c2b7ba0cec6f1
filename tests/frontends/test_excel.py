"""Excel design sheets: values equal the JSON, charts, title block, templates, safe writing, CLI."""

from __future__ import annotations

import copy
import dataclasses
import datetime as dt
import json
import os
from pathlib import Path

import pytest
from openpyxl import Workbook, load_workbook
from openpyxl.workbook.defined_name import DefinedName
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.case import case_to_toml, load_case
from linecheck.core.errors import CaseError
from linecheck.excel import template as tpl
from linecheck.excel.writer import (
    FLAG_NOTE,
    SUMMARY_REACTIONS,
    chart_indices,
    load_result_docs,
    sheet_name,
    write_workbook,
)
from linecheck.io.jsonout import run_to_dict, write_json

from ..conftest import CASES

REACTIONS = ("Rx", "Ry", "Rz")
TITLE = {"project": "Line 7 upgrade", "line": "230 kV Aldon-Brix", "section": "T12-T18",
         "engineer": "A. Engineer", "checked_by": "B. Checker", "date": "2026-01-15", "revision": "B"}


def _short(path: Path, **analysis):
    case = load_case(path)
    return dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, **analysis))


@pytest.fixture(scope="module")
def docs() -> list[dict]:
    """Real run results: a synoptic case (with its spectral block), a downburst case, one realization."""
    cases = [
        _short(CASES / "paper" / "case09-single.toml", duration=60.0, realizations=2),
        _short(CASES / "paper" / "case05-single.toml", realizations=2, mean_states=40),
        _short(CASES / "paper" / "case11-single.toml", duration=60.0, realizations=1),
    ]
    return [run_to_dict(service.run_case(c)) for c in cases]


def _crop(doc: dict, n: int) -> dict:
    """A copy of ``doc`` with its time histories cut to the first ``n`` samples (faster workbooks)."""
    out = copy.deepcopy(doc)
    th = out["time_histories"]
    th["time"] = th["time"][:n]
    for r in REACTIONS:
        th[r] = {k: v[:n] for k, v in th[r].items()}
    return out


@pytest.fixture(scope="module")
def light(docs) -> list[dict]:
    """The same results with short time histories, for tests that are not about the charts."""
    return [_crop(d, 200) for d in docs]


@pytest.fixture(scope="module")
def book(docs, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("xl") / "design.xlsx"
    failed = {"case": "case-broken", "error": "cases/broken.toml: line.sag: value -1.0 is out of range"}
    write_workbook(docs + [failed], path, title=TITLE)
    return path


def _summary_table(wb):
    """Header list and rows (as dicts of the unique headers, plus "_cells": the row as a list)."""
    ws, cell = tpl.destination(wb, tpl.SUMMARY_ANCHOR)
    top, left = ws[cell].row, ws[cell].column
    return _table_at(ws, top, left)


def _table_at(ws, top, left):
    headers = []
    c = left
    while ws.cell(row=top, column=c).value is not None:
        headers.append(ws.cell(row=top, column=c).value)
        c += 1
    rows = []
    r = top + 1
    while ws.cell(row=r, column=left).value is not None:
        cells = [ws.cell(row=r, column=left + k).value for k in range(len(headers))]
        row = {h: v for h, v in zip(headers, cells) if h != "±"}
        row["_cells"] = cells
        rows.append(row)
        r += 1
    return ws, headers, rows


KN = 1e-3
# headers: the short label and unit of the one statistics table (linecheck.io.document.STAT_TABLE)
STAT_COLS = {"mean M\n(kN)": ("mean_max", KN), "peak QS\n(kN)": ("peak_quasi_static", KN),
             "peak Dy\n(kN)": ("peak_dynamic", KN), "GF_Dy": ("GF_Dy", None), "GF_QS": ("GF_QS", None),
             "Cont_M\n(%)": ("Cont_M", 1.0), "Cont_BG\n(%)": ("Cont_BG", 1.0), "Cont_R\n(%)": ("Cont_R", 1.0),
             "peak / g*yp Lx": ("peak_normalised", 1.0)}


def _conv(value, scale, stat):
    if value is None:
        return "**" if stat.startswith("GF") else None
    return same(value * KN if scale == KN else value)


def same(x):
    """Equal as Excel stores it: openpyxl writes numbers with 16 significant digits (Excel shows 15)."""
    return pytest.approx(x, rel=1e-15, abs=0.0)


def test_summary_values_equal_json(docs, book):
    wb = load_workbook(book)
    _, headers, rows = _summary_table(wb)
    assert set(STAT_COLS) <= set(headers)
    by_case = {d["case"]: d for d in docs}
    checked = 0
    for row in rows:
        if row["Case"] == "case-broken":
            assert row["Note"].startswith("FAILED: ") and "line.sag" in row["Note"]
            continue
        doc = by_case[row["Case"]]
        assert row["Wind"].startswith(doc["wind"])
        assert row["Spans"] == doc["spans"] and row["L_x\n(m)"] == doc["span_length"]
        assert row["V_ref\n(m/s)"] == doc["v_ref"] and row["n"] == doc["realizations"]
        assert row["Tower"] == doc["tower_of_interest"]
        block = doc["reactions"][row["Reaction"]]
        cells = row["_cells"]
        for k, h in enumerate(headers):
            if h not in STAT_COLS:
                continue
            stat, scale = STAT_COLS[h]
            assert cells[k] == _conv(block[stat]["mean"], scale, stat), (row["Case"], row["Reaction"], stat)
            if k + 1 < len(headers) and headers[k + 1] == "±":  # the std column after the statistic
                std = block[stat]["std"]
                want = _conv(std, scale, "std") if doc["realizations"] > 1 else None
                assert cells[k + 1] == want, (row["Case"], row["Reaction"], stat, "std")
            checked += 1
        flagged = block["dynamic_analysis"] == "recommended"  # flagged where the 95 % interval of Cont_R lies above 10 %
        assert (row["Note"] == FLAG_NOTE) == flagged
    assert checked == len(docs) * len(SUMMARY_REACTIONS) * len(STAT_COLS)
    assert headers.count("±") == 8  # every statistic but mean_max (realizations > 1 present)
    assert [r["Case"] for r in rows].count("case-broken") == 1
    assert [r["Reaction"] for r in rows[:2]] == ["Rx", "Ry"]  # the paper's Table 5 reactions
    assert len(rows) == len(SUMMARY_REACTIONS) * len(docs) + 1


def test_summary_with_rz_rows(light, tmp_path):
    path = write_workbook(light, tmp_path / "rz.xlsx", reactions=("Rx", "Ry", "Rz"))
    _, _headers, rows = _summary_table(load_workbook(path))
    assert [r["Reaction"] for r in rows] == ["Rx", "Ry", "Rz"] * len(light)
    for row in rows:
        doc = next(d for d in light if d["case"] == row["Case"])
        assert row["peak Dy\n(kN)"] == same(doc["reactions"][row["Reaction"]]["peak_dynamic"]["mean"] / 1000.0)
    with pytest.raises(CaseError, match="expected some of Rx, Ry, Rz"):
        write_workbook(light, tmp_path / "bad.xlsx", reactions=("Ry", "Mz"))


def test_summary_format_and_flags(book):
    wb = load_workbook(book)
    ws, headers, _rows = _summary_table(wb)
    top = ws[tpl.destination(wb, tpl.SUMMARY_ANCHOR)[1]].row
    assert ws.freeze_panes == f"B{top + 1}"
    col = headers.index("Cont_R\n(%)") + 1
    letter = ws.cell(row=1, column=col).column_letter
    assert ws.cell(row=top + 1, column=col).number_format == "0.00%"
    assert ws.cell(row=top + 1, column=headers.index("peak Dy\n(kN)") + 1).number_format == "#,##0.00"
    rules = [(str(rng.sqref), rule) for rng in ws.conditional_formatting for rule in rng.rules]
    assert any(ref.startswith(letter) and rule.operator == "greaterThan" and rule.formula == ["0.1"]
               for ref, rule in rules)
    assert ws.print_area and ws.page_setup.fitToWidth == 1
    # no formulas anywhere: numbers and text only
    for sheet in wb.worksheets:
        for row in sheet.iter_rows():
            for c in row:
                assert not (isinstance(c.value, str) and c.value.startswith("=")), (sheet.title, c.coordinate)


def test_threshold_changes_flags(light, tmp_path):
    path = tmp_path / "t.xlsx"
    write_workbook(light, path, cont_r_threshold=0.001)
    _, _, rows = _summary_table(load_workbook(path))
    from linecheck.io.display import flag_state
    from linecheck.io.document import RunDocument

    typed = [RunDocument.from_json(d) for d in light]
    want = sum(1 for d in typed for r in SUMMARY_REACTIONS if flag_state(d, r, 0.001) == "recommended")
    assert want > 0  # the rule is recomputed at the threshold from the intervals
    assert sum(1 for r in rows if r["Note"] == FLAG_NOTE) == want
    ws = load_workbook(path)["Summary"]
    assert any(rule.formula == ["0.001"] for rng in ws.conditional_formatting for rule in rng.rules)


def test_case_sheets_have_charts_and_tables(docs, book):
    wb = load_workbook(book)
    assert "Peaks" in wb.sheetnames
    assert [type(c).__name__ for c in wb["Peaks"]._charts] == ["BarChart"]
    assert "case-broken" not in wb.sheetnames
    for doc in docs:
        ws = wb[doc["case"]]
        kinds = [type(c).__name__ for c in ws._charts]
        assert kinds == ["ScatterChart", "ScatterChart", "ScatterChart", "BarChart"], doc["case"]
        assert ws.freeze_panes == "A4" and ws.print_area
        text = {c.value for row in ws.iter_rows(max_col=8) for c in row if isinstance(c.value, str)}
        assert "Inputs (case parameters)" in text
        assert any(t.startswith("Still-air state") for t in text)
        assert any(t.startswith("Step 1: mean state") for t in text)
        assert any(t.startswith("Statistics at tower") for t in text)
        assert {"span_length", "v_ref", "elastic_modulus", "realizations"} <= text
        spectral = any(t.startswith("Spectral check: frequency domain") for t in text)
        assert spectral == ("spectral" in doc)


def test_case_sheet_statistics_equal_json(docs, book):
    wb = load_workbook(book)
    for doc in docs:
        ws = wb[doc["case"]]
        start = next(c.row for c in ws["A"] if isinstance(c.value, str) and c.value.startswith("Statistics at"))
        rows = {ws.cell(row=r, column=1).value: r for r in range(start + 2, start + 17)}
        for stat, r in rows.items():
            for k, rn in enumerate(REACTIONS):
                want = doc["reactions"][rn][stat]["mean"]
                got = ws.cell(row=r, column=3 + 2 * k).value
                if want is None:
                    assert got in ("**", None)
                elif ws.cell(row=r, column=2).value == "kN":
                    assert got == same(want / 1000.0)
                else:
                    assert got == same(want)


def test_spectral_block_values(docs, book):
    doc = next(d for d in docs if "spectral" in d)
    ws = load_workbook(book)[doc["case"]]
    row = next(c.row for c in ws["A"] if c.value == "rms_background" and ws.cell(row=c.row, column=2).value == "kN"
               and ws.cell(row=c.row - 1, column=1).value.startswith("mean (time"))
    for k, r in enumerate(REACTIONS):
        assert ws.cell(row=row, column=3 + k).value == same(doc["spectral"]["exact"][r]["rms_background"] / 1000.0)


def test_title_block_defined_names_filled(book):
    wb = load_workbook(book)
    for name in tpl.TITLE_NAMES:
        ws, cell = tpl.destination(wb, name)
        value = ws[cell].value
        if name == "units_note":
            assert value == tpl.DEFAULT_UNITS_NOTE
        else:
            assert value == TITLE[name], name


def test_date_defaults_to_today(light, tmp_path):
    path = write_workbook(light[:1], tmp_path / "d.xlsx")
    wb = load_workbook(path)
    ws, cell = tpl.destination(wb, "date")
    assert ws[cell].value.date() == dt.date.today()


def _user_template(path: Path, *, drop: str | None = None) -> Path:
    """A re-styled template: title block on a "Cover" sheet at other cells, sheet-scoped and workbook names."""
    wb = Workbook()
    cover = wb.active
    cover.title = "Cover"
    cover["A1"] = "ACME Power: conductor design sheet"
    for k, name in enumerate(tpl.TITLE_NAMES):
        cover.cell(row=10 + 2 * k, column=3, value=name.upper())
        if name == drop:
            continue
        ref = f"Cover!$E${10 + 2 * k}:$G${10 + 2 * k}"
        cover.merge_cells(f"E{10 + 2 * k}:G{10 + 2 * k}")
        if name == "revision":  # sheet-scoped name
            cover.defined_names[name] = DefinedName(name, attr_text=ref)
        else:
            wb.defined_names[name] = DefinedName(name, attr_text=ref)
    notes = wb.create_sheet("Notes")
    notes["A1"] = "keep me"
    wb.save(path)
    return path


def test_user_template_with_moved_cells_is_filled(light, tmp_path):
    template = _user_template(tmp_path / "acme.xlsx")
    out = write_workbook(light, tmp_path / "acme-out.xlsx", template=template, title=TITLE)
    wb = load_workbook(out)
    cover = wb["Cover"]
    for k, name in enumerate(tpl.TITLE_NAMES):
        value = cover.cell(row=10 + 2 * k, column=5).value
        assert value == (TITLE[name] if name != "units_note" else tpl.DEFAULT_UNITS_NOTE), name
    assert cover["A1"].value == "ACME Power: conductor design sheet"
    assert wb["Notes"]["A1"].value == "keep me"
    assert "Summary" in wb.sheetnames and "Peaks" in wb.sheetnames
    ws = wb["Summary"]
    top = next(c.row for c in ws["A"] if c.value == "Case")
    _, _headers, rows = _table_at(ws, top, 1)
    assert len(rows) == len(SUMMARY_REACTIONS) * len(light)
    assert rows[0]["peak Dy\n(kN)"] == same(light[0]["reactions"]["Rx"]["peak_dynamic"]["mean"] / 1000.0)
    for d in light:
        assert d["case"] in wb.sheetnames and len(wb[d["case"]]._charts) == 4


def test_template_missing_names_is_a_clear_error(light, tmp_path):
    template = _user_template(tmp_path / "bad.xlsx", drop="checked_by")
    with pytest.raises(CaseError, match=r"bad\.xlsx: template lacks the defined name\(s\) checked_by"):
        write_workbook(light, tmp_path / "x.xlsx", template=template)
    assert not (tmp_path / "x.xlsx").exists()
    (tmp_path / "junk.xlsx").write_text("not a workbook")
    with pytest.raises(CaseError, match="cannot read template"):
        write_workbook(light, tmp_path / "x.xlsx", template=tmp_path / "junk.xlsx")


def test_default_template_file_is_current():
    """templates/design_sheet.xlsx is what templates/make_template.py builds."""
    assert tpl.DEFAULT_TEMPLATE.is_file()
    committed = load_workbook(tpl.DEFAULT_TEMPLATE)
    built = tpl.build_default_template()
    for name in (*tpl.TITLE_NAMES, tpl.SUMMARY_ANCHOR):
        assert list(committed.defined_names[name].destinations) == list(built.defined_names[name].destinations)
    assert set(tpl.STYLE_NAMES) <= set(committed.style_names)


# --------------------------------------------------------------------------- safe writing
def test_existing_file_needs_force(light, tmp_path):
    path = tmp_path / "keep.xlsx"
    path.write_bytes(b"old workbook")
    with pytest.raises(CaseError, match="exists; use --force"):
        write_workbook(light, path)
    assert path.read_bytes() == b"old workbook"
    write_workbook(light, path, force=True)
    assert load_workbook(path)["Summary"] is not None


def test_write_failure_leaves_nothing_half_written(light, tmp_path, monkeypatch):
    path = tmp_path / "keep.xlsx"
    path.write_bytes(b"old workbook")


    def boom(src, dst):  # the disk fills up as the finished file is moved into place
        Path(src).write_bytes(b"partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("linecheck.io.atomic.os.replace", boom)
    with pytest.raises(CaseError, match="cannot write Excel file: no space left on device"):
        write_workbook(light, path, force=True)
    assert path.read_bytes() == b"old workbook"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.xlsx"]


def test_unwritable_or_missing_folder(light, tmp_path):
    with pytest.raises(CaseError, match="does not exist"):
        write_workbook(light, tmp_path / "nope" / "x.xlsx")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(CaseError, match="cannot write Excel file|not writable"):
        write_workbook(light, blocker / "x.xlsx")


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root ignores folder permissions")
def test_read_only_folder(light, tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        with pytest.raises(CaseError, match="not writable"):
            write_workbook(light, ro / "x.xlsx")
    finally:
        ro.chmod(0o700)


def test_locked_file_and_bad_suffix(light, tmp_path):
    (tmp_path / "~$open.xlsx").write_text("lock")
    with pytest.raises(CaseError, match="open in another program"):
        write_workbook(light, tmp_path / "open.xlsx", force=True)
    with pytest.raises(CaseError, match=r"\.xlsx file name"):
        write_workbook(light, tmp_path / "x.xls")


def test_bad_threshold_and_title(light, tmp_path):
    for bad in (0.0, 1.5, -0.1):
        with pytest.raises(CaseError, match="cont-r-threshold"):
            write_workbook(light, tmp_path / "x.xlsx", cont_r_threshold=bad)
    with pytest.raises(CaseError, match="unknown title field 'projekt'"):
        write_workbook(light, tmp_path / "x.xlsx", title={"projekt": "x"})
    assert not (tmp_path / "x.xlsx").exists()


def test_new_file_is_not_private(light, tmp_path):
    path = write_workbook(light[:1], tmp_path / "m.xlsx")
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


# --------------------------------------------------------------------------- histories
def test_chart_thinning_keeps_extremes():
    import numpy as np

    rng = np.random.default_rng(1)
    cols = [rng.standard_normal(20000), np.cumsum(rng.standard_normal(20000))]
    idx = chart_indices(cols, 1000)
    assert idx.size <= 1002 and idx[0] == 0 and idx[-1] == 19999
    for c in cols:
        assert c[idx].max() == c.max() and c[idx].min() == c.min()


def _data_rows(ws) -> int:
    col = next(c.column for c in ws[3] if c.value == "t (s)")
    n = 0
    while ws.cell(row=4 + n, column=col).value is not None:
        n += 1
    return n


def test_histories_thinned_unless_full(docs, tmp_path):
    doc = _crop(next(d for d in docs if d["wind"] == "downburst"), 2500)
    n = len(doc["time_histories"]["time"])
    assert doc["time_histories"]["decimated"] and n == 2500
    path = write_workbook([doc], tmp_path / "thin.xlsx", chart_points=400)
    assert _data_rows(load_workbook(path)[doc["case"]]) <= 402
    full = copy.deepcopy(doc)
    full["time_histories"]["decimated"] = False  # as saved with --full-histories
    path = write_workbook([full], tmp_path / "full.xlsx", chart_points=400)
    assert _data_rows(load_workbook(path)[doc["case"]]) == n


def test_missing_optional_blocks(light, tmp_path):
    """A minimal result (no histories, static, parameters, spectral, codes: the schema's required
    keys only) still gives a sheet."""
    from linecheck.io.document import HEADER_FIELDS

    doc = {k: v for k, v in light[0].items() if k in {h for h, _ in HEADER_FIELDS} | {"reactions", "towers"}}
    path = write_workbook([doc], tmp_path / "min.xlsx")
    wb = load_workbook(path)
    assert [type(c).__name__ for c in wb[doc["case"]]._charts] == ["BarChart"]


def test_sheet_names():
    taken: set[str] = set()
    assert sheet_name("a/b:c*?", taken) == "a_b_c__"
    assert sheet_name("A/b:c*?", taken) == "A_b_c__ (2)"
    assert sheet_name("Summary", taken) == "Summary (2)"
    long = sheet_name("x" * 40, taken)
    assert len(long) == 31 and len(sheet_name("x" * 40, taken)) == 31


def test_load_result_docs_errors(tmp_path, light):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(CaseError, match=r"bad\.json: invalid JSON at line 1"):
        load_result_docs([bad])
    static = tmp_path / "static.json"
    static.write_text(json.dumps({"case": "x", "towers": [], "spans": []}))
    with pytest.raises(CaseError, match="step-1 \\(static\\) result"):
        load_result_docs([static])
    both = tmp_path / "both.json"
    both.write_text(json.dumps(light[:2]))
    loaded = load_result_docs([both])  # typed documents, byte for byte the saved JSON
    assert [d.case for d in loaded] == [d["case"] for d in light[:2]]
    assert json.dumps([d.to_json() for d in loaded]) == json.dumps(light[:2])


# --------------------------------------------------------------------------- CLI
runner = CliRunner()


def _values(path: Path) -> dict:
    wb = load_workbook(path)
    return {ws.title: [[c.value for c in row] for row in ws.iter_rows()] for ws in wb.worksheets}


@pytest.fixture(scope="module")
def short_case_file(tmp_path_factory) -> Path:
    case = _short(CASES / "paper" / "case10-single.toml", duration=60.0, realizations=2)
    path = tmp_path_factory.mktemp("case") / "case10-short.toml"
    path.write_text(case_to_toml(case), encoding="utf-8")
    return path


def test_cli_run_excel_equals_export_from_json(short_case_file, tmp_path):
    js, xl, xl2 = tmp_path / "r.json", tmp_path / "run.xlsx", tmp_path / "export.xlsx"
    res = runner.invoke(app, ["run", str(short_case_file), "--json", str(js), "--excel", str(xl)])
    assert res.exit_code == 0, res.output
    assert f"wrote {xl}" in res.output
    res = runner.invoke(app, ["export", str(js), "--excel", str(xl2)])
    assert res.exit_code == 0, res.output
    assert _values(xl) == _values(xl2)
    doc = json.loads(js.read_text())
    _, _, rows = _summary_table(load_workbook(xl2))
    assert rows[0]["peak Dy\n(kN)"] == same(doc["reactions"]["Rx"]["peak_dynamic"]["mean"] / 1000.0)


def test_cli_run_checks_excel_target_before_running(short_case_file, tmp_path, monkeypatch):
    old = tmp_path / "old.xlsx"
    old.write_bytes(b"old")
    called = []
    monkeypatch.setattr(service, "run_case", lambda *a, **k: called.append(1))
    res = runner.invoke(app, ["run", str(short_case_file), "--excel", str(old)])
    assert res.exit_code == 2
    assert not called
    assert old.read_bytes() == b"old"
    res = runner.invoke(app, ["run", str(short_case_file), "--excel", str(tmp_path / "x.xlsx"),
                              "--template", str(tmp_path / "missing.xlsx")])
    assert res.exit_code == 2 and not called
    assert "template file not found" in res.output


def test_cli_export_existing_file_without_force(light, tmp_path):
    js = tmp_path / "a.json"
    write_json(js, light[0])
    out = tmp_path / "out.xlsx"
    out.write_bytes(b"precious")
    res = runner.invoke(app, ["export", str(js), "--excel", str(out)])
    assert res.exit_code == 2
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "use --force" in lines[0]
    assert out.read_bytes() == b"precious"
    res = runner.invoke(app, ["export", str(js), "--excel", str(out), "--force",
                              "--title", "project=Line 7", "--cont-r-threshold", "0.05"])
    assert res.exit_code == 0, res.output
    wb = load_workbook(out)
    ws, cell = tpl.destination(wb, "project")
    assert ws[cell].value == "Line 7"


def test_cli_export_errors(light, tmp_path):
    js = tmp_path / "a.json"
    write_json(js, light[0])
    cases = [
        (["export", str(tmp_path / "missing.json"), "--excel", str(tmp_path / "o.xlsx")], "file not found"),
        (["export", str(js), "--excel", str(tmp_path / "no" / "o.xlsx")], "does not exist"),
        (["export", str(js), "--excel", str(tmp_path / "o.xlsx"), "--cont-r-threshold", "10"], "between 0 and 1"),
        (["export", str(js), "--excel", str(tmp_path / "o.xlsx"), "--title", "project"], "KEY=VALUE"),
    ]
    for args, msg in cases:
        res = runner.invoke(app, args)
        assert res.exit_code == 2, args
        assert msg in res.output
    assert not (tmp_path / "o.xlsx").exists()


def test_same_case_twice_gets_two_sheets(light, tmp_path):
    path = write_workbook([light[0], light[0]], tmp_path / "twice.xlsx")
    wb = load_workbook(path)
    name = light[0]["case"]
    assert name in wb.sheetnames and f"{name} (2)" in wb.sheetnames
    ws, cell = tpl.destination(wb, tpl.SUMMARY_ANCHOR)
    top = ws[cell].row
    links = [ws.cell(row=top + 1 + k, column=1).hyperlink.location for k in range(2 * len(SUMMARY_REACTIONS))]
    assert links == [f"'{name}'!A1"] * len(SUMMARY_REACTIONS) + [f"'{name} (2)'!A1"] * len(SUMMARY_REACTIONS)
