"""Threads of a run: how many (memory decides), the realization chunks mapped over them with
failure and cancellation handling, and the interpreter's switch interval while they work.
Every realization's arithmetic is its own, so neither the chunking nor the threads change a
bit of a result.  Nothing here prints.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Callable, Iterator

from ..core import budget
from ..core.case import Case
from ..core.errors import Cancelled


class AnyEvent:
    """Set when the caller's cancel event is set or :meth:`set` was called (a failed chunk stops
    its siblings); duck-types the ``is_set`` of :class:`threading.Event` for the core loops."""

    def __init__(self, cancel: threading.Event | None) -> None:
        self._cancel, self._own = cancel, threading.Event()

    def set(self) -> None:
        self._own.set()

    def is_set(self) -> bool:
        return self._own.is_set() or (self._cancel is not None and self._cancel.is_set())


def map_chunks(fn: Callable[[int], object], n: int, threads: int, stop: AnyEvent) -> list:
    """[fn(0), ..., fn(n - 1)] in order, on up to ``threads`` threads.  The first failure sets
    ``stop`` (the other chunks end at their next cancellation check) and is raised once every
    started chunk has ended; a chunk stopped that way raises Cancelled, which is not reported."""
    if threads <= 1 or n <= 1:
        return [fn(i) for i in range(n)]
    from concurrent.futures import ThreadPoolExecutor

    out: list = [None] * n
    errors: list[tuple[int, BaseException]] = []

    def one(i: int) -> None:
        if stop.is_set():
            return
        try:
            out[i] = fn(i)
        except BaseException as exc:
            errors.append((i, exc))
            stop.set()

    ex = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="linecheck-chunk")
    try:
        list(ex.map(one, range(n)))
    except BaseException:  # e.g. Ctrl-C in the calling thread: the chunks stop at their next check
        stop.set()
        raise
    finally:
        ex.shutdown(wait=True, cancel_futures=True)
    if errors:
        real = [e for e in errors if not isinstance(e[1], Cancelled)]
        raise min(real or errors, key=lambda e: e[0])[1]
    if any(o is None for o in out):  # cancelled before that chunk started
        raise Cancelled("run cancelled")
    return out


#: [s] the interpreter's thread switch interval while a run's threads work (default 5 ms): the
#: chunks and the check alternate between GIL-free compiled work and short Python stretches,
#: and a thread that wants the GIL back waited up to the whole interval (measured, 60 spans:
#: two threads 4.3-5.3 s at 5 ms, 3.8-3.9 s at 1 ms, against 4.4-5.8 s on one thread)
SWITCH_INTERVAL = 0.001
_switch_lock = threading.Lock()
_switch_users = [0, 0.0]  # runs inside short_switch_interval, the interval before the first


@contextlib.contextmanager
def short_switch_interval() -> Iterator[None]:
    """:data:`SWITCH_INTERVAL` while at least one threaded run is inside; the previous interval
    restored when the last one leaves."""
    with _switch_lock:
        if _switch_users[0] == 0:
            _switch_users[1] = sys.getswitchinterval()
            sys.setswitchinterval(min(SWITCH_INTERVAL, _switch_users[1]))
        _switch_users[0] += 1
    try:
        yield
    finally:
        with _switch_lock:
            _switch_users[0] -= 1
            if _switch_users[0] == 0:
                sys.setswitchinterval(_switch_users[1])


def run_threads(case: Case, n_real: int, threads: int, *, burn_in: float | None = None,
                spectral_check: bool = True) -> int:
    """Threads for ``run_case``: at most ``threads`` and one per realization, and no more than
    keep the estimated memory (:func:`linecheck.core.budget.estimate`) within the limit; 1 when
    even that does not fit (``check_budget`` then refuses the run with its message)."""
    k = max(1, min(int(threads), int(n_real)))
    limit, _ = budget.memory_limit()
    while k > 1 and budget.estimate(case, "run", realizations=n_real, burn_in=burn_in,
                                    spectral_check=spectral_check, threads=k).memory > limit:
        k -= 1
    return k
