"""
Modes against speed on both models
==================================

Capsize, weave and wobble against speed, each model linearised about upright straight
running and its modes followed continuously over speed
(:func:`motosim.model.sharp.track_modes`): Sharp's (1971) machine on his linear model
(solid), the same machine through the multibody model on his linear relaxing tyres (dashed,
:func:`motosim.model.tyred.sharp_modes`), and the Suzuki GSX-R1000 of Sharp, Evangelou &
Limebeer (2004) on the multibody model with its Magic Formula tyres (dotted,
:func:`motosim.model.tyred.lateral_modes`). The same tables at the command line:
``motosim modes``, ``motosim modes --model multibody`` and
``motosim modes --params sel2004_motorcycle``.
"""

import numpy as np

from motosim.model import sharp, tyred
from motosim.params import load_parameters
from motosim.plotting import plot_mode_comparison, plot_modes

speeds = np.arange(2.0, 60.5, 0.5)  # [m/s]
bike = load_parameters("sharp1971", "sharp")
gsxr = tyred.load_model("sel2004_motorcycle")
tables = {
    "Sharp 1971, linear model": sharp.modes(bike, speeds),
    "Sharp 1971, multibody model": tyred.sharp_modes(bike, speeds),
    "GSX-R1000, multibody on MF tyres": tyred.lateral_modes(gsxr, speeds),
}
fig = plot_mode_comparison(tables, title="Modes against speed: Sharp 1971 and the GSX-R1000")

# %%
# Sharp's machine is the same on both models (the weave and wobble differ by less than 1 % of
# the eigenvalue at 10-50 m/s); the GSX-R1000's weave is faster and its wobble slower, and
# with no steering damper in its set its wobble is unstable above about 28 m/s. Its weave
# and wobble [Hz] at 10, 30 and 50 m/s:
gsxr_table = tables["GSX-R1000, multibody on MF tyres"]
at = np.isin(speeds, [10.0, 30.0, 50.0])
print(np.round(gsxr_table.frequency_hz(gsxr_table.weave[at]), 2))
print(np.round(gsxr_table.frequency_hz(gsxr_table.wobble[at]), 2))

# %%
# The GSX-R1000 alone, its unstable speeds shaded (the figure of ``motosim modes --params
# sel2004_motorcycle --plot modes.png``):
fig_gsxr = plot_modes(gsxr_table, title="GSX-R1000 on its MF tyres (multibody model)")
