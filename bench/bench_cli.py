"""Start-up of the command line: ``motosim --help`` and every ``motosim COMMAND --help``.

The baseline of ``motosim --help`` imports every subcommand module first, as
``motosim.cli.main`` did before the subcommands were imported lazily, and the numerical stack
those modules imported before they built their parsers from light modules only (NumPy, SciPy,
h5py and the compiled models), then runs the same ``--help``. Each subcommand's ``--help`` and
a usage error (an unknown option) are timed too, the slowest reported; their baseline is
``motosim simulate --help`` after importing the modules ``motosim.cli.simulate`` imported
before. All run in a fresh interpreter, best of N wall-clock runs.
"""

import subprocess
import sys
import time

_STACK = (
    "motosim.control.torque_feedback",
    "motosim.cueing",
    "motosim.estimation",
    "motosim.identification",
    "motosim.io.design_file",
    "motosim.io.results",
    "motosim.io.runs",
    "motosim.model.sharp",
    "motosim.sim",
    "motosim.sim.loop_analysis",
    "motosim.sim.metrics",
)
"""What the subcommand modules imported at their top before (``git show 330bc57:src/motosim``)."""
_SIMULATE_STACK = ("motosim.io.results", "motosim.io.runs", "motosim.sim", "motosim.sim.metrics")

_LAZY = "from motosim.cli.main import main; main(['--help'])"
_EAGER = (
    "import importlib\n"
    "from motosim.cli.main import COMMANDS, main\n"
    f"for module in [*(m for m, _ in COMMANDS.values()), *{_STACK!r}]:\n"
    "    importlib.import_module(module)\n"
    "main(['--help'])\n"
)
_COMMAND = "from motosim.cli.main import main; main([{name!r}, {option!r}])"
_SIMULATE_EAGER = (
    f"import {', '.join(_SIMULATE_STACK)}\n"
    "from motosim.cli.main import main\n"
    "main(['simulate', '--help'])\n"
)


def _best(code: str, repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True)
        if done.returncode not in (0, 2):  # 2: the usage error asked for
            raise RuntimeError(f"{code!r} failed: {done.stderr.decode()[-300:]}")
        best = min(best, time.perf_counter() - start)
    return best


def run() -> dict[str, float | str]:
    """Seconds to print ``motosim --help`` (lazy and eager), the slowest subcommand's
    ``--help`` and usage error, the baseline ``simulate --help``, and their ratios."""
    from motosim.cli.main import COMMANDS

    lazy, eager = _best(_LAZY), _best(_EAGER)
    helps = {name: _best(_COMMAND.format(name=name, option="--help"), 3) for name in COMMANDS}
    errors = {name: _best(_COMMAND.format(name=name, option="--no-such"), 3) for name in COMMANDS}
    slow_help, slow_error = max(helps, key=helps.__getitem__), max(errors, key=errors.__getitem__)
    baseline = _best(_SIMULATE_EAGER, 3)
    return {
        "help_lazy_s": lazy,
        "help_eager_s": eager,
        "ratio": eager / lazy,
        "command_help_slowest": slow_help,
        "command_help_slowest_s": helps[slow_help],
        "usage_error_slowest": slow_error,
        "usage_error_slowest_s": errors[slow_error],
        "simulate_help_s": helps["simulate"],
        "simulate_help_stack_loaded_s": baseline,
        "simulate_help_ratio": baseline / helps["simulate"],
    }


if __name__ == "__main__":
    print(run())
