"""Where batch tasks run: in this process, in a local process pool, or on Dask.

All three share one small interface used by the batch and scan runners:

- ``submit(fn, *args, **kwargs)`` -> a handle (``fn`` a top-level importable function
  of :mod:`linecheck.batch.tasks` taking plain data);
- ``wait(handles, timeout)`` -> indices of the handles that are finished;
- ``outcome(handle)`` -> the task's return value, or a :class:`~.tasks.Failure`
  when the task raised (a bug, a killed worker, a broken pool);
- ``running(handle)`` -> best-effort "has started" flag (progress display only);
- ``abort(handles)`` -> cancel what has not run and stop what is running;
- ``close()``;
- process pool only (``reporting``): ``reports()`` -> start/progress messages sent by the
  tasks from inside the workers; ``broken()``/``restart()`` -> a worker died, start a new
  pool and learn which workers died on their own.

The sequential executor runs one task per ``wait`` call in the calling process and
passes it the batch's ``cancel`` event and a progress callback (``in_process``).
The process pool and Dask run tasks elsewhere; cancellation takes effect between
tasks (pending ones are cancelled; running pool tasks are asked to stop through the pool's
stop event and their workers terminated only if they do not).
Dask is imported lazily: without the ``dask`` extra a :class:`CaseError` says how
to install it.  Nothing here prints or imports a UI library.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import signal
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor
from concurrent.futures import wait as futures_wait
from typing import Any

from ..core.errors import Cancelled, CaseError
from .tasks import Failure, init_pool_worker, noop


def default_jobs() -> int:
    """Number of local workers by default: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


class Executor(ABC):
    """Common interface of the batch executors (see the module docstring)."""

    name: str = "executor"
    #: tasks run in the calling process and accept ``progress=``/``cancel=`` keywords
    in_process: bool = False

    @property
    @abstractmethod
    def workers(self) -> int:
        """Number of tasks that can run at once."""

    @abstractmethod
    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any: ...

    @abstractmethod
    def wait(self, handles: Sequence[Any], timeout: float | None = None) -> list[int]: ...

    @abstractmethod
    def outcome(self, handle: Any) -> Any: ...

    def running(self, handle: Any) -> bool:
        return False

    #: tasks accept ``report_key=`` and report start/progress through :meth:`reports`
    reporting: bool = False

    def reports(self) -> list[tuple]:
        """Start/progress messages of the tasks received since the last call (see :attr:`reporting`)."""
        return []

    def broken(self) -> bool:
        """True when the executor lost a worker and must be :meth:`restart`-ed to run more tasks."""
        return False

    def restart(self) -> dict[int, int]:
        """Replace a broken executor's workers; returns ``{pid: exit code}`` of the workers that
        died on their own (not stopped by the executor).  Only where :meth:`broken` can be true."""
        raise NotImplementedError

    @abstractmethod
    def cancel(self, handles: Sequence[Any]) -> None:
        """Cancel tasks that have not started (running ones finish; their results are ignored)."""

    @abstractmethod
    def abort(self, handles: Sequence[Any]) -> None:
        """Stop the batch: cancel pending tasks and stop running ones where possible."""

    def close(self) -> None:  # noqa: B027 - optional hook
        pass

    def describe(self) -> str:
        return f"{self.name} ({self.workers} worker{'s' if self.workers != 1 else ''})"

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# --------------------------------------------------------------------------- sequential
class _Deferred:
    __slots__ = ("args", "fn", "kwargs", "state", "value")

    def __init__(self, fn: Callable[..., Any], args: tuple, kwargs: dict) -> None:
        self.fn, self.args, self.kwargs = fn, args, kwargs
        self.state = "pending"  # pending | running | done | cancelled
        self.value: Any = None


