"""Outputs that must not destroy anything (issue "nothing lost, nothing leaked"): an output that is
an input or another output is refused before any work; a symbolic link, a device or a FIFO is not
replaced by a regular file; messages are one line with hidden characters escaped; a successful
command writes nothing to stderr; an empty path says so."""

from __future__ import annotations

import os
import shutil
import socket
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.errors import CaseError, printable
from linecheck.io.atomic import write_text_atomic
from linecheck.io.outputs import check_outputs, same_file

from ..conftest import CASES, ROOT

runner = CliRunner()
PAPER = CASES / "paper" / "case01-single.toml"


def _one_line(res) -> str:
    """The whole output of a refused command: one ``error:`` line, no traceback."""
    text = res.output.strip()
    assert "\n" not in text, res.output
    assert text.startswith("error:") and "internal error" not in text and "Traceback" not in text, text
    return text


@pytest.fixture
def no_work(monkeypatch):
    """Every computing entry point of the commands fails the test if reached."""
    import linecheck.batch as batch
    import linecheck.excel.writer as writer

    def computed(*_a, **_k):
        raise AssertionError("the command computed before refusing its outputs")

    for name in ("run_case", "run_models", "run_until", "static_analysis", "modes_analysis", "spectral_analysis",
                 "code_loads", "check_budget"):
        monkeypatch.setattr(service, name, computed)
    for name in ("run_batch", "run_scan"):
        monkeypatch.setattr(batch, name, computed)
    monkeypatch.setattr(writer, "load_result_docs", computed)
    monkeypatch.setattr(writer, "write_workbook", computed)


@pytest.fixture
def case(tmp_path) -> Path:
    p = tmp_path / "base.toml"
    shutil.copy(PAPER, p)
    return p


# --------------------------------------------------------------------------- 1. an output is an input
@pytest.mark.parametrize("args", [
    ["run", "{case}", "-n", "1", "--json", "{case}"],
    ["static", "{case}", "--json", "{case}"],
    ["modes", "{case}", "--json", "{case}"],
    ["spectral", "{case}", "--json", "{case}"],
    ["codes", "{case}", "--json", "{case}"],
    ["wind", "{case}", "--csv", "{case}"],
    ["wind", "{case}", "--json", "{case}"],
    ["wind", "{case}", "--field", "{case}"],
    ["scan", "{case}", "--csv", "{case}"],
    ["wind", "{case}", "--csv", "{link}"],  # a symbolic link to the case
    ["static", "{case}", "--json", "{hard}"],  # a hard link to the case
    ["static", "{case}", "--json", "{dotted}"],  # another spelling of the same path
])
def test_an_output_that_is_the_case_file_is_refused_before_computing(args, case, no_work):
    before = case.read_bytes()
    link, hard = case.with_name("link.toml"), case.with_name("hard.toml")
    link.symlink_to(case.name)
    os.link(case, hard)
    dotted = f"{case.parent}/sub/../{case.name}"
    argv = [a.format(case=case, link=link, hard=hard, dotted=dotted) for a in args]
    res = runner.invoke(app, argv)
    assert res.exit_code == 2, res.output
    assert "would overwrite the case file, an input of this command" in _one_line(res)
    assert case.read_bytes() == before and os.path.islink(link) and hard.read_bytes() == before
    assert sorted(p.name for p in case.parent.iterdir()) == ["base.toml", "hard.toml", "link.toml"]


def test_the_tower_table_and_the_field_file_are_inputs(tmp_path, no_work):
    for name in ("section-12span.toml", "section-12span.csv"):
        shutil.copy(CASES / "examples" / name, tmp_path / name)
    table = tmp_path / "section-12span.csv"
    before = table.read_bytes()
    res = runner.invoke(app, ["run", str(tmp_path / "section-12span.toml"), "--json", str(table)])
    assert res.exit_code == 2 and "would overwrite the tower table (line.towers_file)" in _one_line(res)
    assert table.read_bytes() == before

    (tmp_path / "fields").mkdir()
    shutil.copy(CASES / "fields" / "example-field.csv", tmp_path / "fields" / "example-field.csv")
    shutil.copy(CASES / "examples" / "downburst-user-field.toml", tmp_path / "user.toml")
    (tmp_path / "user.toml").write_text((tmp_path / "user.toml").read_text().replace(
        '"../fields/example-field.csv"', '"fields/example-field.csv"'))
    field = tmp_path / "fields" / "example-field.csv"
    before = field.read_bytes()
    res = runner.invoke(app, ["wind", str(tmp_path / "user.toml"), "--csv", str(field)])
    assert res.exit_code == 2 and "would overwrite the field file (wind.downburst.field)" in _one_line(res)
    assert field.read_bytes() == before


