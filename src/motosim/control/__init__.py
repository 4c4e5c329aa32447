"""Robust control design: H-infinity norm, Glover-McFarlane loop shaping, fixed-order tuning.

Design-time, pure functions on numpy/scipy (Section IV of the paper, eqs. (18)-(26)):

* :func:`hinf_norm` -- H-infinity norm and peak frequency (Hamiltonian level sets);
* :func:`ncfsyn` -- full-order Glover-McFarlane controller and ``gamma_min``;
* :func:`four_block_norm`, :func:`closed_loop_poles` -- the eq. (25) objective and the loop;
* :func:`fixed_order_synthesis` -- HIFOO-style low-order controller, e.g. eq. (26).

All controllers follow the paper's **positive**-feedback convention ``u = K y`` with the loop
``(I - G K)^-1`` (eq. (24)).

The names are imported from their modules on first use (PEP 562): a run whose controller is
designed already imports :mod:`motosim.control.statespace` without SciPy's optimisers.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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

_MODULE_OF = {
    "FixedOrderResult": "fixed_order",
    "fixed_order_synthesis": "fixed_order",
    "closed_loop_poles": "loops",
    "four_block_norm": "loops",
    "four_block_system": "loops",
    "NcfsynResult": "ncf",
    "ncfsyn": "ncf",
    "hinf_norm": "norms",
    "balanced_truncation": "reduction",
    "StateSpace": "statespace",
    "as_state_space": "statespace",
    "frequency_response": "statespace",
}


def __getattr__(name: str) -> Any:
    """A name of the package, imported from its module on first use."""
    if name in _MODULE_OF:
        value = getattr(import_module(f"motosim.control.{_MODULE_OF[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
