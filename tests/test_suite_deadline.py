"""The suite's deadline (tests/conftest.py): CI's bound on a cold compilation cache.

Each check runs an inner pytest on this suite's own conftest (and the watchdog it imports) with a light module and one
named like a heavy module (``test_vehicle_car.py``)."""

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


@pytest.fixture
def suite(pytester):
    pytester.makeconftest(CONFTEST)
    pytester.makeini("[pytest]\nmarkers =\n    slow: long test\n")
    pytester.makepyfile(test_light=LIGHT, test_vehicle_car=HEAVY, _watchdog=WATCHDOG)
    return pytester


def _run(suite, monkeypatch, deadline, abandon_after="900"):
    monkeypatch.setenv("JAXVEH_TEST_DEADLINE", str(deadline))
    monkeypatch.setenv("JAXVEH_TEST_ABANDON_AFTER", abandon_after)
    monkeypatch.setenv("JAXVEH_TEST_CACHE", str(suite.path / "jax-cache"))
    return suite.runpytest_subprocess("-v", "-rs", "-p", "no:cacheprovider")


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