@pytest.mark.parametrize("args, first, second", [
    (["run", "{case}", "--json", "{d}/out.xlsx", "--excel", "{d}/out.xlsx"], "--json", "--excel"),
    (["wind", "{case}", "--csv", "{d}/w.out", "--json", "{d}/w.out"], "--csv", "--json"),
    (["wind", "{case}", "--json", "{d}/w.out", "--field", "{d}/./w.out"], "--json", "--field"),
    (["validate", "--json", "{d}/v.md", "--markdown", "{d}/v.md"], "--json", "--markdown"),
])
def test_one_path_for_two_outputs_is_refused(args, first, second, case, no_work, monkeypatch):
    import linecheck.validation as validation

    monkeypatch.setattr(validation, "run_validation", lambda **_k: pytest.fail("validated before refusing"))
    argv = [a.format(case=case, d=case.parent) for a in args]
    res = runner.invoke(app, argv)
    assert res.exit_code == 2, res.output
    assert f"the same file is given for {first} and {second}" in _one_line(res)
    assert sorted(p.name for p in case.parent.iterdir()) == ["base.toml"]  # nothing written


def test_export_and_batch_refuse_to_overwrite_their_inputs(case, no_work):
    folder = case.parent
    template = folder / "template.xlsx"
    shutil.copy(ROOT / "templates" / "design_sheet.xlsx", template)
    result = folder / "saved.xlsx"  # a result JSON under a workbook's name
    result.write_text("{}")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    cases = [
        (["export", str(result), "--excel", str(result), "--force"], "--excel would overwrite the result file"),
        (["export", str(result), "--excel", str(template), "--template", str(template), "--force"],
         "--excel would overwrite the template"),
        (["run", str(case), "--excel", str(template), "--template", str(template), "--force"],
         "--excel would overwrite the template"),
        (["batch", str(case), "--excel", str(template), "--template", str(template), "--force"],
         "--excel would overwrite the template"),
    ]
    for argv, message in cases:
        res = runner.invoke(app, argv)
        assert res.exit_code == 2, (argv, res.output)
        assert message in _one_line(res), argv
    # a batch whose per-case JSON result would be one of its inputs (a tower table named .json)
    for name in ("section-12span.toml", "section-12span.csv"):
        shutil.copy(CASES / "examples" / name, folder / name)
    sec = folder / "sec.toml"
    sec.write_text((folder / "section-12span.toml").read_text().replace('"section-12span.csv"', '"sec.json"'))
    shutil.copy(folder / "section-12span.csv", folder / "sec.json")
    res = runner.invoke(app, ["batch", str(sec), "--json-dir", str(folder)])
    assert res.exit_code == 2, res.output
    assert "result sec.json in --json-dir would overwrite the tower table" in _one_line(res)
    assert (folder / "sec.json").read_bytes() == (folder / "section-12span.csv").read_bytes()
    assert all((folder / n).read_bytes() == b for n, b in before.items())


def test_same_file_and_check_outputs(tmp_path):
    a = tmp_path / "a.txt"
    a.write_text("x")
    (tmp_path / "l.txt").symlink_to("a.txt")
    assert same_file(a, tmp_path / "l.txt") and same_file(a, tmp_path / "sub" / ".." / "a.txt")
    assert not same_file(a, tmp_path / "b.txt")
    check_outputs([("--json", tmp_path / "x.json"), ("--csv", tmp_path / "x.csv"), ("--excel", None)],
                  [("case file", a), ("template", None)])
    # a device takes several outputs: nothing is replaced there
    check_outputs([("--json", "/dev/null"), ("--csv", "/dev/null")])
    with pytest.raises(CaseError, match="--csv would overwrite the case file"):
        check_outputs([("--csv", tmp_path / "l.txt")], [("case file", a)])


