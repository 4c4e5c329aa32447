"""
Motorcycle tyre curves
======================

The front 120/70 ZR17 tyre of Sharp, Evangelou & Limebeer (2004) in the motorcycle Magic
Formula (:mod:`motosim.model.tyres`): side force against sideslip at three loads and four
cambers, longitudinal force against slip, and the friction ellipse of combined slip.
"""

from motosim.model.tyres import cornering_stiffness, tyre_coefficients
from motosim.params import load_parameters
from motosim.plotting import plot_tyre

front = tyre_coefficients(load_parameters("sel2004_front_120_70_zr17", "tyre"))
fig = plot_tyre(front, title="120/70 ZR17 front tyre (Evangelou 2004)")

# %%
# The normalised cornering stiffness at the nominal load of 1100 N [1/rad]:
print(round(cornering_stiffness(front, 1100.0, 0.0) / 1100.0, 2))
