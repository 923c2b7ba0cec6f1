"""The package's architecture contract, checked from the source (no import of the package).

    python tools/architecture.py          # report; exit 1 on a violation
    python tools/architecture.py --list   # also list every function over 60 lines

Rules (docs/architecture.md):

1. **Layers.** Every module of ``linecheck`` belongs to one layer; it imports only modules of its
   own layer or of a lower one.  Lowest first::

       kernel (core._loops, core._loops_wind, core._loops_second_order, core.kernel, core.errors)
       core   (linecheck.core.*, linecheck.reference)
       analysis (linecheck.analysis.*, linecheck.service, linecheck.validation)
       io     (linecheck.io.*)
       excel | batch        (siblings: neither imports the other)
       tui
       cli                  (the entry point: its ``tui`` command starts the TUI)

   The package's ``__init__`` is outside the layers.
2. **No import cycles** between modules, counting imports inside functions too (a deferred
   import hides a cycle from Python, not from a reader); imports under ``if TYPE_CHECKING:`` do
   not count.
3. **No private names across modules**: ``from .x import _name`` only within one module's own
   family (a module and its ``_``-prefixed helper of the same package are one family: none here).
4. **Sizes**: no module over 700 lines; no function over 100 lines; at most ten over 60.
"""

from __future__ import annotations

import argparse
import ast
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "linecheck"

MAX_MODULE_LINES = 700
MAX_FUNCTION_LINES = 100
LONG_FUNCTION_LINES = 60
MAX_LONG_FUNCTIONS = 10

#: (layer name, rank, module prefixes); a module takes the layer of its longest matching prefix
LAYERS = [
    ("kernel", 0, ("linecheck.core._loops", "linecheck.core._loops_wind", "linecheck.core._loops_second_order",
                 "linecheck.core.kernel", "linecheck.core.errors")),
    ("core", 1, ("linecheck.core", "linecheck.reference")),
    ("analysis", 2, ("linecheck.analysis", "linecheck.service", "linecheck.validation")),
    ("io", 3, ("linecheck.io",)),
    ("excel", 4, ("linecheck.excel",)),
    ("batch", 4, ("linecheck.batch",)),
    ("tui", 5, ("linecheck.tui",)),
    ("cli", 6, ("linecheck.cli",)),
]


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def layer_of(module: str) -> tuple[str, int] | None:
    best: tuple[int, str, int] | None = None
    for name, rank, prefixes in LAYERS:
        for p in prefixes:
            if (module == p or module.startswith(p + ".")) and (best is None or len(p) > best[0]):
                best = (len(p), name, rank)
    return None if best is None else (best[1], best[2])


@dataclass
class Module:
    name: str
    path: Path
    is_package: bool
    lines: int
    imports: list[tuple[str, int, tuple[str, ...]]] = field(default_factory=list)  # (target, line, names)
    functions: list[tuple[str, int, int]] = field(default_factory=list)  # (qualified name, line, length)


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                lines.update(range(sub.lineno, (sub.end_lineno or sub.lineno) + 1))
    return lines


def read_modules() -> dict[str, Module]:
    mods: dict[str, Module] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        src = path.read_text()
        mods[module_name(path)] = Module(module_name(path), path, path.name == "__init__.py",
                                         src.count("\n") + (not src.endswith("\n") and bool(src)))
    for m in mods.values():
        tree = ast.parse(m.path.read_text(), str(m.path))
        skip = _type_checking_lines(tree)
        base = m.name if m.is_package else m.name.rsplit(".", 1)[0]
        for node in ast.walk(tree):
            if getattr(node, "lineno", None) in skip:
                continue
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name == "linecheck" or a.name.startswith("linecheck."):
                        m.imports.append((_existing(a.name, mods), node.lineno, ()))
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    pkg = base.split(".")
                    pkg = pkg[: len(pkg) - (node.level - 1)]
                    target = ".".join(pkg + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if not (target == "linecheck" or target.startswith("linecheck.")):
                    continue
                names = tuple(a.name for a in node.names)
                subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in mods]
                for s in subs:  # ``from . import kernel``: the submodule itself
                    m.imports.append((s, node.lineno, ()))
                rest = tuple(n for n in names if f"{target}.{n}" not in mods)
                if rest or not subs:
                    m.imports.append((_existing(target, mods), node.lineno, rest))
        stack: list[tuple[ast.AST, str]] = [(tree, "")]
        while stack:
            node, prefix = stack.pop()
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    q = f"{prefix}{child.name}"
                    if not isinstance(child, ast.ClassDef):
                        m.functions.append((q, child.lineno, (child.end_lineno or child.lineno) - child.lineno + 1))
                    stack.append((child, q + "."))
                else:
                    stack.append((child, prefix))
    return mods


def _existing(name: str, mods: dict[str, Module]) -> str:
    """The module an import refers to (a name inside a module: that module)."""
    while name not in mods and "." in name:
        name = name.rsplit(".", 1)[0]
    return name


def find_cycles(mods: dict[str, Module]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan), each sorted."""
    graph = {n: sorted({t for t, _, _ in m.imports if t in mods and t != n}) for n, m in mods.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on: set[str] = set()
    stack: list[str] = []
    out: list[list[str]] = []
    counter = [0]

    sys.setrecursionlimit(10000)

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def check(list_long: bool = False) -> list[str]:
    mods = read_modules()
    problems: list[str] = []
    for m in mods.values():
        here = layer_of(m.name)
        for target, line, names in m.imports:
            there = layer_of(target)
            where = f"{m.path.relative_to(ROOT)}:{line}"
            if (here is not None and there is not None and target != m.name
                    and (there[1] > here[1] or (there[1] == here[1] and there[0] != here[0]))):
                problems.append(f"{where}: layer {here[0]} imports {target} (layer {there[0]})")
            private = [n for n in names if n.startswith("_") and not n.startswith("__")]
            if private and target != m.name:
                problems.append(f"{where}: imports private {', '.join(private)} from {target}")
        if m.lines > MAX_MODULE_LINES:
            problems.append(f"{m.path.relative_to(ROOT)}: {m.lines} lines (at most {MAX_MODULE_LINES})")
        for q, line, n in m.functions:
            if n > MAX_FUNCTION_LINES:
                problems.append(f"{m.path.relative_to(ROOT)}:{line}: {q} is {n} lines (at most {MAX_FUNCTION_LINES})")
    for comp in find_cycles(mods):
        problems.append("import cycle: " + " <-> ".join(comp))
    long = sorted(((n, f"{m.path.relative_to(ROOT)}:{line}: {q}") for m in mods.values()
                   for q, line, n in m.functions if n > LONG_FUNCTION_LINES), reverse=True)
    if len(long) > MAX_LONG_FUNCTIONS:
        problems.append(f"{len(long)} functions over {LONG_FUNCTION_LINES} lines (at most {MAX_LONG_FUNCTIONS})")
    if list_long:
        for n, what in long:
            print(f"  {n:4d}  {what}")
    return problems


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--list", action="store_true", help="list every function over 60 lines")
    args = ap.parse_args(argv)
    problems = check(args.list)
    for p in problems:
        print(p)
    print(f"architecture: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
