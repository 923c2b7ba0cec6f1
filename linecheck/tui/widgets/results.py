"""Result tabs of the last run: summary, time histories, mean states, wind at p,
contributions, spectral check, natural frequencies; a run of a case with ``[[wires]]``: summary,
contributions and load trees (its one-wire tabs hidden)."""

from __future__ import annotations

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.widgets import DataTable, RadioButton, RadioSet, Static, TabbedContent, TabPane

from ...io.display import STAT_ROWS, doc_frame_caption, kn_text, number_text, uplift_run_text
from ...io.document import RunDocument
from .. import figures
from ..formatting import (
    REACTIONS,
    cont_r_flags,
    davenport_lines,
    how_to_read,
    sanity_rows,
    spectral_compare_rows,
    summary_rows,
    summary_title,
)
from ..plotting import PlotView
from ..runner import RunOutput
from ..wires_text import wires_summary_note, wires_title
from .choice import StepChoice
from .trees import LoadTreeView

NO_RUN = "No results yet: open a case and press r to run it."
TABS = ("res-summary", "res-histories", "res-mean", "res-wind", "res-contrib", "res-spectral", "res-freq",
        "res-trees")
#: The tabs of one wire's run (hidden for a run of several wires); "res-trees" only for several wires.
ONE_WIRE_TABS = ("res-histories", "res-mean", "res-wind", "res-spectral", "res-freq")
WIRES_TABS = ("res-trees",)


class ReactionChoice(StepChoice):
    """Rx / Ry / Rz: the arrow keys pick a reaction at once (no enter needed)."""


