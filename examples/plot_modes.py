"""
Modes of Sharp's motorcycle against speed
=========================================

The lateral model of Sharp (1971) linearised at each forward speed: capsize, weave and wobble,
named at 20 m/s and followed eigenvalue by eigenvalue (:func:`motosim.model.sharp.modes`).
The same figure as ``motosim modes --range 2:60:0.5 --plot modes.png``.
"""

import numpy as np

from motosim.model import sharp
from motosim.params import load_parameters
from motosim.plotting import plot_modes

bike = load_parameters("sharp1971", "sharp")
table = sharp.modes(bike, np.arange(2.0, 60.0, 0.5))  # speeds [m/s]
fig = plot_modes(table, title="Sharp 1971, Appendix 3 machine")

# %%
# The weave at 10 and 30 m/s (eigenvalues in 1/s; Sharp 1971, Table 2, model 1, at 30 and
# 100 ft/s is the reference the tests pin these to):
weave = sharp.modes(bike, [10.0, 30.0]).weave
print(np.round(weave, 2))
