"""The test workers' hang watchdog (tests/_watchdog.py): its decision on CPU samples, the
CPU time of a process tree, a process that sleeps in a "test" ended with its name, and a busy one
ended past its end-by time with a record of it."""

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from _watchdog import HUNG_EXIT, OVERRUN_EXIT, is_hung, overrun_record, tree_cpu_seconds


def test_is_hung_needs_the_whole_window_without_cpu():
    busy = [(t, 0.5 * t) for t in range(0, 700, 15)]
    idle = [(t, 10.0 + 1e-3 * t) for t in range(0, 700, 15)]
    assert not is_hung(busy, 690.0, hang_after=600.0)
    assert is_hung(idle, 690.0, hang_after=600.0)
    assert not is_hung(idle[:5], 60.0, hang_after=600.0)  # not watched long enough yet


def test_tree_cpu_seconds_counts_a_busy_child():
    child = subprocess.Popen([sys.executable, "-c", "import time\nt = time.time()\nwhile time.time() - t < 2: pass"])
    try:
        before = tree_cpu_seconds(os.getpid())
        time.sleep(1.5)
        assert tree_cpu_seconds(os.getpid()) - before > 0.5
    finally:
        child.wait()


def test_a_sleeping_test_ends_its_process_named(tmp_path):
    script = textwrap.dedent("""
        import time
        from _watchdog import Watchdog
        w = Watchdog(period=0.2)
        w.start_test("tests/test_x.py::test_sleeps")
        time.sleep(30)
    """)
    env = os.environ | {"JAXVEH_TEST_HANG_AFTER": "1.5", "PYTHONPATH": str(Path(__file__).parent)}
    t0 = time.monotonic()
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == HUNG_EXIT
    assert time.monotonic() - t0 < 20
    assert "tests/test_x.py::test_sleeps: no CPU used for 2 s" in out.stderr
    assert "time.sleep" in out.stderr or "line 6" in out.stderr  # the Python stack of the hung thread


def test_a_busy_test_past_its_end_by_time_ends_its_process_with_a_record(tmp_path):
    script = textwrap.dedent(f"""
        import time
        from pathlib import Path
        from _watchdog import Watchdog
        w = Watchdog(period=0.2, record_dir=Path({str(tmp_path)!r}))
        w.start_test("tests/test_x.py::test_busy", end_by=time.time() + 1.0)
        start = time.time()
        while time.time() - start < 30:
            sum(range(1000))
    """)
    env = os.environ | {"PYTHONPATH": str(Path(__file__).parent)}
    t0 = time.monotonic()
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == OVERRUN_EXIT
    assert time.monotonic() - t0 < 20
    assert "tests/test_x.py::test_busy: still running past its end-by time" in out.stderr
    assert overrun_record(tmp_path, "tests/test_x.py::test_busy").read_text() == "tests/test_x.py::test_busy"
