"""The compiled stack of :mod:`motosim.sim.stack` behind the loop's :class:`StackStepper`.

:class:`CompiledStack` holds a :class:`~motosim.sim.stack.StackModel` and its
:class:`~motosim.sim.stack.StackData` and calls the very :func:`~motosim.sim.stack.reset`
and :func:`~motosim.sim.stack.step` that the offline simulator calls; it adds only the
bookkeeping of the real-time loop:

- the current the stack is told about is the measured one: ``step`` takes the measured minus
  the commanded current (``current_error``), and the command the drive carried over the last
  period is the one the stack gave then, so ``current_error = i_meas - i_cmd(previous)``
  (zero in an ideal, noise-free loop, as offline);
- the longitudinal force of eq. (2) comes from the scenario's profiles, one value per period;
- the true rider torque is unknown in real time (0: a ``motorcycle.input = "true"`` run is a
  simulation-only reference and is refused by ``motosim run``).

:func:`result_block` turns the loop's rows into the columns of the result files that
``motosim simulate`` writes, so that ``motosim report`` reads a real-time run as it is.
"""

from typing import Any

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.sim.stack import StackModel, new_data, reset, step

__all__ = ["RESULT_SIGNALS", "STACK_SIGNALS", "CompiledStack", "result_block"]

Array = NDArray[np.float64]

STACK_SIGNALS = (
    "tau_r_hat", "theta_h_meas", "theta_h_dot_hat", "i_m", "delta", "v_x", "v_y", "psi_dot",
    "phi_dot", "delta_dot", "phi", "F_yr", "F_yf", "psi", "x", "y",
)  # fmt: skip
"""The stack's row: its estimate, the measurement it used, its command [A] and the virtual
motorcycle's states (names of :mod:`motosim.signals`)."""

RESULT_SIGNALS = ("t", "theta_h", "tau_m", *STACK_SIGNALS)
"""Columns of a real-time run's result files. ``i_m`` is the current *sent* (after the safety
stage), ``tau_m`` = N k_t i_m of the nominal handlebar, and ``theta_h`` the measured angle:
the true one, like ``tau_r``, is not known in real time."""


class CompiledStack:
    """The designed stack as a :class:`~motosim.rt.run.StackStepper`.

    Parameters
    ----------
    model : StackModel
        From :func:`motosim.sim.build_stack`.
    force : ndarray, optional
        Longitudinal force of eq. (2) for each period [N] (the last one held); 0 by default.
    side_force : ndarray, optional
        Side force on the motorcycle (a side wind, to the right) for each period [N] (the
        last one held); 0 by default.

    Notes
    -----
    The constructor runs one step on scratch data so that every compiled kernel is ready
    before the loop's first deadline, and keeps the compiled step for the model's types
    to call it without numba's per-call type dispatch (the same machine code).
    """

    names = STACK_SIGNALS

    def __init__(
        self, model: StackModel, *, force: Array | None = None, side_force: Array | None = None
    ) -> None:
        self.model = model
        self.data = new_data(model)
        self._force = _series(force, "force")
        self._side = _series(side_force, "side_force")
        self._k = 0
        self._last = 0.0
        self._row = np.zeros(len(STACK_SIGNALS))
        scratch = new_data(model)  # warm-up: compile (or load) every kernel now
        reset(model, scratch, 0.0, 0.0)
        step(model, scratch, 0.0, 0.0, 0.0, 0.0, 0.0)
        self._step = _compiled(step, model, self.data)

    def reset(self, theta: float, current: float) -> None:
        """Start the stack at the measured angle [rad] and current [A]."""
        reset(self.model, self.data, theta, current)
        self._k = 0
        self._last = current

    def step(self, theta_meas: float, i_meas: float) -> float:
        """One period of the compiled stack: the motor current command [A]."""
        k = self._k
        force, side = self._force, self._side
        f = force[k] if k < force.size else force[-1]
        fy = side[k] if k < side.size else side[-1]
        command: float = self._step(
            self.model, self.data, theta_meas, i_meas - self._last, 0.0, f, fy
        )
        self._last = command
        self._k += 1
        held, z, row = self.data.held, self.data.motorcycle, self._row
        row[0], row[1], row[2], row[3] = held[3], held[0], held[2], command
        row[4], row[5], row[6], row[7] = z[5], z[8], z[0], z[1]
        row[8], row[9], row[10], row[11] = z[2], z[3], z[4], z[6]
        row[12], row[13], row[14], row[15] = z[7], z[9], z[10], z[11]
        return command

    def row(self) -> Array:
        """The values of :data:`STACK_SIGNALS` after the last step."""
        return self._row


def _compiled(kernel: Any, model: StackModel, data: Any) -> Any:
    """The compiled ``kernel`` for the stack's argument types, called without numba's dispatch.

    A numba dispatcher works out the types of its arguments on every call: for the stack's
    model and data structures that costs about three times the step itself (measured in
    ``bench/bench_rt_period.py``). The compiled overload's ``entry_point`` (in the
    dispatcher's ``overloads``, keyed by the argument types) unboxes the same arguments and
    runs the same machine code. Without numba's JIT (``NUMBA_DISABLE_JIT=1``) the plain
    function is returned.
    """
    overloads = getattr(kernel, "overloads", None)
    if not overloads:
        return kernel
    import numba

    typeof: Any = numba.typeof
    types = tuple(typeof(a) for a in (model, data, 0.0, 0.0, 0.0, 0.0, 0.0))
    found = overloads.get(types)
    return kernel if found is None else found.entry_point


def _series(values: Array | None, name: str) -> Array:
    out = np.zeros(1) if values is None else np.asarray(values, dtype=float)
    if out.ndim != 1 or out.size == 0 or not np.all(np.isfinite(out)):
        raise MotosimError(f"{name}: expected a non-empty 1-D array of finite values [N]")
    return out


def result_block(rows: Array, names: tuple[str, ...], torque_per_amp: float) -> Array:
    """Rows of the loop (columns ``names``) as rows of :data:`RESULT_SIGNALS`.

    Examples
    --------
    >>> names = ("t", "theta_h_meas", "i_safe", *STACK_SIGNALS[:1], "i_m")
    >>> out = result_block(np.array([[0.1, 0.2, 3.0, 0.5, 4.0]]), names, 2.0)
    >>> [float(x) for x in out[0, :4]], float(out[0, RESULT_SIGNALS.index("i_m")])
    ([0.1, 0.2, 6.0, 0.5], 3.0)
    """
    col = {name: i for i, name in enumerate(names)}
    out = np.full((rows.shape[0], len(RESULT_SIGNALS)), np.nan)
    for j, name in enumerate(RESULT_SIGNALS):
        if name == "theta_h":
            out[:, j] = rows[:, col["theta_h_meas"]]
        elif name == "i_m":
            out[:, j] = rows[:, col["i_safe"]]
        elif name == "tau_m":
            out[:, j] = torque_per_amp * rows[:, col["i_safe"]]
        elif name in col:
            out[:, j] = rows[:, col[name]]
    return out
