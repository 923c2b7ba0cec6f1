"""A case with ``[[wires]]`` runs `check`, `static` and `linecheck run` (tests/frontends/
test_wires_run_cli.py): every job that analyses one wire (spectral, modes, wind and its --field,
codes, scan, a batch's run, ``run_case``) refuses it in one line naming the file and what such a
case runs (exit 2), before any work; a batch records it as a failed case and runs the others (the
TUI's run calls ``run_wires``: tests/frontends/test_tui_wires.py)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core.case import load_case
from linecheck.core.errors import CaseError

from ..batch.test_batch import write_short_case
from ..conftest import CASES, one_error_line
from ..two_wires import DOWNBURST, write_two_wires


def refusal(path, job: str) -> str:
    what = ("a batch's run of several wires is not available yet: run the case with `linecheck run` (or in the TUI)"
            if job == "run" else
            f"`{job}` of several wires is not available yet: run each wire as a single-wire case")
    return (f"error: {path}: wires: a case with several wires runs `check`, `static` and `linecheck run` (every "
            f"attachment, the tower totals and load trees); {what}")


def _invoke(*args):
    return CliRunner(env={"COLUMNS": "250"}).invoke(app, [str(a) for a in args])


@pytest.mark.parametrize(("args", "job"), [
    (["spectral"], "spectral"),
    (["modes"], "modes"),
    (["wind"], "wind"),
    (["wind", "--field", "{tmp}/field.npz"], "wind"),
    (["codes"], "codes"),
    (["codes", "--loads-only"], "codes"),
])
def test_every_one_wire_job_refuses_a_case_with_wires(tmp_path, args, job):
    path = write_two_wires(tmp_path)
    command = [a.format(tmp=tmp_path) for a in args]
    r = _invoke(command[0], path, *command[1:])
    assert one_error_line(r) == refusal(path, job)
    assert list(tmp_path.iterdir()) == [path]  # nothing written


def test_scan_refuses_a_case_with_wires(tmp_path):
    path = write_two_wires(tmp_path, wind=DOWNBURST)
    assert one_error_line(_invoke("scan", path, "--jobs", "1")) == refusal(path, "scan")


def test_check_accepts_a_case_with_wires(tmp_path):
    r = _invoke("check", write_two_wires(tmp_path))
    assert r.exit_code == 0, r.output
    assert r.output.startswith("ok ")


def test_a_batch_fails_the_case_with_wires_and_runs_the_others(tmp_path):
    """The case with wires fails before the batch starts (its one line in the summary, exit 1 as
    for any failed case); the single-wire case runs and writes its result."""
    (tmp_path / "cases").mkdir()
    short = write_short_case(CASES / "paper" / "case09-single.toml", tmp_path / "cases", realizations=2)
    two = write_two_wires(tmp_path / "cases")
    out = tmp_path / "res"
    r = _invoke("batch", two, short, "--jobs", "1", "--json-dir", out)
    assert r.exit_code == 1, r.output
    assert " ".join(refusal(two, "run").split()[1:]) in " ".join(r.output.split())
    assert "1 case(s) failed" in r.output
    assert sorted(p.name for p in out.glob("*.json")) == [f"{short.stem}.json"]


def test_the_service_refuses_before_any_work(tmp_path):
    """The one guard every job meets (``check_budget``) and the entry points without a resource
    guard (code loads, the scan's estimate) refuse the case."""
    from linecheck import service
    from linecheck.batch.scan import scan_estimate

    path = write_two_wires(tmp_path)
    case = load_case(path)
    for call, job in [(lambda: service.run_case(case), "run"),
                      (lambda: service.modes_analysis(case), "modes"),
                      (lambda: service.spectral_analysis(case), "spectral"),
                      (lambda: service.wind_at_p(case), "wind"), (lambda: service.code_loads(case), "codes"),
                      (lambda: scan_estimate(case, 10), "scan")]:
        with pytest.raises(CaseError) as info:
            call()
        assert "error: " + str(info.value) == refusal(path, job)
        assert info.value.exit_code == 2
