"""
The handling figure: steer torque and roll in steady turns
==========================================================

The Suzuki GSX-R1000 of Sharp, Evangelou & Limebeer (2004) on the multibody model
(:mod:`motosim.model.tyred`, toroidal wheels, its Magic Formula tyres),
trimmed in steady right turns (:func:`motosim.model.trim.steady_turn`) at 10, 20 and 30 m/s
from 0.05 g to 0.9 g: the rider's steer torque and the roll against lateral acceleration,
the kinematic roll atan(a_y / g) dashed. The same figure at the command line:
``motosim trim --handling --plot handling.png``.
"""

import math

from motosim.model.trim import handling_curve, steady_turn
from motosim.model.tyred import load_model
from motosim.plotting import plot_handling

model = load_model("sel2004_motorcycle")
curves = {speed: handling_curve(model, speed) for speed in (10.0, 20.0, 30.0)}
fig = plot_handling(curves, title="GSX-R1000 (Sharp, Evangelou & Limebeer 2004), steady turns")

# %%
# One turn, 20 m/s on a 50 m radius (0.82 g): the roll and the kinematic roll [deg], the
# rider's steer torque [N m].
turn = steady_turn(model, 20.0, 50.0)
print(round(math.degrees(turn.phi), 2), round(math.degrees(turn.phi_kinematic), 2))
print(round(turn.tau_r, 2))
