"""The closed loop of Fig. 7: the compiled loop, the same loop in plain Python and with
SciPy's integrator, python-control, and the feedforward's cost.

The loop: square rider torque, SIMACOM handlebar with dry friction (exact stick-slip), a
14-bit encoder, Walcott-Zak observer, first-order H-infinity controller, Sharp motorcycle at
20 m/s, 1 kHz. Every figure is a rate in stack periods per second of wall time and of CPU
time (``time.thread_time`` in this process, ``time.process_time`` in a subprocess), with the
load average; which computation each one times:

1. the compiled loop alone (``chunk_loop``'s: the rider, the encoder, the stack's step, the
   true handlebar's exact step, the row), the stack designed and the rig built beforehand;
   the rider a pure torque source (``hands = "off"``, as in the baselines below), and
   again holding the handlebar with the relaxed grip (the arms' impedance in the plant and
   the stack designed for it);
2. the whole ``simulate()`` call (the rig built, the loop, the blocks checked);
3. the same loop alone, the same code with ``NUMBA_DISABLE_JIT=1`` (plain Python and NumPy),
   in a subprocess;
4. the same sampled, quantised loop with the true handlebar integrated between samples by
   ``scipy.integrate.solve_ivp`` (RK45, the stick-slip by a terminal event at zero rate and a
   stick test, as the exact step does) and the stack's compiled step called from Python each
   period: a like-for-like baseline, the integrator apart;
5. python-control's ``input_output_response`` on a *different*, simpler loop written in its
   idiom (continuous time, tanh friction, no encoder, no differentiator, the controller
   continuous, no feedforward, adaptive RK45 with an output every millisecond), as
   interconnected blocks and as one hand-written ``nlsys``: it compares idioms, not the
   same computation;
6. the stack step's slowdown from the observer's stick projection and from the feedforward.

The campaign's figures are measured on the ``motosim campaign`` command itself
(``bench/bench_campaign.py``), the whole ``motosim simulate`` command by
``bench/bench_time_to_result.py``.
"""

import math
import os
import subprocess
import sys
import time
import tomllib
from collections.abc import Callable

import numpy as np
from numba import njit

from motosim.control.torque_feedback import design_torque_feedback
from motosim.params import load_parameters
from motosim.sim import build_stack, parse_scenario, prepare, simulate
from motosim.sim.closed_loop import _UNREFERENCED
from motosim.sim.stack import NO_PREDICTION, StackModel, new_data, reset, step

SCENARIO = """
[scenario]
name = "bench"
duration = {duration}
[rider]
kind = "torque"
profile = {{ kind = "square", low = -10.0, high = 10.0, period = 2.0 }}
hands = "{hands}"
"""


def _inputs(  # type: ignore[no-untyped-def]
    duration: float, inertia: float = 1.0, damping: float = 1.0, hands: str = "off"
):
    hb = load_parameters("simacom_handlebar", "handlebar")
    text = SCENARIO.format(duration=duration, hands=hands)
    sc = parse_scenario(tomllib.loads(text), origin="bench")
    ctrl = _controller()
    import dataclasses

    sc = dataclasses.replace(
        sc,
        handlebar=dataclasses.replace(sc.handlebar, inertia_factor=inertia, damping_factor=damping),
    )
    return prepare(
        sc,
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=ctrl,
    )


_CTRL = None


def _controller():  # type: ignore[no-untyped-def]
    global _CTRL
    if _CTRL is None:
        hb = load_parameters("simacom_handlebar", "handlebar")
        _CTRL = design_torque_feedback(hb, rng=np.random.default_rng(0), n_starts=2).controller
    return _CTRL


def _loop_alone(duration: float, hands: str = "off") -> tuple[float, float]:
    """(periods/s of wall time, of thread CPU time) of the loop alone, best of three; the
    rider's ``hands`` a grip of :data:`motosim.sim.grips.GRIPS`."""
    from motosim.signals import RECORDED
    from motosim.sim.closed_loop import (
        NO_STOP,
        _ensure_current_layout,
        build_rig,
        chunk_loop,
        new_world,
    )

    inputs = _inputs(duration, hands=hands)
    model = build_stack(inputs)
    _ensure_current_layout()
    loop = chunk_loop(model)
    best = (0.0, 0.0)
    for _ in range(1 if os.environ.get("NUMBA_DISABLE_JIT") == "1" else 4):  # the first compiles
        rig = build_rig(inputs, rng=np.random.default_rng(0))
        data = new_data(model)
        reset(model, data, 0.0, 0.0)
        world = new_world(inputs.scenario)
        n = rig.current_noise.size
        out = np.full((n, len(RECORDED)), np.nan)
        wall, cpu = time.perf_counter(), time.thread_time()
        done = loop(0, out, model, data, rig, world, NO_STOP)  # < n: left the domain
        rate = (done / (time.perf_counter() - wall), done / (time.thread_time() - cpu))
        best = max(best, rate)
    return best


