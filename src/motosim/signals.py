"""Glossary of signal and parameter names, their meaning and their SI unit.

Every CSV column, result field and plot label uses these names. New signals are added here
first. Units are SI with angles in radians.
"""

from typing import Final, NamedTuple

__all__ = ["RECORDED", "SIGNALS", "Signal", "unit_of"]


class Signal(NamedTuple):
    """One named signal: its description and SI unit."""

    description: str
    unit: str


SIGNALS: Final[dict[str, Signal]] = {
    "t": Signal("time", "s"),
    # handlebar
    "tau_r": Signal("rider torque on the handlebar", "N*m"),
    "tau_r_active": Signal(
        "rider's active torque on the handlebar: tau_r without the arms' passive torque", "N*m"
    ),
    "tau_r_hat": Signal("estimated rider torque", "N*m"),
    "tau_r_meas": Signal("rider torque measured by a torque sensor at the grips", "N*m"),
    "tau_p": Signal("dry-friction torque on the handlebar axis", "N*m"),
    "tau_m": Signal("motor torque at the handlebar, N k_t i_m", "N*m"),
    "theta_h": Signal("handlebar angle", "rad"),
    "theta_h_dot": Signal("handlebar rate", "rad/s"),
    "theta_h_dot_hat": Signal("differentiated handlebar rate", "rad/s"),
    "theta_h_meas": Signal("measured handlebar angle (sampled, quantised)", "rad"),
    "i_m": Signal("motor current", "A"),
    "u": Signal("motor voltage", "V"),
    # virtual motorcycle (Sharp 1971, the paper's state order) and eq. (2)
    "v_x": Signal("forward speed", "m/s"),
    "v_y": Signal("lateral velocity of the rear-frame ground point", "m/s"),
    "psi_dot": Signal("yaw rate", "rad/s"),
    "phi_dot": Signal("roll rate", "rad/s"),
    "delta_dot": Signal("steer rate", "rad/s"),
    "phi": Signal("roll angle, right side down positive", "rad"),
    "delta": Signal("steer angle, the controller's reference", "rad"),
    "F_yr": Signal("rear tyre side force", "N"),
    "F_yf": Signal("front tyre side force", "N"),
    # the multibody motorcycle's tyres (Sharp 1971: its constant loads, no slips)
    "F_xr": Signal("rear tyre longitudinal force, along the wheel's heading (< 0 braking)", "N"),
    "F_xf": Signal("front tyre longitudinal force, along the wheel's heading (< 0 braking)", "N"),
    "F_zr": Signal("rear tyre normal load", "N"),
    "F_zf": Signal("front tyre normal load", "N"),
    "kappa_r": Signal("rear tyre longitudinal slip (< 0 braking, -1 locked)", "1"),
    "kappa_f": Signal("front tyre longitudinal slip (< 0 braking, -1 locked)", "1"),
    "alpha_r": Signal("rear tyre sideslip angle", "rad"),
    "alpha_f": Signal("front tyre sideslip angle", "rad"),
    "psi": Signal("yaw angle", "rad"),
    "x": Signal("position east of the start (ground frame x)", "m"),
    "y": Signal("position (ground frame y, right of the start heading)", "m"),
    "tau_d": Signal("drive torque at the rear wheel", "N*m"),
    "tau_b": Signal("brake torque", "N*m"),
    "F_wx": Signal("longitudinal wind force", "N"),
    "e_y": Signal("virtual rider's lateral error from its path, right positive", "m"),
    # motion at the rider's head and the platform (motosim.cueing)
    "a_x": Signal(
        "longitudinal acceleration of the rear contact point, v_x' - v_y psi_dot", "m/s^2"
    ),
    "a_y": Signal("lateral acceleration of the rear contact point, v_y' + v_x psi_dot", "m/s^2"),
    "theta": Signal("pitch angle (motorcycle suspension, or platform), nose up positive", "rad"),
    "theta_dot": Signal("pitch rate, nose up positive", "rad/s"),
    "omega_x": Signal("angular velocity of the rider's head about its x axis (roll)", "rad/s"),
    "omega_y": Signal("angular velocity of the rider's head about its y axis (pitch)", "rad/s"),
    "omega_z": Signal("angular velocity of the rider's head about its z axis (yaw)", "rad/s"),
    "f_x": Signal("specific force at the rider's head along its x axis (forward)", "m/s^2"),
    "f_y": Signal("specific force at the rider's head along its y axis (right)", "m/s^2"),
    "f_z": Signal(
        "specific force at the rider's head along its z axis (down); -g at rest", "m/s^2"
    ),
    "phi_s": Signal("platform roll command, right side down positive", "rad"),
    "theta_s": Signal("platform pitch command, nose up positive", "rad"),
    "psi_s": Signal("platform yaw command, nose right positive", "rad"),
    "phi_vis": Signal(
        "roll of the visual horizon on the screen (which rolls with the platform)", "rad"
    ),
}


RECORDED: Final[tuple[str, ...]] = (
    "t",
    "tau_r",
    "tau_r_active",
    "tau_r_hat",
    "tau_p",
    "theta_h",
    "theta_h_dot",
    "theta_h_meas",
    "theta_h_dot_hat",
    "i_m",
    "tau_m",
    "delta",
    "v_x",
    "v_y",
    "psi_dot",
    "phi_dot",
    "delta_dot",
    "phi",
    "F_yr",
    "F_yf",
    "psi",
    "x",
    "y",
    "e_y",
    "F_xr",
    "F_xf",
    "F_zr",
    "F_zf",
    "kappa_r",
    "kappa_f",
    "alpha_r",
    "alpha_f",
    "theta",
)
"""The signals a closed-loop run records, in column order (each one is in :data:`SIGNALS`).

The simulator's output row, the result files' columns and the plots follow this tuple:
adding a recorded signal is one entry here (and in :data:`SIGNALS`) plus the code that
computes it."""


def unit_of(name: str) -> str:
    """Return the SI unit of a signal.

    Parameters
    ----------
    name : str
        Signal name from :data:`SIGNALS`.

    Returns
    -------
    str
        The unit, for example ``"rad/s"``.

    Raises
    ------
    KeyError
        If the name is not in the glossary.
    """
    return SIGNALS[name].unit
