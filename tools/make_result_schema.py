"""Regenerate docs/results.schema.json from the typed result document (linecheck/io/document.py).

Run from the repository root: ``python tools/make_result_schema.py``.  A test checks the file
is up to date and validates every result the test suite writes against it.
"""

from __future__ import annotations

import json
from pathlib import Path

from linecheck.io.document import json_schema

ROOT = Path(__file__).resolve().parents[1]
TARGET = ROOT / "docs" / "results.schema.json"


def render() -> str:
    return json.dumps(json_schema(), indent=2) + "\n"


if __name__ == "__main__":
    TARGET.write_text(render(), encoding="utf-8")
    print(f"wrote {TARGET.relative_to(ROOT)}")
