"""Design statistics through the service: peak windows, --until, the typed result document."""

from __future__ import annotations

import json

import numpy as np
import pytest

from linecheck import service
from linecheck.core.case import load_case, with_values
from linecheck.core.errors import CaseError
from linecheck.core.results import STATISTICS, compute_statistics
from linecheck.io.document import SCHEMA_VERSION, RunDocument
from linecheck.io.jsonout import run_to_dict

from ..conftest import CASES


def _same_stats(a, b) -> None:
    for s in STATISTICS:
        assert np.array_equal(a.stats.values(s), b.stats.values(s), equal_nan=True), s


@pytest.fixture(scope="module")
def case9():
    return load_case(CASES / "paper" / "case09-single.toml")


@pytest.fixture(scope="module")
def run9(case9):
    return service.run_case(case9, realizations=range(2), spectral_check=False)


def test_peak_window_monotone_and_per_window(case9, run9):
    """Nested windows (30 | 60 | 300 | 600 s of the 600 s record): every longer window's peak is
    the largest of the shorter ones it contains, so the mean GF over windows x realizations
    cannot decrease -- and it must increase strictly on this record."""
    j = run9.tower_index
    dt = case9.analysis.time_step
    assert run9.time.size == 12001  # 600 s at 0.05 s, both ends

    def gf(window_s):
        w = int(round(window_s / dt))
        st = compute_statistics(run9.mean[:, j:j + 1], run9.background[:, :, None], run9.resonant[:, :, None],
                                run9.still_air[j:j + 1], case9.g_yp_L, window=w)
        return st

    gfs = [gf(w) for w in (30.0, 60.0, 300.0, 600.0)]
    assert [g.n_samples for g in gfs] == [40, 20, 4, 2]
    ry = [float(g.GF_QS[:, 0, 1].mean()) for g in gfs]
    dy = [float(g.GF_Dy[:, 0, 1].mean()) for g in gfs]
    assert np.all(np.diff(ry) > 0) and np.all(np.diff(dy) > 0), (ry, dy)
    # the whole-record window is the default
    assert ry[-1] == pytest.approx(float(run9.stats.GF_QS[:, j, 1].mean()), rel=1e-12)
    # end to end: [analysis] peak_window = 60 gives the per-window statistics of the same record
    r60 = service.run_case(with_values(case9, {"analysis.peak_window": 60.0}), realizations=range(2),
                           spectral_check=False)
    assert r60.windows == 10 and r60.stats.n_samples == 20
    np.testing.assert_array_equal(r60.stats.GF_QS[:, j, 1], gfs[1].GF_QS[:, 0, 1])
    doc = run_to_dict(r60)
    assert doc["peak_window"] == 60.0 and doc["windows"] == 10 and doc["realizations"] == 2


def test_peak_window_validation(case9):
    with pytest.raises(CaseError, match="peak_window"):
        with_values(case9, {"analysis.peak_window": 0.1})


def test_until_fast_variant_matches_fixed_run(case9):
    """--until 2 % on the single-span synoptic case: stops below the target, and the result is
    bit-identical to a fixed run of the same count (realization r always has the same turbulence)."""
    res = service.run_until(case9, 0.02, max_realizations=40, spectral_check=False)
    n = int(res.realizations.size)
    assert res.until.reached and res.until.achieved <= 0.02
    assert 2 <= n <= 40
    assert res.realizations.tolist() == list(range(n))
    fixed = service.run_case(case9, realizations=range(n), spectral_check=False)
    _same_stats(res, fixed)
    assert service.relative_standard_error(fixed) == res.until.achieved
    a, b = run_to_dict(res), run_to_dict(fixed)
    assert a["reactions"] == b["reactions"]
    assert a["until"]["target"] == 0.02 and a["until"]["achieved"] == res.until.achieved
    assert "until" not in b


def test_until_stops_at_the_cap(case9):
    res = service.run_until(case9, 1e-6, max_realizations=3, spectral_check=False)
    assert res.realizations.size == 3 and not res.until.reached and res.until.achieved > 1e-6


@pytest.mark.slow
def test_until_one_percent_case09_six():
    """Acceptance: --until 1 % on case09-six stops with se <= 1 % and matches a fixed run."""
    case = load_case(CASES / "paper" / "case09-six.toml")
    res = service.run_until(case, 0.01, max_realizations=200, spectral_check=False)
    n = int(res.realizations.size)
    assert res.until.achieved <= 0.01 and n > case.analysis.realizations
    fixed = service.run_case(case, realizations=range(n), spectral_check=False)
    _same_stats(res, fixed)
    assert run_to_dict(res)["reactions"] == run_to_dict(fixed)["reactions"]