# --------------------------------------------------------------------------- 2. links, devices, FIFOs
def test_a_symlink_output_stays_a_symlink_and_its_target_is_replaced(tmp_path):
    real = tmp_path / "real" / "r.json"
    real.parent.mkdir()
    real.write_text("old")
    link = tmp_path / "r.json"
    link.symlink_to(real)
    write_text_atomic(link, "new", what="JSON")
    assert link.is_symlink() and os.readlink(link) == str(real) and real.read_text() == "new"
    assert sorted(p.name for p in real.parent.iterdir()) == ["r.json"]  # no temporary file left
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.json", "real"]


def test_a_dangling_symlink_or_a_loop_is_refused(tmp_path):
    dangling = tmp_path / "d.out"  # not .json: the suite reads every .json a test leaves
    dangling.symlink_to(tmp_path / "missing.out")
    with pytest.raises(CaseError, match="symbolic link to .*missing.out, which does not exist"):
        write_text_atomic(dangling, "x", what="JSON")
    assert dangling.is_symlink() and not (tmp_path / "missing.out").exists()
    (tmp_path / "loop1").symlink_to("loop2")
    (tmp_path / "loop2").symlink_to("loop1")
    with pytest.raises(CaseError, match="loop of symbolic links"):
        write_text_atomic(tmp_path / "loop1", "x")
    assert (tmp_path / "loop1").is_symlink()


def test_a_socket_is_refused(tmp_path):
    path = tmp_path / "s.sock"
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
        with pytest.raises(CaseError, match="JSON path is a socket"):
            write_text_atomic(path, "x", what="JSON")
        assert stat.S_ISSOCK(path.lstat().st_mode)


def test_a_fifo_is_written_through_and_without_reader_refused(tmp_path):
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    with pytest.raises(CaseError, match="no process is reading this FIFO"):  # at once, no hang
        write_text_atomic(fifo, "x", what="JSON")
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # a reader is there (17 kB fit in the pipe's buffer)
    try:
        write_text_atomic(fifo, "through the pipe\n" * 1000, what="JSON")
        got = _read_all(fd)
    finally:
        os.close(fd)
    assert got == b"through the pipe\n" * 1000
    assert stat.S_ISFIFO(fifo.lstat().st_mode) and sorted(p.name for p in tmp_path.iterdir()) == ["out.fifo"]


def _read_all(fd: int) -> bytes:
    out = []
    while True:
        try:
            chunk = os.read(fd, 65536)
        except BlockingIOError:
            break
        if not chunk:
            break
        out.append(chunk)
    return b"".join(out)


def test_dev_null_stays_a_device(case):
    res = runner.invoke(app, ["static", str(case), "--json", "/dev/null"])
    assert res.exit_code == 0, res.output
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    assert sorted(p.name for p in case.parent.iterdir()) == ["base.toml"]


# --------------------------------------------------------------------------- 18. stderr and messages
def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", "from linecheck.cli.app import main; main()", *args],
                          capture_output=True, text=True, cwd=cwd, timeout=300)


def test_a_successful_command_writes_nothing_to_stderr(case):
    out = _cli("static", str(case), "--json", str(case.with_name("s.json")), cwd=case.parent)
    assert out.returncode == 0, out.stderr
    assert out.stderr == "" and "wrote" in out.stdout
    out = _cli("check", str(case), cwd=case.parent)
    assert out.returncode == 0 and out.stderr == ""


def test_messages_show_hidden_characters_escaped(tmp_path):
    name = "evil\x1b[31m\u202etxt.toml"
    res = runner.invoke(app, ["run", str(tmp_path / name)])
    line = _one_line(res)
    assert res.exit_code == 2
    assert "\x1b" not in res.output and "\u202e" not in res.output
    assert "evil\\x1b[31m\\u202etxt.toml" in line
    assert printable("a\x00b\u200bc\u2028d é ° ± ∞") == "a\\x00b\\u200bc\\u2028d é ° ± ∞"
    assert str(CaseError("bad\x1b]0;title\x07 value", file="f\u202e.toml")) == \
        "f\\u202e.toml: bad\\x1b]0;title\\x07 value"


@pytest.mark.parametrize("argv", [["run", ""], ["check", ""], ["static", "{case}", "--json", ""],
                                  ["export", "{case}", "--excel", ""], ["batch", ""]])
def test_an_empty_path_is_said_to_be_empty(argv, case, no_work):
    res = runner.invoke(app, [a.format(case=case) for a in argv])
    assert res.exit_code == 2, res.output
    line = _one_line(res)
    assert "the path is empty" in line and "is a directory" not in line
