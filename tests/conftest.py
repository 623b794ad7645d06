"""Test configuration: float64, strict dtype promotion, rank promotion raises.

Every compiled XLA executable holds a few memory mappings of JIT code. A long-lived test
worker that compiles thousands of functions reaches the kernel's ``vm.max_map_count``
(65530 by default), and the next compile then segfaults inside XLA's CPU compiler (seen in
CI). So JAX's compilation caches are dropped, which frees the executables, when a test
module ends (its module-scoped fixtures, a compiled car, are torn down first) and, within a
long module, after any test that leaves the process above half the limit (later tests of
that module then compile again: slower, never wrong).

Compiled executables also go to a persistent compilation cache (entries that took over a
second to compile): a later module, worker or run that compiles the same program (the car's
static set-up, say) loads it instead. It lives outside the checkout, in
``~/.cache/jaxveh/pytest-jax`` (``$JAXVEH_TEST_CACHE`` moves it), so that a fresh clone on
a machine that ran the suite before skips XLA's compilation of every unchanged program
(tracing still runs); JAX keys each entry by the program and the JAX version, so a changed
program simply misses. Least recently used entries beyond 8 GB are dropped. Programs with run-time
checks (host callbacks) are not stored; the car's manoeuvre and steady-state programs are
traced without them (``jaxveh._core.run_time_checks_off``), so they are.
"""

import ctypes
import ctypes.util
import gc
import logging
import os
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import jax
import pytest
from _watchdog import Watchdog, overrun_record
from jax import monitoring

import jaxveh  # noqa: F401  (enables float64)

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
jax.config.update("jax_numpy_rank_promotion", "raise")
_CACHE = os.environ.get("JAXVEH_TEST_CACHE") or str(Path.home() / ".cache" / "jaxveh" / "pytest-jax")
jax.config.update("jax_compilation_cache_dir", _CACHE)
jax.config.update("jax_compilation_cache_max_size", 8 * 2**30)
jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)

_MAPS, _MAX_MAPS = Path("/proc/self/maps"), Path("/proc/sys/vm/max_map_count")

#: Seconds each module took on a cold cache (both workers busy, 2-core machine; the modules
#: under 50 s are left out), measured on 2026-12-07 by ``--durations=0`` in a whole cold run
#: without a deadline (61 minutes, 122 worker-minutes). Modules run heaviest first, so that
#: with ``-n 2 --dist loadfile --no-loadscope-reorder`` the last module to start is a short
#: one (longest processing time first); within a module the order is the file's. Re-measure
#: with ``--durations=0`` (or ``JAXVEH_COMPILE_LOG``) when a module's cost changes a lot.
MODULE_SECONDS = {
    "test_vehicle_car.py": 666,
    "test_manoeuvre_fourpost.py": 563,
    "test_optimise_braking.py": 539,
    "test_manoeuvre.py": 477,
    "test_optimise_sweep.py": 389,
    "test_optimise_car.py": 353,
    "test_optimise_step_steer.py": 348,
    "test_vehicle_rigs.py": 331,
    "test_multibody_engine.py": 250,
    "test_optimise_frame.py": 247,
    "test_manoeuvre_steady.py": 237,
    "test_analysis_load_transfer.py": 203,
    "test_manoeuvre_straight_line.py": 200,
    "test_manoeuvre_driver.py": 185,
    "test_multibody_flexible.py": 184,
    "test_vehicle_fast.py": 182,
    "test_multibody_imex.py": 162,
    "test_manoeuvre_imex.py": 148,
    "test_optimise_stiffness.py": 142,
    "test_analysis_kinematics.py": 128,
    "test_manoeuvre_frequency.py": 103,
    "test_vehicle_corner.py": 99,
    "test_analytic_dynamics.py": 77,
    "test_suite_deadline.py": 75,
    "test_manoeuvre_replay.py": 67,
    "test_multibody_simplifications.py": 66,
    "test_fe_grad.py": 64,
    "test_plots_layout.py": 58,
    "test_optimise_kinematics.py": 55,
    "test_manoeuvre_brake_in_turn.py": 54,
    "test_multibody_pendulum.py": 52,
}


