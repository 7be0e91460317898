"""Stress recovery: element stresses (linear in each P2 tetrahedron) L2-projected onto the
continuous nodal space, then invariants. SI units in, Pa out.

Voigt order (xx, yy, zz, xy, yz, zx), as in CalculiX's .frd output.
"""

from __future__ import annotations

import numpy as np

from seadesign.fea.assembly import mass_upper
from seadesign.fea.elements import (
    ElementMesh,
    barycentric_gradients,
    lame,
    linear_projection_reference,
    shape_dlam,
)
from seadesign.fea.linsolve import SPDFactorization

_CHUNK = 50000


def vertex_stresses(emesh: ElementMesh, u_m: np.ndarray, youngs_modulus_Pa: float, poisson_ratio: float) -> np.ndarray:
    """Stress (m, 4, 6) in Pa at the four vertices of every element (exact for P1 and P2)."""
    lam, mu = lame(youngs_modulus_Pa, poisson_ratio)
    dlam = shape_dlam(emesh.order, np.eye(4))  # (4 vertices, nen, 4)
    out = np.empty((len(emesh.elements), 4, 6))
    for s in range(0, len(emesh.elements), _CHUNK):
        el = emesh.elements[s : s + _CHUNK]
        grads, _ = barycentric_gradients(emesh.nodes_m, el)
        g = np.einsum("vak,mkc->mvac", dlam, grads)  # (m, 4, nen, 3)
        du = np.einsum("mvac,mai->mvic", g, u_m[el])  # du_i/dx_c
        eps = 0.5 * (du + du.transpose(0, 1, 3, 2))
        tr = np.trace(eps, axis1=2, axis2=3)
        sig = 2 * mu * eps + lam * tr[:, :, None, None] * np.eye(3)
        out[s : s + len(el)] = np.stack(
            [sig[..., 0, 0], sig[..., 1, 1], sig[..., 2, 2], sig[..., 0, 1], sig[..., 1, 2], sig[..., 2, 0]], axis=-1
        )
    return out


def project_to_nodes(emesh: ElementMesh, vertex_values: np.ndarray) -> np.ndarray:
    """L2 projection (n_nodes, c) of a field that is linear in each element, given at its vertices (m, 4, c)."""
    _, vol = barycentric_gradients(emesh.nodes_m, emesh.elements)
    ref = linear_projection_reference(emesh.order)  # (nen, 4)
    local = np.einsum("ak,mkc->mac", ref, vertex_values) * vol[:, None, None]
    n = len(emesh.nodes_m)
    rhs = np.stack(
        [np.bincount(emesh.elements.ravel(), weights=local[..., c].ravel(), minlength=n) for c in range(local.shape[2])],
        axis=1,
    )
    fact = SPDFactorization(mass_upper(emesh).matrix())
    x = fact.solve(rhs)
    fact.close()
    return x


def invariants(voigt_Pa: np.ndarray) -> dict[str, np.ndarray]:
    """von Mises, principal stresses (1st >= 2nd >= 3rd) and max shear (Tresca/2) in Pa."""
    s = voigt_Pa
    t = np.empty((len(s), 3, 3))
    t[:, 0, 0], t[:, 1, 1], t[:, 2, 2] = s[:, 0], s[:, 1], s[:, 2]
    t[:, 0, 1] = t[:, 1, 0] = s[:, 3]
    t[:, 1, 2] = t[:, 2, 1] = s[:, 4]
    t[:, 2, 0] = t[:, 0, 2] = s[:, 5]
    ev = np.linalg.eigvalsh(t)  # ascending
    vm = np.sqrt(
        0.5 * ((s[:, 0] - s[:, 1]) ** 2 + (s[:, 1] - s[:, 2]) ** 2 + (s[:, 2] - s[:, 0]) ** 2)
        + 3.0 * (s[:, 3] ** 2 + s[:, 4] ** 2 + s[:, 5] ** 2)
    )
    return {
        "von_mises": vm,
        "principal_1": ev[:, 2],
        "principal_3": ev[:, 0],
        "max_shear": 0.5 * (ev[:, 2] - ev[:, 0]),
    }
