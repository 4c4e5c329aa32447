"""The wall time ``motosim campaign`` prints counts from the process's start."""

import subprocess
import sys
import time

import pytest

from motosim.cli.campaign import _process_age


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="read from /proc")
def test_the_process_age_is_the_time_since_the_process_started() -> None:
    code = "import time; time.sleep(0.5); from motosim.cli.campaign import _process_age; "
    code += "print(_process_age())"
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    outside = time.perf_counter() - start
    age = float(done.stdout)
    assert 0.5 <= age <= outside + 0.02  # clock ticks of 10 ms
    assert 0.0 < _process_age()
