"""Run the benchmarks: ``make bench`` or ``python bench/run.py [NAME ...] [--json]``.

Each benchmark module ``bench/bench_*.py`` has ``run() -> dict`` that measures the project's
code and a baseline in the same run and returns the figures (speeds and ratios). Timings are
best-of-N on this machine, in wall-clock time and, where the module says so, CPU time
(``time.thread_time``, ``time.process_time`` or a subprocess's ``RUSAGE_CHILDREN``) beside
the load average (``os.getloadavg``): on a shared machine the CPU time is the figure to
compare; compare ratios, not absolute numbers, across machines.
"""

import argparse
import importlib
import json
import sys
from pathlib import Path

HERE = Path(__file__).parent


def main() -> int:
    """Run the selected benchmarks and print their figures."""
    names = sorted(p.stem.removeprefix("bench_") for p in HERE.glob("bench_*.py"))
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("names", nargs="*", help=f"benchmarks to run (of {', '.join(names)})")
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args()
    unknown = set(args.names) - set(names)
    if unknown:
        parser.error(f"unknown benchmark {sorted(unknown)[0]!r}; expected some of {names}")
    sys.path.insert(0, str(HERE))
    results = {}
    for name in args.names or names:
        module = importlib.import_module(f"bench_{name}")
        results[name] = module.run()
        if not args.json:
            print(f"== {name}")
            for key, value in results[name].items():
                shown = f"{value:.4g}" if isinstance(value, float) else str(value)
                print(f"  {key:<44} {shown}")
    if args.json:
        print(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
