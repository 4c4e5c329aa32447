"""The compiled stack of :mod:`motosim.sim.stack` behind the loop's :class:`StackStepper`.

:class:`CompiledStack` holds a :class:`~motosim.sim.stack.StackModel` and its
:class:`~motosim.sim.stack.StackData` and calls the very :func:`~motosim.sim.stack.reset`
and :func:`~motosim.sim.stack.step` that the offline simulator calls; it adds only the
bookkeeping of the real-time loop:

- the current the stack is told about is the measured one and what the safety stage will
  pass: the step takes the share of its command the drive will carry (``scale``: the fade
  and the hands-off gain) and the measured minus the expected current (``current_error =
  i_meas - scale * i_cmd`` of the last period; zero in an ideal, noise-free loop, as
  offline), so a clamp or a slew reaches the estimator at the next status frame;
- the longitudinal force of eq. (2) comes from the scenario's profiles, one value per period;
- the true rider torque is unknown in real time (0: a ``motorcycle.input = "true"`` run is a
  simulation-only reference and is refused by ``motosim run``);
- where the drive's status frames come slower than the control periods (the paper's 100 Hz
  CAN link under a 1 kHz loop), the stack measures in the period a new frame arrives, not on
  its own count: the drive's clock is not the loop's, and a count would read one frame twice
  and skip the next, which the observer's fixed step reads as motion.

:func:`result_block` turns the loop's rows into the columns of the result files that
``motosim simulate`` writes, so that ``motosim report`` reads a real-time run as it is.
"""

from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.signals import RECORDED
from motosim.sim.stack import (
    Held,
    MotorcycleState,
    StackData,
    StackModel,
    new_data,
    reset,
    step_scaled,
)

__all__ = [
    "RESULT_SIGNALS",
    "STACK_SIGNALS",
    "CompiledStack",
    "LoopState",
    "StackParts",
    "compiled",
    "result_block",
    "stack_period",
    "stack_reset",
]

Array = NDArray[np.float64]

_MOTORCYCLE_SIGNALS = tuple(name for name in RECORDED if name in MotorcycleState.__members__)
STACK_SIGNALS = ("tau_r_hat", "theta_h_meas", "theta_h_dot_hat", "i_m", *_MOTORCYCLE_SIGNALS)
"""The stack's row: its estimate, the measurement it used, its command [A] and the virtual
motorcycle's states, in the order of :data:`motosim.signals.RECORDED`."""

_ROW_FROM_HELD = tuple(
    (STACK_SIGNALS.index(h.name), int(h)) for h in Held if h.name in STACK_SIGNALS
)
"""The row's columns of the stack's held outputs, each with its position in them."""
_ROW_FROM_MOTORCYCLE = tuple(
    (STACK_SIGNALS.index(m.name), int(m)) for m in MotorcycleState if m.name in STACK_SIGNALS
)
"""The row's columns of the motorcycle's states, each with its position in the state."""
_ROW_COMMAND = STACK_SIGNALS.index("i_m")
"""The row's column of the command [A] (the one returned, not the held one)."""

RESULT_SIGNALS = tuple(
    name for name in RECORDED if name in {"t", "theta_h", "tau_m", *STACK_SIGNALS}
)
"""Columns of a real-time run's result files: the columns of an offline run's
(:data:`motosim.signals.RECORDED`) that a real-time run knows, in the same order. ``i_m`` is
the current *sent* (after the safety stage), ``tau_m`` = N k_t i_m of the nominal handlebar,
and ``theta_h`` the measured angle: the true one, like ``tau_r``, is not known in real
time."""


class LoopState(IntEnum):
    """Positions in what :func:`stack_period` keeps between periods
    (:attr:`CompiledStack.state`)."""

    period = 0
    """The period's index since the stack's reset."""
    expected_current = 1
    """The current the drive was expected to carry in the last period [A]."""
    since_measurement = 2
    """The periods since the last measurement."""


