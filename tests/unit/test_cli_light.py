"""Every subcommand's help and usage errors answer without loading the numerical stack.

Each ``src/motosim/cli/<command>.py`` builds its parser from light modules only; SciPy, the
numba-compiled models, h5py and the rest are imported by the function that runs the command.
The check is on ``sys.modules`` in a fresh interpreter, not on the wall time.
"""

import subprocess
import sys

import pytest

from motosim.cli.main import COMMANDS

HEAVY = ("numpy", "scipy", "numba", "llvmlite", "h5py", "matplotlib", "pandas")
"""Packages that take from a tenth of a second to seconds to import."""

_SCRIPT = """
import contextlib, io, sys
from motosim.cli.main import main
codes = []
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    for argv in {argvs!r}:
        codes.append(main(argv))
heavy = sorted({{m.split(".")[0] for m in sys.modules}} & set({heavy!r}))
print(codes, heavy)
"""


def _codes_and_heavy(*argvs: list[str]) -> str:
    """``[exit codes] [heavy packages imported]`` of ``motosim argv`` for each, in one fresh
    interpreter."""
    script = _SCRIPT.format(argvs=list(argvs), heavy=HEAVY)
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr[-500:]
    return done.stdout.strip()


@pytest.mark.parametrize("name", list(COMMANDS))
def test_help_and_usage_errors_import_nothing_heavy(name: str) -> None:
    outcome = _codes_and_heavy([name, "--help"], [name, "--no-such-option"])
    assert outcome == "[0, 2] []", f"motosim {name}: {outcome}"


def test_options_refused_before_the_work_import_nothing_heavy() -> None:
    outcome = _codes_and_heavy(
        ["design", "--order", "9"],
        ["cueing", "result", "--rate", "0", "--out", "out"],
        ["modes", "--speeds", "nan"],
        ["simulate", "scenario.toml", "--out", "/no/such/folder/out"],
    )
    assert outcome == "[2, 2, 2, 2] []"


def test_choices_written_out_in_the_commands_equal_their_sources() -> None:
    from motosim.cli import cueing, design, estimate, identify
    from motosim.control.torque_feedback import INTEGRAL_CORNER, MAX_ORDER
    from motosim.cueing import ALGORITHMS
    from motosim.estimation import ESTIMATORS
    from motosim.estimation.registry import SENSOR_ESTIMATOR
    from motosim.identification import METHODS
    from motosim.identification.output_error import DRIVES

    assert cueing.ALGORITHMS == ALGORITHMS
    assert design.MAX_ORDER == MAX_ORDER
    assert design.INTEGRAL_CORNER == INTEGRAL_CORNER
    assert estimate.ESTIMATORS == (*ESTIMATORS, SENSOR_ESTIMATOR)
    assert identify.METHODS == METHODS
    assert identify.DRIVES == DRIVES


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["run", "s.toml", "--out", "o", "--bus", "virtual", "--link", "fast"], "--link fast"),
        (
            ["run", "s.toml", "--out", "o", "--bus", "socketcan:can0", "--wait", "python"],
            "--wait python",
        ),
        (["rig", "s.toml", "--bus", "virtual", "--link", "python-can"], "--link python-can"),
    ],
)
def test_udp_multicast_options_on_another_bus_refused_before_the_work(
    argv: list[str], option: str
) -> None:
    # --link and --wait choose how a udp_multicast bus is read; with another bus they were
    # ignored without a word. The command run as a user runs it: one line, exit 2, and the
    # numerical stack not imported (the scenario file does not even exist)
    done = subprocess.run(
        [sys.executable, "-m", "motosim", *argv], capture_output=True, text=True, check=False
    )
    bus = argv[argv.index("--bus") + 1]
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        f"motosim: error: {option} with --bus {bus!r}; {option.split()[0]} applies only to a "
        "udp_multicast bus: leave it out with this bus\n"
    )
    assert _codes_and_heavy(argv) == "[2] []"


def test_udp_multicast_options_left_out_pass_silently_with_another_bus() -> None:
    # their defaults are not "given": the refusal that comes is the next check's (--spin)
    done = subprocess.run(
        [sys.executable, "-m", "motosim", "rig", "s.toml", "--bus", "virtual", "--spin", "-1"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2
    assert done.stderr == "motosim: error: --spin -1.0; expected microseconds in [0, 1000000)\n"


@pytest.mark.parametrize(
    ("given", "other", "why"),
    [
        (["--pace", "bus"], "--pace bus", "a clock-paced loop (--pace clock)"),
        (["--link", "python-can"], "--link python-can", "the fast link (--link fast)"),
    ],
)
def test_the_compiled_wait_given_where_it_cannot_run_is_refused_before_the_work(
    given: list[str], other: str, why: str
) -> None:
    # paced by the bus, or through python-can's link, the loop waits in Python: --wait
    # compiled given there fell back to it without a word (only timing.json's "wait" said
    # so). One line, exit 2, before the numerical stack is imported (the file does not exist)
    argv = [
        "run",
        "s.toml",
        "--out",
        "o",
        "--bus",
        "udp_multicast:239.74.166.12",
        "--wait",
        "compiled",
        *given,
    ]
    done = subprocess.run(
        [sys.executable, "-m", "motosim", *argv], capture_output=True, text=True, check=False
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr == (
        f"motosim: error: --wait compiled with {other}; the compiled wait applies only to "
        f"{why}: leave --wait out with {other}\n"
    )
    assert _codes_and_heavy(argv) == "[2] []"


@pytest.mark.parametrize("given", [["--pace", "bus"], ["--link", "python-can"]])
@pytest.mark.parametrize("wait", [[], ["--wait", "python"]])
def test_the_wait_left_out_or_python_passes_silently_paced_by_the_bus_or_on_python_can(
    given: list[str], wait: list[str]
) -> None:
    # the default, and the Python wait those runs use, are not refused: the refusal that
    # comes is the next check's (--spin)
    argv = [
        "run",
        "s.toml",
        "--out",
        "o",
        "--bus",
        "udp_multicast:239.74.166.12",
        "--spin",
        "-1",
        *given,
        *wait,
    ]
    done = subprocess.run(
        [sys.executable, "-m", "motosim", *argv], capture_output=True, text=True, check=False
    )
    assert done.returncode == 2
    assert done.stderr == "motosim: error: --spin -1.0; expected microseconds in [0, 1000000)\n"


def test_the_columns_help_names_every_unit_the_log_reader_converts() -> None:
    """``identify --columns`` lists the units of the log's time, angle, current and voltage
    columns: those :mod:`motosim.io.logs` converts (the identify guide lists the same; the
    help left out mV)."""
    import contextlib
    import io
    import re

    from motosim.cli.main import main
    from motosim.io.logs import _UNITS

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["identify", "--help"])
    listed = re.search(r"\(units ([^)]*)\)", " ".join(out.getvalue().split()))
    assert listed is not None
    quantities = ("time", "angle", "current", "voltage")
    converted = {name for name, (what, _) in _UNITS.items() if what in quantities}
    assert {unit.lower() for unit in listed.group(1).split(", ")} == {
        name for name in converted if name.isascii()
    }
