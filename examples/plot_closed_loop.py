"""
A closed-loop run: the lane change at 20 m/s
============================================

The whole loop of the paper's Fig. 7 on a scenario file: a virtual rider steers a 3.5 m lane
change by torque on the simulated handlebar; the stack estimates that torque from the
sampled angle and current, drives Sharp's motorcycle with it and commands the motor so that
the handlebar follows the motorcycle's steer angle. ``motosim simulate`` does the same and
writes the result files and a report; here the run is shortened to 6 s.
"""

import dataclasses
from pathlib import Path

import numpy as np

from motosim.io.results import SimResult
from motosim.io.runs import load_run
from motosim.plotting.closed_loop import plot_torque, plot_tracking
from motosim.sim import build_stack, simulate

# the repository's scenarios/, from its root or from examples/
root = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "scenarios").is_dir())
scenarios = root / "scenarios"
run = load_run(scenarios / "lane_change_20.toml")  # parameter sets and design resolved
run = dataclasses.replace(run, scenario=dataclasses.replace(run.scenario, duration=6.0))
stack = build_stack(run)  # design once ...
series = simulate(run, rng=np.random.default_rng(0), stack=stack)  # ... run

tracking = np.sqrt(np.mean((series["theta_h"] - series["delta"]) ** 2))
estimate = np.sqrt(np.mean((series["tau_r_hat"] - series["tau_r"]) ** 2))
print(f"tracking RMS {np.degrees(tracking):.3f} deg, torque estimate RMS {estimate:.2f} N*m")

# %%
# The figures of the report, from the recorded signals (:data:`motosim.signals.RECORDED`).
result = SimResult(series.t, series.data, series.names, {}, {}, True)
fig_torque = plot_torque(result)
fig_tracking = plot_tracking(result)