class StackParts(NamedTuple):
    """What one period of the compiled stack works on (:func:`stack_period`)."""

    model: StackModel
    """The stack's model (:func:`motosim.sim.build_stack`)."""
    data: StackData
    """Its states (:func:`motosim.sim.stack.new_data`)."""
    force: Array
    """The longitudinal force of each period [N]."""
    side_force: Array
    """The side force of each period [N]."""
    state: Array
    """What :func:`stack_period` keeps between periods, in the order of :class:`LoopState`."""


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
    One period is :func:`stack_period`, which the runner's fused period calls and
    :meth:`step` calls from Python: the constructor compiles (or loads) it before the loop's
    first deadline (:func:`compiled`).
    """

    names = STACK_SIGNALS

    def __init__(
        self, model: StackModel, *, force: Array | None = None, side_force: Array | None = None
    ) -> None:
        self.model = model
        self.data = new_data(model)
        self.force = _series(force, "force")
        self.side_force = _series(side_force, "side_force")
        self.state = np.zeros(len(LoopState))  # in the order of LoopState
        self._row = np.zeros(len(STACK_SIGNALS))
        # before its first step: the motorcycle upright and straight at its speed, as reset
        self._row[STACK_SIGNALS.index("v_x")] = model.speed
        self._parts = StackParts(model, self.data, self.force, self.side_force, self.state)
        self._step = compiled(stack_period, self._parts, self._row, 0.0, 0.0, True, 1.0, 0.0)
        self._reset = compiled(stack_reset, self._parts, 0.0, 0.0)

    @property
    def compiled_parts(self) -> StackParts:
        """What the runner's fused period steps (:mod:`motosim.rt.fused`): the stack itself,
        its arrays shared."""
        return self._parts

    def reset(self, theta: float, current: float) -> None:
        """Start the stack at the measured angle [rad] and current [A]."""
        self._reset(self._parts, theta, current)

    def step(
        self,
        theta_meas: float,
        i_meas: float,
        fresh: bool = True,
        scale: float = 1.0,
        torque: float = 0.0,
    ) -> float:
        """One period of the compiled stack (:func:`stack_period`): the motor current
        command [A]; ``fresh``: a new status frame came this period, ``scale``: the share of
        the command the safety stage will pass, ``torque``: the torque sensor's last reading
        [N*m]."""
        parts, row = self._parts, self._row
        command: float = self._step(parts, row, theta_meas, i_meas, fresh, scale, torque)
        return command

    def row(self) -> Array:
        """The values of :data:`STACK_SIGNALS` after the last step (before the first: the
        motorcycle upright and straight at its speed, every other value 0)."""
        return self._row


@njit(cache=True)
def stack_reset(stack: StackParts, theta: float, current: float) -> None:
    """:func:`~motosim.sim.stack.reset` of ``stack`` at the measured angle [rad] and current
    [A]; the period's index to 0 and the last command to the measured current."""
    reset(stack.model, stack.data, theta, current)
    state = stack.state
    state[LoopState.period] = 0.0
    state[LoopState.expected_current] = current
    state[LoopState.since_measurement] = 0.0


@njit(cache=True)
def stack_period(
    stack: StackParts,
    row: Array,
    theta_meas: float,
    i_meas: float,
    fresh: bool,
    scale: float,
    torque: float,
) -> float:
    """One period of ``stack`` in the loop: the motor current command [A].

    :func:`~motosim.sim.stack.step_scaled` with this period's forces (the last ones held),
    ``scale`` the share of the command the safety stage will pass
    (:func:`~motosim.rt.safety.safety_scale`), ``current_error`` the measured current
    minus the one expected in the last period (``LoopState.expected_current``) and the
    rider's torque ``torque`` [N*m] (a torque sensor's last reading, read by the estimator
    of kind :data:`~motosim.estimation.kernel.TORQUE_SENSOR`; 0 without a sensor); the
    stack's row
    (:data:`STACK_SIGNALS`) into ``row``. With a measurement every
    ``model.measure_every`` > 1 periods, the stack measures in the period a ``fresh``
    status frame came, or 1.5 measurement periods after the last one if none came (the
    last frame again); in no other.
    """
    model, data, force, side_force, state = stack
    every = model.measure_every
    if every > 1:
        if fresh or state[LoopState.since_measurement] >= every + every // 2:
            data.periods[0] = 0
            state[LoopState.since_measurement] = 0.0
        elif data.periods[0] % every == 0:
            data.periods[0] += 1  # the frame is late: wait for it
        state[LoopState.since_measurement] += 1.0
    k = int(state[LoopState.period])
    f = force[k] if k < force.size else force[-1]
    fy = side_force[k] if k < side_force.size else side_force[-1]
    expected = state[LoopState.expected_current]
    command = step_scaled(model, data, theta_meas, i_meas - expected, torque, f, fy, scale)
    state[LoopState.expected_current] = scale * command
    state[LoopState.period] = k + 1
    held, z = data.held, data.motorcycle
    for column, at in _ROW_FROM_HELD:
        row[column] = held[at]
    row[_ROW_COMMAND] = command
    for column, at in _ROW_FROM_MOTORCYCLE:
        row[column] = z[at]
    return command


def compiled(kernel: Any, *args: Any) -> Any:
    """The compiled ``kernel`` for the types of ``args``, called without numba's dispatch.

    A numba dispatcher works out the types of its arguments on every call (its cost in
    ``docs/performance.md``); the overload compiled (or loaded from the cache) here has an
    ``entry_point`` that unboxes the same arguments and runs the same machine code; nothing is
    run. Without numba's JIT (``NUMBA_DISABLE_JIT=1``) the plain function is returned.
    """
    if not hasattr(kernel, "compile"):
        return kernel
    import numba

    typeof: Any = numba.typeof
    types = tuple(typeof(a) for a in args)
    kernel.compile(types)
    return kernel.overloads[types].entry_point


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
    >>> at = RESULT_SIGNALS.index
    >>> [float(out[0, at(n)]) for n in ("t", "theta_h", "tau_m", STACK_SIGNALS[0], "i_m")]
    [0.1, 0.2, 6.0, 0.5, 3.0]
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
