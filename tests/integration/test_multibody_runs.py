"""The multibody motorcycle in the closed loop: the stack steps the model it was given, the
result columns obey the mechanics of braking, the training scenarios meet issue 32's
targets, and a run that falls says why.

References: the load transfer of a braking motorcycle, Delta F_z = m a h / w (Cossalter,
*Motorcycle Dynamics*, 2nd ed., 2006, sec. 5.1, "Braking": the longitudinal forces at the
ground times the mass centre's height balanced by the change of the normal loads over the
wheelbase), with the wheels' angular momentum, slowing with the machine, adding
(I_R / r_R + I_F / r_F) a to the pitching moment (Euler's law for the whole machine about
its mass centre); Newton's second law for the whole machine, m dv/dt = F_xr + F_xf with no
drag.
"""

import math
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest

from motosim.cli.main import main
from motosim.errors import MotosimError
from motosim.io.runs import load_scenario, resolve
from motosim.model import tyred
from motosim.params import load_parameters
from motosim.sim import closed_loop
from motosim.sim.grips import GRIPS, design_hands
from motosim.sim.scenario import ConstantProfile, Scenario, StepsProfile, parse_scenario
from motosim.timeseries import TimeSeries

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"

RIDER = '\n[rider]\nkind = "virtual"\n'

BRAKING = """
[scenario]
name = "braking"
duration = 3.0

[motorcycle]
model = "multibody"
params = "sel2004_motorcycle"
speed = 25.0
front_brake_torque = { kind = "steps", times = [0.5, 0.6, 0.7], values = [100.0, 200.0, 300.0] }
rear_brake_torque = { kind = "steps", times = [0.5, 0.6, 0.7], values = [30.0, 60.0, 100.0] }

[rider]
kind = "virtual"
path = { kind = "straight" }
"""


def _scenario(text: str) -> Scenario:
    return parse_scenario(tomllib.loads(text), origin="test")


def _run(text: str) -> TimeSeries:
    return closed_loop.simulate(resolve(_scenario(text), "."), rng=np.random.default_rng(0))


def _resolved(path: Path) -> closed_loop.RunInputs:
    return resolve(load_scenario(path), path.parent)


def _read(folder: Path) -> dict[str, np.ndarray]:
    """The signals of a result, read by h5py."""
    with h5py.File(folder / "result.h5", "r") as f:
        names = [
            str(n.decode() if isinstance(n, bytes) else n) for n in f["signals"].attrs["names"]
        ]
        table = np.asarray(f["signals"])
    return {name: table[:, j] for j, name in enumerate(names)}


@pytest.mark.parametrize("grip", ["off", "relaxed"])
def test_the_stack_steps_the_multibody_model_it_was_given(grip: str) -> None:
    """A run driven by the rider's true torque is the tyred model stepped by hand with that
    torque held over each 1 ms period (one RK4 step each), to rounding. With hands, the
    torque is the arms' too and the front frame carries the share of their inertia and
    damping the stack is designed for (tyred.held of grips.design_hands)."""
    text = f"""
[scenario]
name = "true"
duration = 1.5
[motorcycle]
model = "multibody"
params = "sel2004_motorcycle"
speed = 20.0
input = "true"
[rider]
profile = {{ kind = "steps", times = [0.2, 0.4], values = [8.0, 0.0] }}
hands = "{grip}"
[controller]
kind = "none"
"""
    run = _run(text)
    model = tyred.load_model("sel2004_motorcycle", speed=20.0)
    arms = design_hands(GRIPS[grip])
    if arms is not None:
        model = tyred.held(model, arms.inertia, arms.damping)
    state = tyred.upright_state(model, 20.0)
    roll, steer = [], []
    for torque in run["tau_r"]:
        roll.append(state.roll)
        steer.append(state.steer)
        state = tyred.step(model, state, tyred.Inputs(steer_torque=torque), 1e-3)
    np.testing.assert_allclose(run["phi"], roll, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run["delta"], steer, rtol=0, atol=1e-12)
    pulse = (run.t >= 0.2) & (run.t < 0.4)
    assert np.allclose(run["tau_r_active"], np.where(pulse, 8.0, 0.0))
    assert np.max(np.abs(run["phi"])) > 0.02  # the pulse did lean it


