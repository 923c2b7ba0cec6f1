"""Command-line front end (Typer).  Commands parse, call one service function, print.

Errors: every :class:`~linecheck.core.errors.LinecheckError` is printed once,
on one line, to stderr, with its exit code (2 for bad input); no tracebacks.
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer
from rich.markup import escape
from rich.console import Console

from ..core.case import Case, load_case
from ..core.errors import LinecheckError

app = typer.Typer(
    name="linecheck",
    help="Dynamic design check of transmission-line conductors under downburst and synoptic winds.",
    no_args_is_help=True,
    rich_markup_mode="rich",
    pretty_exceptions_show_locals=False,
    add_completion=False,
)

# Piped output (CI, files) gets a wide console so result tables are not truncated.
console = Console(width=None if sys.stdout.isatty() else 160)
err_console = Console(stderr=True, width=None if sys.stderr.isatty() else 160)

CaseArg = Annotated[Path, typer.Argument(help="Case file (TOML).", show_default=False)]
CasesArg = Annotated[list[Path], typer.Argument(help="Case files (TOML).", show_default=False)]
JsonOpt = Annotated[Path | None, typer.Option("--json", help="Write the result as JSON to this file.")]

F = TypeVar("F", bound=Callable[..., Any])


def handle_errors(fn: F) -> F:
    """Map linecheck errors to one red line on stderr and their exit code."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except LinecheckError as err:
            err_console.print(f"[bold red]error:[/] {escape(str(err))}", highlight=False, soft_wrap=True, emoji=False)
            raise typer.Exit(err.exit_code) from None
        except KeyboardInterrupt:
            err_console.print("[bold red]interrupted[/]")
            raise typer.Exit(130) from None
        except (typer.Exit, typer.Abort):
            raise
        except Exception as err:  # a bug, not a user error: one line unless debugging
            if os.environ.get("LINECHECK_DEBUG"):
                raise
            err_console.print(f"[bold red]internal error:[/] {type(err).__name__}: {escape(str(err))} "
                              "(set LINECHECK_DEBUG=1 for the traceback; please report it)", highlight=False, emoji=False)
            raise typer.Exit(1) from None

    return wrapper  # type: ignore[return-value]


def read_case(path: Path) -> Case:
    return load_case(path)


# Command modules register themselves on ``app`` when imported.
from . import commands  # noqa: E402,F401


def main() -> None:
    """Console-script entry point."""
    app(prog_name="linecheck")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
