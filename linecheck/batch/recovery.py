"""What a batch does when a process-pool worker dies (an out-of-memory kill, a crash).

The pool is then broken: every unfinished task fails with it.  After the executor restarted the
pool (:meth:`~.executors.Executor.restart`, which says which workers died on their own), the
policy here decides, task by task:

- a task whose worker is known dead fails its case ("worker died (killed by signal 9, ...)");
- when the dead worker is unknown, every running task is suspect: one suspected twice fails;
- after more than :data:`MAX_IDLE_RESTARTS` restarts without any task finishing, the tasks
  that are left fail (a pool that keeps dying must not loop for ever);
- every other unfinished task of a case still running runs again (same results, bit for bit).

A task whose result came in before the pool broke is neither failed nor re-run.  A task of a
case failed earlier in the same recovery is dropped (neither suspected nor re-run).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from .executors import describe_exit
from .tasks import Failure

MAX_IDLE_RESTARTS = 3  # pool restarts without any task finishing before the remaining cases fail


@dataclass(frozen=True)
class HeldTask:
    """An unfinished task of the broken pool, as the recovery policy sees it.

    ``index``: the task's number in the batch; ``case``: its case's number; ``pid``: the worker
    that reported starting it (``None``: not known to have started); ``finished``: its result
    came in before the pool broke.
    """

    index: int
    case: int
    pid: int | None
    finished: bool = False


@dataclass(frozen=True)
class RecoveryPlan:
    """The decision after a restart: the tasks whose case fails (with why their worker ended,
    in task order) and the tasks to submit again."""

    failed: list[tuple[HeldTask, str]]
    rerun: list[HeldTask]


@dataclass
class WorkerRecovery:
    """The worker-recovery policy of one batch (see the module docstring); keeps the count of
    restarts since a task last finished and, per task, how often it was suspected."""

    max_idle_restarts: int = MAX_IDLE_RESTARTS
    idle_restarts: int = 0
    suspected: dict[int, int] = field(default_factory=dict)

    def progressed(self) -> None:
        """A task finished: the pool works, restarts count from zero again."""
        self.idle_restarts = 0

    def after_restart(self, held: Sequence[HeldTask], dead: Mapping[int, int]) -> RecoveryPlan:
        """Which of the ``held`` tasks fail their case and which run again, given ``dead``
        (``{pid: exit code}`` of the workers that died on their own, from the restart)."""
        self.idle_restarts += 1
        failed: list[tuple[HeldTask, str]] = []
        failed_cases: set[int] = set()
        for task in held:
            if task.finished or task.case in failed_cases:
                continue
            why = self.verdict(task, dead)
            if why is not None:
                failed.append((task, why))
                failed_cases.add(task.case)
        rerun = [t for t in held if not t.finished and t.case not in failed_cases]
        return RecoveryPlan(failed, rerun)

    def verdict(self, task: HeldTask, dead: Mapping[int, int]) -> str | None:
        """Why ``task``'s worker is taken to have died under it, or None (it runs again)."""
        pid = task.pid
        if pid is not None and pid in dead:
            return describe_exit(dead[pid])
        if pid is not None and not dead:  # the dead worker is unknown: every running task is suspect
            self.suspected[task.index] = self.suspected.get(task.index, 0) + 1
            return "ended abruptly, twice" if self.suspected[task.index] > 1 else None
        if self.idle_restarts > self.max_idle_restarts:
            return f"ended abruptly {self.idle_restarts} times in a row"
        return None

    @staticmethod
    def failure(why: str, name: str) -> Failure:
        """The failure of a case whose worker died: ``worker died (WHY) while running NAME``."""
        return Failure("WorkerDied", f"worker died ({why}) while running {name}", 1)
