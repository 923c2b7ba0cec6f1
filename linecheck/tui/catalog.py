"""Case discovery for the browser: folders and ``*.toml`` files with a one-line description.

Plain Python (no Textual).  Only the ``name``/``description`` keys are read here
(fast, a plain TOML parse); a case is validated when it is opened.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class CaseEntry:
    """One case file: its name and description, or why it could not be read."""

    path: Path
    name: str
    description: str = ""
    error: str | None = None


@dataclass(frozen=True)
class Folder:
    """A folder of cases (sub-folders first, then files, both sorted)."""

    path: Path
    label: str
    folders: tuple[Folder, ...] = ()
    cases: tuple[CaseEntry, ...] = ()
    error: str | None = None

    def all_cases(self) -> list[CaseEntry]:
        out: list[CaseEntry] = []
        for f in self.folders:
            out.extend(f.all_cases())
        out.extend(self.cases)
        return out


@dataclass
class Catalog:
    """What the browser shows: folders and loose files given on the command line."""

    folders: list[Folder] = field(default_factory=list)
    files: list[CaseEntry] = field(default_factory=list)
    missing: list[Path] = field(default_factory=list)

    def all_cases(self) -> list[CaseEntry]:
        out: list[CaseEntry] = []
        for f in self.folders:
            out.extend(f.all_cases())
        out.extend(self.files)
        return out

    @property
    def empty(self) -> bool:
        return not self.all_cases()


def read_entry(path: Path) -> CaseEntry:
    """Name and description of one case file (never raises)."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        return CaseEntry(path, path.stem, error=f"cannot read: {exc}")
    except tomllib.TOMLDecodeError as exc:
        return CaseEntry(path, path.stem, error=f"TOML syntax error: {exc}")
    name = data.get("name") if isinstance(data.get("name"), str) else None
    desc = data.get("description") if isinstance(data.get("description"), str) else ""
    return CaseEntry(path, name or path.stem, " ".join(desc.split()))


def scan_folder(path: Path, label: str | None = None, *, depth: int = 0, max_depth: int = 6) -> Folder:
    """A folder tree of case files (hidden entries skipped)."""
    try:
        entries = sorted(path.iterdir(), key=lambda p: (p.stem, p.name))  # "a" before "a-edited"
    except OSError as exc:
        return Folder(path, label or path.name, error=str(exc))
    folders = []
    if depth < max_depth:
        for p in entries:
            if p.is_dir() and not p.name.startswith((".", "__")):
                sub = scan_folder(p, depth=depth + 1, max_depth=max_depth)
                if sub.folders or sub.cases:
                    folders.append(sub)
    cases = tuple(read_entry(p) for p in entries if p.is_file() and p.suffix == ".toml" and not p.name.startswith("."))
    return Folder(path, label or path.name, tuple(folders), cases)


def default_paths(cwd: Path | None = None) -> list[Path]:
    """``./cases`` when it exists, else the ``cases/`` folder next to the package (source checkouts)."""
    cwd = Path.cwd() if cwd is None else cwd
    if (cwd / "cases").is_dir():
        return [Path("cases")] if cwd == Path.cwd() else [cwd / "cases"]
    shipped = Path(__file__).resolve().parents[2] / "cases"
    return [shipped] if shipped.is_dir() else []


def shown_path(p: Path) -> str:
    """``p`` relative to the working folder when it is below it."""
    try:
        return str(p.resolve().relative_to(Path.cwd().resolve())) or "."
    except ValueError:
        return str(p)


def discover(paths: list[Path] | None = None) -> Catalog:
    """The catalog of ``paths`` (folders and files); :func:`default_paths` when none are given."""
    cat = Catalog()
    for p in (default_paths() if not paths else paths):
        p = Path(p)
        if p.is_dir():
            cat.folders.append(scan_folder(p, label=shown_path(p)))
        elif p.is_file():
            cat.files.append(read_entry(p))
        else:
            cat.missing.append(p)
    return cat
