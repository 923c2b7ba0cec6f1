"""Help screen: the keys and a typical session."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Markdown

HELP = """\
# linecheck tui

Design check of conductor reactions under downburst and synoptic winds
(hybrid method: step 1 mean states, steps 2-3 dynamics and quasi-static split).

## Keys

- `1` `2` `3` `4` `5`: tabs Cases, Parameters, Results, Compare, Codes (design codes beside the peaks)
- arrows, `enter`: move; open a case (Cases) or edit a parameter (Parameters)
- `e`: edit the highlighted parameter; `enter` applies, `esc` cancels
- a section case (towers) has its tower table under the parameters: `tab` to it, arrows to a
  cell, `enter` edits it (checked like the case file; saved as inline `[[line.towers]]`)
- `s`: save the edited case as a new TOML file in the working folder (an existing file is never
  replaced silently; a shipped case folder such as `cases/paper/` needs a second `enter`)
- `r`: run the case (steps 1-3, natural frequencies, wind at p); `c` cancels the run. A case with
  `[[wires]]` runs every wire in one correlated wind, as `linecheck run` does: its Results are the
  Summary (the tower totals' forces at the tower of interest), Contributions and Load trees
- `[` `]`: previous / next result tab
- Load trees (a run of several wires): `↑` `↓` pick the tower, `←` `→` the load case; every wire's
  vertical, transverse and longitudinal load (kN) at the instant the case's total is reached, and
  the tower's totals
- `p`: pin the result for Compare
- `x` / `j`: export the result to Excel (.xlsx) / JSON
- `ctrl+p`: command palette: "case: ...", "run: ...", "export: ..."
- `?` or `f1`: this help; `ctrl+q` quits (twice when the case has unsaved edits)

## A typical session

1. `1` Cases: arrows to a case, `enter` opens it (with unsaved edits it asks first).
2. `2` Parameters: arrows to `wind.v_ref`, `enter`, type `20`, `enter`.
   A bad value is refused with the same message as `linecheck check`.
3. `r` runs it; the bars show each stage; `c` cancels.
4. `3` Results: the summary (kN, %, ± std over realizations); `]` steps through
   the reaction histories M, M+B, M+B+R, the running-mean tension and displacements,
   the wind at point p, the contributions, the spectral check and the frequencies.
5. `p` pins the result; change a parameter; `r`; `4` Compare shows both with differences.
6. `x` writes an Excel design sheet, `j` the JSON result; `s` saves the edited case.

Values are the same as `linecheck run CASE --json` for the same case and seed.
Wind-induced reactions (still air removed) at the tower of interest.
The wind type cannot be switched in the editor: start from a case file of the other type.

Press `esc` to close.
"""


class HelpScreen(ModalScreen[None]):
    BINDINGS = [Binding("escape,q,question_mark,f1", "close", "Close")]

    def compose(self) -> ComposeResult:
        with VerticalScroll(id="help-box", classes="dialog"):
            yield Markdown(HELP)

    def action_close(self) -> None:
        self.dismiss(None)