def _whole_simulate(duration: float) -> tuple[float, float]:
    """(periods/s of wall time, of thread CPU time) of a whole ``simulate()``, best of three."""
    inputs = _inputs(duration)
    stack = build_stack(inputs)
    simulate(inputs, rng=np.random.default_rng(0), stack=stack, keep=False)
    best = (0.0, 0.0)
    n = round(duration * 1000.0)
    for _ in range(3):
        wall, cpu = time.perf_counter(), time.thread_time()
        simulate(inputs, rng=np.random.default_rng(0), stack=stack, keep=False, chunk=duration)
        best = max(best, (n / (time.perf_counter() - wall), n / (time.thread_time() - cpu)))
    return best


def _plain_python(duration: float) -> tuple[float, float]:
    """The loop alone with the JIT off, in a subprocess: (periods/s wall, CPU)."""
    code = (
        "import sys; sys.path.insert(0, 'bench'); from bench_closed_loop import _loop_alone;"
        f"print(*_loop_alone({duration}))"
    )
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    wall, cpu = out.stdout.strip().splitlines()[-1].split()
    return float(wall), float(cpu)


def _solve_ivp_loop(duration: float) -> tuple[float, float]:
    """The sampled, quantised loop with the handlebar by ``solve_ivp``: (periods/s wall, CPU)."""
    from scipy.integrate import solve_ivp

    from motosim.sim.closed_loop import build_rig

    inputs = _inputs(duration)
    model = build_stack(inputs)
    rig = build_rig(inputs, rng=np.random.default_rng(0))
    data = new_data(model)
    reset(model, data, 0.0, 0.0)
    step(model, data, 0.0, 0.0, 0.0, 0.0, 0.0)  # compiled before the clock starts
    reset(model, data, 0.0, 0.0)
    J, beta, beta_s, nkt = (float(v) for v in rig.handlebar)
    q, h, n_sub = rig.quantum, model.dt, rig.plant_substeps

    def period(theta: float, omega: float, torque: float, t0: float, t1: float) -> list[float]:
        while t0 < t1:
            if omega == 0.0:
                if abs(torque) <= beta_s:
                    return [theta, 0.0]  # stuck for the rest of the period (torque held)
                s = 1.0 if torque > 0.0 else -1.0
            else:
                s = 1.0 if omega > 0.0 else -1.0

            def rhs(t: float, y: np.ndarray, s: float = s) -> list[float]:
                return [y[1], (torque - beta * y[1] - beta_s * s) / J]

            def stops(t: float, y: np.ndarray) -> float:
                return float(y[1])

            stops.terminal = True  # type: ignore[attr-defined]
            stops.direction = -s  # type: ignore[attr-defined]
            sol = solve_ivp(rhs, (t0, t1), [theta, omega], events=stops, rtol=1e-8, atol=1e-10)
            if sol.status == 1:
                theta, omega, t0 = float(sol.y_events[0][0][0]), 0.0, float(sol.t_events[0][0])
            else:
                return [float(sol.y[0, -1]), float(sol.y[1, -1])]
        return [theta, omega]

    n = round(duration / h)
    theta, omega = 0.0, 0.0
    wall, cpu = time.perf_counter(), time.thread_time()
    for k in range(n):
        meas = math.floor(theta / q + 0.5) * q if q > 0.0 else theta
        tau_r = float(rig.rider_profile[k * n_sub])
        i_cmd = step(
            model, data, meas, rig.current_noise[k], tau_r, rig.force[k], rig.side_force[k]
        )
        theta, omega = period(theta, omega, tau_r + nkt * i_cmd, k * h, (k + 1) * h)
    return n / (time.perf_counter() - wall), n / (time.thread_time() - cpu)