def test_braking_loads_obey_newton_and_the_load_transfer() -> None:
    """Steady braking: the tyres' longitudinal forces decelerate the machine's mass, and the
    normal loads change by m a h / w (Cossalter 2006, sec. 5.1)."""
    run = _run(BRAKING)
    params = load_parameters("sel2004_motorcycle", "multibody")
    m, g = params.mass, params.g
    x_G, z_G = params.mass_centre
    steady = (run.t > 1.5) & (run.t < 2.8)
    a = -np.polyfit(run.t[steady], run["v_x"][steady], 1)[0]
    force = -(run["F_xr"] + run["F_xf"])[steady].mean()
    assert a > 4.0  # about half a g
    assert force == pytest.approx(m * a, rel=1e-3)
    weight = (run["F_zr"] + run["F_zf"])[steady].mean()
    assert weight == pytest.approx(m * g, rel=0.005)
    front_static = m * g * x_G / params.w
    transfer = run["F_zf"][steady].mean() - front_static
    # the mass centre's m a h, and the wheels' spin slowing: (I_R / r_R + I_F / r_F) a
    spin = (params.I_Ryy / params.r_R + params.I_Fyy / params.r_F) * a
    assert transfer == pytest.approx((m * a * -z_G + spin) / params.w, rel=0.02)
    assert run["theta"][steady].mean() < 0.0  # nose down
    assert np.all(run["kappa_f"][steady] < 0.0) and np.all(run["kappa_r"][steady] < 0.0)


def test_sharp_runs_record_constant_loads_and_no_slip() -> None:
    """Sharp 1971's normal loads are its constant ones (Z_f in front), its tyres slip not."""
    sharp = load_parameters("sharp1971", "sharp")
    run = closed_loop.simulate(
        _resolved(SCENARIOS / "emergency_braking.toml"), rng=np.random.default_rng(0)
    )
    np.testing.assert_allclose(run["F_zf"], -sharp.Z_f)
    np.testing.assert_allclose(run["F_zr"] + run["F_zf"], (sharp.m_f + sharp.m_r) * sharp.g)
    for name in ("kappa_r", "kappa_f", "alpha_r", "alpha_f", "theta", "F_xf"):
        assert np.all(run[name] == 0.0), name
    assert run["F_xr"].min() < -1000.0  # eq. (2)'s braking force at the rear


def test_limit_braking_reaches_the_road_friction(tmp_path: Path) -> None:
    """Issue 32's target: the virtual rider brakes at >= 0.85 of the road's friction without
    a fall, its brake controller keeping the rear wheel down."""
    assert (
        main(
            [
                "simulate",
                str(SCENARIOS / "limit_braking.toml"),
                "--out",
                str(tmp_path),
                "--no-report",
            ]
        )
        == 0
    )
    s = _read(tmp_path)
    t = s["t"]
    braking = (t > 1.3) & (t < 3.3)
    a = -np.polyfit(t[braking], s["v_x"][braking], 1)[0]
    assert a >= 0.85 * 1.0 * 9.81
    assert s["F_zr"][braking].min() > 0.0
    assert np.max(np.abs(s["phi"])) < math.radians(2.0)
    held = (t > 1.6) & (t < 3.3)  # the slip target, -0.1, held down to 4 m/s
    for column in ("kappa_f", "kappa_r"):
        assert np.all(np.abs(s[column][held] + 0.1) < 0.01), column


def test_lean_45_holds_its_path(tmp_path: Path) -> None:
    """Issue 32's target: the virtual rider rides the 45 deg lean turn within 0.5 m RMS."""
    assert (
        main(["simulate", str(SCENARIOS / "lean_45.toml"), "--out", str(tmp_path), "--no-report"])
        == 0
    )
    s = _read(tmp_path)
    steady = (s["t"] > 4.5) & (s["t"] < 8.5)
    assert np.degrees(np.abs(s["phi"][steady])).mean() == pytest.approx(45.0, abs=1.0)
    assert np.sqrt(np.mean(s["e_y"] ** 2)) <= 0.5
    assert np.sqrt(np.mean(s["e_y"][steady] ** 2)) <= 0.05


def test_a_locked_front_wheel_ends_in_a_fall_named_with_its_times(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        [
            "simulate",
            str(SCENARIOS / "front_wheel_lock.toml"),
            "--out",
            str(tmp_path),
            "--no-report",
        ]
    )
    err = capsys.readouterr().err
    assert code == 3
    locked = float(err.split("the front wheel locked at t = ")[1].split(" s")[0])
    fell = float(err.split("the motorcycle fell at t = ")[1].split(" s")[0])
    assert 3.2 < locked < fell < locked + 0.3 and "tucked under" in err
    assert len([line for line in err.splitlines() if "run failed" in line]) == 1
    s = _read(tmp_path)  # the rows up to the fall are kept
    assert s["t"][-1] == pytest.approx(fell, abs=0.002)
    assert s["kappa_f"][-200:].min() <= -0.9