#: Unix time after which long tests are skipped (``$JAXVEH_TEST_DEADLINE``; unset: none).
#: CI sets it so that the suite ends within CI's limit on a cold compilation cache. Long
#: tests are those marked ``slow`` and those of the heavy modules (``MODULE_SECONDS`` of
#: 200 s or more: the heaviest of the modules that compile the car). Past the deadline none
#: starts, and one still running ``ABANDON_AFTER`` seconds past it (``$JAXVEH_TEST_ABANDON_AFTER``; 900) is
#: abandoned, reported as skipped, the next time Python runs: a single test can take half an
#: hour on a cold cache, so the deadline alone does not bound the suite (a CI run was
#: stopped at 90 minutes with one worker inside a test it had started before the deadline).
#: A plain ``pytest`` run has no deadline.
#: A test inside compiled code (an XLA compilation, a deadlock) runs no Python signal
#: handler, so one still running ``KILL_GRACE`` seconds later (``$JAXVEH_TEST_KILL_GRACE``;
#: 120) has its worker ended by the watchdog (:mod:`_watchdog`) and is reported as skipped
#: (:func:`pytest_handlecrashitem`).
_DEADLINE = float(os.environ.get("JAXVEH_TEST_DEADLINE") or "inf")
ABANDON_AFTER = float(os.environ.get("JAXVEH_TEST_ABANDON_AFTER") or 15 * 60)
KILL_GRACE = float(os.environ.get("JAXVEH_TEST_KILL_GRACE") or 120)
#: Where workers leave word of the tests they ended (shared with pytest-xdist's controller,
#: which sets it before it starts the workers).
_RECORDS = Path(os.environ.setdefault(
    "JAXVEH_TEST_RECORDS", os.path.join(tempfile.gettempdir(), f"jaxveh-test-records-{os.getpid()}-{time.time_ns()}")))
_HEAVY_MODULES = {name for name, seconds in MODULE_SECONDS.items() if seconds >= 200}
_current_test = ["(collection)"]
_in_setup_or_call = [False]


def pytest_collection_modifyitems(config, items):
    """Order the modules (a stable sort: each module's own order is kept). Without a
    deadline, heaviest first, so that the last module to start is a short one (longest
    processing time first: the shortest run). With one, cheapest first, so that the light
    modules all run and as many long tests as fit run before the deadline."""
    sign = 1.0 if _DEADLINE < float("inf") else -1.0
    items.sort(key=lambda item: sign * MODULE_SECONDS.get(item.path.name, 0.0))


def _is_long(item) -> bool:
    return item.path.name in _HEAVY_MODULES or item.get_closest_marker("slow") is not None


def _abandon(signum, frame):
    """SIGALRM: abandon the long test running past the deadline (during its set-up or call;
    anywhere else in pytest's machinery, try again a second later)."""
    if _in_setup_or_call[0]:
        pytest.skip(f"abandoned: still running {ABANDON_AFTER:.0f} s past the suite's deadline "
                    "($JAXVEH_TEST_DEADLINE, set by .ci/run); run pytest without it to run this test")
    signal.setitimer(signal.ITIMER_REAL, 1.0)


def _can_use_alarm() -> bool:
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    """Skip a long test past the deadline, arm its abandonment, and name the test whose
    set-up (module fixtures included), call and teardown compile (``JAXVEH_COMPILE_LOG``)."""
    _current_test[0] = item.nodeid
    if _is_long(item) and _DEADLINE < float("inf"):
        now = time.time()
        if now > _DEADLINE:
            pytest.skip("past the suite's deadline ($JAXVEH_TEST_DEADLINE, set by .ci/run so that CI ends "
                        "in time on a cold compilation cache); run pytest without it to run this test")
        if _can_use_alarm():
            signal.signal(signal.SIGALRM, _abandon)
            signal.setitimer(signal.ITIMER_REAL, _DEADLINE + ABANDON_AFTER - now)
    return (yield from _within_setup_or_call())


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    return (yield from _within_setup_or_call())


