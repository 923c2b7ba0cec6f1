"""Hostile result documents and field files (issue "nothing lost, nothing leaked"): names that no
workbook can hold, JSON that cannot be parsed, values outside the result schema, field files that
are not what they claim.  Each is one line with exit code 2 naming the file, or (names) a workbook
that opens."""

from __future__ import annotations

import copy
import dataclasses
import json
import re
import warnings
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from openpyxl import load_workbook
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.case import load_case
from linecheck.core.errors import CaseError
from linecheck.core.wind.mean import load_field_table
from linecheck.excel.cells import clean_text, sheet_name
from linecheck.io.document import RunDocument, json_schema, read_result_file
from linecheck.io.jsonout import run_to_dict
from linecheck.io.schema import first_violation

from ..conftest import CASES

runner = CliRunner()


@pytest.fixture(scope="module")
def doc(tmp_path_factory) -> dict:
    """A downburst result of one realization (case 1, single span: about a second)."""
    case = load_case(CASES / "paper" / "case01-single.toml")
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, realizations=1))
    return json.loads(json.dumps(run_to_dict(service.run_case(case, spectral_check=False))))


def _one_line(res, path: Path) -> str:
    text = res.output.strip()
    assert "\n" not in text, res.output
    assert text.startswith(f"error: {path}: "), text
    assert "internal error" not in text and "Traceback" not in text
    return text


# --------------------------------------------------------------------------- 5. names a workbook cannot hold
HOSTILE_NAME = "bad\x1b[31mname\x00x\u202e\ud800 it's\n\t[a]/b:c*?"


def test_export_of_a_hostile_case_name_writes_a_workbook_that_opens(doc, tmp_path):
    bad = copy.deepcopy(doc)
    bad["case"] = HOSTILE_NAME
    bad["description"] = "desc\x00\x1b\ud800"
    bad["parameters"]["name"] = HOSTILE_NAME
    src = tmp_path / "r.json"  # valid for the schema: only names are hostile
    src.write_text(json.dumps(bad), encoding="utf-8")
    out = tmp_path / "out.xlsx"
    res = runner.invoke(app, ["export", str(src), "--excel", str(out), "--project", "P\x07\x1b"])
    assert res.exit_code == 0, res.output
    with zipfile.ZipFile(out) as z:  # every part is well-formed XML
        for part in z.namelist():
            if part.endswith((".xml", ".rels")):
                ET.fromstring(z.read(part))
        charts = [z.read(n).decode() for n in z.namelist() if n.startswith("xl/charts/")]
    wb = load_workbook(out)
    title = sheet_name(HOSTILE_NAME, set())
    assert title in wb.sheetnames
    assert "\x1b" not in title and "\x00" not in title and "\n" not in title and "\ud800" not in title
    assert "\ufffd" in title
    quoted = "'" + title.replace("'", "''") + "'!"
    assert any(quoted in c for c in charts)  # the chart references name the cleaned sheet
    assert wb[title].print_area is not None
    cells = [c.value for row in wb[title].iter_rows(max_row=3) for c in row if isinstance(c.value, str)]
    assert any(v.startswith("bad\ufffd[31mname\ufffdx\u202e\ufffd it's") for v in cells)


def test_clean_text_keeps_what_xml_holds():
    assert clean_text("a\tb\nc\rd é ∞ \u202e") == "a\tb\nc\rd é ∞ \u202e"
    assert clean_text("\x00\x08\x0b\x1f\ud800\ufffe\uffff") == "\ufffd" * 7
    assert sheet_name("x\ny\tz", set()) == "x y z"
    assert sheet_name("'\x00'", set()) == "\ufffd"


