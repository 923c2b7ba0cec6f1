"""One error hierarchy for linecheck.

Front ends catch :class:`LinecheckError`, print ``str(err)`` once (one line) and
exit with ``err.exit_code``.  Nothing in the core prints.

- :class:`CaseError` -- bad user input (case file, field file, CLI value): exit 2.
- :class:`ConvergenceError` -- the static solver found no admissible equilibrium: exit 1.
- :class:`NumericalError` -- NaN/inf or a non-positive-definite state: exit 1.
- :class:`Cancelled` -- the user cancelled a long job: exit 130.
"""

from __future__ import annotations


class LinecheckError(Exception):
    """Base class of every error linecheck reports to a user."""

    exit_code: int = 1
    title: str = "Error"

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:  # one line, always
        return " ".join(self.message.split())


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


class Cancelled(LinecheckError):
    """A long job was cancelled through its cancel event."""

    exit_code = 130
    title = "Cancelled"
