"""Where a result was computed: library versions, the BLAS in use and the compiled kernel's pieces.

``linecheck info`` prints :func:`provenance`; every result document carries its JSON form as the
top-level ``"provenance"`` block, so that two results that differ by more than their tolerance
can be traced to a library version, another CPU's BLAS kernels (OpenBLAS picks its core kernels
per CPU: Haswell, SkylakeX, Zen, ... round differently) or a compiled piece that was off
(:mod:`linecheck.core.kernel`: whether a piece runs depends only on the installation and
``LINECHECK_KERNEL``, so the pieces on when the document is made are those the run used).

JSON layout (:meth:`Provenance.to_json`)::

    {"linecheck": "0.1.0", "python": "3.11.7", "numpy": "2.4.6", "scipy": "1.17.1",
     "numba": "0.61.2" | "not installed",
     "blas": {"library", "version", "core", "threads", "path"},   # the BLAS numpy calls
     "scipy_blas": {...} | null,    # the BLAS/LAPACK scipy.linalg calls, null when numpy's
     "kernel": {"installed": bool, "mode": "auto" | "numpy" | "numba",
                "pieces": [{"name", "on", "reason"}, ...]}}

Versions come from the installed distributions (:mod:`importlib.metadata`: Numba is not
imported for its version); the BLAS from ``threadpoolctl`` (the libraries loaded in this
process, each with its version, OpenBLAS's core type and thread count), imported inside
:func:`blas_libraries`.  No UI imports.
"""

from __future__ import annotations

import platform
from dataclasses import dataclass
from pathlib import Path
from typing import Any

NOT_INSTALLED = "not installed"


def _version(dist: str) -> str:
    """The installed version of distribution ``dist``, or :data:`NOT_INSTALLED`."""
    from importlib import metadata

    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return NOT_INSTALLED


@dataclass(frozen=True)
class Blas:
    """A BLAS library loaded in this process.

    Attributes:
        library: its kind as threadpoolctl names it ("openblas", "mkl", "blis"), or "unknown".
        version: its version, None when it does not say.
        core: the core kernel it selected for this CPU (OpenBLAS: "Haswell", "SkylakeX",
            "Zen", ...), None when the library does not say.
        threads: [-] its thread count, None when unknown.
        path: the shared library's file.
    """

    library: str
    version: str | None = None
    core: str | None = None
    threads: int | None = None
    path: str | None = None

    def to_json(self) -> dict[str, Any]:
        return {"library": self.library, "version": self.version, "core": self.core, "threads": self.threads,
                "path": self.path}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Blas:
        return cls(str(d.get("library", "unknown")), d.get("version"), d.get("core"), d.get("threads"), d.get("path"))

    def text(self) -> str:
        """``"openblas 0.3.30, core SkylakeX, 2 threads"``."""
        parts = [" ".join(x for x in (self.library, self.version) if x)]
        if self.core:
            parts.append(f"core {self.core}")
        if self.threads is not None:
            parts.append(f"{self.threads} thread{'s' if self.threads != 1 else ''}")
        return ", ".join(parts)


@dataclass(frozen=True)
class Piece:
    """One piece of the compiled kernel: on (compiled) or off and why (``reason``, "" when on)."""

    name: str
    on: bool
    reason: str = ""
    description: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "on": self.on, "reason": self.reason}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Piece:
        return cls(str(d["name"]), bool(d["on"]), str(d.get("reason", "")))


@dataclass(frozen=True)
class Kernel:
    """The compiled kernel: Numba installed, ``LINECHECK_KERNEL`` mode, every piece's state."""

    installed: bool
    mode: str
    pieces: tuple[Piece, ...]

    @property
    def off(self) -> tuple[Piece, ...]:
        return tuple(p for p in self.pieces if not p.on)

    def to_json(self) -> dict[str, Any]:
        return {"installed": self.installed, "mode": self.mode, "pieces": [p.to_json() for p in self.pieces]}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Kernel:
        return cls(bool(d.get("installed", False)), str(d.get("mode", "auto")),
                   tuple(Piece.from_json(p) for p in d.get("pieces", ())))


