"""linecheck: dynamic design check of transmission-line conductors under wind.

The dense linear algebra here is small (a few hundred unknowns) and parallelism is at
the process level (``linecheck batch --jobs``), so multi-threaded BLAS only adds
contention: on a busy 2-core machine a 344x344 eigenproblem took 0.2-3 s with two
OpenBLAS threads and 0.065 s with one (docs/performance.md).  Unless the user chose
otherwise, linecheck asks for one BLAS thread; this takes effect when numpy is first
imported after linecheck (the CLI, the TUI, batch workers).
"""

import os as _os

_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__version__ = "0.1.0"
