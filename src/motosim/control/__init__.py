"""Robust control design: H-infinity norm, Glover-McFarlane loop shaping, fixed-order tuning.

Design-time, pure functions on numpy/scipy (Section IV of the paper, eqs. (18)-(26)):

* :func:`hinf_norm` -- H-infinity norm and peak frequency (Hamiltonian level sets);
* :func:`ncfsyn` -- full-order Glover-McFarlane controller and ``gamma_min``;
* :func:`four_block_norm`, :func:`closed_loop_poles` -- the eq. (25) objective and the loop;
* :func:`fixed_order_synthesis` -- HIFOO-style low-order controller, e.g. eq. (26).

All controllers follow the paper's **positive**-feedback convention ``u = K y`` with the loop
``(I - G K)^-1`` (eq. (24)).
"""

from motosim.control.fixed_order import FixedOrderResult, fixed_order_synthesis
from motosim.control.loops import closed_loop_poles, four_block_norm, four_block_system
from motosim.control.ncf import NcfsynResult, ncfsyn
from motosim.control.norms import hinf_norm
from motosim.control.reduction import balanced_truncation
from motosim.control.statespace import StateSpace, as_state_space, frequency_response

__all__ = [
    "FixedOrderResult",
    "NcfsynResult",
    "StateSpace",
    "as_state_space",
    "balanced_truncation",
    "closed_loop_poles",
    "fixed_order_synthesis",
    "four_block_norm",
    "four_block_system",
    "frequency_response",
    "hinf_norm",
    "ncfsyn",
]
