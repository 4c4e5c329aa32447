"""Start-up of the command line: ``motosim --help`` with lazy subcommands against eager ones.

The baseline imports every subcommand module first, as ``motosim.cli.main`` did before the
subcommands were imported lazily (the cost of NumPy, SciPy, h5py and the models), then runs
the same ``--help``. Both run in a fresh interpreter, best of 5 wall-clock runs.
"""

import subprocess
import sys
import time

_LAZY = "from motosim.cli.main import main; main(['--help'])"
_EAGER = (
    "import importlib\n"
    "from motosim.cli.main import COMMANDS, main\n"
    "for module, _ in COMMANDS.values():\n"
    "    importlib.import_module(module)\n"
    "main(['--help'])\n"
)


def _best(code: str, repeats: int = 5) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
        best = min(best, time.perf_counter() - start)
    return best


def run() -> dict[str, float]:
    """Seconds to print ``motosim --help``, lazy and eager, and their ratio."""
    lazy, eager = _best(_LAZY), _best(_EAGER)
    return {"help_lazy_s": lazy, "help_eager_s": eager, "ratio": eager / lazy}


if __name__ == "__main__":
    print(run())
