"""
A small campaign: the lane change's sharpness against the motor's torque constant
===================================================================================

A campaign runs one scenario many times over values a simulator builder does not know
exactly. Here four runs of the virtual rider's 3.5 m lane change at 20 m/s with the paper's
+/-10 N*m square torque added, on a 2 x 2 grid of the true motor's torque constant k_t and
the lane change's length (the shorter, the harder the rider steers), 10 s each, in this
process (``jobs=1``); ``motosim campaign FILE --out DIR`` runs the same file on every core or
on a Dask cluster. The observer converts current to torque with the nominal k_t, so a k_t
that is off shows in the torque estimate's error, in proportion to the torque: the sharper
lane change, where the rider steers harder, weighs more than the 20 % on k_t here.
"""

import tempfile
import tomllib
from pathlib import Path

import numpy as np

from motosim.campaign import load_results, parse_campaign, run_campaign
from motosim.plotting.campaign import plot_metric_vs_factors

# the repository's campaigns/, from its root or from examples/
root = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "campaigns").is_dir())
base = root / "campaigns" / "paper_robustness_base.toml"
text = f"""
[campaign]
name = "gallery"
scenario = "{base.as_posix()}"
sampling = "grid"
seed = 0
metrics = ["rms_tau_r_error", "rms_tracking_error"]

[factors]
"true_handlebar.k_t" = [0.2, 0.3]            # N*m/A; the nominal handlebar has 0.25
"rider.path.length" = [40.0, 120.0]          # m, at 20 m/s: 2 s or 6 s
"""
campaign = parse_campaign(tomllib.loads(text), origin="gallery.toml", folder=base.parent)

out = Path(tempfile.mkdtemp()) / "campaign"
summary = run_campaign(campaign, out, jobs=1)
rows = load_results(out)
for k_t, length, error in zip(
    rows["true_handlebar.k_t"], rows["rider.path.length"], rows["rms_tau_r_error"], strict=True
):
    print(f"k_t {k_t:.2f} N*m/A, {length:3.0f} m: torque estimate RMS error {error:5.2f} N*m")

# %%
# Each metric against each factor, as in the campaign's report.
fig = plot_metric_vs_factors(
    {key: rows[key] for key in ("true_handlebar.k_t", "rider.path.length")},
    rows["rms_tau_r_error"],
    rows["status"] != "ok",
    label="rms_tau_r_error [N*m]",
)
print(np.unique(rows["status"]))
