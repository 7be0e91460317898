"""The compressible neo-Hookean law in closed form, written apart from `fea.hyperelastic`: the Cauchy stress
of a deformation gradient and the homogeneous uniaxial state with free lateral faces."""

from __future__ import annotations

import numpy as np

from seadesign.design.materials import Hyperelastic


def neo_hooke_cauchy(law: Hyperelastic, F: np.ndarray) -> np.ndarray:
    """Cauchy stress (Pa): 2 C10 J^(-5/3) dev(F F^T) + 2 (J - 1) / D1 I."""
    J, b = np.linalg.det(F), F @ F.T
    return 2 * law.c10_Pa * J ** (-5 / 3) * (b - np.trace(b) / 3 * np.eye(3)) + 2 * (J - 1) / law.d1_per_Pa * np.eye(3)


def uniaxial(law: Hyperelastic, stretch: float) -> np.ndarray:
    """F = diag(stretch, s, s) with the lateral Cauchy stress zero (free faces), s found by bisection."""
    lo, hi = 0.3, 3.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lateral = neo_hooke_cauchy(law, np.diag([stretch, mid, mid]))[1, 1]
        lo, hi = (mid, hi) if lateral < 0 else (lo, mid)
    return np.diag([stretch, 0.5 * (lo + hi), 0.5 * (lo + hi)])
