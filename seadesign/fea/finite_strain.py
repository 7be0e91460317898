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
from seadesign.fea.hyperelastic import det_and_inverse_transpose, i1_tangent, isochoric_energy_density, stress, tangent, volumetric

_CHUNK = 4096  # elements per vectorised block
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
        """F = I + grad u (m, q, 3, 3) at the quadrature points of the selected elements: the element's
        displacements combined with the constant D (one product), then with its Gamma."""
        ue = u_m[self.mesh.elements[elements]]  # (m, nen, 3)
        q, nen = self.dlam.shape[0], self.dlam.shape[1]
        d = self.dlam.transpose(0, 2, 1).reshape(q * 4, nen)
        uk = (d @ ue.transpose(1, 0, 2).reshape(nen, -1)).reshape(q, 4, len(ue), 3)  # sum_a D[q, a, k] u_ai
        return np.eye(3) + uk.transpose(2, 0, 3, 1) @ self.bary[elements][:, None]

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
            _scatter(f, self.mesh.elements[s], self._contract(p, s))
        return f

    def _contract(self, p: np.ndarray, el: slice | np.ndarray) -> np.ndarray:
        """f_ai = sum_q w P_ij G_aj (m, nen, 3) for P (m, q, 3, 3): (w P Gamma^T), then the constant D."""
        r = (p * self.weights_m3[el][..., None, None]) @ np.swapaxes(self.bary[el], -1, -2)[:, None]  # (m, q, i, k)
        q, nen = self.dlam.shape[0], self.dlam.shape[1]
        m = len(r)
        d = self.dlam.transpose(1, 0, 2).reshape(nen, q * 4)
        return (d @ r.transpose(1, 3, 0, 2).reshape(q * 4, m * 3)).reshape(nen, m, 3).transpose(1, 0, 2)

    def _point_terms(self, u_m: np.ndarray, el: slice | np.ndarray) -> tuple[np.ndarray, np.ndarray, tuple | None]:
        """The element tangent's point terms: K_ab[i, j] = sum_{q,k,l} D[q, a, k] D[q, b, l] E[q, k, l, m, i, j]
        + D[q, a, l] D[q, b, k] X[q, k, l, m, i, j], with E + X = w sum_JL Gamma_kJ A_iJjL Gamma_lL and X the
        part whose indices run crosswise (so that no term needs a transpose): one product with a constant
        matrix (`_pair_coefficients`). Laws in I1bar and J build them from their tangent terms
        (`hyperelastic.I1Tangent`) as outer products of F Gamma, H Gamma and D Gamma, never the 81-component
        A. Also, for the mean dilatation, beta = dv/du (m, nen, 3) and U''(Jbar) / V (m,), else None."""
        F, w, gam = self.deformation_gradient(u_m, el), self.weights_m3[el], self.bary[el]
        md = self._mean_dilatation(F, w)
        pressure = None if md is None else md[0]
        m, q = w.shape
        if self.law.c01_Pa:
            _, a = tangent(self.law, F, pressure)
            e = np.einsum("mkJ,mqiJjL,mlL,mq->qklmij", gam, a, gam, w, optimize=True)
            x = np.zeros_like(e)
        else:
            t = i1_tangent(self.law, F, pressure)
            fg = gam[:, None] @ np.swapaxes(t.F, -1, -2)  # (F Gamma_k)_i
            hg = gam[:, None] @ np.swapaxes(t.H, -1, -2)
            # cross (F x H + H x F) + hh H x H = pg x hg + hg x pg
            pg = (t.cross * w)[..., None, None] * fg + 0.5 * (t.hh * w)[..., None, None] * hg
            left, right = [pg, hg], [hg, pg]
            if np.any(t.w11):
                dg = gam[:, None] @ np.swapaxes(t.D, -1, -2)
                left, right = left + [(t.w11 * w)[..., None, None] * dg], right + [dg]
            n = len(left)
            e = (np.stack(left, axis=-1).reshape(m * q, 12, n) @ np.stack(right, axis=2).reshape(m * q, n, 12))
            e = e.reshape(m, q, 4, 3, 4, 3)
            gram = (gam @ np.swapaxes(gam, -1, -2))[:, None] * (t.delta * w)[..., None, None]
            for i in range(3):
                e[:, :, :, i, :, i] += gram
            # hx H_iL H_jJ = (H Gamma_l)_i (H Gamma_k)_j: an outer product read with k and l exchanged
            x = (((t.hx * w)[..., None, None] * hg).reshape(m * q, 12, 1) @ hg.reshape(m * q, 1, 12))
            e = e.transpose(1, 2, 4, 0, 3, 5)
            x = x.reshape(m, q, 4, 3, 4, 3).transpose(1, 2, 4, 0, 3, 5)
        volumetric_terms = None
        if md is not None:
            j, h = det_and_inverse_transpose(F)
            volumetric_terms = self._contract(j[..., None, None] * h, el), md[1] / w.sum(axis=1)  # beta = int J F^-T G dV
        return np.ascontiguousarray(e), np.ascontiguousarray(x), volumetric_terms

    def _pair_coefficients(self, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
        """[C, C'] (P, 2 q 16): C[p, (q, k, l)] = D[q, a_p, k] D[q, b_p, l] and C' the same with k, l exchanged."""
        d = self.dlam
        c = (d[:, ia, :, None] * d[:, ib, None, :]).transpose(1, 0, 2, 3)
        return np.concatenate([c.reshape(len(ia), -1), c.transpose(0, 1, 3, 2).reshape(len(ia), -1)], axis=1)

    def _blocks(self, u_m: np.ndarray, el: slice | np.ndarray, ia: np.ndarray, ib: np.ndarray) -> np.ndarray:
        """Tangent blocks K_ab (P, m, 3, 3) in N/m of the selected elements for the pairs (ia, ib)."""
        e, x, md = self._point_terms(u_m, el)
        q, m = e.shape[0], e.shape[3]
        ex = np.concatenate([e.reshape(q * 16, m * 9), x.reshape(q * 16, m * 9)])
        blocks = (self._pair_coefficients(ia, ib) @ ex).reshape(len(ia), m, 3, 3)
        if md is not None:  # the mean dilatation's rank-one volumetric stiffness
            beta, c = md
            bi, bj = beta[:, ia].transpose(1, 0, 2), beta[:, ib].transpose(1, 0, 2)
            blocks += c[None, :, None, None] * bi[..., None] * bj[..., None, :]
        return blocks

    def tangent(self, u_m: np.ndarray, node_index: np.ndarray, n: int) -> UpperBlocks:
        """Tangent stiffness (N/m) at u as upper 3x3 node blocks; node_index maps nodes to block rows
        (-1: no row, e.g. a prescribed node), as `assembly.sum_pair_blocks`."""
        ia, ib = upper_pairs(self.mesh.order)
        blocks = np.empty((len(ia), len(self.mesh.elements), 3, 3))
        for s in _chunks(len(self.mesh.elements)):
            blocks[:, s] = self._blocks(u_m, s, ia, ib)
        return sum_pair_blocks(self.mesh.elements, self.mesh.order, blocks, node_index, n)

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
            _scatter(f, self.mesh.elements[el], np.einsum("abmik,mbk->mai", k, v_m[self.mesh.elements[el]]))
        return f

    def element_strain_stress(self, u_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per element, the largest over its quadrature points of the principal stretch (max eigenvalue
        of U = sqrt(F^T F), so engineering strain = stretch - 1, logarithmic = ln stretch) and of the Cauchy
        von Mises stress (Pa) of sigma = P F^T / J; both (m,)."""
        m = len(self.mesh.elements)
        stretch, mises = np.empty(m), np.empty(m)
        for s in _chunks(m):
            F = self.deformation_gradient(u_m, s)
            stretch[s] = np.sqrt(np.linalg.eigvalsh(np.swapaxes(F, -1, -2) @ F)[..., -1].max(axis=1))
            md = self._mean_dilatation(F, self.weights_m3[s])
            sig = stress(self.law, F, None if md is None else md[0]) @ np.swapaxes(F, -1, -2)
            sig /= det_and_inverse_transpose(F)[0][..., None, None]
            dev = sig - np.trace(sig, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3
            mises[s] = np.sqrt(1.5 * np.einsum("...ij,...ij->...", dev, dev)).max(axis=1)
        return stretch, mises


def _chunks(m: int) -> list[slice]:
    return [slice(s, min(s + _CHUNK, m)) for s in range(0, m, _CHUNK)]


def _scatter(f: np.ndarray, elements: np.ndarray, fe: np.ndarray) -> None:
    idx = elements.ravel()
    for i in range(3):
        f[:, i] += np.bincount(idx, weights=fe[..., i].ravel(), minlength=len(f))