def _python_control(duration: float, *, blocks: bool) -> float:
    """Samples per second of python-control on the loop: one nlsys, or interconnected blocks."""
    import control as ct

    from motosim.estimation.walcott_zak import design
    from motosim.model import sharp as sm
    from motosim.params import derived_geometry

    hb = load_parameters("simacom_handlebar", "handlebar")
    p = load_parameters("sharp1971", "sharp")
    g = design(hb)
    K = _controller()
    A0, A1, Bv = sm.lpv_matrices(p)
    d = derived_geometry(p)
    nk = K.A.shape[0]

    def handlebar(t, x, u, params):  # type: ignore[no-untyped-def]
        tau_r, i_m = u[0], float(np.clip(u[1], -30, 30))
        friction = -hb.beta_s * np.tanh(x[1] / 0.05)
        return [x[1], (tau_r + hb.torque_per_amp * i_m - hb.beta_eq * x[1] + friction) / hb.J_eq]

    def observer(t, x, u, params):  # type: ignore[no-untyped-def]
        y, i_m = np.array([u[0], u[1]]), float(np.clip(u[2], -30, 30))
        s = float(g.F @ (y - g.C @ x[:2]))
        E = g.eta * s / (abs(s) + g.epsilon)
        friction = -hb.beta_s * np.tanh(u[1] / 0.05)
        dx = (g.A - g.L @ g.C) @ x[:2] + g.B * i_m + g.L @ y + g.D * (friction + E)
        return np.concatenate([dx, [(E - x[2]) / 0.01]])

    def bike(t, z, u, params):  # type: ignore[no-untyped-def]
        v = z[8]
        dz = np.empty(12)
        dz[:8] = A0 @ z[:8] + v * (A1 @ z[:8]) + Bv * u[0]
        dz[8] = (d["m"] * z[1] * z[0]) / d["m_eq"]
        dz[9] = z[1]
        dz[10] = v * np.cos(z[9]) - z[0] * np.sin(z[9])
        dz[11] = v * np.sin(z[9]) + z[0] * np.cos(z[9])
        return dz

    t = np.arange(0.0, duration, 1e-3)
    tau = np.where((t % 2.0) < 1.0, 10.0, -10.0)
    if blocks:
        plant = ct.nlsys(
            handlebar,
            lambda t, x, u, p: x,
            name="handlebar",
            inputs=["tau_r", "i_m"],
            outputs=["theta", "omega"],
            states=2,
        )
        est = ct.nlsys(
            observer,
            lambda t, x, u, p: [x[2]],
            name="observer",
            inputs=["theta", "omega", "i_m"],
            outputs=["tau_hat"],
            states=3,
        )
        moto = ct.nlsys(
            bike,
            lambda t, z, u, p: [z[5]],
            name="bike",
            inputs=["tau_hat"],
            outputs=["delta"],
            states=12,
        )
        err = ct.summing_junction(inputs=["theta", "-delta"], output="e", name="error")
        ctrl = ct.ss(K.A, K.B, K.C, K.D, inputs="e", outputs="i_m", name="controller")
        loop = ct.interconnect(
            [plant, est, moto, err, ctrl], inputs="tau_r", outputs=["theta", "delta", "tau_hat"]
        )
        x0 = np.zeros(loop.nstates)
        x0[list(loop.state_labels).index("bike_x[8]")] = 20.0
    else:

        def update(t, x, u, params):  # type: ignore[no-untyped-def]
            xk, xo, z = x[2 : 2 + nk], x[2 + nk : 5 + nk], x[5 + nk :]
            e = x[0] - z[5]
            i_m = (K.C @ xk)[0] + K.D[0, 0] * e
            return np.concatenate(
                [
                    handlebar(t, x[:2], [u[0], i_m], None),
                    K.A @ xk + K.B[:, 0] * e,
                    observer(t, xo, [x[0], x[1], i_m], None),
                    bike(t, z, [xo[2]], None),
                ]
            )

        n = 2 + nk + 3 + 12
        loop = ct.nlsys(update, None, inputs=1, states=n, outputs=n)
        x0 = np.zeros(n)
        x0[-4] = 20.0
    start = time.perf_counter()
    ct.input_output_response(loop, t, tau, x0, t_eval=t, solve_ivp_method="RK45")
    return t.size / (time.perf_counter() - start)


@njit(cache=True, **_UNREFERENCED)
def _drive_stack(model, data, theta, torque):  # type: ignore[no-untyped-def]
    """The stack step alone, fed a recorded angle and rider torque; returns a checksum."""
    total = 0.0
    for k in range(theta.size):
        total += step(model, data, theta[k], 0.0, torque[k], 0.0, 0.0)
    return total


