"""A lock-step run: the stack against the virtual rig in one process, on a simulated clock.

``motosim run`` and ``motosim rig`` run the stack and the virtual rig in two processes over a
bus, on the machine's clock. :class:`Lockstep` builds the same pieces from a run's inputs
in one process, over python-can's in-process ``virtual`` bus and on a
:class:`~motosim.rt.clock.SimulatedClock` that advances the rig to each deadline before the
loop's period: the run is deterministic and takes no longer than its computation. It is
how ``scripts/rt_frames_study.py`` and the real-time tests that compare the loop with the
offline simulator study slow status frames and bus latency (the tests of the frozen-sensor
monitor and of a stack stepped from Python build their own: they need a handlebar or a
stepper this class does not take).
"""

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.io.can import Link, handlebar_codecs, open_link
from motosim.rt.clock import SimulatedClock
from motosim.rt.config import refuse_offline_only
from motosim.rt.loop import RateLoop
from motosim.rt.rig import RigRider, RigSettings, VirtualRider, VirtualRig, torque_sensor
from motosim.rt.run import RealtimeRunner, RunSettings
from motosim.rt.safety import SafetyLimits
from motosim.rt.stack import CompiledStack
from motosim.rt.telemetry import StateReceiver, StateSender
from motosim.sim import RunInputs, Scenario, build_rig, build_stack
from motosim.sim.closed_loop import RigModel
from motosim.sim.stack import StackModel, account_for_delay

if TYPE_CHECKING:
    from motosim.rt.platform import PlatformOutput

__all__ = ["Lockstep", "free_limits", "ideal_rig"]


def ideal_rig(scenario: Scenario) -> RigSettings:
    """The virtual rig of ``scenario`` over an ideal bus, without current noise.

    Its plant and status frames at the scenario's plant and measurement rates [Hz], its
    encoder, the drive's current limit at the controller's [A]; no latency, jitter, loss
    or fault.

    Examples
    --------
    >>> from motosim.sim import parse_scenario
    >>> square = {"kind": "square", "low": -5.0, "high": 5.0, "period": 0.2}
    >>> sc = parse_scenario({
    ...     "scenario": {"name": "x"}, "rates": {"measurement": 100.0},
    ...     "rider": {"kind": "torque", "profile": square},
    ... }, origin="x")
    >>> rig = ideal_rig(sc)
    >>> rig.plant_rate, rig.status_rate, rig.current_noise, rig.latency
    (10000.0, 100.0, 0.0, 0.0)
    """
    return RigSettings(
        plant_rate=scenario.rates.plant,
        status_rate=scenario.rates.measurement,
        encoder_bits=scenario.measurement.encoder_bits,
        current_noise=0.0,
        max_current=scenario.controller.max_current,
    )


def free_limits(rate: float) -> SafetyLimits:
    """Safety limits that never bind, with a fade-in of one period at ``rate`` [Hz]: the
    safety stage passes the stack's command as it is, so the loop computes what the offline
    simulator computes.

    Examples
    --------
    >>> limits = free_limits(1000.0)
    >>> limits.max_current, limits.fade_in
    (1000.0, 0.001)
    """
    return SafetyLimits(
        max_current=1e3,
        max_slew=1e9,
        max_speed=1e3,
        speed_band=1.0,
        soft_stop=10.0,
        hard_stop=20.0,
        end_stop_gain=0.0,
        hands_off_torque=0.0,
        hands_off_time=1.0,
        hands_off_gain=1.0,
        fade_in=1.0 / rate,
    )


def _stack_and_world(inputs: RunInputs, delay: float, seed: int) -> tuple[StackModel, RigModel]:
    """The stack of ``inputs`` for status frames ``delay`` old and the rig's world, checked
    before any socket is opened."""
    if not (math.isfinite(delay) and delay >= 0.0):
        raise MotosimError(f"delay = {delay!r} s: expected a non-negative time")
    refuse_offline_only(inputs.scenario, origin=inputs.scenario.name)
    model = account_for_delay(build_stack(inputs), delay, inputs.design_handlebar)
    world = build_rig(inputs, rng=np.random.default_rng(seed))
    if world.virtual_rider:
        VirtualRider.check(world)
    return model, world


