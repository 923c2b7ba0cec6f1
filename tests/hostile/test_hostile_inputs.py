"""Hostile input files: what a tower CSV, a long list or a byte-order mark may not do.

- A tower CSV cell obeys the TOML strings' rule: no control character (ESC, NUL, a quoted
  newline) reaches a name, a terminal or a JSON document.
- ``towers_file`` pointing at a file that is not a tower table (``/etc/shadow``) is refused as
  "not a tower table" without quoting the file's content -- on the terminal and in the batch
  workbook; a column name is quoted only when it is a short printable token of a CSV table.
- Checking a list is linear in its length, and a message names the first bad item (its position
  and value), never the whole list: counted calls of the formatting, not timings.
- A UTF-8 byte-order mark (spreadsheets write one) is accepted in a TOML case and a tower CSV.

Every refusal: exit 2, one line, no traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core import case_geometry, case_load, case_towers, case_validate
from linecheck.core.case import case_hash, load_case
from linecheck.core.errors import CaseError

from ..conftest import CASES, one_error_line

EXAMPLE = CASES / "examples" / "section-12span.toml"
CSV = CASES / "examples" / "section-12span.csv"
SHADOW = "root:*:20228:0:99999:7:::\ndaemon:*:20228:0:99999:7:::\nsecret-user:$6$saltsalt$hashhashhash:20228::::::\n"


def cli(*args: str):
    return CliRunner().invoke(app, list(args))


def section(tmp_path: Path, csv_text: str, *, csv_name: str = "towers.csv", bom: bool = False) -> Path:
    """The 12-span example with its tower table replaced by ``csv_text`` (in ``csv_name``)."""
    toml = EXAMPLE.read_text(encoding="utf-8").replace('towers_file = "section-12span.csv"',
                                                       f'towers_file = "{csv_name}"')
    assert f'towers_file = "{csv_name}"' in toml
    (tmp_path / csv_name).write_text(csv_text, encoding="utf-8", newline="")
    path = tmp_path / "section.toml"
    path.write_text(("\ufeff" if bom else "") + toml, encoding="utf-8")
    return path



def with_first_name(name_cell: str) -> str:
    """The example's tower table with the first tower's name cell replaced (CSV-quoted as given)."""
    lines = CSV.read_text(encoding="utf-8").splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("T1,"))
    lines[k] = name_cell + lines[k][len("T1"):]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- 3. control characters
@pytest.mark.parametrize(("cell", "code"), [("T\x1b[31mred", "U+001B"), ("T\x00one", "U+0000"),
                                            ('"T\none"', "U+000A"), ("T\x7fdel", "U+007F")],
                         ids=["esc", "nul", "quoted-newline", "del"])
def test_control_characters_in_a_tower_csv_are_refused_like_toml_strings(tmp_path, cell, code):
    path = section(tmp_path, with_first_name(cell))
    line = one_error_line(cli("check", str(path)))
    assert f"{tmp_path / 'towers.csv'}: row 3, column name: control character {code} at position 2 is not allowed" \
        in line
    assert "\x1b" not in line and "\x00" not in line
    # the same name inline in TOML is refused by the same rule
    toml_path = tmp_path / "inline.toml"
    toml_path.write_text('name = "x\\u001b"\n[line]\n', encoding="utf-8")
    with pytest.raises(CaseError, match="control character U\\+001B at position 2 is not allowed"):
        load_case(toml_path)


def test_a_tab_and_unicode_in_a_tower_name_stay_allowed(tmp_path):
    path = section(tmp_path, with_first_name("Tö\twer"))
    assert load_case(path).line.towers[0].name == "Tö\twer"


# --------------------------------------------------------------------------- 4. not a tower table
@pytest.mark.parametrize("content", [
    SHADOW,
    "127.0.0.1 localhost\n::1 localhost ip6-localhost\n",  # one cell per row: not a table
    "AKIAIOSFODNN7EXAMPLE,wJalrXUtnFEMI/K7MDENG/bPxRfiCYEXAMPLEKEY\n1,2\n",  # not column names
    "x" * 5000 + ",y\n1,2\n",
    "\x1b]0;title\x07,station\n1,2\n",
], ids=["shadow", "hosts", "key-pair", "long-cell", "escape-in-header"])
def test_a_file_that_is_not_a_tower_table_is_refused_without_its_content(tmp_path, content):
    path = section(tmp_path, content, csv_name="not-towers.csv")
    line = one_error_line(cli("check", str(path)))
    assert f"{tmp_path / 'not-towers.csv'}: not a tower table: expected a comma-separated (CSV) file" in line
    for secret in ("root:", "daemon", "$6$", "localhost", "AKIA", "wJalr", "xxxxxxxx", "title"):
        assert secret not in line, line
    assert len(line) < 400


def test_a_tower_table_with_an_unknown_column_quotes_only_that_token(tmp_path):
    text = CSV.read_text(encoding="utf-8").replace("insulator_length", "insulator_lenght")
    line = one_error_line(cli("check", str(section(tmp_path, text))))
    assert 'unknown column "insulator_lenght"; did you mean "insulator_length"?' in line
    text = CSV.read_text(encoding="utf-8").replace("name,station", "name,Station")
    line = one_error_line(cli("check", str(section(tmp_path, text))))
    assert 'unknown column "Station"; did you mean "station"?' in line


def test_a_long_bad_number_is_described_not_quoted(tmp_path):
    text = CSV.read_text(encoding="utf-8").replace("T3,655,141.0,", "T3,655," + "9" * 30 + "z" * 30 + ",")
    line = one_error_line(cli("check", str(section(tmp_path, text))))
    assert "row 5, column ground: value of 60 characters is not a number" in line and "zzz" not in line


def test_batch_workbook_does_not_quote_a_file_that_is_not_a_tower_table(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    path = section(tmp_path, SHADOW, csv_name="shadow")
    book = tmp_path / "out.xlsx"
    r = CliRunner(env={"COLUMNS": "250"}).invoke(app, ["batch", str(path), "--jobs", "1", "--excel", str(book),
                                                       "--json-dir", str(tmp_path / "res")])
    assert r.exit_code == 1, r.output
    assert "not a tower table" in r.output and "root:" not in r.output and "20228" not in r.output
    wb = openpyxl.load_workbook(book)
    cells = [str(c.value) for ws in wb.worksheets for row in ws.iter_rows() for c in row if c.value is not None]
    assert any("not a tower table" in c for c in cells)
    assert not any(s in c for c in cells for s in ("root:", "daemon", "$6$", "20228"))


# --------------------------------------------------------------------------- 6. long lists
def _synoptic_with_span_speeds(tmp_path: Path, values: list[str]) -> Path:
    text = (CASES / "paper" / "case09-single.toml").read_text(encoding="utf-8")
    assert "[wind]\n" in text
    p = tmp_path / "long.toml"
    p.write_text(text.replace("[wind]\n", f"[wind]\nspan_speeds = [{', '.join(values)}]\n", 1), encoding="utf-8")
    return p


@pytest.fixture
def fmt_calls(monkeypatch):
    """Counts the calls of the message formatting (``case_validate.fmt_value``, wherever the case
    modules call it) while a case is checked."""
    calls = [0]
    real = case_validate.fmt_value

    def counting(value):
        calls[0] += 1
        return real(value)

    for module in (case_validate, case_load, case_geometry, case_towers):
        monkeypatch.setattr(module, "fmt_value", counting)
    return calls


def test_checking_a_long_list_formats_a_bounded_number_of_items(tmp_path, fmt_calls, monkeypatch):
    """10,000 valid entries: each is checked once (linear), the message formatting runs a
    bounded number of times (it ran 10,000 times over the whole list before: quadratic, 135 s),
    and the message (a wrong count for this 1-span line) shows a few items and the length."""
    n = 10_000
    checked = [0]
    real_ok = case_validate._number_ok

    def counting_ok(spec, v):
        checked[0] += 1
        return real_ok(spec, v)

    path = _synoptic_with_span_speeds(tmp_path, ["30.0"] * n)
    monkeypatch.setattr(case_validate, "_number_ok", counting_ok)
    with pytest.raises(CaseError) as info:
        load_case(path)
    msg = str(info.value)
    assert "wind.span_speeds: value [30.0, 30.0, 30.0, 30.0, 30.0, ... (10000 items)] has 10000 entries: " \
           "expected 1, one per span" in msg
    assert len(msg) < 300
    assert n <= checked[0] <= n + 100  # linear: each item once (plus the scalar keys)
    assert fmt_calls[0] <= 20


def test_a_bad_item_of_a_long_list_is_named_by_position_and_value(tmp_path, fmt_calls):
    values = ["30.0"] * 10_000
    values[4999] = "-3.5"
    values[7000] = "true"
    line = one_error_line(cli("check", str(_synoptic_with_span_speeds(tmp_path, values))))
    assert "wind.span_speeds: item 5000 of 10000 (value -3.5) is out of range: expected a list of numbers >= 0" in line
    assert len(line) < 300
    assert fmt_calls[0] <= 5
    values[4999] = '"fast"'
    line = one_error_line(cli("check", str(_synoptic_with_span_speeds(tmp_path, values))))
    assert 'item 5000 of 10000 (value "fast") is not allowed' in line


def test_a_bad_item_of_a_string_list_is_named_by_position(tmp_path):
    text = (CASES / "paper" / "case01-six.toml").read_text(encoding="utf-8")
    text = text.replace('"suspension", "suspension", "strain"]', '"suspension", "suspenzion", "strain"]')
    p = tmp_path / "c.toml"
    p.write_text(text, encoding="utf-8")
    line = one_error_line(cli("check", str(p)))
    assert 'line.supports: item 6 of 7 (value "suspenzion") is not allowed' in line


# --------------------------------------------------------------------------- 15. byte-order mark
def test_a_byte_order_mark_is_accepted_in_a_toml_case_and_a_tower_csv(tmp_path):
    plain = load_case(EXAMPLE)
    path = section(tmp_path, "\ufeff" + CSV.read_text(encoding="utf-8"), bom=True)
    assert path.read_bytes().startswith(b"\xef\xbb\xbf")
    assert (tmp_path / "towers.csv").read_bytes().startswith(b"\xef\xbb\xbf")
    r = cli("check", str(path))
    assert r.exit_code == 0, r.output
    marked = load_case(path)
    assert marked.line.towers == plain.line.towers and marked.name == plain.name
    import hashlib

    assert case_hash(path) == hashlib.sha256(path.read_bytes()).hexdigest()  # the hash is of the bytes, mark included


def test_a_byte_order_mark_in_a_saved_result_is_read_back(tmp_path):
    from linecheck.core.case import MAX_RESULT_BYTES, read_text_file

    p = tmp_path / "r.json"
    p.write_bytes(b"\xef\xbb\xbf" + json.dumps({"a": 1}).encode())
    assert json.loads(read_text_file(p, "a JSON result", MAX_RESULT_BYTES)) == {"a": 1}


# --------------------------------------------------------------------------- 4, 15. the field file too
FIELD_CASE = CASES / "examples" / "downburst-user-field.toml"
FIELD_CSV = CASES / "fields" / "example-field.csv"


def field_case(tmp_path: Path, csv_text: str) -> Path:
    toml = FIELD_CASE.read_text(encoding="utf-8").replace('field = "../fields/example-field.csv"', 'field = "f.csv"')
    assert 'field = "f.csv"' in toml
    (tmp_path / "f.csv").write_text(csv_text, encoding="utf-8")
    path = tmp_path / "user-field.toml"
    path.write_text(toml, encoding="utf-8")
    return path


def test_a_field_file_that_is_not_a_field_table_is_refused_without_its_content(tmp_path):
    line = one_error_line(cli("check", str(field_case(tmp_path, SHADOW))))
    assert f"{tmp_path / 'f.csv'}:1: not a field table: expected a comma-separated (CSV) file" in line
    assert "root:" not in line and "daemon" not in line and "20228" not in line
    # a field table's own unknown column is still named, a long bad value described by its length
    line = one_error_line(cli("check", str(field_case(tmp_path, "r_over_dj,z,t,v_radial\n0,0,0,1\n"))))
    assert 'header column 2 "z" is not allowed' in line
    line = one_error_line(cli("check", str(field_case(tmp_path, "r_over_dj,z_over_dj,t,v_radial\n0,0,0," + "q" * 80))))
    assert "value of 80 characters is not a number" in line and "qqq" not in line


def test_a_byte_order_mark_is_accepted_in_a_field_csv(tmp_path):
    r = cli("check", str(field_case(tmp_path, "\ufeff" + FIELD_CSV.read_text(encoding="utf-8"))))
    assert r.exit_code == 0, r.output


# --------------------------------------------------------------------------- 18. TOML dates in messages
@pytest.mark.parametrize("value, shown", [("1979-05-27T07:32:00Z", "1979-05-27T07:32:00+00:00"),
                                          ("1979-05-27", "1979-05-27"), ("07:32:00", "07:32:00")])
def test_a_toml_date_or_time_is_shown_as_toml_text(tmp_path, value, shown):
    """A date where a number belongs is named in its TOML spelling (RFC 3339), not as a Python
    repr such as datetime.datetime(1979, 5, 27, ...)."""
    text = (CASES / "paper" / "case09-single.toml").read_text().replace("realizations = 10", f"realizations = {value}")
    path = tmp_path / "dated.toml"
    path.write_text(text)
    with pytest.raises(CaseError) as err:
        load_case(path)
    msg = str(err.value)
    assert f"analysis.realizations: value {shown} is not allowed" in msg and "datetime" not in msg
