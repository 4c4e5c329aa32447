"""
Braking at the tyre limit on the multibody motorcycle
=====================================================

The training scenario ``limit_braking``: both brakes demanded hard from 25 m/s on a dry
road. The virtual motorcycle is the multibody model on the sel2004 set's Magic Formula tyres
(a GSX-R1000 with its rider), so the load moves to the front wheel and the machine pitches
forward on its tyres; the virtual rider's brake controller holds each wheel's slip at -0.1,
near the tyres' peak, and keeps the rear wheel on the ground. The run decelerates at 1.0 g,
the road's friction, while Sharp's (1971) model, with its constant loads, would not know it
had a limit.
"""

from pathlib import Path

import numpy as np

from motosim.io.runs import load_run
from motosim.plotting import plot_tyre_loads
from motosim.sim import simulate

root = next(p for p in (Path.cwd(), *Path.cwd().parents) if (p / "scenarios").is_dir())
run = load_run(root / "scenarios" / "limit_braking.toml")  # the model and the rider designed
series = simulate(run, rng=np.random.default_rng(0))

braking = (series.t > 1.3) & (series.t < 3.3)
deceleration = -np.polyfit(series.t[braking], series["v_x"][braking], 1)[0]
transfer = series["F_zf"][braking].mean() - series["F_zf"][0]
print(f"deceleration {deceleration / 9.81:.2f} g, load moved to the front {transfer:.0f} N")

# %%
# The normal loads (the rear's falls to about 320 N, kept above its floor), the longitudinal
# forces (the front's equals its load: the road's whole friction), the slips held at -0.1
# and the pitch, nose down, against the speed.
fig = plot_tyre_loads(series, title="limit_braking: sel2004 on mu = 1")
