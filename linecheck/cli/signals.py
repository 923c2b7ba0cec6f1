"""SIGTERM handled like a cancel by the long commands (``batch``, ``scan``).

A job scheduler, ``kill`` or a closing session ends a process with SIGTERM.  Python's default
action ends it at once: no summary, the results of finished cases unreported, the process
pool's workers and their semaphores left to the resource tracker ("leaked semaphore objects").
Inside :func:`sigterm_cancels` the first SIGTERM sets the command's cancel event instead, which
the batch and scan coordinators poll (every ``linecheck.batch.runner.POLL_S``): the command stops
as on Ctrl-C — tasks cancelled, workers stopped, the summary printed, exit 130.

The handler only sets the event, from a short thread: it raises nothing in the main thread.  An
exception raised asynchronously there (as a KeyboardInterrupt from a handler would be) can land
between a lock's acquire and its ``try``, leaving a future's lock held, and the process pool's
manager thread then waits on it for ever at exit (seen as a hung batch after SIGTERM).  A second
SIGTERM while the command stops ends the process at once (the default action).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


@contextlib.contextmanager
def sigterm_cancels(cancel: threading.Event) -> Iterator[None]:
    """Within the block the first SIGTERM sets ``cancel``; a second one takes the default action.

    Only in the main thread (where Python runs signal handlers); elsewhere it does nothing.
    The previous handler is restored on the way out.
    """
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        yield
        return

    def on_sigterm(signum: int, frame: object) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second SIGTERM: the default action
        # set from another thread: the interrupted code may hold the event's own lock
        threading.Thread(target=cancel.set, name="sigterm-cancel", daemon=True).start()

    previous = signal.signal(signal.SIGTERM, on_sigterm)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)
