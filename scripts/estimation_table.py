"""Regenerate the estimation table of the identify guide (section V.A of the paper, Fig. 9).

    .venv/bin/python scripts/estimation_table.py [--plot FIG.png]

Every case of :data:`motosim.estimation.study.PAPER_CASES` is simulated and each estimator
of :data:`motosim.estimation.ESTIMATORS` reconstructs the square rider torque (10/70 N*m);
the table gives the RMS error outside 0.1 s after each step, in per cent of the 60 N*m step,
and the worst convergence time to within 5 % of the step.
"""

import argparse
import sys

from motosim.estimation import ESTIMATORS
from motosim.estimation.study import PAPER_CASES, run_case
from motosim.params import load_parameters


def main() -> int:
    """Print the Markdown table; optionally draw the nominal and perturbed estimates."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--plot", help="figure of the Walcott-Zak estimates (.png)")
    args = parser.parse_args()
    hb = load_parameters("simacom_handlebar", "handlebar")
    names = list(ESTIMATORS)
    print("| case | " + " | ".join(f"{n}: RMS, convergence" for n in names) + " |")
    print("|---|" + "---|" * len(names))
    runs = {}
    for case in PAPER_CASES:
        cells = []
        for name in names:
            out = run_case(case, hb, name)
            runs[(case.name, name)] = out
            conv = (
                "never"
                if out.convergence_time == float("inf")
                else (f"{1000 * out.convergence_time:.0f} ms")
            )
            cells.append(f"{100 * out.relative_rms:.2f} %, {conv}")
        print(f"| {case.name} | " + " | ".join(cells) + " |")
    if args.plot:
        from motosim.plotting import plot_torque_estimates

        shown = [c.name for c in PAPER_CASES[:3]] + [PAPER_CASES[5].name]
        fig = plot_torque_estimates({c: runs[(c, "walcott_zak")] for c in shown})
        fig.savefig(args.plot, dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
