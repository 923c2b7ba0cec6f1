"""``--max-memory`` and resource warnings shared by the commands (resource guard).

The limit travels in the environment variable ``LINECHECK_MAX_MEMORY`` so that local batch
workers (spawned processes) inherit it; the estimate itself is
:func:`linecheck.service.check_budget`.
"""

from __future__ import annotations

import os
from typing import Annotated

import typer

from ..core.budget import ENV_MAX_MEMORY, parse_size
from .common import error_line

MaxMemoryOpt = Annotated[str | None, typer.Option(
    "--max-memory", help="Refuse jobs estimated to need more memory than this (e.g. 8GB, 512MB; "
                         "default 75 % of the physical memory, or LINECHECK_MAX_MEMORY).",
    show_default=False)]


def apply_max_memory(value: str | None) -> None:
    """Validate ``--max-memory`` (CaseError, exit 2) and hand it to the service and workers."""
    if value is None:
        return
    parse_size(value, key="--max-memory")
    os.environ[ENV_MAX_MEMORY] = value


def warn(message: str) -> None:
    """Print a resource warning (one line, stderr)."""
    error_line(message, label="warning", style="yellow")