# --------------------------------------------------------------------------- 11. JSON that cannot be parsed
def test_export_of_unparsable_json_is_one_line(doc, tmp_path):
    text = json.dumps(doc)
    # not named .json: the suite validates every result .json a test leaves (conftest)
    huge = tmp_path / "huge.txt"
    huge.write_text(text.replace(f'"seed": {doc["seed"]}', '"seed": ' + "7" * 5001))
    deep = tmp_path / "deep.txt"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    deep_obj = tmp_path / "deep-object.txt"
    deep_obj.write_text('{"a":' * 100_000 + "1" + "}" * 100_000)
    huge_elsewhere = tmp_path / "huge-block.txt"  # in a block the schema does not describe
    huge_elsewhere.write_text(text[:-1] + ', "extra": {"n": ' + "1" * 5001 + "}}")
    expected = {huge: "seed: value (an integer of 5001 digits) is not allowed",
                deep: "arrays or objects nested too deeply to read",
                deep_obj: "arrays or objects nested too deeply to read",
                huge_elsewhere: "extra.n: value (an integer of 5001 digits) is not allowed"}
    for path, message in expected.items():
        res = runner.invoke(app, ["export", str(path), "--excel", str(tmp_path / "o.xlsx")])
        assert res.exit_code == 2, (path, res.output)
        assert message in _one_line(res, path)
        with pytest.raises(CaseError, match=re.escape(str(path))):  # what batch --resume reads through
            d = read_result_file(path)
            RunDocument.from_json(d, source=str(path))
    assert not (tmp_path / "o.xlsx").exists()


def test_batch_resume_reruns_a_result_it_cannot_read(doc, tmp_path):
    """An unreadable saved result (a 5,001-digit integer, 100,000 nested brackets, a value outside
    the schema) is run again like any other damaged result; the batch goes on."""
    text = (CASES / "paper" / "case01-single.toml").read_text()
    text = re.sub(r"(?m)^realizations = .*$", "realizations = 1", text)
    names = ("huge", "badvalue", "deep")
    for name in names:
        (tmp_path / f"{name}.toml").write_text(text)
    results = tmp_path / "results"
    results.mkdir()
    (results / "huge.json").write_text(json.dumps(doc).replace(f'"seed": {doc["seed"]}', '"seed": ' + "7" * 5001))
    (results / "badvalue.json").write_text(json.dumps(dict(doc, realizations=-3)))
    (results / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    res = runner.invoke(app, ["batch", *(str(tmp_path / f"{n}.toml") for n in names), "--json-dir", str(results),
                              "--resume", "-j", "1"])
    assert res.exit_code == 0, res.output
    assert "3 run, 0 skipped, 0 failed" in res.output
    for name in names:
        RunDocument.from_json(json.loads((results / f"{name}.json").read_text()), source=name)


# --------------------------------------------------------------------------- 17. values outside the schema
@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(realizations=-3), "realizations: value -3 is not allowed: expected an integer between 1 and"),
    (lambda d: d.update(schema_version="2"), 'schema_version: value "2" is not allowed: expected 2'),
    (lambda d: d.update(seed=10**400), "seed: value (an integer of 401 digits) is not allowed: expected an integer "
                                       "between 0 and 9223372036854775807"),
    (lambda d: d.update(tower_of_interest=0), "tower_of_interest: value 0 is not allowed: expected an integer >= 1"),
    (lambda d: d["reactions"]["Rx"]["GF_Dy"].update(mean="1.2"),
     'reactions.Rx.GF_Dy.mean: value "1.2" is not allowed: expected a number or null'),
    (lambda d: d["towers"][0].update(index=True), "towers[0].index: value true is not allowed: expected an integer"),
    (lambda d: d["reactions"]["Ry"]["GF_Dy"].pop("ci"), "reactions.Ry.GF_Dy.ci: missing"),
    (lambda d: d["time_histories"]["Rx"]["M"].__setitem__(3, 1e308),
     "time_histories.Rx.M[3]: value 1e+308 is not allowed: expected a finite number of magnitude at most 1e+15"),
    (lambda d: d["parameters"]["line"].update(sag=float("nan")),
     "parameters.line.sag: value NaN is not allowed: expected a finite number"),
])
def test_a_document_outside_its_schema_is_one_line(doc, tmp_path, change, message):
    bad = copy.deepcopy(doc)
    change(bad)
    path = tmp_path / "bad.txt"  # not .json: conftest validates every result .json a test leaves
    path.write_text(json.dumps(bad), encoding="utf-8")
    res = runner.invoke(app, ["export", str(path), "--excel", str(tmp_path / "o.xlsx")])
    assert res.exit_code == 2, res.output
    assert f"error: {path}: {message}" in _one_line(res, path)
    assert not (tmp_path / "o.xlsx").exists()