def test_the_low_friction_patch_and_the_limit_swerve_stay_up() -> None:
    for name in ("low_friction_patch", "limit_swerve"):
        run = closed_loop.simulate(
            _resolved(SCENARIOS / f"{name}.toml"), rng=np.random.default_rng(0)
        )
        assert run.t[-1] == pytest.approx(load_scenario(SCENARIOS / f"{name}.toml").duration - 1e-3)
    # the swerve uses all the front tyre's friction at its peak
    run = closed_loop.simulate(
        _resolved(SCENARIOS / "limit_swerve.toml"), rng=np.random.default_rng(0)
    )
    assert np.max(np.abs(run["F_yf"]) / run["F_zf"]) == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        (
            '[motorcycle]\nmodel = "multibody"\nbrake_torque = 100.0\n',
            "brake_torque does not act on model = 'multibody'",
        ),
        (
            "[motorcycle]\nfront_brake_torque = 100.0\n",
            "front_brake_torque does not act on model = 'sharp1971'",
        ),
        ("[road]\nfriction = 0.5\n", "[road] friction acts on the multibody"),
        ('[motorcycle]\nmodel = "multibody"\n[road]\nfriction = 0.0\n', "friction reaches 0"),
        (
            '[motorcycle]\nmodel = "multibody"\n[road]\n'
            'friction = { kind = "steps", times = [1.0], values = [0.5] }\n',
            "first at t = 0",
        ),
        ('[motorcycle]\nmodel = "multibody"\nside_wind = 100.0\n', "no wind yet"),
        ('[rider]\nkind = "virtual"\nbrake_slip = 0.7\n', "brake_slip"),
        ('[motorcycle]\nmodel = "bikesim"\n', "model"),
    ],
)
def test_bad_multibody_keys_are_one_line_errors(table: str, message: str) -> None:
    with pytest.raises(MotosimError, match=message.replace("[", r"\[")) as err:
        _scenario(
            '[scenario]\nname = "x"\nduration = 1.0\n' + table + RIDER * ("[rider]" not in table)
        )
    assert "\n" not in str(err.value)


def test_profiles_of_the_multibody_keys() -> None:
    sc = _scenario(
        '[scenario]\nname = "x"\n[motorcycle]\nmodel = "multibody"\n'
        "front_brake_torque = 200.0\n[road]\n"
        'friction = { kind = "steps", times = [0.0, 2.0], values = [1.0, 0.3] }\n' + RIDER
    )
    assert sc.motorcycle.front_brake_torque == ConstantProfile(200.0)
    assert sc.road.friction == StepsProfile((0.0, 2.0), (1.0, 0.3))


REALTIME = """
[scenario]
name = "mb_rt"
duration = 2.0
[rates]
plant = 10000.0
[motorcycle]
model = "multibody"
params = "sel2004_motorcycle"
[rider]
profile = { kind = "square", low = -5.0, high = 5.0, period = 1.0, start = 0.2 }
[controller]
kind = "paper"
"""


def test_the_real_time_loop_steps_the_multibody_motorcycle_as_offline() -> None:
    """The same compiled step in the real-time loop (lock-step over python-can's virtual bus)
    as offline: the steer angle within 1e-3 rad (the bus rounds the angle and current)."""
    pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
    pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")
    from motosim.rt.lockstep import Lockstep, free_limits

    inputs = resolve(_scenario(REALTIME), ".")
    offline = closed_loop.simulate(inputs, rng=np.random.default_rng(0))
    lock = Lockstep(inputs, free_limits(1000.0), channel="rt_multibody")
    rows = lock.run()
    col = {name: j for j, name in enumerate(lock.runner.names)}
    assert rows.shape[0] == offline.t.size and lock.runner.counters().fault == "NONE"
    assert np.max(np.abs(offline["delta"])) > 1e-3
    assert np.max(np.abs(rows[:, col["delta"]] - offline["delta"])) < 1e-3


def test_real_time_refuses_what_it_does_not_read_of_the_multibody(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "braking.toml"
    safety = (SCENARIOS / "realtime_square.toml").read_text().split("[realtime.safety]")[1]
    path.write_text(BRAKING + "\n[realtime.safety]" + safety)
    code = main(["run", str(path), "--bus", "virtual:x", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "front_brake_torque on the multibody motorcycle is read offline" in err
    assert err.count("\n") == 1


def test_a_campaign_on_the_multibody_motorcycle_names_its_falls(tmp_path: Path) -> None:
    """The front brake grabbed in a wet bend (front_wheel_lock) with and without the rider's
    brake controller: with it the wheel holds and the rider rides on, without it the wheel
    locks and the front tucks under; the campaign records that run as a failure with the
    reason `motosim simulate` gives."""
    from motosim.campaign import load_campaign, load_results, run_campaign

    (tmp_path / "lock.toml").write_text((SCENARIOS / "front_wheel_lock.toml").read_text())
    (tmp_path / "c.toml").write_text(
        '[campaign]\nname = "lock"\nscenario = "lock.toml"\nsampling = "grid"\nruns = 2\n'
        'metrics = ["max_abs_phi"]\n[factors]\n"rider.brake_control" = [true, false]\n'
    )
    summary = run_campaign(load_campaign(tmp_path / "c.toml"), tmp_path / "out", jobs=1)
    results = load_results(tmp_path / "out")
    grabbed = ~results["rider.brake_control"].astype(bool)
    assert summary.failed == 1 and set(results["status"][grabbed]) == {"failed"}
    (reason,) = results["reason"][grabbed]
    assert reason.startswith("the front wheel locked at t = 3.358 s") and "tucked under" in reason
    assert set(results["status"][~grabbed]) == {"ok"}