class Lockstep:
    """The run ``inputs`` against the virtual rig, in lock-step on a simulated clock.

    The compiled stack of the run, accounting for status frames ``delay`` old; the virtual
    rig of its true handlebar with the scenario's rider from the rig's t = 0 (its torque
    profile, or its :class:`~motosim.rt.rig.VirtualRider` steering by the stack's rows, sent
    over UDP on localhost; its hands as :func:`~motosim.sim.build_rig` holds them); the
    runner, stamping its rows on the simulated clock, whose first deadline is at t = 0.
    Unlike ``motosim run``, the runner has no frozen-sensor monitor (no handlebar given) and
    goes on outside the model's range unless ``validity`` is given.

    Parameters
    ----------
    inputs : RunInputs
        The run (:func:`motosim.sim.prepare`, :func:`motosim.io.runs.load_run`).
    limits : SafetyLimits
        The safety stage's limits.
    settings : RigSettings, optional
        The rig's drive, sensors and bus; by default :func:`ideal_rig` of the scenario.
    delay : float
        The status frames' age the stack accounts for [s], >= 0; 0: the stack as designed,
        for a fresh sample.
    channel : str
        The name of the python-can ``virtual`` channel (runs alive together need their own).
    seed : int
        The seed of the rig's noise, jitter and frame loss, and of the generator the run's
        world is built with (:func:`~motosim.sim.build_rig`); 0 by default, the seed the
        tests give the offline simulator they compare with (``motosim run`` and ``motosim
        rig`` take the scenario's ``seed``).
    validity : tuple of float, optional
        The runner's ``validity``: the virtual motorcycle's largest roll [rad], lowest and
        highest speed [m/s], beyond which the torque fades out and the run ends.
    platform : PlatformOutput, optional
        The runner's motion platform stage.

    Attributes
    ----------
    clock : SimulatedClock
        The clock; more listeners (a platform twin, a recorder) run after the rig's.
    host : Link
        The runner's end of the bus.
    rig : VirtualRig
        The virtual rig.
    runner : RealtimeRunner
        The runner.
    rider_torques : list of tuple of float
        With a virtual rider, ``(t, tau_r)`` each time the rig asked for the rider's torque
        (once per status frame): its time [s] and the torque [N*m]; empty with a profile.

    Examples
    --------
    A square rider torque of 5 N*m on the SIMACOM handlebar with the paper's controller,
    0.5 s at 1 kHz, safety limits that never bind:

    >>> from motosim.control.torque_feedback import PAPER_CONTROLLER
    >>> from motosim.params import load_parameters
    >>> from motosim.sim import parse_scenario, prepare
    >>> scenario = parse_scenario({
    ...     "scenario": {"name": "square", "duration": 0.5},
    ...     "rider": {"kind": "torque", "profile": {"kind": "square", "low": -5.0,
    ...               "high": 5.0, "period": 0.2}},
    ...     "controller": {"kind": "paper"},
    ... }, origin="square")
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> run = prepare(scenario, sharp=load_parameters("sharp1971", "sharp"), true_handlebar=hb,
    ...               nominal_handlebar=hb, controller=PAPER_CONTROLLER)
    >>> lock = Lockstep(run, free_limits(1000.0), channel="doctest")
    >>> rows = lock.run()
    >>> rows.shape[0], lock.runner.counters().fault, float(rows[-1, 0])  # periods, fault, t [s]
    (500, 'NONE', 0.499)
    """

    def __init__(
        self,
        inputs: RunInputs,
        limits: SafetyLimits,
        *,
        settings: RigSettings | None = None,
        delay: float = 0.0,
        channel: str = "lockstep",
        seed: int = 0,
        validity: tuple[float, float, float] | None = None,
        platform: "PlatformOutput | None" = None,
    ) -> None:
        model, world = _stack_and_world(inputs, delay, seed)
        sc = inputs.scenario
        self._rate = sc.rates.control
        self._periods = round(sc.duration * self._rate)
        codecs = handlebar_codecs()
        self.clock = SimulatedClock(-1.0 / self._rate)  # the first deadline at t = 0
        self.rider_torques: list[tuple[float, float]] = []
        self._receiver: StateReceiver | None = None
        self._sender: StateSender | None = None
        self._links: list[Link] = []
        try:
            rider = self._rider(world)
            self.host = open_link(f"virtual:{channel}")
            self._links.append(self.host)
            drive = open_link(f"virtual:{channel}")
            self._links.append(drive)
            held = RigRider(rider, on_enable=False, arms=world.arms, hands_off=world.hands_off)
            self.rig = VirtualRig(
                inputs.true_handlebar,
                settings or ideal_rig(sc),
                codecs,
                drive,
                held,
                np.random.default_rng(seed),
                torque_sensor=torque_sensor(sc),
            )
            run_settings = RunSettings(
                limits,
                self._rate,
                capacity=max(1 << 16, self._periods + 1),
                periods_per_frame=model.measure_every,
                torque_sensor=world.sensed,
                validity=validity,
            )
            self.runner = RealtimeRunner(
                CompiledStack(model, force=world.force, side_force=world.side_force),
                self.host,
                codecs,
                run_settings,
                platform=platform,
                now=self.clock.now,
                telemetry=None if self._sender is None else self._sender.send,
            )
        except BaseException:
            self.close()
            raise
        self.clock.listen(self.rig.advance_to)

    def _rider(self, world: RigModel) -> NDArray[np.float64] | Callable[[float], float]:
        """The rig's rider: the scenario's torque profile, or the virtual rider steering by
        the state stream (its torques kept in :attr:`rider_torques`)."""
        if not world.virtual_rider:
            return world.rider_profile
        self._receiver = StateReceiver(("127.0.0.1", 0))
        self._sender = StateSender(self._receiver.address)
        virtual = VirtualRider(world, self._receiver, rate=self._rate)

        def rider_now(t: float) -> float:
            torque = virtual(t)
            self.rider_torques.append((self.rig.t, torque))
            return torque

        return rider_now

    def run(self) -> NDArray[np.float64]:
        """Run the scenario's duration (until the runner ends the run), then close the bus
        and the state stream; the rows.

        Returns
        -------
        ndarray, shape (n_periods, n_signals)
            The rows the runner recorded (its ``names``), drained from its ring.
        """
        if not self._links:
            raise MotosimError("this lock-step run has run: build another")
        try:
            RateLoop(self._rate, self.clock).run(self.runner.period, periods=self._periods)
        finally:
            self.close()
        return self.runner.ring.drain()

    def close(self) -> None:
        """Close the bus's two ends and the state stream (once the run has ended)."""
        for link in self._links:
            link.close()
        self._links.clear()
        for end in (self._sender, self._receiver):
            if end is not None:
                end.close()
        self._sender = self._receiver = None
