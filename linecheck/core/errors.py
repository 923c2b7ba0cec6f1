"""One error hierarchy for linecheck.

Front ends catch :class:`LinecheckError`, print ``str(err)`` once (one line) and
exit with ``err.exit_code``.  Nothing in the core prints.

- :class:`CaseError` -- bad user input (case file, field file, CLI value): exit 2.
- :class:`ConvergenceError` -- the static solver found no admissible equilibrium: exit 1.
- :class:`NumericalError` -- NaN/inf or a non-positive-definite state: exit 1.
- :class:`UpliftError` -- a job that linearises about the mean states met an uplifting
  suspension insulator (step 1 itself reports the uplift): exit 1.
- :class:`Cancelled` -- the user cancelled a long job: exit 130.

Every message is shown through :func:`printable`: control characters (ESC, NUL, ...), bidi
overrides (U+202E) and other invisible format characters a file or a name may carry are shown
escaped (``\\x1b``, ``\\u202e``), never sent raw to a terminal.
"""

from __future__ import annotations

import unicodedata

#: Unicode categories shown escaped: controls (Cc), format characters such as the bidi overrides
#: and zero-width marks (Cf), lone surrogates (Cs), line and paragraph separators (Zl, Zp).
_HIDDEN = frozenset({"Cc", "Cf", "Cs", "Zl", "Zp"})


def _escaped(ch: str) -> str:
    n = ord(ch)
    return f"\\x{n:02x}" if n < 0x100 else (f"\\u{n:04x}" if n < 0x10000 else f"\\U{n:08x}")


def printable(text: str) -> str:
    r"""``text`` with every control, bidi or other invisible format character escaped
    (ESC -> ``\x1b``, U+202E -> ``\u202e``); other text (accents, symbols,
    any script) unchanged.  The one helper every message goes through before a terminal, a log
    or a dialog shows it."""
    if text.isprintable():  # the usual case: nothing hidden (str.isprintable is False for all of _HIDDEN)
        return text
    return "".join(_escaped(ch) if unicodedata.category(ch) in _HIDDEN else ch for ch in text)


class LinecheckError(Exception):
    """Base class of every error linecheck reports to a user."""

    exit_code: int = 1
    title: str = "Error"

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:  # one line, always; hidden characters shown escaped
        return printable(" ".join(self.message.split()))


class CaseError(LinecheckError):
    """Invalid input: names the file, key (and line), value and what is allowed."""

    exit_code = 2
    title = "Invalid input"

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        key: str | None = None,
        line: int | None = None,
    ) -> None:
        where = ""
        if file is not None:
            where = f"{file}"
            if line is not None:
                where += f":{line}"
            where += ": "
        if key is not None:
            where += f"{key}: "
        super().__init__(where + message)
        self.file = file
        self.key = key
        self.line = line


class ConvergenceError(LinecheckError):
    """The non-linear static solver did not converge (names the state and residual)."""

    exit_code = 1
    title = "No convergence"


class NumericalError(LinecheckError):
    """NaN/inf or a non-positive-definite matrix was met; nothing is written."""

    exit_code = 1
    title = "Numerical failure"


class UpliftError(LinecheckError):
    """A suspension insulator would be in compression (uplift) in a state a job needs in tension:
    the dynamic model linearises about the mean states with every suspension insulator hanging.
    Names the case, the tower and its vertical margin [N]."""

    exit_code = 1
    title = "Uplift"


class Cancelled(LinecheckError):
    """A long job was cancelled through its cancel event."""

    exit_code = 130
    title = "Cancelled"
