"""Every piece of the compiled kernel with its load check registered.

:mod:`linecheck.core.kernel` knows the pieces' names but imports no other core module; each core
module that owns a piece's numpy form registers the piece's load check when it is imported
(:func:`linecheck.core.kernel.register_check`).  Importing this module imports all of them, so
that :func:`status` reports every piece (``linecheck info``, the provenance block).
"""

from __future__ import annotations

from . import dynamics, kernel, results, second_order, spectral, static
from .kernel import PieceState
from .wind import mean, turbulence, wires

#: the modules that register the kernel's pieces (piece -> module)
OWNERS = {
    "newmark": dynamics, "rotate": dynamics, "rowdot": dynamics, "spectrum": turbulence, "mixing": wires,
    "loads": kernel, "span": static, "reductions": results, "field": mean, "quad": spectral,
    "second_order": second_order, "second_order_loop": second_order,
}


def status() -> tuple[PieceState, ...]:
    """:func:`linecheck.core.kernel.status` with every piece's check registered."""
    return kernel.status()