class SequentialExecutor(Executor):
    """Run tasks one by one in this process (``--jobs 1``)."""

    name = "sequential"
    in_process = True

    @property
    def workers(self) -> int:
        return 1

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> _Deferred:
        return _Deferred(fn, args, kwargs)

    def wait(self, handles: Sequence[_Deferred], timeout: float | None = None) -> list[int]:
        done = [i for i, h in enumerate(handles) if h.state in ("done", "cancelled")]
        if done:
            return done
        for i, h in enumerate(handles):
            if h.state == "pending":
                h.state = "running"
                try:
                    h.value = h.fn(*h.args, **h.kwargs)
                except Cancelled:
                    h.state = "cancelled"
                    raise
                except Exception as exc:  # a bug in one task must not stop the others
                    h.value = Failure.of(exc)
                h.state = "done"
                return [i]
        return []

    def outcome(self, handle: _Deferred) -> Any:
        return handle.value

    def running(self, handle: _Deferred) -> bool:
        return handle.state != "pending"

    def cancel(self, handles: Sequence[_Deferred]) -> None:
        for h in handles:
            if h.state == "pending":
                h.state = "cancelled"

    def abort(self, handles: Sequence[_Deferred]) -> None:
        self.cancel(handles)


# --------------------------------------------------------------------------- process pool
#: environment of the pool's worker processes: one BLAS/OpenMP thread each (N workers already
#: use the N cores; with more threads the workers' spinning BLAS threads fight for them)
WORKER_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


@contextlib.contextmanager
def _worker_environment() -> Iterator[None]:
    """Set :data:`WORKER_ENV` (where not set by the user) while worker processes start."""
    added = {k: v for k, v in WORKER_ENV.items() if k not in os.environ}
    os.environ.update(added)
    try:
        yield
    finally:
        for k in added:
            os.environ.pop(k, None)


#: [s] how long an aborted batch waits for its running tasks to stop on their own before it
#: terminates their workers (they check for cancellation every block of steps: milliseconds)
ABORT_GRACE_S = 30.0


class ProcessPool(Executor):
    """A local :class:`concurrent.futures.ProcessPoolExecutor` (``--jobs N``).

    Workers are started at once with the ``spawn`` method -- they never inherit the
    coordinator's threads (progress display, Dask) -- and with one BLAS thread each
    (:data:`WORKER_ENV`, unless set by the user).  Ctrl-C is left to the coordinator.
    Workers exit when the coordinator dies (:func:`~.tasks.init_pool_worker`).

    Tasks report their start (with the worker's pid) and progress on a queue
    (:meth:`reports`).  When a worker dies (an out-of-memory kill, a crash) the pool is
    *broken*: every unfinished task fails with ``BrokenProcessPool`` and the other workers
    are stopped; :meth:`restart` starts a new pool and says which workers died on their
    own, so the runner can fail only the tasks those held and re-run the others.
    """

    name = "process pool"
    reporting = True

    def __init__(self, jobs: int | None = None) -> None:
        if jobs is not None and jobs < 1:
            raise CaseError(f"--jobs: value {jobs} is not allowed: expected an integer >= 1")
        self._jobs = jobs or default_jobs()
        self._start()

    def _start(self) -> None:
        ctx = multiprocessing.get_context("spawn")
        self._queue = ctx.SimpleQueue()
        self._stop = ctx.Event()  # set by abort: the workers' tasks end at their next cancellation check
        # PR_SET_PDEATHSIG follows the thread that starts a worker: only from the main thread
        pdeathsig = threading.current_thread() is threading.main_thread()
        self._pool = ProcessPoolExecutor(max_workers=self._jobs, mp_context=ctx, initializer=init_pool_worker,
                                         initargs=(self._queue, os.getpid(), pdeathsig, self._stop))
        with _worker_environment():  # each submit starts one worker while none is idle
            for _ in range(self._jobs):
                self._pool.submit(noop)

    @property
    def workers(self) -> int:
        return self._jobs

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        return self._pool.submit(fn, *args, **kwargs)

    def wait(self, handles: Sequence[Future], timeout: float | None = None) -> list[int]:
        futures_wait(handles, timeout=timeout, return_when=FIRST_COMPLETED)
        return [i for i, f in enumerate(handles) if f.done()]

    def reports(self) -> list[tuple]:
        out = []
        q = self._queue
        with contextlib.suppress(OSError, EOFError, ValueError):
            while not q.empty():
                out.append(q.get())
        return out

    def outcome(self, handle: Future) -> Any:
        if handle.cancelled():
            return Failure("Cancelled", "cancelled", 130)
        exc = handle.exception()
        if exc is not None:
            return Failure.of(exc)
        return handle.result()

    def running(self, handle: Future) -> bool:
        return handle.running() or handle.done()

    def broken(self) -> bool:
        return bool(getattr(self._pool, "_broken", False))

    def restart(self) -> dict[int, int]:
        processes = dict(getattr(self._pool, "_processes", None) or {})
        self._pool.shutdown(wait=True, cancel_futures=True)  # the broken pool stops and joins its workers
        for p in processes.values():
            p.join()
        dead = {pid: p.exitcode for pid, p in processes.items()
                if p.exitcode not in (0, None, -signal.SIGTERM)}  # SIGTERM: stopped by the pool itself
        with contextlib.suppress(OSError):
            self._queue.close()
        self._start()
        return dead

    def cancel(self, handles: Sequence[Future]) -> None:
        for f in handles:
            f.cancel()

    def abort(self, handles: Sequence[Future]) -> None:
        """Cancel the pending tasks and ask the running ones to stop (the pool's stop event:
        they raise Cancelled at their next cancellation check, within a block of steps or a
        scan point); a worker still busy after :data:`ABORT_GRACE_S` is terminated.  Workers
        that stop on their own leave the pool's queues clean, so its shutdown cannot hang on
        a message cut off by a kill."""
        processes = dict(getattr(self._pool, "_processes", None) or {})
        self._stop.set()
        self.cancel(handles)
        futures_wait([f for f in handles if not f.done()], timeout=ABORT_GRACE_S)
        self._pool.shutdown(wait=False, cancel_futures=True)
        for p in processes.values():  # a task that did not stop in time (Python < 3.14 has no API)
            if p.is_alive() and any(not f.done() for f in handles):
                p.terminate()
        for p in processes.values():
            p.join(timeout=5)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        with contextlib.suppress(OSError):
            self._queue.close()