class ResultsView(Vertical):
    """Tabs over one :class:`~linecheck.tui.runner.RunOutput` (plus the pinned one in Contributions)."""

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        self.output: RunOutput | None = None
        self.pinned: RunOutput | None = None
        self.reaction = "Ry"

    def compose(self) -> ComposeResult:
        yield Static(NO_RUN, id="results-title")
        with TabbedContent(id="results-tabs"):
            with TabPane("Summary", id="res-summary"):
                yield DataTable(id="summary-table", cursor_type="row", zebra_stripes=True)
                yield Static("", id="summary-notes")
            with TabPane("Reactions", id="res-histories"):
                with Horizontal(id="reaction-bar"):
                    yield Static("reaction (←/→): ", classes="inline-label")
                    with ReactionChoice(id="reaction-choice"):
                        for r in REACTIONS:
                            yield RadioButton(r, value=(r == self.reaction), id=f"pick-{r}")
                yield PlotView(NO_RUN, id="plot-history")
            with TabPane("Mean states", id="res-mean"):
                yield PlotView(NO_RUN, id="plot-tension")
                yield PlotView(NO_RUN, id="plot-displacement")
            with TabPane("Wind at p", id="res-wind"):
                yield PlotView(NO_RUN, id="plot-wind")
            with TabPane("Contributions", id="res-contrib"):
                yield PlotView(NO_RUN, id="plot-contrib")
            with TabPane("Spectral check", id="res-spectral"), VerticalScroll(id="spectral-box"):
                yield Static(NO_RUN, id="spectral-notes")
                yield DataTable(id="spectral-table", cursor_type="row", zebra_stripes=True)
                yield Static("", id="spectral-davenport")
                yield DataTable(id="sanity-table", cursor_type="row", zebra_stripes=True)
            with TabPane("Frequencies", id="res-freq"):
                yield Static(NO_RUN, id="freq-notes")
                yield DataTable(id="freq-table", cursor_type="row", zebra_stripes=True)
            with TabPane("Load trees", id="res-trees"):
                yield LoadTreeView(id="tree-view")

    def on_mount(self) -> None:
        t = self.query_one("#summary-table", DataTable)
        for c in ("statistic", "unit", *REACTIONS):
            t.add_column(c, key=c)
        self.query_one("#sanity-table", DataTable).add_columns(
            "reaction", "sanity check", "time domain ± std", "frequency domain", "allowed difference", "verdict")
        self.query_one("#freq-table", DataTable).add_columns("mode", "still air (Hz)", "dir", "mean state (Hz)", "dir")
        self._tabs_for(wires=False)

    # ------------------------------------------------------------------ tabs
    @property
    def active_tab(self) -> str:
        return self.query_one("#results-tabs", TabbedContent).active

    @active_tab.setter
    def active_tab(self, tab: str) -> None:
        self.query_one("#results-tabs", TabbedContent).active = tab

    def cycle_tab(self, step: int) -> None:
        """The next (``step`` 1) or previous (-1) of the tabs shown."""
        shown = [t for t in TABS if self.has_tab(t)]
        i = shown.index(self.active_tab) if self.active_tab in shown else 0
        self.active_tab = shown[(i + step) % len(shown)]

    def has_tab(self, tab: str) -> bool:
        """Whether the view ``tab`` is shown (the tabs depend on the result: one or several wires)."""
        return bool(self.query_one("#results-tabs", TabbedContent).get_tab(tab).display)

    def _tabs_for(self, *, wires: bool) -> None:
        """Show the tabs of a run of several wires (``wires``) or of one wire, hide the others."""
        tabs = self.query_one("#results-tabs", TabbedContent)
        for tab in ONE_WIRE_TABS:
            (tabs.hide_tab if wires else tabs.show_tab)(tab)
        for tab in WIRES_TABS:
            (tabs.show_tab if wires else tabs.hide_tab)(tab)

    # ------------------------------------------------------------------ content
    def show(self, output: RunOutput, pinned: RunOutput | None = None, *, stale: str | None = None) -> None:
        """Fill every tab from ``output``; ``stale``: why it is not the current case (shown)."""
        self.output, self.pinned = output, pinned
        doc = output.doc
        wires = doc.has_wires
        title = Text(wires_title(doc) if wires else summary_title(doc), style="bold")
        title.append(f"   run in {output.seconds:.1f} s", style="dim")
        if stale:
            title.append(f"   ({stale})", style="yellow")
        self.query_one("#results-title", Static).update(title)
        self._tabs_for(wires=wires)
        self._summary(doc)
        self.show_contributions()
        self.query_one(LoadTreeView).show(doc)
        if wires:  # no time histories, mean-state series, wind at p, spectral check or modes of several wires
            return
        self._history()
        self.query_one("#plot-tension", PlotView).show(figures.mean_tension(output.result))
        self.query_one("#plot-displacement", PlotView).show(figures.mean_displacement(output.result))
        wind = self.query_one("#plot-wind", PlotView)
        wind.show(figures.wind_at_p(output.wind) if output.wind is not None else None, "wind at p not computed")
        self._spectral(doc)
        self._frequencies(output)

    def mark_stale(self, stale: str | None) -> None:
        if self.output is not None:
            self.show(self.output, self.pinned, stale=stale)

    def _summary(self, doc: RunDocument) -> None:
        t = self.query_one("#summary-table", DataTable)
        t.clear()
        flagged = cont_r_flags(doc)
        for row in summary_rows(doc):
            cells = list(row)
            if row[0] == "Cont_R":
                # flagged cells in reverse video: visible on the cursor row and the zebra stripes
                cells = [Text(cells[0], style="bold yellow") if flagged else cells[0], cells[1]] + [
                    Text(c, style="bold black on yellow") if r in flagged else c for r, c in zip(REACTIONS, cells[2:])]
            t.add_row(*cells, key=row[0])
        notes = Text()
        if doc.has_wires:
            notes.append(wires_summary_note(doc) + "\n", style="bold")
        notes.append("Wind-induced reactions (still air removed) at the tower of interest, "
                     f"{doc_frame_caption(doc)}; "
                     "** : GF undefined, mean zero by symmetry or < 1 % of the largest mean. "
                     "Cont_R: share of the peak a quasi-static analysis misses.", style="dim")
        if flagged:
            notes.append(f"\nCont_R above 10 % (95 % interval) for {', '.join(flagged)}: dynamic analysis recommended.",
                         style="bold yellow")
        unsure = cont_r_flags(doc, "inconclusive")
        if unsure:
            notes.append(f"\nCont_R interval straddles 10 % for {', '.join(unsure)}: inconclusive, run more "
                         "realizations (linecheck run --until 1%).", style="yellow")
        for line in how_to_read(doc):
            notes.append("\n" + line, style="dim")
        if doc.models is not None:
            notes.append("\n" + models_text(doc))
        sa = doc.still_air.reactions if doc.still_air is not None else {}
        if sa:
            notes.append("\nstill air: " + ", ".join(f"{r} {kn_text(v)} kN" for r, v in sa.items() if v is not None),
                         style="dim")
        uplift = uplift_run_text(doc)
        if uplift is not None:
            notes.append("\n" + uplift, style="dim")
        self.query_one("#summary-notes", Static).update(notes)

    def _history(self) -> None:
        if self.output is not None and self.output.doc.time_histories is not None:
            self.query_one("#plot-history", PlotView).show(figures.reaction_history(self.output.doc, self.reaction))

    @on(TabbedContent.TabActivated, "#results-tabs")
    def _tab_activated(self, event: TabbedContent.TabActivated) -> None:
        if event.pane.id == "res-histories":
            self.query_one(ReactionChoice).focus()
        elif event.pane.id == "res-trees":
            self.query_one("#tree-towers").focus()

    @on(RadioSet.Changed, "#reaction-choice")
    def _reaction_changed(self, event: RadioSet.Changed) -> None:
        event.stop()
        self.reaction = str(event.pressed.label)
        self._history()

    def show_contributions(self) -> None:
        if self.output is None:
            return
        docs = [("", self.output.doc)]
        if self.pinned is not None and self.pinned is not self.output:
            docs = [("pinned", self.pinned.doc), ("current", self.output.doc)]
        self.query_one("#plot-contrib", PlotView).show(figures.contributions(docs))

    def _spectral(self, doc: RunDocument) -> None:
        """Frequency-domain check beside the time domain (synoptic runs with a "spectral" block)."""
        notes = self.query_one("#spectral-notes", Static)
        table = self.query_one("#spectral-table", DataTable)
        sanity = self.query_one("#sanity-table", DataTable)
        dav = self.query_one("#spectral-davenport", Static)
        table.clear(columns=True)
        sanity.clear()
        if doc.spectral is None:
            why = ("a downburst is non-stationary: the frequency-domain check applies to synoptic winds"
                   if doc.wind == "downburst" else "this result has no \"spectral\" block")
            notes.update(Text(f"No spectral check: {why}.", style="dim"))
            for w in (table, sanity, dav):
                w.display = False
            return
        compare = spectral_compare_rows(doc)
        checks = sanity_rows(doc)
        lines = davenport_lines(doc)
        table.add_columns("statistic", "unit", *(f"{r} {d}" for r in REACTIONS for d in ("time", "freq")))
        for row in compare:
            table.add_row(*row)
        notes.update(Text("Time domain (mean over realizations) beside the frequency domain "
                          "(exact linear random vibration of the same model).", style="dim"))
        table.display = True
        dav.display = bool(lines)
        dav.update(Text("\n".join(lines)))
        sanity.display = bool(checks)
        for row in checks:
            verdict = Text(row[-1], style="green" if row[-1] == "ok" else "bold yellow")
            sanity.add_row(*row[:-1], verdict)

    def _frequencies(self, output: RunOutput) -> None:
        table = self.query_one("#freq-table", DataTable)
        table.clear()
        notes = self.query_one("#freq-notes", Static)
        m = output.modes
        if m is None:
            notes.update("natural frequencies not computed")
            return
        dirs = "xyz"
        ds, dm = m.still_air.dominant_direction(), m.mean.dominant_direction()
        for i in range(m.still_air.frequencies_hz.size):
            table.add_row(str(i + 1), f"{m.still_air.frequencies_hz[i]:.4f}", dirs[ds[i]],
                          f"{m.mean.frequencies_hz[i]:.4f}", dirs[dm[i]])
        text = "Undamped natural frequencies of the still-air state and of the mean state"
        if output.case.wind.type == "downburst":
            text += f" at t = {m.mean_time:.1f} s (largest mean reaction at the tower of interest)"
        notes.update(Text(text + "; dir: direction holding most of the mode's kinetic energy.", style="dim"))


def models_text(doc: RunDocument) -> str:
    """Downburst model spread: peak dynamic Rx/Ry and GF_Dy per model, and the envelope."""
    pk, gf = STAT_ROWS["peak_dynamic"], STAT_ROWS["GF_Dy"]

    def fmt(v, st):
        return "**" if v is None else number_text(v, st)

    lines = [f"model spread (shown above: {doc.model or '?'}):"]
    for name, blk in (doc.models or {}).items():
        lines.append(f"  {name:<14} peak Rx {fmt(blk['Rx'][pk.name].mean, pk)} kN, "
                     f"Ry {fmt(blk['Ry'][pk.name].mean, pk)} kN; GF_Dy Rx "
                     f"{fmt(blk['Rx'][gf.name].mean, gf)}, Ry {fmt(blk['Ry'][gf.name].mean, gf)}")
    env = doc.models_envelope or {}
    lines.append("  envelope       " + ", ".join(
        f"peak {r} {fmt(env[r][pk.name].value, pk)} kN ({env[r][pk.name].model})" for r in ("Rx", "Ry")))
    return "\n".join(lines)
