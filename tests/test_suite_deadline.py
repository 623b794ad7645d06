"""The suite's deadline (tests/conftest.py): CI's bound on a cold compilation cache.

Each check runs an inner pytest on this suite's own conftest (and the watchdog it imports) with a light module and one
named like a heavy module (``test_vehicle_car.py``); the last two run it under pytest-xdist, as CI does, with tests
that end their worker."""

import time
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

CONFTEST = (Path(__file__).parent / "conftest.py").read_text()
WATCHDOG = (Path(__file__).parent / "_watchdog.py").read_text()

LIGHT = """
import pytest

def test_light():
    pass

@pytest.mark.slow
def test_marked_slow():
    pass
"""

HEAVY = """
import time

def test_heavy_loops_a_minute():
    start = time.time()
    while time.time() - start < 60.0:
        sum(range(1000))

def test_heavy_after():
    pass
"""


BLOCKS_SIGNALS = """
import signal
import time

def test_heavy_inside_compiled_code():
    signal.signal(signal.SIGALRM, signal.SIG_IGN)  # as inside XLA: the abandonment's handler never runs
    start = time.time()
    while time.time() - start < 600.0:
        sum(range(1000))

def test_heavy_after():
    pass
"""

CRASHES = """
import os
from pathlib import Path

def test_crashes_once():
    marker = Path(os.environ["CRASH_MARKER"])
    if not marker.exists():
        marker.write_text("crashed")
        os._exit(3)

def test_crashes_every_time():
    os._exit(3)

def test_after():
    pass
"""


@pytest.fixture
def suite(pytester):
    pytester.makeconftest(CONFTEST)
    pytester.makeini("[pytest]\nmarkers =\n    slow: long test\n")
    pytester.makepyfile(test_light=LIGHT, test_vehicle_car=HEAVY, _watchdog=WATCHDOG)
    return pytester


def _run(suite, monkeypatch, deadline, abandon_after="900", *args):
    monkeypatch.setenv("JAXVEH_TEST_DEADLINE", str(deadline))
    monkeypatch.setenv("JAXVEH_TEST_ABANDON_AFTER", abandon_after)
    monkeypatch.setenv("JAXVEH_TEST_CACHE", str(suite.path / "jax-cache"))
    monkeypatch.delenv("JAXVEH_TEST_RECORDS", raising=False)  # this run's own, not the outer suite's
    return suite.runpytest_subprocess("-v", "-rs", "-p", "no:cacheprovider", *args)


def test_past_the_deadline_only_light_tests_run(suite, monkeypatch):
    result = _run(suite, monkeypatch, deadline=time.time() - 1.0)
    result.assert_outcomes(passed=1, skipped=3)
    result.stdout.fnmatch_lines(["*test_light.py::test_light PASSED*"])
    result.stdout.fnmatch_lines(["SKIPPED [[]3[]]*past the suite's deadline*"])


def test_a_long_test_is_abandoned_past_the_deadline(suite, monkeypatch):
    start = time.time()
    result = _run(suite, monkeypatch, deadline=time.time() + 8.0, abandon_after="1")
    result.assert_outcomes(passed=2, skipped=2)
    result.stdout.fnmatch_lines(["SKIPPED [[]1[]]*abandoned: still running*past the suite's deadline*"])
    result.stdout.fnmatch_lines(["*test_vehicle_car.py::test_heavy_after SKIPPED (past the suite*"])
    assert time.time() - start < 45.0


def test_with_a_deadline_light_modules_run_first(suite, monkeypatch):
    result = _run(suite, monkeypatch, deadline=time.time() - 1.0)
    lines = [line for line in result.outlines if "::test_" in line]
    assert "test_light.py" in lines[0] and "test_vehicle_car.py" in lines[-1]


def test_without_a_deadline_heavy_modules_run_first(suite, monkeypatch):
    monkeypatch.delenv("JAXVEH_TEST_DEADLINE", raising=False)
    monkeypatch.setenv("JAXVEH_TEST_CACHE", str(suite.path / "jax-cache"))
    result = suite.runpytest_subprocess("-v", "-p", "no:cacheprovider", "-k", "not loops")
    result.assert_outcomes(passed=3, deselected=1)
    lines = [line for line in result.outlines if "::test_" in line]
    assert "test_vehicle_car.py" in lines[0] and "test_light.py" in lines[-1]


def test_a_long_test_inside_compiled_code_is_ended_and_skipped(suite, monkeypatch):
    """Past the abandonment, a test that no signal handler can stop has its worker ended by the
    watchdog; the controller reports it skipped, the module's next test is skipped by the
    deadline in the fresh worker, and the run passes."""
    (suite.path / "test_vehicle_car.py").write_text(BLOCKS_SIGNALS)
    monkeypatch.setenv("JAXVEH_TEST_KILL_GRACE", "1")
    start = time.time()
    result = _run(suite, monkeypatch, time.time() + 40.0, "1", "-n", "1", "--dist", "loadfile")
    assert result.ret == 0, result.stdout.str()
    result.assert_outcomes(passed=2, skipped=2)
    result.stdout.fnmatch_lines(["SKIPPED [[]1[]]*abandoned: still running past the suite's deadline*inside compiled*"])
    assert time.time() - start < 180.0


def test_a_crashed_test_reruns_once_in_a_fresh_worker(suite, monkeypatch):
    (suite.path / "test_crash.py").write_text(CRASHES)
    monkeypatch.setenv("CRASH_MARKER", str(suite.path / "crashed-once"))
    result = _run(suite, monkeypatch, time.time() + 600.0, "900", "-n", "1", "--dist", "loadfile", "-k", "not loops")
    outcomes = result.parseoutcomes()
    assert (outcomes.get("passed"), outcomes.get("failed"), outcomes.get("rerun")) == (5, 1, 2), result.stdout.str()
    result.stdout.fnmatch_lines(["*FAILED test_crash.py::test_crashes_every_time*"])
    assert result.ret == 1
