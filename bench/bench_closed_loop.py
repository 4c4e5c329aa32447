"""The closed loop of Fig. 7: compiled step, plain Python, python-control, and a campaign.

Four measurements in one run, on the same loop (square rider torque, SIMACOM handlebar with
dry friction, Walcott-Zak observer, first-order H-infinity controller, Sharp motorcycle at
20 m/s, 1 kHz):

1. the compiled stack step (numba), as ``motosim simulate`` runs it;
2. the same code with ``NUMBA_DISABLE_JIT=1`` (plain Python), in a subprocess;
3. the same loop written as one python-control ``nlsys`` in continuous time and simulated by
   ``input_output_response`` with an output every millisecond (python-control's idiom);
4. a campaign of 1000 perturbed 10 s runs (J_eq and beta_eq drawn in [0.5, 1.5] x nominal)
   on both cores.
"""

import os
import subprocess
import sys
import time
import tomllib
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from numba import njit

from motosim.control.torque_feedback import design_torque_feedback
from motosim.params import load_parameters
from motosim.sim import build_stack, parse_scenario, prepare, simulate
from motosim.sim.stack import StackModel, new_data, reset, step

SCENARIO = """
[scenario]
name = "bench"
duration = {duration}
[rider]
kind = "torque"
profile = {{ kind = "square", low = -10.0, high = 10.0, period = 2.0 }}
"""


def _inputs(duration: float, inertia: float = 1.0, damping: float = 1.0):  # type: ignore[no-untyped-def]
    hb = load_parameters("simacom_handlebar", "handlebar")
    sc = parse_scenario(tomllib.loads(SCENARIO.format(duration=duration)), origin="bench")
    ctrl = _controller()
    import dataclasses

    sc = dataclasses.replace(
        sc,
        handlebar=dataclasses.replace(sc.handlebar, inertia_factor=inertia, damping_factor=damping),
    )
    return prepare(
        sc, sharp=load_parameters("sharp1971", "sharp"), true_handlebar=hb,
        nominal_handlebar=hb, controller=ctrl,
    )  # fmt: skip


_CTRL = None


def _controller():  # type: ignore[no-untyped-def]
    global _CTRL
    if _CTRL is None:
        hb = load_parameters("simacom_handlebar", "handlebar")
        _CTRL = design_torque_feedback(hb, rng=np.random.default_rng(0), n_starts=2).controller
    return _CTRL


def _compiled(duration: float) -> float:
    inputs = _inputs(duration)
    simulate(inputs, rng=np.random.default_rng(0), keep=False)
    start = time.perf_counter()
    simulate(inputs, rng=np.random.default_rng(0), keep=False, chunk=duration)
    return duration * 1000.0 / (time.perf_counter() - start)


def _plain_python(duration: float) -> float:
    code = (
        "import time, numpy as np, sys; sys.path.insert(0, 'bench');"
        "from bench_closed_loop import _inputs; from motosim.sim import simulate;"
        f"inp = _inputs({duration}); t0 = time.perf_counter();"
        f"simulate(inp, rng=np.random.default_rng(0), keep=False, chunk={duration});"
        f"print({duration} * 1000.0 / (time.perf_counter() - t0))"
    )
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    return float(out.stdout.strip().splitlines()[-1])


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
            handlebar, lambda t, x, u, p: x, name="handlebar", inputs=["tau_r", "i_m"],
            outputs=["theta", "omega"], states=2,
        )  # fmt: skip
        est = ct.nlsys(
            observer, lambda t, x, u, p: [x[2]], name="observer",
            inputs=["theta", "omega", "i_m"], outputs=["tau_hat"], states=3,
        )  # fmt: skip
        moto = ct.nlsys(
            bike, lambda t, z, u, p: [z[5]], name="bike", inputs=["tau_hat"],
            outputs=["delta"], states=12,
        )  # fmt: skip
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


def _campaign_share(seeds: list[int]) -> int:
    stack = build_stack(_inputs(10.0))  # designed once, run on every perturbed handlebar
    steps = 0
    for seed in seeds:
        rng = np.random.default_rng(seed)
        inertia, damping = rng.uniform(0.5, 1.5, 2)
        inputs = _inputs(10.0, inertia, damping)
        run = simulate(inputs, rng=rng, stack=stack, keep=False, chunk=10.0)
        steps += 10_000 if run.t.size else 0
    return steps


def _campaign(runs: int) -> float:
    with ProcessPoolExecutor(2) as pool:
        list(pool.map(_campaign_share, [[0], [1]]))  # compile and design in each worker
        start = time.perf_counter()
        shares = [list(range(2, runs + 2, 2)), list(range(3, runs + 2, 2))]
        total = sum(pool.map(_campaign_share, shares))
        elapsed = time.perf_counter() - start
    assert total == runs * 10_000
    return elapsed


@njit(cache=True)
def _drive_stack(model, data, theta, torque):  # type: ignore[no-untyped-def]
    """The stack step alone, fed a recorded angle and rider torque; returns a checksum."""
    total = 0.0
    for k in range(theta.size):
        total += step(model, data, theta[k], 0.0, torque[k], 0.0, 0.0)
    return total


def _ratio(duration: float, variant: Callable[[StackModel], StackModel], repeats: int = 7) -> float:
    """Time of the default stack's step over that of ``variant(stack)``.

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
    return best["on"] / best["off"]


def _without_projection(model: StackModel) -> StackModel:
    """The stack with the observer's stick projection off."""
    settings = model.estimator.p.copy()
    settings[9] = 0.0
    return model._replace(estimator=model.estimator._replace(p=settings))


def _without_feedforward(model: StackModel) -> StackModel:
    """The stack with neither feedforward term (rider-torque cancellation, predicted or not,
    reference inverse dynamics): the step skips their code, as it did before they existed."""
    ff = model.feedforward.copy()
    ff[:2] = 0.0
    return model._replace(feedforward=ff, prediction=np.zeros_like(model.prediction))


def run() -> dict[str, float]:
    """Steps per second of each, the ratios, and the campaign's wall time."""
    projection = _ratio(20.0, _without_projection)
    feedforward = _ratio(20.0, _without_feedforward)
    compiled = max(_compiled(60.0) for _ in range(3))
    plain = _plain_python(0.5)
    blocks = _python_control(0.5, blocks=True)
    single = _python_control(0.5, blocks=False)
    campaign = _campaign(1000)
    return {
        "compiled closed loop [steps/s]": compiled,
        "plain Python, same code [steps/s]": plain,
        "python-control, interconnected blocks [samples/s]": blocks,
        "python-control, one hand-written nlsys [samples/s]": single,
        "compiled / plain Python": compiled / plain,
        "compiled / python-control blocks": compiled / blocks,
        "compiled / python-control one nlsys": compiled / single,
        "stick projection on / off (time of a run)": projection,
        "both feedforward terms on / off (time of a run)": feedforward,
        "1000 perturbed 10 s runs at 1 kHz, 2 processes [s]": campaign,
    }