_watchdog: list[Watchdog] = []


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Watch the test for a deadlock (:mod:`_watchdog`), from its set-up to its teardown, in
    the process that runs it (never in pytest-xdist's controller, whose process tree holds
    every worker)."""
    if not _watchdog and Path("/proc/self/stat").exists():
        _watchdog.append(Watchdog(record_dir=_RECORDS))
    end_by = _DEADLINE + ABANDON_AFTER + KILL_GRACE if _is_long(item) else float("inf")
    for w in _watchdog:
        w.start_test(item.nodeid, end_by=end_by)
    try:
        return (yield)
    finally:
        for w in _watchdog:
            w.end_test()


def _crash_count(nodeid: str) -> int:
    """How many times test ``nodeid`` has crashed its worker so far in this run (and count this one)."""
    counter = overrun_record(_RECORDS, nodeid).with_suffix(".crashes")
    count = int(counter.read_text()) if counter.exists() else 0
    counter.parent.mkdir(parents=True, exist_ok=True)
    counter.write_text(str(count + 1))
    return count


def _drop_finished_modules(sched, also: str | None = None) -> None:
    """pytest-xdist 3.8's ``--dist loadfile`` puts every module the crashed worker had, its
    finished ones included, back in the queue; a fresh worker handed a finished one gets an
    empty batch and waits forever, and so does the run (a CI run ended at its 90 minutes
    so). Drop the finished ones; ``also``: a test to count as finished (not run again)."""
    queue = getattr(sched, "workqueue", None)
    if queue is None:
        return
    for tests in queue.values():
        if also in tests:
            tests[also] = True
    for scope in [scope for scope, tests in queue.items() if all(tests.values())]:
        del queue[scope]


@pytest.hookimpl(optionalhook=True, trylast=True)
def pytest_handlecrashitem(crashitem, report, sched):
    """pytest-xdist's controller, on a test whose worker died: a test the watchdog ended past
    the deadline is reported as skipped. Any other crash (XLA's CPU compiler has segfaulted
    twice in long runs, in two unrelated tests, never reproducibly; a deadlock ended by the
    watchdog) is reported as a rerun the first time, as the test is run again in a fresh
    worker (``--dist loadfile`` hands the crashed module's unfinished tests, that one
    included, to the new worker), and as a failure the second time."""
    path = report.location[0] if report.location else crashitem.split("::")[0]
    first_crash = _crash_count(crashitem) == 0
    if overrun_record(_RECORDS, crashitem).exists():
        _drop_finished_modules(sched, also=crashitem)
        report.outcome = "skipped"
        report.longrepr = (path, None, "Skipped: abandoned: still running past the suite's deadline "
                           "($JAXVEH_TEST_DEADLINE, set by .ci/run) inside compiled code; its worker was ended")
    elif first_crash and hasattr(sched, "workqueue"):  # xdist's LoadScope schedulers requeue it
        _drop_finished_modules(sched)
        report.outcome = "rerun"
    else:
        _drop_finished_modules(sched, also=crashitem)


def pytest_report_teststatus(report, config):
    """A crashed test that runs again (:func:`pytest_handlecrashitem`): ``R``."""
    if report.outcome == "rerun":
        return "rerun", "R", ("RERUN", {"yellow": True})
    return None


def _within_setup_or_call():
    _in_setup_or_call[0] = True
    try:
        return (yield)
    finally:
        _in_setup_or_call[0] = False


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_teardown(item, nextitem):
    """Disarm the abandonment before the test's teardown."""
    _in_setup_or_call[0] = False
    if _can_use_alarm():
        signal.setitimer(signal.ITIMER_REAL, 0.0)


_COMPILE_LOG = os.environ.get("JAXVEH_COMPILE_LOG")

