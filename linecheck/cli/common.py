"""What every CLI command shares: the Typer app they register on, the consoles, the error
handling, the path parser and the argument/option types.

Errors: every :class:`~linecheck.core.errors.LinecheckError` is printed once,
on one line, to stderr, with its exit code (2 for bad input); no tracebacks.

The commands import this module; :mod:`linecheck.cli.app` imports the commands (which registers
them on :data:`app`) and holds the console-script entry point.
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
from typer.core import TyperArgument, TyperGroup, TyperOption

try:  # the click that Typer runs on: vendored in recent Typer releases, the click package before
    from typer._click.exceptions import NoArgsIsHelpError, UsageError
except ImportError:  # pragma: no cover - older Typer
    from click.exceptions import NoArgsIsHelpError, UsageError
from rich.console import Console

from ..core.case import Case, load_case
from ..core.errors import LinecheckError, printable


def usage_line(err: UsageError) -> str:
    """One line for a command-line usage error: what is wrong, the usage, where the help is."""
    ctx = err.ctx
    msg = err.format_message().rstrip(".")
    if ctx is None:
        return msg
    pieces = " ".join(ctx.command.collect_usage_pieces(ctx))
    return f"{msg}; usage: {ctx.command_path} {pieces} (see {ctx.command_path} --help)"


class LinecheckGroup(TyperGroup):
    """The command group: a usage error of a command (a missing argument, an unknown option, a bad
    value) is one red line on stderr and exit code 2, like every other bad input (README)."""

    def invoke(self, ctx: Any) -> Any:
        try:
            return super().invoke(ctx)
        except NoArgsIsHelpError:
            raise
        except UsageError as err:
            error_line(usage_line(err))
            raise typer.Exit(2) from None


def _flag_without_type(option_cls: type) -> None:
    """Show a flag (``--force``) without a ``<bool>`` type beside it in the help: it takes no value.

    Typer's rich help prints the type of every option, flags included; this leaves the type
    column of flags empty (and keeps it for options that take a value).  A path parsed by
    :func:`path_value` shows as ``<path>``, like a plain ``Path`` parameter.
    """
    show = getattr(option_cls, "display_type_rich", None)
    if show is None or getattr(show, "_linecheck", False):
        return

    def display_type_rich(self: Any, ctx: Any) -> str | None:
        if getattr(self, "is_flag", False) and getattr(self, "metavar", None) is None:
            return None
        label = show(self, ctx)
        return "<path>" if label == "<Path>" else label

    display_type_rich._linecheck = True  # type: ignore[attr-defined]
    option_cls.display_type_rich = display_type_rich


_flag_without_type(TyperOption)
_flag_without_type(TyperArgument)

app = typer.Typer(
    cls=LinecheckGroup,
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

def error_line(text: str, label: str = "error", style: str = "bold red") -> None:
    """Print one message line to stderr, ``label: text``: no markup, no wrapping, hidden characters
    (ESC, NUL, bidi overrides) shown escaped (:func:`linecheck.core.errors.printable`).  Every
    error and warning line of the CLI goes through here."""
    err_console.print(f"[{style}]{label}:[/] {escape(printable(text))}", highlight=False, soft_wrap=True, emoji=False)


def path_value(value: str | Path) -> Path:
    """Parser of every path argument and option: the path as given.  An empty one (``''``) is a
    usage error saying so (a plain ``Path('')`` would be the current folder, ``.``)."""
    if isinstance(value, Path):
        return value
    if not value:
        raise typer.BadParameter("the path is empty: expected a file name")
    return Path(value)


CaseArg = Annotated[Path, typer.Argument(help="Case file (TOML).", show_default=False, metavar="CASE_FILE",
                                         parser=path_value)]
CasesArg = Annotated[list[Path], typer.Argument(help="Case files (TOML).", show_default=False, metavar="CASE_FILE",
                                                parser=path_value)]
JsonOpt = Annotated[Path | None, typer.Option("--json", help="Write the result as JSON to this file.",
                                              parser=path_value)]

F = TypeVar("F", bound=Callable[..., Any])


def handle_errors(fn: F) -> F:
    """Map linecheck errors to one red line on stderr and their exit code."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except LinecheckError as err:
            error_line(str(err))
            raise typer.Exit(err.exit_code) from None
        except KeyboardInterrupt:
            err_console.print("[bold red]interrupted[/]")
            raise typer.Exit(130) from None
        except (typer.Exit, typer.Abort):
            raise
        except Exception as err:  # a bug, not a user error: one line unless debugging
            if os.environ.get("LINECHECK_DEBUG"):
                raise
            error_line(f"{type(err).__name__}: {' '.join(str(err).split())} (set LINECHECK_DEBUG=1 for the traceback; "
                       "please report it)", label="internal error")
            raise typer.Exit(1) from None

    return wrapper  # type: ignore[return-value]


def read_case(path: Path) -> Case:
    return load_case(path)


def write_run_outputs(doc: Any, json_out: Path | None, excel: Path | None, template: Path | None,
                      force: bool, fields: dict[str, str] | None) -> None:
    """Write a run document's JSON result and Excel workbook asked for (``doc`` a
    :class:`~linecheck.io.document.RunDocument`, one wire or several), each with a "wrote" line."""
    if json_out is not None:
        from ..io.jsonout import write_json

        write_json(json_out, doc)
        console.print(f"wrote {json_out}")
    if excel is not None:
        from ..excel.writer import write_workbook

        write_workbook([doc], excel, template=template, force=force, title=fields or None)
        console.print(f"wrote {excel}")
