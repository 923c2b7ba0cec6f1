"""SIGTERM handled like Ctrl-C by the long commands (``batch``, ``scan``).

A job scheduler, ``kill`` or a closing session ends a process with SIGTERM.  Python's default
action ends it at once: no summary, the results of finished cases unreported, the process
pool's workers and their semaphores left to the resource tracker ("leaked semaphore objects").
Inside :func:`sigterm_as_interrupt` the first SIGTERM raises :class:`KeyboardInterrupt` in the
main thread instead, exactly what Ctrl-C does, so the command stops the same way: the batch
cancels its tasks, stops its workers, prints the summary and exits with 130.  A second SIGTERM
while it does so ends the process at once (the default action).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block (or the decorated command), SIGTERM raises KeyboardInterrupt once.

    Only in the main thread (where Python runs signal handlers); elsewhere it does nothing.
    The previous handler is restored on the way out.
    """
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        yield
        return

    def interrupt(signum: int, frame: object) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second SIGTERM: the default action
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)
