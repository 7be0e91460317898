"""Newton's stall rule (`fea.newton.stalled`): a solve whose residual wanders gives up, one that converges, even
only linearly at a fair rate, does not. The sequences: Newton's own on a creasing notch (the 8 x 4 mm candidate's
path mesh, the first 12 of an attempt that took 49 iterations), quadratic and linear convergence written out.
The line search (`fea.newton._line_search`) on a one-unknown energy with a penalty wall, written out."""

from __future__ import annotations

import numpy as np

from seadesign.fea.newton import NewtonSettings, _line_search, stalled

# residual norms (N) of an attempt at 0.4348 rad on the 8 x 4 mm candidate's crease (measured)
CREASE = [16.0, 16.0, 11.0, 12.0, 9.4, 8.8, 12.0, 15.0, 12.0, 10.0, 9.3, 12.0]


def test_a_wandering_residual_stalls_after_the_window():
    assert not any(stalled(CREASE[:n], 10) for n in range(1, 11))  # fewer than 11 norms: not judged yet
    assert stalled(CREASE[:11], 10)  # 9.3 is more than half of 16


def test_converging_residuals_never_stall():
    quadratic = [1.0]
    while quadratic[-1] > 1e-12:
        quadratic.append(min(0.5 * quadratic[-1], quadratic[-1] ** 2))
    linear = [0.92 ** k for k in range(60)]  # 0.92^10 = 0.43: halves within the window
    for norms in (quadratic, linear):
        assert not any(stalled(norms[:n], 10) for n in range(1, len(norms) + 1))
    slow = [0.95 ** k for k in range(12)]  # 0.95^10 = 0.60: does not halve
    assert stalled(slow[:11], 10) and not stalled(slow[:10], 10)


def test_without_a_window_nothing_stalls():
    assert NewtonSettings().stall_window is None
    assert not stalled(CREASE * 10, None)


class _Wall:
    """One unknown x (the first component of node 0) with the energy (x - 1.8)^2 / 2 + k/2 max(0, x - 1.5)^2: a
    spring pressed past a penalty wall at 1.5, equilibrium at x = (1.8 + 1.5 k) / (1 + k)."""

    free = np.array([0])

    def __init__(self, k: float):
        self.k = k

    def forces(self, u: np.ndarray) -> np.ndarray:
        f = np.zeros_like(u)
        f[0, 0] = u[0, 0] - 1.8 + self.k * max(0.0, u[0, 0] - 1.5)
        return f

    def residual(self, f: np.ndarray) -> np.ndarray:
        return f[self.free].ravel()

    def energy(self, u: np.ndarray) -> float:
        return 0.5 * (u[0, 0] - 1.8) ** 2 + 0.5 * self.k * max(0.0, u[0, 0] - 1.5) ** 2


def _search(k: float, step: float) -> float | None:
    wall, u = _Wall(k), np.zeros((1, 3))
    r = wall.residual(wall.forces(u))
    direction = np.array([[step, 0.0, 0.0]])
    trial, _ = _line_search(wall, u, r, direction, float(np.linalg.norm(r)))
    return None if trial is None else float(trial[0, 0])


def test_the_line_search_halves_a_step_whose_penetration_multiplies_the_residual():
    # from x = 0 (residual 1.8, energy 1.62) a step to x = 2 meets the wall (k = 10): the energy falls to 1.27, as
    # Armijo asks, but the residual rises to 5.2; half the step, x = 1, cuts the residual to 0.8
    assert _search(10.0, 2.0) == 1.0
    # without the wall the full step cuts the residual (to 0.2) and is taken
    assert _search(0.0, 2.0) == 2.0
    # a step to x = 4 with a stiff wall (k = 100): the residual rises at 4 (252) and at 2 (50.2), and so does the
    # energy at 4 (315) and at 2 (12.52); at 1 the residual falls to 0.8
    assert _search(100.0, 4.0) == 1.0
    # an ascent direction: neither the residual nor the energy falls at any step down to 1/1000 of it
    assert _search(0.0, -1.0) is None