@dataclass(frozen=True)
class Provenance:
    """Versions, BLAS and kernel state of this process (:func:`provenance`)."""

    linecheck: str
    python: str
    numpy: str
    scipy: str
    numba: str
    blas: Blas
    scipy_blas: Blas | None
    kernel: Kernel

    def to_json(self) -> dict[str, Any]:
        return {"linecheck": self.linecheck, "python": self.python, "numpy": self.numpy, "scipy": self.scipy,
                "numba": self.numba, "blas": self.blas.to_json(),
                "scipy_blas": None if self.scipy_blas is None else self.scipy_blas.to_json(),
                "kernel": self.kernel.to_json()}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Provenance:
        sb = d.get("scipy_blas")
        return cls(str(d["linecheck"]), str(d["python"]), str(d["numpy"]), str(d["scipy"]), str(d["numba"]),
                   Blas.from_json(d.get("blas") or {}), None if sb is None else Blas.from_json(sb),
                   Kernel.from_json(d.get("kernel") or {}))


def _owned_by(path: str, package: Any) -> bool:
    """Whether the library file ``path`` ships with ``package`` (in its folder or its wheel's
    ``<name>.libs`` folder beside it)."""
    folder = Path(package.__file__).resolve().parent
    try:
        first = Path(path).resolve().relative_to(folder.parent).parts[0]
    except (ValueError, IndexError):
        return False
    return first in (folder.name, folder.name + ".libs")


def blas_libraries() -> tuple[Blas, Blas | None]:
    """(the BLAS numpy calls, the BLAS scipy.linalg calls or None when it is numpy's).

    The wheels on PyPI each ship their own OpenBLAS (numpy's for ``matmul``; scipy's for LAPACK,
    the banded solves, and the compiled second-order loop's ``dgemm``); a conda or system
    install links both to one library.  Loads scipy.linalg (and with it scipy's BLAS) to see it.
    """
    import numpy
    import scipy
    import scipy.linalg

    try:
        from threadpoolctl import threadpool_info
    except ImportError:  # a dependency; an install without it still runs
        return Blas("unknown (threadpoolctl not installed)"), None
    found = [i for i in threadpool_info() if i.get("user_api") == "blas"]

    def blas(i: dict[str, Any]) -> Blas:
        return Blas(str(i.get("internal_api") or "unknown"), i.get("version"), i.get("architecture"),
                    i.get("num_threads"), i.get("filepath"))

    own = [i for i in found if _owned_by(str(i.get("filepath", "")), numpy)]
    theirs = [i for i in found if _owned_by(str(i.get("filepath", "")), scipy)]
    np_blas = own[0] if own else next((i for i in found if i not in theirs), found[0] if found else None)
    sp_blas = theirs[0] if theirs and theirs[0] is not np_blas else None
    return (Blas("unknown") if np_blas is None else blas(np_blas)), (None if sp_blas is None else blas(sp_blas))


def kernel_state() -> Kernel:
    """Every piece of the compiled kernel (:func:`linecheck.core.kernel.status`: loads the kernel
    first unless ``LINECHECK_KERNEL=numpy``; ≈ 0.5 s once per process with Numba's cache warm)."""
    from ..core.pieces import kernel  # with every piece's load check registered

    pieces = tuple(Piece(p.name, bool(p.on), p.reason, p.description) for p in kernel.status())
    return Kernel(kernel.installed(), kernel.mode(), pieces)


def provenance() -> Provenance:
    """Versions (linecheck, Python, numpy, scipy, Numba), the BLAS libraries in use and the
    compiled kernel's pieces in this process: what ``linecheck info`` prints and every result
    document records as ``"provenance"``."""
    np_blas, sp_blas = blas_libraries()
    return Provenance(_version("linecheck"), platform.python_version(), _version("numpy"), _version("scipy"),
                      _version("numba"), np_blas, sp_blas, kernel_state())


def kernel_warning(k: Kernel | None = None) -> str | None:
    """One line naming the compiled kernel's pieces that are off and why, or None: when every
    piece is on, Numba is not installed or ``LINECHECK_KERNEL=numpy`` (numpy by choice: nothing
    to warn about).  ``k`` defaults to :func:`kernel_state` (which loads the kernel)."""
    from ..core import kernel

    if k is None:
        if not kernel.installed() or kernel.mode() == "numpy":
            return None  # decided without loading the kernel
        k = kernel_state()
    if not k.installed or k.mode == "numpy" or not k.off:
        return None
    pieces = ", ".join(f"{p.name} ({p.reason})" if p.reason else p.name for p in k.off)
    return f"compiled kernel pieces off: {pieces}; results are the same within tolerance, slower"
