"""Build the default design-sheet template ``templates/design_sheet.xlsx``.

    python templates/make_template.py [OUT.xlsx]

The template holds the title block (cells addressed by the defined names project,
line, section, engineer, checked_by, date, revision, units_note; and summary_table,
the top-left cell of the summary table), the named table styles (lc_*) and the page
setup.  Charts and tables are created by ``linecheck.excel.writer``.  Copy the file,
restyle or move the cells (keep the defined names) and pass it with ``--template``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from linecheck.excel.template import build_default_template


def main(argv: list[str]) -> int:
    out = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parent / "design_sheet.xlsx"
    wb = build_default_template()
    wb.save(out)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
