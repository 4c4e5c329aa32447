"""Models: the Sharp (1971) motorcycle, its longitudinal equation, and the handlebar.

Each model is a set of pure functions of the parameters; steppers with memory live in
:mod:`motosim.model.handlebar` and :mod:`motosim.model.sharp` as plain numeric kernels.
"""

from motosim.model.linear import StateSpace

__all__ = ["StateSpace"]