def test_every_float_1e308_is_refused_without_a_numpy_warning(doc, tmp_path):
    def big(x):
        if isinstance(x, float):
            return 1e308
        if isinstance(x, dict):
            return {k: big(v) for k, v in x.items()}
        if isinstance(x, list):
            return [big(v) for v in x]
        return x

    path = tmp_path / "big.txt"
    path.write_text(json.dumps(big(doc)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = runner.invoke(app, ["export", str(path), "--excel", str(tmp_path / "o.xlsx")])
    assert res.exit_code == 2 and "value 1e+308 is not allowed" in _one_line(res, path)


def test_a_valid_document_and_the_schema_agree(doc):
    schema = json_schema()
    assert first_violation(doc, schema) is None
    assert RunDocument.from_json(doc).to_json() == doc
    old = {k: v for k, v in doc.items() if k != "schema_version"}  # version 1: the regenerate message
    with pytest.raises(CaseError, match="schema_version 1 is not supported"):
        RunDocument.from_json(old, source="old.json")


# --------------------------------------------------------------------------- 12, 16. field files
@pytest.fixture
def field_case(tmp_path):
    """A copy of the user-field example whose field file is ``field.npz`` next to it."""
    table = load_field_table(CASES / "fields" / "example-field.csv")
    text = (CASES / "examples" / "downburst-user-field.toml").read_text()
    case = tmp_path / "user.toml"
    case.write_text(text.replace('"../fields/example-field.csv"', '"field.npz"'))
    return case, table


def _save(path: Path, table, **arrays) -> None:
    data = {"r_over_dj": table.r, "z_over_dj": table.z, "t": table.t, "v_radial": table.radial}
    data.update(arrays)
    np.savez(path, **data)


def test_a_field_file_that_is_not_a_zip_archive(field_case):
    case, _ = field_case
    field = case.with_name("field.npz")
    field.write_bytes(b"PK\x03\x04garbage")
    res = runner.invoke(app, ["check", str(case)])
    assert res.exit_code == 2, res.output
    assert "not a readable NPZ file" in _one_line(res, field)


@pytest.mark.parametrize("name, make, dtype", [
    ("v_radial", lambda a: a + 0.5j, "complex128 (complex numbers)"),
    ("v_radial", lambda a: a.astype(str), "(text)"),
    ("v_radial", lambda a: a > 0, "bool (booleans)"),
    ("r_over_dj", lambda a: a + 0j, "complex128 (complex numbers)"),
    ("t", lambda a: a.astype("m8[s]"), "timedelta64[s] (time spans)"),
])
def test_a_field_array_of_the_wrong_dtype_says_so(field_case, name, make, dtype):
    case, table = field_case
    base = {"r_over_dj": table.r, "t": table.t, "v_radial": table.radial}
    _save(case.with_name("field.npz"), table, **{name: make(base[name])})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning
        res = runner.invoke(app, ["check", str(case)])
    assert res.exit_code == 2, res.output
    line = _one_line(res, case.with_name("field.npz"))
    assert f'array "{name}" has dtype' in line and dtype in line
    assert "expected real numbers (a floating-point array, or integers)" in line


def test_an_integer_field_is_still_accepted(field_case):
    case, table = field_case
    _save(case.with_name("field.npz"), table, v_radial=np.rint(table.radial * 100).astype(np.int64))
    res = runner.invoke(app, ["check", str(case)])
    assert res.exit_code == 0, res.output