def _ratio(
    duration: float, variant: Callable[[StackModel], StackModel], repeats: int = 7
) -> tuple[float, float]:
    """Time of the default stack's step over that of ``variant(stack)``, and the default
    step's time [s per period of wall time].

    The step alone (no plant: the handlebar's stick-slip would make the two runs' worlds
    differ), fed the angle and rider torque of one recorded run, interleaved so that the
    machine's load falls on both alike; best of ``repeats`` each.
    """
    inputs = _inputs(duration)
    recorded = simulate(inputs, rng=np.random.default_rng(0))
    theta = np.ascontiguousarray(recorded["theta_h_meas"])
    torque = np.ascontiguousarray(recorded["tau_r"])
    on = build_stack(inputs)
    off = variant(on)
    best = {"on": float("inf"), "off": float("inf")}
    for _ in range(repeats):
        for name, model in (("on", on), ("off", off)):
            data = new_data(model)
            reset(model, data, 0.0, 0.0)
            start = time.perf_counter()
            _drive_stack(model, data, theta, torque)
            best[name] = min(best[name], time.perf_counter() - start)
    return best["on"] / best["off"], best["on"] / theta.size


def _without_projection(model: StackModel) -> StackModel:
    """The stack with the observer's stick projection off."""
    settings = model.estimator.walcott_zak._replace(stick_projection=False)
    return model._replace(estimator=model.estimator._replace(walcott_zak=settings))


def _without_feedforward(model: StackModel) -> StackModel:
    """The stack with neither feedforward term (rider-torque cancellation, predicted or not,
    reference inverse dynamics): the step skips their code, as it did before they existed."""
    ff = model.feedforward._replace(cancellation=0.0, reference=0.0)
    return model._replace(feedforward=ff, prediction=NO_PREDICTION)


def run() -> dict[str, float]:
    """Periods per second of each (wall and CPU time), the ratios, the feedforward's cost."""
    load = os.getloadavg()[0]
    projection, step_alone = _ratio(20.0, _without_projection)
    feedforward, _ = _ratio(20.0, _without_feedforward)
    loop_wall, loop_cpu = _loop_alone(60.0)
    _, held_cpu = _loop_alone(60.0, hands="relaxed")
    whole_wall, whole_cpu = _whole_simulate(60.0)
    plain_wall, plain_cpu = _plain_python(0.5)
    ivp_wall, ivp_cpu = _solve_ivp_loop(0.5)
    blocks = _python_control(0.5, blocks=True)
    single = _python_control(0.5, blocks=False)
    return {
        "load average (1 min) before": load,
        "compiled loop alone [periods/s of CPU]": loop_cpu,
        "compiled loop alone [periods/s of wall time]": loop_wall,
        "compiled loop alone, the relaxed grip [periods/s of CPU]": held_cpu,
        "compiled loop, the relaxed grip / no hands (CPU time of a run)": loop_cpu / held_cpu,
        "whole simulate() (rig built, loop, checks) [periods/s of CPU]": whole_cpu,
        "whole simulate() [periods/s of wall time]": whole_wall,
        "same loop, plain Python and NumPy [periods/s of CPU]": plain_cpu,
        "same loop, plain Python and NumPy [periods/s of wall time]": plain_wall,
        "same loop, handlebar by solve_ivp, step compiled [periods/s of CPU]": ivp_cpu,
        "same loop, handlebar by solve_ivp [periods/s of wall time]": ivp_wall,
        "python-control, simpler loop, interconnected blocks [samples/s wall]": blocks,
        "python-control, simpler loop, one nlsys [samples/s wall]": single,
        "compiled / plain Python, same loop (CPU)": loop_cpu / plain_cpu,
        "compiled / solve_ivp, same loop (CPU)": loop_cpu / ivp_cpu,
        "compiled / python-control blocks (different loops, wall)": loop_wall / blocks,
        "compiled / python-control one nlsys (different loops, wall)": loop_wall / single,
        "the stack step alone, fed a recorded run [us per period of wall time]": step_alone * 1e6,
        "stick projection on / off (time of a run)": projection,
        "both feedforward terms on / off (time of a run)": feedforward,
        "load average (1 min) after": os.getloadavg()[0],
    }


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description="The closed loop's speed.")
    parser.add_argument(
        "--only", choices=["loop"], help="loop: the compiled loop alone (case 1), 60 s of 1 kHz"
    )
    args = parser.parse_args()
    if args.only == "loop":
        before = os.getloadavg()[0]
        wall, cpu = _loop_alone(60.0)
        figures = {
            "load average (1 min) before": before,
            "compiled loop alone [periods/s of CPU]": cpu,
            "compiled loop alone [periods/s of wall time]": wall,
            "load average (1 min) after": os.getloadavg()[0],
        }
    else:
        figures = run()
    for name, value in figures.items():
        print(f"{name}: {value:.4g}")