def describe_exit(code: int | None) -> str:
    """How a worker process ended, for messages: ``killed by signal 9, SIGKILL: out of memory?``."""
    if code is None:
        return "ended"
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = "unknown signal"
        hint = ": out of memory?" if -code == getattr(signal, "SIGKILL", 9) else ""
        return f"killed by signal {-code}, {name}{hint}"
    return f"exited with code {code}"


# --------------------------------------------------------------------------- Dask
DASK_MISSING = ("--scheduler needs Dask distributed, which is not installed: "
                "pip install 'linecheck[dask]' (or: pip install 'dask[distributed]')")


DEFAULT_CONNECT_TIMEOUT = 10.0  # [s] --connect-timeout: TCP connection, then the scheduler's handshake
MAX_HANDSHAKE_BYTES = 1 << 20  # a Dask handshake is a few hundred bytes; more is not a Dask scheduler


def check_scheduler_address(address: str) -> tuple[str, int]:
    """Validate a scheduler address ``tcp://HOST:PORT`` (port default 8786); returns (host, port).

    Only ``tcp://`` is accepted: ``tls://`` needs certificates this command cannot take,
    ``ucx://``/``inproc://`` are not reachable from a separate process.
    """
    from urllib.parse import urlsplit

    expected = "expected an address like tcp://HOST:PORT"
    scheme, sep, rest = address.partition("://")
    if not sep or not scheme or not rest:
        raise CaseError(f"--scheduler: value {address!r} is not allowed: {expected}")
    if scheme.lower() != "tcp":
        raise CaseError(f"--scheduler: value {address!r} is not allowed: scheme {scheme}:// is not supported, "
                        f"{expected}")
    try:
        parts = urlsplit(address)
        host, port = parts.hostname, parts.port
    except ValueError:
        raise CaseError(f"--scheduler: value {address!r} is not allowed: bad port, {expected}") from None
    if not host or parts.path not in ("", "/") or parts.query or parts.fragment or parts.username:
        raise CaseError(f"--scheduler: value {address!r} is not allowed: {expected}")
    return host, port if port is not None else 8786


def check_connect_timeout(timeout: float) -> float:
    if not (timeout > 0 and timeout <= 3600):
        raise CaseError(f"--connect-timeout: value {timeout!r} is not allowed: expected seconds in (0, 3600]")
    return float(timeout)


