"""Total-Lagrangian finite-strain elasticity on the Lagrange tetrahedra of `fea.elements`: the
strain energy, internal forces and tangent stiffness of a hyperelastic law (`fea.hyperelastic`)
at a displacement field u (m). Mesh coordinates in m; forces in N; energies in J.

Quadrature: the 4-point rule for P2 (as CalculiX's C3D10) and 1 point for P1.

Two volumetric formulations:
- "full": U(J) at every quadrature point (CalculiX's C3D10; locks as nu -> 0.5);
- "mean_dilatation": U of each element's mean volume ratio Jbar = (1/V) int J dV (a constant
  pressure per element, the P2/P0 mixed element condensed), free of volumetric locking.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from seadesign.design.materials import Hyperelastic
from seadesign.fea.assembly import UpperBlocks, sum_pair_blocks
from seadesign.fea.elements import ElementMesh, barycentric_gradients, quadrature, shape_dlam, upper_pairs
from seadesign.fea.hyperelastic import isochoric_energy_density, stress, tangent, volumetric

_CHUNK = 4096  # elements per vectorised block
FORMULATIONS = ("full", "mean_dilatation")


@dataclass(frozen=True)
class Solid:
    """A hyperelastic body on an element mesh: shape-function gradients dN/dX (m, q, nen, 3) in 1/m at
    the quadrature points, quadrature weights times volume (m, q) in m^3, the law and the formulation."""

    mesh: ElementMesh
    law: Hyperelastic
    grads: np.ndarray
    weights_m3: np.ndarray
    formulation: str = "full"

    @classmethod
    def of(cls, mesh: ElementMesh, law: Hyperelastic, formulation: str = "full") -> "Solid":
        if formulation not in FORMULATIONS:
            raise ValueError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}")
        qlam, qw = quadrature(2 if mesh.order == 2 else 1)
        dlam = shape_dlam(mesh.order, qlam)  # (q, nen, 4)
        g, vol = barycentric_gradients(mesh.nodes_m, mesh.elements)
        return cls(mesh, law, np.einsum("qak,mki->mqai", dlam, g), vol[:, None] * qw[None, :], formulation)

    def deformation_gradient(self, u_m: np.ndarray, elements: slice | np.ndarray = slice(None)) -> np.ndarray:
        """F = I + grad u (m, q, 3, 3) at the quadrature points of the selected elements."""
        return np.eye(3) + np.einsum("mai,mqaj->mqij", u_m[self.mesh.elements[elements]], self.grads[elements])

    def _pressure(self, F: np.ndarray, w: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray]:
        """Mean dilatation: U'(Jbar) per point (m, q), U''(Jbar) per element and Jbar; full: None, None, J."""
        J = np.linalg.det(F)
        if self.formulation == "full":
            return None, None, J
        jbar = (J * w).sum(axis=1) / w.sum(axis=1)
        _, du, ddu = volumetric(self.law, jbar)
        return np.broadcast_to(du[:, None], J.shape), ddu, jbar

    def energy(self, u_m: np.ndarray) -> float:
        """Total strain energy (J)."""
        total = 0.0
        for s in _chunks(len(self.mesh.elements)):
            F, w = self.deformation_gradient(u_m, s), self.weights_m3[s]
            total += float(np.sum(isochoric_energy_density(self.law, F) * w))
            _, _, j = self._pressure(F, w)
            total += float(np.sum(volumetric(self.law, j)[0] * (w if j.ndim == 2 else w.sum(axis=1))))
        return total

    def forces(self, u_m: np.ndarray) -> np.ndarray:
        """(N, 3) internal nodal forces dE/du in N."""
        f = np.zeros((len(self.mesh.nodes_m), 3))
        for s in _chunks(len(self.mesh.elements)):
            F = self.deformation_gradient(u_m, s)
            p = stress(self.law, F, self._pressure(F, self.weights_m3[s])[0])
            _scatter(f, self.mesh.elements[s], np.einsum("mqij,mqaj,mq->mai", p, self.grads[s], self.weights_m3[s]))
        return f

    def _element_tangents(self, u_m: np.ndarray, el: slice | np.ndarray) -> np.ndarray:
        """Element tangent stiffness (m, a, i, k, b) in N/m: K_ab[i, k] = sum_q w G_aJ A_iJkL G_bL, plus the
        mean dilatation's rank-one volumetric term U''(Jbar) / V beta_a,i beta_b,k (beta = dv/du)."""
        F, g, w = self.deformation_gradient(u_m, el), self.grads[el], self.weights_m3[el]
        pressure, ddu, _ = self._pressure(F, w)
        _, a = tangent(self.law, F, pressure)
        m, q, nen = g.shape[0], g.shape[1], g.shape[2]
        ga = np.einsum("mqaJ,mqiJkL,mq->mqaikL", g, a, w, optimize=True).reshape(m, q, nen * 9, 3)
        k = (ga @ np.swapaxes(g, -1, -2)).sum(axis=1).reshape(m, nen, 3, 3, nen)
        if ddu is not None:
            jh = np.linalg.det(F)[..., None, None] * np.swapaxes(np.linalg.inv(F), -1, -2)  # J F^-T
            beta = np.einsum("mqiJ,mqaJ,mq->mai", jh, g, w)
            k += (ddu / w.sum(axis=1))[:, None, None, None, None] * np.einsum("mai,mbk->maikb", beta, beta)
        return k

    def tangent(self, u_m: np.ndarray, node_index: np.ndarray, n: int) -> UpperBlocks:
        """Tangent stiffness (N/m) at u as upper 3x3 node blocks; node_index maps nodes to block rows
        (-1: no row, e.g. a prescribed node), as `assembly.sum_pair_blocks`."""
        ia, ib = upper_pairs(self.mesh.order)
        blocks = np.empty((len(ia), len(self.mesh.elements), 3, 3))
        for s in _chunks(len(self.mesh.elements)):
            blocks[:, s] = self._element_tangents(u_m, s)[:, ia, :, :, ib]
        return sum_pair_blocks(self.mesh.elements, self.mesh.order, blocks, node_index, n)

    def tangent_product(self, u_m: np.ndarray, v_m: np.ndarray) -> np.ndarray:
        """(N, 3) tangent stiffness at u times the nodal vector v (N), from the elements v touches."""
        f = np.zeros((len(self.mesh.nodes_m), 3))
        touched = np.flatnonzero(np.any(v_m[self.mesh.elements] != 0, axis=(1, 2)))
        for start in range(0, len(touched), _CHUNK):
            el = touched[start : start + _CHUNK]
            k = self._element_tangents(u_m, el)
            _scatter(f, self.mesh.elements[el], np.einsum("maikb,mbk->mai", k, v_m[self.mesh.elements[el]]))
        return f

    def peak_principal_strain(self, u_m: np.ndarray) -> float:
        """Largest principal engineering strain (max stretch - 1) over the quadrature points."""
        peak = 0.0
        for s in _chunks(len(self.mesh.elements)):
            F = self.deformation_gradient(u_m, s)
            peak = max(peak, float(np.sqrt(np.linalg.eigvalsh(np.swapaxes(F, -1, -2) @ F)[..., -1].max())) - 1.0)
        return peak


def _chunks(m: int) -> list[slice]:
    return [slice(s, min(s + _CHUNK, m)) for s in range(0, m, _CHUNK)]


def _scatter(f: np.ndarray, elements: np.ndarray, fe: np.ndarray) -> None:
    idx = elements.ravel()
    for i in range(3):
        f[:, i] += np.bincount(idx, weights=fe[..., i].ravel(), minlength=len(f))
