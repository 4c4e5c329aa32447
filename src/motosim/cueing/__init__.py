"""Motion cueing for the platform (roll, pitch, yaw) and vestibular scoring.

Layer: after :mod:`motosim.model`, beside identification, estimation and control. From a
recorded run (or, in the stack, sample by sample): the motorcycle's motion at the rider's
head (:mod:`~motosim.cueing.head`), a cueing algorithm (the classical washout of
:mod:`~motosim.cueing.washout`, compiled; the MPC of :mod:`~motosim.cueing.mpc` on OSQP),
the limit manager (:mod:`~motosim.cueing.limits`) and the score by what the rider would
perceive (:mod:`~motosim.cueing.vestibular`). Each algorithm has a pure ``design_*``
function returning frozen coefficients and a one-sample step; :func:`cue` runs the chain on
a whole series.
"""

from motosim.cueing.head import HEAD_SIGNALS, platform_motion, vehicle_motion
from motosim.cueing.limits import (
    LimitDesign,
    actuator_response,
    apply_limits,
    design_limits,
    limit_step,
)
from motosim.cueing.pipeline import ALGORITHMS, COMMAND_SIGNALS, CueingRun, cue, decimate
from motosim.cueing.platform import CueingConfig, Platform, list_platforms, load_platform
from motosim.cueing.vestibular import (
    BENSON_1986_1989,
    CHANNELS,
    TELBAN_CARDULLO_2005,
    CueingScore,
    VestibularModel,
    perceive,
    score,
)
from motosim.cueing.washout import WashoutDesign, apply_washout, design_washout, washout_step

__all__ = [
    "ALGORITHMS",
    "BENSON_1986_1989",
    "CHANNELS",
    "COMMAND_SIGNALS",
    "HEAD_SIGNALS",
    "TELBAN_CARDULLO_2005",
    "CueingConfig",
    "CueingRun",
    "CueingScore",
    "LimitDesign",
    "Platform",
    "VestibularModel",
    "WashoutDesign",
    "actuator_response",
    "apply_limits",
    "apply_washout",
    "cue",
    "decimate",
    "design_limits",
    "design_washout",
    "limit_step",
    "list_platforms",
    "load_platform",
    "perceive",
    "platform_motion",
    "score",
    "vehicle_motion",
    "washout_step",
]
