"""One cueing run over a recorded motorcycle run: motion at the head, algorithm, limits, score.

``vehicle_motion -> washout or MPC -> limit manager -> actuator twin -> platform_motion ->
score``, all at one loop rate (the recorded rate decimated by an integer factor).
"""

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from motosim.cueing.filters import run_section
from motosim.cueing.head import check_rate, platform_motion, vehicle_motion
from motosim.cueing.limits import actuator_response, apply_limits, design_limits
from motosim.cueing.platform import CueingConfig
from motosim.cueing.preview import (
    Road,
    arc_length,
    curve_persistence,
    preview_trust,
    road_preview,
)
from motosim.cueing.vestibular import CueingScore, VestibularModel, perceive, score
from motosim.cueing.washout import WASHOUT_OUTPUTS, apply_washout, design_washout
from motosim.errors import MotosimError
from motosim.params.sharp import SharpParameters
from motosim.timeseries import TimeSeries

__all__ = ["ALGORITHMS", "COMMAND_SIGNALS", "CueingRun", "cue", "decimate"]

ALGORITHMS = ("washout", "mpc")
COMMAND_SIGNALS = WASHOUT_OUTPUTS
"""Columns of :attr:`CueingRun.commands`: platform roll, pitch, yaw and horizon roll."""


@dataclass(frozen=True, slots=True)
class CueingRun:
    """Everything one cueing run produced, at the loop rate.

    Attributes
    ----------
    algorithm : str
        ``"washout"`` or ``"mpc"``.
    vehicle : TimeSeries
        Motion at the head on the motorcycle (:data:`~motosim.cueing.head.HEAD_SIGNALS`).
    commands : TimeSeries
        Limited platform commands and the horizon roll [rad] (:data:`COMMAND_SIGNALS`).
    platform : TimeSeries
        Motion at the head on the platform, from the achieved angles.
    perceived_vehicle, perceived_platform : TimeSeries
        Vestibular outputs (:data:`~motosim.cueing.vestibular.CHANNELS`).
    score : CueingScore
        The comparison.
    """

    algorithm: str
    vehicle: TimeSeries
    commands: TimeSeries
    platform: TimeSeries
    perceived_vehicle: TimeSeries
    perceived_platform: TimeSeries
    score: CueingScore


def decimate(series: TimeSeries, rate: float) -> TimeSeries:
    """Keep every k-th sample so that the rate is ``rate`` [Hz] (k an integer).

    Raises
    ------
    MotosimError
        If ``rate`` is above the series' rate or does not divide it.
    """
    dt = check_rate(series.t)
    ratio = 1.0 / (dt * rate) if rate > 0 else math.nan
    k = round(ratio) if math.isfinite(ratio) else 0
    if k < 1 or abs(ratio - k) > 1e-6 * ratio:
        raise MotosimError(
            f"loop rate {rate:g} Hz; expected an integer divisor of the run's {1 / dt:g} Hz"
        )
    return TimeSeries(series.t[::k].copy(), series.data[::k].copy(), series.names)


def cue(
    config: CueingConfig,
    series: TimeSeries,
    model: VestibularModel,
    *,
    algorithm: Literal["washout", "mpc"] = "washout",
    rate: float | None = None,
    params: SharpParameters | None = None,
    road: Road | None = None,
) -> CueingRun:
    """Cue the platform from a recorded run and score it.

    Parameters
    ----------
    config : CueingConfig
        Platform, rider's head and tunings (:func:`motosim.cueing.platform.load_platform`).
    series : TimeSeries
        The run (signals of :mod:`motosim.signals`) at a constant rate.
    model : VestibularModel
        Vestibular model for the MPC and the score.
    algorithm : {"washout", "mpc"}, optional
        The cueing algorithm; ``"mpc"`` needs the ``cueing`` extra (osqp).
    rate : float, optional
        Loop rate [Hz], an integer divisor of the run's rate; default the run's rate.
    params : SharpParameters, optional
        The motorcycle, for eq. (2) when the run has ``tau_d`` and ``tau_b``.
    road : Road, optional
        The road the run's rider follows: the MPC then plans its roll with the motion
        predicted from the road ahead of the run's position ``x``, ``y``, trusted by the
        lean the road asks for (:mod:`motosim.cueing.preview`); without it the MPC plans
        from the present motion only. Ignored by the washout.

    Returns
    -------
    CueingRun
        Commands, motions, perceptions and score.

    Raises
    ------
    MotosimError
        On an unknown algorithm, a bad rate or missing signals (``x`` and ``y`` with a
        ``road``).
    """
    if algorithm not in ALGORITHMS:
        raise MotosimError(
            f"cueing algorithm {algorithm!r}; expected one of {', '.join(ALGORITHMS)}"
        )
    run = series if rate is None else decimate(series, rate)
    dt = check_rate(run.t)
    vehicle = vehicle_motion(run, config.rider, params=params)
    inputs = np.column_stack([run["phi"], vehicle["theta"], vehicle["a_x"], run["psi_dot"]])
    horizon_gain = config.washout.horizon_gain
    washout = design_washout(config.washout, dt)
    targets = apply_washout(washout, inputs)[:, :3]
    rates = None
    if algorithm == "mpc":  # the washout's commands are the MPC's angle reference
        from motosim.cueing.mpc import COAST_TIMES, apply_mpc, design_mpc

        # the suspension pitch's onset is fed through (the washout's high-passed pitch):
        # [angle fed through, the vehicle's head-frame pitch rate it renders]
        onset = np.zeros((targets.shape[0], 2, 3))
        onset[:, 0, 1] = run_section(np.asarray(washout.pitch_onset), vehicle["theta"])
        onset[:, 1, 1] = vehicle["theta_dot"] * np.cos(run["phi"])
        preview = trust = persistence = None
        if road is not None:
            missing = [name for name in ("x", "y") if name not in run.names]
            if missing:
                raise MotosimError(
                    f"road preview of a run without {' and '.join(missing)}; expected the "
                    "positions of a `motosim simulate` result"
                )
            tuning = config.mpc
            arc = arc_length(road, run["x"], run["y"])
            preview = road_preview(road, arc, run["v_x"], horizon=tuning.horizon, step=tuning.step)
            trust = preview_trust(road, arc, run["v_x"], ahead=tuning.horizon * tuning.step)
            # the horizon and the time its terminal tilt is felt after it, ahead and behind
            window = tuning.horizon * tuning.step + COAST_TIMES[-1]
            persistence = curve_persistence(road, arc, run["v_x"], ahead=window, behind=window)
        targets, rates = apply_mpc(
            design_mpc(config, model, dt), vehicle, targets, onset, preview, trust, persistence
        )
    limited = apply_limits(design_limits(config.platform, dt), targets, rates)
    horizon = horizon_gain * run["phi"] - limited[:, 0]
    commands = TimeSeries(run.t, np.column_stack([limited, horizon]), COMMAND_SIGNALS)
    achieved = actuator_response(config.platform, dt, limited)
    motion = platform_motion(run.t, achieved[:, 0], achieved[:, 1], achieved[:, 2], config.platform)
    result = score(model, vehicle, motion, config.platform, limited)
    return CueingRun(
        algorithm=algorithm,
        vehicle=vehicle,
        commands=commands,
        platform=motion,
        perceived_vehicle=perceive(model, vehicle),
        perceived_platform=perceive(model, motion),
        score=result,
    )
