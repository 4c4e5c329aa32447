"""The modes of the GSX-R1000 (Sharp, Evangelou & Limebeer 2004) on its Magic Formula tyres.

``tyred.lateral_modes`` of ``load_model("sel2004_motorcycle")``: the multibody model on the
MF-MC tyres linearised about upright straight running. The paper's own root loci are of a
machine with frame twist, suspension, a rider's lean freedom and a steering damper that this
four-body set does not have, so its figures are not the reference here (and its modal results
could not be read). What is checked:

* the table is the spectrum of a directly computed lateral matrix, and follows each mode
  continuously over speed;
* the modes are in the ranges the literature gives for motorcycles: weave below 4-5 Hz and
  lightly damped at high speed, wobble at 6-10 Hz ("A Screw-Axis Approach to the Stability of
  Two-Wheeled Vehicles", Appl. Sci. 11(16):7393, 2021, section 1, doi:10.3390/app11167393);
* the wobble is the front frame's oscillation about the steering axis: its frequency is that
  of the front frame alone, the rear frame held, on the relaxing front tyre (the inertia about
  the steering axis as Meijaard et al. 2007, Appendix A, form it; the tyre's cornering
  stiffness at the static load through the normal trail, its lateral relaxation length):
  I s^2 (sigma s / v + 1) + c_n^2 K s / v + c_n K cos(lambda) = 0.
"""

import math

import numpy as np
import pytest

from motosim.model import tyred
from motosim.model.sharp import ModeTable
from motosim.params import load_parameter_set, load_parameters
from motosim.params.multibody import MultibodyParameters

SPEEDS = np.arange(2.0, 60.5, 0.5)


@pytest.fixture(scope="module")
def model() -> tyred.TyredModel:
    return tyred.load_model("sel2004_motorcycle")


@pytest.fixture(scope="module")
def table(model: tyred.TyredModel) -> ModeTable:
    return tyred.lateral_modes(model, SPEEDS)


def test_the_modes_are_eigenvalues_of_the_lateral_matrix(
    model: tyred.TyredModel, table: ModeTable
) -> None:
    for k in (0, 16, 36, 76, 116):  # 2, 10, 20, 40, 60 m/s
        ev = np.linalg.eigvals(tyred.lateral_matrix(model, float(SPEEDS[k])))
        np.testing.assert_allclose(np.sort_complex(table.eigenvalues[k]), np.sort_complex(ev))
        for name in ("capsize", "weave", "wobble"):
            assert np.min(np.abs(ev - table.mode(name)[k])) < 1e-9
    # heading and lateral position are left out: no eigenvalue at zero
    assert np.min(np.abs(table.eigenvalues)) > 0.05


def test_each_mode_is_continuous_in_speed(table: ModeTable) -> None:
    for name in ("weave", "wobble"):
        steps = np.abs(np.diff(table.mode(name)))
        assert np.max(steps) < 2.5  # [1/s] per 0.5 m/s, the eigenvalues spanning about 60 1/s
    # above the weave's low-speed split, the weave stays below the wobble in frequency
    fast = SPEEDS >= 6.0
    assert np.all(table.weave[fast].imag > 0)
    assert np.all(table.weave[fast].imag < table.wobble[fast].imag)


def test_weave_and_wobble_are_in_the_published_ranges(table: ModeTable) -> None:
    road = SPEEDS >= 10.0
    weave_hz = ModeTable.frequency_hz(table.weave[road])
    wobble_hz = ModeTable.frequency_hz(table.wobble[road])
    assert np.all(weave_hz < 5.0)
    assert np.all((wobble_hz > 6.0) & (wobble_hz < 10.0))
    # the weave's frequency rises with speed towards its high-speed value
    assert np.all(np.diff(weave_hz) > 0)
    # lightly damped at high speed, less damped the faster
    zeta = ModeTable.damping_ratio(table.weave)
    high = SPEEDS >= 20.0
    assert np.all(np.diff(zeta[high]) < 0)
    assert zeta[SPEEDS == 60.0][0] < 0.1 < zeta[SPEEDS == 20.0][0]


def _front_frame_hz(
    params: MultibodyParameters, front: tyred.LinearTyre, load: float, v: float
) -> float:
    """The rear frame held: the front frame and wheel on the relaxing front tyre [Hz]."""
    lam, w, c = params.lam, params.w, params.c
    z_F = -(params.r_F + params.t_F)
    m_A = params.m_H + params.m_F
    x_A = (params.m_H * params.x_H + params.m_F * w) / m_A
    z_A = (params.m_H * params.z_H + params.m_F * z_F) / m_A
    # the assembly's inertia about its mass centre (the wheel's about any diameter I_Fxx)
    I_xx = params.I_Hxx + params.I_Fxx + params.m_H * (params.z_H - z_A) ** 2
    I_xx += params.m_F * (z_F - z_A) ** 2
    I_xz = params.I_Hxz - params.m_H * (params.x_H - x_A) * (params.z_H - z_A)
    I_xz -= params.m_F * (w - x_A) * (z_F - z_A)
    I_zz = params.I_Hzz + params.I_Fxx + params.m_H * (params.x_H - x_A) ** 2
    I_zz += params.m_F * (w - x_A) ** 2
    u_A = (x_A - w - c) * math.cos(lam) - z_A * math.sin(lam)
    sl, cl = math.sin(lam), math.cos(lam)
    inertia = m_A * u_A**2 + I_xx * sl**2 + 2 * I_xz * sl * cl + I_zz * cl**2
    c_n = c * cl
    K = front.cornering * load
    sigma = front.relaxation_length
    roots = np.roots([inertia * sigma / v, inertia, c_n**2 * K / v, c_n * K * cl])
    return float(np.max(roots.imag) / (2 * math.pi))


@pytest.mark.parametrize("speed", [16.0, 20.0, 30.0, 40.0, 50.0])
def test_the_wobble_is_the_front_frame_on_its_tyre(table: ModeTable, speed: float) -> None:
    pset = load_parameter_set("sel2004_motorcycle")
    params = pset.values
    assert isinstance(params, MultibodyParameters)
    x_G, _ = params.mass_centre
    load = params.mass * params.g * x_G / params.w
    front = tyred.linearised_tyre(load_parameters(pset.tyres["front_tyre"], "tyre"), load, speed)
    held = _front_frame_hz(params, front, load, speed)
    wobble = ModeTable.frequency_hz(table.wobble[SPEEDS == speed])[0]
    assert 6.0 < held < 7.0
    assert wobble == pytest.approx(held, rel=0.08)