def probe_scheduler(address: str, timeout: float = DEFAULT_CONNECT_TIMEOUT) -> None:
    """Connect to a Dask scheduler and read its handshake, all within ``timeout`` [s].

    A Dask scheduler speaks first: on a new connection it sends its handshake, a message
    framed by an 8-byte little-endian length (distributed ``comm/tcp.py``).  A peer that
    accepts and stays silent (a hung process, an HTTP server) or answers something else
    would make ``distributed.Client`` wait without bound or try to allocate a huge buffer,
    so it is refused here with a one-line CaseError (exit 2).
    """
    import socket
    import struct
    import time

    host, port = check_scheduler_address(address)
    where = f"--scheduler: {address}"
    deadline = time.monotonic() + timeout
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except TimeoutError:
        raise CaseError(f"{where}: no connection within {timeout:g} s (--connect-timeout)") from None
    except socket.gaierror as exc:
        raise CaseError(f"{where}: unknown host {host!r} ({exc.strerror})") from None
    except OSError as exc:
        raise CaseError(f"{where}: cannot connect: {exc.strerror or exc}") from None

    def read(n: int) -> bytes:
        buf = b""
        while len(buf) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            sock.settimeout(left)
            got = sock.recv(n - len(buf))
            if not got:
                raise ConnectionResetError("connection closed by the peer")
            buf += got
        return buf

    try:
        with sock:
            (n,) = struct.unpack("<Q", read(8))
            if not 0 < n <= MAX_HANDSHAKE_BYTES:
                raise CaseError(f"{where}: the peer's answer is not a Dask handshake: is a Dask scheduler "
                                "listening there?")
            read(n)
    except TimeoutError:
        raise CaseError(f"{where}: connected, but no Dask handshake within {timeout:g} s (--connect-timeout): "
                        "is a Dask scheduler listening there?") from None
    except OSError as exc:
        raise CaseError(f"{where}: connection lost during the Dask handshake: {exc.strerror or exc}") from None


@contextlib.contextmanager
def _quiet_unraisable() -> Iterator[None]:
    """Swallow destructor noise (``Client.__del__`` of a client that failed to start)."""
    import gc
    import sys

    old = sys.unraisablehook
    sys.unraisablehook = lambda *_: None
    try:
        yield
    finally:
        gc.collect()
        sys.unraisablehook = old


def _open_client(distributed: Any, address: str, timeout: float) -> Any:
    """``distributed.Client(address)`` with a bound on the whole start-up (``2 * timeout`` + 5 s)."""
    box: dict[str, Any] = {}

    def start() -> None:
        try:
            box["client"] = distributed.Client(address, timeout=timeout, set_as_default=False)
        except BaseException as exc:
            box["error"] = exc

    with _quiet_unraisable():
        t = threading.Thread(target=start, name="linecheck-dask-connect", daemon=True)
        t.start()
        t.join(2 * timeout + 5.0)
        if t.is_alive():
            raise CaseError(f"--scheduler: {address}: the Dask client did not start within "
                            f"{2 * timeout + 5.0:g} s (--connect-timeout {timeout:g})")
        if "error" in box:
            exc = box["error"]
            msg = " ".join(str(exc).split()) or type(exc).__name__
            raise CaseError(f"--scheduler: cannot connect to the Dask scheduler at {address}: {msg}") from None
    return box["client"]


#: the loggers whose records about a lost scheduler connection :class:`DaskExecutor` drops
#: (reconnection attempts, ``ConnectionRefusedError -> CommClosedError -> CancelledError``
#: tracebacks): the batch reports the loss itself, one line per case
DASK_CONNECTION_LOGGERS = ("distributed.client", "distributed.utils", "distributed.core", "distributed.comm",
                           "distributed.comm.tcp", "distributed.comm.core", "distributed.batched")
#: :class:`~.tasks.Failure` kind of a task lost with the connection to the Dask scheduler
SCHEDULER_LOST = "SchedulerLost"


class _LostSchedulerFilter:
    """Logging filter: drops the records of a client whose scheduler connection is gone."""

    def __init__(self, executor: DaskExecutor) -> None:
        self.executor = executor

    def filter(self, record: Any) -> bool:
        return not self.executor.lost()


