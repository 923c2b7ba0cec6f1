"""Case browser: the case folders as a tree, a one-line description per case, a preview."""

from __future__ import annotations

from pathlib import Path

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical, VerticalScroll
from textual.widgets import Static, Tree

from ...core.case import load_case
from ...core.errors import LinecheckError
from ...io.display import kn
from ...io.section import line_summary
from ..catalog import CaseEntry, Catalog, Folder, shown_path
from ..messages import OpenCaseRequested


def case_label(entry: CaseEntry) -> Text:
    """``name  description`` (dim), or the read error in red."""
    text = Text(entry.name, style="bold")
    if entry.error:
        text.append("  " + entry.error, style="red")
    elif entry.description:
        text.append("  " + entry.description, style="dim")
    return text


def preview(path: Path) -> Text:
    """A few lines about a case file: validated parameters, or the validation error."""
    try:
        case = load_case(path)
    except LinecheckError as err:
        return Text.assemble((f"{path}\n\n", "dim"), ("cannot open: ", "bold red"), str(err))
    ln, w, a = case.line, case.wind, case.analysis
    out = Text()
    out.append(f"{case.name}\n", style="bold")
    if case.description:
        out.append(f"{case.description}\n")
    out.append(f"{shown_path(path)}\n\n", style="dim")
    out.append("line      ", style="bold")
    out.append(f"{line_summary(ln)}, tower of interest {ln.tower_of_interest}\n")
    out.append("          ", style="bold")
    if ln.is_section:  # a section: the towers, not one support word per tower
        src = f" from {ln.towers_file}" if ln.towers_file else ""
        turns = [f"{t.name} {t.angle:+g} deg" for t in ln.towers if t.angle]
        out.append(f"{ln.n_towers} towers{src}, H0 {kn(ln.tension):g} kN"
                   + (f", angles {', '.join(turns)}" if turns else "") + "\n")
    else:
        out.append(f"supports {', '.join(ln.supports)}\n")
    out.append("wind      ", style="bold")
    out.append(f"{w.type}, V_ref {w.v_ref:g} m/s, I = {w.turbulence_intensity:g}")
    if w.direction or w.profile_exponent:
        out.append(f", direction {w.direction:g} deg, profile exponent {w.profile_exponent:g}")
    if w.downburst is not None:
        db = w.downburst
        out.append(f"\n          D_j {db.jet_diameter:g} m, R {db.distance:g} m, angle {db.angle:g} deg"
                   + (f" (preset {db.preset})" if db.preset else ""))
    out.append("\n")
    out.append("analysis  ", style="bold")
    dur = "default" if a.duration is None else f"{a.duration:g} s"
    out.append(f"duration {dur}, dt {a.time_step:g} s, {a.realizations} realizations, seed {a.seed}\n\n")
    out.append("enter", style="bold reverse")
    out.append(" open this case")
    return out


class CaseBrowser(Vertical):
    """Tree of case folders/files (top) and a preview of the highlighted case (bottom)."""

    def __init__(self, catalog: Catalog, **kwargs) -> None:
        super().__init__(**kwargs)
        self.catalog = catalog

    def compose(self) -> ComposeResult:
        tree: Tree[Path | None] = Tree("cases", id="case-tree")
        tree.show_root = False
        tree.guide_depth = 3
        yield tree
        with VerticalScroll(id="case-preview-box"):
            yield Static(self._empty_text(), id="case-preview")

    def _empty_text(self) -> Text:
        if self.catalog.empty:
            return Text("No case files found.\n\nStart with folders or files: linecheck tui cases/ my-case.toml")
        return Text("Move with the arrow keys; enter opens a case.", style="dim")

    def on_mount(self) -> None:
        self._fill()

    def reload(self, catalog: Catalog) -> None:
        """Show ``catalog`` instead (e.g. after a case was saved)."""
        self.catalog = catalog
        self.query_one(Tree).clear()
        self._fill(focus=False)

    def _fill(self, *, focus: bool = True) -> None:
        tree = self.query_one(Tree)
        for folder in self.catalog.folders:
            self._add_folder(tree.root, folder, expand=True)
        for entry in self.catalog.files:
            tree.root.add_leaf(case_label(entry), data=entry.path)
        for p in self.catalog.missing:
            tree.root.add_leaf(Text.assemble((str(p), "bold"), ("  not found", "red")), data=None)
        tree.root.expand()
        if focus:
            tree.focus()
            first = self._find(tree.root, lambda node: node.data is not None)
            if first is not None:
                self.call_after_refresh(tree.move_cursor, first)

    def _find(self, node, test):
        if test(node):
            return node
        for child in node.children:
            found = self._find(child, test)
            if found is not None:
                return found
        return None

    def _add_folder(self, parent, folder: Folder, *, expand: bool) -> None:
        label = Text(folder.label + "/", style="bold")
        if folder.error:
            label.append("  " + folder.error, style="red")
        node = parent.add(label, data=None, expand=expand)
        for sub in folder.folders:
            self._add_folder(node, sub, expand=True)
        for entry in folder.cases:
            node.add_leaf(case_label(entry), data=entry.path)

    def on_tree_node_highlighted(self, event: Tree.NodeHighlighted) -> None:
        path = event.node.data
        box = self.query_one("#case-preview", Static)
        box.update(preview(path) if path is not None else self._empty_text())

    def on_tree_node_selected(self, event: Tree.NodeSelected) -> None:
        if event.node.data is not None:
            event.stop()
            self.post_message(OpenCaseRequested(event.node.data))

    def select_path(self, path: Path) -> None:
        """Move the tree cursor to ``path`` (when it is listed)."""
        tree = self.query_one(Tree)
        node = self._find(tree.root, lambda n: n.data is not None and Path(n.data).resolve() == path.resolve())
        if node is not None:
            tree.move_cursor(node)
