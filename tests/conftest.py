"""Shared fixtures: paths and paper systems."""

from __future__ import annotations

from pathlib import Path

import pytest

from linecheck.validation import paper_line  # noqa: F401  (the paper's system, Table 1)

ROOT = Path(__file__).resolve().parents[1]
CASES = ROOT / "cases"
DATA = Path(__file__).resolve().parent / "data"


@pytest.fixture
def cases_dir() -> Path:
    return CASES


# --------------------------------------------------------------------------- result schema
# Every run-result document the suite produces (RunDocument.to_json: `run --json`, batch, the TUI,
# Excel inputs) and every result JSON a test writes under tmp_path is validated against
# docs/results.schema.json.
_SCHEMA_STATS = {"validated": 0}


def _result_schema():
    import json

    return json.loads((ROOT / "docs" / "results.schema.json").read_text(encoding="utf-8"))


def _check_result(doc, where: str) -> None:
    from .schema_check import errors

    errs = errors(doc, _result_schema())
    assert not errs, f"{where} violates docs/results.schema.json: " + "; ".join(errs[:5])
    _SCHEMA_STATS["validated"] += 1


@pytest.fixture(autouse=True, scope="session")
def _validate_every_result_document():
    from linecheck.io import document

    original = document.RunDocument.to_json

    def checked(self):
        d = original(self)
        _check_result(d, f"result of case {d.get('case')!r}")
        return d

    document.RunDocument.to_json = checked
    yield
    document.RunDocument.to_json = original


@pytest.fixture(autouse=True)
def _validate_written_results(request):
    yield
    tmp = request.node.funcargs.get("tmp_path") if hasattr(request.node, "funcargs") else None
    if tmp is None:
        return
    import json

    for p in Path(tmp).rglob("*.json"):
        try:
            d = json.loads(p.read_text(encoding="utf-8"))
        except (ValueError, UnicodeDecodeError):
            continue
        if isinstance(d, dict) and "schema_version" in d and "reactions" in d:
            _check_result(d, str(p))


def pytest_terminal_summary(terminalreporter):
    n = _SCHEMA_STATS["validated"]
    if n:
        terminalreporter.write_line(f"result documents validated against docs/results.schema.json: {n}")


def one_error_line(result) -> str:
    """The single line of a refused command (CliRunner result): exit 2, no traceback, exactly one
    non-empty line, starting with ``error: ``; returns it."""
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1, lines
    assert lines[0].startswith("error: ")
    return lines[0]
