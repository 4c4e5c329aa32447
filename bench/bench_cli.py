"""Start-up of the command line: ``motosim --help`` and every ``motosim COMMAND --help``.

The baseline of ``motosim --help`` imports every subcommand module first, as
``motosim.cli.main`` did before the subcommands were imported lazily, and the numerical stack
those modules imported before they built their parsers from light modules only (NumPy, SciPy,
h5py and the compiled models), then runs the same ``--help``. Each subcommand's ``--help`` and
a usage error (an unknown option) are timed too, the slowest reported; their baseline is
``motosim simulate --help`` after importing the modules ``motosim.cli.simulate`` imported
before. The time to the error line of a misspelt file (:data:`MISSPELT`: the command's input,
or the output of a command that reads none) and of a misspelt option is timed for every
command, and of a scenario value out of range (:data:`OUT_OF_RANGE`) for the commands that
read a scenario (target 0.5 s). All run in a fresh interpreter, best of N wall-clock runs, from a
scratch folder.
"""

import json
import os
import subprocess
import sys
import tempfile
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
MISSPELT: dict[str, list[str]] = {
    "params": ["params", "show", "nope.toml"],
    "modes": ["modes", "--params", "nope.toml"],
    "excite": ["excite", "--handlebar", "nope.toml", "--out", "x.csv"],
    "identify": ["identify", "nope.csv"],
    "estimate": ["estimate", "nope.csv", "--out", "x.csv"],
    "design": ["design", "--handlebar", "nope.toml"],
    "simulate": ["simulate", "nope.toml", "--out", "r"],
    "report": ["report", "nope"],
    "paper": ["paper", "--out", "nope/out"],
    "view": ["view", "nope"],
    "telemetry": ["telemetry", "nope", "--mcap", "x.mcap"],
    "campaign": ["campaign", "nope.toml", "--out", "c"],
    "fidelity": ["fidelity", "nope.toml"],
    "cueing": ["cueing", "nope", "--out", "q"],
    "run": ["run", "nope.toml", "--bus", "virtual", "--out", "r"],
    "rig": ["rig", "nope.toml", "--bus", "virtual"],
    "rt-check": ["rt-check", "--rate", "abc"],
    "cache": ["cache", "nope"],
}
"""A misspelt file for each command (rt-check reads none: a misspelt number; cache neither: a
misspelt action)."""
OUT_OF_RANGE: dict[str, list[str]] = {
    "simulate": ["simulate", "bad.toml", "--out", "r"],
    "campaign": ["campaign", "campaign.toml", "--out", "c"],
    "run": ["run", "bad.toml", "--bus", "virtual", "--out", "r"],
    "rig": ["rig", "bad.toml", "--bus", "virtual"],
}
"""A scenario value out of range (a drive torque of 1e6 N*m) for each command that reads a
scenario, the campaign's in its base scenario."""
_BAD_SCENARIO = '[scenario]\nname = "bad"\n[motorcycle]\ndrive_torque = 1e6\n'
_BAD_CAMPAIGN = '[campaign]\nscenario = "bad.toml"\nruns = 2\n'
_ARGV = (
    "import json, sys\nfrom motosim.cli.main import main\nsys.exit(main(json.loads(sys.argv[1])))"
)
_SIMULATE_EAGER = (
    f"import {', '.join(_SIMULATE_STACK)}\n"
    "from motosim.cli.main import main\n"
    "main(['simulate', '--help'])\n"
)


def _best(code: str, repeats: int = 5, *args: str, cwd: str | None = None) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-c", code, *args], check=False, capture_output=True, cwd=cwd
        )
        if done.returncode not in (0, 2):  # 2: the usage error asked for
            raise RuntimeError(f"{code!r} {args} failed: {done.stderr.decode()[-300:]}")
        best = min(best, time.perf_counter() - start)
    return best


def time_to_error() -> dict[str, dict[str, float]]:
    """Seconds to the error line of a misspelt file and of a misspelt option, per command,
    and of a scenario value out of range for the commands that read a scenario."""
    from motosim.cli.main import COMMANDS

    env_path = os.pathsep.join(sys.path)
    os.environ["PYTHONPATH"] = env_path  # the scratch folder is not where motosim is
    out: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as scratch:
        for name in COMMANDS:
            out[name] = {
                "misspelt_file_s": _best(_ARGV, 3, json.dumps(MISSPELT[name]), cwd=scratch),
                "misspelt_option_s": _best(_ARGV, 3, json.dumps([name, "--no-such"]), cwd=scratch),
            }
        with open(os.path.join(scratch, "bad.toml"), "w", encoding="utf-8") as f:
            f.write(_BAD_SCENARIO)
        with open(os.path.join(scratch, "campaign.toml"), "w", encoding="utf-8") as f:
            f.write(_BAD_CAMPAIGN)
        for name, argv in OUT_OF_RANGE.items():
            out[name]["out_of_range_s"] = _best(_ARGV, 3, json.dumps(argv), cwd=scratch)
    return out


def run() -> dict[str, float | str]:
    """Seconds to print ``motosim --help`` (lazy and eager), the slowest subcommand's
    ``--help`` and usage error, the baseline ``simulate --help``, and their ratios; the time
    to the error line of a misspelt file and option for every command."""
    from motosim.cli.main import COMMANDS

    lazy, eager = _best(_LAZY), _best(_EAGER)
    helps = {name: _best(_COMMAND.format(name=name, option="--help"), 3) for name in COMMANDS}
    errors = {name: _best(_COMMAND.format(name=name, option="--no-such"), 3) for name in COMMANDS}
    slow_help, slow_error = max(helps, key=helps.__getitem__), max(errors, key=errors.__getitem__)
    baseline = _best(_SIMULATE_EAGER, 3)
    to_error = time_to_error()
    slow_file = max(to_error, key=lambda n: to_error[n]["misspelt_file_s"])
    return {
        "misspelt_file_slowest": slow_file,
        "misspelt_file_slowest_s": to_error[slow_file]["misspelt_file_s"],
        "misspelt_option_slowest_s": max(v["misspelt_option_s"] for v in to_error.values()),
        "time_to_error": to_error,
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
    if sys.argv[1:] == ["--errors"]:
        print(json.dumps(time_to_error(), indent=1))
    else:
        print(run())
