"""The curves of a motorcycle tyre: side force, longitudinal force and the friction ellipse."""

import numpy as np
from matplotlib.figure import Figure

from motosim.model.tyres import TyreCoefficients, tyre_curves

__all__ = ["plot_tyre"]


def plot_tyre(
    tyre: TyreCoefficients,
    *,
    loads: tuple[float, ...] = (),
    cambers_deg: tuple[float, ...] = (0.0, 15.0, 30.0, 45.0),
    title: str = "",
) -> Figure:
    """Side force against sideslip, longitudinal force against slip, and the friction ellipse.

    Parameters
    ----------
    tyre : TyreCoefficients
        From :func:`motosim.model.tyres.tyre_coefficients` (or the linear tyre).
    loads : tuple of float
        Normal loads [N] of the curves; by default 0.5, 1 and 1.5 times the nominal load.
    cambers_deg : tuple of float
        Cambers [deg] of the side-force curves at the nominal load (and of the ellipse).
    title : str
        Figure title.

    Returns
    -------
    Figure
        Three panels: ``F_y / F_z`` against ``alpha`` at each load (zero camber, solid) and at
        each camber (nominal load, dashed); ``F_x / F_z`` against ``kappa`` at each load; the
        combined ``F_x``, ``F_y`` over ``kappa`` at fixed sideslips, at the nominal load.
    """
    F_z0 = tyre.F_z0
    loads = loads or (0.5 * F_z0, F_z0, 1.5 * F_z0)
    fig = Figure(figsize=(12.0, 4.2), layout="constrained")
    ax_y, ax_x, ax_e = fig.subplots(1, 3)
    alpha = np.radians(np.linspace(-15.0, 15.0, 301))
    for F_z in loads:
        F_y = tyre_curves(tyre, load=F_z, alpha=alpha).F_y
        ax_y.plot(np.degrees(alpha), F_y / F_z, label=f"F_z = {F_z:.0f} N")
    for gamma in cambers_deg:
        if gamma == 0.0:
            continue
        F_y = tyre_curves(tyre, load=F_z0, alpha=alpha, gamma=np.radians(gamma)).F_y
        ax_y.plot(np.degrees(alpha), F_y / F_z0, "--", lw=1, label=f"camber {gamma:g} deg")
    ax_y.set_xlabel("sideslip alpha [deg]")
    ax_y.set_ylabel("F_y / F_z")
    ax_y.legend(fontsize=7)
    kappa = np.linspace(-0.5, 0.5, 501)
    for F_z in loads:
        F_x = tyre_curves(tyre, load=F_z, kappa=kappa).F_x
        ax_x.plot(kappa, F_x / F_z, label=f"F_z = {F_z:.0f} N")
    ax_x.set_xlabel("longitudinal slip kappa")
    ax_x.set_ylabel("F_x / F_z")
    ax_x.legend(fontsize=7)
    kappa = np.linspace(-1.0, 1.0, 801)
    for alpha_deg in (1.0, 2.0, 4.0, 8.0, 15.0):
        forces = tyre_curves(tyre, load=F_z0, kappa=kappa, alpha=np.radians(alpha_deg))
        ax_e.plot(forces.F_y / F_z0, forces.F_x / F_z0, lw=1, label=f"alpha {alpha_deg:g} deg")
    ax_e.set_xlabel("F_y / F_z")
    ax_e.set_ylabel("F_x / F_z")
    ax_e.set_aspect("equal", adjustable="datalim")
    ax_e.legend(fontsize=7)
    for ax in (ax_y, ax_x, ax_e):
        ax.grid(True, alpha=0.3)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.axvline(0.0, color="k", lw=0.6)
    if title:
        fig.suptitle(title)
    return fig
