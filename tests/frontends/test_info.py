"""`linecheck info`, the "provenance" block of every result document, and the one warning line
of run/batch when compiled kernel pieces are off (versions, BLAS, kernel state)."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from importlib import metadata
from pathlib import Path

import pytest
from typer.testing import CliRunner

from linecheck.cli.app import app
from linecheck.core import kernel
from linecheck.core.case import case_to_toml, load_case
from linecheck.io.document import RunDocument
from linecheck.io.provenance import NOT_INSTALLED, Kernel, Piece, kernel_warning, provenance

from ..conftest import CASES

runner = CliRunner()

PROVENANCE_KEYS = ["linecheck", "python", "numpy", "scipy", "numba", "blas", "scipy_blas", "kernel"]
BLAS_KEYS = ["library", "version", "core", "threads", "path"]


@pytest.fixture(scope="module")
def short_case(tmp_path_factory) -> Path:
    """A synoptic paper case cut to 60 s and one realization (a run of a few seconds)."""
    case = load_case(CASES / "paper" / "case10-single.toml")
    case = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, duration=60.0, realizations=1))
    path = tmp_path_factory.mktemp("case") / "case10-short.toml"
    path.write_text(case_to_toml(case), encoding="utf-8")
    return path


def kernel_as(monkeypatch, *, installed: bool = True, mode: str = "auto", off: dict[str, str] | None = None):
    """Make :mod:`linecheck.core.kernel` report a state (its contract: installed(), mode(), status())."""
    real = kernel.status()
    off = off or {}
    states = tuple(dataclasses.replace(p, on=p.name not in off, reason=off.get(p.name, "")) for p in real)
    monkeypatch.setattr(kernel, "installed", lambda: installed)
    monkeypatch.setattr(kernel, "mode", lambda: mode)
    monkeypatch.setattr(kernel, "status", lambda: states)
    return states


def test_info_json_has_versions_blas_and_every_piece():
    r = runner.invoke(app, ["info", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert list(d) == PROVENANCE_KEYS
    assert d["linecheck"] == metadata.version("linecheck")
    assert d["numpy"] == metadata.version("numpy") and d["scipy"] == metadata.version("scipy")
    numba_here = importlib.util.find_spec("numba") is not None
    assert d["numba"] == (metadata.version("numba") if numba_here else NOT_INSTALLED)
    assert list(d["blas"]) == BLAS_KEYS and d["blas"]["library"]
    if d["blas"]["library"] == "openblas":  # threadpoolctl names OpenBLAS's core kernel for this CPU
        assert d["blas"]["core"] and d["blas"]["threads"] >= 1 and Path(d["blas"]["path"]).exists()
    k = d["kernel"]
    assert k["installed"] is numba_here and k["mode"] == kernel.mode()
    assert [p["name"] for p in k["pieces"]] == [p.name for p in kernel.status()]
    for p in k["pieces"]:
        assert list(p) == ["name", "on", "reason"] and (p["reason"] == "") is p["on"], p


def test_info_table_names_blas_and_each_piece_state(monkeypatch):
    states = kernel_as(monkeypatch, off={"newmark": "load check: differs from numpy by 3.1e-09 of the largest "
                                                    "value (allowed 1e-12)"})
    r = CliRunner(env={"COLUMNS": "250"}).invoke(app, ["info"])
    assert r.exit_code == 0, r.output
    out = r.stdout
    assert "BLAS (numpy)" in out and "numba" in out and "Python" in out
    assert f"{len(states) - 1} of {len(states)} pieces on" in out
    line = next(x for x in out.splitlines() if " newmark " in x)
    assert "off: load check: differs from numpy by 3.1e-09" in line
    assert all(p.name in out for p in states)


def test_info_without_numba_says_not_installed(monkeypatch):
    real = metadata.version

    def version(dist):
        if dist == "numba":
            raise metadata.PackageNotFoundError(dist)
        return real(dist)

    monkeypatch.setattr(metadata, "version", version)
    why = "Numba not installed (linecheck[fast])"
    kernel_as(monkeypatch, installed=False, off={p.name: why for p in kernel.status()})
    d = json.loads(runner.invoke(app, ["info", "--json"]).stdout)
    assert d["numba"] == NOT_INSTALLED and d["kernel"]["installed"] is False
    assert {p["reason"] for p in d["kernel"]["pieces"]} == {why} and not any(p["on"] for p in d["kernel"]["pieces"])


def test_kernel_warning_only_when_numba_is_installed_and_a_piece_is_off():
    on, off = Piece("rotate", True), Piece("newmark", False, "load check: differs from numpy by 3.1e-09")
    assert kernel_warning(Kernel(True, "auto", (on, on))) is None
    assert kernel_warning(Kernel(False, "auto", (off,))) is None  # not installed: numpy by design
    assert kernel_warning(Kernel(True, "numpy", (off,))) is None  # LINECHECK_KERNEL=numpy: by choice
    msg = kernel_warning(Kernel(True, "auto", (on, off, Piece("span", False, "load check failed: x"))))
    assert msg == ("compiled kernel pieces off: newmark (load check: differs from numpy by 3.1e-09), "
                   "span (load check failed: x); results are the same within tolerance, slower")


def test_run_prints_one_warning_line_and_records_the_pieces(short_case, tmp_path, monkeypatch):
    why = "load check: differs from numpy by 3.1e-09 of the largest value (allowed 1e-12)"
    kernel_as(monkeypatch, off={"newmark": why})
    out = tmp_path / "r.json"
    r = runner.invoke(app, ["run", str(short_case), "--json", str(out), "--jobs", "1"])
    assert r.exit_code == 0, r.output
    warnings = [x for x in r.stderr.splitlines() if "compiled kernel" in x]
    assert warnings == [f"warning: compiled kernel pieces off: newmark ({why}); results are the same within "
                        "tolerance, slower"]
    prov = json.loads(out.read_text())["provenance"]
    assert {p["name"]: (p["on"], p["reason"]) for p in prov["kernel"]["pieces"]}["newmark"] == (False, why)
    assert sum(not p["on"] for p in prov["kernel"]["pieces"]) == 1


@pytest.mark.parametrize("state", ["all on", "not installed", "numpy"])
def test_run_prints_no_kernel_warning(short_case, monkeypatch, state):
    if state == "all on":
        kernel_as(monkeypatch)
    elif state == "not installed":
        kernel_as(monkeypatch, installed=False, off={p.name: "Numba not installed" for p in kernel.status()})
    else:
        kernel_as(monkeypatch, mode="numpy", off={p.name: "LINECHECK_KERNEL=numpy" for p in kernel.status()})
    r = runner.invoke(app, ["run", str(short_case), "--jobs", "1", "--no-check"])
    assert r.exit_code == 0, r.output
    assert "compiled kernel" not in r.stderr


def test_batch_prints_one_warning_line(short_case, tmp_path, monkeypatch):
    kernel_as(monkeypatch, off={"rotate": "load check failed: x", "span": "load check failed: y"})
    r = runner.invoke(app, ["batch", str(short_case), "--jobs", "1", "--json-dir", str(tmp_path / "res")])
    assert r.exit_code == 0, r.output
    assert [x for x in r.stderr.splitlines() if "compiled kernel" in x] == [
        "warning: compiled kernel pieces off: rotate (load check failed: x), span (load check failed: y); "
        "results are the same within tolerance, slower"]
    saved = json.loads((tmp_path / "res" / f"{short_case.stem}.json").read_text())
    assert [p["name"] for p in saved["provenance"]["kernel"]["pieces"] if not p["on"]] == ["rotate", "span"]


def test_result_document_records_provenance_and_older_results_still_read(short_case, tmp_path):
    out = tmp_path / "r.json"
    assert runner.invoke(app, ["run", str(short_case), "--json", str(out), "--jobs", "1"]).exit_code == 0
    text = out.read_text()
    d = json.loads(text)
    assert list(d["provenance"]) == PROVENANCE_KEYS and list(d)[-1] == "provenance"
    assert d["provenance"] == provenance().to_json()  # the same process state as `linecheck info --json`
    typed = RunDocument.from_json(d)
    assert typed.provenance is not None and typed.provenance.blas.library == d["provenance"]["blas"]["library"]
    assert json.dumps(typed.to_json(), indent=2) + "\n" == text  # read and written again: the same bytes
    # a result saved before the block existed reads (no provenance) and exports
    old = {k: v for k, v in d.items() if k != "provenance"}
    assert RunDocument.from_json(old).provenance is None and RunDocument.from_json(old).to_json() == old
    (tmp_path / "old.json").write_text(json.dumps(old), encoding="utf-8")
    r = runner.invoke(app, ["export", str(tmp_path / "old.json"), "--excel", str(tmp_path / "old.xlsx")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "old.xlsx").exists()


@pytest.mark.parametrize("command", ["static", "modes", "spectral", "wind"])
def test_other_result_documents_record_provenance(short_case, tmp_path, command):
    out = tmp_path / f"{command}.json"
    r = runner.invoke(app, [command, str(short_case), "--json", str(out)])
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    assert list(d["provenance"]) == PROVENANCE_KEYS
    assert d["provenance"]["kernel"]["mode"] == kernel.mode()
