"""A hang watchdog for test workers: a test that uses no CPU for a long time is deadlocked.

jaxlib 0.10.2 can deadlock when two batched LAPACK calls of one program run at once (each
waits inside ``ParallelBatchMap`` for the CPU threads the other holds; docs/optimise.md).
The process then sleeps forever with no CPU, where no Python signal handler can run, and
CI would wait until its limit. The watchdog thread samples the CPU time of the test process
and its live descendants (compiler threads, CLI subprocesses, Ray workers); when a test has
used less than ``MIN_CPU_S`` in ``HANG_AFTER_S`` it prints the test's name and every
thread's Python stack and ends the process, so that pytest-xdist reports the worker as
crashed and pytest-rerunfailures runs the test once more in a fresh worker.
"""

import faulthandler
import os
import sys
import threading
import time
from pathlib import Path

#: Seconds without CPU after which a running test counts as hung ($JAXVEH_TEST_HANG_AFTER).
HANG_AFTER_S = float(os.environ.get("JAXVEH_TEST_HANG_AFTER") or 600.0)
#: CPU seconds that count as progress within ``HANG_AFTER_S``.
MIN_CPU_S = 1.0
#: Exit status of a process ended as hung.
HUNG_EXIT = 70
_TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def _stat(pid: str) -> tuple[int, float] | None:
    """``(parent pid, user + system CPU seconds)`` of a process from ``/proc``."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) "
    return int(fields[1]), (int(fields[11]) + int(fields[12])) / _TICK


def tree_cpu_seconds(root: int) -> float:
    """CPU seconds used so far by process ``root`` and its live descendants."""
    stats = {int(p): s for p in os.listdir("/proc") if p.isdigit() and (s := _stat(p)) is not None}
    children: dict[int, list[int]] = {}
    for pid, (parent, _) in stats.items():
        children.setdefault(parent, []).append(pid)
    total, stack = 0.0, [root]
    while stack:
        pid = stack.pop()
        if pid in stats:
            total += stats[pid][1]
        stack.extend(children.get(pid, ()))
    return total


def is_hung(samples: list[tuple[float, float]], now: float, hang_after: float = HANG_AFTER_S,
            min_cpu: float = MIN_CPU_S) -> bool:
    """Whether ``(time, cpu seconds)`` samples of one test show under ``min_cpu`` CPU
    seconds in the last ``hang_after`` seconds (samples must reach back that far)."""
    old = [cpu for t, cpu in samples if t <= now - hang_after]
    return bool(old) and samples[-1][1] - old[-1] < min_cpu


class Watchdog:
    """Samples the CPU time every ``period`` seconds while a test runs (:meth:`start_test`
    / :meth:`end_test`); ends the process when :func:`is_hung`."""

    def __init__(self, period: float = 15.0):
        self.period = period
        self._lock = threading.Lock()
        self._test: str | None = None
        self._samples: list[tuple[float, float]] = []
        threading.Thread(target=self._run, name="jaxveh-hang-watchdog", daemon=True).start()

    def start_test(self, nodeid: str) -> None:
        with self._lock:
            self._test, self._samples = nodeid, []

    def end_test(self) -> None:
        with self._lock:
            self._test, self._samples = None, []

    def _run(self) -> None:
        pid = os.getpid()
        while True:
            time.sleep(self.period)
            now, cpu = time.monotonic(), tree_cpu_seconds(pid)
            with self._lock:
                if self._test is None:
                    continue
                self._samples.append((now, cpu))
                if is_hung(self._samples, now):
                    sys.stderr.write(f"\n{self._test}: no CPU used for {HANG_AFTER_S:.0f} s, a deadlock (see "
                                     "tests/_watchdog.py); ending this worker so that the test reruns once\n")
                    faulthandler.dump_traceback(file=sys.stderr, all_threads=True)
                    sys.stderr.flush()
                    os._exit(HUNG_EXIT)
