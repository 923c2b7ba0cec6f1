"""Typed messages of the TUI (dataclasses; Pilot tests record and assert on them)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from textual.message import Message

from ..core.case import Case
from .runner import RunOutput


@dataclass
class OpenCaseRequested(Message):
    """The browser (or the command palette) asks to open a case file."""

    path: Path


@dataclass
class CaseOpened(Message):
    """A case file was loaded and validated; it is now the current case."""

    case: Case
    path: Path


@dataclass
class ParameterChanged(Message):
    """The editor applied a valid value: ``case`` is the validated copy."""

    case: Case
    key: str
    value: Any


@dataclass
class ParameterRejected(Message):
    """The editor refused a value; ``message`` is the case validation's text (as in the CLI)."""

    key: str
    text: str
    message: str


@dataclass
class RunStarted(Message):
    case: Case


@dataclass
class RunProgress(Message):
    """``progress(stage, done, total)`` of the service, posted from the worker thread."""

    stage: str
    done: int
    total: int

    def can_replace(self, message: Message) -> bool:
        # a flood of updates of one stage collapses to the newest
        return isinstance(message, RunProgress) and message.stage == self.stage


@dataclass
class RunFinished(Message):
    """A run completed; ``output.doc`` is the typed ``linecheck run`` document (RunDocument)."""

    output: RunOutput


@dataclass
class RunCancelled(Message):
    case: Case


@dataclass
class RunFailed(Message):
    """A run stopped with an error (shown in a modal); ``title`` and ``message`` as shown."""

    title: str
    message: str


@dataclass
class Exported(Message):
    """A file was written: ``kind`` is "xlsx", "json" or "toml"."""

    kind: str
    path: Path
