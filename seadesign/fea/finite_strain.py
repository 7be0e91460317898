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
from seadesign.fea.assembly import PairPattern, UpperBlocks
from seadesign.fea.elements import ElementMesh, barycentric_gradients, quadrature, shape_dlam, upper_pairs
from seadesign.fea.hyperelastic import (det_and_inverse_transpose, i1_tangent, isochoric_energy_density, mooney_rivlin_fields,
                                       stress, volumetric)
from seadesign.fea.kernels import (add_element_vectors, contract, deformation_gradients, i1_pair_blocks,
                                   mooney_rivlin_pair_blocks)

_CHUNK = 4096  # elements per vectorised block
# A principal direction is tensile (compressive) when its Cauchy stress is above (below) this fraction of the
# point's largest principal stress magnitude: a free face of a squeezed region carries only the
# discretisation's noise along its normal, which must not turn the region's bulge into a tensile strain.
TENSION_FLOOR = 0.01
FORMULATIONS = ("full", "mean_dilatation")


@dataclass(frozen=True)
class Solid:
    """A hyperelastic body on an element mesh, the law and the volumetric formulation.

    Shape-function gradients are combinations of the element's constant barycentric gradients
    (straight-sided elements): G_a(x_q) = sum_k D[q, a, k] Gamma_k with D (q, nen, 4) the same for
    every element. `bary` holds Gamma (m, 4, 3) in 1/m and `weights_m3` the quadrature weights times
    volume (m, q) in m^3.
    """

    mesh: ElementMesh
    law: Hyperelastic
    dlam: np.ndarray
    bary: np.ndarray
    weights_m3: np.ndarray
    formulation: str = "full"

    @classmethod
    def of(cls, mesh: ElementMesh, law: Hyperelastic, formulation: str = "full") -> "Solid":
        if formulation not in FORMULATIONS:
            raise ValueError(f"formulation must be one of {FORMULATIONS}, got {formulation!r}")
        qlam, qw = quadrature(2 if mesh.order == 2 else 1)
        dlam = shape_dlam(mesh.order, qlam)  # (q, nen, 4)
        g, vol = barycentric_gradients(mesh.nodes_m, mesh.elements)
        return cls(mesh, law, dlam, g, vol[:, None] * qw[None, :], formulation)

    def deformation_gradient(self, u_m: np.ndarray, elements: slice | np.ndarray = slice(None)) -> np.ndarray:
        """F = I + grad u (m, q, 3, 3) at the quadrature points of the selected elements."""
        return deformation_gradients(self.dlam, self._gamma(elements), self.mesh.elements[elements], u_m)

    def _gamma(self, elements: slice | np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(self.bary[elements])

    def _mean_dilatation(self, F: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """U'(Jbar) per point (m, q), U''(Jbar) and Jbar per element; None for the full formulation."""
        if self.formulation == "full":
            return None
        J = det_and_inverse_transpose(F)[0]
        jbar = (J * w).sum(axis=1) / w.sum(axis=1)
        _, du, ddu = volumetric(self.law, jbar)
        return np.broadcast_to(du[:, None], J.shape), ddu, jbar

    def energy(self, u_m: np.ndarray) -> float:
        """Total strain energy (J)."""
        total = 0.0
        for s in _chunks(len(self.mesh.elements)):
            F, w = self.deformation_gradient(u_m, s), self.weights_m3[s]
            total += float(np.sum(isochoric_energy_density(self.law, F) * w))
            md = self._mean_dilatation(F, w)
            if md is None:
                total += float(np.sum(volumetric(self.law, det_and_inverse_transpose(F)[0])[0] * w))
            else:
                total += float(np.sum(volumetric(self.law, md[2])[0] * w.sum(axis=1)))
        return total

    def forces(self, u_m: np.ndarray) -> np.ndarray:
        """(N, 3) internal nodal forces dE/du in N."""
        f = np.zeros((len(self.mesh.nodes_m), 3))
        for s in _chunks(len(self.mesh.elements)):
            F = self.deformation_gradient(u_m, s)
            md = self._mean_dilatation(F, self.weights_m3[s])
            p = stress(self.law, F, None if md is None else md[0])
            add_element_vectors(f, self.mesh.elements[s], self._contract(p, s))
        return f

    def _contract(self, p: np.ndarray, el: slice | np.ndarray) -> np.ndarray:
        """f_ai = sum_q w P_ij G_aj (m, nen, 3) for P (m, q, 3, 3)."""
        return contract(self.dlam, self._gamma(el), np.ascontiguousarray(self.weights_m3[el]), np.ascontiguousarray(p))

    def _blocks(self, u_m: np.ndarray, el: slice | np.ndarray, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
        """Tangent blocks K_ab (P, m, 3, 3) in N/m of the selected elements for the pairs (ia, ib): the law's
        tangent at the quadrature points contracted with the gradients in `fea.kernels` (laws in I1bar and J as the
        five terms of `hyperelastic.I1Tangent`; Mooney-Rivlin's 81-component A built and contracted point by point,
        never stored); with the mean dilatation,
        plus its rank-one volumetric stiffness U''(Jbar) / V beta_a beta_b, beta = int J F^-T G dV."""
        F, w, gam = self.deformation_gradient(u_m, el), self.weights_m3[el], self._gamma(el)
        md = self._mean_dilatation(F, w)
        pressure = None if md is None else md[0]
        c = np.ascontiguousarray
        if self.law.c01_Pa:
            blocks = mooney_rivlin_pair_blocks(self.dlam, gam, c(w), *mooney_rivlin_fields(self.law, F, pressure), ia, ib)
        else:
            t = i1_tangent(self.law, F, pressure)
            terms = (np.broadcast_to(x, w.shape).astype(float) for x in (t.delta, t.cross, t.hh, t.hx, t.w11))
            blocks = i1_pair_blocks(self.dlam, gam, c(w), c(t.F), c(t.H), c(t.D), *map(c, terms), ia, ib)
        if md is not None:
            j, h = det_and_inverse_transpose(F)
            beta, k = self._contract(j[..., None, None] * h, el), md[1] / w.sum(axis=1)
            bi, bj = beta[:, ia].transpose(1, 0, 2), beta[:, ib].transpose(1, 0, 2)
            blocks += k[None, :, None, None] * bi[..., None] * bj[..., None, :]
        return blocks

    def tangent(self, u_m: np.ndarray, pattern: PairPattern | None = None) -> UpperBlocks:
        """Tangent stiffness (N/m) at u as upper 3x3 node blocks, numbered by `pattern` (`PairPattern.of` this
        mesh; default: every node its own row)."""
        ia, ib = upper_pairs(self.mesh.order)
        if pattern is None:
            n = len(self.mesh.nodes_m)
            pattern = PairPattern.of(self.mesh.elements, self.mesh.order, np.arange(n), n)
        blocks = np.empty((len(ia), len(self.mesh.elements), 3, 3))
        for s in _chunks(len(self.mesh.elements)):
            blocks[:, s] = self._blocks(u_m, s, ia, ib)
        return pattern.sum(blocks)

    def tangent_product(self, u_m: np.ndarray, v_m: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """(N, 3) tangent stiffness at u times the nodal vector v (N), from the elements v touches; with
        `rows` (node ids) only those rows are wanted and only the elements touching them are used."""
        f = np.zeros((len(self.mesh.nodes_m), 3))
        nen = self.mesh.elements.shape[1]
        ia, ib = (x.ravel() for x in np.meshgrid(np.arange(nen), np.arange(nen), indexing="ij"))
        used = np.any(v_m[self.mesh.elements] != 0, axis=(1, 2))
        if rows is not None:
            used &= np.isin(self.mesh.elements, rows).any(axis=1)
        touched = np.flatnonzero(used)
        for start in range(0, len(touched), _CHUNK):
            el = touched[start : start + _CHUNK]
            k = self._blocks(u_m, el, ia, ib).reshape(nen, nen, len(el), 3, 3)
            add_element_vectors(f, self.mesh.elements[el], np.einsum("abmik,mbk->mai", k, v_m[self.mesh.elements[el]]))
        return f

    def element_strain_stress(self, u_m: np.ndarray) -> ElementStrainStress:
        """Per element, the largest over its quadrature points of the tensile and the compressive principal
        engineering strain (`principal_strains`) and of the Cauchy von Mises stress (Pa)."""
        m = len(self.mesh.elements)
        tensile, compressive, mises = np.empty(m), np.empty(m), np.empty(m)
        for s in _chunks(m):
            F = self.deformation_gradient(u_m, s)
            md = self._mean_dilatation(F, self.weights_m3[s])
            sig = stress(self.law, F, None if md is None else md[0]) @ np.swapaxes(F, -1, -2)
            sig /= det_and_inverse_transpose(F)[0][..., None, None]
            t, c = principal_strains(F, sig)
            tensile[s], compressive[s] = t.max(axis=1), c.max(axis=1)
            dev = sig - np.trace(sig, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3
            mises[s] = np.sqrt(1.5 * np.einsum("...ij,...ij->...", dev, dev)).max(axis=1)
        return ElementStrainStress(tensile, compressive, mises)


@dataclass(frozen=True)
class ElementStrainStress:
    """Per element (m,): the largest tensile and compressive principal engineering strain and the Cauchy von
    Mises stress (Pa) over its quadrature points."""

    tensile_strain: np.ndarray
    compressive_strain: np.ndarray
    von_mises_Pa: np.ndarray


def principal_strains(F: np.ndarray, sigma_Pa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tensile and the compressive principal engineering strain at each point (..., 3, 3 -> ...).

    The principal stretches lambda_i and spatial directions n_i are the eigen-pairs of b = F F^T; in an
    isotropic law the Cauchy stress sigma is coaxial with b, so n_i sigma n_i is the principal stress along
    n_i. A direction is tensile where that stress exceeds `TENSION_FLOOR` times the point's largest principal
    stress magnitude, compressive where it is below minus that. Tensile strain: the largest lambda_i - 1 along
    a tensile direction; compressive: the largest 1 - lambda_i along a compressive one (0 where none). A
    squeezed region's bulge (stretched, but free or confined) is not a tensile fibre and does not count."""
    lam2, n = np.linalg.eigh(F @ np.swapaxes(F, -1, -2))
    stretch = np.sqrt(np.clip(lam2, 0.0, None))
    principal = np.einsum("...ji,...jk,...ki->...i", n, sigma_Pa, n)
    floor = TENSION_FLOOR * np.abs(principal).max(axis=-1, keepdims=True)
    tensile = np.where(principal > floor, stretch - 1.0, 0.0).max(axis=-1)
    compressive = np.where(principal < -floor, 1.0 - stretch, 0.0).max(axis=-1)
    return np.maximum(tensile, 0.0), np.maximum(compressive, 0.0)


def _chunks(m: int) -> list[slice]:
    return [slice(s, min(s + _CHUNK, m)) for s in range(0, m, _CHUNK)]