def test_document_keys_roundtrip_and_old_files(run9, tmp_path):
    doc = json.loads(json.dumps(run_to_dict(run9), allow_nan=False))
    assert doc["schema_version"] == SCHEMA_VERSION and doc["realizations"] == 2
    ry = doc["reactions"]["Ry"]
    for s in STATISTICS:
        assert set(ry[s]) >= {"mean", "std", "se", "p05", "p50", "p95"}, s
    assert set(ry["peak_dynamic"]["gumbel"]) == {"location", "scale", "ppcc", "design"}
    assert "gumbel" not in ry["GF_Dy"] and "ci" not in ry["peak_dynamic"]
    for s in ("GF_Dy", "GF_QS", "Cont_R"):
        lo, hi = ry[s]["ci"]
        assert lo < ry[s]["mean"] < hi
    assert ry["dynamic_analysis"] in ("recommended", "inconclusive", None)
    # numbers: se = std / sqrt(n); the Gumbel design value at the median = u + 0.3665 beta
    v = run9.stats.peak_dynamic[:, run9.tower_index, 1]
    assert ry["peak_dynamic"]["mean"] == pytest.approx(v.mean())
    assert ry["peak_dynamic"]["se"] == pytest.approx(np.std(v, ddof=1) / np.sqrt(2))
    g = ry["peak_dynamic"]["gumbel"]
    assert g["design"] == pytest.approx(g["location"] - g["scale"] * np.log(np.log(2.0)))
    # round trip through the typed document
    typed = RunDocument.from_json(doc)
    assert typed.to_json() == doc
    assert typed.reactions["Ry"]["GF_Dy"].mean == ry["GF_Dy"]["mean"]
    # byte for byte, keys in the same order: what a front end reads is what was written
    assert json.dumps(typed.to_json(), indent=2) == json.dumps(doc, indent=2)
    # every block is typed (attribute access for the front ends) ...
    assert typed.still_air.reactions["Ry"] == doc["still_air"]["reactions"]["Ry"]
    assert typed.time_histories.series["Ry"]["R"] == doc["time_histories"]["Ry"]["R"]
    assert typed.spectral is None and "spectral" not in doc  # spectral_check=False (typed: test_cli_outputs)
    code = next(iter(doc["codes"]))
    assert typed.codes[code].towers[0].index == doc["codes"][code]["towers"][0]["index"]
    assert typed.burn_in.seconds == doc["burn_in"]["seconds"] and typed.blocks == {}
    # ... and a key this version does not know passes through, after the typed ones
    d2 = dict(doc, custom={"x": 1})
    assert list(RunDocument.from_json(d2).to_json())[-1] == "custom"
    assert RunDocument.from_json(d2).to_json()["custom"] == {"x": 1}
    # a damaged typed block fails with the regenerate message (exit 2), not a traceback
    with pytest.raises(CaseError, match="incomplete or damaged"):
        RunDocument.from_json(dict(doc, burn_in={"seconds": 1.0}), source="cut.json")
    # an old (pre-issue-18) document fails with a message saying how to regenerate it
    old = {k: v for k, v in doc.items() if k != "schema_version"}
    with pytest.raises(CaseError, match="regenerate it with `linecheck run"):
        RunDocument.from_json(old, source="old.json")
    with pytest.raises(CaseError, match="not a linecheck run result"):
        RunDocument.from_json({"x": 1}, source="x.json")


