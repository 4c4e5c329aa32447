"""Fixed-order H-infinity loop shaping, HIFOO style (the paper's eq. (26)).

The paper reduces the Glover-McFarlane design to the first-order controller
``K(s) = (b1 s + b0) / (s + a0)`` by minimising the four-block norm of eq. (25) with HIFOO
(Burke, Henrion, Lewis & Overton 2006). This module does the same with numpy/scipy:

1. seeds: balanced truncations of the full-order :func:`~motosim.control.ncf.ncfsyn`
   controllers (factors 1.1, 1.01 and 1.5), plus random perturbations of them and random points;
2. stabilisation phase: from an unstable start, minimise the closed-loop spectral abscissa;
3. optimisation phase: BFGS with a weak-Wolfe line search (Lewis & Overton 2013), which
   copes with the nonsmooth objective, using the analytic gradient of the H-infinity norm at
   its peak frequency; the objective is +inf outside the set of stabilising controllers;
4. polish: alternate Nelder-Mead (derivative-free, it escapes the kinks where BFGS stalls)
   and BFGS from the two best local minima.

The full-order optimum ``gamma_min`` is a lower bound for every fixed order and is returned
alongside, so callers can see how much the order restriction costs.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize

from motosim.control.loops import _four_block, is_stable
from motosim.control.ncf import ncfsyn
from motosim.control.norms import _hinf_norm_stable
from motosim.control.reduction import balanced_truncation
from motosim.control.statespace import StateSpace, _from_array_likes, frequency_response
from motosim.errors import MotosimError

__all__ = ["FixedOrderResult", "fixed_order_synthesis"]

Array = NDArray[np.float64]
_FG = Callable[[Array], tuple[float, Array]]

_UNSTABLE_PENALTY = 1e20  # finite stand-in for +inf given to Nelder-Mead
_N_POLISH = 2  # local minima polished by Nelder-Mead
_POLISH_ROUNDS = 3  # at most this many Nelder-Mead + BFGS rounds each


@dataclass(frozen=True, slots=True)
class FixedOrderResult:
    """A fixed-order controller minimising the four-block norm of eq. (25).

    Attributes
    ----------
    order : int
        Number of controller states.
    A, B, C, D : NDArray[np.float64]
        Controller state space, shapes (k, k), (k, p), (m, k), (m, p), positive feedback
        ``u = K y`` (loop ``(I - G_s K)^-1``, eq. (24)).
    num, den : NDArray[np.float64] or None
        For a first-order SISO controller, ``K(s) = (num[0] s + num[1]) / (s + den[1])`` with
        ``den = [1, a0]`` (the structure of eq. (26)); ``None`` otherwise.
    gamma : float
        Four-block norm achieved (``math.inf`` if no stabilising controller was found).
    gamma_full_order : float
        Full-order optimum ``gamma_min`` of :func:`~motosim.control.ncf.ncfsyn` for the same
        plant, a lower bound for ``gamma``.
    is_stable : bool
        True if the controller stabilises the plant (closed loop internally stable).
    closed_loop_poles : NDArray[np.complex128]
        Poles of the loop [rad/s].
    n_evaluations : int
        Number of H-infinity norm (or spectral-abscissa) evaluations spent.
    """

    order: int
    A: Array
    B: Array
    C: Array
    D: Array
    num: Array | None
    den: Array | None
    gamma: float
    gamma_full_order: float
    is_stable: bool
    closed_loop_poles: NDArray[np.complex128]
    n_evaluations: int

    @property
    def controller(self) -> StateSpace:
        """The controller as a :class:`~motosim.control.statespace.StateSpace`."""
        return StateSpace(self.A, self.B, self.C, self.D)


class _Problem:
    """Parametrisation ``theta -> (A_K, B_K, C_K, D_K)``, objective and gradient."""

    def __init__(self, plant: StateSpace, order: int) -> None:
        self.G = plant
        self.k = order
        self.m = plant.n_inputs
        self.p = plant.n_outputs
        # First-order SISO: B_K = 1 fixes the state scaling (eq. (26) structure).
        self.fixed_B = order == 1 and self.p == 1
        k, m, p = order, self.m, self.p
        self.sizes = (k * k, 0 if self.fixed_B else k * p, m * k, m * p)
        self.size = sum(self.sizes)
        self.n_eval = 0
        self.omega_hint: float | None = None

    def unpack(self, theta: Array) -> tuple[Array, Array, Array, Array]:
        k, m, p = self.k, self.m, self.p
        i0 = self.sizes[0]
        i1 = i0 + self.sizes[1]
        i2 = i1 + self.sizes[2]
        Ak = theta[:i0].reshape(k, k)
        Bk = np.ones((1, 1)) if self.fixed_B else theta[i0:i1].reshape(k, p)
        Ck = theta[i1:i2].reshape(m, k)
        Dk = theta[i2:].reshape(m, p)
        return Ak, Bk, Ck, Dk

    def pack(self, K: StateSpace) -> Array:
        Ak, Bk, Ck, Dk = K.A, K.B, K.C, K.D
        if self.fixed_B:
            b = float(Bk[0, 0])
            if abs(b) < 1e-300:
                b = 1.0
            Bk, Ck = Bk / b, Ck * b
        parts = [Ak.ravel(), Ck.ravel(), Dk.ravel()]
        if not self.fixed_B:
            parts.insert(1, Bk.ravel())
        return np.concatenate(parts)

    def closed_loop(self, theta: Array) -> StateSpace:
        G = self.G
        return _four_block(G.A, G.B, G.C, G.D, *self.unpack(theta))

    def abscissa(self, theta: Array) -> float:
        self.n_eval += 1
        try:
            A = self.closed_loop(theta).A
        except MotosimError:
            return math.inf
        return float(np.max(np.linalg.eigvals(A).real)) if A.size else -math.inf

    def value_and_gradient(self, theta: Array) -> tuple[float, Array]:
        """Four-block norm and its gradient (+inf and zeros if unstable)."""
        self.n_eval += 1
        zero = np.zeros_like(theta)
        try:
            T = self.closed_loop(theta)
        except MotosimError:
            return math.inf, zero
        poles = np.linalg.eigvals(T.A).astype(np.complex128)
        if not is_stable(poles, float(np.linalg.norm(T.A, 1))):
            return math.inf, zero
        gamma, omega = _hinf_norm_stable(T.A, T.B, T.C, T.D, poles, 1e-10, self.omega_hint)
        self.omega_hint = omega
        return gamma, self._gradient(theta, T, omega)

    def _gradient(self, theta: Array, T: StateSpace, omega: float) -> Array:
        """Gradient of sigma_max(T(j omega)) at the peak (Notes of the function)."""
        Ak, Bk, Ck, _ = self.unpack(theta)
        p, k = self.p, self.k
        Tw = frequency_response(T, omega)
        Phi: NDArray[np.complex128] = np.zeros((k, k), dtype=np.complex128)
        if not math.isinf(omega) and k > 0:
            M = 1j * omega * np.eye(k) - Ak
            try:
                Phi = np.asarray(np.linalg.inv(M), dtype=np.complex128)
            except np.linalg.LinAlgError:  # controller pole exactly at j omega: nudge it
                Phi = np.asarray(
                    np.linalg.inv(M + 1e-12 * max(1.0, abs(omega)) * np.eye(k)), dtype=np.complex128
                )
        U, _, Vh = np.linalg.svd(Tw)
        u, v = U[:, 0], Vh[0].conj()
        # dT = (T[:, w2] + [0; I]) dK T[y, :]  =>  d sigma = Re(c^H dK a).
        left = Tw[:, p:].copy()
        left[p:, :] += np.eye(self.m)
        a = Tw[:p, :] @ v
        c = left.conj().T @ u
        PhiBa = Phi @ Bk @ a
        d = Phi.conj().T @ Ck.conj().T @ c
        gA = np.real(np.outer(d.conj(), PhiBa))
        gB = np.real(np.outer(d.conj(), a))
        gC = np.real(np.outer(c.conj(), PhiBa))
        gD = np.real(np.outer(c.conj(), a))
        parts = [gA.ravel(), gC.ravel(), gD.ravel()]
        if not self.fixed_B:
            parts.insert(1, gB.ravel())
        return np.concatenate(parts)


def _weak_wolfe(
    fg: _FG, x: Array, f0: float, g0: Array, d: Array
) -> tuple[bool, Array, float, Array]:
    """Weak-Wolfe bracketing line search (Lewis & Overton); tolerates f = +inf."""
    c1, c2 = 1e-4, 0.9
    slope = float(g0 @ d)
    lo, hi, t = 0.0, math.inf, 1.0
    best: tuple[Array, float, Array] | None = None
    for _ in range(40):
        xt = x + t * d
        ft, gt = fg(xt)
        if not ft <= f0 + c1 * t * slope:
            hi = t
        else:
            if best is None or ft < best[1]:
                best = (xt, ft, gt)
            if float(gt @ d) < c2 * slope:
                lo = t
            else:
                return True, xt, ft, gt
        t = 0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * lo
    if best is not None:
        return False, *best
    return False, x, f0, g0


def _bfgs(fg: _FG, x0: Array, max_iter: int) -> tuple[Array, float]:
    """BFGS for nonsmooth functions (Lewis & Overton 2013): stops at a stall or max_iter."""
    x = x0.copy()
    f, g = fg(x)
    if not math.isfinite(f):
        return x, f
    n = x.size
    H = np.eye(n)
    first = True
    for _ in range(max_iter):
        d = -H @ g
        if not float(g @ d) < 0.0:
            H = np.eye(n)
            d = -g
        if float(np.linalg.norm(d)) <= 1e-14 * (1.0 + float(np.linalg.norm(x))):
            break
        ok, xn, fn, gn = _weak_wolfe(fg, x, f, g, d)
        if fn >= f:
            break
        s, y = xn - x, gn - g
        sy = float(s @ y)
        x, f, g = xn, fn, gn
        if not ok:
            break
        if sy > 0.0:
            if first:
                H *= sy / float(y @ y)
                first = False
            rho = 1.0 / sy
            V = np.eye(n) - rho * np.outer(s, y)
            H = V @ H @ V.T + rho * np.outer(s, s)
    return x, f


def _stabilise(problem: _Problem, x0: Array, scale: Array, max_iter: int) -> Array:
    """Minimise the closed-loop spectral abscissa until it is negative (HIFOO phase 1)."""

    def fg(z: Array) -> tuple[float, Array]:
        theta = z * scale
        f = problem.abscissa(theta)
        if not math.isfinite(f):
            return math.inf, np.zeros_like(z)
        if f < 0.0:
            return -math.inf, np.zeros_like(z)  # stop: any stable point will do
        h = 1e-6 * np.maximum(np.abs(z), 1.0)
        g = np.empty_like(z)
        for i in range(z.size):
            e = np.zeros_like(z)
            e[i] = h[i]
            g[i] = (problem.abscissa((z + e) * scale) - problem.abscissa((z - e) * scale)) / (
                2.0 * h[i]
            )
        g[~np.isfinite(g)] = 0.0
        return f, g

    f0, _ = fg(x0)
    if f0 == -math.inf or not math.isfinite(f0):
        return x0
    z, _ = _bfgs(fg, x0, max_iter)
    return z


def _seeds(problem: _Problem, plant: StateSpace) -> tuple[list[Array], float]:
    """Controllers from balanced truncation of full-order ncfsyn designs, and gamma_min."""
    seeds: list[Array] = []
    gamma_min = math.nan
    k, m, p = problem.k, problem.m, problem.p
    for factor in (1.1, 1.01, 1.5):
        res = ncfsyn(plant.A, plant.B, plant.C, plant.D, factor)
        gamma_min = res.gamma_min
        try:
            K = balanced_truncation(res.controller, k)
        except MotosimError:
            continue
        nk = K.n_states
        if nk < k:  # pad with fast, weakly coupled modes
            fast = 10.0 * max(1.0, float(np.max(np.abs(np.linalg.eigvals(plant.A)))))
            A = np.zeros((k, k))
            A[:nk, :nk] = K.A
            A[nk:, nk:] = -fast * np.eye(k - nk)
            B = np.vstack((K.B, 1e-3 * np.ones((k - nk, p))))
            C = np.hstack((K.C, 1e-3 * np.ones((m, k - nk))))
            K = StateSpace(A, B, C, K.D)
        seeds.append(problem.pack(K))
    return seeds, gamma_min


def fixed_order_synthesis(
    A: ArrayLike,
    B: ArrayLike,
    C: ArrayLike,
    D: ArrayLike,
    order: int = 1,
    *,
    rng: np.random.Generator,
    n_starts: int = 8,
    max_iter: int = 200,
    polish: bool = True,
) -> FixedOrderResult:
    """Controller of fixed order minimising the four-block norm of eq. (25).

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix of the shaped plant ``G_s`` [1/s] (integrators allowed).
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (p, m)
        Direct feedthrough.
    order : int, optional
        Number of controller states k >= 0 (0: static gain). Default 1, the paper's
        ``K(s) = (b1 s + b0) / (s + a0)`` for a SISO plant.
    rng : numpy.random.Generator
        Source of the random starting points.
    n_starts : int, optional
        Number of starting points: the ncfsyn seeds, perturbations of them and random points.
    max_iter : int, optional
        BFGS iterations per start.
    polish : bool, optional
        Finish with Nelder-Mead from the best point.

    Returns
    -------
    FixedOrderResult
        The best controller found, in the positive-feedback convention ``u = K y``
        (loop ``(I - G_s K)^-1``, eq. (24)), its ``gamma``, the full-order ``gamma_min`` and
        the stability status.

    Raises
    ------
    MotosimError
        If the plant matrices are invalid, ``order < 0`` or ``n_starts < 1``, or the plant is
        not stabilisable/detectable (from :func:`~motosim.control.ncf.ncfsyn`).

    Notes
    -----
    Parametrisation: ``A_K, B_K, C_K, D_K`` entries, except for k = 1 and one measurement,
    where ``B_K = 1`` and ``K(s) = C_K / (s - A_K) + D_K``, i.e. ``a0 = -A_K``, ``b1 = D_K``,
    ``b0 = C_K - b1 A_K``. The gradient of ``f = sigma_max(T(j omega*))`` at the peak
    frequency ``omega*`` with top singular vectors ``u, v`` is ``Re(c^H dK(j omega*) a)``
    with ``a = S [I, G] v``, ``c = u_2 + ([I; K] S G)^H u``, ``S = (I - G K)^-1``, chained
    through ``K(s) = C_K (sI - A_K)^-1 B_K + D_K``. A local minimum is not guaranteed to be
    global; ``gamma >= gamma_full_order`` always holds.

    References
    ----------
    J. V. Burke, D. Henrion, A. S. Lewis, M. L. Overton, "HIFOO - a MATLAB package for
    fixed-order controller design and H-infinity optimization", IFAC ROCOND, 2006.
    A. S. Lewis, M. L. Overton, "Nonsmooth optimization via quasi-Newton methods",
    Math. Programming 141:135-163, 2013.
    """
    plant = _from_array_likes(A, B, C, D)
    if not isinstance(order, int | np.integer) or order < 0:
        raise MotosimError(f"order = {order!r}; expected an integer >= 0")
    if not isinstance(n_starts, int | np.integer) or n_starts < 1:
        raise MotosimError(f"n_starts = {n_starts!r}; expected an integer >= 1")
    problem = _Problem(plant, int(order))
    seeds, gamma_full = _seeds(problem, plant)
    if seeds:
        ref = seeds[0]
    else:
        ref = np.zeros(problem.size)
    scale = np.maximum(np.abs(ref), 1e-2 * max(float(np.max(np.abs(ref), initial=0.0)), 1.0))

    starts: list[Array] = [sd / scale for sd in seeds][:n_starts]
    while len(starts) < n_starts:
        base = starts[int(rng.integers(len(seeds)))] if seeds else np.zeros(problem.size)
        if len(starts) % 3 == 2 or not seeds:
            starts.append(rng.standard_normal(problem.size) * 2.0)
        else:
            sigma = float(rng.choice([0.1, 0.3, 1.0]))
            starts.append(base * (1.0 + sigma * rng.standard_normal(problem.size)))

    def fg(z: Array) -> tuple[float, Array]:
        f, g = problem.value_and_gradient(z * scale)
        return f, g * scale

    results: list[tuple[float, Array]] = []
    for z0 in starts:
        if problem.abscissa(z0 * scale) >= 0.0:
            z0 = _stabilise(problem, z0, scale, max_iter)
        z, f = _bfgs(fg, z0, max_iter)
        results.append((f, z))
    results.sort(key=lambda r: r[0])
    best_f, best_z = results[0]

    if polish and math.isfinite(best_f):

        def fun(z: Array) -> float:
            f, _ = problem.value_and_gradient(z * scale)
            return f if math.isfinite(f) else _UNSTABLE_PENALTY

        # Alternate Nelder-Mead (escapes the kinks where BFGS stalls) and BFGS from the best
        # _N_POLISH local minima, until a round gains less than 1e-9 relative.
        for f, z in results[:_N_POLISH]:
            if not math.isfinite(f):
                break
            for _ in range(_POLISH_ROUNDS):
                out = minimize(
                    fun,
                    z,
                    method="Nelder-Mead",
                    options={
                        "xatol": 1e-10,
                        "fatol": 1e-12,
                        "maxfev": min(100 * problem.size, 400),
                    },
                )
                z_new, f_new = _bfgs(fg, np.asarray(out.x, dtype=np.float64), max_iter)
                if not f_new < f:
                    break
                gain = (f - f_new) / f
                z, f = z_new, f_new
                if gain < 1e-9:
                    break
            if f < best_f:
                best_f, best_z = f, z
        best_f, _ = fg(best_z)

    theta = best_z * scale
    Ak, Bk, Ck, Dk = problem.unpack(theta)
    poles = np.linalg.eigvals(problem.closed_loop(theta).A).astype(np.complex128)
    stable = math.isfinite(best_f)
    num: Array | None = None
    den: Array | None = None
    if problem.k == 1 and problem.m == 1 and problem.p == 1:
        a0 = -float(Ak[0, 0])
        b1 = float(Dk[0, 0])
        num = np.array([b1, float(Ck[0, 0] * Bk[0, 0]) + b1 * a0])
        den = np.array([1.0, a0])
    return FixedOrderResult(
        order=problem.k,
        A=Ak.copy(),
        B=Bk.copy(),
        C=Ck.copy(),
        D=Dk.copy(),
        num=num,
        den=den,
        gamma=float(best_f),
        gamma_full_order=gamma_full,
        is_stable=stable,
        closed_loop_poles=poles,
        n_evaluations=problem.n_eval,
    )
