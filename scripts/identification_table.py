"""Regenerate the identification accuracy table of the identify guide (the rig logs).

    .venv/bin/python scripts/identification_table.py [--seeds 10]

Each handlebar is simulated by the independent rig of the reference tests
(``tests/reference/identification/independent_rig.py``: Heun at 5 us, Karnopp stick-slip,
no motosim code), with a continuous measured current (0.1-4 Hz chirp, 4 A, 5 mA noise), a
14-bit encoder at a different count phase per seed and the handlebar moving at the start;
60 s at 100 Hz or 20 s at 1 kHz. Each log is identified with the default options, as
``motosim identify LOG --ratio 1 --torque-constant 1``. The table gives the worst error over
the seeds, the median 95 % half-width and how many intervals hold the true value.
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from motosim.identification import identify
from motosim.timeseries import TimeSeries

sys.path.insert(0, str(Path(__file__).parents[1] / "tests" / "reference" / "identification"))
from independent_rig import rig_log

HANDLEBARS = [(0.028, 18.5, 1.0), (0.045, 15.0, 2.0), (0.06, 9.0, 1.0), (0.08, 6.0, 0.5)]
COUNT = 2.0 * math.pi / 2**14


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    print(
        "| J, beta, beta_s (J/beta) | rate | J_eq error, half-width, covered | beta_eq | beta_s |"
    )
    print("|---|---|---|---|---|")
    for rate, duration in ((100.0, 60.0), (1000.0, 20.0)):
        for truth in HANDLEBARS:
            J, beta, beta_s = truth
            errors, halves, inside = [], [], np.zeros(3, dtype=int)
            for seed in range(args.seeds):
                t, theta, current = rig_log(
                    J=J,
                    beta=beta,
                    beta_s=beta_s,
                    sample_rate=rate,
                    duration=duration,
                    amplitude=4.0,
                    seed=seed,
                    theta0=0.2 + 0.1 * seed * COUNT,
                    omega0=0.3,
                )
                log = TimeSeries(t, np.column_stack([theta, current]), ("theta_h", "i_m"))
                est = identify(log, torque_per_amp=1.0)
                assert est.confidence is not None
                p = np.array(truth)
                errors.append(np.abs(est.parameters / p - 1.0))
                halves.append(0.5 * (est.confidence[:, 1] - est.confidence[:, 0]) / p)
                inside += (est.confidence[:, 0] <= p) & (p <= est.confidence[:, 1])
            worst = np.max(errors, axis=0)
            half = np.median(halves, axis=0)
            cells = [
                f"{100 * worst[k]:.2g} %, +/-{100 * half[k]:.2g} %, {inside[k]}/{args.seeds}"
                for k in range(3)
            ]
            print(
                f"| {J:g}, {beta:g}, {beta_s:g} ({1e3 * J / beta:.2g} ms) | {rate:g} Hz | "
                + " | ".join(cells)
                + " |"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