if _COMPILE_LOG:

    def _append_to_log(*fields: str):
        """Append the current test and ``fields`` as one tab-separated line to ``$JAXVEH_COMPILE_LOG``."""
        with open(_COMPILE_LOG, "a") as f:
            f.write("\t".join((_current_test[0], *fields)) + "\n")

    def _log_compile_phase(event: str, duration: float, **kwargs):
        """Append ``test, phase, seconds, function`` for each tracing, lowering, XLA
        compilation and disk-cache retrieval (tab-separated) to ``$JAXVEH_COMPILE_LOG``."""
        if event.endswith("_duration") or "compilation_cache" in event:
            _append_to_log(event.rsplit("/", 1)[-1], f"{duration:.3f}", kwargs.get("fun_name", ""))

    class _CacheLookups(logging.Handler):
        """Append ``test, cache_hit|cache_miss, 0, program, key`` for each lookup in the
        persistent cache: the same key missed in two tests is a program compiled twice."""

        def emit(self, record):
            message = record.getMessage()
            outcome = ("cache_miss" if message.startswith("PERSISTENT COMPILATION CACHE MISS")
                       else "cache_hit" if message.startswith("Persistent compilation cache hit") else None)
            if outcome is not None:
                program, key = record.args
                _append_to_log(outcome, "0", program, key)

    monitoring.register_event_duration_secs_listener(_log_compile_phase)
    _compiler_logger = logging.getLogger("jax._src.compiler")
    _compiler_logger.setLevel(logging.DEBUG)
    _compiler_logger.addHandler(_CacheLookups(level=logging.DEBUG))


_MEMORY_LOG = os.environ.get("JAXVEH_MEMORY_LOG")
_STATUS, _CLEAR_REFS = Path("/proc/self/status"), Path("/proc/self/clear_refs")


def _status_kib(field: str) -> int:
    for line in _STATUS.read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    return -1


if _MEMORY_LOG and _STATUS.exists():

    def pytest_runtest_logstart(nodeid, location):
        """Reset the process's peak resident memory (VmHWM) before each test."""
        _CLEAR_REFS.write_text("5")

    def pytest_runtest_logfinish(nodeid, location):
        """Append ``test, peak MiB, resident MiB`` (set-up, call and teardown together) to
        the file ``$JAXVEH_MEMORY_LOG``: which tests two workers must not overlap."""
        peak, now = _status_kib("VmHWM") // 1024, _status_kib("VmRSS") // 1024
        with open(_MEMORY_LOG, "a") as f:
            f.write(f"{nodeid}\t{peak}\t{now}\n")


#: glibc, to hand freed heap back to the system (None off glibc).
_LIBC = ctypes.CDLL(ctypes.util.find_library("c")) if sys.platform.startswith("linux") else None


def _trim_heap():
    """Return the heap's free memory to the system. XLA's compiler frees gigabytes after a
    large compilation, but glibc keeps them in its arenas: measured on the 2-mode car's
    skid-pad, 3.2 GB resident after ``jax.clear_caches()`` and ``gc.collect()``, 0.65 GB
    after ``malloc_trim``. Without it each worker's resident size ratchets up to its largest
    compilation so far, and two workers at 10-12 GB each exhaust a 24 GB machine without
    swap: the kernel then evicts code pages and the suite crawls (a CI run was stopped at
    90 minutes 22 % through)."""
    if _LIBC is not None:
        _LIBC.malloc_trim(0)


def _release():
    jax.clear_caches()
    gc.collect()
    _trim_heap()


def _near_map_limit() -> bool:
    if not (_MAPS.exists() and _MAX_MAPS.exists()):
        return False
    with _MAPS.open("rb") as f:
        count = sum(1 for _ in f)
    return count > int(_MAX_MAPS.read_text()) // 2


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_code_per_module():
    """Free the module's compiled executables (and their memory mappings) when it ends."""
    yield
    _release()


@pytest.fixture(autouse=True)
def _release_compiled_code_near_limit():
    """Free compiled executables after a test that leaves the process near the map limit,
    and hand the heap's free memory back after every test (:func:`_trim_heap`)."""
    yield
    if _near_map_limit():
        _release()
    else:
        _trim_heap()
