"""A watchdog for test workers: it ends a deadlocked test's process, and one that overran.

A test that uses no CPU for a long time is deadlocked.

jaxlib 0.10.2 can deadlock when two batched LAPACK calls of one program run at once (each
waits inside ``ParallelBatchMap`` for the CPU threads the other holds; docs/optimise.md).
The process then sleeps forever with no CPU, where no Python signal handler can run, and
CI would wait until its limit. The watchdog thread samples the CPU time of the test process
and its live descendants (compiler threads, CLI subprocesses, Ray workers); when a test has
used less than ``MIN_CPU_S`` in ``HANG_AFTER_S`` it prints the test's name and every
thread's Python stack and ends the process; pytest-xdist reports the worker as crashed and
runs the test once more in a fresh worker (tests/conftest.py, ``pytest_handlecrashitem``).

A test may also be given a time to end by (:meth:`Watchdog.start_test`): CI's deadline,
which a test inside compiled code cannot be stopped at by a Python signal handler. Past it
the watchdog writes :func:`overrun_record` for the test and ends the process, and the
controller reports the test as skipped.
"""

import faulthandler
import hashlib
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
#: Exit status of a process ended because its test ran past its end-by time.
OVERRUN_EXIT = 71
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


def overrun_record(directory: Path, nodeid: str) -> Path:
    """The file that says the test ``nodeid`` was ended for running past its end-by time."""
    return Path(directory) / (hashlib.sha1(nodeid.encode()).hexdigest()[:16] + ".overrun")


def is_hung(samples: list[tuple[float, float]], now: float, hang_after: float = HANG_AFTER_S,
            min_cpu: float = MIN_CPU_S) -> bool:
    """Whether ``(time, cpu seconds)`` samples of one test show under ``min_cpu`` CPU
    seconds in the last ``hang_after`` seconds (samples must reach back that far)."""
    old = [cpu for t, cpu in samples if t <= now - hang_after]
    return bool(old) and samples[-1][1] - old[-1] < min_cpu


class Watchdog:
    """Samples the CPU time every ``period`` seconds while a test runs (:meth:`start_test`
    / :meth:`end_test`); ends the process when :func:`is_hung` or past the test's end-by
    time (its :func:`overrun_record` then goes to ``record_dir``)."""

    def __init__(self, period: float = 15.0, record_dir: Path | None = None):
        self.period = period
        self.record_dir = record_dir
        self._lock = threading.Lock()
        self._test: str | None = None
        self._end_by = float("inf")
        self._samples: list[tuple[float, float]] = []
        threading.Thread(target=self._run, name="jaxveh-hang-watchdog", daemon=True).start()

    def start_test(self, nodeid: str, end_by: float = float("inf")) -> None:
        """Watch test ``nodeid``; ``end_by``: Unix time past which its process is ended."""
        with self._lock:
            self._test, self._samples, self._end_by = nodeid, [], end_by

    def end_test(self) -> None:
        with self._lock:
            self._test, self._samples, self._end_by = None, [], float("inf")

    def _end_overrun(self) -> None:
        sys.stderr.write(f"\n{self._test}: still running past its end-by time (the suite's deadline, "
                         "tests/conftest.py); ending this worker, the test is reported as skipped\n")
        sys.stderr.flush()
        if self.record_dir is not None:
            record = overrun_record(self.record_dir, self._test)
            record.parent.mkdir(parents=True, exist_ok=True)
            record.write_text(self._test)
        os._exit(OVERRUN_EXIT)

    def _run(self) -> None:
        pid = os.getpid()
        while True:
            time.sleep(self.period)
            now, cpu = time.monotonic(), tree_cpu_seconds(pid)
            with self._lock:
                if self._test is None:
                    continue
                self._samples.append((now, cpu))
                if time.time() > self._end_by:
                    self._end_overrun()
                if is_hung(self._samples, now):
                    sys.stderr.write(f"\n{self._test}: no CPU used for {HANG_AFTER_S:.0f} s, a deadlock (see "
                                     "tests/_watchdog.py); ending this worker so that the test reruns once\n")
                    faulthandler.dump_traceback(file=sys.stderr, all_threads=True)
                    sys.stderr.flush()
                    os._exit(HUNG_EXIT)