def test_result_schema_file_is_generated_and_validates(run9):
    """docs/results.schema.json is what tools/make_result_schema.py generates, and the validator
    rejects broken documents (so the suite-wide validation in conftest can fail)."""
    import importlib.util

    from ..conftest import ROOT, _result_schema
    from ..schema_check import errors

    spec = importlib.util.spec_from_file_location("mrs", ROOT / "tools" / "make_result_schema.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert (ROOT / "docs" / "results.schema.json").read_text() == mod.render()
    schema = _result_schema()
    doc = json.loads(json.dumps(run_to_dict(run9)))
    assert errors(doc, schema) == []
    bad = json.loads(json.dumps(doc))
    del bad["reactions"]["Ry"]["GF_Dy"]["ci"]
    bad["reactions"]["Rx"]["dynamic_analysis"] = "maybe"
    bad["towers"][0]["reactions"]["Rz"]["peak_dynamic"]["gumbel"]["ppcc"] = "high"
    errs = errors(bad, schema)
    assert len(errs) == 3, errs


# --------------------------------------------------------------------------- CLI
def _short_case(tmp_path, name="case09-single", realizations=3, duration=60.0):
    import re

    text = (CASES / "paper" / f"{name}.toml").read_text(encoding="utf-8")
    text = re.sub(r"(?m)^\s*(duration|realizations)\s*=.*$", "", text)
    text = text.replace("[analysis]", f"[analysis]\nduration = {duration}\nrealizations = {realizations}", 1)
    p = tmp_path / f"{name}.toml"
    p.write_text(text, encoding="utf-8")
    return p


@pytest.mark.numerics  # bitwise determinism: CI repeats it under another BLAS core type
def test_cli_run_until_and_export_of_old_results(tmp_path):
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    runner = CliRunner(env={"COLUMNS": "250"})
    case = _short_case(tmp_path)
    out = tmp_path / "r.json"
    res = runner.invoke(app, ["run", str(case), "--until", "3%", "--max-realizations", "30", "--no-check",
                              "--json", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads(out.read_text())
    assert doc["until"]["target"] == 0.03 and doc["until"]["achieved"] <= 0.03
    assert f"--until 3 %: {doc['realizations']} realizations" in res.output
    assert "design values at tower 1" in res.output
    fixed = service.run_case(load_case(case), realizations=range(doc["realizations"]), spectral_check=False)
    assert json.loads(json.dumps(run_to_dict(fixed)["reactions"])) == doc["reactions"]  # bit for bit
    bad = runner.invoke(app, ["run", str(case), "--until", "abc"])
    assert bad.exit_code == 2 and "--until" in bad.output and "1%" in bad.output
    # a result saved before the typed document (no schema_version, statistics {"mean", "std"} only)
    old = {k: v for k, v in doc.items() if k not in ("schema_version", "until")}
    old["reactions"] = {r: {s: {"mean": e["mean"], "std": e["std"]} for s, e in blk.items() if isinstance(e, dict)}
                        for r, blk in doc["reactions"].items()}
    (tmp_path / "old.json").write_text(json.dumps(old))
    res = runner.invoke(app, ["export", str(tmp_path / "old.json"), "--excel", str(tmp_path / "o.xlsx")])
    assert res.exit_code == 2, res.output
    assert "schema_version 1" in res.output and "regenerate it with `linecheck run" in res.output
    assert not (tmp_path / "o.xlsx").exists()
    res = runner.invoke(app, ["export", str(out), "--excel", str(tmp_path / "n.xlsx")])
    assert res.exit_code == 0, res.output


def test_excel_summary_design_block(run9, tmp_path):
    """The Summary sheet's design block: R_x, R_y, R_z rows with the Gumbel design peak, the total
    (still air + wind) design reaction, intervals and the flag state, from the JSON values."""
    from openpyxl import load_workbook

    from linecheck.excel.design import HEADERS
    from linecheck.excel.writer import write_workbook

    doc = json.loads(json.dumps(run_to_dict(run9)))
    path = write_workbook([doc], tmp_path / "d.xlsx")
    ws = load_workbook(path)["Summary"]
    rows = [[c for c in r] for r in ws.iter_rows(values_only=True)]
    head = next(i for i, r in enumerate(rows) if "design total\n(kN)" in r)
    cols = {v: k for k, v in enumerate(rows[head]) if v is not None}
    body = {r[cols["Reaction"]]: r for r in rows[head + 1:head + 4]}
    assert set(body) == {"Rx", "Ry", "Rz"}
    for r in ("Rx", "Ry", "Rz"):
        e = doc["reactions"][r]
        assert body[r][cols["design total\n(kN)"]] == pytest.approx(e["peak_dynamic_total"]["gumbel"]["design"] / 1e3)
        assert body[r][cols["design peak\nwind (kN)"]] == pytest.approx(e["peak_dynamic"]["gumbel"]["design"] / 1e3)
        assert body[r][cols["still air\n(kN)"]] == pytest.approx(doc["still_air"]["reactions"][r] / 1e3)
    # each 95 % interval is two numbers (low, high) in the statistic's own format
    for key, mean, low, high in (("GF_Dy", "GF_Dy", "GF_Dy 95 %\nCI low", "GF_Dy 95 %\nCI high"),
                                 ("GF_QS", "GF_QS", "GF_QS 95 %\nCI low", "GF_QS 95 %\nCI high"),
                                 ("Cont_R", "Cont_R\n(%)", "Cont_R 95 %\nCI low (%)", "Cont_R 95 %\nCI high (%)")):
        lo, hi = doc["reactions"]["Ry"][key]["ci"]
        assert body["Ry"][cols[low]] == pytest.approx(lo) and body["Ry"][cols[high]] == pytest.approx(hi)
        mean_fmt = ws.cell(row=head + 3, column=cols[mean] + 1).number_format
        assert ws.cell(row=head + 3, column=cols[low] + 1).number_format == mean_fmt
    assert not any(isinstance(v, str) and v.startswith("[") for r in rows[head + 1:head + 4] for v in r)
    # printing: the print area holds the design block and every note; the notes wrap inside it
    from openpyxl.utils import column_index_from_string, get_column_letter

    area = ws.print_area.split("!")[1].replace("$", "")
    right, bottom = area.split(":")[1].rstrip("0123456789"), int(area.split(":")[1].lstrip("ABCDEFGHIJKLMNOPQRSTUVWXYZ"))
    right_col = column_index_from_string(right)
    assert right_col >= max(cols.values()) + 1 and bottom >= len(rows)
    notes = [r for r in range(1, ws.max_row + 1) if ws.cell(row=r, column=1).style == "lc_note"
             and isinstance(ws.cell(row=r, column=1).value, str)]
    assert len(notes) >= 5
    merged = {str(m) for m in ws.merged_cells.ranges}
    for r in notes:
        assert f"A{r}:{right}{r}" in merged and ws.cell(row=r, column=1).alignment.wrap_text
        width = sum(ws.column_dimensions[get_column_letter(c)].width or 8.43 for c in range(1, right_col + 1))
        lines = ws.row_dimensions[r].height / 12.0
        assert lines * width * 1.1 >= len(ws.cell(row=r, column=1).value)
    for _k, (label, width) in enumerate(HEADERS[:-1]):  # every design column as wide as it asks
        assert ws.column_dimensions[get_column_letter(cols[label] + 1)].width >= width


def test_batch_until_matches_run_until(tmp_path):
    """batch --until: each case stops like run_until and saves the same numbers (one task per case)."""
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    case = _short_case(tmp_path)
    out = tmp_path / "res"
    res = CliRunner(env={"COLUMNS": "250"}).invoke(
        app, ["batch", str(case), "--until", "3%", "--max-realizations", "30", "--jobs", "1", "--json-dir", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / f"{case.stem}.json").read_text())
    ref = service.run_until(load_case(case), 0.03, max_realizations=30)
    assert doc["realizations"] == ref.realizations.size and doc["until"]["achieved"] == ref.until.achieved
    assert doc["reactions"] == json.loads(json.dumps(run_to_dict(ref)["reactions"]))


def test_negative_cont_r_is_explained_in_excel_and_the_tui_figure(run9, tmp_path):
    """A negative mean Cont_R (the dynamic peak below the quasi-static one) gets its "how to read"
    note on the Summary sheet and on the TUI's contributions figure."""
    from openpyxl import load_workbook

    from linecheck.excel.writer import write_workbook
    from linecheck.io.display import HOW_TO_READ_NEGATIVE_CONT_R
    from linecheck.io.document import RunDocument
    from linecheck.tui.figures import contributions

    doc = json.loads(json.dumps(run_to_dict(run9)))
    doc["reactions"]["Ry"]["Cont_R"]["mean"] = -0.05
    texts = [c for r in load_workbook(write_workbook([doc], tmp_path / "r.xlsx"))["Summary"].iter_rows(values_only=True)
             for c in r if isinstance(c, str)]
    assert HOW_TO_READ_NEGATIVE_CONT_R in texts and "How to read" in texts
    fig = contributions([("", RunDocument.from_json(doc))])
    assert any(n.startswith("Cont_R < 0") for n in fig.notes)
    doc["reactions"]["Ry"]["Cont_R"]["mean"] = 0.05
    assert not any(n.startswith("Cont_R < 0") for n in contributions([("", RunDocument.from_json(doc))]).notes)