class DaskExecutor(Executor):
    """Tasks on a Dask distributed cluster (``--scheduler tcp://HOST:PORT``).

    Pass either the scheduler ``address`` (a client is opened and closed here) or an
    existing ``client`` (left open).  Workers need linecheck installed and the case
    files (and any downburst field files) at the same paths -- a shared file system.

    A lost scheduler (its process ended, the network gone) cancels every task the client
    holds: :meth:`outcome` reports each as a :data:`SCHEDULER_LOST` failure naming the
    scheduler, and while the connection is lost distributed's own log records about it
    (reconnection attempts and their tracebacks) are dropped (:data:`DASK_CONNECTION_LOGGERS`).
    """

    name = "dask"

    def __init__(self, address: str | None = None, *, client: Any = None,
                 timeout: float = DEFAULT_CONNECT_TIMEOUT) -> None:
        if client is None and address is not None:
            check_scheduler_address(address)  # a usage error first, whether or not Dask is installed
            check_connect_timeout(timeout)
        try:
            import distributed
        except ImportError:
            raise CaseError(DASK_MISSING) from None
        self._distributed = distributed
        self._own = client is None
        if client is None:
            if address is None:
                raise CaseError("--scheduler: no address given")
            probe_scheduler(address, timeout)  # bounded: a silent or foreign peer is refused here
            client = _open_client(distributed, address, timeout)
        self.client = client
        self.address = address or getattr(client.scheduler, "address", "")
        self._lost = False
        self._filter = _LostSchedulerFilter(self)
        for name in DASK_CONNECTION_LOGGERS:
            logging.getLogger(name).addFilter(self._filter)

    def lost(self) -> bool:
        """True once the client has lost its scheduler (it is reconnecting, or closed since)."""
        if not self._lost:
            status = getattr(self.client, "status", "running")
            self._lost = str(getattr(status, "value", status)) not in ("running", "newly-created")
        return self._lost

    def _lost_failure(self) -> Failure:
        return Failure(SCHEDULER_LOST, f"lost the connection to the Dask scheduler at {self.address} before the "
                                       "case finished", 1)

    @property
    def workers(self) -> int:
        try:
            return max(1, sum(self.client.nthreads().values()))
        except Exception:  # pragma: no cover - scheduler gone
            return 1

    def describe(self) -> str:
        n = self.workers
        return f"dask at {self.address} ({n} worker thread{'s' if n != 1 else ''})"

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
        return self.client.submit(fn, *args, pure=False, **kwargs)

    def wait(self, handles: Sequence[Any], timeout: float | None = None) -> list[int]:
        try:
            self._distributed.wait(list(handles), timeout=timeout, return_when="FIRST_COMPLETED")
        except TimeoutError:
            pass
        except Exception:
            pass
        return [i for i, f in enumerate(handles) if f.done()]

    def outcome(self, handle: Any) -> Any:
        if handle.status == "cancelled":
            exc = getattr(getattr(handle, "_state", None), "exception", None)
            if getattr(exc, "reason", None) == "scheduler-connection-lost" or self.lost():
                self._lost = True
                return self._lost_failure()
            return Failure("Cancelled", "cancelled", 130)
        try:
            return handle.result()
        except Exception as exc:
            if self.lost():
                return self._lost_failure()
            return Failure.of(exc)

    def cancel(self, handles: Sequence[Any]) -> None:
        if not handles:
            return
        try:
            self.client.cancel(list(handles))
        except Exception:  # pragma: no cover
            pass

    def abort(self, handles: Sequence[Any]) -> None:
        self.cancel(handles)

    def close(self) -> None:
        try:
            if self._own:
                if self.lost():  # the reconnection attempt ends now: its CancelledError is not logged
                    with contextlib.suppress(Exception):
                        self.client.close(timeout=5)
                else:
                    self.client.close()
        finally:
            for name in DASK_CONNECTION_LOGGERS:
                logging.getLogger(name).removeFilter(self._filter)


def make_executor(jobs: int | None = None, scheduler: str | None = None,
                  connect_timeout: float = DEFAULT_CONNECT_TIMEOUT) -> Executor:
    """The executor for ``--jobs`` / ``--scheduler`` / ``--connect-timeout`` (CaseError for bad values)."""
    if scheduler is not None:
        if jobs is not None:
            raise CaseError("--jobs and --scheduler cannot be combined: the cluster's workers set the parallelism")
        return DaskExecutor(scheduler, timeout=connect_timeout)
    if jobs is not None and jobs < 1:
        raise CaseError(f"--jobs: value {jobs} is not allowed: expected an integer >= 1")
    n = jobs or default_jobs()
    return SequentialExecutor() if n == 1 else ProcessPool(n)
